//! Sparse Cholesky LLᵀ of a symmetric positive definite [`SymCsc`] (faer, supernodal or
//! simplicial as faer decides), with a caller-supplied fill-reducing permutation (METIS nested
//! dissection by default, see [`super::ordering`]) or faer's AMD. The symbolic analysis can be
//! kept ([`Symbolic`]) and reused for matrices of the same pattern. A factor can keep a
//! single-precision copy of L for fast, less accurate solves ([`Cholesky::keep_single`]).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering};
use faer::{Conj, Mat, MatMut, Par, Side};

use super::sparse::SymCsc;
use crate::error::{Error, Result};

/// Which fill-reducing ordering to use.
#[derive(Clone, Debug)]
pub enum Ordering {
    /// `perm[new] = old`, e.g. from METIS nested dissection.
    Custom(Vec<usize>),
    /// Approximate minimum degree (faer's).
    Amd,
}

/// The symbolic analysis of a pattern (ordering and structure of L), shared by the
/// factorizations of matrices with that pattern.
#[derive(Clone, Debug)]
pub struct Symbolic(std::sync::Arc<SymbolicCholesky<usize>>);

/// A numeric LLᵀ factorization, ready to solve.
pub struct Cholesky {
    symbolic: Symbolic,
    values: Vec<f64>,
    /// L rounded to f32, when kept.
    single: Option<Vec<f32>>,
}

fn fail(r: String) -> Error {
    Error::numerical("Cholesky factorization", r)
}

impl Symbolic {
    /// Orders and analyzes the pattern of `a` (its values are not read).
    pub fn analyze(a: &SymCsc, ordering: Ordering) -> Result<Self> {
        let view = a.as_faer();
        let inv: Vec<usize>;
        let (fwd, ord) = match ordering {
            Ordering::Custom(p) => {
                if p.len() != a.n {
                    return Err(fail(format!("ordering has {} entries for {} unknowns", p.len(), a.n)));
                }
                let mut i = vec![0; a.n];
                for (new, &old) in p.iter().enumerate() {
                    i[old] = new;
                }
                inv = i;
                (p, true)
            }
            Ordering::Amd => {
                inv = vec![];
                (vec![], false)
            }
        };
        let ord = if ord { SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, a.n)) } else { SymmetricOrdering::Amd };
        let symbolic = factorize_symbolic_cholesky(view.symbolic(), Side::Lower, ord, CholeskySymbolicParams::default())
            .map_err(|e| fail(format!("symbolic analysis: {e:?}")))?;
        Ok(Symbolic(std::sync::Arc::new(symbolic)))
    }
}

impl Cholesky {
    /// Factorizes `a`; fails with the reason if `a` is not numerically positive definite.
    pub fn factorize(a: &SymCsc, ordering: Ordering) -> Result<Self> {
        Cholesky::with_symbolic(Symbolic::analyze(a, ordering)?, a)
    }

    /// Factorizes `a`, whose pattern is the one `symbolic` analyzed.
    pub fn with_symbolic(symbolic: Symbolic, a: &SymCsc) -> Result<Self> {
        let view = a.as_faer();
        let par = faer::get_global_parallelism();
        let sym = &symbolic.0;
        let mut values = vec![0.0; sym.len_val()];
        let mut mem = MemBuffer::try_new(sym.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
            .map_err(|_| fail("out of memory for the factorization workspace".into()))?;
        sym.factorize_numeric_llt(&mut values, view, Side::Lower, LltRegularization::default(), par, MemStack::new(&mut mem), Default::default())
            .map_err(|e| fail(format!("matrix is not positive definite ({e:?}); is the body held by enough Dirichlet conditions?")))?;
        if values.iter().any(|v| !v.is_finite()) {
            return Err(fail("factor contains NaN or infinity".into()));
        }
        Ok(Cholesky { symbolic, values, single: None })
    }

    /// Order of the factorized matrix.
    pub fn n(&self) -> usize {
        self.symbolic.0.nrows()
    }

    /// The trailing nb × nb block L_bb of L (lower triangular, in the factor's order of its last
    /// nb unknowns): with those unknowns b ordered last, L_bb L_bbᵀ = S = A_bb − A_bi A_ii⁻¹ A_ib
    /// and (A⁻¹)_bb = S⁻¹.
    pub fn trailing_block(&self, nb: usize) -> Mat<f64> {
        trailing_block(&self.symbolic.0, &self.values, nb)
    }

    /// Number of stored entries of L.
    pub fn nnz_l(&self) -> usize {
        self.values.len()
    }

    /// Keeps a copy of L in single precision (half the bytes of L more) for
    /// [`Cholesky::solve_in_place_single`].
    pub fn keep_single(&mut self) {
        self.single = Some(self.values.iter().map(|&v| v as f32).collect());
    }

    /// Bytes of the single-precision copy (0 when none is kept).
    pub fn single_bytes(&self) -> usize {
        self.single.as_ref().map_or(0, |v| v.len() * std::mem::size_of::<f32>())
    }

    /// Solves A x = b in place with the single-precision copy of L (b rounded to f32, the
    /// solution widened back); with no copy kept, in double precision.
    pub fn solve_in_place_single(&self, b: &mut [f64]) {
        let Some(single) = &self.single else {
            return self.solve_in_place(b);
        };
        let mut bs: Vec<f32> = b.iter().map(|&v| v as f32).collect();
        llt_solve(&self.symbolic.0, single, &mut bs, 1);
        b.iter_mut().zip(&bs).for_each(|(a, &v)| *a = v as f64);
    }

    /// Solves A x = b in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        self.solve_many_in_place(b, 1)
    }

    /// Solves A X = B in place for the `ncols` columns of `b` (column-major, n × ncols).
    pub fn solve_many_in_place(&self, b: &mut [f64], ncols: usize) {
        if ncols > 0 {
            llt_solve(&self.symbolic.0, &self.values, b, ncols);
        }
    }
}

/// X ← (LLᵀ)⁻¹X for the `ncols` columns of `b` (column-major), L's values in `values` (f64, or
/// the single-precision copy), sequential.
fn llt_solve<T: faer::traits::ComplexField>(sym: &SymbolicCholesky<usize>, values: &[T], b: &mut [T], ncols: usize) {
    let n = sym.nrows();
    assert_eq!(b.len(), n * ncols);
    let par = Par::Seq;
    let mut mem = MemBuffer::new(sym.solve_in_place_scratch::<T>(ncols, par));
    let rhs = MatMut::from_column_major_slice_mut(b, n, ncols);
    LltRef::new(sym, values).solve_in_place_with_conj(Conj::No, rhs, par, MemStack::new(&mut mem));
}

/// The trailing nb × nb block of the factor L whose values `values` follow the structure `sym`
/// (supernodal: read supernode by supernode; simplicial: column by column).
pub(crate) fn trailing_block(sym: &SymbolicCholesky<usize>, values: &[f64], nb: usize) -> Mat<f64> {
    let n = sym.nrows();
    let ni = n - nb;
    let mut l = Mat::<f64>::zeros(nb, nb);
    match sym.raw() {
        SymbolicCholeskyRaw::Supernodal(sn) => {
            let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
            let (rptr, vptr, rows) = (sn.col_ptr_for_row_idx(), sn.col_ptr_for_val(), sn.row_idx());
            for s in 0..sn.n_supernodes() {
                let (b0, e0) = (begin[s], end[s]);
                if e0 <= ni {
                    continue;
                }
                let ncols = e0 - b0;
                let pattern = &rows[rptr[s]..rptr[s + 1]];
                let nrows = ncols + pattern.len();
                let block = &values[vptr[s]..vptr[s + 1]];
                for jc in 0..ncols {
                    let c = b0 + jc;
                    if c < ni {
                        continue;
                    }
                    for r in jc..nrows {
                        let row = if r < ncols { b0 + r } else { pattern[r - ncols] };
                        l[(row - ni, c - ni)] = block[r + jc * nrows];
                    }
                }
            }
        }
        SymbolicCholeskyRaw::Simplicial(sp) => {
            let (ptr, rows) = (sp.col_ptr(), sp.row_idx());
            for c in ni..n {
                for p in ptr[c]..ptr[c + 1] {
                    l[(rows[p] - ni, c - ni)] = values[p];
                }
            }
        }
    }
    l
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// 1-D Laplacian + identity, n × n, lower triangle.
    pub(crate) fn laplace(n: usize) -> SymCsc {
        let mut col_ptr = vec![0];
        let mut row_idx = vec![];
        let mut values = vec![];
        for j in 0..n {
            row_idx.push(j);
            values.push(3.0);
            if j + 1 < n {
                row_idx.push(j + 1);
                values.push(-1.0);
            }
            col_ptr.push(row_idx.len());
        }
        SymCsc { n, col_ptr, row_idx, values }
    }

    #[test]
    fn solves_with_custom_and_amd_orderings() {
        let a = laplace(50);
        let x: Vec<f64> = (0..50).map(|i| (i as f64).sin()).collect();
        let b = a.mul(&x);
        let rev: Vec<usize> = (0..50).rev().collect();
        for ord in [Ordering::Custom(rev), Ordering::Amd] {
            let c = Cholesky::factorize(&a, ord).unwrap();
            let mut y = b.clone();
            c.solve_in_place(&mut y);
            for i in 0..50 {
                assert!((y[i] - x[i]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn single_precision_solves_agree_to_single_precision() {
        let a = laplace(30);
        let mut c = Cholesky::factorize(&a, Ordering::Amd).unwrap();
        let b: Vec<f64> = (0..a.n).map(|i| ((i * 7919) % 101) as f64 / 101.0 - 0.5).collect();
        let mut x = b.clone();
        c.solve_in_place(&mut x);
        let mut y = b.clone();
        c.solve_in_place_single(&mut y);
        assert_eq!(x, y, "without a copy the single solve is the double one");
        c.keep_single();
        assert_eq!(c.single_bytes(), 4 * c.nnz_l());
        let mut y = b.clone();
        c.solve_in_place_single(&mut y);
        let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
        let d: Vec<f64> = x.iter().zip(&y).map(|(a, b)| a - b).collect();
        let rel = norm(&d) / norm(&x);
        assert!(rel > 1e-12 && rel < 1e-4, "single against double: {rel:e}");
    }

    #[test]
    fn indefinite_matrix_is_an_error() {
        let mut a = laplace(5);
        a.values[0] = -1.0;
        let e = Cholesky::factorize(&a, Ordering::Amd).err().unwrap();
        assert!(e.to_string().contains("not positive definite"), "{e}");
    }
}
