//! KKT residuals of a dual solution λ with its gradient r = Aλ − b = −(Bu − c): what a result
//! must satisfy, measured independently of any solver's stopping test. Equilibrium
//! `Ku = f − Bᵀλ` holds by the recovery (it is checked on the primal side, per body).
//!
//! Per pair i: no penetration `rν,ᵢ ≥ 0` (the current gap); `λν,ᵢ ≥ 0`; complementarity
//! `λν,ᵢ rν,ᵢ = 0`; the friction bound `λ̄τ,ᵢ ∈ Λτ,ᵢ`; the friction law: either stick,
//! `r̄τ,ᵢ = 0` (no slip), or slip: λ̄τ on the boundary and the slip `ūτ = −r̄τ` along the
//! outward normal n of the set there (`r̄τ·t = 0`, `r̄τ·n ≤ 0`). The friction-law residual of a
//! pair is the smaller of its stick residual `‖r̄τ‖` and its slip residual (distance to the
//! boundary, tangential and outward parts of r̄τ), so that an inexact λ̄τ a hair inside the
//! bound of a sliding pair is not read as a moving sticking one. Forces are relative to
//! `max(max λν, max gᵢ)`, the gradient to ‖b‖.

use super::lambda::Lambda;
use super::sets::ConvexSet;

/// Relative KKT residuals (all ≥ 0; 0 at an exact solution).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Kkt {
    /// No penetration: max of −rν,ᵢ, relative to ‖b‖.
    pub penetration: f64,
    /// λν ≥ 0: max of −λν,ᵢ, relative to the force scale.
    pub normal_sign: f64,
    /// Complementarity: max of |λν,ᵢ rν,ᵢ|, relative to the force scale and ‖b‖.
    pub complementarity: f64,
    /// Friction bound: max distance of λ̄τ,ᵢ from Λτ,ᵢ, relative to the force scale.
    pub friction_bound: f64,
    /// Friction law: max over the pairs of the smaller of the stick and slip residuals.
    pub friction_law: f64,
}

impl Kkt {
    /// The largest of the residuals.
    pub fn worst(&self) -> f64 {
        [self.penetration, self.normal_sign, self.complementarity, self.friction_bound, self.friction_law].into_iter().fold(0.0, f64::max)
    }
}

/// The KKT residuals of λ with gradient r; `bnorm` = ‖b‖.
pub fn residuals(set: &Lambda, lambda: &[f64], r: &[f64], bnorm: f64) -> Kkt {
    residuals_scaled(set, lambda, r, bnorm, 0.0)
}

/// [`residuals`] with the forces relative to at least `force`: the problem's force scale
/// (‖b‖/σ_max(A), the size of the multipliers an ε‖b‖ gradient moves), so that multipliers of
/// round-off size where every pair is open (and every bound 0) are not read as forces.
pub fn residuals_scaled(set: &Lambda, lambda: &[f64], r: &[f64], bnorm: f64, force: f64) -> Kkt {
    let m = set.layout.m;
    let mut lscale = lambda[..m].iter().fold(0.0f64, |s, v| s.max(v.abs())).max(if force.is_finite() { force } else { 0.0 });
    let mut k = Kkt::default();
    let bnorm = bnorm.max(f64::MIN_POSITIVE);
    // each set's size: the projection of a far point lies on its boundary
    let sizes: Vec<f64> = set
        .tangent
        .iter()
        .map(|s| {
            let mut far = [0.0; 2];
            s.project(&[1e300, 1e300], &mut far);
            far[0].hypot(far[1])
        })
        .collect();
    lscale = sizes.iter().fold(lscale, |a, &b| a.max(b));
    let lscale = lscale.max(f64::MIN_POSITIVE);
    for i in 0..m {
        k.penetration = k.penetration.max((-r[i]).max(0.0) / bnorm);
        k.normal_sign = k.normal_sign.max((-lambda[i]).max(0.0) / lscale);
        k.complementarity = k.complementarity.max((lambda[i] * r[i]).abs() / (lscale * bnorm));
    }
    for (i, s) in set.tangent.iter().enumerate() {
        let j = set.layout.tangent(i, 0);
        let x = [lambda[j], lambda[j + 1]];
        let g = [r[j], r[j + 1]];
        let mut px = [0.0; 2];
        s.project(&x, &mut px);
        k.friction_bound = k.friction_bound.max((x[0] - px[0]).hypot(x[1] - px[1]) / lscale);
        if s.is_outside(&[f64::MIN_POSITIVE, f64::MIN_POSITIVE]) {
            continue; // the point set {0}: every r̄τ is admissible
        }
        // a set shrunk to a point admits every r̄τ: a tiny one (a Coulomb cone cut at a λν of
        // round-off size) is that far from it
        let size = sizes[i] / lscale;
        let stick = g[0].hypot(g[1]) / bnorm;
        // the nearest boundary point: px itself if λ̄τ is outside, else the boundary point
        // along the ray from 0 through λ̄τ (exact for a disc, a bound for an ellipse)
        if px == [0.0, 0.0] {
            k.friction_law = k.friction_law.max(stick.min(size));
            continue;
        }
        let on = if s.is_outside(&x) {
            px
        } else {
            let t = s.max_step(&px, &[-px[0], -px[1]]);
            [px[0] * (1.0 + t), px[1] * (1.0 + t)]
        };
        let dist = (on[0] - px[0]).hypot(on[1] - px[1]) / lscale;
        let t = s.boundary_tangent(&on);
        let n = [t[1], -t[0]];
        let along = (g[0] * t[0] + g[1] * t[1]).abs();
        let outward = (g[0] * n[0] + g[1] * n[1]).max(0.0);
        let slip = dist.max(along.max(outward) / bnorm);
        k.friction_law = k.friction_law.max(stick.min(slip).min(size));
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qp::sets::{Disc, TangentSet};

    /// One pair with a disc of radius 1: λ = (λν, λτ₁, λτ₂), r likewise.
    fn set() -> Lambda {
        Lambda::new(1, Some(vec![TangentSet::Disc(Disc::new(1.0))]))
    }

    #[test]
    fn round_off_multipliers_of_open_pairs_are_not_forces_at_the_problem_scale() {
        // Coulomb cones cut at λν = 1e-20 (every pair open, λ of round-off size): relative to
        // the largest λν itself the pair looks pressed and open at once
        let s = Lambda::new(1, Some(vec![TangentSet::Disc(Disc::new(2e-20))]));
        let (lam, r) = ([1e-20, 0.0, 0.0], [1e-3, 0.0, 0.0]);
        assert!(residuals(&s, &lam, &r, 1e-2).complementarity > 0.05);
        // at the problem's force scale (‖b‖/σ_max = 100) it is round-off
        assert!(residuals_scaled(&s, &lam, &r, 1e-2, 100.0).worst() < 1e-15);
        // a real force stays one: λν = 1 with the pair open by 1e-3
        assert!(residuals_scaled(&s, &[1.0, 0.0, 0.0], &r, 1e-2, 100.0).complementarity > 1e-4);
    }

    #[test]
    fn exact_points_have_zero_residuals_and_each_violation_is_seen() {
        let s = set();
        // contact with sliding along +x: λ̄τ on the bound, slip ūτ = −r̄τ along λ̄τ
        let ok = residuals(&s, &[2.0, 1.0, 0.0], &[0.0, -0.3, 0.0], 1.0);
        assert_eq!(ok.worst(), 0.0, "{ok:?}");
        // open with zero force, sticking
        assert_eq!(residuals(&s, &[0.0, 0.5, 0.0], &[0.7, 0.0, 0.0], 1.0).worst(), 0.0);
        let k = residuals(&s, &[2.0, 1.0, 0.0], &[-0.1, -0.3, 0.0], 1.0);
        assert!(k.penetration > 0.09 && k.complementarity > 0.09, "{k:?}");
        let k = residuals(&s, &[-0.5, 0.0, 0.0], &[0.0, 0.0, 0.0], 1.0);
        assert!(k.normal_sign > 0.2, "{k:?}");
        let k = residuals(&s, &[1.0, 1.5, 0.0], &[0.0, -0.3, 0.0], 1.0);
        assert!(k.friction_bound > 0.2, "{k:?}");
        // inside the bound but moving: a sticking pair may not slip
        let k = residuals(&s, &[1.0, 0.5, 0.0], &[0.0, -0.3, 0.0], 1.0);
        assert!(k.friction_law > 0.2, "{k:?}");
        // on the bound but slipping against the friction force, or sideways
        assert!(residuals(&s, &[1.0, 1.0, 0.0], &[0.0, 0.3, 0.0], 1.0).friction_law > 0.2);
        assert!(residuals(&s, &[1.0, 1.0, 0.0], &[0.0, 0.0, 0.3], 1.0).friction_law > 0.2);
    }

    #[test]
    fn a_cone_cut_at_round_off_is_as_far_from_admissible_as_its_size() {
        // a Coulomb pair with λν = 1e-14 (an open pair left at round-off): its disc has radius
        // μλν; any slip is admissible up to that size, while a real disc keeps the full residual
        let tiny = Lambda::new(2, Some(vec![TangentSet::Disc(Disc::new(3e-15)), TangentSet::Disc(Disc::new(1.0))]));
        // pair 0: λτ inside its tiny disc, slipping sideways; pair 1 exact (sliding along +x)
        let k = residuals(&tiny, &[1e-14, 2.0, 1e-15, 0.0, 1.0, 0.0], &[0.5, 0.0, 0.0, 0.3, -0.3, 0.0], 1.0);
        assert!(k.friction_law <= 2e-15, "{k:?}");
        // the same slip at a disc of radius 0.5 is a violation
        let half = Lambda::new(2, Some(vec![TangentSet::Disc(Disc::new(0.5)), TangentSet::Disc(Disc::new(1.0))]));
        let k = residuals(&half, &[1e-14, 2.0, 1e-15, 0.0, 1.0, 0.0], &[0.5, 0.0, 0.0, 0.3, -0.3, 0.0], 1.0);
        assert!(k.friction_law > 0.2, "{k:?}");
    }
}
