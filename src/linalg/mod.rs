//! Sparse linear algebra: the symmetric CSC matrix we assemble into, the METIS nested-dissection
//! ordering, the sparse Cholesky factorization (faer) built on both, and the Schur complement
//! onto boundary DOFs (the FETI Dirichlet and lumped preconditioners).

pub mod cholesky;
pub mod ordering;
pub mod schur;
pub mod sparse;
