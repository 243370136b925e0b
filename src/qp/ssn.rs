//! SSN-BiCGSTAB — the paper's baseline: the semi-smooth Newton method on the unsymmetrized
//! equation `F(λ) = λ − P_Λ(λ − ρ r(λ)) = 0`, r = Aλ − b (DESIGN §3).
//!
//! Each outer step solves the Newton system `J δ = −F(λᵏ)` with the full slant derivative
//! `J = I − D(I − ρA)`, D = ∂P_Λ(λᵏ − ρ rᵏ) block-diagonal (0/1 on the normal components; on a
//! sliding pair the ψ° of its disc or ellipse, I on a sticking one), by BiCGSTAB (two
//! A-products per iteration), and sets λ^{k+1} = λᵏ + δ. The inner solve stops at
//! `‖Jδ + F‖ ≤ tol·s` with s = ρ‖b‖ (`CgStop::Rhs`) or ‖F(λᵏ)‖ (`CgStop::InitialGradient`),
//! tol adaptive as in IMSSN (`min(rtol·err_k/err_0, cfact·tol_k)`) or fixed (`Params::inner_tol`:
//! the paper's counts need near-exact solves, about 1e-6), and never below 0.1·ε·ρ‖b‖.
//! The products A p and A s that BiCGSTAB makes anyway give Aδ, so r^{k+1} = rᵏ + Aδ costs
//! no extra product. Iterates need not lie in Λ; the stop `‖r̃_ρ‖ ≤ ε‖b‖` is confirmed at
//! P_Λ(λ) with a fresh product, and P_Λ(λ) is the result. No globalization: the method is
//! locally superlinear, and a run that does not converge ends in `QpError::NoConvergence`.

use super::lambda::Lambda;
use super::{confirm_projected, err_of, q_of, residual, CgStop, Info, Params, QpError, QpSolution, Setup, Step};
use crate::dual::DualOperator;

/// Solves min ½λᵀAλ − λᵀb over Λ from λ0 by SSN with BiCGSTAB inner solves.
pub fn solve<A: DualOperator>(a: &A, b: &[f64], set: &Lambda, lambda0: &[f64], p: &Params) -> Result<QpSolution, QpError> {
    let n = a.dim();
    let st = Setup::new(a, b, p)?;
    let (rho, bnorm) = (st.rho, st.bnorm);
    let mut lambda = vec![0.0; n];
    set.project(lambda0, &mut lambda);
    let mut r = vec![0.0; n];
    residual(a, b, &lambda, &mut r);
    let mut rt = vec![0.0; n];
    let mut err = err_of(a, set, &lambda, &r, &st, &mut rt);
    let err0 = err.max(f64::MIN_POSITIVE);
    let mut tol = p.rtol / p.cfact;
    let mut info: Info = st.info();
    let (mut y, mut z, mut rz) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut work = Bicgstab::new(n);
    for k in 0.. {
        if !err.is_finite() {
            return Err(QpError::NotFinite { what: "the reduced gradient", outer: k });
        }
        if err <= p.eps {
            match confirm_projected(a, b, set, &st, p.eps, k, &mut lambda, &mut r, &mut z, &mut rz, &mut rt, &mut info) {
                Ok(sol) => return Ok(sol),
                Err(e) => err = e,
            }
        }
        if k == p.max_outer || st.products(a) >= p.max_products {
            info.iterations = k;
            info.err = err;
            info.n_a = st.products(a);
            return Err(QpError::NoConvergence { info: Box::new(info), eps: p.eps });
        }
        let sets = set.active_sets(&lambda, &r, rho);
        for i in 0..n {
            y[i] = lambda[i] - rho * r[i];
        }
        let d = set.slant(&y);
        // −F(λ) = −ρ r̃_ρ(λ); rt holds r̃ at the current λ (from the last err_of)
        let rhs: Vec<f64> = rt.iter().map(|v| -rho * v).collect();
        tol = match p.inner_tol {
            Some(t) => t,
            None => (p.rtol * err / err0).min(p.cfact * tol),
        };
        let scale = match p.cg_stop {
            CgStop::Rhs => rho * bnorm,
            CgStop::InitialGradient => a.norm(&rhs),
        };
        // never ask less than a reduction by rtol of the current residual: from a warm start
        // (err_0 small) tol·scale could exceed ‖rhs‖ and the step would be zero
        let threshold = (tol * scale).min(p.rtol * a.norm(&rhs)).max(p.inner_floor * p.eps * rho * bnorm);
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
        let inner = work.solve(a, &rhs, threshold, p.max_inner, jacobian, k)?;
        for i in 0..n {
            lambda[i] += work.x[i];
            r[i] += work.ax[i];
        }
        err = err_of(a, set, &lambda, &r, &st, &mut rt);
        info.inner_iterations += inner;
        info.history.push(Step::newton(a, err, tol, q_of(a, &lambda, &r, b), &sets, inner, st.products(a)));
    }
    unreachable!("the outer loop returns")
}

/// BiCGSTAB workspace: the solution x of J x = rhs and A x, accumulated from the products.
struct Bicgstab {
    x: Vec<f64>,
    ax: Vec<f64>,
    res: Vec<f64>,
    rhat: Vec<f64>,
    p: Vec<f64>,
    v: Vec<f64>,
    ap: Vec<f64>,
    s: Vec<f64>,
    t: Vec<f64>,
    as_: Vec<f64>,
}

impl Bicgstab {
    fn new(n: usize) -> Self {
        let z = || vec![0.0; n];
        Bicgstab { x: z(), ax: z(), res: z(), rhat: z(), p: z(), v: z(), ap: z(), s: z(), t: z(), as_: z() }
    }

    /// Solves J x = rhs from x = 0 until ‖rhs − Jx‖ ≤ threshold; returns the iterations.
    /// A breakdown after some progress ends the solve with the last iterate (Newton goes on
    /// from an inexact step); one before any progress is an error.
    fn solve<A: DualOperator>(
        &mut self,
        a: &A,
        rhs: &[f64],
        threshold: f64,
        max_iter: usize,
        jacobian: impl Fn(&[f64], &mut [f64], &mut [f64]),
        outer: usize,
    ) -> Result<usize, QpError> {
        let n = rhs.len();
        self.x.fill(0.0);
        self.ax.fill(0.0);
        self.res.copy_from_slice(rhs);
        self.rhat.copy_from_slice(rhs);
        self.p.fill(0.0);
        self.v.fill(0.0);
        self.ap.fill(0.0);
        let (mut rho_old, mut alpha, mut omega) = (1.0, 1.0, 1.0);
        let mut it = 0;
        let mut rnorm = a.norm(&self.res);
        let fail = |it: usize, what| if it == 0 { Err(QpError::BicgstabBreakdown { outer, what }) } else { Ok(it) };
        while rnorm > threshold && it < max_iter {
            if !rnorm.is_finite() {
                return Err(QpError::NotFinite { what: "the BiCGSTAB residual", outer });
            }
            let rho_new = a.dot(&self.rhat, &self.res);
            if rho_new == 0.0 {
                return fail(it, "r̂ᵀr = 0");
            }
            let beta = (rho_new / rho_old) * (alpha / omega);
            for i in 0..n {
                self.p[i] = self.res[i] + beta * (self.p[i] - omega * self.v[i]);
            }
            jacobian(&self.p, &mut self.v, &mut self.ap);
            let rv = a.dot(&self.rhat, &self.v);
            if rv == 0.0 || !rv.is_finite() {
                return fail(it, "r̂ᵀJp = 0");
            }
            alpha = rho_new / rv;
            for i in 0..n {
                self.s[i] = self.res[i] - alpha * self.v[i];
            }
            it += 1;
            let snorm = a.norm(&self.s);
            if snorm <= threshold {
                for i in 0..n {
                    self.x[i] += alpha * self.p[i];
                    self.ax[i] += alpha * self.ap[i];
                }
                return Ok(it);
            }
            jacobian(&self.s, &mut self.t, &mut self.as_);
            let tt = a.dot(&self.t, &self.t);
            omega = if tt > 0.0 { a.dot(&self.t, &self.s) / tt } else { 0.0 };
            for i in 0..n {
                self.x[i] += alpha * self.p[i] + omega * self.s[i];
                self.ax[i] += alpha * self.ap[i] + omega * self.as_[i];
                self.res[i] = self.s[i] - omega * self.t[i];
            }
            if omega == 0.0 {
                return Ok(it);
            }
            rnorm = a.norm(&self.res);
            rho_old = rho_new;
        }
        Ok(it)
    }
}
