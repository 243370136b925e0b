//! The Schur complement `S = K_bb − K_bi K_ii⁻¹ K_ib` of a symmetric stiffness K onto a set of
//! boundary DOFs b (those a piece's rows of B touch) — the local part of the FETI Dirichlet
//! preconditioner — applied matrix-free (a K_ii solve per application) or held as an explicit
//! dense matrix from a partial factorization (b ordered last: the trailing block of the
//! Cholesky factor of K + αI_b gives S + αI), and its cheap stand-ins K_bb (lumped) and
//! diag(K_bb) (superlumped).
//! K may be singular (a floating TFETI subdomain); K_ii must be positive definite, which holds
//! once the boundary DOFs hold the piece in place.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, CholeskySymbolicParams, SymmetricOrdering};
use faer::sparse::linalg::SupernodalThreshold;
use faer::{Mat, Par, Side};

use super::cholesky::{Cholesky, Ordering};
use super::sparse::SymCsc;
use crate::error::{Error, Result};

/// How S is represented.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Form {
    /// K_bb (the lumped preconditioner), held on the boundary DOFs alone.
    Lumped,
    /// diag(K_bb) (the superlumped preconditioner).
    Superlumped,
    /// S applied through a K_ii solve.
    MatrixFree,
    /// S as a dense matrix on the boundary DOFs.
    Dense,
}

/// S (Dirichlet) or K_bb (lumped) of one piece.
pub struct Schur {
    /// Interior DOF of each DOF (`usize::MAX` for boundary DOFs).
    interior: Vec<usize>,
    /// Boundary DOFs, ascending.
    pub boundary: Vec<usize>,
    op: Op,
}

/// What a [`Form`] keeps.
enum Op {
    /// K_bb (lower triangle, in the order of `boundary`).
    Lumped(SymCsc),
    /// diag(K_bb), in the order of `boundary`.
    Diagonal(Vec<f64>),
    /// K and K_ii's factor (`None` when every DOF is on the boundary).
    MatrixFree(SymCsc, Option<Cholesky>),
    /// S on the boundary DOFs, in the order of `boundary`.
    Dense(Mat<f64>),
}

impl Schur {
    /// The operator of K (lower triangle) onto the DOFs `boundary` (any order, no repeats) in
    /// the given form.
    pub fn new(k: &SymCsc, boundary: &[usize], form: Form) -> Result<Schur> {
        let n = k.n;
        let mut boundary = boundary.to_vec();
        boundary.sort_unstable();
        boundary.dedup();
        let mut interior = vec![0; n];
        let mut ni = 0;
        let mut b = boundary.iter().peekable();
        for (d, slot) in interior.iter_mut().enumerate() {
            if b.peek() == Some(&&d) {
                b.next();
                *slot = usize::MAX;
            } else {
                *slot = ni;
                ni += 1;
            }
        }
        let op = match form {
            Form::Lumped => {
                let mut at = vec![usize::MAX; n];
                for (i, &d) in boundary.iter().enumerate() {
                    at[d] = i;
                }
                Op::Lumped(k.principal(&at))
            }
            Form::Superlumped => Op::Diagonal(boundary.iter().map(|&d| k.position(d, d).map_or(0.0, |p| k.values[p])).collect()),
            Form::MatrixFree => {
                let chol = if ni > 0 { Some(Cholesky::factorize(&k.principal(&interior), Ordering::Amd)?) } else { None };
                Op::MatrixFree(k.clone(), chol)
            }
            Form::Dense => Op::Dense(dense_schur(k, &interior, &boundary)?),
        };
        Ok(Schur { interior, boundary, op })
    }

    /// x ← S x for x zero off the boundary (the result is zero off the boundary too).
    pub fn apply_in_place(&self, x: &mut [f64]) {
        let (k, chol) = match &self.op {
            Op::Lumped(kbb) => {
                let xb: Vec<f64> = self.boundary.iter().map(|&d| x[d]).collect();
                let yb = kbb.mul(&xb);
                x.fill(0.0);
                for (&d, y) in self.boundary.iter().zip(yb) {
                    x[d] = y;
                }
                return;
            }
            Op::Diagonal(kd) => {
                let yb: Vec<f64> = self.boundary.iter().zip(kd).map(|(&d, v)| v * x[d]).collect();
                x.fill(0.0);
                for (&d, y) in self.boundary.iter().zip(yb) {
                    x[d] = y;
                }
                return;
            }
            Op::Dense(s) => {
                let xb = Mat::from_fn(self.boundary.len(), 1, |i, _| x[self.boundary[i]]);
                let yb = s * &xb;
                x.fill(0.0);
                for (i, &d) in self.boundary.iter().enumerate() {
                    x[d] = yb[(i, 0)];
                }
                return;
            }
            Op::MatrixFree(k, chol) => (k, chol),
        };
        let y = k.mul(x);
        x.fill(0.0);
        for &d in &self.boundary {
            x[d] = y[d];
        }
        if let Some(chol) = chol {
            // w = K_ii⁻¹ (K x)_i, then subtract (K w)_b
            let mut t = vec![0.0; chol.n()];
            for (d, &i) in self.interior.iter().enumerate() {
                if i != usize::MAX {
                    t[i] = y[d];
                }
            }
            chol.solve_in_place(&mut t);
            let mut w = vec![0.0; k.n];
            for (d, &i) in self.interior.iter().enumerate() {
                if i != usize::MAX {
                    w[d] = t[i];
                }
            }
            let kw = k.mul(&w);
            for &d in &self.boundary {
                x[d] -= kw[d];
            }
        }
    }
}

/// S = K_bb − K_bi K_ii⁻¹ K_ib as a dense matrix (rows and columns in the order of `boundary`)
/// from one sparse factorization of K̂ = K + αI_b with the interior DOFs first (AMD order of
/// K_ii) and the boundary DOFs last: K̂'s factor ends in the block L_bb with L_bb L_bbᵀ = S + αI
/// (α = the largest diagonal entry of K_bb, which makes K̂ positive definite for a floating
/// piece too); the supernodal factor is read block by block.
fn dense_schur(k: &SymCsc, interior: &[usize], boundary: &[usize]) -> Result<Mat<f64>> {
    let fail = |r: String| Error::numerical("dense Schur complement", r);
    let n = k.n;
    let nb = boundary.len();
    let ni = n - nb;
    // the interior's fill-reducing order: AMD of K_ii
    let interior_dofs: Vec<usize> = (0..n).filter(|&d| interior[d] != usize::MAX).collect();
    let kii = k.principal(interior);
    let mut fwd: Vec<usize> = if ni > 0 {
        let sym = factorize_symbolic_cholesky(kii.as_faer().symbolic(), Side::Lower, SymmetricOrdering::Amd, CholeskySymbolicParams::default())
            .map_err(|e| fail(format!("ordering K_ii: {e:?}")))?;
        match sym.perm() {
            Some(p) => p.arrays().0.iter().map(|&i| interior_dofs[i]).collect(),
            None => interior_dofs.clone(),
        }
    } else {
        vec![]
    };
    fwd.extend_from_slice(boundary);
    let mut inv = vec![0; n];
    for (new, &old) in fwd.iter().enumerate() {
        inv[old] = new;
    }
    let mut kh = k.clone();
    let alpha = boundary.iter().filter_map(|&d| k.position(d, d).map(|p| k.values[p].abs())).fold(0.0f64, f64::max).max(f64::MIN_POSITIVE);
    for &d in boundary {
        let p = kh.position(d, d).ok_or_else(|| fail(format!("no diagonal entry at DOF {d}")))?;
        kh.values[p] += alpha;
    }
    let params = CholeskySymbolicParams { supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL, ..Default::default() };
    let sym = factorize_symbolic_cholesky(kh.as_faer().symbolic(), Side::Lower, SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, n)), params)
        .map_err(|e| fail(format!("symbolic analysis: {e:?}")))?;
    let par = Par::Seq;
    let mut values = vec![0.0; sym.len_val()];
    let mut mem = MemBuffer::try_new(sym.factorize_numeric_llt_scratch::<f64>(par, Default::default())).map_err(|_| fail("out of memory".into()))?;
    sym.factorize_numeric_llt(&mut values, kh.as_faer(), Side::Lower, LltRegularization::default(), par, MemStack::new(&mut mem), Default::default())
        .map_err(|e| fail(format!("K + αI_b is not positive definite ({e:?}); is the piece held by its boundary DOFs?")))?;
    let l = super::cholesky::trailing_block(&sym, &values, nb);
    let mut s = &l * l.transpose();
    for i in 0..nb {
        s[(i, i)] -= alpha;
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schur_complement_inverts_the_boundary_block_of_the_inverse() {
        // S = ((K⁻¹)_bb)⁻¹: S (K⁻¹ e_b)_b = e_b for a unit vector on the boundary
        let k = crate::linalg::cholesky::tests::laplace(7);
        let boundary = [0, 3, 6];
        let s = Schur::new(&k, &boundary, Form::MatrixFree).unwrap();
        let chol = Cholesky::factorize(&k, Ordering::Amd).unwrap();
        for &e in &boundary {
            let mut kinv_e = vec![0.0; 7];
            kinv_e[e] = 1.0;
            chol.solve_in_place(&mut kinv_e);
            let mut x = vec![0.0; 7];
            for &d in &boundary {
                x[d] = kinv_e[d];
            }
            s.apply_in_place(&mut x);
            for d in 0..7 {
                let want = if d == e { 1.0 } else { 0.0 };
                assert!((x[d] - want).abs() < 1e-12, "S (K⁻¹)_bb e{e} at {d}: {} (want {want})", x[d]);
            }
        }
        // lumped: K_bb
        let l = Schur::new(&k, &boundary, Form::Lumped).unwrap();
        let mut x = vec![0.0; 7];
        x[3] = 1.0;
        l.apply_in_place(&mut x);
        assert_eq!(x, vec![0.0, 0.0, 0.0, 3.0, 0.0, 0.0, 0.0]);
        // superlumped: diag(K_bb) on coupled boundary DOFs, against K's diagonal read through
        // products with unit vectors; the lumped K_bb keeps the coupling and differs
        let coupled = [2, 3, 4];
        let kdd = |d: usize| {
            let mut e = vec![0.0; 7];
            e[d] = 1.0;
            k.mul(&e)[d]
        };
        let x0: Vec<f64> = (0..7).map(|d| if coupled.contains(&d) { 1.0 + d as f64 } else { 0.0 }).collect();
        let want: Vec<f64> = (0..7).map(|d| kdd(d) * x0[d]).collect();
        let mut x = x0.clone();
        Schur::new(&k, &coupled, Form::Superlumped).unwrap().apply_in_place(&mut x);
        assert_eq!(x, want);
        let mut xl = x0;
        Schur::new(&k, &coupled, Form::Lumped).unwrap().apply_in_place(&mut xl);
        assert!(xl.iter().zip(&want).any(|(a, b)| (a - b).abs() > 0.5), "K_bb couples 2, 3, 4: {xl:?}");
    }

    #[test]
    fn the_dense_schur_complement_is_the_matrix_free_one() {
        // a singular K (floating: the 1-D Laplacian without its identity shift) and a regular one
        for shift in [0.0, 1.0] {
            let mut k = crate::linalg::cholesky::tests::laplace(40);
            for j in 0..k.n {
                let p = k.position(j, j).unwrap();
                // diagonal 2 + shift inside, 1 + shift at the ends: singular for shift 0
                k.values[p] = if j == 0 || j + 1 == k.n { 1.0 } else { 2.0 } + shift;
            }
            let boundary = [0, 7, 8, 20, 39];
            let mf = Schur::new(&k, &boundary, Form::MatrixFree).unwrap();
            let de = Schur::new(&k, &boundary, Form::Dense).unwrap();
            for &e in &boundary {
                let mut x = vec![0.0; 40];
                x[e] = 1.0;
                let mut y = x.clone();
                mf.apply_in_place(&mut x);
                de.apply_in_place(&mut y);
                let d = x.iter().zip(&y).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                assert!(d < 1e-12, "shift {shift}, column {e}: differ by {d:e}");
            }
        }
    }
}
