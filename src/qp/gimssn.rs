//! GIMSSN — the globally convergent, inexact, symmetrized semi-smooth Newton method of the paper
//! (DESIGN §3), with the feasible CG inner solver CGMfeas.
//!
//! Each outer step k: the sets (12)–(13) at λᵏ; `tol_{k+1} = min(rtol·err_k/err_0, cfact·tol_k)`;
//! a projected-gradient step `λ^{k+1,0} = P_Λ(λᵏ − ρ r(λᵏ))` that puts the fixed components
//! (inactive normals: 0; sliding pairs: ψ_g(λ̄τ − ρ r̄τ)) exactly where the Newton system (11)
//! wants them; then CG on the free components from there (CGMfeas), stopped when the free
//! gradient is below the tolerance or — taking the step up to the boundary — when a CG step
//! would leave Λ. Every iterate is in Λ and q(λᵏ) decreases monotonically for ρ ∈ (0, 2/σ_max).
//! ρ = rho_factor/(1.1·σ_est) with σ_est from power iterations (the 1.1 covers their
//! underestimate, DESIGN §3a). Stop: ‖r̃_ρ(λ)‖ ≤ ε‖b‖, confirmed with a fresh A-product.
//!
//! The same loop gives the paper's two other symmetrized variants ([`Variant`]): **IMSSN** fixes
//! the components of (11) but starts CG from λᵏ's free components, runs CG without the
//! feasibility test, and measures the error at P_Λ(λ^{k+1}) (one more product per step); the
//! result is P_Λ(λ). **MSSN** is IMSSN with the free-set system solved to round-off.

use super::lambda::Lambda;
use crate::dual::DualOperator;

/// What the CG tolerance is relative to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CgStop {
    /// ‖g_F‖ ≤ tol·‖b‖ (the faster choice, DESIGN §3a).
    Rhs,
    /// ‖g_F‖ ≤ tol·‖g_F at the start of CG‖ (the paper's).
    InitialGradient,
}

#[derive(Clone, Debug)]
pub struct Params {
    /// ε: stop when ‖r̃_ρ(λ)‖ ≤ ε‖b‖.
    pub eps: f64,
    /// ρ = rho_factor / (1.1 σ_est); must stay below 2 for the monotone theory.
    pub rho_factor: f64,
    pub rtol: f64,
    pub cfact: f64,
    pub max_outer: usize,
    /// CG iterations per outer step at most.
    pub max_inner: usize,
    pub power_iterations: usize,
    pub cg_stop: CgStop,
    pub variant: Variant,
}

/// Which member of the symmetrized semi-smooth Newton family runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// Monotone, feasible (CGMfeas), globally convergent.
    Gimssn,
    /// Inexact: CG to the adaptive tolerance, iterates may leave Λ.
    Imssn,
    /// Exact inner solves.
    Mssn,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            eps: 1e-6,
            rho_factor: 1.9,
            rtol: 0.5,
            cfact: 0.9,
            max_outer: 1000,
            max_inner: 10_000,
            power_iterations: 30,
            cg_stop: CgStop::Rhs,
            variant: Variant::Gimssn,
        }
    }
}

/// One outer iteration.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// ‖r̃_ρ(λ^{k+1})‖ / ‖b‖.
    pub err: f64,
    pub tol: f64,
    pub q: f64,
    pub normal_active: usize,
    pub stick: usize,
    pub slip: usize,
    /// CG iterations of this step.
    pub inner: usize,
    /// A-products so far (without the power iterations).
    pub n_a: usize,
}

/// Counters of a solve.
#[derive(Clone, Debug, Default)]
pub struct Info {
    pub iterations: usize,
    /// A-products, the power iterations excluded.
    pub n_a: usize,
    /// A-products of the power iterations for σ_max.
    pub n_a_power: usize,
    pub inner_iterations: usize,
    pub sigma_est: f64,
    pub rho: f64,
    /// Final ‖r̃_ρ(λ)‖/‖b‖ from a fresh product.
    pub err: f64,
    pub q: f64,
    pub history: Vec<Step>,
}

/// Why a solve failed.
#[derive(Clone, Debug, thiserror::Error)]
pub enum QpError {
    #[error("no convergence in {} outer iterations (‖r̃‖/‖b‖ = {:.3e}, ε = {eps:.1e})", info.iterations, info.err)]
    NoConvergence { info: Box<Info>, eps: f64 },
    #[error("CG breakdown: pᵀAp = {p_ap:.3e} ≤ 0 at outer iteration {outer} (A not positive definite on the free set)")]
    Breakdown { outer: usize, p_ap: f64 },
    #[error("non-finite value (NaN or infinity) in {what} at outer iteration {outer}")]
    NotFinite { what: &'static str, outer: usize },
}

/// σ_max(A) by `iterations` power iterations from a fixed start vector.
pub fn power_sigma<A: DualOperator>(a: &A, iterations: usize) -> f64 {
    let n = a.dim();
    let mut x: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * ((i * 7919) % 13) as f64).collect();
    let nx = a.norm(&x);
    x.iter_mut().for_each(|v| *v /= nx);
    let mut y = vec![0.0; n];
    let mut sigma = 0.0;
    for _ in 0..iterations {
        a.apply(&x, &mut y);
        sigma = a.norm(&y);
        if sigma == 0.0 || !sigma.is_finite() {
            break;
        }
        for (xi, yi) in x.iter_mut().zip(&y) {
            *xi = yi / sigma;
        }
    }
    sigma
}

fn q_of<A: DualOperator>(a: &A, lambda: &[f64], r: &[f64], b: &[f64]) -> f64 {
    // q = ½λᵀAλ − λᵀb = ½λᵀ(r − b) with r = Aλ − b
    let rb: Vec<f64> = r.iter().zip(b).map(|(x, y)| x - y).collect();
    0.5 * a.dot(lambda, &rb)
}

/// The result of a QP solve.
#[derive(Clone, Debug)]
pub struct QpSolution {
    /// λ ∈ Λ.
    pub lambda: Vec<f64>,
    /// r(λ) = Aλ − b from a fresh product (= −(Bu − c)).
    pub gradient: Vec<f64>,
    pub info: Info,
}

/// Solves min ½λᵀAλ − λᵀb over Λ from λ0 (projected onto Λ first).
pub fn solve<A: DualOperator>(a: &A, b: &[f64], set: &Lambda, lambda0: &[f64], p: &Params) -> Result<QpSolution, QpError> {
    let n = a.dim();
    let n0 = a.products();
    let sigma = power_sigma(a, p.power_iterations);
    let n_power = a.products() - n0;
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(QpError::NotFinite { what: "the σ_max estimate", outer: 0 });
    }
    let rho = p.rho_factor / (1.1 * sigma);
    let bnorm = a.norm(b).max(f64::MIN_POSITIVE);
    let products = || a.products() - n0 - n_power;
    let residual = |x: &[f64], r: &mut [f64]| {
        a.apply(x, r);
        r.iter_mut().zip(b).for_each(|(ri, bi)| *ri -= bi);
    };
    let mut lambda = vec![0.0; n];
    set.project(lambda0, &mut lambda);
    let mut r = vec![0.0; n];
    residual(&lambda, &mut r);
    let mut rt = vec![0.0; n];
    let err_of = |lambda: &[f64], r: &[f64], rt: &mut [f64]| {
        set.reduced_gradient(lambda, r, rho, rt);
        a.norm(rt) / bnorm
    };
    let mut err = err_of(&lambda, &r, &mut rt);
    let err0 = err.max(f64::MIN_POSITIVE);
    let mut tol = p.rtol / p.cfact;
    let mut info = Info { sigma_est: sigma, rho, n_a_power: n_power, ..Default::default() };
    let (mut x, mut g, mut gf, mut d, mut ad) =
        (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut y = vec![0.0; n];
    let feasible = p.variant == Variant::Gimssn;
    // (z, rz): the point in Λ the error is measured at and its gradient; for GIMSSN z = λ
    let (mut z, mut rz) = (lambda.clone(), r.clone());
    let mut pz = vec![0.0; n];
    for k in 0.. {
        if !err.is_finite() {
            return Err(QpError::NotFinite { what: "the reduced gradient", outer: k });
        }
        if err <= p.eps {
            if feasible {
                // confirm with a fresh product: the CG recurrences drift
                residual(&z, &mut rz);
                err = err_of(&z, &rz, &mut rt);
            }
            if err <= p.eps {
                info.iterations = k;
                info.err = err;
                info.q = q_of(a, &z, &rz, b);
                info.n_a = products();
                return Ok(QpSolution { lambda: z, gradient: rz, info });
            }
        }
        if k == p.max_outer {
            info.iterations = k;
            info.err = err;
            info.n_a = products();
            return Err(QpError::NoConvergence { info: Box::new(info), eps: p.eps });
        }
        let sets = set.active_sets(&lambda, &r, rho);
        tol = (p.rtol * err / err0).min(p.cfact * tol);
        // the fixed components as (11) wants them: P_Λ(λᵏ − ρ r(λᵏ)) there
        for i in 0..n {
            y[i] = lambda[i] - rho * r[i];
        }
        set.project(&y, &mut x);
        if !feasible {
            // IMSSN/MSSN: the free components start from λᵏ
            for i in 0..n {
                if sets.free[i] {
                    x[i] = lambda[i];
                }
            }
        }
        residual(&x, &mut g);
        // CG on the free set (CGMfeas for GIMSSN)
        let masked = |g: &[f64], out: &mut [f64]| {
            for i in 0..n {
                out[i] = if sets.free[i] { g[i] } else { 0.0 };
            }
        };
        masked(&g, &mut gf);
        let gf0 = a.norm(&gf);
        let scale = match p.cg_stop {
            CgStop::Rhs => bnorm,
            CgStop::InitialGradient => gf0,
        };
        let threshold = match p.variant {
            Variant::Mssn => 1e-13 * bnorm,
            // never ask CG for more than a tenth of the outer tolerance (round-off floor)
            _ => (tol * scale).max(0.1 * p.eps * bnorm),
        };
        d.copy_from_slice(&gf);
        let mut inner = 0;
        let mut gg = gf0 * gf0;
        while gg.sqrt() > threshold && inner < p.max_inner {
            a.apply(&d, &mut ad);
            inner += 1;
            let dad = a.dot(&d, &ad);
            if !(dad > 0.0) {
                if !dad.is_finite() {
                    return Err(QpError::NotFinite { what: "the CG curvature pᵀAp", outer: k });
                }
                return Err(QpError::Breakdown { outer: k, p_ap: dad });
            }
            let alpha = a.dot(&gf, &d) / dad;
            if feasible {
                let alpha_f = set.max_step(&x, &d);
                if alpha > alpha_f {
                    // the CG step would leave Λ: go to the boundary and stop
                    for i in 0..n {
                        x[i] -= alpha_f * d[i];
                        g[i] -= alpha_f * ad[i];
                    }
                    break;
                }
            }
            for i in 0..n {
                x[i] -= alpha * d[i];
                g[i] -= alpha * ad[i];
            }
            masked(&g, &mut gf);
            let beta = a.dot(&gf, &ad) / dad;
            for i in 0..n {
                d[i] = gf[i] - beta * d[i];
            }
            gg = a.dot(&gf, &gf);
        }
        std::mem::swap(&mut lambda, &mut x);
        std::mem::swap(&mut r, &mut g);
        if feasible {
            z.copy_from_slice(&lambda);
            rz.copy_from_slice(&r);
        } else {
            set.project(&lambda, &mut pz);
            std::mem::swap(&mut z, &mut pz);
            residual(&z, &mut rz);
        }
        err = err_of(&z, &rz, &mut rt);
        info.inner_iterations += inner;
        info.history.push(Step {
            err,
            tol,
            q: q_of(a, &z, &rz, b),
            normal_active: sets.normal_active,
            stick: sets.stick,
            slip: sets.slip,
            inner,
            n_a: products(),
        });
    }
    unreachable!("the outer loop returns")
}
