//! SSN-BiCGSTAB — the paper's baseline: the semi-smooth Newton method on the unsymmetrized
//! equation `F(λ) = λ − P_Λ(λ − ρ r(λ)) = 0`, r = Aλ − b (DESIGN §3).
//!
//! Each outer step solves the Newton system `J δ = −F(λᵏ)` with the full slant derivative
//! `J = I − D(I − ρA)`, D = ∂P_Λ(λᵏ − ρ rᵏ) block-diagonal (0/1 on the normal components; on a
//! sliding pair the ψ° of its disc or ellipse, I on a sticking one), by BiCGSTAB (two
//! A-products per iteration), and sets λ^{k+1} = λᵏ + δ. The inner solve stops at
//! `‖Jδ + F‖ ≤ tol·s` with s = ρ‖b‖ (`CgStop::Rhs`) or ‖F(λᵏ)‖ (`CgStop::InitialGradient`),
//! tol adaptive as in IMSSN (`min(rtol·err_k/err_0, cfact·tol_k)`) or fixed ([`Ssn::inner_tol`]:
//! the paper's counts need near-exact solves, about 1e-6), and never below 0.1·ε·ρ‖b‖.
//! The products A p and A s that BiCGSTAB makes anyway give Aδ, so r^{k+1} = rᵏ + Aδ costs
//! no extra product. Iterates need not lie in Λ; the stop `‖r̃_ρ‖ ≤ ε‖b‖` is confirmed at
//! P_Λ(λ) with a fresh product, and P_Λ(λ) is the result. No globalization: the method is
//! locally superlinear, and a run that does not converge ends in `QpError::NoConvergence`.

use super::driver::{Driver, Monitor, Setup};
use super::krylov::Bicgstab;
use super::operator::{Operator, Space};
use super::params::{Common, Ssn};
use super::{CgStop, Qp, QpError, QpSolution, StepKind};

/// Solves min ½λᵀAλ − λᵀb over Λ from λ0 by SSN with BiCGSTAB inner solves.
pub fn solve<A: Operator>(qp: &Qp<'_, A>, lambda0: &[f64], c: &Common, p: &Ssn, monitor: &mut dyn Monitor) -> Result<QpSolution, QpError> {
    let (a, set) = (qp.a, qp.set);
    let sp = a.space();
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
    let mut tol = p.rtol / p.cfact;
    let (mut y, mut z, mut rz) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut work = Bicgstab::new(n);
    for k in 0.. {
        drv.check(k, err, "the reduced gradient")?;
        if drv.met(err) {
            match drv.confirm_projected(k, &mut lambda, &mut r, &mut z, &mut rz, &mut rt) {
                Ok(sol) => return Ok(sol),
                Err(e) => err = e,
            }
        }
        drv.budget(k, err)?;
        let sets = set.active_sets(&lambda, &r, rho);
        for i in 0..n {
            y[i] = lambda[i] - rho * r[i];
        }
        let d = set.slant(&y);
        // −F(λ) = −ρ r̃_ρ(λ); rt holds r̃ at the current λ (from the last err)
        let rhs: Vec<f64> = rt.iter().map(|v| -rho * v).collect();
        tol = match p.inner_tol {
            Some(t) => t,
            None => (p.rtol * err / err0).min(p.cfact * tol),
        };
        let scale = match p.cg_stop {
            CgStop::Rhs => rho * bnorm,
            CgStop::InitialGradient => sp.norm(&rhs),
        };
        // never ask less than a reduction by rtol of the current residual: from a warm start
        // (err_0 small) tol·scale could exceed ‖rhs‖ and the step would be zero
        let threshold = (tol * scale).min(p.rtol * sp.norm(&rhs)).max(p.inner_floor * c.eps * rho * bnorm);
        // J v = v − D(v − ρ A v), also returning A v
        let jacobian = |v: &[f64], jv: &mut [f64], av: &mut [f64]| {
            a.apply(v, av);
            for i in 0..n {
                jv[i] = v[i] - rho * av[i];
            }
            d.apply_in_place(jv);
            for i in 0..n {
                jv[i] = v[i] - jv[i];
            }
        };
        let inner = work.solve(sp, &rhs, threshold, c.max_inner, jacobian, k)?;
        for i in 0..n {
            lambda[i] += work.x[i];
            r[i] += work.ax[i];
        }
        err = drv.err(&lambda, &r, &mut rt);
        let q = drv.q(&lambda, &r);
        let step = drv.newton(StepKind::Newton, err, tol, q, &sets, inner);
        drv.record(step);
    }
    unreachable!("the outer loop returns")
}
