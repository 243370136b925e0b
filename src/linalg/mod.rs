//! Sparse linear algebra: the symmetric CSC matrix we assemble into, the METIS nested-dissection
//! ordering, the sparse Cholesky factorization (faer) built on both, and the Schur complement
//! onto boundary DOFs (the FETI Dirichlet and lumped preconditioners).

pub mod cholesky;
pub mod ordering;
pub(crate) mod schur;
pub mod sparse;

/// A fixed probe vector's component at global index i (pseudo-random in [−1, 1]).
pub fn probe(i: usize) -> f64 {
    let mut z = (i as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}
