//! One TFETI subdomain: its stiffness K_s over all 3·n_s DOFs, its load f_s, its rigid-body
//! modes R_s and a generalized inverse K_s⁺.
//!
//! **Dirichlet conditions** are either multiplier rows (every DOF floating: R_s the six rigid
//! motions) or, hybrid, eliminated inside the subdomain that carries them: the held DOFs D are
//! taken out of K_s (their rows and columns act as absent, u_D = g_D, f̂ = f − K g on the rest)
//! and the kernel shrinks to the rigid motions that leave D at rest, R_s N with N an
//! orthonormal basis of Ker R_D ([`held_kernel`]): 0 to 6 columns (a clamped face: none; a
//! roller face: the three in-plane motions). A subdomain whose held DOFs stop a rigid motion
//! only weakly (nearly collinear points) keeps its rows instead.
//!
//! **R_s**: the three translations and three rotations about the subdomain's centroid,
//! orthonormalized (modified Gram–Schmidt, twice), so that Rᵀ_s R_s = I and G = RᵀBᵀ is well
//! scaled.
//!
//! **K_s⁺ by fixing DOFs.** As many DOFs as the kernel has columns are chosen such that R_s
//! restricted to them is regular (then no rigid motion vanishes on them, and K_s with those
//! rows and columns removed, K_rr, is positive definite). K_s⁺ = Pᵀ diag(K_rr⁻¹, 0) P is a
//! symmetric generalized inverse (K_s K_s⁺ K_s = K_s, because rank K_rr = rank K_s). The
//! candidates are the nine DOFs of three nodes spread over the subdomain (the node farthest
//! from the centroid, the node farthest from it, the node farthest from the line through
//! both), every free DOF if they do not suffice; the fixing DOFs are picked from them by
//! Gram–Schmidt with pivoting on the rows of R_s, which keeps K_rr as well conditioned as the
//! geometry allows. Chosen over a regularization K_s + ρ R_s R_sᵀ (dense) or a
//! Tikhonov shift (inexact): it is exact, keeps the sparse pattern and costs nothing extra.
//! Implementation: the fixed (and held) rows and columns of K_s are replaced by the identity
//! and the whole matrix is factorized once (faer sparse Cholesky, METIS nested dissection on
//! the node graph); K_s⁺x zeroes those entries of x, solves, and zeroes them again.

use crate::error::{Error, Result};
use crate::fem::assembly::{assemble_elements, AssemblyError, DofMap};
use crate::fem::material::Lame;
use crate::feti::decomposition::Subdomain;
use crate::linalg::cholesky::{Cholesky, Ordering};
use crate::linalg::ordering::{expand_to_dofs, nested_dissection};
use crate::linalg::sparse::SymCsc;
use crate::mesh::{Cell, Mesh};
use crate::scene::OrderingKind;

/// Rigid-body modes per subdomain.
pub const NR: usize = 6;

/// The six rigid-body modes of `nodes`, orthonormalized: column-major, 3·n × 6, DOF 3·l + c.
pub fn rigid_modes(coords: &[[f64; 3]]) -> Vec<f64> {
    let n = coords.len();
    let nd = 3 * n;
    let mut c = [0.0; 3];
    for p in coords {
        for d in 0..3 {
            c[d] += p[d] / n as f64;
        }
    }
    let mut r = vec![0.0; nd * NR];
    for (l, p) in coords.iter().enumerate() {
        let (x, y, z) = (p[0] - c[0], p[1] - c[1], p[2] - c[2]);
        for d in 0..3 {
            r[d * nd + 3 * l + d] = 1.0;
        }
        // ω × (x − c) for ω = e_x, e_y, e_z
        let rot = [[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]];
        for (k, v) in rot.iter().enumerate() {
            r[(3 + k) * nd + 3 * l..(3 + k) * nd + 3 * l + 3].copy_from_slice(v);
        }
    }
    for _ in 0..2 {
        for k in 0..NR {
            for j in 0..k {
                let (a, b) = r.split_at_mut(k * nd);
                let (cj, ck) = (&a[j * nd..(j + 1) * nd], &mut b[..nd]);
                let h: f64 = cj.iter().zip(ck.iter()).map(|(p, q)| p * q).sum();
                ck.iter_mut().zip(cj).for_each(|(q, p)| *q -= h * p);
            }
            let ck = &mut r[k * nd..(k + 1) * nd];
            let nrm = ck.iter().map(|v| v * v).sum::<f64>().sqrt();
            // a vanishing mode (collinear nodes) stays zero; fixing_dofs then refuses
            let inv = if nrm > 1e-12 { 1.0 / nrm } else { 0.0 };
            ck.iter_mut().for_each(|v| *v *= inv);
        }
    }
    r
}

/// Share μ of a rigid motion's squared norm on the held DOFs (an eigenvalue of R_Dᵀ R_D, R
/// orthonormal) at or below which the motion counts as left free by them.
pub const FREE_SHARE: f64 = 1e-11;
/// Share at or above which it counts as held; a subdomain with a motion in between keeps its
/// Dirichlet rows (eliminating them would leave K_s nearly singular).
pub const HELD_SHARE: f64 = 1e-8;
/// Least [`hold_ratio`] at which a subdomain eliminates its held DOFs: below it a motion held
/// by a small patch of Dirichlet DOFs but glued along a large interface would turn into a soft
/// mode of K_s (σ_max(F) up 8× on the seed at S = 4), so the subdomain floats and keeps its
/// rows, and the coarse space takes the motion. Chosen on the benchmark set (docs/method.md,
/// "TFETI and H-TFETI").
pub const HOLD_RATIO: f64 = 0.03;

/// The rigid motions of the nodes at `coords` that leave the DOFs `held` (local, sorted) at
/// rest: R N, N an orthonormal basis of Ker R_D, column-major 3n × k with zeros on `held`, and
/// k. The six modes of [`rigid_modes`] when nothing is held; `None` when a motion is held
/// only weakly ([`FREE_SHARE`] < μ < [`HELD_SHARE`]).
pub fn held_kernel(coords: &[[f64; 3]], held: &[usize]) -> Option<(Vec<f64>, usize)> {
    let r = rigid_modes(coords);
    if held.is_empty() {
        return Some((r, NR));
    }
    let nd = 3 * coords.len();
    let m = faer::Mat::<f64>::from_fn(NR, NR, |i, j| held.iter().map(|&d| r[i * nd + d] * r[j * nd + d]).sum());
    let eig = m.self_adjoint_eigen(faer::Side::Lower).ok()?;
    let (mu, n) = (eig.S(), eig.U());
    let free: Vec<usize> = (0..NR).filter(|&i| mu[i] <= FREE_SHARE).collect();
    if (0..NR).any(|i| mu[i] > FREE_SHARE && mu[i] < HELD_SHARE) {
        return None;
    }
    let k = free.len();
    let mut out = vec![0.0; nd * k];
    for (c, &i) in free.iter().enumerate() {
        let col = &mut out[c * nd..(c + 1) * nd];
        for j in 0..NR {
            let w = n[(j, i)];
            col.iter_mut().zip(&r[j * nd..(j + 1) * nd]).for_each(|(o, x)| *o += w * x);
        }
        for &d in held {
            col[d] = 0.0;
        }
    }
    Some((out, k))
}

/// How firmly the held DOFs hold the rigid motions they stop, against the interface DOFs
/// `interface` (those with gluing rows): the smallest ratio μ_D/μ_B over those motions, μ the
/// share of a motion's squared norm on each set (the generalized eigenvalues of R_DᵀR_D and
/// R_BᵀR_B on the held motions). ∞ without an interface or without held motions.
pub fn hold_ratio(coords: &[[f64; 3]], held: &[usize], interface: &[usize]) -> f64 {
    let r = rigid_modes(coords);
    let nd = 3 * coords.len();
    let gram = |dofs: &[usize]| faer::Mat::<f64>::from_fn(NR, NR, |i, j| dofs.iter().map(|&d| r[i * nd + d] * r[j * nd + d]).sum());
    let Ok(eig) = gram(held).self_adjoint_eigen(faer::Side::Lower) else { return 0.0 };
    let (mu, q) = (eig.S(), eig.U());
    // the held motions, scaled to unit μ_D: W = Q_h diag(μ)^{-1/2}
    let hs: Vec<usize> = (0..NR).filter(|&i| mu[i] > FREE_SHARE).collect();
    if hs.is_empty() || interface.is_empty() {
        return f64::INFINITY;
    }
    let w = faer::Mat::<f64>::from_fn(NR, hs.len(), |j, c| q[(j, hs[c])] / mu[hs[c]].sqrt());
    let b = w.transpose() * gram(interface) * &w;
    let Ok(top) = b.self_adjoint_eigenvalues(faer::Side::Lower) else { return 0.0 };
    let max = top.iter().copied().fold(0.0, f64::max);
    if max > 0.0 {
        1.0 / max
    } else {
        f64::INFINITY
    }
}

/// `k` fixing DOFs (local DOF indices, ascending) for the nodes at `coords` with the `k` modes
/// `r` (column-major), none of them in `held` (sorted); `None` if no such DOFs determine the
/// modes (collinear nodes).
pub fn fixing_dofs(coords: &[[f64; 3]], r: &[f64], k: usize, held: &[usize]) -> Option<Vec<usize>> {
    let n = coords.len();
    let nd = 3 * n;
    if k == 0 {
        return Some(vec![]);
    }
    let dist2 = |a: [f64; 3], b: [f64; 3]| (0..3).map(|d| (a[d] - b[d]).powi(2)).sum::<f64>();
    let mut c = [0.0; 3];
    for p in coords {
        (0..3).for_each(|d| c[d] += p[d] / n as f64);
    }
    let far = |from: &dyn Fn(usize) -> f64| (0..n).max_by(|&a, &b| from(a).total_cmp(&from(b)).then(b.cmp(&a))).unwrap_or(0);
    let a = far(&|v| dist2(coords[v], c));
    let b = far(&|v| dist2(coords[v], coords[a]));
    let ab = [0, 1, 2].map(|d| coords[b][d] - coords[a][d]);
    let lab = dist2(coords[b], coords[a]).max(f64::MIN_POSITIVE);
    let off_line = |v: usize| {
        let p = [0, 1, 2].map(|d| coords[v][d] - coords[a][d]);
        let t = (0..3).map(|d| p[d] * ab[d]).sum::<f64>() / lab;
        (0..3).map(|d| (p[d] - t * ab[d]).powi(2)).sum::<f64>()
    };
    let cc = far(&off_line);
    let free = |dof: &usize| held.binary_search(dof).is_err();
    let mut candidates: Vec<usize> = [a, b, cc].iter().flat_map(|&v| (0..3).map(move |d| 3 * v + d)).filter(free).collect();
    candidates.dedup();
    pivoted(r, nd, k, &candidates).or_else(|| (!held.is_empty()).then(|| pivoted(r, nd, k, &(0..nd).filter(free).collect::<Vec<_>>())).flatten())
}

/// `k` of the `candidates` DOFs on which the `k` modes `r` are regular: Gram–Schmidt with
/// pivoting on the largest row norm.
fn pivoted(r: &[f64], nd: usize, k: usize, candidates: &[usize]) -> Option<Vec<usize>> {
    let mut rows: Vec<(usize, Vec<f64>)> = candidates.iter().map(|&dof| (dof, (0..k).map(|j| r[j * nd + dof]).collect())).collect();
    let norm = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>().sqrt();
    let first = rows.iter().map(|x| norm(&x.1)).fold(0.0, f64::max);
    let mut chosen = Vec::with_capacity(k);
    for _ in 0..k {
        let (p, best) = rows.iter().enumerate().map(|(i, x)| (i, norm(&x.1))).max_by(|x, y| x.1.total_cmp(&y.1))?;
        if !(best > 1e-8 * first) {
            return None;
        }
        let (dof, q) = rows.swap_remove(p);
        let q: Vec<f64> = q.iter().map(|v| v / best).collect();
        chosen.push(dof);
        for (_, x) in &mut rows {
            let h: f64 = x.iter().zip(&q).map(|(a, b)| a * b).sum();
            x.iter_mut().zip(&q).for_each(|(a, b)| *a -= h * b);
        }
    }
    chosen.sort_unstable();
    Some(chosen)
}

/// A subdomain assembled and factorized.
pub struct SubdomainSystem {
    /// Index in the decomposition.
    pub index: usize,
    /// Number of nodes n_s (3·n_s DOFs, DOF 3·l + c for local node l).
    pub nn: usize,
    /// K_s, lower triangle, all DOFs (held ones included).
    pub k: SymCsc,
    /// f̂_s = f_s − K_s g on the free DOFs, 0 on the held ones; f_s: the nodal loads, each
    /// node's load on its first copy only.
    pub f: Vec<f64>,
    /// The kernel R_s, column-major 3n_s × `kdim`, orthonormal columns, 0 on the held DOFs.
    pub r: Vec<f64>,
    pub kdim: usize,
    pub fixed: Vec<usize>,
    /// The eliminated (held) DOFs, ascending, and their values g.
    pub held: Vec<usize>,
    pub g: Vec<f64>,
    /// fixed ∪ held: the entries K_s⁺ zeroes.
    zeroed: Vec<usize>,
    chol: Cholesky,
}

/// A subdomain's part of the mesh in its local node numbering: what assembling K_s reads.
pub struct SubdomainMesh<'a> {
    /// Coordinates of its nodes.
    pub coords: &'a [[f64; 3]],
    /// Its elements' nodes, local.
    pub cells: &'a [Cell],
    /// The global index of each element, its body's name and the body's first element (for
    /// messages).
    pub elems: &'a [usize],
    pub body: &'a str,
    pub body_elems_start: usize,
}

impl SubdomainSystem {
    /// [`SubdomainSystem::from_part`] of subdomain `sd` of `mesh`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(mesh: &Mesh, sd: &Subdomain, index: usize, lame: Lame, ordering: OrderingKind, f: Vec<f64>, held: Vec<usize>, g: Vec<f64>) -> Result<Self> {
        let coords: Vec<[f64; 3]> = sd.nodes.iter().map(|&v| mesh.nodes[v]).collect();
        let cells: Vec<Cell> = sd.elems.iter().map(|&e| mesh.cells[e].map(|v| sd.local(v).expect("element node in its subdomain"))).collect();
        let body = &mesh.bodies[sd.body];
        let part = SubdomainMesh { coords: &coords, cells: &cells, elems: &sd.elems, body: &body.name, body_elems_start: body.elems.start };
        Self::from_part(&part, index, lame, ordering, f, held, g)
    }

    /// Assembles K_s over the subdomain's elements (`part`, in its local numbering) and
    /// factorizes it with its fixing DOFs; `f` is f_s (per local DOF), `held` the eliminated
    /// DOFs (ascending) and `g` their values.
    #[allow(clippy::too_many_arguments)]
    pub fn from_part(part: &SubdomainMesh<'_>, index: usize, lame: Lame, ordering: OrderingKind, f: Vec<f64>, held: Vec<usize>, g: Vec<f64>) -> Result<Self> {
        let coords = part.coords;
        let nn = coords.len();
        let what = || format!("subdomain {index} (body \"{}\")", part.body);
        let (r, kdim) =
            held_kernel(coords, &held).ok_or_else(|| Error::numerical(what(), "its held DOFs stop a rigid motion only weakly: keep its Dirichlet rows"))?;
        let fixed = fixing_dofs(coords, &r, kdim, &held).ok_or_else(|| Error::numerical(what(), "its nodes are collinear: no rigid-body fixing DOFs"))?;
        let all = DofMap::new(0..nn, &[]);
        let sys = assemble_elements(coords, part.cells, 0..part.cells.len(), nn, |v| v, lame, &all, &f).map_err(|e| match e {
            AssemblyError::Element(e, msg) => Error::mesh(format!("body {}", part.body), format!("element {} is {msg}", part.elems[e] - part.body_elems_start)),
            AssemblyError::Memory(e) => e,
        })?;
        let k = sys.k;
        let mut zeroed: Vec<usize> = fixed.iter().chain(&held).copied().collect();
        zeroed.sort_unstable();
        // K̂: K with the fixed and held rows and columns replaced by the identity
        let kh = identity_on(&k, &fixed, &held);
        let ord = match ordering {
            OrderingKind::Metis => {
                let (xadj, adj) = &sys.graph;
                let perm = nested_dissection(xadj, adj)?;
                Ordering::Custom(expand_to_dofs(&perm, 3 * nn, |v| [0, 1, 2].map(|c| Some(3 * v + c))))
            }
            OrderingKind::Amd => Ordering::Amd,
        };
        let chol = Cholesky::factorize(&kh, ord).map_err(|e| Error::numerical(what(), e.to_string()))?;
        let mut s = SubdomainSystem { index, nn, k, f: vec![], r, kdim, fixed, held, g: vec![], zeroed, chol };
        s.set_load(sys.f, g);
        Ok(s)
    }

    /// A new load: f̂ = f − K g on the free DOFs, 0 on the held ones (`g`: their values).
    pub fn set_load(&mut self, mut f: Vec<f64>, g: Vec<f64>) {
        assert_eq!(g.len(), self.held.len(), "one value per held DOF");
        if g.iter().any(|&v| v != 0.0) {
            let mut full = vec![0.0; self.ndof()];
            self.held.iter().zip(&g).for_each(|(&d, &v)| full[d] = v);
            let kg = self.k.mul(&full);
            f.iter_mut().zip(&kg).for_each(|(a, b)| *a -= b);
        }
        for &d in &self.held {
            f[d] = 0.0;
        }
        (self.f, self.g) = (f, g);
    }

    pub fn ndof(&self) -> usize {
        3 * self.nn
    }

    /// Stored entries of the Cholesky factor.
    pub fn nnz_l(&self) -> usize {
        self.chol.nnz_l()
    }

    /// x ← K_s⁺ x.
    pub fn pinv_in_place(&self, x: &mut [f64]) {
        self.pinv_in_place_as(x, false);
    }

    /// x ← K_s⁺ x, with the single-precision copy of the factor when `single` and one is kept.
    pub fn pinv_in_place_as(&self, x: &mut [f64], single: bool) {
        for &d in &self.zeroed {
            x[d] = 0.0;
        }
        if single {
            self.chol.solve_in_place_single(x);
        } else {
            self.chol.solve_in_place(x);
        }
        for &d in &self.zeroed {
            x[d] = 0.0;
        }
    }

    /// Keeps a single-precision copy of the factor; returns its bytes.
    pub fn keep_single(&mut self) -> usize {
        self.chol.keep_single();
        self.chol.single_bytes()
    }

    /// X ← K_s⁺ X for the `ncols` columns of `x` (column-major).
    pub fn pinv_many_in_place(&self, x: &mut [f64], ncols: usize) {
        let nd = self.ndof();
        for col in x.chunks_exact_mut(nd) {
            self.zeroed.iter().for_each(|&d| col[d] = 0.0);
        }
        self.chol.solve_many_in_place(x, ncols);
        for col in x.chunks_exact_mut(nd) {
            self.zeroed.iter().for_each(|&d| col[d] = 0.0);
        }
    }

    /// x += R_s α (`kdim` values).
    pub fn add_r_mul(&self, alpha: &[f64], x: &mut [f64]) {
        let nd = self.ndof();
        for (k, &a) in alpha.iter().enumerate().take(self.kdim) {
            x.iter_mut().zip(&self.r[k * nd..(k + 1) * nd]).for_each(|(xi, ri)| *xi += a * ri);
        }
    }

    /// x_D ← g: the held values.
    pub fn set_held(&self, x: &mut [f64]) {
        self.held.iter().zip(&self.g).for_each(|(&d, &v)| x[d] = v);
    }

    /// K_s with the held rows and columns replaced by the identity: the stiffness of the free
    /// DOFs alone (the FETI preconditioner's).
    pub fn k_free(&self) -> std::borrow::Cow<'_, SymCsc> {
        if self.held.is_empty() {
            return std::borrow::Cow::Borrowed(&self.k);
        }
        std::borrow::Cow::Owned(identity_on(&self.k, &[], &self.held))
    }
}

/// `k` with the rows and columns of `fixed` and `held` replaced by the identity; the held
/// ones' off-diagonal entries leave the pattern (they cost no fill), the fixed ones' stay.
fn identity_on(k: &SymCsc, fixed: &[usize], held: &[usize]) -> SymCsc {
    let mut mask = vec![0u8; k.n];
    fixed.iter().for_each(|&d| mask[d] = 1);
    held.iter().for_each(|&d| mask[d] = 2);
    let mut out = SymCsc { n: k.n, col_ptr: vec![0], row_idx: Vec::with_capacity(k.nnz()), values: Vec::with_capacity(k.nnz()) };
    for j in 0..k.n {
        for p in k.col_ptr[j]..k.col_ptr[j + 1] {
            let i = k.row_idx[p];
            let v = if mask[i] == 0 && mask[j] == 0 {
                k.values[p]
            } else if i == j {
                1.0
            } else {
                0.0
            };
            if i == j || (mask[i] != 2 && mask[j] != 2) {
                out.row_idx.push(i);
                out.values.push(v);
            }
        }
        out.col_ptr.push(out.row_idx.len());
    }
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::feti::decomposition::decompose;
    use crate::mesh::boxgen;

    /// A reproducible uniform value in [−1, 1).
    pub(crate) fn lcg(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    pub(crate) fn norm(v: &[f64]) -> f64 {
        v.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    fn frobenius(k: &SymCsc) -> f64 {
        let mut s = 0.0;
        for j in 0..k.n {
            for p in k.col_ptr[j]..k.col_ptr[j + 1] {
                s += if k.row_idx[p] == j { 1.0 } else { 2.0 } * k.values[p].powi(2);
            }
        }
        s.sqrt()
    }

    /// ‖K R‖ ≈ 0, RᵀR = I and K K⁺ K = K on random vectors, for every subdomain of the box
    /// `nodes` split into `parts`.
    fn check(min: [f64; 3], max: [f64; 3], nodes: [usize; 3], parts: usize) -> usize {
        let mut mesh = Mesh::default();
        mesh.push_body("b", boxgen::generate(min, max, nodes));
        let d = decompose(&mesh, parts).unwrap();
        let lame = Lame::from_young_poisson(50000.0, 0.3);
        let mut s = 11u64;
        for (i, sd) in d.subdomains.iter().enumerate() {
            let nd = 3 * sd.nodes.len();
            let sys = SubdomainSystem::new(&mesh, sd, i, lame, OrderingKind::Metis, vec![0.0; nd], vec![], vec![]).unwrap();
            let kn = frobenius(&sys.k);
            for k in 0..NR {
                let col = &sys.r[k * nd..(k + 1) * nd];
                let kr = sys.k.mul(col);
                assert!(norm(&kr) <= 1e-10 * kn, "subdomain {i}: ‖K r_{k}‖ = {:.2e}, ‖K‖ = {kn:.2e}", norm(&kr));
                for j in 0..NR {
                    let d: f64 = col.iter().zip(&sys.r[j * nd..(j + 1) * nd]).map(|(a, b)| a * b).sum();
                    assert!((d - if j == k { 1.0 } else { 0.0 }).abs() < 1e-12);
                }
            }
            for _ in 0..3 {
                let x: Vec<f64> = (0..nd).map(|_| lcg(&mut s)).collect();
                let kx = sys.k.mul(&x);
                let mut z = kx.clone();
                sys.pinv_in_place(&mut z);
                let kz = sys.k.mul(&z);
                let diff: Vec<f64> = kz.iter().zip(&kx).map(|(a, b)| a - b).collect();
                assert!(norm(&diff) <= 1e-10 * norm(&kx), "subdomain {i}: ‖KK⁺Kx − Kx‖/‖Kx‖ = {:.2e}", norm(&diff) / norm(&kx));
            }
        }
        d.subdomains.len()
    }

    #[test]
    fn kernel_and_generalized_inverse_of_floating_subdomains() {
        // a cube, METIS parts of a cube, a long bar, a thin sliver (one element thick), one element
        assert_eq!(check([0.0; 3], [1.0; 3], [6, 6, 6], 1), 1);
        assert_eq!(check([0.0; 3], [2.0, 1.0, 1.0], [9, 5, 5], 8), 8);
        assert_eq!(check([0.0; 3], [10.0, 0.5, 0.5], [21, 2, 2], 3), 3);
        assert_eq!(check([0.0; 3], [2.0, 2.0, 0.02], [12, 12, 2], 5), 5);
        assert_eq!(check([0.0; 3], [1.0, 1.0, 1.0], [2, 2, 2], 1), 1);
    }

    /// Held DOFs eliminated: the kernel is the rigid motions they leave free (rollers on one
    /// face: three; a clamped face: none; one fully held node: the three rotations about it),
    /// K_free R = 0 with R zero on the held DOFs and orthonormal, K_free K⁺ K_free = K_free, and
    /// u = K⁺f̂ + g satisfies K u = f on the free DOFs for non-zero held values g.
    #[test]
    fn eliminated_dofs_leave_the_motions_they_do_not_stop() {
        let mut mesh = Mesh::default();
        mesh.push_body("b", boxgen::generate([0.0; 3], [2.0, 1.0, 1.0], [7, 4, 4]));
        let d = decompose(&mesh, 1).unwrap();
        let sd = &d.subdomains[0];
        let nd = 3 * sd.nodes.len();
        let on = |pred: &dyn Fn([f64; 3]) -> bool, comps: &[usize]| -> Vec<usize> {
            let mut v: Vec<usize> =
                (0..sd.nodes.len()).filter(|&l| pred(mesh.nodes[sd.nodes[l]])).flat_map(|l| comps.iter().map(move |&c| 3 * l + c)).collect();
            v.sort_unstable();
            v
        };
        let rollers = on(&|p| p[1] == 0.0, &[1]);
        let clamp = on(&|p| p[0] == 0.0, &[0, 1, 2]);
        let point = on(&|p| p == [0.0, 0.0, 0.0], &[0, 1, 2]);
        let lame = Lame::from_young_poisson(50000.0, 0.3);
        let mut s = 3u64;
        for (held, k_expected) in [(rollers, 3), (clamp, 0), (point, 3)] {
            let g: Vec<f64> = held.iter().map(|_| 1e-3 * lcg(&mut s)).collect();
            let f: Vec<f64> = (0..nd).map(|_| lcg(&mut s)).collect();
            let sys = SubdomainSystem::new(&mesh, sd, 0, lame, OrderingKind::Metis, f.clone(), held.clone(), g.clone()).unwrap();
            assert_eq!(sys.kdim, k_expected);
            let kf = sys.k_free();
            let kn = frobenius(&kf);
            for k in 0..sys.kdim {
                let col = &sys.r[k * nd..(k + 1) * nd];
                assert!(held.iter().all(|&dof| col[dof] == 0.0));
                assert!(norm(&kf.mul(col)) <= 1e-10 * kn, "‖K_free r_{k}‖ = {:.2e}", norm(&kf.mul(col)));
                for j in 0..sys.kdim {
                    let dot: f64 = col.iter().zip(&sys.r[j * nd..(j + 1) * nd]).map(|(a, b)| a * b).sum();
                    assert!((dot - if j == k { 1.0 } else { 0.0 }).abs() < 1e-12);
                }
            }
            // K_free K⁺ K_free x = K_free x on x with zero held entries
            let mut x: Vec<f64> = (0..nd).map(|_| lcg(&mut s)).collect();
            held.iter().for_each(|&dof| x[dof] = 0.0);
            let kx = kf.mul(&x);
            let mut z = kx.clone();
            sys.pinv_in_place(&mut z);
            let diff: Vec<f64> = kf.mul(&z).iter().zip(&kx).map(|(a, b)| a - b).collect();
            assert!(norm(&diff) <= 1e-10 * norm(&kx), "‖KK⁺Kx − Kx‖/‖Kx‖ = {:.2e}", norm(&diff) / norm(&kx));
            // a load orthogonal to the kernel: u = K⁺f̂ + g solves K u = f off the held DOFs
            if sys.kdim == 0 {
                let mut u = sys.f.clone();
                sys.pinv_in_place(&mut u);
                sys.set_held(&mut u);
                let ku = sys.k.mul(&u);
                let mut r: Vec<f64> = ku.iter().zip(&f).map(|(a, b)| a - b).collect();
                held.iter().for_each(|&dof| r[dof] = 0.0);
                assert!(norm(&r) <= 1e-9 * norm(&f), "‖K u − f‖ = {:.2e}", norm(&r));
                assert!(held.iter().zip(&g).all(|(&dof, &v)| u[dof] == v));
            }
        }
    }

    /// A cube glued on five faces: held on the sixth it is held firmly, held at one corner node
    /// it is not; without an interface the ratio is infinite.
    #[test]
    fn hold_ratio_tells_a_face_from_a_patch() {
        let coords: Vec<[f64; 3]> =
            (0..5).flat_map(|i| (0..5).flat_map(move |j| (0..5).map(move |k| [i as f64 / 4.0, j as f64 / 4.0, k as f64 / 4.0]))).collect();
        let on = |pred: &dyn Fn([f64; 3]) -> bool| -> Vec<usize> {
            (0..coords.len()).filter(|&l| pred(coords[l])).flat_map(|l| (0..3).map(move |c| 3 * l + c)).collect()
        };
        let face = on(&|p| p[0] == 0.0);
        let node = on(&|p| p == [0.0, 0.0, 0.0]);
        // glued on its five other faces
        let interface: Vec<usize> =
            on(&|p| p[0] == 1.0 || p[1] == 0.0 || p[1] == 1.0 || p[2] == 0.0 || p[2] == 1.0).into_iter().filter(|d| !face.contains(d)).collect();
        let firm = hold_ratio(&coords, &face, &interface);
        let weak = hold_ratio(&coords, &node, &interface);
        assert!(firm >= HOLD_RATIO, "a face: {firm:.2e}");
        assert!(weak < HOLD_RATIO, "one node: {weak:.2e}");
        assert_eq!(hold_ratio(&coords, &face, &[]), f64::INFINITY);
    }

    #[test]
    fn collinear_nodes_have_no_fixing_dofs() {
        let coords: Vec<[f64; 3]> = (0..4).map(|i| [i as f64, 0.0, 0.0]).collect();
        let r = rigid_modes(&coords);
        // the rotation about x vanishes on the line: R has rank 5 there
        assert!(fixing_dofs(&coords, &r, NR, &[]).is_none());
    }
}
