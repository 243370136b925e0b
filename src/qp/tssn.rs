//! TSSN — the tangent-symmetric semi-smooth Newton method (docs/method.md, "The solvers"): the exact Newton step of
//! SSN-BiCGSTAB written as a symmetric positive definite system, so that CG (and a symmetric
//! preconditioner) solve it.
//!
//! **Derivation.** SSN solves `F(λ) = λ − P_Λ(y) = 0`, `y = λ − ρ r(λ)`, `r = Aλ − b`, by
//! `J δ = −F` with `J = I − D(I − ρA)`, D = ∂P_Λ(y). With `λ⁺ = λ + δ`, `y⁺ = λ⁺ − ρ r(λ⁺)` this
//! is, block by block, `λ⁺ − D y⁺ = P_Λ(y) − D y`:
//! * normal with `yᵢ < 0` (D = 0): `λ⁺ᵢ = 0` — fixed;
//! * normal with `yᵢ ≥ 0`, a sticking pair, an E component (D = I): `r(λ⁺)ᵢ = 0` — free;
//! * a sliding pair (y outside its disc or ellipse): D = μ t tᵀ with x = P(y) on the boundary,
//!   n the outward normal, t the tangent there, μ = 1/(1 + κ·dist) (κ the curvature, dist =
//!   ‖y − x‖; μ = g/‖y‖ on a disc). Since `tᵀ(y − x) = 0`, the n-row says `nᵀλ⁺ = nᵀx` — the
//!   radial part stays on the tangent line at x — and the t-row, divided by μρ, says
//!   `tᵀ r(λ⁺) + cᵢ σᵢ = 0` with `λ̄⁺τ,ᵢ = x + σᵢ t` and `cᵢ = (1/μ − 1)/ρ = κ·dist/ρ ≥ 0`
//!   (on a disc `(‖y‖ − gᵢ)/(ρgᵢ)`, the slip rate at the solution). One scalar unknown σᵢ.
//!
//! Let W map the free unknowns (free components, one σ per sliding pair) into λ (identity on the
//! free components, t on a sliding pair) and λ_fix hold the fixed values (0, x). The step is
//! `λ⁺ = λ_fix + W z` with `(WᵀAW + C) z = −Wᵀ r(λ_fix)`, `C = diag(0, cᵢ)`: symmetric positive
//! definite — CG. It is the exact SSN step (the SSN-BiCGSTAB iterate with exact inner solves)
//! and the paper's symmetrized MSSN is its limit `cᵢ → ∞` (σ frozen at 0). A pair whose cᵢ is
//! infinite (a segment's end, the point set) is fixed at x; one with `cᵢ = 0` (a segment's flat
//! side) moves freely along it.
//!
//! **One outer step** from xᵏ with r(xᵏ): the sets and frames at yᵏ; the start
//! `x⁰ = λ_fix` on the fixed components and `P_Λ(xᵏ)` on the free ones (the retraction onto Λ,
//! folded into the start so it costs no product; x⁰ ∈ Λ up to the σ's); `r(x⁰)` by one fresh
//! product (the only fixed overhead per step: it also resets the recurrences' drift); CG on the
//! subspace (vectors v with v = Πv, Π the mask and t tᵀ on sliding pairs; operator
//! `Π A v + C v`), each iteration one A-product, r(x) updated by the recurrence, stopped at
//! `‖Π r + Cσ‖ ≤ max(min(rtol·(err_k/err_0)^θ·‖b‖, rtol·‖start‖), floor·ε·‖b‖)` (forcing
//! exponent θ = [`Tssn::forcing`]: superlinear for θ > 1). The result x^{k+1} (its gradient from
//! the recurrence) need not lie in Λ; the test `‖r̃_ρ‖ ≤ ε‖b‖` is made there and confirmed at
//! P_Λ(x) with a fresh product, which is the result.
//!
//! **Safeguard** (non-monotone). q at the starts x⁰ (in Λ, exact gradient) should decrease,
//! not necessarily at every step: a semi-smooth Newton step that changes the sets may raise q
//! once and recover. When q(x⁰) exceeds the last accepted value at [`Tssn::patience`] starts in
//! a row (1: at once; 0, the default: never), the step is undone and a GIMSSN step (projected gradient, then CGMfeas;
//! monotone for ρ < 2/σ_max) is taken from the last accepted start instead
//! ([`StepKind::Safeguard`]); a start that rose and was let through is not accepted as the
//! reference. Newton steps are [`StepKind::Tangent`].

use std::borrow::Cow;

use super::cone::{cut, Coefficient};
use super::driver::{err_of, Driver, Monitor, Setup, SIGMA_SAFETY};
use super::gimssn;
use super::krylov::{pcg, Coefficients, InnerSystem, Pcg, Recycle};
use super::lambda::Lambda;
use super::operator::{Operator, Space};
use super::params::{Common, RhoRule, Tssn};
use super::sets::ConvexSet;
use super::{Qp, QpError, QpSolution, StepKind};

/// A sliding pair's part of the Newton system: its first component, the unit tangent t at
/// x = P(y) and cᵢ.
#[derive(Clone, Copy, Debug)]
struct Slide {
    k: usize,
    t: [f64; 2],
    c: f64,
}

/// The structure of one Newton system: which components move, and the sliding pairs.
struct System {
    sets: super::lambda::ActiveSets,
    slides: Vec<Slide>,
}

impl System {
    /// Sets and frames at y = x − ρ r; writes the start x⁰ (fixed values, P_Λ(x) elsewhere);
    /// sliding pairs with cᵢ > `cap` stay at x (no σᵢ). `damp` = (the last step's free
    /// components, t): a normal row keeps its last state where |yᵢ| < t ([`Tssn::damping`]).
    /// `rho_n`: ρᵢ of the normal rows' decision yᵢ = xᵢ − ρᵢrᵢ ([`Tssn::rho`]; ρ when None).
    fn new(set: &Lambda, x: &[f64], r: &[f64], (rho, rho_n): (f64, Option<&[f64]>), cap: f64, damp: Option<(&[bool], f64)>, x0: &mut [f64]) -> System {
        let n = x.len();
        let m = set.layout.m;
        let y: Vec<f64> = (0..n).map(|i| x[i] - rho_n.filter(|_| i < m).map_or(rho, |v| v[i]) * r[i]).collect();
        let mut sets = set.active_sets_with(x, r, rho, rho_n);
        if let Some((last, t)) = damp.filter(|d| d.0.len() == n) {
            for i in 0..set.layout.m {
                if sets.free[i] != last[i] && y[i].abs() < t {
                    sets.free[i] = last[i];
                    if last[i] {
                        sets.normal_active += 1;
                    } else {
                        sets.normal_active -= 1;
                    }
                }
            }
        }
        set.project(x, x0);
        for i in 0..set.layout.m {
            if !sets.free[i] {
                x0[i] = 0.0;
            }
        }
        let mut slides = Vec::new();
        for (i, ts) in set.tangent.iter().enumerate() {
            let k = set.layout.tangent(i, 0);
            if sets.free[k] {
                continue;
            }
            match ts.frame(&y[k..k + 2]) {
                Some(f) => {
                    x0[k] = f.point[0];
                    x0[k + 1] = f.point[1];
                    let c = f.curvature * f.distance / rho;
                    if c.is_finite() && c <= cap {
                        slides.push(Slide { k, t: f.tangent, c });
                    }
                }
                // on the boundary to rounding: P(y) is y
                None => ts.project(&y[k..k + 2], &mut x0[k..k + 2]),
            }
        }
        System { sets, slides }
    }
}

impl InnerSystem for System {
    /// out = Π g + C v (v in the subspace): the operator on v when g = A v; the residual of the
    /// Newton system at x⁰ (σ = 0) when g = r(x⁰) and v is None.
    fn apply(&self, g: &[f64], v: Option<&[f64]>, out: &mut [f64]) {
        for (o, (gi, f)) in out.iter_mut().zip(g.iter().zip(&self.sets.free)) {
            *o = if *f { *gi } else { 0.0 };
        }
        for s in &self.slides {
            let (k, t) = (s.k, s.t);
            let mut a = t[0] * g[k] + t[1] * g[k + 1];
            if let Some(v) = v {
                a += s.c * (t[0] * v[k] + t[1] * v[k + 1]);
            }
            out[k] = a * t[0];
            out[k + 1] = a * t[1];
        }
    }
}

/// Solves min ½λᵀAλ − λᵀb over Λ from λ0 (projected onto Λ first) by TSSN; the QP's
/// preconditioner, if any, acts in the inner CG.
pub fn solve<A: Operator>(qp: &Qp<'_, A>, lambda0: &[f64], c: &Common, p: &Tssn, monitor: &mut dyn Monitor) -> Result<QpSolution, QpError> {
    run(qp, None, lambda0, c, p, monitor)
}

/// The TSSN iteration on Λ, or — with Coulomb coefficients `mu` — with lagged bounds: each
/// outer step takes Λ(λᵏ), the cones cut at the iterate's normals, as fixed for its Newton
/// system (symmetric: the bound's dependence on λν is left out of the derivative), and the stop
/// test is made on Λ(λ) at the result ([`super::coulomb::lagged`]).
pub(crate) fn run<'q, A: Operator>(
    qp: &Qp<'q, A>,
    mu: Option<&[Coefficient]>,
    lambda0: &[f64],
    c: &Common,
    p: &Tssn,
    monitor: &mut dyn Monitor,
) -> Result<QpSolution, QpError> {
    let (a, set) = (qp.a, qp.set);
    let at = |x: &[f64]| cut(set, mu, x);
    let sp = a.space();
    let n = a.dim();
    let mut drv = Driver::new(qp, Setup::new(a, qp.b, c)?, c, monitor);
    let (rho, bnorm) = (drv.st.rho, drv.st.bnorm);
    let rho_n = normal_rho(a, set.layout.m, rho, p.rho);
    let mut x = vec![0.0; n];
    at(lambda0).project(lambda0, &mut x);
    let mut r = vec![0.0; n];
    if sp.max(x.iter().fold(0.0f64, |m, v| m.max(v.abs()))) == 0.0 {
        // r(0) = −b: no product
        r.iter_mut().zip(qp.b).for_each(|(ri, bi)| *ri = -bi);
    } else {
        drv.residual(&x, &mut r);
    }
    let mut rt = vec![0.0; n];
    let mut err = err_of(sp, &at(&x), &x, &r, &drv.st, &mut rt);
    let err0 = err.max(f64::MIN_POSITIVE);
    let (mut x0, mut g0) = (vec![0.0; n], vec![0.0; n]);
    // the last accepted start (in Λ, exact gradient) and its q
    let (mut base, mut base_r, mut base_q) = (x.clone(), r.clone(), f64::INFINITY);
    // Newton starts in a row whose q exceeded the last accepted one
    let mut strikes = 0;
    let (mut z, mut rz) = (vec![0.0; n], vec![0.0; n]);
    // Coulomb: the best error so far, and — once a step has raised it LAG_JUMP-fold — the frozen
    // Λ(λ) with the normals it was cut at
    let mut best = err;
    let mut frozen: Option<(Lambda, Vec<f64>)> = None;
    // Krylov recycling: the kept directions, valid for the structure `moving` (free components
    // and sliding pairs' first components) of the system they came from
    let mut bank = (p.recycle > 0).then(|| Recycle::new(p.recycle));
    // the largest estimate of the Newton systems' condition number so far (Lanczos, from the
    // inner CGs)
    let mut kappa: Option<f64> = None;
    // whether the operator has inexact products at all (else no κ is estimated)
    let inexact_possible = a.allow_error(f64::INFINITY);
    a.allow_error(0.0);
    let mut moving: Vec<bool> = vec![];
    // the last Newton step's free components (the damped active set's reference)
    let mut held: Vec<bool> = vec![];
    for k in 0.. {
        drv.check(k, err, "the reduced gradient")?;
        if drv.met(err) {
            match drv.confirm_projected(k, mu, &mut x, &mut r, &mut z, &mut rz, &mut rt) {
                Ok(sol) => return Ok(sol),
                Err(e) => err = e,
            }
        }
        drv.budget(k, err)?;
        let set_k = match &frozen {
            Some((f, _)) => Cow::Borrowed(f),
            None => at(&x),
        };
        let damp = (p.damping > 0.0 && held.len() == n).then(|| (held.as_slice(), damping_threshold(sp, &set_k, &x, &r, rho, &held, p.damping)));
        let sys = System::new(&set_k, &x, &r, (rho, rho_n.as_deref()), p.slide_cap * drv.st.sigma, damp, &mut x0);
        if p.damping > 0.0 {
            held.clone_from(&sys.sets.free);
        }
        let restrict = |g: &'q dyn super::Coarse| {
            let slides: Vec<(usize, [f64; 2])> = sys.slides.iter().map(|s| (s.k, s.t)).collect();
            g.restrict(&sys.sets.free, &slides).ok_or(QpError::SingularCoarse { outer: k })
        };
        // a QP that keeps Gλ = e itself: restricted first (its gradient is the Lagrangian's on
        // this W), the start closed onto Gλ = e by W's least-norm correction
        let mut coarse = match qp.coarse.filter(|g| g.keeps_equality()) {
            Some(g) => Some(restrict(g)?),
            None => None,
        };
        if let Some(corr) = coarse.as_deref().and_then(|p| p.close(&x0)) {
            sys.apply(&corr, None, &mut g0);
            x0.iter_mut().zip(&g0).for_each(|(a, b)| *a += b);
        }
        drv.residual(&x0, &mut g0);
        let q0 = drv.q(&x0, &g0);
        if !q0.is_finite() {
            return Err(QpError::NotFinite { what: "q at the Newton start", outer: k });
        }
        let tol = p.rtol * (err / err0).powf(p.forcing);
        let rises = q0 > base_q + 1e-12 * base_q.abs();
        strikes = if rises { strikes + 1 } else { 0 };
        if rises && p.patience > 0 && strikes >= p.patience {
            // the safeguard: a GIMSSN step from the last accepted start
            // GIMSSN's descent needs ρ < 2/σ_max
            let rho_g = rho.min(1.9 / (SIGMA_SAFETY * drv.st.sigma));
            let g = gimssn::feasible_step(&drv, &set_k, &base, &base_r, rho_g, (tol * bnorm).max(p.inner_floor * c.eps * bnorm), c.max_inner, k)?;
            x.copy_from_slice(&g.lambda);
            r.copy_from_slice(&g.gradient);
            base.copy_from_slice(&x);
            base_r.copy_from_slice(&r);
            base_q = drv.q(&x, &r);
            strikes = 0;
            err = err_of(sp, &at(&x), &x, &r, &drv.st, &mut rt);
            let step = drv.newton(StepKind::Safeguard, err, tol, base_q, &sys.sets, g.inner);
            drv.record(step);
            continue;
        }
        if !rises {
            base.copy_from_slice(&x0);
            base_r.copy_from_slice(&g0);
            base_q = q0;
        }
        // CG on the subspace from x⁰ (σ = 0 there)
        x.copy_from_slice(&x0);
        r.copy_from_slice(&g0);
        if coarse.is_none() {
            coarse = match qp.coarse {
                Some(g) => Some(restrict(g)?),
                None => None,
            };
        }
        let opts = Pcg {
            system: &sys,
            preconditioner: qp.preconditioner.map(|m| (m, rho)),
            coarse: coarse.as_deref(),
            coefficients: Coefficients::Standard,
            feasible: false,
            max_iter: c.max_inner,
            outer: k,
            relax: kappa,
            lanczos: inexact_possible,
        };
        let threshold = |h0: f64| (tol * bnorm).min(p.rtol * h0).max(p.inner_floor * c.eps * bnorm);
        if let Some(b) = bank.as_mut() {
            let mut now = sys.sets.free.clone();
            for s in &sys.slides {
                now[s.k] = true;
            }
            let changed = if moving.len() == now.len() { now.iter().zip(&moving).filter(|(a, b)| a != b).count() } else { now.len() };
            if sp.count(changed) > 0 {
                b.clear();
            }
            moving = now;
        }
        let cg = pcg(qp, &opts, &mut x, &mut r, threshold, |_| {}, bank.as_mut())?;
        drv.info.preconditioner_applications += cg.applications;
        drv.info.inexact_products += cg.inexact;
        err = err_of(sp, &at(&x), &x, &r, &drv.st, &mut rt);
        if mu.is_some() {
            settle_bounds(sp, &mut frozen, &at, set.layout.m, &x, &r, (err, best, c.eps), &drv.st, &mut z);
            best = best.min(err);
        }
        // the largest estimate so far: a short solve sees little of the spectrum
        kappa = match (kappa, cg.kappa) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
        let step = drv.newton(StepKind::Tangent, err, tol, q0, &sys.sets, cg.iterations);
        drv.record(step);
    }
    unreachable!("the outer loop returns")
}

/// ρᵢ of the normal rows for [`RhoRule::Diagonal`]: ρ · max_j dⱼ / dᵢ over the m normal rows of all
/// ranks, d the operator's estimate of diag(A) (no product); None for the scalar rule or without an estimate.
fn normal_rho<A: Operator>(a: &A, m: usize, rho: f64, rule: RhoRule) -> Option<Vec<f64>> {
    if rule == RhoRule::Scalar {
        return None;
    }
    let d = a.diagonal_estimate()?;
    let dmax = a.space().max(d[..m].iter().fold(0.0f64, |s, &v| s.max(v)));
    (dmax > 0.0).then(|| d[..m].iter().map(|&di| if di > 0.0 { rho * dmax / di } else { rho }).collect())
}

/// The damped active set's threshold ([`Tssn::damping`]): θ times the largest |yᵢ| = |λᵢ − ρrᵢ|
/// over the normal rows whose state at y differs from `held`, the last step's free components.
fn damping_threshold<S: Space>(sp: &S, set: &Lambda, x: &[f64], r: &[f64], rho: f64, held: &[bool], theta: f64) -> f64 {
    let want = set.active_sets(x, r, rho);
    let largest = (0..set.layout.m).filter(|&i| want.free[i] != held[i]).map(|i| (x[i] - rho * r[i]).abs()).fold(0.0, f64::max);
    theta * sp.max(largest)
}

/// An error rise of this factor over the best so far ends the lagged bounds: they are frozen
/// and re-cut only as the fixed point would ([`settle_bounds`]). With [`RECUT`], what won on the
/// Coulomb scenes (docs/performance.md, "Coulomb friction: lagged bounds").
const LAG_JUMP: f64 = 10.0;
/// Frozen bounds are re-cut once the error over them is at most this fraction of the relative
/// change of λν since their cut.
const RECUT: f64 = 0.01;

/// The lagged bounds' safeguard after a Coulomb step to x (error `err` over Λ(x), `best` the
/// lowest before): near the solution a few pairs at the stick/slip border can flip back and
/// forth under lagged bounds (the error then cycles); a rise by [`LAG_JUMP`] over the best
/// freezes Λ(x), and frozen bounds are re-cut at x once the error over them is at most
/// [`RECUT`] times the relative change of λν since their cut, or at most ε — the fixed point's
/// rule, without its restarts. `m`: the pairs (normal components first); `work` is workspace.
#[allow(clippy::too_many_arguments)]
fn settle_bounds<'s, S: Space>(
    sp: &S,
    frozen: &mut Option<(Lambda, Vec<f64>)>,
    at: &impl Fn(&[f64]) -> Cow<'s, Lambda>,
    m: usize,
    x: &[f64],
    r: &[f64],
    (err, best, eps): (f64, f64, f64),
    st: &Setup,
    work: &mut [f64],
) {
    // the normal part of a vector, as a whole vector of the space (the fixed point's measure)
    let normals = |v: &[f64]| -> Vec<f64> { v.iter().enumerate().map(|(i, a)| if i < m { *a } else { 0.0 }).collect() };
    match frozen {
        None if err > LAG_JUMP * best => *frozen = Some((at(x).into_owned(), normals(x))),
        None => {}
        Some((f, cut_at)) => {
            let now = normals(x);
            let diff: Vec<f64> = now.iter().zip(cut_at.iter()).map(|(a, b)| a - b).collect();
            let change = sp.norm(&diff) / sp.norm(&now).max(f64::MIN_POSITIVE);
            let ef = err_of(sp, f, x, r, st, work);
            if ef <= RECUT * change || ef <= eps {
                *f = at(x).into_owned();
                *cut_at = now;
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::qp::sets::{Disc, Ellipse, TangentSet};
    use crate::qp::{kkt, solve, Method, Params, ProductCounter, Replicated, Silent};

    /// A dense SPD A = QᵀQ + shift·I (Q random), counting its products.
    pub(crate) struct Dense {
        n: usize,
        a: Vec<f64>,
        counter: ProductCounter,
    }

    impl Dense {
        pub(crate) fn random(n: usize, shift: f64, seed: &mut u64) -> Dense {
            let q: Vec<f64> = (0..n * n).map(|_| lcg(seed)).collect();
            let mut a = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    a[i * n + j] = (0..n).map(|k| q[k * n + i] * q[k * n + j]).sum::<f64>() + if i == j { shift } else { 0.0 };
                }
            }
            Dense { n, a, counter: ProductCounter::default() }
        }

        /// diag(d).
        pub(crate) fn diagonal(d: &[f64]) -> Dense {
            let n = d.len();
            let mut a = vec![0.0; n * n];
            d.iter().enumerate().for_each(|(i, v)| a[i * n + i] = *v);
            Dense { n, a, counter: ProductCounter::default() }
        }
    }

    impl Operator for Dense {
        type Space = Replicated;
        fn space(&self) -> &Replicated {
            &Replicated
        }
        fn dim(&self) -> usize {
            self.n
        }
        fn apply(&self, x: &[f64], y: &mut [f64]) {
            self.counter.tick();
            for (i, yi) in y.iter_mut().enumerate() {
                *yi = self.a[i * self.n..(i + 1) * self.n].iter().zip(x).map(|(a, b)| a * b).sum();
            }
        }
        fn products(&self) -> usize {
            self.counter.get()
        }
        fn diagonal_estimate(&self) -> Option<Vec<f64>> {
            Some((0..self.n).map(|i| self.a[i * self.n + i]).collect())
        }
    }

    pub(crate) fn lcg(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// m pairs with friction, discs and ellipses alternating, b pushing into contact and sliding.
    fn problem(m: usize, seed: &mut u64) -> (Dense, Vec<f64>, Lambda) {
        let a = Dense::random(3 * m, 1.0, seed);
        let b: Vec<f64> = (0..3 * m).map(|i| if i < m { 2.0 + lcg(seed) } else { 3.0 * lcg(seed) }).collect();
        let tangent = (0..m)
            .map(|i| if i % 2 == 0 { TangentSet::Disc(Disc::new(0.5 + 0.3 * lcg(seed).abs())) } else { TangentSet::Ellipse(Ellipse::new(0.8, 0.2)) })
            .collect();
        (a, b, Lambda::new(m, Some(tangent)))
    }

    #[test]
    fn tssn_matches_ssn_on_discs_and_ellipses_with_kkt() {
        let mut seed = 7;
        for _ in 0..5 {
            let (a, b, set) = problem(12, &mut seed);
            let zero = vec![0.0; a.dim()];
            let qp = Qp::new(&a, &b, &set);
            let p = Params::default().with_eps(1e-11);
            let t = solve(&qp, &zero, &p.with_method(Method::Tssn), &mut Silent).expect("TSSN converges");
            let s = solve(&qp, &zero, &p, &mut Silent).expect("SSN converges");
            let d = t.lambda.iter().zip(&s.lambda).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            let scale = s.lambda.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(d <= 1e-8 * scale, "TSSN and SSN differ by {d:e} of {scale:e}");
            let k = kkt::residuals(&set, &t.lambda, &t.gradient, Replicated.norm(&b));
            assert!(k.worst() <= 1e-9, "KKT {k:?}");
            assert!(set.contains(&t.lambda, 1e-12), "the result lies in Λ");
            let slides = t.info.history.iter().map(|h| h.slip).max().unwrap_or(0);
            assert!(slides > 0, "the problem has sliding pairs");
            assert!(t.info.history.iter().all(|h| h.kind == StepKind::Tangent), "no safeguard step at ρ = 1.9/σ");
        }
    }

    /// The damped active set reaches SSN's solution (KKT, in Λ) for θ = 0.5 and 0.9, and it
    /// acts: the normal active counts of some problem's history differ from the undamped run.
    #[test]
    fn the_damped_active_set_reaches_the_same_solution() {
        let mut seed = 7;
        let mut acted = false;
        for _ in 0..5 {
            let (a, b, set) = problem(12, &mut seed);
            let zero = vec![0.0; a.dim()];
            let qp = Qp::new(&a, &b, &set);
            let p = Params::default().with_eps(1e-11);
            let reference = solve(&qp, &zero, &p, &mut Silent).expect("SSN converges");
            let scale = reference.lambda.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let counts = |s: &QpSolution| s.info.history.iter().map(|h| h.normal_active).collect::<Vec<_>>();
            let plain = counts(&solve(&qp, &zero, &p.with_method(Method::Tssn), &mut Silent).expect("TSSN converges"));
            for theta in [0.5, 0.9] {
                let mut pd = Params::new(Method::Tssn).with_eps(1e-11);
                if let crate::qp::MethodParams::Tssn(t) = &mut pd.method {
                    t.damping = theta;
                }
                let t = solve(&qp, &zero, &pd, &mut Silent).unwrap_or_else(|e| panic!("damped TSSN (θ = {theta}) converges: {e}"));
                let d = t.lambda.iter().zip(&reference.lambda).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
                assert!(d <= 1e-8 * scale, "θ = {theta}: differs from SSN by {d:e} of {scale:e}");
                let k = kkt::residuals(&set, &t.lambda, &t.gradient, Replicated.norm(&b));
                assert!(k.worst() <= 1e-9, "θ = {theta}: KKT {k:?}");
                acted |= counts(&t) != plain;
            }
        }
        assert!(acted, "the damping never changed an active set");
    }

    /// The per-row ρ of the active-set decision ([`RhoRule::Diagonal`]) on rows scaled over three
    /// decades (A ← S A S): the same solution as SSN (KKT, in Λ), and it acts — another
    /// sequence of active sets than the scalar ρ's on some problem.
    #[test]
    fn the_diagonal_rho_reaches_the_same_solution_on_badly_scaled_rows() {
        let mut seed = 11;
        let mut acted = false;
        for _ in 0..5 {
            let (mut a, b, set) = problem(12, &mut seed);
            let n = a.dim();
            let scale: Vec<f64> = (0..n).map(|_| 10f64.powf(1.5 * (1.0 + lcg(&mut seed)))).collect();
            for i in 0..n {
                for j in 0..n {
                    a.a[i * n + j] *= scale[i] * scale[j];
                }
            }
            let b: Vec<f64> = b.iter().zip(&scale).map(|(v, s)| v * s).collect();
            let zero = vec![0.0; n];
            let qp = Qp::new(&a, &b, &set);
            let p = Params::default().with_eps(1e-11);
            let reference = solve(&qp, &zero, &p, &mut Silent).expect("SSN converges");
            let norm = reference.lambda.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let counts = |s: &QpSolution| s.info.history.iter().map(|h| h.normal_active).collect::<Vec<_>>();
            let plain = counts(&solve(&qp, &zero, &p.with_method(Method::Tssn), &mut Silent).expect("TSSN converges"));
            let mut pd = Params::new(Method::Tssn).with_eps(1e-11);
            if let crate::qp::MethodParams::Tssn(t) = &mut pd.method {
                t.rho = RhoRule::Diagonal;
            }
            let t = solve(&qp, &zero, &pd, &mut Silent).unwrap_or_else(|e| panic!("TSSN with the diagonal ρ converges: {e}"));
            let d = t.lambda.iter().zip(&reference.lambda).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            assert!(d <= 1e-7 * norm, "differs from SSN by {d:e} of {norm:e}");
            let k = kkt::residuals(&set, &t.lambda, &t.gradient, Replicated.norm(&b));
            assert!(k.worst() <= 1e-9, "KKT {k:?}");
            assert!(set.contains(&t.lambda, 1e-12 * norm), "the result lies in Λ");
            acted |= counts(&t) != plain;
        }
        assert!(acted, "the diagonal ρ never changed an active set");
    }

    /// M = diag(A)⁻¹ on every component.
    struct Jacobi(Vec<f64>);

    impl crate::qp::Preconditioner for Jacobi {
        fn block(&self) -> std::ops::Range<usize> {
            0..self.0.len()
        }
        fn apply(&self, x: &[f64], y: &mut [f64]) {
            y.iter_mut().zip(x).zip(&self.0).for_each(|((y, x), d)| *y = x * d);
        }
    }

    #[test]
    fn preconditioned_ssn_gimssn_and_mpgp_reach_the_same_solution_and_the_monotone_ones_stay_monotone() {
        let mut seed = 5;
        for _ in 0..3 {
            let (a, b, set) = problem(12, &mut seed);
            let n = a.dim();
            let jacobi = Jacobi((0..n).map(|i| 1.0 / a.a[i * n + i]).collect());
            let zero = vec![0.0; n];
            let reference = solve(&Qp::new(&a, &b, &set), &zero, &Params::default().with_eps(1e-11), &mut Silent).expect("SSN converges");
            let scale = reference.lambda.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for method in [Method::SsnBicgstab, Method::Gimssn, Method::Mpgp, Method::Tssn] {
                let mut p = Params::new(method).with_eps(1e-11);
                p.common.max_outer = 20_000;
                let qp = Qp::new(&a, &b, &set).with_preconditioner(Some(&jacobi));
                let s = solve(&qp, &zero, &p, &mut Silent).unwrap_or_else(|e| panic!("{} converges: {e}", method.name()));
                let d = s.lambda.iter().zip(&reference.lambda).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
                assert!(d <= 1e-8 * scale, "{} with M differs by {d:e} of {scale:e}", method.name());
                assert!(s.info.preconditioner_applications > 0, "{} applied M", method.name());
                if matches!(method, Method::Gimssn | Method::Mpgp) {
                    let q: Vec<f64> = s.info.history.iter().map(|h| h.q).collect();
                    assert!(q.windows(2).all(|w| w[1] <= w[0] + 1e-12 * w[0].abs()), "{} is monotone with M: {q:?}", method.name());
                }
            }
        }
    }

    #[test]
    fn the_safeguard_takes_over_when_rho_is_far_too_large_and_still_converges() {
        // ρ far above 2/σ_max: the Newton sets cycle; GIMSSN steps ('g') restore descent
        let mut seed = 11;
        let mut fired = 0;
        for _ in 0..5 {
            let (a, b, set) = problem(12, &mut seed);
            let zero = vec![0.0; a.dim()];
            let mut p = Params::new(Method::Tssn).with_eps(1e-9);
            p.common.rho_factor = 300.0;
            p.common.max_outer = 2000;
            if let crate::qp::MethodParams::Tssn(t) = &mut p.method {
                t.patience = 1;
            }
            let t = solve(&Qp::new(&a, &b, &set), &zero, &p, &mut Silent).expect("converges with the safeguard");
            fired += t.info.history.iter().filter(|h| h.kind == StepKind::Safeguard).count();
            let k = kkt::residuals(&set, &t.lambda, &t.gradient, Replicated.norm(&b));
            assert!(k.worst() <= 1e-7, "KKT {k:?}");
        }
        assert!(fired > 0, "the safeguard never fired at ρ = 300/σ");
    }
}

#[cfg(test)]
mod recycle_tests {
    use super::tests::{lcg, Dense};
    use super::*;
    use crate::qp::krylov::{pcg, Coefficients, Pcg, Recycle, Whole};
    use crate::qp::{solve, Method, MethodParams, Params, Replicated, Silent};

    /// CG restarted every 8 iterations on one SPD system: with the bank the restarts lose
    /// nothing (each restart is deflated by the directions before it, so the iteration goes on
    /// as one CG), without it each restart starts the Krylov space afresh.
    #[test]
    fn recycled_restarts_continue_the_cg() {
        let mut seed = 3;
        let a = Dense::random(120, 1e-3, &mut seed);
        let b: Vec<f64> = (0..120).map(|_| lcg(&mut seed)).collect();
        let set = Lambda::new(0, None);
        let qp = Qp::new(&a, &b, &set);
        let opts = Pcg {
            system: &Whole,
            preconditioner: None,
            coarse: None,
            coefficients: Coefficients::Standard,
            feasible: false,
            max_iter: 8,
            outer: 0,
            relax: None,
            lanczos: false,
        };
        let bnorm = Replicated.norm(&b);
        let restarts = |mut bank: Option<Recycle>| {
            let (mut x, mut g) = (vec![0.0; 120], b.iter().map(|v| -v).collect::<Vec<f64>>());
            for k in 1..=60 {
                pcg(&qp, &opts, &mut x, &mut g, |_| 1e-10 * bnorm, |_| {}, bank.as_mut()).expect("SPD");
                a.apply(&x, &mut g);
                g.iter_mut().zip(&b).for_each(|(gi, bi)| *gi -= bi);
                if Replicated.norm(&g) <= 1e-8 * bnorm {
                    return k;
                }
            }
            61
        };
        let (plain, recycled) = (restarts(None), restarts(Some(Recycle::new(200))));
        assert!(recycled * 2 <= plain, "recycled restarts {recycled}, plain {plain}");
    }

    /// The Lanczos estimate of κ from the CG coefficients: from below, and close once the
    /// CG has seen much of the spectrum (diag(1 … 1000) geometric, 30 iterations of 60: 731).
    #[test]
    fn the_inner_cg_estimates_the_condition_number() {
        let d: Vec<f64> = (0..60).map(|i| 1000f64.powf(i as f64 / 59.0)).collect();
        let a = Dense::diagonal(&d);
        let b = vec![1.0; 60];
        let set = Lambda::new(0, None);
        let qp = Qp::new(&a, &b, &set);
        let opts = Pcg {
            system: &Whole,
            preconditioner: None,
            coarse: None,
            coefficients: Coefficients::Standard,
            feasible: false,
            max_iter: 30,
            outer: 0,
            relax: None,
            lanczos: true,
        };
        let (mut x, mut g) = (vec![0.0; 60], vec![-1.0; 60]);
        let info = pcg(&qp, &opts, &mut x, &mut g, |_| 0.0, |_| {}, None).expect("SPD");
        let kappa = info.kappa.expect("30 iterations");
        assert!((500.0..=1000.0 * (1.0 + 1e-9)).contains(&kappa), "κ estimate {kappa}");
    }

    #[test]
    fn tssn_with_recycling_reaches_the_same_solution() {
        let mut seed = 7;
        let a = Dense::random(36, 1.0, &mut seed);
        let b: Vec<f64> = (0..36).map(|i| if i < 12 { 2.0 + lcg(&mut seed) } else { 3.0 * lcg(&mut seed) }).collect();
        let tangent = (0..12).map(|_| crate::qp::sets::TangentSet::Disc(crate::qp::sets::Disc::new(0.5 + 0.3 * lcg(&mut seed).abs()))).collect();
        let set = Lambda::new(12, Some(tangent));
        let qp = Qp::new(&a, &b, &set);
        let zero = vec![0.0; 36];
        let mut p = Params::new(Method::Tssn).with_eps(1e-11);
        let plain = solve(&qp, &zero, &p, &mut Silent).expect("TSSN converges");
        if let MethodParams::Tssn(t) = &mut p.method {
            t.recycle = 30;
        }
        let recycled = solve(&qp, &zero, &p, &mut Silent).expect("TSSN with recycling converges");
        let d = plain.lambda.iter().zip(&recycled.lambda).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        assert!(d <= 1e-8, "recycling changed λ by {d:e}");
    }
}
