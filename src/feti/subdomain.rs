//! One floating TFETI subdomain: its stiffness K_s over all 3·n_s DOFs (nothing eliminated:
//! Dirichlet conditions are multiplier rows), its load f_s, its rigid-body modes R_s and a
//! generalized inverse K_s⁺.
//!
//! **R_s**: the three translations and three rotations about the subdomain's centroid,
//! orthonormalized (modified Gram–Schmidt, twice), so that Rᵀ_s R_s = I and G = RᵀBᵀ is well
//! scaled.
//!
//! **K_s⁺ by fixing DOFs.** Six DOFs are chosen such that R_s restricted to them is a regular
//! 6×6 matrix (then no rigid motion vanishes on them, and K_s with those rows and columns removed,
//! K_rr, is positive definite). K_s⁺ = Pᵀ diag(K_rr⁻¹, 0) P is a symmetric generalized inverse
//! (K_s K_s⁺ K_s = K_s, because rank K_rr = rank K_s). The candidates are the nine DOFs of three
//! nodes spread over the subdomain (the node farthest from the centroid, the node farthest
//! from it, the node farthest from the line through both); the six are picked from them by
//! Gram–Schmidt with pivoting on the rows of R_s, which keeps K_rr as well conditioned as the
//! geometry allows. Chosen over a regularization K_s + ρ R_s R_sᵀ (dense) or a
//! Tikhonov shift (inexact): it is exact, keeps the sparse pattern and costs nothing extra.
//! Implementation: the fixed rows and columns of K_s are replaced by the identity and the
//! whole matrix is factorized once (faer sparse Cholesky, METIS nested dissection on the node
//! graph); K_s⁺x zeroes the fixed entries of x, solves, and zeroes them again.

use crate::error::{Error, Result};
use crate::fem::assembly::{assemble_elements, DofMap};
use crate::fem::material::Lame;
use crate::linalg::cholesky::{Cholesky, Ordering};
use crate::linalg::ordering::{expand_to_dofs, nested_dissection};
use crate::linalg::sparse::SymCsc;
use crate::mesh::Mesh;
use crate::feti::decomposition::Subdomain;
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

/// The six fixing DOFs (local DOF indices) for the nodes at `coords` with modes `r`; `None` if
/// the nodes are collinear (no six DOFs determine a rigid motion).
pub fn fixing_dofs(coords: &[[f64; 3]], r: &[f64]) -> Option<[usize; NR]> {
    let n = coords.len();
    let nd = 3 * n;
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
    // rows of R at the nine candidate DOFs, Gram–Schmidt with pivoting on the largest norm
    let mut rows: Vec<(usize, [f64; NR])> = [a, b, cc]
        .iter()
        .flat_map(|&v| (0..3).map(move |d| 3 * v + d))
        .map(|dof| (dof, std::array::from_fn(|k| r[k * nd + dof])))
        .collect();
    rows.dedup_by_key(|x| x.0);
    let norm = |x: &[f64; NR]| x.iter().map(|v| v * v).sum::<f64>().sqrt();
    let first = rows.iter().map(|x| norm(&x.1)).fold(0.0, f64::max);
    let mut chosen = [0usize; NR];
    for k in 0..NR {
        let (p, best) = rows.iter().enumerate().map(|(i, x)| (i, norm(&x.1))).max_by(|x, y| x.1.total_cmp(&y.1))?;
        if !(best > 1e-8 * first) {
            return None;
        }
        let (dof, q) = rows.swap_remove(p);
        let q = q.map(|v| v / best);
        chosen[k] = dof;
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
    /// K_s, lower triangle, all DOFs.
    pub k: SymCsc,
    /// f_s: the nodal loads, each node's load on its first copy only.
    pub f: Vec<f64>,
    /// R_s, column-major 3n_s × 6, orthonormal columns.
    pub r: Vec<f64>,
    pub fixed: [usize; NR],
    chol: Cholesky,
}

impl SubdomainSystem {
    /// Assembles K_s over the subdomain's elements and factorizes it with its fixing DOFs; `f`
    /// is f_s (per local DOF).
    pub fn new(mesh: &Mesh, sd: &Subdomain, index: usize, lame: Lame, ordering: OrderingKind, f: Vec<f64>) -> Result<Self> {
        let nn = sd.nodes.len();
        let what = || format!("subdomain {index} (body \"{}\")", mesh.bodies[sd.body].name);
        let coords: Vec<[f64; 3]> = sd.nodes.iter().map(|&v| mesh.nodes[v]).collect();
        let r = rigid_modes(&coords);
        let fixed = fixing_dofs(&coords, &r).ok_or_else(|| Error::numerical(what(), "its nodes are collinear: no rigid-body fixing DOFs"))?;
        let all = DofMap::new(0..nn, &[]);
        let sys = assemble_elements(mesh, sd.elems.iter().copied(), nn, |v| sd.local(v).expect("element node in its subdomain"), lame, &all, &f)
            .map_err(|(e, msg)| Error::mesh(format!("body {}", mesh.bodies[sd.body].name), format!("element {} is {msg}", e - mesh.bodies[sd.body].elems.start)))?;
        let k = sys.k;
        // K̂: K with the fixed rows and columns replaced by the identity
        let mut kh = k.clone();
        for j in 0..kh.n {
            for p in kh.col_ptr[j]..kh.col_ptr[j + 1] {
                let i = kh.row_idx[p];
                if fixed.contains(&i) || fixed.contains(&j) {
                    kh.values[p] = if i == j { 1.0 } else { 0.0 };
                }
            }
        }
        let ord = match ordering {
            OrderingKind::Metis => {
                let (xadj, adj) = &sys.graph;
                let perm = nested_dissection(xadj, adj)?;
                Ordering::Custom(expand_to_dofs(&perm, 3 * nn, |v| [0, 1, 2].map(|c| Some(3 * v + c))))
            }
            OrderingKind::Amd => Ordering::Amd,
        };
        let chol = Cholesky::factorize(&kh, ord).map_err(|e| Error::numerical(what(), e.to_string()))?;
        Ok(SubdomainSystem { index, nn, k, f: sys.f, r, fixed, chol })
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
        for &d in &self.fixed {
            x[d] = 0.0;
        }
        self.chol.solve_in_place(x);
        for &d in &self.fixed {
            x[d] = 0.0;
        }
    }

    /// R_sᵀ x (six values).
    pub fn rt_mul(&self, x: &[f64]) -> [f64; NR] {
        let nd = self.ndof();
        std::array::from_fn(|k| self.r[k * nd..(k + 1) * nd].iter().zip(x).map(|(a, b)| a * b).sum())
    }

    /// x += R_s α.
    pub fn add_r_mul(&self, alpha: &[f64], x: &mut [f64]) {
        let nd = self.ndof();
        for k in 0..NR {
            let a = alpha[k];
            x.iter_mut().zip(&self.r[k * nd..(k + 1) * nd]).for_each(|(xi, ri)| *xi += a * ri);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::feti::decomposition::decompose;
    use crate::mesh::boxgen;

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    fn norm(v: &[f64]) -> f64 {
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
            let sys = SubdomainSystem::new(&mesh, sd, i, lame, OrderingKind::Metis, vec![0.0; nd]).unwrap();
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

    #[test]
    fn collinear_nodes_have_no_fixing_dofs() {
        let coords: Vec<[f64; 3]> = (0..4).map(|i| [i as f64, 0.0, 0.0]).collect();
        let r = rigid_modes(&coords);
        // the rotation about x vanishes on the line: R has rank 5 there
        assert!(fixing_dofs(&coords, &r).is_none());
    }
}
