//! Symmetric sparse matrices stored as their lower triangle in CSC (sorted row indices).

use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};

/// A symmetric matrix held by its lower triangle (row ≥ column), CSC, rows sorted per column.
#[derive(Clone, Debug, Default)]
pub struct SymCsc {
    /// Order of the matrix.
    pub n: usize,
    /// Start of each column in `row_idx` and `values` (n + 1 entries).
    pub col_ptr: Vec<usize>,
    /// Row index of each stored entry.
    pub row_idx: Vec<usize>,
    /// Value of each stored entry.
    pub values: Vec<f64>,
}

impl SymCsc {
    /// Stored entries (the lower triangle's nonzeros).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// The faer view (lower triangle only; use with `Side::Lower`).
    pub fn as_faer(&self) -> SparseColMatRef<'_, usize, f64> {
        SparseColMatRef::new(SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx), &self.values)
    }

    /// Position of entry (i, j), i ≥ j, in `values`.
    #[inline]
    pub fn position(&self, i: usize, j: usize) -> Option<usize> {
        let (a, b) = (self.col_ptr[j], self.col_ptr[j + 1]);
        self.row_idx[a..b].binary_search(&i).ok().map(|p| a + p)
    }

    /// y = A x using the symmetry.
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n];
        for j in 0..self.n {
            let xj = x[j];
            let mut acc = 0.0;
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[p];
                let v = self.values[p];
                y[i] += v * xj;
                if i != j {
                    acc += v * x[i];
                }
            }
            y[j] += acc;
        }
        y
    }

    /// y = |A| |x| (entrywise absolute values): the size of the terms whose sums A x forms.
    pub fn abs_mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n];
        for j in 0..self.n {
            let xj = x[j].abs();
            let mut acc = 0.0;
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let (i, v) = (self.row_idx[p], self.values[p].abs());
                y[i] += v * xj;
                if i != j {
                    acc += v * x[i].abs();
                }
            }
            y[j] += acc;
        }
        y
    }

    /// The principal submatrix on the unknowns d with `at[d] != usize::MAX`, renumbered to
    /// `at[d]` (which must grow with d).
    pub fn principal(&self, at: &[usize]) -> SymCsc {
        let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
        for j in (0..self.n).filter(|&j| at[j] != usize::MAX) {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                if at[self.row_idx[p]] != usize::MAX {
                    row_idx.push(at[self.row_idx[p]]);
                    values.push(self.values[p]);
                }
            }
            col_ptr.push(row_idx.len());
        }
        SymCsc { n: col_ptr.len() - 1, col_ptr, row_idx, values }
    }

    /// Largest absolute entry.
    pub fn max_abs(&self) -> f64 {
        self.values.iter().fold(0.0, |a, v| a.max(v.abs()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symmetric_product() {
        // [[4,1,0],[1,3,2],[0,2,5]]
        let a = SymCsc { n: 3, col_ptr: vec![0, 2, 4, 5], row_idx: vec![0, 1, 1, 2, 2], values: vec![4.0, 1.0, 3.0, 2.0, 5.0] };
        assert_eq!(a.mul(&[1.0, 2.0, 3.0]), vec![6.0, 13.0, 19.0]);
        assert_eq!(a.position(2, 1), Some(3));
        assert_eq!(a.position(2, 0), None);
    }
}
