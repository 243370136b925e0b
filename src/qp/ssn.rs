//! SSN-BiCGSTAB — the paper's baseline: the semi-smooth Newton method on the unsymmetrized
//! equation `F(λ) = λ − P_Λ(λ − ρ r(λ)) = 0`, r = Aλ − b (docs/method.md, "The solvers").
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
//! With the QP's preconditioner M the Newton system is right-preconditioned (J M_J y = −F,
//! δ = M_J y, so the inner stop still tests ‖Jδ + F‖): J = [ρA_WW, ·; 0, I] up to the sliding
//! pairs' μρ on their tangents, so `M_J = (I − Π) + P_W Π M Π S`, Π the step's subspace W (D = I
//! components; t tᵀ on sliding pairs whose cᵢ ≤ [`SLIDE_CAP`]·σ, as TSSN's), S = 1/ρ there and
//! 1/(μρ) on a slide, P_W the orthogonal projection onto Ker G ∩ W when the QP has a coarse
//! space: the FETI preconditioner in its projected form (docs/method.md, "TFETI and H-TFETI": the FETI preconditioner).
//! The same iteration solves the Coulomb law directly ([`run`] with coefficients: Λ(λ) cut at
//! the iterate's normals, the bound's dependence on λν in J; `qp::coulomb::newton`).

use super::cone::{cut, Coefficient};
use super::driver::{err_of, Driver, Monitor, Setup};
use super::krylov::{precondition, Bicgstab, InnerSystem, Subspace};
use super::operator::{Operator, Space};
use super::params::{Common, Ssn};
use super::{CgStop, Qp, QpError, QpSolution, StepKind};

/// A sliding pair whose cᵢ = (1/μ − 1)/ρ exceeds this multiple of σ_max(A) is left out of
/// the preconditioned subspace (its tangent row of J is then nearly (1 − μ)·I): TSSN's default
/// `slide_cap`.
pub const SLIDE_CAP: f64 = 0.5;

/// Solves min ½λᵀAλ − λᵀb over Λ from λ0 by SSN with BiCGSTAB inner solves.
pub fn solve<A: Operator>(qp: &Qp<'_, A>, lambda0: &[f64], c: &Common, p: &Ssn, monitor: &mut dyn Monitor) -> Result<QpSolution, QpError> {
    run(qp, None, lambda0, c, p, monitor)
}

/// The Newton iteration, on Λ or — with isotropic Coulomb coefficients `mu` — on Λ(λ), the cones
/// cut at the iterate's own normals ([`super::coulomb::newton`]): then the slant derivative
/// also carries the bound's dependence on λν.
pub(crate) fn run<A: Operator>(
    qp: &Qp<'_, A>,
    mu: Option<&[Coefficient]>,
    lambda0: &[f64],
    c: &Common,
    p: &Ssn,
    monitor: &mut dyn Monitor,
) -> Result<QpSolution, QpError> {
    let (a, set) = (qp.a, qp.set);
    let sp = a.space();
    let n = a.dim();
    let at = |x: &[f64]| cut(set, mu, x);
    let mut drv = Driver::new(qp, Setup::new(a, qp.b, c)?, c, monitor);
    let (rho, bnorm) = (drv.st.rho, drv.st.bnorm);
    let mut lambda = vec![0.0; n];
    at(lambda0).project(lambda0, &mut lambda);
    let mut r = vec![0.0; n];
    match qp.start {
        // the caller's λ with its gradient: no product
        Some((l, g)) if l == lambda.as_slice() => r.copy_from_slice(g),
        _ => drv.residual(&lambda, &mut r),
    }
    let mut rt = vec![0.0; n];
    let mut err = err_of(sp, &at(&lambda), &lambda, &r, &drv.st, &mut rt);
    let err0 = err.max(f64::MIN_POSITIVE);
    let mut tol = p.rtol / p.cfact;
    let (mut y, mut z, mut rz) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut work = Bicgstab::new(n);
    for k in 0.. {
        drv.check(k, err, "the reduced gradient")?;
        if drv.met(err) {
            // confirm at the projection (onto the cones cut there, with Coulomb)
            at(&lambda).project(&lambda, &mut z);
            drv.residual(&z, &mut rz);
            let ez = err_of(sp, &at(&z), &z, &rz, &drv.st, &mut rt);
            if drv.met(ez) {
                return Ok(drv.finish(k, z, rz, ez));
            }
            std::mem::swap(&mut lambda, &mut z);
            std::mem::swap(&mut r, &mut rz);
            err = ez;
        }
        drv.budget(k, err)?;
        let set_k = at(&lambda);
        let sets = set_k.active_sets(&lambda, &r, rho);
        for i in 0..n {
            y[i] = lambda[i] - rho * r[i];
        }
        let d = set_k.slant(&y);
        let dg = mu.map(|mu| bound_slant(set.layout, mu, &lambda, &y)).unwrap_or_default();
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
        // J v = v − D(v − ρ A v) (− the bound's part), also returning A v
        let jacobian = |v: &[f64], jv: &mut [f64], av: &mut [f64]| {
            a.apply(v, av);
            for i in 0..n {
                jv[i] = v[i] - rho * av[i];
            }
            d.apply_in_place(jv);
            for i in 0..n {
                jv[i] = v[i] - jv[i];
            }
            for &(kn, kt, g) in &dg {
                jv[kt] -= g[0] * v[kn];
                jv[kt + 1] -= g[1] * v[kn];
            }
        };
        // the right preconditioner M_J on this step's subspace
        let free = &sets.free;
        let mut slides = Vec::new();
        let mut scale = vec![];
        if qp.preconditioner.is_some() {
            for (i, ts) in set_k.tangent.iter().enumerate() {
                let kt = set_k.layout.tangent(i, 0);
                if free[kt] {
                    continue;
                }
                if let Some(f) = ts.frame(&y[kt..kt + 2]) {
                    let ci = (1.0 / f.mu - 1.0) / rho;
                    if f.mu > 0.0 && ci <= SLIDE_CAP * drv.st.sigma {
                        slides.push((kt, f.tangent));
                        scale.push(1.0 / (f.mu * rho));
                    }
                }
            }
        }
        let subspace = Subspace { free, slides: &slides };
        let coarse = match (qp.preconditioner, qp.coarse) {
            (Some(_), Some(g)) => Some(g.restrict(free, &slides).ok_or(QpError::SingularCoarse { outer: k })?),
            _ => None,
        };
        let len = if qp.preconditioner.is_some() { n } else { 0 };
        let (mut sv, mut pv, mut work_m) = (vec![0.0; len], vec![0.0; len], vec![0.0; len]);
        let mut applications = 0;
        let mut m_j = |v: &[f64], out: &mut [f64]| {
            let m = qp.preconditioner.expect("a preconditioner");
            // S v on W, then P_W Π M Π; plus (I − Π) v
            subspace.apply(v, None, &mut pv);
            for i in 0..n {
                sv[i] = pv[i] / rho;
            }
            for (&(kt, _), s) in slides.iter().zip(&scale) {
                sv[kt] = pv[kt] * s;
                sv[kt + 1] = pv[kt + 1] * s;
            }
            precondition(m, rho, &subspace, coarse.as_deref(), &sv, out, &mut work_m);
            for i in 0..n {
                out[i] += v[i] - pv[i];
            }
            applications += 1;
        };
        let m_j: Option<&mut dyn FnMut(&[f64], &mut [f64])> = if qp.preconditioner.is_some() { Some(&mut m_j) } else { None };
        let inner = work.solve(sp, &rhs, threshold, c.max_inner, jacobian, m_j, k)?;
        drv.info.preconditioner_applications += applications;
        for i in 0..n {
            lambda[i] += work.x[i];
            r[i] += work.ax[i];
        }
        err = err_of(sp, &at(&lambda), &lambda, &r, &drv.st, &mut rt);
        let q = drv.q(&lambda, &r);
        let step = drv.newton(StepKind::Newton, err, tol, q, &sets, inner);
        drv.record(step);
    }
    unreachable!("the outer loop returns")
}

/// The Coulomb bound's part of the slant derivative: for each sliding pair in contact (λν > 0,
/// ‖yτ‖ > μλν) its (λν row, first λτ row, μ·yτ/‖yτ‖) — ∂P/∂g = yτ/‖yτ‖, ∂g/∂λν = μ.
fn bound_slant(l: super::Layout, mu: &[Coefficient], lambda: &[f64], y: &[f64]) -> Vec<(usize, usize, [f64; 2])> {
    let mut dg = Vec::new();
    if !l.friction {
        return dg;
    }
    for (i, cf) in mu.iter().enumerate() {
        let Coefficient::Isotropic(m) = *cf else { continue };
        let (kt, kn) = (l.tangent(i, 0), l.normal(i));
        let ny = y[kt].hypot(y[kt + 1]);
        if lambda[kn] > 0.0 && ny > m * lambda[kn] {
            dg.push((kn, kt, [m * y[kt] / ny, m * y[kt + 1] / ny]));
        }
    }
    dg
}
