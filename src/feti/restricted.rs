//! Bodies held by contact alone solved by TSSN itself, without SMALSE-M's outer loop
//! (`decomposition.restricted`): the unknown is λ, min ½λᵀFλ − λᵀd̃ over Gλ = e, λ_I ∈ Λ, and
//! each Newton step keeps Gλ = e exactly on its subspace W (its free components and sliding
//! directions, the E rows always free). The QP operator ([`Held`]) is F with the gradient of the
//! Lagrangian, r = Fλ − d̃ − Gᵀα with α = (GΠGᵀ)⁻¹GΠ(Fλ − d̃) the rigid amplitudes W's rows fix
//! (the oblique projector P̃_W = I − Gᵀ(GΠGᵀ)⁻¹GΠ on Fλ − d̃); its coarse space is G restricted
//! to W, factorized once per Newton step, which also closes the step's start onto Gλ = e by the
//! least-norm correction on W. Before the first step W is the pairs the start presses (else
//! every row: the gradient P(Fλ − d̃), P the orthogonal projector). Coulomb: TSSN's lagged bounds.

use std::cell::RefCell;
use std::rc::Rc;

use super::distribution::{Clock, Distribution};
use super::dual::TfetiDual;
use super::smalse::Penalized;
use crate::comm::Comm;
use crate::linalg::cholesky::Cholesky;
use crate::qp::params::{MethodParams, Tssn};
use crate::qp::{self, CoarseProjector, Lambda, Monitor, Operator, Params, ProductCounter, Qp, QpError, QpSolution, Space, SIGMA_SAFETY};

/// The smallest residual, relative to σ‖λ_e‖, that double precision reaches on the dual
/// gradient: the stop test's scale is kept at least this over ε (as SMALSE-M's).
const REACHABLE: f64 = 1e3 * f64::EPSILON;

/// The forcing exponent θ where the scene's method is not TSSN.
const FORCING: f64 = 2.0;

/// The forcing exponent for Coulomb (lagged bounds converge linearly once the sets settle: θ = 2
/// over-solved the tied stack's steps, 240 products against θ = 1.5's 54;
/// run/results/floating_restricted2.txt).
const FORCING_COULOMB: f64 = 1.5;

/// The Krylov directions kept across Newton steps where the scene's method is not TSSN.
const RECYCLE: usize = 20;

/// The inner CG's floor, relative to ε·‖b‖, where the scene's method is not TSSN: the last
/// Newton step stops near ε instead of a decade below it (traction sphere 84 → 77 products).
const INNER_FLOOR: f64 = 0.5;

/// W's GΠGᵀ is taken as singular where its inverse exceeds GGᵀ's by this factor.
const SINGULAR: f64 = 1e12;

/// One Newton step's W: GΠGᵀ factorized and Π on this rank's owned rows.
struct Step {
    chol: Rc<Cholesky>,
    free: Vec<bool>,
    slides: Vec<(usize, [f64; 2])>,
}

/// F with the Lagrangian's gradient on the current Newton step's W (the QP operator and its
/// coarse space).
pub struct Held<'a, 'c, C: Comm> {
    dual: &'a TfetiDual<'c, C>,
    /// d̃ − Fλ_e on the owned rows, the QP's b.
    d: Vec<f64>,
    /// λ_e = Gᵀ(GGᵀ)⁻¹e on the owned rows.
    lambda_e: Vec<f64>,
    current: RefCell<Option<Rc<Step>>>,
    counter: ProductCounter,
    /// The singularity probe v and ‖(GGᵀ)⁻¹v‖ ([`Held::singular`]), made once.
    probe: (Vec<f64>, f64),
}

impl<'a, 'c, C: Comm> Held<'a, 'c, C> {
    /// The operator of `dual` (built with the orthogonal projector, a body held by contact
    /// alone) and its b = d̃ − Fλ_e (the dual's, no product).
    pub fn new(dual: &'a TfetiDual<'c, C>) -> Self {
        let lambda_e = dual.dist.owned_part(&dual.lambda_hat);
        let d = dual.d_hat.clone();
        let n = dual.coarse.dim();
        let v: Vec<f64> = (0..n).map(|i| 1.0 + ((i * 7919) % 13) as f64 / 13.0).collect();
        let mut y = v.clone();
        dual.coarse.full_solve(&dual.dist, &mut y);
        let probe = (v, norm(&y).max(f64::MIN_POSITIVE));
        Held { dual, d, lambda_e, current: RefCell::new(None), counter: ProductCounter::default(), probe }
    }

    /// Whether W's GΠGᵀ is singular to round-off (its rows hold a rigid motion by nothing, e.g.
    /// Coulomb pairs whose tangents are all fixed: the factorization then succeeds on round-off
    /// pivots): ‖(GΠGᵀ)⁻¹v‖ over ‖(GGᵀ)⁻¹v‖ beyond [`SINGULAR`] for a fixed v.
    fn singular(&self, chol: &Cholesky) -> bool {
        let mut x = self.probe.0.clone();
        chol.solve_in_place(&mut x);
        !(norm(&x) / self.probe.1 <= SINGULAR)
    }

    fn dist(&self) -> &Distribution<'c, C> {
        &self.dual.dist
    }

    /// y ← P̃_W y = y − Gᵀ(GΠGᵀ)⁻¹GΠy (P y before the first step).
    fn lagrangian(&self, y: &mut [f64]) {
        let coarse = &self.dual.coarse;
        match self.current.borrow().as_ref() {
            None => coarse.project_orthogonal(self.dist(), y),
            Some(w) => {
                let nc = self.dual.layout.contact_dim();
                let mut pw: Vec<f64> = y.iter().enumerate().map(|(i, &v)| if i >= nc || w.free[i] { v } else { 0.0 }).collect();
                for &(k, t) in &w.slides {
                    let s = t[0] * y[k] + t[1] * y[k + 1];
                    (pw[k], pw[k + 1]) = (t[0] * s, t[1] * s);
                }
                let alpha = coarse.alpha_restricted(self.dist(), &w.chol, &pw);
                let r = coarse.residual_after(self.dist(), &alpha, y);
                y.copy_from_slice(&r);
            }
        }
    }
}

impl<'c, C: Comm> Operator for Held<'_, 'c, C> {
    type Space = Distribution<'c, C>;
    fn space(&self) -> &Distribution<'c, C> {
        self.dual.space()
    }

    fn dim(&self) -> usize {
        self.dual.dim()
    }

    /// P̃_W(Fx − d̃) + b with Fx − d̃ = F(x − λ_e) − b: the residual y − b is then the
    /// Lagrangian's gradient (affine in x; the solver's products of directions go through
    /// `apply_kernel`).
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.counter.tick();
        let dx: Vec<f64> = x.iter().zip(&self.lambda_e).map(|(a, b)| a - b).collect();
        self.dual.apply_f(&dx, y);
        y.iter_mut().zip(&self.d).for_each(|(a, b)| *a -= b);
        self.lagrangian(y);
        y.iter_mut().zip(&self.d).for_each(|(a, b)| *a += b);
    }

    fn products(&self) -> usize {
        self.counter.get()
    }

    /// F x.
    fn apply_kernel(&self, x: &[f64], y: &mut [f64]) {
        self.counter.tick();
        self.dual.apply_f(x, y);
    }

    /// y ← P̃_W y.
    fn finish_kernel(&self, y: &mut [f64]) {
        self.lagrangian(y);
    }
}

impl<C: Comm> qp::Coarse for Held<'_, '_, C> {
    /// GΠGᵀ of W, which becomes the operator's W too.
    fn restrict<'a>(&'a self, free: &[bool], slides: &[(usize, [f64; 2])]) -> Option<Box<dyn CoarseProjector + 'a>> {
        let (free_all, slides_all) = self.dual.global_pi(free, slides);
        let clock = &self.dist().clock;
        let chol =
            Clock::time(&clock.restricted, || Clock::time(&clock.restricted_factor, || self.dual.coarse.restricted(self.dist(), &free_all, &slides_all)));
        // every rank must agree: a rank without the factor makes all of them fail
        let mut bad = [f64::from(u8::from(chol.is_none()))];
        self.dist().comm().max_f64(&mut bad);
        if bad[0] > 0.0 {
            return None;
        }
        let chol = Rc::new(chol.expect("checked"));
        if self.singular(&chol) {
            return None;
        }
        let nc = self.dual.layout.contact_dim();
        *self.current.borrow_mut() = Some(Rc::new(Step { chol: chol.clone(), free: free[..nc].to_vec(), slides: slides.to_vec() }));
        Some(Box::new(Projector { held: self, chol }))
    }

    fn keeps_equality(&self) -> bool {
        true
    }
}

/// The coarse part of P_W, and the start's correction onto Gλ = e.
struct Projector<'a, 'b, 'c, C: Comm> {
    held: &'a Held<'b, 'c, C>,
    chol: Rc<Cholesky>,
}

impl<C: Comm> CoarseProjector for Projector<'_, '_, '_, C> {
    fn apply(&self, x: &mut [f64]) {
        self.held.dual.coarse.project_restricted(self.held.dist(), &self.chol, x);
    }

    fn close(&self, x: &[f64]) -> Option<Vec<f64>> {
        let (h, coarse) = (self.held, &self.held.dual.coarse);
        let dx: Vec<f64> = x.iter().zip(&h.lambda_e).map(|(a, b)| a - b).collect();
        let a = coarse.alpha_restricted(h.dist(), &self.chol, &dx);
        Some(coarse.residual_after(h.dist(), &a, &vec![0.0; x.len()]))
    }
}

/// Solves the TFETI dual of a body held by contact alone by TSSN on [`Held`] from λ = `x0`
/// (TSSN's settings from `p` when its method is TSSN, else θ = 2 (1.5 for Coulomb), 20 recycled
/// directions and the inner floor 0.5; Coulomb coefficients `mu`: TSSN's lagged bounds). The stop test ‖r̃_ρ‖ ≤ ε·s has SMALSE-M's scale s =
/// max(‖P(d̃ − Fλ_e)‖, 1000 ε_mach/ε·σ‖λ_e‖), σ = σ_max(PFP) (`p.common.sigma` when given).
/// [`QpError::SingularCoarse`] when a Newton step's rows do not fix the rigid motions (also to round-off).
pub fn solve<C: Comm>(
    dual: &TfetiDual<'_, C>,
    set: &Lambda,
    mu: Option<&[crate::qp::cone::Coefficient]>,
    x0: &[f64],
    p: &Params,
    monitor: &mut dyn Monitor,
) -> Result<QpSolution, QpError> {
    let sp = dual.space();
    let held = Held::new(dual);
    let pfp = Penalized::new(dual, 0.0);
    let n_power = if p.common.sigma.is_some() { 0 } else { p.common.power_iterations };
    let sigma = p.common.sigma.unwrap_or_else(|| qp::estimate_sigma(&pfp, &p.common));
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(QpError::NotFinite { what: "the σ_max estimate", outer: 0 });
    }
    let mut pd = dual.d_hat.clone();
    dual.coarse.project_orthogonal(&dual.dist, &mut pd);
    let eps = p.common.eps;
    let scale = sp.norm(&pd).max(REACHABLE / eps * sigma * sp.norm(&held.lambda_e)).max(f64::MIN_POSITIVE);
    let dnorm = sp.norm(&held.d).max(f64::MIN_POSITIVE);
    let mut inner = p.clone();
    inner.common.eps = eps * scale / dnorm;
    inner.common.sigma = Some(SIGMA_SAFETY * sigma);
    inner.common.power_iterations = 0;
    // TSSN's own settings where the scene chose it, else superlinear forcing and recycled
    // Krylov directions (the traction sphere of run/bench: 128 products with TSSN's defaults,
    // 89 with these; run/results/floating_restricted.txt)
    let tssn = match &p.method {
        MethodParams::Tssn(t) => t.clone(),
        _ => Tssn { forcing: if mu.is_some() { FORCING_COULOMB } else { FORCING }, recycle: RECYCLE, inner_floor: INNER_FLOOR, ..Tssn::default() },
    };
    // the first step's W from the pressed pairs (traction sphere 89 → 84 products, 10 → 8 Newton
    // steps; run/results/floating_restricted2.txt)
    first_w(&held, x0);
    let qp = Qp::new(&held, &held.d, set).with_coarse(Some(&held as &dyn qp::Coarse));
    let mut sol = qp::tssn::run(&qp, mu, x0, &inner.common, &tssn, monitor)?;
    // the σ estimate's products are counted apart
    sol.info.n_a_power = n_power;
    sol.info.sigma_est = sigma;
    sol.info.err *= dnorm / scale;
    Ok(sol)
}

/// The first Newton step's W: the pairs the start presses (λν > 0: the touching start's, or
/// the last load step's solution's) with the E rows, where they hold the body; else every row.
fn first_w<C: Comm>(held: &Held<'_, '_, C>, x0: &[f64]) {
    let l = held.dual.layout;
    let mut free = vec![true; x0.len()];
    for i in 0..l.m {
        let on = x0[l.normal(i)] > 0.0;
        free[l.normal(i)] = on;
        if l.friction {
            free[l.tangent(i, 0)] = on;
            free[l.tangent(i, 1)] = on;
        }
    }
    // a singular GΠGᵀ leaves W at every row
    let _ = qp::Coarse::restrict(held, &free, &[]);
}

/// The Euclidean norm of a replicated coarse vector.
fn norm(a: &[f64]) -> f64 {
    a.iter().map(|t| t * t).sum::<f64>().sqrt()
}
