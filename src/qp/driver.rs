//! The outer loop every solver shares: σ_est and ρ (`Setup`), the stop test `‖r̃_ρ‖ ≤ ε‖b‖`
//! with its confirmation by a fresh product, the budgets (outer steps, A-products), non-finite
//! values, the history and [`Info`], and the [`Monitor`] that sees each outer step as it ends.

use std::time::Instant;

use super::cone::{cut, Coefficient};
use super::lambda::{ActiveSets, Lambda};
use super::operator::{Operator, Space};
use super::params::{Common, SigmaEstimate};
use super::{Info, Qp, QpError, QpSolution, Step, StepKind};

/// The safety factor on the power iterations' σ_max estimate (they underestimate it,
/// docs/method.md, "The solvers"): ρ = rho_factor/(SIGMA_SAFETY·σ_est).
pub const SIGMA_SAFETY: f64 = 1.1;

/// Sees every outer step as the solver records it (PETSc's `-ksp_monitor`). Called on every rank
/// with the same values; solvers never print.
pub trait Monitor {
    /// Sees outer step `k` (its index in [`Info::history`], from 0) as it is recorded.
    fn step(&mut self, k: usize, step: &Step);
}

/// The monitor that ignores everything.
pub struct Silent;

impl Monitor for Silent {
    fn step(&mut self, _: usize, _: &Step) {}
}

/// The unit start vector of the σ_max estimates, the same for every distribution of the
/// components (it depends on the global index only).
fn start_vector<A: Operator>(a: &A) -> Vec<f64> {
    let sp = a.space();
    let mut x: Vec<f64> = (0..a.dim()).map(|i| 1.0 + 0.1 * ((sp.global_index(i) * 7919) % 13) as f64).collect();
    let nx = sp.norm(&x);
    x.iter_mut().for_each(|v| *v /= nx);
    x
}

/// σ_max(A) by `iterations` power iterations from a fixed start vector.
pub fn power_sigma<A: Operator>(a: &A, iterations: usize) -> f64 {
    let sp = a.space();
    let n = a.dim();
    let mut x = start_vector(a);
    let mut y = vec![0.0; n];
    let mut sigma = 0.0;
    for _ in 0..iterations {
        a.apply(&x, &mut y);
        sigma = sp.norm(&y);
        if sigma == 0.0 || !sigma.is_finite() {
            break;
        }
        for (xi, yi) in x.iter_mut().zip(&y) {
            *xi = yi / sigma;
        }
    }
    sigma
}

/// σ_max(A) by `steps` Lanczos steps from the power iterations' start vector: the largest
/// eigenvalue of the tridiagonal T_k (a Ritz value, below σ_max and converging to it much faster
/// than the power method: its error falls like a Chebyshev polynomial of degree k, not like
/// (σ₂/σ₁)^k). No reorthogonalization: lost orthogonality only repeats converged Ritz values.
pub fn lanczos_sigma<A: Operator>(a: &A, steps: usize) -> f64 {
    let sp = a.space();
    let n = a.dim();
    let mut q = start_vector(a);
    let (mut q_prev, mut w) = (vec![0.0; n], vec![0.0; n]);
    let (mut alpha, mut beta) = (Vec::with_capacity(steps), Vec::with_capacity(steps));
    let mut b_prev = 0.0;
    for _ in 0..steps {
        a.apply(&q, &mut w);
        for i in 0..n {
            w[i] -= b_prev * q_prev[i];
        }
        let al = sp.dot(&q, &w);
        for i in 0..n {
            w[i] -= al * q[i];
        }
        alpha.push(al);
        let b = sp.norm(&w);
        // breakdown (an invariant subspace) or NaN: T_k is all there is
        if b.is_nan() || b <= 1e-14 * al.abs() || !b.is_finite() {
            break;
        }
        beta.push(b);
        std::mem::swap(&mut q_prev, &mut q);
        for i in 0..n {
            q[i] = w[i] / b;
        }
        b_prev = b;
    }
    beta.truncate(alpha.len().saturating_sub(1));
    tridiagonal_max_eigenvalue(&alpha, &beta)
}

/// The largest eigenvalue of the symmetric tridiagonal matrix (diagonal `a`, off-diagonal `b`)
/// by bisection on the Sturm sequence count (NaN for empty or non-finite input).
fn tridiagonal_max_eigenvalue(a: &[f64], b: &[f64]) -> f64 {
    if a.is_empty() || a.iter().chain(b).any(|v| !v.is_finite()) {
        return f64::NAN;
    }
    // Gershgorin bounds
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..a.len() {
        let r = if i > 0 { b[i - 1].abs() } else { 0.0 } + if i < b.len() { b[i].abs() } else { 0.0 };
        lo = lo.min(a[i] - r);
        hi = hi.max(a[i] + r);
    }
    // eigenvalues below x: the negative pivots of T − xI
    let below = |x: f64| {
        let (mut d, mut count) = (1.0, 0);
        for i in 0..a.len() {
            let off = if i > 0 { b[i - 1] * b[i - 1] } else { 0.0 };
            d = a[i] - x - if i > 0 { off / d } else { 0.0 };
            if d == 0.0 {
                d = -f64::MIN_POSITIVE;
            }
            if d < 0.0 {
                count += 1;
            }
        }
        count
    };
    let n = a.len();
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if below(mid) < n {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// σ_max(A) as `c` asks: `power_iterations` steps of the power method or of Lanczos.
pub fn estimate_sigma<A: Operator>(a: &A, c: &Common) -> f64 {
    match c.sigma_estimate {
        SigmaEstimate::Power => power_sigma(a, c.power_iterations),
        SigmaEstimate::Lanczos => lanczos_sigma(a, c.power_iterations),
    }
}

/// The common start of every solver: σ_est, ρ, ‖b‖ and the product count at the start.
pub(crate) struct Setup {
    pub n0: usize,
    pub n_power: usize,
    pub sigma: f64,
    pub rho: f64,
    pub bnorm: f64,
}

impl Setup {
    pub fn new<A: Operator>(a: &A, b: &[f64], c: &Common) -> Result<Setup, QpError> {
        let n0 = a.products();
        let sigma = c.sigma.unwrap_or_else(|| estimate_sigma(a, c));
        let n_power = a.products() - n0;
        if !(sigma.is_finite() && sigma > 0.0) {
            return Err(QpError::NotFinite { what: "the σ_max estimate", outer: 0 });
        }
        let rho = c.rho_factor / (SIGMA_SAFETY * sigma);
        let bnorm = a.space().norm(b).max(f64::MIN_POSITIVE);
        Ok(Setup { n0, n_power, sigma, rho, bnorm })
    }

    /// Without σ_max (plain CG).
    pub fn unconstrained<A: Operator>(a: &A, b: &[f64]) -> Setup {
        Setup { n0: a.products(), n_power: 0, sigma: 0.0, rho: 0.0, bnorm: a.space().norm(b).max(f64::MIN_POSITIVE) }
    }
}

/// The outer loop's bookkeeping for one solve of `qp`.
pub(crate) struct Driver<'q, 'm, A: Operator> {
    pub qp: &'q Qp<'q, A>,
    pub st: Setup,
    pub info: Info,
    eps: f64,
    max_outer: usize,
    max_products: usize,
    monitor: &'m mut dyn Monitor,
    t0: Instant,
}

impl<'q, 'm, A: Operator> Driver<'q, 'm, A> {
    pub fn new(qp: &'q Qp<'q, A>, st: Setup, c: &Common, monitor: &'m mut dyn Monitor) -> Self {
        let info = Info { sigma_est: st.sigma, rho: st.rho, n_a_power: st.n_power, ..Default::default() };
        Driver { qp, st, info, eps: c.eps, max_outer: c.max_outer, max_products: c.max_products, monitor, t0: Instant::now() }
    }

    pub fn space(&self) -> &'q A::Space {
        self.qp.a.space()
    }

    /// A-products since the start, the power iterations excluded.
    pub fn products(&self) -> usize {
        self.qp.a.products() - self.st.n0 - self.st.n_power
    }

    /// Whether err meets ε.
    pub fn met(&self, err: f64) -> bool {
        err <= self.eps
    }

    /// The checks before outer step k: a non-finite error is an error; so is a spent budget
    /// (outer steps or A-products).
    pub fn check(&self, k: usize, err: f64, what: &'static str) -> Result<(), QpError> {
        if !err.is_finite() {
            return Err(QpError::NotFinite { what, outer: k });
        }
        Ok(())
    }

    /// After the stop test failed at step k: ends the solve when a budget is spent.
    pub fn budget(&mut self, k: usize, err: f64) -> Result<(), QpError> {
        if k == self.max_outer || self.products() >= self.max_products {
            return Err(self.no_convergence(k, err));
        }
        Ok(())
    }

    /// The error of a solve that stops unconverged after k outer steps at error err.
    pub fn no_convergence(&mut self, k: usize, err: f64) -> QpError {
        self.info.iterations = k;
        self.info.err = err;
        self.info.n_a = self.products();
        QpError::NoConvergence { info: Box::new(std::mem::take(&mut self.info)), eps: self.eps }
    }

    /// The solution λ with gradient r and error err after k outer steps.
    pub fn finish(&mut self, k: usize, lambda: Vec<f64>, gradient: Vec<f64>, err: f64) -> QpSolution {
        self.info.iterations = k;
        self.info.err = err;
        self.info.q = q_of(self.qp, &lambda, &gradient);
        self.info.n_a = self.products();
        QpSolution { lambda, gradient, info: std::mem::take(&mut self.info) }
    }

    /// Records an outer step (its n_a and time filled in here) and shows it to the monitor.
    pub fn record(&mut self, mut step: Step) {
        step.n_a = self.products();
        step.time = self.t0.elapsed().as_secs_f64();
        self.info.inner_iterations += step.inner;
        let k = self.info.history.len();
        self.monitor.step(k, &step);
        self.info.history.push(step);
    }

    /// A Newton step's record with the sets it started from (counted over all ranks).
    pub fn newton(&self, kind: StepKind, err: f64, tol: f64, q: f64, sets: &ActiveSets, inner: usize) -> Step {
        let sp = self.space();
        let (normal_active, stick, slip) = (sp.count(sets.normal_active), sp.count(sets.stick), sp.count(sets.slip));
        Step { err, tol, q, normal_active, stick, slip, inner, n_a: 0, kind, time: 0.0 }
    }

    /// ‖r̃_ρ(λ)‖/‖b‖, with r̃ written to `rt`.
    pub fn err(&self, lambda: &[f64], r: &[f64], rt: &mut [f64]) -> f64 {
        err_of(self.qp.a.space(), self.qp.set, lambda, r, &self.st, rt)
    }

    /// r = A x − b.
    pub fn residual(&self, x: &[f64], r: &mut [f64]) {
        residual(self.qp, x, r)
    }

    /// q(λ) from its gradient.
    pub fn q(&self, lambda: &[f64], r: &[f64]) -> f64 {
        q_of(self.qp, lambda, r)
    }

    /// The stop test of a solver whose iterate x need not lie in Λ (SSN, TSSN), once its own
    /// ‖r̃_ρ(x)‖ ≤ ε‖b‖: confirm at P_Λ(x) with a fresh product (with Coulomb coefficients `mu`:
    /// on Λ(x), then tested on Λ(P(x))). Returns the solution when it holds there; otherwise x,
    /// r become P_Λ(x) and its gradient (the solver goes on from there) and the error there is
    /// returned. `z`, `rz` are workspace, r̃ goes to `rt`.
    #[allow(clippy::too_many_arguments)]
    pub fn confirm_projected(
        &mut self,
        k: usize,
        mu: Option<&[Coefficient]>,
        x: &mut Vec<f64>,
        r: &mut Vec<f64>,
        z: &mut Vec<f64>,
        rz: &mut Vec<f64>,
        rt: &mut [f64],
    ) -> Result<QpSolution, f64> {
        cut(self.qp.set, mu, x).project(x, z);
        self.residual(z, rz);
        let ez = err_of(self.space(), &cut(self.qp.set, mu, z), z, rz, &self.st, rt);
        if self.met(ez) {
            return Ok(self.finish(k, std::mem::take(z), std::mem::take(rz), ez));
        }
        std::mem::swap(x, z);
        std::mem::swap(r, rz);
        Err(ez)
    }
}

/// r = A x − b.
pub(crate) fn residual<A: Operator>(qp: &Qp<'_, A>, x: &[f64], r: &mut [f64]) {
    qp.a.apply(x, r);
    r.iter_mut().zip(qp.b).for_each(|(ri, bi)| *ri -= bi);
}

/// q(λ) = ½λᵀAλ − λᵀb = ½λᵀ(r − b) with r = Aλ − b.
pub(crate) fn q_of<A: Operator>(qp: &Qp<'_, A>, lambda: &[f64], r: &[f64]) -> f64 {
    let rb: Vec<f64> = r.iter().zip(qp.b).map(|(x, y)| x - y).collect();
    0.5 * qp.a.space().dot(lambda, &rb)
}

/// ‖r̃_ρ(λ)‖/‖b‖, with r̃ written to `rt`.
pub(crate) fn err_of<S: Space>(sp: &S, set: &Lambda, lambda: &[f64], r: &[f64], s: &Setup, rt: &mut [f64]) -> f64 {
    set.reduced_gradient(lambda, r, s.rho, rt);
    sp.norm(rt) / s.bnorm
}

/// ad = A d and the curvature dᵀAd, which must be positive (else a breakdown or NaN error).
pub(crate) fn curvature<A: Operator>(a: &A, d: &[f64], ad: &mut [f64], outer: usize) -> Result<f64, QpError> {
    a.apply(d, ad);
    let dad = a.space().dot(d, ad);
    positive_curvature(dad, "the curvature dᵀAd", outer)
}

/// dᵀMd checked: positive and finite, else a breakdown or NaN error.
pub(crate) fn positive_curvature(dmd: f64, what: &'static str, outer: usize) -> Result<f64, QpError> {
    if dmd > 0.0 && dmd.is_finite() {
        Ok(dmd)
    } else if !dmd.is_finite() {
        Err(QpError::NotFinite { what, outer })
    } else {
        Err(QpError::Breakdown { outer, p_ap: dmd })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qp::{ProductCounter, Replicated};

    /// diag(1, 2, …, n) in a rotated basis would do; a diagonal operator is enough for Lanczos.
    struct Diagonal(Vec<f64>, ProductCounter);

    impl Operator for Diagonal {
        type Space = Replicated;
        fn space(&self) -> &Replicated {
            &Replicated
        }
        fn dim(&self) -> usize {
            self.0.len()
        }
        fn apply(&self, x: &[f64], y: &mut [f64]) {
            self.1.tick();
            for ((yi, xi), d) in y.iter_mut().zip(x).zip(&self.0) {
                *yi = d * xi;
            }
        }
        fn products(&self) -> usize {
            self.1.get()
        }
    }

    #[test]
    fn lanczos_finds_sigma_max_from_below_and_faster_than_the_power_method() {
        // eigenvalues 1…200, σ₂/σ₁ = 0.995: the power method creeps, Lanczos does not
        let a = Diagonal((1..=200).map(f64::from).collect(), ProductCounter::default());
        let (l, p) = (lanczos_sigma(&a, 15), power_sigma(&a, 15));
        assert!(l <= 200.0 * (1.0 + 1e-12) && l > 0.97 * 200.0, "Lanczos {l}");
        assert!(p < l, "power {p} vs Lanczos {l}");
        assert_eq!(a.products(), 30);
        let exact = lanczos_sigma(&a, 200);
        assert!((exact - 200.0).abs() <= 1e-8 * 200.0, "{exact}");
        assert_eq!(tridiagonal_max_eigenvalue(&[2.0, 2.0], &[1.0]), 3.0);
    }
}
