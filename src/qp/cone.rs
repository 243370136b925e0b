//! The Coulomb cone's data shared by the fixed point ([`super::coulomb`]) and the Newton
//! method on the Coulomb law ([`super::ssn`]): each pair's friction coefficient and the Tresca
//! set Λ(λ) whose tangential sets are the cones cut at the normal multipliers λν.

use std::borrow::Cow;

use super::lambda::Lambda;
use super::sets::{Disc, Ellipse, TangentSet};

/// The friction coefficient of one pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Coefficient {
    /// Not a Coulomb pair: its tangential set stays as given.
    Fixed,
    /// Isotropic: ‖λτ,ᵢ‖ ≤ μ λν,ᵢ.
    Isotropic(f64),
    /// Orthotropic in the pair's frame: (λ₁/μ₁)² + (λ₂/μ₂)² ≤ λν,ᵢ².
    Orthotropic(f64, f64),
}

/// `set` with the tangential set of every Coulomb pair k cut at λν,k = x\[k\] (negative values
/// count as 0: the point set).
pub fn bounds(set: &Lambda, mu: &[Coefficient], x: &[f64]) -> Lambda {
    let mut out = set.clone();
    for (k, (t, c)) in out.tangent.iter_mut().zip(mu).enumerate() {
        let ln = x[set.layout.normal(k)].max(0.0);
        match *c {
            Coefficient::Fixed => {}
            Coefficient::Isotropic(m) => *t = TangentSet::Disc(Disc::new(m * ln)),
            Coefficient::Orthotropic(a, b) => *t = TangentSet::Ellipse(Ellipse::new(a * ln, b * ln)),
        }
    }
    out
}

/// Λ itself, or — with coefficients — Λ(x), the cones of `set` cut at x's normals ([`bounds`]).
pub fn cut<'s>(set: &'s Lambda, mu: Option<&[Coefficient]>, x: &[f64]) -> Cow<'s, Lambda> {
    match mu {
        Some(mu) => Cow::Owned(bounds(set, mu, x)),
        None => Cow::Borrowed(set),
    }
}
