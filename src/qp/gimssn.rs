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
//! The same loop gives the paper's two other symmetrized variants: **IMSSN** fixes
//! the components of (11) but starts CG from λᵏ's free components, runs CG without the
//! feasibility test, and projects: λ^{k+1} = P_Λ(CG result), with a fresh gradient (one more
//! product per step). (Going on from the unprojected CG result instead, as a literal reading of
//! the paper allows, took 13 steps where the paper reports 10 at N = 16; from the projected one
//! we get the paper's 10.) **MSSN** is IMSSN with the free-set system solved to round-off.
//!
//! The variant is `Params::method` (GIMSSN, IMSSN or MSSN).

use super::lambda::Lambda;
use super::{curvature, err_of, q_of, residual, CgStop, Info, Method, Params, QpError, QpSolution, Setup, Step};
use crate::dual::DualOperator;

/// Solves min ½λᵀAλ − λᵀb over Λ from λ0 (projected onto Λ first).
pub fn solve<A: DualOperator>(a: &A, b: &[f64], set: &Lambda, lambda0: &[f64], p: &Params) -> Result<QpSolution, QpError> {
    let n = a.dim();
    let st = Setup::new(a, b, p)?;
    let (rho, bnorm) = (st.rho, st.bnorm);
    let products = || st.products(a);
    let residual = |x: &[f64], r: &mut [f64]| residual(a, b, x, r);
    let variant = p.method;
    let mut lambda = vec![0.0; n];
    set.project(lambda0, &mut lambda);
    let mut r = vec![0.0; n];
    residual(&lambda, &mut r);
    let mut rt = vec![0.0; n];
    let err_of = |lambda: &[f64], r: &[f64], rt: &mut [f64]| err_of(a, set, lambda, r, &st, rt);
    let mut err = err_of(&lambda, &r, &mut rt);
    let err0 = err.max(f64::MIN_POSITIVE);
    let mut tol = p.rtol / p.cfact;
    let mut info: Info = st.info();
    let (mut x, mut g) = (vec![0.0; n], vec![0.0; n]);
    let mut y = vec![0.0; n];
    let feasible = variant == Method::Gimssn;
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
        if k == p.max_outer || products() >= p.max_products {
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
        let threshold = match variant {
            Method::Mssn => 1e-13 * bnorm,
            _ => {
                let scale = match p.cg_stop {
                    CgStop::Rhs => bnorm,
                    CgStop::InitialGradient => free_norm(a, &sets.free, &g),
                };
                // never ask CG for much more than the outer tolerance (inner_floor·ε·‖b‖)
                (tol * scale).max(p.inner_floor * p.eps * bnorm)
            }
        };
        let inner = cg_free(a, set, &sets.free, &mut x, &mut g, threshold, p.max_inner, feasible, k)?;
        std::mem::swap(&mut lambda, &mut x);
        std::mem::swap(&mut r, &mut g);
        if feasible {
            z.copy_from_slice(&lambda);
            rz.copy_from_slice(&r);
        } else {
            set.project(&lambda, &mut pz);
            std::mem::swap(&mut z, &mut pz);
            residual(&z, &mut rz);
            // go on from the projected iterate (its gradient is at hand)
            lambda.copy_from_slice(&z);
            r.copy_from_slice(&rz);
        }
        err = err_of(&z, &rz, &mut rt);
        info.inner_iterations += inner;
        info.history.push(Step::newton(a, err, tol, q_of(a, &z, &rz, b), &sets, inner, products()));
    }
    unreachable!("the outer loop returns")
}

/// ‖g‖ on the free components.
fn free_norm<A: DualOperator>(a: &A, free: &[bool], g: &[f64]) -> f64 {
    let gf: Vec<f64> = g.iter().zip(free).map(|(v, f)| if *f { *v } else { 0.0 }).collect();
    a.norm(&gf)
}

/// CG on the components `free` from x with g = r(x), the others frozen, until the free gradient
/// is at most `threshold`; `feasible` (CGMfeas): stop at the boundary of Λ, with the step taken
/// up to it, when a CG step would leave Λ. x and g = r(x) (by the recurrence) are updated;
/// returns the CG iterations (one A-product each).
#[allow(clippy::too_many_arguments)]
fn cg_free<A: DualOperator>(a: &A, set: &Lambda, free: &[bool], x: &mut [f64], g: &mut [f64], threshold: f64, max_inner: usize, feasible: bool, outer: usize) -> Result<usize, QpError> {
    let n = x.len();
    let masked = |g: &[f64], out: &mut [f64]| {
        for i in 0..n {
            out[i] = if free[i] { g[i] } else { 0.0 };
        }
    };
    let (mut gf, mut ad) = (vec![0.0; n], vec![0.0; n]);
    masked(g, &mut gf);
    let mut d = gf.clone();
    let mut gg = a.dot(&gf, &gf);
    let mut inner = 0;
    while gg.sqrt() > threshold && inner < max_inner {
        let dad = curvature(a, &d, &mut ad, outer)?;
        inner += 1;
        let alpha = a.dot(&gf, &d) / dad;
        if feasible {
            let alpha_f = a.min(set.max_step(x, &d));
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
        masked(g, &mut gf);
        let beta = a.dot(&gf, &ad) / dad;
        for i in 0..n {
            d[i] = gf[i] - beta * d[i];
        }
        gg = a.dot(&gf, &gf);
    }
    Ok(inner)
}

/// The result of one [`feasible_step`].
pub(crate) struct FeasibleStep {
    pub lambda: Vec<f64>,
    pub gradient: Vec<f64>,
    pub inner: usize,
}

/// One GIMSSN step from λ ∈ Λ with r = r(λ): the sets at λ, the projected-gradient step
/// P_Λ(λ − ρr) (one product for its gradient), then CGMfeas to `threshold`. q does not increase
/// for ρ < 2/σ_max. (TSSN's safeguard.)
#[allow(clippy::too_many_arguments)]
pub(crate) fn feasible_step<A: DualOperator>(a: &A, b: &[f64], set: &Lambda, lambda: &[f64], r: &[f64], rho: f64, threshold: f64, max_inner: usize, outer: usize) -> Result<FeasibleStep, QpError> {
    let sets = set.active_sets(lambda, r, rho);
    let y: Vec<f64> = lambda.iter().zip(r).map(|(l, g)| l - rho * g).collect();
    let mut x = vec![0.0; y.len()];
    set.project(&y, &mut x);
    let mut g = vec![0.0; y.len()];
    residual(a, b, &x, &mut g);
    let inner = cg_free(a, set, &sets.free, &mut x, &mut g, threshold, max_inner, true, outer)?;
    Ok(FeasibleStep { lambda: x, gradient: g, inner })
}
