//! The FETI preconditioner of the whole TFETI dual (docs/method.md, "TFETI and H-TFETI": the FETI preconditioner): with the scaled
//! B̃ = (BΔBᵀ)⁻¹BΔ (Δ = diag(Δ_s), Δ_s = μ_min/μ_s the stiffness weighting of subdomain s;
//! for one material B̃ = (BBᵀ)⁻¹B),
//!
//! ```text
//! M⁻¹ = Σ_s B̃_s S_s B̃_sᵀ = (BΔBᵀ)⁻¹ (Σ_s Δ_s² B_s S_s B_sᵀ) (BΔBᵀ)⁻¹,
//! ```
//!
//! S_s the Schur complement of K_s onto the DOFs its rows of B touch (gluing, Dirichlet and
//! contact rows; Dirichlet) or K_s's block there (lumped). BΔBᵀ is block-diagonal over groups
//! of rows that share DOFs ([`Scaling`]); with orthonormal gluing and unit Dirichlet rows most
//! groups are diagonal, so only the groups around contact nodes (and chain gluing) need a
//! gather. Mortar contact rows share master nodes, so all rows of a non-matching interface form
//! one group: a group of more than [`DENSE_MAX`] rows is held as a sparse Cholesky factor of its
//! block instead of a dense inverse. The solver applies it as P M⁻¹ P with the orthogonal
//! projector of its coarse space ([`crate::qp::Coarse`]).

use super::constraints::Constraints;
use super::distribution::Distribution;
use crate::comm::Comm;
use crate::error::{Error, Result};
use crate::linalg::cholesky::{Cholesky, Ordering};
use crate::linalg::sparse::SymCsc;

/// The largest group of rows whose block of BΔBᵀ is inverted densely.
pub const DENSE_MAX: usize = 256;

/// The largest group of rows whose singular block (rows that repeat each other) is taken by its
/// dense pseudo-inverse; a larger one is an error.
pub const PSEUDO_MAX: usize = 2048;

/// Eigenvalues of a singular group's block below this fraction of its largest are its null space.
const PSEUDO_TOL: f64 = 1e-12;

/// The inverse of one group's block of BΔBᵀ.
enum GroupInverse {
    /// Row-major k × k.
    Dense(Vec<f64>),
    /// The block's sparse LLᵀ.
    Sparse(Cholesky),
}

/// (BΔBᵀ)⁻¹ over the groups of rows that share DOFs, Δ = diag(Δ_s) the subdomains' weights:
/// a group whose block is diagonal (one row, or orthonormal rows) is a scale per row, applied
/// locally; the others (around contact nodes, chain gluing) are held whole by every rank (B is
/// replicated) and applied to gathered values.
pub struct Scaling {
    /// Per subdomain, Δ_s.
    pub weight: Vec<f64>,
    /// Per owned row: 1/(BΔBᵀ)_rr for the rows of diagonal groups (0 for a zero row).
    diag: Vec<f64>,
    /// Global rows of the other groups, ascending.
    rows: Vec<usize>,
    /// The owned rows among them: (owned index, position in `rows`).
    mine: Vec<(usize, usize)>,
    /// Per such group: positions in `rows` and the inverse of its block.
    groups: Vec<(Vec<usize>, GroupInverse)>,
}

impl Scaling {
    /// The groups of BΔBᵀ from the constraint rows of every subdomain; `weight[s]` = Δ_s;
    /// `owned`: this rank's rows (global, as in its dual vectors).
    pub fn new(cons: &Constraints, weight: Vec<f64>, owned: &[usize]) -> Result<Scaling> {
        let n = cons.layout.dim();
        // rows sharing a DOF: BΔBᵀ entries and union-find
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        let mut entries: Vec<(usize, usize, f64)> = Vec::new();
        for (rows, &w) in cons.rows.iter().zip(&weight) {
            let mut by_dof: std::collections::BTreeMap<usize, Vec<(usize, f64)>> = Default::default();
            for &(r, j, c) in rows.iter().filter(|x| x.2 != 0.0) {
                by_dof.entry(j).or_default().push((r, c));
            }
            for list in by_dof.values() {
                for &(r1, c1) in list {
                    for &(r2, c2) in list {
                        entries.push((r1, r2, w * c1 * c2));
                    }
                    let (a, b) = (find(&mut parent, r1), find(&mut parent, list[0].0));
                    parent[a] = b;
                }
            }
        }
        let mut members: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for r in 0..n {
            let root = find(&mut parent, r);
            members.entry(root).or_default().push(r);
        }
        let mut block: std::collections::HashMap<(usize, usize), f64> = Default::default();
        for (a, b, v) in entries {
            *block.entry((a, b)).or_insert(0.0) += v;
        }
        let mut diag = vec![0.0; n];
        let mut dense: Vec<(Vec<usize>, GroupInverse)> = Vec::new();
        let singular = |rows: &[usize]| {
            let shown: Vec<String> = rows.iter().take(8).map(|r| r.to_string()).collect();
            let more = if rows.len() > 8 { format!(", … ({} rows)", rows.len()) } else { String::new() };
            Error::numerical("the FETI preconditioner's scaling", format!("BBᵀ is singular on the rows [{}{more}]: B lacks full row rank", shown.join(", ")))
        };
        for rows in members.into_values() {
            let k = rows.len();
            if k > DENSE_MAX {
                if let Some(chol) = sparse_block(&rows, &block) {
                    dense.push((rows, GroupInverse::Sparse(chol)));
                    continue;
                }
                if k > PSEUDO_MAX {
                    return Err(singular(&rows));
                }
            }
            let m: Vec<f64> = (0..k * k).map(|p| block.get(&(rows[p / k], rows[p % k])).copied().unwrap_or(0.0)).collect();
            let scale = m.iter().map(|v| v.abs()).fold(0.0, f64::max);
            if (0..k * k).all(|p| p / k == p % k || m[p].abs() <= 1e-14 * scale) {
                // a zero row (a contact row on held DOFs only) keeps 0: M is zero there too
                for (a, &r) in rows.iter().enumerate() {
                    diag[r] = if m[a * k + a] > 0.0 { 1.0 / m[a * k + a] } else { 0.0 };
                }
                continue;
            }
            // rows that repeat each other (e.g. mortar rows at slave nodes a Dirichlet face holds,
            // acting on fewer free master DOFs than there are rows): the pseudo-inverse on the
            // rows' range, where the dual's residual lies when the constraints are consistent
            // (a factorization of a singular block can succeed on round-off pivots: an inverse
            // beyond 1/PSEUDO_TOL of the block's scale is taken as singular too)
            let regular = inverse(&m, k).filter(|inv| inv.iter().fold(0.0f64, |a, v| a.max(v.abs())) * scale * PSEUDO_TOL <= 1.0);
            let inv = regular.or_else(|| pseudo_inverse(&m, k)).ok_or_else(|| singular(&rows))?;
            dense.push((rows, GroupInverse::Dense(inv)));
        }
        let mut all: Vec<usize> = dense.iter().flat_map(|g| g.0.iter().copied()).collect();
        all.sort_unstable();
        let groups = dense.into_iter().map(|(rows, inv)| (rows.iter().map(|r| all.binary_search(r).expect("listed")).collect(), inv)).collect();
        let mine = owned.iter().enumerate().filter_map(|(i, r)| all.binary_search(r).ok().map(|p| (i, p))).collect();
        let diag = owned.iter().map(|&r| diag[r]).collect();
        Ok(Scaling { weight, diag, rows: all, mine, groups })
    }

    /// x ← (BΔBᵀ)⁻¹ x on owned vectors: diagonal groups in place; the rows of the others are
    /// gathered on every rank (one contributor per entry: exact), multiplied, and each rank
    /// keeps its own.
    pub fn apply<C: Comm>(&self, dist: &Distribution<'_, C>, x: &mut [f64]) {
        let mut buf = vec![0.0; self.rows.len()];
        for &(i, p) in &self.mine {
            buf[p] = x[i];
        }
        // the rows of dense groups have diag 0 and are written back below
        x.iter_mut().zip(&self.diag).for_each(|(v, d)| *v *= d);
        if self.rows.is_empty() {
            return;
        }
        dist.reduce(&mut buf);
        let mut out = vec![0.0; buf.len()];
        for (pos, inv) in &self.groups {
            let k = pos.len();
            match inv {
                GroupInverse::Dense(inv) => {
                    for (a, &pa) in pos.iter().enumerate() {
                        out[pa] = pos.iter().enumerate().map(|(b, &pb)| inv[a * k + b] * buf[pb]).sum();
                    }
                }
                GroupInverse::Sparse(chol) => {
                    let mut y: Vec<f64> = pos.iter().map(|&p| buf[p]).collect();
                    chol.solve_in_place(&mut y);
                    for (&p, v) in pos.iter().zip(y) {
                        out[p] = v;
                    }
                }
            }
        }
        for &(i, p) in &self.mine {
            x[i] = out[p];
        }
    }
}

/// The sparse LLᵀ (AMD ordering) of the block of BΔBᵀ on `rows` (ascending), from its entries;
/// `None` when it is not positive definite.
fn sparse_block(rows: &[usize], block: &std::collections::HashMap<(usize, usize), f64>) -> Option<Cholesky> {
    let k = rows.len();
    let pos = |r: usize| rows.binary_search(&r).ok();
    let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); k];
    for (&(a, b), &v) in block {
        if let (Some(i), Some(j)) = (pos(a), pos(b)) {
            if i >= j && v != 0.0 {
                cols[j].push((i, v));
            }
        }
    }
    let mut a = SymCsc { n: k, col_ptr: vec![0], row_idx: Vec::new(), values: Vec::new() };
    for mut c in cols {
        c.sort_unstable_by_key(|e| e.0);
        a.row_idx.extend(c.iter().map(|e| e.0));
        a.values.extend(c.iter().map(|e| e.1));
        a.col_ptr.push(a.row_idx.len());
    }
    Cholesky::factorize(&a, Ordering::Amd).ok()
}

/// The inverse of a small symmetric positive definite matrix (row-major k × k); `None` when it
/// is not positive definite.
fn inverse(m: &[f64], k: usize) -> Option<Vec<f64>> {
    let a = faer::Mat::<f64>::from_fn(k, k, |i, j| m[i * k + j]);
    use faer::linalg::solvers::DenseSolveCore;
    let inv = a.llt(faer::Side::Lower).ok()?.inverse();
    Some((0..k * k).map(|p| inv[(p / k, p % k)]).collect())
}

/// The pseudo-inverse of the symmetric positive semidefinite k × k block `m` (row-major):
/// U diag(1/sᵢ) Uᵀ over the eigenvalues above [`PSEUDO_TOL`] × the largest; `None` where the
/// block has a negative eigenvalue beyond that tolerance or none above it.
fn pseudo_inverse(m: &[f64], k: usize) -> Option<Vec<f64>> {
    let a = faer::Mat::<f64>::from_fn(k, k, |i, j| m[i * k + j]);
    let eig = a.self_adjoint_eigen(faer::Side::Lower).ok()?;
    let (vals, vecs) = (eig.S(), eig.U());
    let top = (0..k).map(|i| vals[i].abs()).fold(0.0, f64::max);
    if !(top > 0.0) || (0..k).any(|i| vals[i] < -PSEUDO_TOL * top) {
        return None;
    }
    let kept: Vec<usize> = (0..k).filter(|&i| vals[i] > PSEUDO_TOL * top).collect();
    Some((0..k * k).map(|p| kept.iter().map(|&e| vecs[(p / k, e)] * vecs[(p % k, e)] / vals[e]).sum()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pseudo-inverse of a singular Gram matrix (rows that repeat each other) is one:
    /// M M⁺ M = M and M⁺ M M⁺ = M⁺ (faer's LLᵀ of this M succeeds on a round-off pivot: its
    /// inverse's entries are beyond 1/[`PSEUDO_TOL`] of M's, which the scaling takes as singular).
    #[test]
    fn pseudo_inverse_of_repeated_rows() {
        // B: 3 rows over 2 columns, the third the sum of the first two
        let b = [[1.0, 0.5], [0.25, 2.0], [1.25, 2.5]];
        let k = 3;
        let m: Vec<f64> = (0..k * k).map(|p| (0..2).map(|j| b[p / k][j] * b[p % k][j]).sum()).collect();
        let big = inverse(&m, k).map_or(f64::INFINITY, |inv| inv.iter().fold(0.0f64, |a, v| a.max(v.abs())));
        assert!(big * m.iter().fold(0.0f64, |a, v| a.max(v.abs())) * PSEUDO_TOL > 1.0, "the LLᵀ inverse is not taken: {big:e}");
        let pinv = pseudo_inverse(&m, k).expect("a pseudo-inverse");
        let mul = |x: &[f64], y: &[f64]| -> Vec<f64> { (0..k * k).map(|p| (0..k).map(|q| x[p / k * k + q] * y[q * k + p % k]).sum()).collect() };
        let (mpm, pmp) = (mul(&mul(&m, &pinv), &m), mul(&mul(&pinv, &m), &pinv));
        let scale = m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(mpm.iter().zip(&m).all(|(x, y)| (x - y).abs() <= 1e-12 * scale), "M M⁺ M ≠ M");
        let pscale = pinv.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(pmp.iter().zip(&pinv).all(|(x, y)| (x - y).abs() <= 1e-12 * pscale), "M⁺ M M⁺ ≠ M⁺");
    }

    /// (BΔBᵀ)⁻¹ as applied equals the dense inverse of BΔBᵀ on the seed scene with contact
    /// (non-trivial groups at the contact nodes, prescribed DOFs among them), for unit and
    /// contrasting weights; so B̃ = (BΔBᵀ)⁻¹BΔ is a left inverse of Bᵀ.
    #[test]
    fn scaling_inverts_b_delta_bt() {
        let (_, d, cons) = crate::feti::seed_fixture(4, 2);
        let comm = crate::comm::SerialComm;
        let dist = Distribution::new(&comm, &cons, &vec![0; d.subdomains.len()]);
        let n = cons.layout.dim();
        for weight in [vec![1.0; d.subdomains.len()], d.subdomains.iter().map(|s| if s.body == 0 { 1.0 } else { 1e-3 }).collect()] {
            let sc = Scaling::new(&cons, weight.clone(), &dist.owned).unwrap();
            assert!(!sc.rows.is_empty(), "contact rows make non-trivial groups");
            // dense BΔBᵀ
            let mut m = vec![0.0; n * n];
            for (rows, &w) in cons.rows.iter().zip(&weight) {
                for &(a, ja, ca) in rows {
                    for &(b, jb, cb) in rows {
                        if ja == jb {
                            m[a * n + b] += w * ca * cb;
                        }
                    }
                }
            }
            let mut s = 3u64;
            let x: Vec<f64> = (0..n)
                .map(|_| {
                    s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
                })
                .collect();
            let mut y = x.clone();
            sc.apply(&dist, &mut y);
            // BΔBᵀ y = x (zero rows: y = 0 there)
            for i in 0..n {
                let v: f64 = (0..n).map(|j| m[i * n + j] * y[j]).sum();
                if m[i * n + i] == 0.0 {
                    assert_eq!(y[i], 0.0);
                } else {
                    assert!((v - x[i]).abs() < 1e-9, "row {i}: {v} vs {}", x[i]);
                }
            }
        }
    }
}
