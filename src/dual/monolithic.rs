//! The paper's dual operator: each body keeps its own stiffness (Dirichlet DOFs eliminated) and
//! its sparse Cholesky factor; B holds the contact rows N (one per pair) and T (two per pair,
//! only with friction). One A-product is Bᵀ (scatter to the bodies), one solve per body, B
//! (gather), and one sum over the ranks: bodies may live on different ranks, the (short) dual
//! vector is replicated.

use super::{add_tangential, gather_rows, scatter_rows, tangential_jump, DualProblem, Recovered};
use crate::comm::Comm;
use crate::contact::pairing::Contact;
use crate::fem::assembly::{BodySystem, DofMap, FIXED};
use crate::linalg::cholesky::Cholesky;
use crate::qp::{Layout, Operator, ProductCounter, Replicated};

/// One body owned by this rank: assembled and factorized.
pub struct LocalBody {
    /// Index of the body.
    pub body: usize,
    /// Its DOFs: free, and prescribed with their values.
    pub dofs: DofMap,
    /// Its assembled system K_ff u_f = f_f.
    pub sys: BodySystem,
    /// The Cholesky factor of its K_ff.
    pub chol: Cholesky,
    /// The free DOFs the factor orders last, in its order (empty: none): the contact DOFs,
    /// whose block of K⁻¹ is then the inverse of the factor's trailing block's LLᵀ.
    pub trailing: Vec<usize>,
}

/// One body on this rank with the entries (row of B, free DOF, coefficient) of B acting on it.
pub struct BodyBlock {
    /// The body, assembled and factorized.
    pub local: LocalBody,
    /// The entries of B on the body: (row of B, free DOF, coefficient).
    pub b: Vec<(usize, usize, f64)>,
    /// The explicit product, when the factor orders B's DOFs last.
    pub dense: Option<Trailing>,
}

/// B K⁻¹ Bᵀ of one body through its factor's trailing block L_bb (B's DOFs ordered last):
/// (K⁻¹)_bb = L_bb⁻ᵀ L_bb⁻¹, so a product is B_b L_bb⁻ᵀ L_bb⁻¹ B_bᵀ — two dense triangular solves
/// of the contact DOFs' size instead of the solves with the whole factor.
pub struct Trailing {
    l: faer::Mat<f64>,
    /// (row of B, position in the block, coefficient).
    b: Vec<(usize, usize, f64)>,
}

impl Trailing {
    /// From a factor whose last DOFs are `trailing` (in order) and B's entries `b` on the body,
    /// if every entry falls in them.
    fn new(local: &LocalBody, b: &[(usize, usize, f64)]) -> Option<Trailing> {
        if local.trailing.is_empty() {
            return None;
        }
        let mut pos = vec![usize::MAX; local.dofs.nfree];
        for (p, &d) in local.trailing.iter().enumerate() {
            pos[d] = p;
        }
        let b: Option<Vec<_>> = b.iter().map(|&(r, j, c)| (pos[j] != usize::MAX).then(|| (r, pos[j], c))).collect();
        Some(Trailing { l: local.chol.trailing_block(local.trailing.len()), b: b? })
    }

    /// y += B_b L_bb⁻ᵀ L_bb⁻¹ B_bᵀ x.
    fn apply_add(&self, x: &[f64], y: &mut [f64]) {
        use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
        let mut z = faer::Mat::<f64>::zeros(self.l.nrows(), 1);
        for &(r, p, c) in &self.b {
            z[(p, 0)] += c * x[r];
        }
        solve_lower_triangular_in_place(self.l.as_ref(), z.as_mut(), faer::Par::Seq);
        solve_upper_triangular_in_place(self.l.transpose(), z.as_mut(), faer::Par::Seq);
        for &(r, p, c) in &self.b {
            y[r] += c * z[(p, 0)];
        }
    }
}

/// A = B K⁻¹ Bᵀ over the bodies of all ranks.
pub struct MonolithicDual<'c, C: Comm> {
    comm: &'c C,
    /// Layout of the multipliers.
    pub layout: Layout,
    /// The bodies on this rank with their blocks of B.
    pub blocks: Vec<BodyBlock>,
    /// c = [d; 0] − B_c u_c (the prescribed values moved to the right) + the last load step's
    /// tangential jump ([`MonolithicDual::set_load`]).
    c: Vec<f64>,
    /// c without the last step's jump.
    c0: Vec<f64>,
    counter: ProductCounter,
    /// Mixed precision, as the TFETI dual's: η of the single-precision
    /// factors and whether the products use them now.
    single: Option<f64>,
    single_now: std::cell::Cell<bool>,
    /// With explicit products ([`Trailing`]) on every rank: the contact DOFs of all blocks.
    explicit: Option<usize>,
}

/// The rows of B (free part) for the body with DOF map `dofs`, and the shift of c by the
/// prescribed values: returns (entries, c_shift) where c_shift\[r\] = Σ coef·u_prescribed.
pub fn body_rows(contact: &Contact, layout: Layout, dofs: &DofMap) -> (Vec<(usize, usize, f64)>, Vec<f64>) {
    let mut entries = Vec::new();
    let mut shift = vec![0.0; layout.dim()];
    let mut add = |row: usize, node: usize, sign: f64, dir: [f64; 3]| {
        if !dofs.nodes.contains(&node) {
            return;
        }
        for c in 0..3 {
            let coef = sign * dir[c];
            if coef == 0.0 {
                continue;
            }
            let d = dofs.local(node, c);
            match dofs.free[d] {
                FIXED => shift[row] += coef * dofs.prescribed[d],
                j => entries.push((row, j, coef)),
            }
        }
    };
    for i in 0..contact.len() {
        let rows = std::iter::once((layout.normal(i), contact.normal[i]))
            .chain(layout.friction.then(|| [(layout.tangent(i, 0), contact.t1[i]), (layout.tangent(i, 1), contact.t2[i])]).into_iter().flatten());
        for (k, (row, dir)) in rows.enumerate() {
            if k > 0 && contact.is_void(i, k - 1) {
                continue;
            }
            for &(v, coef) in contact.row(i) {
                add(row, v, coef, dir);
            }
        }
    }
    (entries, shift)
}

impl<'c, C: Comm> MonolithicDual<'c, C> {
    /// The operator over this rank's factorized bodies, and b = B K⁻¹ f − c.
    pub fn new(comm: &'c C, contact: &Contact, bodies: Vec<LocalBody>) -> (Self, Vec<f64>) {
        let layout = Layout::contact(contact.len(), contact.has_friction());
        let mut blocks = bodies
            .into_iter()
            .map(|local| {
                let (b, _) = body_rows(contact, layout, &local.dofs);
                let dense = Trailing::new(&local, &b);
                BodyBlock { local, b, dense }
            })
            .collect::<Vec<BodyBlock>>();
        // explicit products only where every rank's bodies have their blocks (a decision all
        // ranks share: the products' reductions must match)
        let mut v = [if blocks.iter().all(|blk| blk.dense.is_some()) { 0.0 } else { 1.0 }];
        comm.max_f64(&mut v);
        let mut dofs = [blocks.iter().filter_map(|blk| blk.dense.as_ref()).map(|d| d.l.nrows() as f64).sum::<f64>()];
        comm.sum_f64(&mut dofs);
        let explicit = if v[0] == 0.0 {
            Some(dofs[0] as usize)
        } else {
            blocks.iter_mut().for_each(|blk| blk.dense = None);
            None
        };
        let mut dual = MonolithicDual {
            comm,
            layout,
            blocks,
            c: vec![],
            c0: vec![],
            counter: ProductCounter::default(),
            single: None,
            single_now: Default::default(),
            explicit,
        };
        dual.set_c(contact, None);
        let rhs = dual.rhs();
        (dual, rhs)
    }

    /// A new load state on the same bodies and constrained DOFs (a step of a load path): each
    /// local body's prescribed values and f (`state` maps the body to them), and the tangential
    /// rows of c moved by `jump` (B_T u of the last step, [`MonolithicDual::jump`]): friction
    /// acts on the slip increment. Returns b.
    pub fn set_load(&mut self, contact: &Contact, mut state: impl FnMut(&LocalBody) -> (DofMap, Vec<f64>), jump: &[f64]) -> Vec<f64> {
        for blk in &mut self.blocks {
            let (dofs, f) = state(&blk.local);
            blk.local.dofs = dofs;
            blk.local.sys.f = f;
        }
        self.set_c(contact, Some(jump));
        self.rhs()
    }

    /// B u on the tangential rows (prescribed parts included, 0 on the normal rows) from the
    /// gap c − Bu of a recovered solution: what the next load step's slip is measured from.
    pub fn jump(&self, gap: &[f64]) -> Vec<f64> {
        tangential_jump(self.layout, &self.c, &self.c0, gap)
    }

    /// c0 = [d; 0] − B_c u_c from the bodies' prescribed values (summed over the ranks) and
    /// c = c0 + `jump` on the tangential rows.
    fn set_c(&mut self, contact: &Contact, jump: Option<&[f64]>) {
        let mut shift = vec![0.0; self.layout.dim()];
        for blk in &self.blocks {
            for (a, v) in shift.iter_mut().zip(body_rows(contact, self.layout, &blk.local.dofs).1) {
                *a += v;
            }
        }
        self.comm.sum_f64(&mut shift);
        let mut c = vec![0.0; self.layout.dim()];
        for (i, g) in contact.gap.iter().enumerate() {
            c[self.layout.normal(i)] = *g;
        }
        for (ci, s) in c.iter_mut().zip(&shift) {
            *ci -= s;
        }
        self.c0 = c.clone();
        if let Some(j) = jump {
            add_tangential(self.layout, j, &mut c);
        }
        self.c = c;
    }

    /// c on every row (replicated): the normal rows' gap minus the prescribed shift, the
    /// tangential rows' −shift (0 unless prescribed DOFs touch the pair); the constraint is
    /// B u ≤ c on the normal rows.
    pub fn c(&self) -> &[f64] {
        &self.c
    }

    /// Bᵀx restricted to each local body.
    fn scatter(&self, x: &[f64]) -> Vec<Vec<f64>> {
        self.blocks.iter().map(|blk| scatter_rows(&blk.b, x, blk.local.dofs.nfree)).collect()
    }

    /// Σ over bodies and ranks of B_b z_b.
    fn gather(&self, z: &[Vec<f64>], y: &mut [f64]) {
        gather_rows(self.comm, self.blocks.iter().zip(z).map(|(blk, zb)| (blk.b.as_slice(), zb.as_slice())), y);
    }

    /// b = B K⁻¹ f − c.
    fn rhs(&self) -> Vec<f64> {
        let z: Vec<Vec<f64>> = self
            .blocks
            .iter()
            .map(|blk| {
                let mut v = blk.local.sys.f.clone();
                blk.local.chol.solve_in_place(&mut v);
                v
            })
            .collect();
        let mut b = vec![0.0; self.layout.dim()];
        self.gather(&z, &mut b);
        b.iter_mut().zip(&self.c).for_each(|(bi, ci)| *bi -= ci);
        b
    }

    /// u_b = K_b⁻¹(f_b − B_bᵀλ) for each local body, as free DOF vectors, with the right-hand
    /// sides f_b − B_bᵀλ.
    fn solve_bodies(&self, lambda: &[f64]) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let mut rhs = self.scatter(lambda);
        for (blk, zb) in self.blocks.iter().zip(&mut rhs) {
            for (v, f) in zb.iter_mut().zip(&blk.local.sys.f) {
                *v = f - *v;
            }
        }
        let u = self
            .blocks
            .iter()
            .zip(&rhs)
            .map(|(blk, f)| {
                let mut x = f.clone();
                blk.local.chol.solve_in_place(&mut x);
                x
            })
            .collect();
        (u, rhs)
    }
}

impl<C: Comm> DualProblem for MonolithicDual<'_, C> {
    /// u = K⁻¹(f − Bᵀλ) per body and the gap c − Bu (replicated).
    fn recover(&self, lambda: &[f64]) -> Recovered {
        let (u, rhs) = self.solve_bodies(lambda);
        let mut gap = vec![0.0; self.layout.dim()];
        self.gather(&u, &mut gap);
        gap.iter_mut().zip(&self.c).for_each(|(g, c)| *g = c - *g);
        Recovered { u, rhs, lambda: lambda.to_vec(), gap, alpha: vec![], feasibility: 0.0 }
    }
}

impl<C: Comm> Operator for MonolithicDual<'_, C> {
    /// The (short) dual vector is replicated on every rank.
    type Space = Replicated;
    fn space(&self) -> &Replicated {
        &Replicated
    }

    fn dim(&self) -> usize {
        self.layout.dim()
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.counter.tick();
        self.apply_as(x, y, self.single_now.get());
    }

    fn products(&self) -> usize {
        self.counter.get()
    }

    /// Products with single-precision factors while their measured error η is within `rel`.
    fn allow_error(&self, rel: f64) -> bool {
        self.single_now.set(self.single.is_some_and(|eta| eta <= rel));
        self.single_now.get()
    }

    /// dᵢ = Σ over the bodies of Σ_j Bᵢⱼ² / (K_ff)_jj, summed over the ranks.
    fn diagonal_estimate(&self) -> Option<Vec<f64>> {
        let mut d = vec![0.0; self.layout.dim()];
        for blk in &self.blocks {
            let k = &blk.local.sys.k;
            for &(i, j, c) in &blk.b {
                let kjj = k.position(j, j).map_or(0.0, |q| k.values[q]);
                if kjj > 0.0 {
                    d[i] += c * c / kjj;
                }
            }
        }
        self.comm.sum_f64(&mut d);
        Some(d)
    }
}

impl<C: Comm> MonolithicDual<'_, C> {
    /// y = B K⁻¹ Bᵀ x (not counted), with the single-precision factors when `single`.
    fn apply_as(&self, x: &[f64], y: &mut [f64], single: bool) {
        if self.explicit() {
            y.fill(0.0);
            for blk in &self.blocks {
                blk.dense.as_ref().expect("dense").apply_add(x, y);
            }
            self.comm.sum_f64(y);
            return;
        }
        let mut z = self.scatter(x);
        for (blk, zb) in self.blocks.iter().zip(&mut z) {
            if single {
                blk.local.chol.solve_in_place_single(zb);
            } else {
                blk.local.chol.solve_in_place(zb);
            }
        }
        self.gather(&z, y);
    }

    /// Keeps single-precision copies of the local factors and measures η = ‖Ãv − Av‖/‖Av‖ on
    /// a fixed vector (two uncounted products). Returns η; none when the products are explicit
    /// ([`Trailing`]: nothing to save).
    pub fn keep_single(&mut self) -> Option<f64> {
        if self.explicit() {
            return None;
        }
        for blk in &mut self.blocks {
            blk.local.chol.keep_single();
        }
        let v: Vec<f64> = (0..self.layout.dim()).map(crate::linalg::probe).collect();
        let (mut ad, mut as_) = (vec![0.0; v.len()], vec![0.0; v.len()]);
        self.apply_as(&v, &mut ad, false);
        self.apply_as(&v, &mut as_, true);
        let norm = |a: &[f64]| a.iter().map(|x| x * x).sum::<f64>().sqrt();
        let d: Vec<f64> = ad.iter().zip(&as_).map(|(a, b)| a - b).collect();
        let eta = norm(&d) / norm(&ad).max(f64::MIN_POSITIVE);
        self.single = Some(eta);
        Some(eta)
    }

    /// Whether every product goes through the bodies' trailing blocks ([`Trailing`]), the same
    /// on every rank.
    pub fn explicit(&self) -> bool {
        self.explicit.is_some()
    }

    /// The contact DOFs of all trailing blocks, with explicit products.
    pub fn explicit_dofs(&self) -> Option<usize> {
        self.explicit
    }

    /// η of [`MonolithicDual::keep_single`], when single-precision factors are kept.
    pub fn single_error(&self) -> Option<f64> {
        self.single
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::comm::SerialComm;
    use crate::pipeline::{assemble_and_factorize, Timings};
    use crate::scene::{self, OrderingKind};

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// The seed scene at N = 5, with a prescribed (non-zero) displacement on a contact node's
    /// body to exercise the shift of c.
    fn seed(friction: bool) -> (crate::model::Model, Vec<LocalBody>) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("run/seed.toml");
        let mut sets = vec!["mesh.n=5".to_string(), "dirichlet.1.value=[1e-4, -2e-4, 3e-5]".to_string()];
        if !friction {
            sets.push("contact.pair.0.friction={type=\"none\"}".into());
        }
        let ls = scene::load(&path, &sets).unwrap();
        let model = crate::model::build(&ls).unwrap();
        let bodies = assemble_and_factorize(&SerialComm, &model, OrderingKind::Metis, true, &mut Timings::default()).unwrap();
        (model, bodies)
    }

    #[test]
    fn explicit_products_are_the_solves_with_the_whole_factor() {
        // contact nodes ordered last: B L_bb⁻ᵀ L_bb⁻¹ Bᵀ against B K⁻¹ Bᵀ by whole solves
        for friction in [true, false] {
            let (model, bodies) = seed(friction);
            let contact = model.pairs.as_ref().unwrap();
            let sparse = assemble_and_factorize(&SerialComm, &model, OrderingKind::Metis, false, &mut Timings::default()).unwrap();
            let (de, b1) = MonolithicDual::new(&SerialComm, contact, bodies);
            let (sp, b2) = MonolithicDual::new(&SerialComm, contact, sparse);
            assert!(de.explicit() && !sp.explicit());
            let n = de.dim();
            let x: Vec<f64> = (0..n).map(crate::linalg::probe).collect();
            let (mut y1, mut y2) = (vec![0.0; n], vec![0.0; n]);
            de.apply(&x, &mut y1);
            sp.apply(&x, &mut y2);
            let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
            let d: Vec<f64> = y1.iter().zip(&y2).map(|(a, b)| a - b).collect();
            assert!(norm(&d) <= 1e-12 * norm(&y2), "explicit and whole-factor products differ by {:e} of {:e}", norm(&d), norm(&y2));
            let db: Vec<f64> = b1.iter().zip(&b2).map(|(a, b)| a - b).collect();
            assert!(norm(&db) <= 1e-12 * norm(&b2));
            // no single-precision copies where the products are explicit
            let mut de = de;
            assert!(de.keep_single().is_none() && de.single_error().is_none());
        }
    }

    #[test]
    fn a_is_symmetric_positive_definite_and_consistent_with_the_primal() {
        for friction in [true, false] {
            let (model, bodies) = seed(friction);
            let contact = model.pairs.as_ref().unwrap();
            let (dual, b) = MonolithicDual::new(&SerialComm, contact, bodies);
            let n = dual.dim();
            assert_eq!(n, if friction { 75 } else { 25 });
            let mut s = 7u64;
            let x: Vec<f64> = (0..n).map(|_| lcg(&mut s)).collect();
            let y: Vec<f64> = (0..n).map(|_| lcg(&mut s)).collect();
            let (mut ax, mut ay) = (vec![0.0; n], vec![0.0; n]);
            dual.apply(&x, &mut ax);
            dual.apply(&y, &mut ay);
            let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| p * q).sum::<f64>();
            let (xay, yax) = (dot(&x, &ay), dot(&y, &ax));
            assert!((xay - yax).abs() <= 1e-12 * xay.abs().max(yax.abs()), "{xay} vs {yax}");
            assert!(dot(&x, &ax) > 0.0);
            assert_eq!(dual.products(), 2);
            // r(λ) = Aλ − b = −(Bu − c) with u = K⁻¹(f − Bᵀλ): evaluate Bu − c on the primal side
            let rec = dual.recover(&x);
            let u = rec.u;
            for (g, (axi, bi)) in rec.gap.iter().zip(ax.iter().zip(&b)) {
                // c − Bu = Aλ − b
                assert!((g - (axi - bi)).abs() <= 1e-9 * b.iter().fold(0.0f64, |a, v| a.max(v.abs())));
            }
            let mut full = vec![[0.0; 3]; model.mesh.nodes.len()];
            for (blk, ub) in dual.blocks.iter().zip(&u) {
                let r = blk.local.dofs.nodes.clone();
                for (k, v) in blk.local.dofs.expand(ub).into_iter().enumerate() {
                    full[r.start + k] = v;
                }
                // K u = f − Bᵀλ on the free DOFs
                let ku = blk.local.sys.k.mul(ub);
                let mut btx = vec![0.0; ub.len()];
                for &(row, j, c) in &blk.b {
                    btx[j] += c * x[row];
                }
                for j in 0..ub.len() {
                    assert!((ku[j] - (blk.local.sys.f[j] - btx[j])).abs() <= 1e-9 * (1.0 + blk.local.sys.f[j].abs()));
                }
            }
            let rel = |i: usize, dir: [f64; 3]| contact.row(i).iter().map(|&(v, coef)| (0..3).map(|c| coef * full[v][c] * dir[c]).sum::<f64>()).sum::<f64>();
            let scale = b.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for i in 0..contact.len() {
                let r = ax[i] - b[i];
                let bu_c = rel(i, contact.normal[i]) - contact.gap[i];
                assert!((r + bu_c).abs() <= 1e-9 * scale, "normal row {i}: {r} vs {}", -bu_c);
                if friction {
                    for (k, t) in [contact.t1[i], contact.t2[i]].into_iter().enumerate() {
                        let row = dual.layout.tangent(i, k);
                        assert!((ax[row] - b[row] + rel(i, t)).abs() <= 1e-9 * scale);
                    }
                }
            }
        }
    }
}
