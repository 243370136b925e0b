//! GIMSSN — the globally convergent, inexact, symmetrized semi-smooth Newton method of the paper
//! (docs/method.md, "The solvers"), with the feasible CG inner solver CGMfeas.
//!
//! Each outer step k: the sets (12)–(13) at λᵏ; `tol_{k+1} = min(rtol·err_k/err_0, cfact·tol_k)`;
//! a projected-gradient step `λ^{k+1,0} = P_Λ(λᵏ − ρ r(λᵏ))` that puts the fixed components
//! (inactive normals: 0; sliding pairs: ψ_g(λ̄τ − ρ r̄τ)) exactly where the Newton system (11)
//! wants them; then CG on the free components from there (CGMfeas), stopped when the free
//! gradient is below the tolerance or — taking the step up to the boundary — when a CG step
//! would leave Λ. Every iterate is in Λ and q(λᵏ) decreases monotonically for ρ ∈ (0, 2/σ_max).
//! ρ = rho_factor/(1.1·σ_est) with σ_est from power iterations (the 1.1 covers their
//! underestimate, docs/method.md, "The solvers"). Stop: ‖r̃_ρ(λ)‖ ≤ ε‖b‖, confirmed with a fresh A-product.
//!
//! The same loop gives the paper's two other symmetrized variants: **IMSSN** fixes
//! the components of (11) but starts CG from λᵏ's free components, runs CG without the
//! feasibility test, and projects: λ^{k+1} = P_Λ(CG result), with a fresh gradient (one more
//! product per step); going on from the projected iterate, not the unprojected CG result that
//! a literal reading of the paper allows, is what reproduces the paper's step counts (docs/validation.md,
//! "The paper's benchmark"). **MSSN** is IMSSN with the free-set system solved to round-off.
//!
//! The variant is [`Variant`] (GIMSSN, IMSSN or MSSN).

use super::driver::{Driver, Monitor, Setup};
use super::krylov::{pcg, Coefficients, Masked, Pcg};
use super::lambda::Lambda;
use super::operator::Operator;
use super::params::{Common, Inexact};
use super::{CgStop, Qp, QpError, QpSolution, StepKind};

/// Which of the symmetrized methods.
#[derive(Clone, Copy, Debug)]
pub enum Variant<'a> {
    /// GIMSSN: feasible CGMfeas, monotone.
    Feasible(&'a Inexact),
    /// IMSSN: CG unconstrained, then projected.
    Inexact(&'a Inexact),
    /// MSSN: IMSSN with exact inner solves.
    Exact,
}

/// Solves min ½λᵀAλ − λᵀb over Λ from λ0 (projected onto Λ first).
pub fn solve<A: Operator>(qp: &Qp<'_, A>, lambda0: &[f64], c: &Common, variant: Variant<'_>, monitor: &mut dyn Monitor) -> Result<QpSolution, QpError> {
    let (a, set) = (qp.a, qp.set);
    let n = a.dim();
    let mut drv = Driver::new(qp, Setup::new(a, qp.b, c)?, c, monitor);
    let (rho, bnorm) = (drv.st.rho, drv.st.bnorm);
    let mut lambda = vec![0.0; n];
    set.project(lambda0, &mut lambda);
    let mut r = vec![0.0; n];
    drv.residual(&lambda, &mut r);
    let mut rt = vec![0.0; n];
    let mut err = drv.err(&lambda, &r, &mut rt);
    let err0 = err.max(f64::MIN_POSITIVE);
    // MSSN records no tolerance of its own
    let adaptive = match variant {
        Variant::Feasible(m) | Variant::Inexact(m) => Some(m),
        Variant::Exact => None,
    };
    let mut tol = adaptive.map_or(0.0, |m| m.rtol / m.cfact);
    let (mut x, mut g) = (vec![0.0; n], vec![0.0; n]);
    let mut y = vec![0.0; n];
    let feasible = matches!(variant, Variant::Feasible(_));
    // (z, rz): the point in Λ the error is measured at and its gradient; for GIMSSN z = λ
    let (mut z, mut rz) = (lambda.clone(), r.clone());
    let mut pz = vec![0.0; n];
    for k in 0.. {
        drv.check(k, err, "the reduced gradient")?;
        if drv.met(err) {
            if feasible {
                // confirm with a fresh product: the CG recurrences drift
                drv.residual(&z, &mut rz);
                err = drv.err(&z, &rz, &mut rt);
            }
            if drv.met(err) {
                return Ok(drv.finish(k, z, rz, err));
            }
        }
        drv.budget(k, err)?;
        let sets = set.active_sets(&lambda, &r, rho);
        if let Some(m) = adaptive {
            tol = (m.rtol * err / err0).min(m.cfact * tol);
        }
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
        drv.residual(&x, &mut g);
        let threshold = |h0: f64| match adaptive {
            None => 1e-13 * bnorm,
            Some(m) => {
                let scale = match m.cg_stop {
                    CgStop::Rhs => bnorm,
                    CgStop::InitialGradient => h0,
                };
                // never ask CG for much more than the outer tolerance (inner_floor·ε·‖b‖)
                (tol * scale).max(m.inner_floor * c.eps * bnorm)
            }
        };
        let (inner, applications) = cg_free(&drv, &sets.free, &mut x, &mut g, threshold, c.max_inner, feasible, k)?;
        drv.info.preconditioner_applications += applications;
        std::mem::swap(&mut lambda, &mut x);
        std::mem::swap(&mut r, &mut g);
        if feasible {
            z.copy_from_slice(&lambda);
            rz.copy_from_slice(&r);
        } else {
            set.project(&lambda, &mut pz);
            std::mem::swap(&mut z, &mut pz);
            drv.residual(&z, &mut rz);
            // go on from the projected iterate (its gradient is at hand)
            lambda.copy_from_slice(&z);
            r.copy_from_slice(&rz);
        }
        err = drv.err(&z, &rz, &mut rt);
        let q = drv.q(&z, &rz);
        let step = drv.newton(StepKind::Newton, err, tol, q, &sets, inner);
        drv.record(step);
    }
    unreachable!("the outer loop returns")
}

/// CG on the components `free` from x with g = r(x), the others frozen, until the free gradient
/// is at most `threshold(‖g_free‖)`; `feasible` (CGMfeas): stop at the boundary of Λ, with the
/// step taken up to it, when a CG step would leave Λ. With the QP's preconditioner (GIMSSN
/// only: preconditioning in face) PCG with M restricted to the free components and projected
/// onto Ker G ∩ W by the QP's coarse space: each step still minimizes q along its direction,
/// so q stays monotone. x and g = r(x) (by the recurrence) are updated; returns the CG
/// iterations (one A-product each) and the preconditioner's applications.
#[allow(clippy::too_many_arguments)]
fn cg_free<A: Operator>(
    drv: &Driver<'_, '_, A>,
    free: &[bool],
    x: &mut [f64],
    g: &mut [f64],
    threshold: impl FnOnce(f64) -> f64,
    max_inner: usize,
    feasible: bool,
    outer: usize,
) -> Result<(usize, usize), QpError> {
    let qp = drv.qp;
    let m = qp.preconditioner.filter(|_| feasible);
    let coarse = match (m, qp.coarse) {
        (Some(_), Some(g)) => Some(g.restrict(free, &[]).ok_or(QpError::SingularCoarse { outer })?),
        _ => None,
    };
    let coefficients = if m.is_some() { Coefficients::Standard } else { Coefficients::Conjugated };
    let system = Masked(free);
    let opts = Pcg {
        system: &system,
        preconditioner: m.map(|m| (m, drv.st.rho)),
        coarse: coarse.as_deref(),
        coefficients,
        feasible,
        max_iter: max_inner,
        outer,
        relax: None,
        lanczos: false,
    };
    let info = pcg(qp, &opts, x, g, threshold, |_| {}, None)?;
    Ok((info.iterations, info.applications))
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
pub(crate) fn feasible_step<A: Operator>(
    drv: &Driver<'_, '_, A>,
    set: &Lambda,
    lambda: &[f64],
    r: &[f64],
    rho: f64,
    threshold: f64,
    max_inner: usize,
    outer: usize,
) -> Result<FeasibleStep, QpError> {
    let sets = set.active_sets(lambda, r, rho);
    let y: Vec<f64> = lambda.iter().zip(r).map(|(l, g)| l - rho * g).collect();
    let mut x = vec![0.0; y.len()];
    set.project(&y, &mut x);
    let mut g = vec![0.0; y.len()];
    drv.residual(&x, &mut g);
    let (inner, _) = cg_free(drv, &sets.free, &mut x, &mut g, |_| threshold, max_inner, true, outer)?;
    Ok(FeasibleStep { lambda: x, gradient: g, inner })
}
