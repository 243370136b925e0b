//! The convex blocks of the dual feasible set `Λ = R₊ᵐ × Π_i Λτ,ᵢ` (docs/method.md, "The problem" and "The solvers"): one small
//! closed convex set in R^d (d = 1 or 2) per contact pair and direction.
//!
//! * [`HalfLine`] (d = 1): `{x ≥ 0}` for the normal multiplier λν,ᵢ. `P(y) = max(0, y)`; slant
//!   derivative 1 for `y ≥ 0`, 0 for `y < 0` — the paper's convention `A_ν = {y ≥ 0}` (12): y = 0
//!   counts as free.
//! * [`Disc`] (d = 2): `{‖x‖ ≤ g}` for isotropic Tresca. The projection is the radial scaling
//!   `ψ_g(y) = y` if `‖y‖ ≤ g`, else `g·y/‖y‖`; its slant derivative is `I` for `‖y‖ ≤ g`
//!   (stick, `A_τ` of (13)) and `ψ°_g(y) = (g/‖y‖)(I − ŷŷᵀ)`, `ŷ = y/‖y‖`, for `‖y‖ > g` (slip).
//!   Radius 0 is allowed: `ψ_0 ≡ 0`, slant 0.
//! * [`Ellipse`] (d = 2): `{(x₁/a)² + (x₂/b)² ≤ 1}` for orthotropic Tresca (semi-axes a along the
//!   first, b along the second tangential direction); its projection (Newton's method on the
//!   secular equation) and slant derivative are set out in the docs of `ellipse.rs`.
//!
//! [`TangentSet`] dispatches statically between the disc and the ellipse (one per contact pair)
//! and adds the local boundary geometry a tangent-symmetric Newton step needs (docs/method.md, "The solvers"):
//! [`TangentSet::boundary_tangent`], [`TangentSet::curvature`] and, for a sliding pair,
//! [`TangentSet::frame`] (projection, normal, tangent, distance, curvature and slant factor μ at
//! once; the term `cᵢ = (1/μ − 1)/ρ` of §3b is best computed as `κ·dist/ρ`).
//!
//! Everything here is allocation-free and panic-free for finite input (slices of
//! the wrong length aside); NaN input gives NaN (or arbitrary) output but never loops.
//!
//! One file per set: `half_line.rs` ([`HalfLine`]), `disc.rs` ([`Disc`]), `ellipse.rs`
//! ([`Ellipse`]), `tangent.rs` ([`TangentSet`]); `frame.rs` holds [`BoundaryFrame`] and the
//! small 2-D helpers the disc and the ellipse share, this file the trait [`ConvexSet`], and
//! `tests.rs` the unit tests.

// `!(a > b)` is used on purpose: it is true for NaN, which must stop loops and pick fallbacks.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod disc;
mod ellipse;
mod frame;
mod half_line;
mod tangent;
#[cfg(test)]
mod tests;

pub use disc::Disc;
pub use ellipse::Ellipse;
pub use frame::BoundaryFrame;
pub use half_line::HalfLine;
pub use tangent::TangentSet;

/// Axis ratio `min(a, b)/max(a, b)` at or below which an [`Ellipse`] is treated as the segment
/// along its longer axis (the difference is below 1e-100 of its size; it keeps `a_k²` and the
/// secular equation's terms far from underflow and overflow).
pub const DEGENERATE_RATIO: f64 = 1e-100;

const EPS: f64 = f64::EPSILON;

/// A closed convex set in R^d (d = 1 or 2): the block of one contact pair in `Λ`.
pub trait ConvexSet {
    /// The dimension d.
    fn dim(&self) -> usize;
    /// Euclidean projection of y onto the set, into `out`.
    fn project(&self, y: &[f64], out: &mut [f64]);
    /// Whether x lies in the set up to `tol` (absolute, in the units of x): dist(x, set) ≤ tol.
    fn contains(&self, x: &[f64], tol: f64) -> bool;
    /// For x in the set: the largest α ≥ 0 with x − α·d in the set (`f64::INFINITY` if
    /// unbounded, e.g. d = 0). (CGMfeas' feasibility test and step to the boundary.) For x
    /// outside by rounding: 0 if −d points outward, else where the ray leaves the set.
    fn max_step(&self, x: &[f64], d: &[f64]) -> f64;
    /// A slant (generalized Jacobian) derivative of the projection at y, row-major d×d, into
    /// `out`.
    fn slant(&self, y: &[f64], out: &mut [f64]);
    /// Whether the projection of y lies on the boundary with y outside (the pair is
    /// "active"/"sliding"): y ∉ set. Exactly the points that `project` moves.
    fn is_outside(&self, y: &[f64]) -> bool;
}

/// `if a < 0 { 0 } else { a }`, letting NaN through.
#[inline]
fn nonneg(a: f64) -> f64 {
    if a < 0.0 {
        0.0
    } else {
        a
    }
}
