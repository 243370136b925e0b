//! The Krylov kernels of the inner solves: one masked, preconditioned CG (`pcg`) for every
//! symmetric inner system (GIMSSN's CGMfeas, IMSSN/MSSN, TSSN, plain CG) and one BiCGSTAB
//! (`Bicgstab`, right-preconditioned where a preconditioner is given) for SSN's unsymmetric
//! Newton systems. [`Recycle`] keeps the directions of earlier inner solves, which `pcg` then
//! deflates (its directions kept S-orthogonal to them) when the system has not changed its
//! structure.

use super::driver::positive_curvature;
use super::operator::{CoarseProjector, Operator, Preconditioner, Space};
use super::{Qp, QpError};

/// The symmetric inner system `S v = Π A v + C v` on a subspace of the dual vectors (v = Π v):
/// Π a projection (a mask of free components, and t tᵀ on TSSN's sliding pairs), C ≥ 0 diagonal
/// on the subspace.
pub(crate) trait InnerSystem {
    /// out = Π g + C v; with `v` None, out = Π g (the system's residual from a gradient g).
    fn apply(&self, g: &[f64], v: Option<&[f64]>, out: &mut [f64]);
}

/// Every component free, C = 0: S = A.
pub(crate) struct Whole;

impl InnerSystem for Whole {
    fn apply(&self, g: &[f64], _: Option<&[f64]>, out: &mut [f64]) {
        out.copy_from_slice(g);
    }
}

/// The components where `free` holds, C = 0.
pub(crate) struct Masked<'a>(pub &'a [bool]);

impl InnerSystem for Masked<'_> {
    fn apply(&self, g: &[f64], _: Option<&[f64]>, out: &mut [f64]) {
        for ((o, gi), f) in out.iter_mut().zip(g).zip(self.0) {
            *o = if *f { *gi } else { 0.0 };
        }
    }
}

/// The components where `free` holds and the lines t of `slides` (first component, unit t):
/// Π = the mask, t tᵀ on a sliding pair; C = 0.
pub(crate) struct Subspace<'a> {
    pub free: &'a [bool],
    pub slides: &'a [(usize, [f64; 2])],
}

impl InnerSystem for Subspace<'_> {
    fn apply(&self, g: &[f64], _: Option<&[f64]>, out: &mut [f64]) {
        Masked(self.free).apply(g, None, out);
        for &(k, t) in self.slides {
            let a = t[0] * g[k] + t[1] * g[k + 1];
            out[k] = a * t[0];
            out[k + 1] = a * t[1];
        }
    }
}

/// M v into `buf` with a (right) preconditioner, v itself without one (no copy).
fn right<'a>(m: &mut Option<&mut dyn FnMut(&[f64], &mut [f64])>, v: &'a [f64], buf: &'a mut [f64]) -> &'a [f64] {
    match m {
        Some(m) => {
            m(v, buf);
            buf
        }
        None => v,
    }
}

/// z = P_W Π M̂ Π h: the preconditioner M on its block, `scale`·I on the other components,
/// restricted to the system's subspace and projected onto Ker G ∩ W (`work`: scratch).
pub(crate) fn precondition(
    m: &dyn Preconditioner,
    scale: f64,
    system: &dyn InnerSystem,
    coarse: Option<&dyn CoarseProjector>,
    h: &[f64],
    z: &mut [f64],
    work: &mut [f64],
) {
    m.apply(h, work);
    let block = m.block();
    for (k, (p, hk)) in work.iter_mut().zip(h).enumerate() {
        if !block.contains(&k) {
            *p = scale * hk;
        }
    }
    system.apply(work, None, z);
    project(system, coarse, z, work);
}

/// How the CG coefficients are formed (equal in exact arithmetic).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Coefficients {
    /// α = hᵀz/dᵀSd, β = h₊ᵀz₊/hᵀz, d = z + βd: the textbook PCG (TSSN, plain CG).
    Standard,
    /// α = hᵀd/dᵀSd, β = h₊ᵀSd/dᵀSd, d = h − βd: conjugacy enforced against the last direction
    /// (the paper's CGMfeas; no preconditioner).
    Conjugated,
}

/// One inner solve: the system, where it stops, what it may use.
pub(crate) struct Pcg<'a> {
    pub system: &'a dyn InnerSystem,
    /// M on its block, with ρ·I on the other components (then projected by Π).
    pub preconditioner: Option<(&'a dyn Preconditioner, f64)>,
    /// Keeps the residuals and directions in Ker G ∩ W (projected CG).
    pub coarse: Option<&'a dyn CoarseProjector>,
    pub coefficients: Coefficients,
    /// CGMfeas: a step that would leave Λ goes to the boundary and ends the solve.
    pub feasible: bool,
    pub max_iter: usize,
    pub outer: usize,
    /// Inexact products allowed ([`RELAXATION`]) with this estimate of the condition number κ
    /// of the (preconditioned) system — from the last solve, [`PcgInfo::kappa`] — for an inner
    /// solve of an outer iteration that recomputes its residual exactly; `None`: exact products
    /// (the plain CG, where the relaxation measured slower).
    pub relax: Option<f64>,
    /// Estimate κ from the CG coefficients ([`PcgInfo::kappa`]; for `relax` of a later solve).
    pub lanczos: bool,
}

/// v ← Π(v − Gᵀ(GΠGᵀ)⁻¹Gv) for v in the subspace: the orthogonal projection onto Ker G ∩ W.
fn project(system: &dyn InnerSystem, coarse: Option<&dyn CoarseProjector>, v: &mut [f64], work: &mut [f64]) {
    if let Some(p) = coarse {
        p.apply(v);
        system.apply(v, None, work);
        v.copy_from_slice(work);
    }
}

/// The directions of earlier inner solves and their A-products (as the solve formed them:
/// `apply_kernel` under a coarse space), kept for deflation — Krylov recycling across Newton
/// steps. The caller empties it when the system's structure (which components move) changes;
/// within one structure the subspace and C move only with the sliding pairs' tangents and cᵢ,
/// so the stored products are those of the new system up to that drift, which only slows
/// the deflation (the iteration's own products are exact). The oldest go first past `cap`.
pub(crate) struct Recycle {
    cap: usize,
    w: std::collections::VecDeque<(Vec<f64>, Vec<f64>)>,
}

impl Recycle {
    pub fn new(cap: usize) -> Self {
        Recycle { cap, w: Default::default() }
    }
    pub fn clear(&mut self) {
        self.w.clear();
    }
    fn push(&mut self, d: Vec<f64>, ad: Vec<f64>) {
        if self.cap == 0 {
            return;
        }
        if self.w.len() == self.cap {
            self.w.pop_front();
        }
        self.w.push_back((d, ad));
    }
}

/// A kept direction w whose projection onto the new system's subspace moved by more than this
/// fraction of ‖w‖ is not used: its stored product is too stale.
const DRIFT_MAX: f64 = 1e-2;

/// The deflation space of one solve: U (the kept directions brought into the system's subspace),
/// A U (stored), S U, and the pseudo-inverse of E = UᵀSU.
struct Deflation {
    u: Vec<Vec<f64>>,
    au: Vec<Vec<f64>>,
    su: Vec<Vec<f64>>,
    /// E⁺ = Q diag(1/θ) Qᵀ over E's eigenpairs with θ > 1e-10 θ_max, row-major k × k.
    einv: Vec<f64>,
}

impl Deflation {
    fn new<S: Space>(sp: &S, bank: &Recycle, system: &dyn InnerSystem, coarse: Option<&dyn CoarseProjector>, work: &mut [f64]) -> Option<Deflation> {
        let k = bank.w.len();
        if k == 0 {
            return None;
        }
        let n = work.len();
        let (mut u, mut au, mut su) = (Vec::with_capacity(k), Vec::with_capacity(k), Vec::with_capacity(k));
        for (w, aw) in &bank.w {
            let mut v = vec![0.0; n];
            system.apply(w, None, &mut v);
            project(system, coarse, &mut v, work);
            let dv: Vec<f64> = v.iter().zip(w).map(|(a, b)| a - b).collect();
            if sp.norm(&dv) > DRIFT_MAX * sp.norm(w) {
                continue;
            }
            let mut sv = vec![0.0; n];
            system.apply(aw, Some(&v), &mut sv);
            project(system, coarse, &mut sv, work);
            u.push(v);
            au.push(aw.clone());
            su.push(sv);
        }
        let k = u.len();
        if k == 0 {
            return None;
        }
        let mut pairs = Vec::with_capacity(k * (k + 1) / 2);
        for i in 0..k {
            for j in 0..=i {
                pairs.push((&u[i][..], &su[j][..]));
            }
        }
        let mut e = vec![0.0; pairs.len()];
        sp.dots(&pairs, &mut e);
        let mut m = faer::Mat::<f64>::zeros(k, k);
        let mut at = 0;
        for i in 0..k {
            for j in 0..=i {
                m[(i, j)] = e[at];
                m[(j, i)] = e[at];
                at += 1;
            }
        }
        let eig = m.self_adjoint_eigen(faer::Side::Lower).ok()?;
        let (theta, q) = (eig.S(), eig.U());
        let top = (0..k).map(|i| theta[i]).fold(0.0, f64::max);
        if !(top > 0.0 && top.is_finite()) {
            return None;
        }
        let mut einv = vec![0.0; k * k];
        for l in (0..k).filter(|&l| theta[l] > 1e-10 * top) {
            for i in 0..k {
                for j in 0..k {
                    einv[i * k + j] += q[(i, l)] * q[(j, l)] / theta[l];
                }
            }
        }
        Some(Deflation { u, au, su, einv })
    }

    /// c = E⁺ Vᵀ y for V = U (`by_u`) or S U.
    fn coefficients<S: Space>(&self, sp: &S, y: &[f64], by_u: bool) -> Vec<f64> {
        let k = self.u.len();
        let v = if by_u { &self.u } else { &self.su };
        let pairs: Vec<(&[f64], &[f64])> = v.iter().map(|v| (&v[..], y)).collect();
        let mut t = vec![0.0; k];
        sp.dots(&pairs, &mut t);
        (0..k).map(|i| (0..k).map(|j| self.einv[i * k + j] * t[j]).sum()).collect()
    }
}

/// The relative product error [`pcg`] allows at an iteration whose residual is ‖h‖: this
/// fraction of threshold/‖h‖ (the relaxation bound of inexact Krylov methods: Simoncini and
/// Szyld 2003, van den Eshof and Sleijpen 2004).
pub(crate) const RELAXATION: f64 = 0.1;

/// What one [`pcg`] did.
pub(crate) struct PcgInfo {
    pub iterations: usize,
    /// Applications of the preconditioner.
    pub applications: usize,
    /// Iterations whose product was inexact ([`Operator::allow_error`]): the gradient's
    /// recurrence carries their error.
    pub inexact: usize,
    /// With `lanczos`: λ_max/λ_min of the Lanczos tridiagonal of the solve (standard
    /// coefficients, ≥ 3 iterations): an estimate, from below, of the preconditioned system's
    /// condition number.
    pub kappa: Option<f64>,
}

/// The Lanczos tridiagonal of the κ estimate takes at most this many of a solve's first
/// coefficients (its eigenvalues cost O(k³); an estimate from below either way).
const LANCZOS_MAX: usize = 200;

/// λ_max/λ_min of the Lanczos tridiagonal T of a PCG run with coefficients α_j, β_j:
/// T_jj = 1/α_j + β_{j−1}/α_{j−1}, T_{j,j+1} = √β_j/α_j. None below 3 iterations.
fn condition(alpha: &[f64], beta: &[f64]) -> Option<f64> {
    let k = alpha.len();
    if k < 3 {
        return None;
    }
    let mut t = faer::Mat::<f64>::zeros(k, k);
    for j in 0..k {
        t[(j, j)] = 1.0 / alpha[j] + if j > 0 { beta[j - 1] / alpha[j - 1] } else { 0.0 };
        if j + 1 < k && j < beta.len() {
            let off = beta[j].sqrt() / alpha[j];
            t[(j, j + 1)] = off;
            t[(j + 1, j)] = off;
        }
    }
    let ev = t.self_adjoint_eigenvalues(faer::Side::Lower).ok()?;
    let (lo, hi) = ev.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &v| (l.min(v), h.max(v)));
    (lo > 0.0 && hi.is_finite()).then_some(hi / lo)
}

/// CG on the inner system from x with g = r(x) = A x − b: the system's residual h = Π g (+ C σ,
/// σ = 0 at the start), stopped at ‖h‖ ≤ `threshold(‖h₀‖)` or after `max_iter` iterations (one
/// A-product each). x and g (by the recurrence) are updated in place; `each(‖h‖)` is called
/// after every iteration. With a `bank` (standard coefficients only) its directions deflate the
/// solve — the start is corrected over them (x −= U c, UᵀS U c = Uᵀh) and every direction is
/// kept S-orthogonal to them (deflated PCG, Saad et al. 2000) — and this solve's directions are
/// added to it.
pub(crate) fn pcg<A: Operator>(
    qp: &Qp<'_, A>,
    opts: &Pcg<'_>,
    x: &mut [f64],
    g: &mut [f64],
    threshold: impl FnOnce(f64) -> f64,
    mut each: impl FnMut(f64),
    bank: Option<&mut Recycle>,
) -> Result<PcgInfo, QpError> {
    let a = qp.a;
    let sp = a.space();
    let n = x.len();
    let mut run = PcgRun::new(opts, n);
    run.residual(sp, g);
    let threshold = threshold(run.hnorm);
    // projected: the directions lie in Ker G, so A d = F d + Gᵀ(…) (`apply_kernel`), whose Gᵀ
    // part the projection of md removes; the gradient's recurrence sums F d and is mapped to
    // A's once at the end (`finish_kernel`)
    let g0 = if opts.coarse.is_some() { g.to_vec() } else { vec![] };
    debug_assert!(bank.is_none() || opts.coefficients == Coefficients::Standard);
    let deflation = match (&bank, run.hnorm > threshold) {
        (Some(b), true) => {
            let mut scratch = vec![0.0; n];
            Deflation::new(sp, b, opts.system, opts.coarse, &mut scratch)
        }
        _ => None,
    };
    if let Some(df) = &deflation {
        run.correct_start(sp, df, x, g);
    }
    run.first_direction(sp, deflation.as_ref());
    let h_start = run.hnorm;
    let mut kept: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    let (mut it, mut inexact) = (0, 0);
    // the CG coefficients α_j, β_j: the Lanczos tridiagonal of the preconditioned system
    let mut lanczos: (Vec<f64>, Vec<f64>) = (vec![], vec![]);
    while run.hnorm > threshold && it < opts.max_iter {
        if run.relax(a, threshold) {
            inexact += 1;
        }
        let dmd = run.product(a)?;
        if bank.is_some() {
            kept.push((run.d.clone(), run.ad.clone()));
        }
        it += 1;
        let alpha = run.alpha(sp, dmd);
        if opts.lanczos && lanczos.0.len() < LANCZOS_MAX {
            lanczos.0.push(alpha);
        }
        if opts.feasible && run.to_boundary(qp, alpha, x, g) {
            each(run.hnorm);
            break;
        }
        run.step(alpha, x, g);
        let beta = run.next_direction(sp, dmd, deflation.as_ref());
        if let Some(beta) = beta.filter(|_| opts.lanczos && lanczos.1.len() < LANCZOS_MAX) {
            lanczos.1.push(beta);
        }
        each(run.hnorm);
        if deflation.is_some() && run.hnorm > 2.0 * h_start {
            // stale deflation (the tangents moved more than the drift test saw): the iteration
            // is no longer a CG; stop here and let the Newton step go on from x
            break;
        }
    }
    a.allow_error(0.0);
    if opts.coarse.is_some() && it > 0 {
        finish_gradient(a, &g0, g);
    }
    if run.preconditioned {
        // the last residual's preconditioning counts too (as it always did: one per iteration + 1)
        debug_assert_eq!(run.applications, it + 1);
    }
    if let Some(b) = bank {
        for (d, ad) in kept {
            b.push(d, ad);
        }
    }
    let kappa = (opts.lanczos && opts.coefficients == Coefficients::Standard).then(|| condition(&lanczos.0, &lanczos.1)).flatten();
    Ok(PcgInfo { iterations: it, applications: run.applications, inexact, kappa })
}

/// g = g₀ − Σ α A d = g₀ − P̃(g₀ − g): the projected solve's gradient mapped to A's.
fn finish_gradient<A: Operator>(a: &A, g0: &[f64], g: &mut [f64]) {
    let mut sum: Vec<f64> = g0.iter().zip(g.iter()).map(|(a, b)| a - b).collect();
    a.finish_kernel(&mut sum);
    for ((gi, g0i), si) in g.iter_mut().zip(g0).zip(&sum) {
        *gi = g0i - si;
    }
}

/// d −= U E⁺ (SU)ᵀ z: a direction made S-orthogonal to the deflation space (none: unchanged).
fn deflate<S: Space>(sp: &S, deflation: Option<&Deflation>, z: &[f64], d: &mut [f64]) {
    if let Some(df) = deflation {
        let n = d.len();
        let mu = df.coefficients(sp, z, false);
        for (j, mj) in mu.iter().enumerate() {
            for i in 0..n {
                d[i] -= mj * df.u[j][i];
            }
        }
    }
}

/// The vectors and scalars of one [`pcg`] run: residual h, preconditioned residual z,
/// direction d and its products A d and S d.
struct PcgRun<'o, 'a> {
    opts: &'o Pcg<'a>,
    h: Vec<f64>,
    z: Vec<f64>,
    d: Vec<f64>,
    ad: Vec<f64>,
    md: Vec<f64>,
    /// The preconditioner's and the projection's scratch (empty where unused).
    pz: Vec<f64>,
    work: Vec<f64>,
    /// Applications of the preconditioner.
    applications: usize,
    /// hᵀz and ‖h‖.
    hz: f64,
    hnorm: f64,
    preconditioned: bool,
}

impl<'o, 'a> PcgRun<'o, 'a> {
    /// The run's vectors for n unknowns, zero.
    fn new(opts: &'o Pcg<'a>, n: usize) -> Self {
        PcgRun {
            opts,
            h: vec![0.0; n],
            z: vec![0.0; n],
            d: vec![0.0; n],
            ad: vec![0.0; n],
            md: vec![0.0; n],
            pz: if opts.preconditioner.is_some() { vec![0.0; n] } else { vec![] },
            work: if opts.coarse.is_some() { vec![0.0; n] } else { vec![] },
            applications: 0,
            hz: 0.0,
            hnorm: 0.0,
            preconditioned: opts.preconditioner.is_some(),
        }
    }

    /// z = Π M h (z = h without a preconditioner).
    fn apply_m(&mut self) {
        match self.opts.preconditioner {
            Some((m, scale)) => {
                precondition(m, scale, self.opts.system, self.opts.coarse, &self.h, &mut self.z, &mut self.pz);
                self.applications += 1;
            }
            None => self.z.copy_from_slice(&self.h),
        }
    }

    /// The system's residual h = Π g (projected), hᵀh and ‖h‖.
    fn residual<S: Space>(&mut self, sp: &S, g: &[f64]) {
        self.opts.system.apply(g, None, &mut self.h);
        project(self.opts.system, self.opts.coarse, &mut self.h, &mut self.work);
        self.hz = sp.dot(&self.h, &self.h);
        self.hnorm = self.hz.sqrt();
    }

    /// The start's Galerkin correction over the deflation space U.
    fn correct_start<S: Space>(&mut self, sp: &S, df: &Deflation, x: &mut [f64], g: &mut [f64]) {
        let n = x.len();
        let c = df.coefficients(sp, &self.h, true);
        for (j, cj) in c.iter().enumerate() {
            for i in 0..n {
                x[i] -= cj * df.u[j][i];
                g[i] -= cj * df.au[j][i];
                self.h[i] -= cj * df.su[j][i];
            }
        }
        self.hz = sp.dot(&self.h, &self.h);
        self.hnorm = self.hz.sqrt();
    }

    /// z = Π M h, hᵀz, and the first direction d = z − U E⁺ (SU)ᵀ z.
    fn first_direction<S: Space>(&mut self, sp: &S, deflation: Option<&Deflation>) {
        if self.preconditioned {
            self.apply_m();
            self.hz = sp.dot(&self.h, &self.z);
        } else {
            self.z.copy_from_slice(&self.h);
        }
        self.d.copy_from_slice(&self.z);
        deflate(sp, deflation, &self.z, &mut self.d);
    }

    /// Allows this iteration's product an error where the solve relaxes (inexact Krylov: a
    /// product's error enters the iterate in proportion to the step, which shrinks with ‖h‖, so
    /// the error allowed grows as ‖h‖ falls toward the threshold); whether it is inexact.
    fn relax<A: Operator>(&self, a: &A, threshold: f64) -> bool {
        // a product's error η·‖A‖‖d‖ against the ‖A d‖ ≥ λ_min‖d‖ of the worst direction
        self.opts.relax.is_some_and(|kappa| a.allow_error(RELAXATION * threshold / (self.hnorm * kappa)))
    }

    /// A d, S d (projected) and the curvature dᵀSd, which must be positive.
    fn product<A: Operator>(&mut self, a: &A) -> Result<f64, QpError> {
        let opts = self.opts;
        if opts.coarse.is_some() {
            a.apply_kernel(&self.d, &mut self.ad);
        } else {
            a.apply(&self.d, &mut self.ad);
        }
        opts.system.apply(&self.ad, Some(&self.d), &mut self.md);
        project(opts.system, opts.coarse, &mut self.md, &mut self.work);
        positive_curvature(a.space().dot(&self.d, &self.md), "the curvature dᵀSd", opts.outer)
    }

    /// The step length α along d.
    fn alpha<S: Space>(&self, sp: &S, dmd: f64) -> f64 {
        match self.opts.coefficients {
            Coefficients::Standard => self.hz / dmd,
            Coefficients::Conjugated => sp.dot(&self.h, &self.d) / dmd,
        }
    }

    /// CGMfeas: where the CG step α would leave Λ, goes to the boundary instead; whether it did
    /// (the solve then stops).
    fn to_boundary<A: Operator>(&self, qp: &Qp<'_, A>, alpha: f64, x: &mut [f64], g: &mut [f64]) -> bool {
        let alpha_f = qp.a.space().min(qp.set.max_step(x, &self.d));
        if alpha > alpha_f {
            for i in 0..x.len() {
                x[i] -= alpha_f * self.d[i];
                g[i] -= alpha_f * self.ad[i];
            }
            return true;
        }
        false
    }

    /// x, g and h moved by the step α along d.
    fn step(&mut self, alpha: f64, x: &mut [f64], g: &mut [f64]) {
        for i in 0..x.len() {
            x[i] -= alpha * self.d[i];
            g[i] -= alpha * self.ad[i];
            self.h[i] -= alpha * self.md[i];
        }
    }

    /// The next direction and ‖h‖ (with the standard coefficients also z and hᵀz); the
    /// standard coefficients' β.
    fn next_direction<S: Space>(&mut self, sp: &S, dmd: f64, deflation: Option<&Deflation>) -> Option<f64> {
        let n = self.d.len();
        match self.opts.coefficients {
            Coefficients::Standard => {
                let hz_new = if self.preconditioned {
                    self.apply_m();
                    let v = sp.dot(&self.h, &self.z);
                    self.hnorm = sp.norm(&self.h);
                    v
                } else {
                    self.z.copy_from_slice(&self.h);
                    let v = sp.dot(&self.h, &self.h);
                    self.hnorm = v.sqrt();
                    v
                };
                let beta = hz_new / self.hz;
                self.hz = hz_new;
                for i in 0..n {
                    self.d[i] = self.z[i] + beta * self.d[i];
                }
                deflate(sp, deflation, &self.z, &mut self.d);
                Some(beta)
            }
            Coefficients::Conjugated => {
                let beta = sp.dot(&self.h, &self.md) / dmd;
                for i in 0..n {
                    self.d[i] = self.h[i] - beta * self.d[i];
                }
                self.hnorm = sp.dot(&self.h, &self.h).sqrt();
                None
            }
        }
    }
}

/// BiCGSTAB workspace: the solution x of J x = rhs and A x, accumulated from the products.
pub(crate) struct Bicgstab {
    pub x: Vec<f64>,
    pub ax: Vec<f64>,
    res: Vec<f64>,
    rhat: Vec<f64>,
    p: Vec<f64>,
    v: Vec<f64>,
    ap: Vec<f64>,
    s: Vec<f64>,
    t: Vec<f64>,
    as_: Vec<f64>,
    /// M p and M s (right preconditioning; empty without).
    mp: Vec<f64>,
    ms: Vec<f64>,
}

impl Bicgstab {
    pub fn new(n: usize) -> Self {
        let z = || vec![0.0; n];
        Bicgstab { x: z(), ax: z(), res: z(), rhat: z(), p: z(), v: z(), ap: z(), s: z(), t: z(), as_: z(), mp: vec![], ms: vec![] }
    }

    /// Solves J x = rhs from x = 0 until ‖rhs − Jx‖ ≤ threshold; returns the iterations.
    /// `jacobian(v, jv, av)` writes J v and A v. With `precondition` (y = M v, M ≈ J⁻¹) it
    /// solves J M y = rhs, x = M y (right preconditioning: the residual it tests is J x's own).
    /// A breakdown after some progress ends the solve with the last iterate (Newton goes on
    /// from an inexact step); one before any progress is an error.
    #[allow(clippy::too_many_arguments)]
    pub fn solve<S: Space>(
        &mut self,
        sp: &S,
        rhs: &[f64],
        threshold: f64,
        max_iter: usize,
        jacobian: impl Fn(&[f64], &mut [f64], &mut [f64]),
        mut precondition: Option<&mut dyn FnMut(&[f64], &mut [f64])>,
        outer: usize,
    ) -> Result<usize, QpError> {
        let n = rhs.len();
        if precondition.is_some() {
            self.mp.resize(n, 0.0);
            self.ms.resize(n, 0.0);
        }
        self.x.fill(0.0);
        self.ax.fill(0.0);
        self.res.copy_from_slice(rhs);
        self.rhat.copy_from_slice(rhs);
        self.p.fill(0.0);
        self.v.fill(0.0);
        self.ap.fill(0.0);
        let (mut rho_old, mut alpha, mut omega) = (1.0, 1.0, 1.0);
        let mut it = 0;
        let mut rnorm = sp.norm(&self.res);
        let fail = |it: usize, what| if it == 0 { Err(QpError::BicgstabBreakdown { outer, what }) } else { Ok(it) };
        while rnorm > threshold && it < max_iter {
            if !rnorm.is_finite() {
                return Err(QpError::NotFinite { what: "the BiCGSTAB residual", outer });
            }
            let rho_new = sp.dot(&self.rhat, &self.res);
            if rho_new == 0.0 {
                return fail(it, "r̂ᵀr = 0");
            }
            let beta = (rho_new / rho_old) * (alpha / omega);
            for i in 0..n {
                self.p[i] = self.res[i] + beta * (self.p[i] - omega * self.v[i]);
            }
            let mp = right(&mut precondition, &self.p, &mut self.mp);
            jacobian(mp, &mut self.v, &mut self.ap);
            let rv = sp.dot(&self.rhat, &self.v);
            if rv == 0.0 || !rv.is_finite() {
                return fail(it, "r̂ᵀJp = 0");
            }
            alpha = rho_new / rv;
            for i in 0..n {
                self.s[i] = self.res[i] - alpha * self.v[i];
            }
            it += 1;
            let snorm = sp.norm(&self.s);
            if snorm <= threshold {
                for i in 0..n {
                    self.x[i] += alpha * mp[i];
                    self.ax[i] += alpha * self.ap[i];
                }
                return Ok(it);
            }
            let ms = right(&mut precondition, &self.s, &mut self.ms);
            jacobian(ms, &mut self.t, &mut self.as_);
            let tt = sp.dot(&self.t, &self.t);
            omega = if tt > 0.0 { sp.dot(&self.t, &self.s) / tt } else { 0.0 };
            for i in 0..n {
                self.x[i] += alpha * mp[i] + omega * ms[i];
                self.ax[i] += alpha * self.ap[i] + omega * self.as_[i];
                self.res[i] = self.s[i] - omega * self.t[i];
            }
            if omega == 0.0 {
                return Ok(it);
            }
            rnorm = sp.norm(&self.res);
            rho_old = rho_new;
        }
        Ok(it)
    }
}
