//! Sparse linear algebra: the symmetric CSC matrix we assemble into, the METIS nested-dissection
//! ordering, and the sparse Cholesky factorization (faer) built on both.

pub mod cholesky;
pub mod ordering;
pub mod sparse;
