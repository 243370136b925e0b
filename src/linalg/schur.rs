//! The Schur complement `S = K_bb − K_bi K_ii⁻¹ K_ib` of a symmetric stiffness K onto a set of
//! boundary DOFs b (those a piece's rows of B touch), applied matrix-free — the local part of
//! the FETI Dirichlet preconditioner — and its cheap stand-in K_bb (the lumped preconditioner).
//! K may be singular (a floating TFETI subdomain); K_ii must be positive definite, which holds
//! once the boundary DOFs hold the piece in place.

use super::cholesky::{Cholesky, Ordering};
use super::sparse::SymCsc;
use crate::error::Result;

/// S (Dirichlet) or K_bb (lumped) of one piece.
pub struct Schur {
    k: SymCsc,
    /// Interior DOF of each DOF (`usize::MAX` for boundary DOFs).
    interior: Vec<usize>,
    /// Boundary DOFs, ascending.
    pub boundary: Vec<usize>,
    /// K_ii's factor; `None`: lumped (S ≈ K_bb).
    chol: Option<Cholesky>,
}

impl Schur {
    /// The operator of K (lower triangle) onto the DOFs `boundary` (any order, no repeats);
    /// `dirichlet`: factorize K_ii for the exact Schur complement, else K_bb only.
    pub fn new(k: &SymCsc, boundary: &[usize], dirichlet: bool) -> Result<Schur> {
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
        let chol = if dirichlet && ni > 0 {
            // K_ii: the lower triangle's entries with both indices interior (order kept)
            let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
            for j in 0..n {
                if interior[j] == usize::MAX {
                    continue;
                }
                for p in k.col_ptr[j]..k.col_ptr[j + 1] {
                    let i = k.row_idx[p];
                    if interior[i] != usize::MAX {
                        row_idx.push(interior[i]);
                        values.push(k.values[p]);
                    }
                }
                col_ptr.push(row_idx.len());
            }
            let kii = SymCsc { n: ni, col_ptr, row_idx, values };
            Some(Cholesky::factorize(&kii, Ordering::Amd)?)
        } else {
            None
        };
        Ok(Schur { k: k.clone(), interior, boundary, chol })
    }

    /// x ← S x for x zero off the boundary (the result is zero off the boundary too).
    pub fn apply_in_place(&self, x: &mut [f64]) {
        let y = self.k.mul(x);
        x.fill(0.0);
        for &d in &self.boundary {
            x[d] = y[d];
        }
        if let Some(chol) = &self.chol {
            // w = K_ii⁻¹ (K x)_i, then subtract (K w)_b
            let mut t = vec![0.0; chol.n()];
            for (d, &i) in self.interior.iter().enumerate() {
                if i != usize::MAX {
                    t[i] = y[d];
                }
            }
            chol.solve_in_place(&mut t);
            let mut w = vec![0.0; self.k.n];
            for (d, &i) in self.interior.iter().enumerate() {
                if i != usize::MAX {
                    w[d] = t[i];
                }
            }
            let kw = self.k.mul(&w);
            for &d in &self.boundary {
                x[d] -= kw[d];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schur_complement_inverts_the_boundary_block_of_the_inverse() {
        // S = ((K⁻¹)_bb)⁻¹: S (K⁻¹ e_b)_b = e_b for a unit vector on the boundary
        let k = crate::linalg::cholesky::tests::laplace(7);
        let boundary = [0, 3, 6];
        let s = Schur::new(&k, &boundary, true).unwrap();
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
        let l = Schur::new(&k, &boundary, false).unwrap();
        let mut x = vec![0.0; 7];
        x[3] = 1.0;
        l.apply_in_place(&mut x);
        assert_eq!(x, vec![0.0, 0.0, 0.0, 3.0, 0.0, 0.0, 0.0]);
    }
}
