//! SMALSE-M on the TFETI dual: the alternative to the oblique projector that keeps the
//! orthogonal projector P = I − Gᵀ(GGᵀ)⁻¹G (DESIGN §2, Dostál's SMALSE-M with the QP solver as
//! the inner loop). With λ = λ̂ + λ̃ (λ̂_I = 0, so λ̃_I = λ_I and Λ is unchanged) the problem is
//!
//! ```text
//! min ½λ̃ᵀFλ̃ − λ̃ᵀd̂   subject to  Gλ̃ = 0,  λ̃_I ∈ Λ,        d̂ = d̃ − Fλ̂,
//! ```
//!
//! and each outer step k minimizes the augmented Lagrangian
//! `½λ̃ᵀ(PFP + ϱQ)λ̃ − λ̃ᵀ(Pd̂ − ν_k)` over Λ (Q = I − P, ν_k = Gᵀμ_k kept as a vector in Im Gᵀ)
//! with any of the QP solvers, then updates ν_{k+1} = ν_k + ϱQλ̃. ϱ = penalty·σ_max(PFP) (σ measured
//! once by power iterations; penalty 1 by default): the penalty then does not raise ‖A‖, so the inner solvers keep their
//! step length, and PFP on Ker G is far better conditioned than P̃FP̃ᵀ (DESIGN §3a). The inner
//! tolerance follows the feasibility: ε_{k+1} = max(ε, min(ε_k, Mϱ‖Qλ̃_k‖/‖Pd̂‖)), M = 1, ε_1 =
//! 1e-2. Stop when both ‖r̃_ρ‖ and ϱ‖Qλ̃‖ (the infeasibility in the gradient's units) are below
//! ε‖Pd̂‖.

use super::distribution::Distribution;
use super::dual::TfetiDual;
use crate::comm::Comm;
use crate::qp::{self, Info, Lambda, Monitor, Operator, Params, ProductCounter, Qp, QpError, QpSolution, Space, SIGMA_SAFETY};

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

/// Counters of the outer loop beside the summed inner [`Info`].
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct SmalseInfo {
    pub outer: usize,
    pub penalty: f64,
    /// ϱ‖Qλ̃‖/‖Pd̂‖ at the end.
    pub feasibility: f64,
}

/// Solves the TFETI dual by SMALSE-M with `p.method` inside and ϱ = `penalty`·σ_max(PFP); returns λ̃ (λ = λ̂ + λ̃) with the
/// inner solvers' counters summed (A-products of A_ϱ = F-products).
pub fn solve<C: Comm>(dual: &TfetiDual<'_, C>, set: &Lambda, p: &Params, penalty: f64, monitor: &mut dyn Monitor) -> Result<(QpSolution, SmalseInfo), QpError> {
    let n = dual.dim();
    let sp = dual.space();
    let mut b0 = dual.d_hat.clone();
    dual.coarse.project_orthogonal(&dual.dist, &mut b0);
    let bnorm = sp.norm(&b0).max(f64::MIN_POSITIVE);
    let mut op = Penalized::new(dual, 0.0);
    let n_power = p.common.power_iterations;
    let sigma = qp::estimate_sigma(&op, &p.common);
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(QpError::NotFinite { what: "the σ_max estimate", outer: 0 });
    }
    op.penalty = penalty * sigma;
    let sigma = sigma.max(op.penalty);
    let mut lambda = vec![0.0; n];
    let mut nu = vec![0.0; n];
    let eps = p.common.eps;
    let mut eps_k = eps.max(1e-2);
    let mut total = Info { sigma_est: sigma, n_a_power: n_power, ..Default::default() };
    let mut sm = SmalseInfo { penalty: op.penalty, ..Default::default() };
    for k in 0..p.common.max_outer {
        let b: Vec<f64> = b0.iter().zip(&nu).map(|(a, v)| a - v).collect();
        let bk = sp.norm(&b).max(f64::MIN_POSITIVE);
        let mut inner = p.clone();
        inner.common.eps = eps_k * bnorm / bk;
        inner.common.sigma = Some(SIGMA_SAFETY * sigma);
        inner.common.power_iterations = 0;
        let sol = qp::solve(&Qp::new(&op, &b, set), &lambda, &inner, monitor)?;
        lambda = sol.lambda;
        let err = sol.info.err * bk / bnorm;
        total.iterations += sol.info.iterations;
        total.inner_iterations += sol.info.inner_iterations;
        total.n_a += sol.info.n_a;
        total.rho = sol.info.rho;
        total.q = sol.info.q;
        total.history.extend(sol.info.history);
        let ql = op.q(&lambda);
        let feas = op.penalty * sp.norm(&ql) / bnorm;
        sm.outer = k + 1;
        sm.feasibility = feas;
        total.err = err.max(feas);
        if err <= eps && feas <= eps {
            return Ok((QpSolution { lambda, gradient: sol.gradient, info: total }, sm));
        }
        nu.iter_mut().zip(&ql).for_each(|(v, q)| *v += op.penalty * q);
        eps_k = eps.max(eps_k.min(feas));
    }
    Err(QpError::NoConvergence { info: Box::new(total), eps })
}
