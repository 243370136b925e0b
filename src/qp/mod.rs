//! Quadratic programs with separable convex constraints: the constraint sets, and (later) the
//! solvers.
//!
//! The dual contact problem (DESIGN §1, §3) is `min ½ λᵀAλ − λᵀb` over a product
//! `Λ = Π_i Λ_i` of small closed convex blocks, one per contact pair: a half-line for the
//! normal multiplier `λν,ᵢ ≥ 0` and a disc (isotropic Tresca) or an ellipse (orthotropic
//! Tresca) for the tangential pair `λ̄τ,ᵢ`. [`sets`] holds these blocks behind one trait
//! ([`sets::ConvexSet`]): projection, feasibility, largest feasible step, slant derivative.

pub mod gimssn;
pub mod lambda;
pub mod sets;
