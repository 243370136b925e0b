//! Plain conjugate gradients for the unconstrained dual (TFETI without contact: only the free
//! gluing and Dirichlet multipliers, so Λ = R^n and the reduced gradient is the gradient). One
//! outer iteration per CG iteration; stops on the common criterion ‖r‖ ≤ ε‖b‖, confirmed with a
//! fresh product (CG restarts from there when it does not hold). The QP's preconditioner, if
//! any, makes it PCG.

use super::driver::{Driver, Monitor, Setup};
use super::krylov::{pcg, Coefficients, Pcg, Whole};
use super::operator::{Operator, Space};
use super::params::Common;
use super::{Qp, QpError, QpSolution, Step, StepKind};

/// Solves A λ = b from λ0 by CG, at most max(max_outer, max_inner) iterations (CG steps are the
/// inner iterations of the other solvers).
pub fn solve<A: Operator>(qp: &Qp<'_, A>, lambda0: &[f64], c: &Common, monitor: &mut dyn Monitor) -> Result<QpSolution, QpError> {
    let a = qp.a;
    let n = a.dim();
    let mut drv = Driver::new(qp, Setup::unconstrained(a, qp.b), c, monitor);
    let bnorm = drv.st.bnorm;
    let limit = c.max_outer.max(c.max_inner);
    let mut x = lambda0.to_vec();
    let mut r = vec![0.0; n];
    drv.residual(&x, &mut r);
    let mut total = 0;
    let all = vec![true; n];
    let coarse = match qp.coarse {
        Some(g) => Some(g.restrict(&all, &[]).ok_or(QpError::SingularCoarse { outer: 0 })?),
        None => None,
    };
    loop {
        let opts = Pcg {
            system: &Whole,
            preconditioner: qp.preconditioner.map(|m| (m, 1.0)),
            coarse: coarse.as_deref(),
            coefficients: Coefficients::Standard,
            feasible: false,
            max_iter: limit - total,
            outer: total,
            relax: None,
            lanczos: false,
        };
        let cg = pcg(
            qp,
            &opts,
            &mut x,
            &mut r,
            |_| c.eps * bnorm,
            |h| {
                drv.record(Step { err: h / bnorm, tol: 0.0, q: 0.0, normal_active: 0, stick: 0, slip: 0, inner: 1, n_a: 0, kind: StepKind::Cg, time: 0.0 });
            },
            None,
        )?;
        total += cg.iterations;
        drv.info.preconditioner_applications += cg.applications;
        // confirm with a fresh product: the recurrences drift
        drv.residual(&x, &mut r);
        let err = a.space().norm(&r) / bnorm;
        drv.check(total, err, "the CG residual")?;
        if drv.met(err) {
            return Ok(drv.finish(total, x, r, err));
        }
        if total >= limit || cg.iterations == 0 {
            return Err(drv.no_convergence(total, err));
        }
    }
}
