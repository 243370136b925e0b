//! Plain conjugate gradients for the unconstrained dual (TFETI without contact: only the free
//! gluing and Dirichlet multipliers, so Λ = R^n and the reduced gradient is the gradient). Stops
//! on the common criterion ‖r‖ ≤ ε‖b‖, confirmed with a fresh product.

use super::{curvature, residual, Info, Params, QpError, QpSolution, Setup, Step};
use crate::dual::DualOperator;

/// Solves A λ = b from λ0 by CG; one "outer" iteration per CG step, at most
/// max(max_outer, max_inner) of them (CG steps are the inner iterations of the other solvers).
pub fn solve<A: DualOperator>(a: &A, b: &[f64], lambda0: &[f64], p: &Params) -> Result<QpSolution, QpError> {
    let n = a.dim();
    let st = Setup { n0: a.products(), n_power: 0, sigma: 0.0, rho: 0.0, bnorm: a.norm(b).max(f64::MIN_POSITIVE) };
    let mut info: Info = st.info();
    let mut x = lambda0.to_vec();
    let mut r = vec![0.0; n];
    residual(a, b, &x, &mut r);
    let mut d = r.clone();
    let mut ad = vec![0.0; n];
    let mut rr = a.dot(&r, &r);
    for k in 0..p.max_outer.max(p.max_inner) {
        let mut err = rr.sqrt() / st.bnorm;
        if !err.is_finite() {
            return Err(QpError::NotFinite { what: "the CG residual", outer: k });
        }
        if err <= p.eps {
            residual(a, b, &x, &mut r);
            err = a.norm(&r) / st.bnorm;
            if err <= p.eps {
                info.iterations = k;
                info.inner_iterations = k;
                info.n_a = st.products(a);
                info.err = err;
                let rb: Vec<f64> = r.iter().zip(b).map(|(ri, bi)| ri - bi).collect();
                info.q = 0.5 * a.dot(&x, &rb);
                return Ok(QpSolution { lambda: x, gradient: r, info });
            }
            d.copy_from_slice(&r);
            rr = a.dot(&r, &r);
        }
        let dad = curvature(a, &d, &mut ad, k)?;
        let alpha = rr / dad;
        x.iter_mut().zip(&d).for_each(|(xi, di)| *xi -= alpha * di);
        r.iter_mut().zip(&ad).for_each(|(ri, adi)| *ri -= alpha * adi);
        let rr_new = a.dot(&r, &r);
        let beta = rr_new / rr;
        rr = rr_new;
        d.iter_mut().zip(&r).for_each(|(di, ri)| *di = ri + beta * *di);
        info.history.push(Step { err: rr.sqrt() / st.bnorm, tol: 0.0, q: 0.0, normal_active: 0, stick: 0, slip: 0, inner: 1, n_a: st.products(a), kind: 'c' });
    }
    info.iterations = info.history.len();
    info.n_a = st.products(a);
    info.err = rr.sqrt() / st.bnorm;
    Err(QpError::NoConvergence { info: Box::new(info), eps: p.eps })
}
