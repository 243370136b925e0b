//! What the solvers see of a dual problem: the operator A ([`Operator`], counting its products),
//! the space its vectors live in ([`Space`]: every reduction, so that all ranks take the same
//! branches) and an optional preconditioner M ≈ A⁻¹ on a block of the components
//! ([`Preconditioner`]).

use std::cell::Cell;
use std::ops::Range;

/// The reductions over the dual vectors. Each rank holds some components of every vector
/// (replicated vectors: all of them); these return the same value on every rank. There are no
/// single-process defaults: a distributed implementation that forgot one would be silently
/// rank-local. Replicated vectors say so with [`Replicated`].
pub trait Space {
    /// Inner product of two dual vectors.
    fn dot(&self, x: &[f64], y: &[f64]) -> f64;
    /// The inner products of several pairs in one reduction: `out[j] = dot(pairs[j])`, each
    /// equal to what [`Space::dot`] returns for it.
    fn dots(&self, pairs: &[(&[f64], &[f64])], out: &mut [f64]);
    /// The maximum over the ranks of a value each rank computed from its own components.
    fn max(&self, v: f64) -> f64;
    /// The sum over the ranks of a count each rank made on its own components.
    fn count(&self, n: usize) -> usize;
    /// The global index of component `i` of this rank's vectors.
    fn global_index(&self, i: usize) -> usize;

    /// The global Euclidean norm ‖x‖.
    fn norm(&self, x: &[f64]) -> f64 {
        self.dot(x, x).sqrt()
    }
    /// The minimum over the ranks (see [`Space::max`]).
    fn min(&self, v: f64) -> f64 {
        -self.max(-v)
    }
}

/// Vectors held whole on every rank (the monolithic dual, serial problems): every reduction is
/// local.
#[derive(Clone, Copy, Debug, Default)]
pub struct Replicated;

impl Space for Replicated {
    fn dot(&self, x: &[f64], y: &[f64]) -> f64 {
        x.iter().zip(y).map(|(a, b)| a * b).sum()
    }
    fn dots(&self, pairs: &[(&[f64], &[f64])], out: &mut [f64]) {
        for (o, (x, y)) in out.iter_mut().zip(pairs) {
            *o = self.dot(x, y);
        }
    }
    fn max(&self, v: f64) -> f64 {
        v
    }
    fn count(&self, n: usize) -> usize {
        n
    }
    fn global_index(&self, i: usize) -> usize {
        i
    }
}

/// "Apply A": a symmetric positive (semi)definite operator on the dual vectors. Every call
/// counts as one A-product (nA).
pub trait Operator {
    /// The space of the dual vectors.
    type Space: Space;
    /// The space of the dual vectors (the reductions).
    fn space(&self) -> &Self::Space;
    /// Length of this rank's part of a dual vector.
    fn dim(&self) -> usize;
    /// y = A x.
    fn apply(&self, x: &[f64], y: &mut [f64]);
    /// A-products so far.
    fn products(&self) -> usize;
    /// For x in Ker G of the QP's [`Coarse`] space: a y with A x = y + Gᵀa for some a, without
    /// the work that only adds the Gᵀa part (TFETI: F x, no coarse solves). A solver that
    /// projects its residuals onto Ker G ∩ W loses nothing; [`Operator::finish_kernel`] turns a
    /// sum of such products into the sum of the A-products. Counts as one. Default: A x.
    fn apply_kernel(&self, x: &[f64], y: &mut [f64]) {
        self.apply(x, y)
    }
    /// y ← the A-products' sum from the sum y of [`Operator::apply_kernel`] results (TFETI: P̃ y).
    /// Default: nothing to do.
    fn finish_kernel(&self, _y: &mut [f64]) {}
    /// The products that follow may have a relative error up to `rel` (0: exact, the
    /// default state); an operator with a cheaper, less accurate product (single-precision
    /// factors) uses it where its error is within `rel`. Called with values all ranks share.
    /// Returns whether the products are now inexact. Default: exact products always.
    fn allow_error(&self, _rel: f64) -> bool {
        false
    }
    /// An estimate of diag(A) on this rank's components without a product (the dual operators:
    /// dᵢ = Σ_j Bᵢⱼ²/K_jj, the diagonal of B diag(K)⁻¹ Bᵀ), for a per-row ρ ([`super::params::RhoRule`]).
    /// Default: none.
    fn diagonal_estimate(&self) -> Option<Vec<f64>> {
        None
    }
}

/// y = M x with M ≈ A⁻¹ symmetric positive semidefinite on the components [`Preconditioner::block`]
/// (this rank's indices); the other components of y are left to the solver (a scaled identity
/// there). Not an A-product. With a [`Coarse`] space the solver projects M's result (P M P).
pub trait Preconditioner {
    /// The components M acts on (this rank's indices).
    fn block(&self) -> Range<usize>;
    /// y = M x on [`Preconditioner::block`].
    fn apply(&self, x: &[f64], y: &mut [f64]);
}

/// A linear equality G δ = 0 on the directions of the inner solves (TFETI's natural coarse
/// space G = RᵀBᵀ). With it a Newton step's corrections stay in Ker G ∩ W, W the step's
/// subspace, and CG runs on the orthogonally projected system — the form in which a FETI
/// preconditioner acts (projected PCG). The operator A must agree with G's null space: for
/// δ ∈ Ker G, A δ differs from the unprojected operator only by a vector in Im Gᵀ.
pub trait Coarse {
    /// The projector for W = Im Π, Π the inner system's projection: `free` marks this rank's
    /// free components; `slides` lists (first component, unit tangent t) of the pairs that move
    /// along t only. `None` when G Π Gᵀ is singular.
    fn restrict<'a>(&'a self, free: &[bool], slides: &[(usize, [f64; 2])]) -> Option<Box<dyn CoarseProjector + 'a>>;

    /// Whether the QP keeps Gλ = e itself (its unknowns are λ, not a vector of Ker G): a
    /// Newton step then restricts first, closes its start onto Gλ = e ([`CoarseProjector::close`])
    /// and the operator's gradient is the Lagrangian's on that step's W. Default false.
    fn keeps_equality(&self) -> bool {
        false
    }
}

/// One restriction of a [`Coarse`] space.
pub trait CoarseProjector {
    /// x ← x − Gᵀ(GΠGᵀ)⁻¹G x: for x ∈ W, Π of the result is x's orthogonal projection onto
    /// Ker G ∩ W.
    fn apply(&self, x: &mut [f64]);

    /// Where the QP keeps Gλ = e ([`Coarse::keeps_equality`]): −Gᵀ(GΠGᵀ)⁻¹(Gx − e), whose Π
    /// part added to x closes Gx = e on W. `None` (the default): nothing to close.
    fn close(&self, _x: &[f64]) -> Option<Vec<f64>> {
        None
    }
}

/// A counter of A-products for the implementations of [`Operator`].
#[derive(Debug, Default)]
pub struct ProductCounter(Cell<usize>);

impl ProductCounter {
    /// Counts one A-product.
    pub fn tick(&self) {
        self.0.set(self.0.get() + 1);
    }
    /// A-products counted so far.
    pub fn get(&self) -> usize {
        self.0.get()
    }
}
