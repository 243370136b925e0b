//! Coulomb friction as a fixed point on the slip bounds: each step solves the Tresca problem
//! whose tangential sets are the pairs' friction cones cut at the current normal multipliers
//! (gᵢ = μᵢ·λν,ᵢ), warm-started from the last λ (σ_max measured once), to a tolerance tied to
//! the last change of λν; it stops when λν — hence every bound — changed by at most ε relative
//! and the last solve ran at ε. The solve of one Tresca problem is the caller's (any method,
//! any dual), so this layer knows nothing of meshes or FETI. [`newton`] is the other way: the
//! semi-smooth Newton method on the Coulomb law itself (the default for isotropic μ).

use super::cone::{bounds, Coefficient};
use super::driver::Monitor;
use super::lambda::Lambda;
use super::operator::{Operator, Space};
use super::params::{MethodParams, Params, Ssn, Tssn};
use super::Qp;
use super::{Info, QpError, QpSolution};

/// Settings of the fixed point.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedPoint {
    /// Fixed-point steps at most.
    pub max_iterations: usize,
    /// A step's tolerance: max(ε, inner_factor · the last relative change of λν).
    pub inner_factor: f64,
}

impl Default for FixedPoint {
    fn default() -> Self {
        FixedPoint { max_iterations: 100, inner_factor: 0.1 }
    }
}

/// Counters of the fixed point beside the summed ones of its Tresca solves.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FixedPointInfo {
    pub iterations: usize,
    /// Relative change of λν in the last step.
    pub change: f64,
}

/// Solves the Coulomb problem on the pairs of `set` (`mu` per pair, in the set's order) from
/// `x0` to ε = `params.common.eps`: `solve_one(Λ_k, x, params)` solves the Tresca problem over
/// Λ_k from x. Returns the last solution (its `info` sums every step's counters, the history
/// concatenated), the Λ it satisfies and the fixed point's counters.
pub fn solve<S: Space>(
    space: &S,
    set: &Lambda,
    mu: &[Coefficient],
    x0: &[f64],
    params: &Params,
    fp: &FixedPoint,
    mut solve_one: impl FnMut(&Lambda, &[f64], &Params) -> Result<QpSolution, QpError>,
) -> Result<(QpSolution, Lambda, FixedPointInfo), QpError> {
    let eps = params.common.eps;
    let m = set.layout.m;
    let normals = |x: &[f64]| {
        let mut v = vec![0.0; x.len()];
        v[..m].copy_from_slice(&x[..m]);
        v
    };
    let mut p = params.clone();
    let mut x = x0.to_vec();
    let mut change = 1.0f64;
    let mut total = Info::default();
    let mut current = bounds(set, mu, &x);
    for it in 1..=fp.max_iterations {
        p.common.eps = (fp.inner_factor * change).max(eps);
        let sol = solve_one(&current, &x, &p)?;
        total.absorb(&sol.info);
        // σ_max does not depend on Λ: measured once
        p.common.sigma.get_or_insert(sol.info.sigma_est);
        let (old, new) = (normals(&x), normals(&sol.lambda));
        let diff: Vec<f64> = new.iter().zip(&old).map(|(a, b)| a - b).collect();
        // relative to the new λν; λν falling to 0 (every pair opening) is a change of 1, not an
        // overflow; both 0 is no change
        let (dn, nn) = (space.norm(&diff), space.norm(&new));
        change = if nn > 0.0 {
            dn / nn
        } else if dn > 0.0 {
            1.0
        } else {
            0.0
        };
        if !change.is_finite() {
            return Err(QpError::NotFinite { what: "the Coulomb fixed point's normal multipliers", outer: it });
        }
        x.copy_from_slice(&sol.lambda);
        if change <= eps && p.common.eps <= eps {
            total.fixed_point_iterations = it;
            let info = FixedPointInfo { iterations: it, change };
            return Ok((QpSolution { info: total, ..sol }, current, info));
        }
        current = bounds(set, mu, &x);
    }
    Err(QpError::FixedPoint { iterations: fp.max_iterations, change, eps })
}

/// The semi-smooth Newton method on the Coulomb law itself (Hüeber–Stadler–Wohlmuth's idea on
/// the dual): F(λ) = λ − P_{Λ(λ)}(λ − ρ r(λ)) = 0 with Λ(λ) the cones cut at λ's own normal
/// multipliers, gᵢ = μᵢ·max(λν,ᵢ, 0). Its slant derivative is SSN's J = I − D(I − ρA) plus, on
/// a sliding pair in contact, the bound's dependence on λν: −μᵢ·yτ/‖yτ‖ in the λν,ᵢ column of
/// the tangential rows. J is unsymmetric: BiCGSTAB inner solves with SSN-BiCGSTAB's adaptive
/// tolerance (its settings when that is the method, else their defaults). Stops at
/// ‖r̃_ρ(λ)‖ ≤ ε‖b‖ over Λ(λ), confirmed at the projection with a fresh product; the returned
/// λ lies in Λ(λ). Isotropic μ only ([`super::solve_friction`] sends orthotropic scenes to the
/// fixed point).
pub fn newton<A: Operator>(qp: &Qp<'_, A>, mu: &[Coefficient], lambda0: &[f64], params: &Params, monitor: &mut dyn Monitor) -> Result<QpSolution, QpError> {
    let p = match &params.method {
        MethodParams::SsnBicgstab(s) => s.clone(),
        _ => Ssn::default(),
    };
    super::ssn::run(qp, Some(mu), lambda0, &params.common, &p, monitor)
}

/// TSSN with lagged bounds on the Coulomb law: each outer step's Newton system is TSSN's over
/// Λ(λᵏ), the cones cut at the iterate's normals (the bound's dependence on λν left out, so the
/// system stays symmetric and takes CG, the preconditioner and the coarse projector); the stop
/// test ‖r̃_ρ(λ)‖ ≤ ε‖b‖ is made over Λ(λ) and confirmed at the projection, so the result is a
/// fixed point of the bounds to ε. Isotropic and orthotropic μ.
pub fn lagged<A: Operator>(qp: &Qp<'_, A>, mu: &[Coefficient], lambda0: &[f64], params: &Params, monitor: &mut dyn Monitor) -> Result<QpSolution, QpError> {
    let p = match &params.method {
        MethodParams::Tssn(t) => t.clone(),
        _ => Tssn::default(),
    };
    super::tssn::run(qp, Some(mu), lambda0, &params.common, &p, monitor)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qp::sets::{Disc, TangentSet};
    use crate::qp::tssn::tests::{lcg, Dense};
    use crate::qp::{kkt, Method, Qp, Replicated, Silent};

    /// m pairs, A random SPD, pressing loads (b_ν > 0) with tangential pushes, Λ with zero discs.
    fn problem(m: usize, mut seed: u64) -> (Dense, Vec<f64>, Lambda) {
        let n = 3 * m;
        let a = Dense::random(n, 1.0, &mut seed);
        let b: Vec<f64> = (0..n).map(|i| if i < m { 2.0 + lcg(&mut seed) } else { 3.0 * lcg(&mut seed) }).collect();
        (a, b, Lambda::new(m, Some(vec![TangentSet::Disc(Disc::new(0.0)); m])))
    }

    #[test]
    fn the_fixed_point_is_a_tresca_solution_with_its_own_bounds() {
        let (m, (a, b, set)) = (10, problem(10, 7));
        let n = 3 * m;
        let mu = vec![Coefficient::Isotropic(0.3); m];
        let p = crate::qp::Params::new(Method::Tssn).with_eps(1e-10);
        let (sol, fixed, info) =
            solve(&Replicated, &set, &mu, &vec![0.0; n], &p, &FixedPoint::default(), |s, x, p| crate::qp::solve(&Qp::new(&a, &b, s), x, p, &mut Silent))
                .expect("the fixed point converges");
        assert!(info.iterations > 1 && info.change <= 1e-10, "{info:?}");
        // the bounds it satisfies are μ times its own normals (to ε)
        for k in 0..m {
            let TangentSet::Disc(d) = fixed.tangent[k] else { panic!("a disc") };
            let want = 0.3 * sol.lambda[k].max(0.0);
            assert!((d.radius - want).abs() <= 1e-8 * (1.0 + want), "pair {k}: bound {} vs μλν {want}", d.radius);
        }
        // a Tresca solve with those bounds from zero gives the same λ
        let t = crate::qp::solve(&Qp::new(&a, &b, &fixed), &vec![0.0; n], &p, &mut Silent).unwrap();
        let d = t.lambda.iter().zip(&sol.lambda).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        assert!(d <= 1e-7, "Tresca with the fixed point's bounds differs by {d:e}");
        let k = kkt::residuals(&fixed, &sol.lambda, &sol.gradient, Replicated.norm(&b));
        assert!(k.worst() <= 1e-8, "KKT {k:?}");
        // some pair slides on its cone
        let on_cone = (0..m)
            .filter(|&k| {
                let (l1, l2) = (sol.lambda[m + 2 * k], sol.lambda[m + 2 * k + 1]);
                sol.lambda[k] > 1e-6 && ((l1 * l1 + l2 * l2).sqrt() - 0.3 * sol.lambda[k]).abs() <= 1e-6 * (1.0 + sol.lambda[k])
            })
            .count();
        assert!(on_cone > 0, "no pair on its friction cone");
        // TSSN with lagged bounds lands on the same λ, and so does the Newton method on the law
        for how in [crate::qp::params::CoulombSolve::Lagged, crate::qp::params::CoulombSolve::Newton] {
            let mut q = p.clone();
            q.common.coulomb = how;
            let l = crate::qp::solve_friction(&Qp::new(&a, &b, &set), Some(&mu), &vec![0.0; n], &q, &mut Silent).unwrap();
            let d = l.lambda.iter().zip(&sol.lambda).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            assert!(l.info.coulomb == Some(how) && d <= 1e-7, "{how:?} differs from the fixed point by {d:e}");
        }
    }

    /// On orthotropic cones (ellipses cut at λν) too: the lagged bounds reach the fixed point's λ.
    #[test]
    fn lagged_bounds_reach_the_fixed_point_on_orthotropic_cones() {
        let (m, (a, b, set)) = (10, problem(10, 9));
        let n = 3 * m;
        let mu = vec![Coefficient::Orthotropic(0.4, 0.1); m];
        let mut p = crate::qp::Params::new(Method::Tssn).with_eps(1e-10);
        let (sol, ..) =
            solve(&Replicated, &set, &mu, &vec![0.0; n], &p, &FixedPoint::default(), |s, x, p| crate::qp::solve(&Qp::new(&a, &b, s), x, p, &mut Silent))
                .unwrap();
        p.common.coulomb = crate::qp::params::CoulombSolve::Lagged;
        let l = crate::qp::solve_friction(&Qp::new(&a, &b, &set), Some(&mu), &vec![0.0; n], &p, &mut Silent).unwrap();
        let d = l.lambda.iter().zip(&sol.lambda).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        assert!(d <= 1e-7, "lagged differs from the fixed point by {d:e}");
        let k = kkt::residuals(&bounds(&set, &mu, &l.lambda), &l.lambda, &l.gradient, Replicated.norm(&b));
        assert!(k.worst() <= 1e-8, "KKT {k:?}");
    }
}
