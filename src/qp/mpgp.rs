//! MPGP — modified proportioning with gradient projections (Dostál & Kozubek, Math. Program.
//! 135 (2012); the disc step bound from Bouchala, Dostál & Vodstrčil, JOTA 157 (2013)): the
//! peer method for separable convex constraints (docs/method.md, "The solvers").
//!
//! At λ ∈ Λ a block is *active* when λ lies on its boundary (λν,ᵢ = 0; ‖λ̄τ,ᵢ‖ = gᵢ or on the
//! ellipse), *free* otherwise. The gradient g = Aλ − b splits into the free gradient φ (g on free
//! blocks, 0 on active ones) and the chopped gradient β (0 on free blocks; on an active block
//! the projected gradient `g − min(0, gᵀn) n`, n the outward normal: for a disc that is the
//! inward normal part or the tangential part of g). φ̃ = (λ − P_Λ(λ − ᾱφ))/ᾱ is the reduced free
//! gradient. Each step is one of:
//! - **CG** (λ proportional, ‖β‖² ≤ Γ² φ̃ᵀφ, and the CG step stays in Λ): a conjugate gradient
//!   step on the free blocks;
//! - **expansion** (proportional, but the CG step would leave Λ): to the boundary, then the
//!   projected step `λ ← P_Λ(λ − ᾱ φ)` with the fixed length ᾱ ∈ (0, 2/‖A‖], CG restarted;
//! - **proportioning** (not proportional): an exact line search along −β while that stays in
//!   Λ; on a curved boundary the tangential part of β admits no feasible step, so there (and
//!   where the line search would leave Λ) the step ends with the gradient projection of the
//!   active blocks `λ_A ← P_Λ(λ_A − ᾱ g_A)` (a projected gradient step of the restricted
//!   problem, monotone for ᾱ < 2/‖A‖; the same step along β is not).
//!
//! With the QP's preconditioner M (preconditioning in face, Dostál's MPRGP variant; Kružík &
//! Horák 2025) the CG directions start from z = P_W Π M Π P_W φ, Π the mask of the free blocks
//! and P_W the orthogonal projection onto Ker G ∩ W of the QP's coarse space (restricted anew
//! whenever the face changes), with conjugacy enforced against the last direction; φᵀz ≥ 0, so
//! the CG step still descends and q still decreases in every step. Expansion and proportioning
//! steps are unchanged.
//!
//! ᾱ = ρ = rho_factor/(1.1 σ_est); the stop is the same as the Newton methods'
//! (`‖r̃_ρ(λ)‖ ≤ ε‖b‖`, confirmed with a fresh product). q decreases in every step. One
//! outer iteration is one step; `inner_iterations` counts the CG steps.

use super::driver::{curvature, Driver, Monitor, Setup};
use super::krylov::{precondition, InnerSystem, Masked};
use super::lambda::Lambda;
use super::operator::CoarseProjector;
use super::operator::{Operator, Space};
use super::params::{Common, Mpgp};
use super::sets::ConvexSet;
use super::{Qp, QpError, QpSolution, Step, StepKind};

/// Relative distance to the boundary under which a block counts as active.
const ON_BOUNDARY: f64 = 1e-10;

/// The gradient split at λ.
struct Split {
    phi: Vec<f64>,
    beta: Vec<f64>,
    /// φ̃, the reduced free gradient.
    phit: Vec<f64>,
    /// The free blocks' components (the face).
    free: Vec<bool>,
    /// Free normals, free (interior) tangential pairs, active tangential pairs.
    free_normal: usize,
    free_tangent: usize,
    active_tangent: usize,
}

fn split<S: Space>(sp: &S, set: &Lambda, lambda: &[f64], g: &[f64], alpha: f64, out: &mut Split) {
    let m = set.layout.m;
    let lmax = sp.max(lambda[..m].iter().fold(0.0f64, |s, v| s.max(v.abs())));
    let (phi, beta, phit) = (&mut out.phi, &mut out.beta, &mut out.phit);
    out.free_normal = 0;
    out.free_tangent = 0;
    out.active_tangent = 0;
    let free = &mut out.free;
    for i in 0..m {
        free[i] = lambda[i] > ON_BOUNDARY * lmax;
        if free[i] {
            phi[i] = g[i];
            beta[i] = 0.0;
            out.free_normal += 1;
            // φ̃ᵢ = (λᵢ − max(0, λᵢ − ᾱgᵢ))/ᾱ
            phit[i] = if g[i] > 0.0 { g[i].min(lambda[i] / alpha) } else { g[i] };
        } else {
            phi[i] = 0.0;
            phit[i] = 0.0;
            beta[i] = g[i].min(0.0);
        }
    }
    for (i, s) in set.tangent.iter().enumerate() {
        let k = set.layout.tangent(i, 0);
        let x = [lambda[k], lambda[k + 1]];
        let gi = [g[k], g[k + 1]];
        let degenerate = s.is_outside(&[f64::MIN_POSITIVE, f64::MIN_POSITIVE]);
        let scaled = [x[0] * (1.0 + ON_BOUNDARY), x[1] * (1.0 + ON_BOUNDARY)];
        let interior = !degenerate && !s.is_outside(&scaled);
        free[k] = interior;
        free[k + 1] = interior;
        if degenerate {
            // the point set {0}: nothing can move
            phi[k..k + 2].fill(0.0);
            phit[k..k + 2].fill(0.0);
            beta[k..k + 2].fill(0.0);
            out.active_tangent += 1;
        } else if s.is_outside(&scaled) {
            let t = s.boundary_tangent(&x);
            let nrm = [t[1], -t[0]];
            let gn = (gi[0] * nrm[0] + gi[1] * nrm[1]).min(0.0);
            phi[k..k + 2].fill(0.0);
            phit[k..k + 2].fill(0.0);
            beta[k] = gi[0] - gn * nrm[0];
            beta[k + 1] = gi[1] - gn * nrm[1];
            out.active_tangent += 1;
        } else {
            phi[k] = gi[0];
            phi[k + 1] = gi[1];
            beta[k..k + 2].fill(0.0);
            let mut px = [0.0; 2];
            s.project(&[x[0] - alpha * gi[0], x[1] - alpha * gi[1]], &mut px);
            phit[k] = (x[0] - px[0]) / alpha;
            phit[k + 1] = (x[1] - px[1]) / alpha;
            out.free_tangent += 1;
        }
    }
    // the unconstrained components (TFETI's λ_E) are always free
    let e = set.free_range();
    free[e.clone()].fill(true);
    phi[e.clone()].copy_from_slice(&g[e.clone()]);
    phit[e.clone()].copy_from_slice(&g[e.clone()]);
    beta[e].fill(0.0);
}

/// Solves min ½λᵀAλ − λᵀb over Λ from λ0 by MPGP.
pub fn solve<A: Operator>(qp: &Qp<'_, A>, lambda0: &[f64], c: &Common, p: &Mpgp, monitor: &mut dyn Monitor) -> Result<QpSolution, QpError> {
    let (a, set) = (qp.a, qp.set);
    let sp = a.space();
    let n = a.dim();
    let mut drv = Driver::new(qp, Setup::new(a, qp.b, c)?, c, monitor);
    let alpha_bar = drv.st.rho;
    let mut lambda = vec![0.0; n];
    set.project(lambda0, &mut lambda);
    let mut g = vec![0.0; n];
    drv.residual(&lambda, &mut g);
    let mut spl = Split { phi: vec![0.0; n], beta: vec![0.0; n], phit: vec![0.0; n], free: vec![false; n], free_normal: 0, free_tangent: 0, active_tangent: 0 };
    split(sp, set, &lambda, &g, alpha_bar, &mut spl);
    // preconditioning in face: z = P_W Π M Π P_W φ, the face's coarse projection kept until the
    // face changes
    let mut face: Option<(Vec<bool>, Option<Box<dyn CoarseProjector + '_>>)> = None;
    let (mut h, mut work) = (vec![0.0; n], vec![0.0; n]);
    let applications = std::cell::Cell::new(0);
    let mut start = |spl: &Split, z: &mut [f64], outer: usize| -> Result<(), QpError> {
        let Some(m) = qp.preconditioner else {
            z.copy_from_slice(&spl.phi);
            return Ok(());
        };
        // the face changed on some rank: every rank restricts anew (a collective decision)
        let changed = face.as_ref().is_none_or(|(f, _)| *f != spl.free);
        if sp.max(f64::from(u8::from(changed))) > 0.0 {
            let restricted = match qp.coarse {
                Some(g) => Some(g.restrict(&spl.free, &[]).ok_or(QpError::SingularCoarse { outer })?),
                None => None,
            };
            face = Some((spl.free.clone(), restricted));
        }
        let (free, coarse) = face.as_ref().expect("set above");
        let system = Masked(free);
        h.copy_from_slice(&spl.phi);
        if let Some(c) = coarse {
            c.apply(&mut h);
            system.apply(&h, None, &mut work);
            h.copy_from_slice(&work);
        }
        precondition(m, alpha_bar, &system, coarse.as_deref(), &h, z, &mut work);
        applications.set(applications.get() + 1);
        Ok(())
    };
    let mut dir = vec![0.0; n];
    start(&spl, &mut dir, 0)?;
    let mut z = vec![0.0; n];
    let (mut ad, mut y, mut rt) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut err = drv.err(&lambda, &g, &mut rt);
    // λ ← P_Λ(λ − ᾱ v), g fresh, split, CG restarted
    let projected_step = |lambda: &mut Vec<f64>, v: &[f64], g: &mut Vec<f64>, y: &mut Vec<f64>| {
        for i in 0..n {
            y[i] = lambda[i] - alpha_bar * v[i];
        }
        set.project(y, lambda);
        super::driver::residual(qp, lambda, g);
    };
    for k in 0.. {
        drv.check(k, err, "the reduced gradient")?;
        if drv.met(err) {
            // confirm with a fresh product: the recurrences drift
            drv.residual(&lambda, &mut g);
            err = drv.err(&lambda, &g, &mut rt);
            if drv.met(err) {
                drv.info.preconditioner_applications = applications.get();
                return Ok(drv.finish(k, lambda, g, err));
            }
            split(sp, set, &lambda, &g, alpha_bar, &mut spl);
            start(&spl, &mut dir, k)?;
        }
        drv.budget(k, err)?;
        let (free_normal, stick, slip) = (sp.count(spl.free_normal), sp.count(spl.free_tangent), sp.count(spl.active_tangent));
        let bb = sp.dot(&spl.beta, &spl.beta);
        let kind;
        if bb <= p.gamma * p.gamma * sp.dot(&spl.phit, &spl.phi) {
            let pap = curvature(a, &dir, &mut ad, k)?;
            let acg = sp.dot(&g, &dir) / pap;
            let af = sp.min(set.max_step(&lambda, &dir));
            if acg <= af {
                kind = StepKind::Cg;
                for i in 0..n {
                    lambda[i] -= acg * dir[i];
                    g[i] -= acg * ad[i];
                }
                split(sp, set, &lambda, &g, alpha_bar, &mut spl);
                start(&spl, &mut z, k)?;
                let gamma = sp.dot(&z, &ad) / pap;
                for i in 0..n {
                    dir[i] = z[i] - gamma * dir[i];
                }
            } else {
                kind = StepKind::Expansion;
                for i in 0..n {
                    lambda[i] -= af * dir[i];
                    g[i] -= af * ad[i];
                }
                split(sp, set, &lambda, &g, alpha_bar, &mut spl);
                let phi = std::mem::take(&mut spl.phi);
                projected_step(&mut lambda, &phi, &mut g, &mut y);
                spl.phi = phi; // split overwrites every entry
                split(sp, set, &lambda, &g, alpha_bar, &mut spl);
                start(&spl, &mut dir, k)?;
            }
        } else {
            kind = StepKind::Proportioning;
            // the search direction d = β lives in `dir` (reset to φ below)
            dir.copy_from_slice(&spl.beta);
            let d: &[f64] = &dir;
            let af = sp.min(set.max_step(&lambda, d));
            let mut done = false;
            if af > 0.0 {
                let dad = curvature(a, d, &mut ad, k)?;
                let acg = sp.dot(&g, d) / dad;
                let step = acg.min(af);
                for i in 0..n {
                    lambda[i] -= step * d[i];
                    g[i] -= step * ad[i];
                }
                split(sp, set, &lambda, &g, alpha_bar, &mut spl);
                done = acg <= af;
            }
            if !done {
                // the gradient-projection step on the active blocks (monotone for ᾱ < 2/‖A‖)
                for i in 0..n {
                    ad[i] = g[i] - spl.phi[i];
                }
                projected_step(&mut lambda, &ad, &mut g, &mut y);
                split(sp, set, &lambda, &g, alpha_bar, &mut spl);
            }
            start(&spl, &mut dir, k)?;
        }
        err = drv.err(&lambda, &g, &mut rt);
        let q = drv.q(&lambda, &g);
        drv.record(Step { err, tol: 0.0, q, normal_active: free_normal, stick, slip, inner: usize::from(kind == StepKind::Cg), n_a: 0, kind, time: 0.0 });
    }
    unreachable!("the outer loop returns")
}
