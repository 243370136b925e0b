//! The dual problem: multipliers λ of the contact rows, the operator A = B K⁻¹ Bᵀ applied
//! matrix-free behind [`DualOperator`], the right-hand side b = B K⁻¹ f − c, and the recovery
//! u = K⁻¹(f − Bᵀλ). [`monolithic`] is the paper's setting (one piece per body, Dirichlet
//! eliminated, dual vectors replicated on every rank); the TFETI operator
//! (`feti::dual`) implements the same trait on distributed dual vectors, each rank holding its
//! own components: the solvers reach the other ranks only through the trait's reductions
//! (dot, norm, max, min, count), so every rank takes the same branches.

pub mod monolithic;

use std::cell::Cell;

/// "Apply A": a symmetric positive (semi)definite operator on the dual vectors. Every call
/// counts as one A-product (nA).
pub trait DualOperator {
    /// Length of a dual vector.
    fn dim(&self) -> usize;
    /// y = A x.
    fn apply(&self, x: &[f64], y: &mut [f64]);
    /// A-products so far.
    fn products(&self) -> usize;
    /// Inner product of two dual vectors (replicated vectors: local; distributed ones reduce
    /// over the ranks), so that every rank sees the same value.
    fn dot(&self, x: &[f64], y: &[f64]) -> f64 {
        x.iter().zip(y).map(|(a, b)| a * b).sum()
    }
    fn norm(&self, x: &[f64]) -> f64 {
        self.dot(x, x).sqrt()
    }
    /// The maximum over the ranks of a value each rank computed from its own components.
    fn max(&self, v: f64) -> f64 {
        v
    }
    /// The minimum over the ranks (see [`DualOperator::max`]).
    fn min(&self, v: f64) -> f64 {
        -self.max(-v)
    }
    /// The sum over the ranks of a count each rank made on its own components.
    fn count(&self, n: usize) -> usize {
        n
    }
    /// The global index of component `i` of this rank's vectors.
    fn global_index(&self, i: usize) -> usize {
        i
    }
    /// y = M x with M ≈ A⁻¹ symmetric positive semidefinite on the components a preconditioner
    /// covers (see [`Preconditioner`]), `scale·x` on the others (all of them when none was
    /// built). Not an A-product.
    fn precondition(&self, x: &[f64], y: &mut [f64], scale: f64) {
        y.iter_mut().zip(x).for_each(|(a, b)| *a = scale * b);
    }
    /// Whether [`DualOperator::precondition`] is more than the identity.
    fn preconditioned(&self) -> bool {
        false
    }
}

/// The FETI preconditioner of the symmetric inner solves (TSSN's CG) on the TFETI gluing and
/// Dirichlet block: `M_E = Σ_s B_E,s D_s S_s D_s B_E,sᵀ` over the subdomains s, S_s the Schur
/// complement of K_s onto the DOFs its E rows touch (Dirichlet) or just K_s's block there
/// (lumped), D_s the stiffness scaling of the rows (a row shared by subdomains s and o gets
/// k_o/(k_s + k_o), k the diagonal stiffness B sees; a row of one subdomain 1); applied as
/// `P̃ diag(M_E, scale·I) P̃ᵀ`. The E components are free in every inner solve, so M_E acts on
/// them unrestricted. (The contact block is left to the scaled identity: the same Dirichlet
/// operator on the contact rows of the monolithic dual cut unconstrained CG from 43 to 12
/// iterations at N = 16, but restricted to TSSN's free sets it made the solve dearer, 111 vs
/// 96 A-products.)
#[derive(Clone, Copy, Debug, serde::Deserialize, serde::Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Preconditioner {
    None,
    Lumped,
    Dirichlet,
}

/// Per row of B (as indexed by `entries`, `nrows` of them): the diagonal stiffness
/// Σ c²·K_jj the piece's entries put there, and 1 where the piece touches the row.
pub fn row_stiffness(entries: &[(usize, usize, f64)], k: &crate::linalg::sparse::SymCsc, nrows: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut s, mut touched) = (vec![0.0; nrows], vec![0.0; nrows]);
    for &(r, j, c) in entries {
        let kjj = k.position(j, j).map_or(0.0, |p| k.values[p]);
        s[r] += c * c * kjj.abs();
        touched[r] = 1.0;
    }
    (s, touched)
}

/// The entries scaled by D_p given the totals over all pieces of [`row_stiffness`] (at the same
/// row indices): the weight of row r is (total − own)/(total·(count − 1)), or 1 for a row of
/// this piece alone.
pub fn scaled_entries(entries: &[(usize, usize, f64)], own: &[f64], total: &[f64], count: &[f64]) -> Vec<(usize, usize, f64)> {
    entries
        .iter()
        .map(|&(r, j, c)| {
            let w = if count[r] > 1.5 && total[r] > 0.0 { (total[r] - own[r]) / (total[r] * (count[r] - 1.0)) } else { 1.0 };
            (r, j, c * w)
        })
        .collect()
}

/// The entries (row of B, local DOF, coefficient) of B acting on one piece (a body or a
/// subdomain): z = B_pᵀx on the piece's `ndof` DOFs.
pub fn scatter_rows(rows: &[(usize, usize, f64)], x: &[f64], ndof: usize) -> Vec<f64> {
    let mut z = vec![0.0; ndof];
    for &(r, j, c) in rows {
        z[j] += c * x[r];
    }
    z
}

/// y = Σ_p B_p z_p over the pieces of this rank, then summed over the ranks.
pub fn gather_rows<'a, C: crate::comm::Comm>(comm: &C, pieces: impl Iterator<Item = (&'a [(usize, usize, f64)], &'a [f64])>, y: &mut [f64]) {
    y.fill(0.0);
    for (rows, z) in pieces {
        for &(r, j, c) in rows {
            y[r] += c * z[j];
        }
    }
    comm.sum_f64(y);
}

/// A counter of A-products shared by the implementations.
#[derive(Debug, Default)]
pub struct ProductCounter(Cell<usize>);

impl ProductCounter {
    pub fn tick(&self) {
        self.0.set(self.0.get() + 1);
    }
    pub fn get(&self) -> usize {
        self.0.get()
    }
}

/// Layout of the multipliers: λ = (λν ∈ Rᵐ, λτ ∈ R²ᵐ, λ_E ∈ R^free), λτ absent when
/// frictionless; pair i owns λν[i] and λτ[2i], λτ[2i+1]. λ_E are the unconstrained
/// multipliers (TFETI's gluing and Dirichlet rows; none in the monolithic dual).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub m: usize,
    pub friction: bool,
    pub free: usize,
}

impl Layout {
    /// The contact multipliers only.
    pub fn contact(m: usize, friction: bool) -> Self {
        Layout { m, friction, free: 0 }
    }

    /// Number of contact multipliers (λν and λτ): the free ones start here.
    pub fn contact_dim(&self) -> usize {
        if self.friction { 3 * self.m } else { self.m }
    }

    pub fn dim(&self) -> usize {
        self.contact_dim() + self.free
    }
    /// Index of λν,ᵢ.
    pub fn normal(&self, i: usize) -> usize {
        i
    }
    /// Index of the k-th tangential component of pair i (k = 0, 1).
    pub fn tangent(&self, i: usize, k: usize) -> usize {
        debug_assert!(self.friction);
        self.m + 2 * i + k
    }
}
