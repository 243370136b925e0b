//! SMALSE-M on the TFETI dual: the alternative to the oblique projector that keeps the
//! orthogonal projector P = I − Gᵀ(GGᵀ)⁻¹G (docs/method.md, "TFETI and H-TFETI", Dostál's SMALSE-M with the QP solver as
//! the inner loop), and the one that solves bodies held by contact alone: G = RᵀBᵀ spans every
//! row, so Gλ = e holds with bounded multipliers and C = G_E G_Eᵀ may be singular. With
//! Q = I − P and λ_e = Gᵀ(GGᵀ)⁻¹e (Gλ = e ⇔ Qλ = λ_e, and then λ = Pλ + λ_e) the problem is
//!
//! ```text
//! min ½λᵀPFPλ − λᵀP(d̃ − Fλ_e)   subject to  Qλ = λ_e,  λ_I ∈ Λ,
//! ```
//!
//! and each outer step k minimizes the augmented Lagrangian
//! `½λᵀ(PFP + ϱQ)λ − λᵀ(P(d̃ − Fλ_e) + ϱλ_e − ν_k)` over Λ (ν_k kept as a vector in Im Gᵀ)
//! with any of the QP solvers, then updates ν_{k+1} = ν_k + ϱ(Qλ − λ_e). ϱ = penalty·σ_max(PFP)
//! (σ measured once; penalty 1 by default): the penalty then does not raise ‖A‖, so the inner
//! solvers keep their step length, and PFP on Ker G is far better conditioned than P̃FP̃ᵀ
//! (docs/method.md, "The solvers"). The inner tolerance follows the feasibility: ε_{k+1} = max(ε, min(ε_k,
//! Mϱ‖Qλ − λ_e‖/‖P(d̃ − Fλ_e)‖)), M = 1, ε_1 = 1e-2. Stop when both ‖r̃_ρ‖ and ϱ‖Qλ − λ_e‖ (the
//! infeasibility in the gradient's units) are below ε‖P(d̃ − Fλ_e)‖.
//!
//! A FETI preconditioner M of F acts on A_ϱ as `P M P + ϱ⁻¹Q` ([`PenalizedPreconditioner`]):
//! A_ϱ is PFP on Ker G = Im P and ϱ on Im Q, so this is its inverse where M is F's on Ker G.

use super::distribution::Distribution;
use super::dual::TfetiDual;
use crate::comm::Comm;
use crate::qp::cone::Coefficient;
use crate::qp::{self, Info, Lambda, Monitor, Operator, Params, Preconditioner, ProductCounter, Qp, QpError, QpSolution, Space, SIGMA_SAFETY};

/// A_ϱ = PFP + ϱQ.
pub struct Penalized<'a, 'c, C: Comm> {
    dual: &'a TfetiDual<'c, C>,
    /// The penalty ϱ.
    pub penalty: f64,
    counter: ProductCounter,
}

impl<'a, 'c, C: Comm> Penalized<'a, 'c, C> {
    pub fn new(dual: &'a TfetiDual<'c, C>, penalty: f64) -> Self {
        Penalized { dual, penalty, counter: ProductCounter::default() }
    }

    /// Q x = x − P x.
    fn q(&self, x: &[f64]) -> Vec<f64> {
        let mut p = x.to_vec();
        self.dual.coarse.project_orthogonal(&self.dual.dist, &mut p);
        x.iter().zip(&p).map(|(a, b)| a - b).collect()
    }
}

impl<'c, C: Comm> Operator for Penalized<'_, 'c, C> {
    /// The TFETI dual's distributed vectors.
    type Space = Distribution<'c, C>;
    fn space(&self) -> &Distribution<'c, C> {
        self.dual.space()
    }

    fn dim(&self) -> usize {
        self.dual.dim()
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.counter.tick();
        let mut w = x.to_vec();
        self.dual.coarse.project_orthogonal(&self.dual.dist, &mut w);
        self.dual.apply_f(&w, y);
        self.dual.coarse.project_orthogonal(&self.dual.dist, y);
        // + ϱ Q x = ϱ (x − P x)
        for ((yi, xi), wi) in y.iter_mut().zip(x).zip(&w) {
            *yi += self.penalty * (xi - wi);
        }
    }

    fn products(&self) -> usize {
        self.counter.get()
    }
}

/// The smallest residual, relative to σ‖λ‖, that double precision reaches on the dual
/// gradient (1000 ε_mach): SMALSE-M's residual scale is kept at least this over ε.
const REACHABLE: f64 = 1e3 * f64::EPSILON;

/// `P M P + ϱ⁻¹Q` ≈ A_ϱ⁻¹ from a preconditioner M of F on every row.
pub struct PenalizedPreconditioner<'a, 'c, C: Comm> {
    dual: &'a TfetiDual<'c, C>,
    m: &'a dyn Preconditioner,
    penalty: f64,
}

impl<C: Comm> Preconditioner for PenalizedPreconditioner<'_, '_, C> {
    fn block(&self) -> std::ops::Range<usize> {
        0..self.dual.dim()
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        let mut px = x.to_vec();
        self.dual.coarse.project_orthogonal(&self.dual.dist, &mut px);
        self.m.apply(&px, y);
        self.dual.coarse.project_orthogonal(&self.dual.dist, y);
        for ((yi, xi), pi) in y.iter_mut().zip(x).zip(&px) {
            *yi += (xi - pi) / self.penalty;
        }
    }
}

/// Counters of the outer loop beside the summed inner [`Info`].
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct SmalseInfo {
    pub outer: usize,
    pub penalty: f64,
    /// ϱ‖Qλ̃‖/‖Pd̂‖ at the end.
    pub feasibility: f64,
    /// A-products of this solve (the σ_max estimate's excluded): with the accuracy guard, of
    /// its last solve only.
    #[serde(default, rename = "nA")]
    pub n_a: usize,
    /// The multipliers ν of Gλ = e at the end (this rank's part): a later solve of the same
    /// dual (the accuracy guard's at a tighter ε) continues from them.
    #[serde(skip)]
    pub nu: Vec<f64>,
    /// The inner tolerance ε_k the outer loop had reached.
    #[serde(skip)]
    pub eps_k: f64,
}

/// Solves the TFETI dual by SMALSE-M from λ = `x0` with `p.method` inside (with `coulomb`
/// coefficients per pair: the Coulomb problem, each inner step by [`qp::solve_friction`]) and ϱ =
/// `penalty`·σ_max(PFP) (`p.common.sigma` when given), the inner solves preconditioned by
/// [`PenalizedPreconditioner`] when `m` (a preconditioner of F) is given; returns λ with the inner solvers'
/// counters summed (A-products of A_ϱ = F-products). The dual must be built with the orthogonal
/// projector (its λ̂ solves Gλ̂ = e; λ = λ̂ is the natural start). With `warm`, an earlier
/// solve of the same dual and b that stopped at λ = `x0` (the accuracy guard's re-solve at a
/// tighter ε), its ν and ε_k are kept when its ϱ is this one's: the first inner solve then
/// starts at its own minimizer's neighbourhood, where ν = 0 would pull λ back to the first
/// outer step's and repeat the whole outer loop.
#[allow(clippy::too_many_arguments)]
pub fn solve<C: Comm>(
    dual: &TfetiDual<'_, C>,
    m: Option<&dyn Preconditioner>,
    set: &Lambda,
    coulomb: Option<&[Coefficient]>,
    x0: &[f64],
    warm: Option<&SmalseInfo>,
    p: &Params,
    penalty: f64,
    monitor: &mut dyn Monitor,
) -> Result<(QpSolution, SmalseInfo), QpError> {
    let sp = dual.space();
    // the dual's λ̂ solves Gλ̂ = e; λ_e = Qλ̂, and P(d̃ − Fλ_e) = P(d̃ − Fλ̂) + PFPλ̂
    let lambda_p = dual.dist.owned_part(&dual.lambda_hat);
    let mut op = Penalized::new(dual, 0.0);
    let lambda_e = op.q(&lambda_p);
    let mut b0 = dual.d_hat.clone();
    dual.coarse.project_orthogonal(&dual.dist, &mut b0);
    let pl: Vec<f64> = lambda_p.iter().zip(&lambda_e).map(|(a, b)| a - b).collect();
    let shifted = sp.norm(&pl) > 0.0;
    if shifted {
        let mut y = vec![0.0; pl.len()];
        op.apply(&pl, &mut y);
        b0.iter_mut().zip(&y).for_each(|(b, v)| *b += v);
    }
    let b0_norm = sp.norm(&b0);
    let n_power = if p.common.sigma.is_some() { 0 } else { p.common.power_iterations };
    let sigma = p.common.sigma.unwrap_or_else(|| qp::estimate_sigma(&op, &p.common));
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(QpError::NotFinite { what: "the σ_max estimate", outer: 0 });
    }
    op.penalty = penalty * sigma;
    let pm = m.map(|m| PenalizedPreconditioner { dual, m, penalty: op.penalty });
    let sigma = sigma.max(op.penalty);
    let mut lambda = x0.to_vec();
    let warm = warm.filter(|w| w.nu.len() == x0.len() && w.penalty == op.penalty);
    let mut nu = warm.map_or_else(|| vec![0.0; x0.len()], |w| w.nu.clone());
    // ϱλ_e: the penalty's pull toward Gλ = e
    let b0: Vec<f64> = b0.iter().zip(&lambda_e).map(|(b, l)| b + op.penalty * l).collect();
    // the scale of the residuals: ‖P(d̃ − Fλ̂)‖, but not below what ε of it double precision
    // can reach on a gradient of size σ‖λ_e‖ — where Gλ = e alone carries the load (a body
    // held by contact alone, pressed uniformly) the projected rhs is round-off
    let eps = p.common.eps;
    let bnorm = b0_norm.max(REACHABLE / eps * sigma * sp.norm(&lambda_e)).max(f64::MIN_POSITIVE);
    let mut eps_k = eps.max(warm.map_or(1e-2, |w| w.eps_k.min(1e-2)));
    let mut total = Info { sigma_est: sigma, n_a_power: n_power, n_a: usize::from(shifted), ..Default::default() };
    let mut sm = SmalseInfo { penalty: op.penalty, ..Default::default() };
    // the gradient A_ϱλ − b_k at λ, once an inner solve has left one
    let mut gradient: Option<Vec<f64>> = None;
    for k in 0..p.common.max_outer {
        let b: Vec<f64> = b0.iter().zip(&nu).map(|(a, v)| a - v).collect();
        let bk = sp.norm(&b).max(f64::MIN_POSITIVE);
        let mut inner = p.clone();
        inner.common.eps = eps_k * bnorm / bk;
        inner.common.sigma = Some(SIGMA_SAFETY * sigma);
        inner.common.power_iterations = 0;
        let qp = Qp::new(&op, &b, set)
            .with_preconditioner(pm.as_ref().map(|m| m as &dyn Preconditioner))
            .with_start(gradient.as_deref().map(|g| (lambda.as_slice(), g)));
        let sol = qp::solve_friction(&qp, coulomb, &lambda, &inner, monitor)?;
        total.preconditioner_applications += sol.info.preconditioner_applications;
        lambda = sol.lambda;
        let err = sol.info.err * bk / bnorm;
        total.iterations += sol.info.iterations;
        total.inner_iterations += sol.info.inner_iterations;
        total.fixed_point_iterations += sol.info.fixed_point_iterations;
        total.n_a += sol.info.n_a;
        total.rho = sol.info.rho;
        total.q = sol.info.q;
        total.history.extend(sol.info.history);
        let ql: Vec<f64> = op.q(&lambda).iter().zip(&lambda_e).map(|(q, l)| q - l).collect();
        let feas = op.penalty * sp.norm(&ql) / bnorm;
        sm.outer = k + 1;
        sm.feasibility = feas;
        total.err = err.max(feas);
        if err <= eps && feas <= eps {
            (sm.nu, sm.eps_k, sm.n_a) = (nu, eps_k, total.n_a);
            return Ok((QpSolution { lambda, gradient: sol.gradient, info: total }, sm));
        }
        nu.iter_mut().zip(&ql).for_each(|(v, q)| *v += op.penalty * q);
        // b_{k+1} = b_k − ϱ(Qλ − λ_e): the next inner solve's gradient at this λ without a product
        let mut g = sol.gradient;
        g.iter_mut().zip(&ql).for_each(|(r, q)| *r += op.penalty * q);
        gradient = Some(g);
        eps_k = eps.max(eps_k.min(feas));
    }
    Err(QpError::NoConvergence { info: Box::new(total), eps })
}
