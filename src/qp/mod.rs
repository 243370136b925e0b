//! Quadratic programs with separable convex constraints: the constraint sets and the solvers.
//!
//! The dual contact problem (DESIGN §1, §3) is `min q(λ) = ½ λᵀAλ − λᵀb` over a product
//! `Λ = Π_i Λ_i` of small closed convex blocks, one per contact pair: a half-line for the
//! normal multiplier `λν,ᵢ ≥ 0` and a disc (isotropic Tresca) or an ellipse (orthotropic
//! Tresca) for the tangential pair `λ̄τ,ᵢ`. [`sets`] holds these blocks behind one trait,
//! [`lambda`] their product Λ. The solvers see A only through [`DualOperator`]: the
//! symmetrized semi-smooth Newton family ([`gimssn`]: GIMSSN, IMSSN, MSSN), the unsymmetrized
//! SSN with BiCGSTAB ([`ssn`]), its symmetric form TSSN with CG ([`tssn`]) and MPGP ([`mpgp`]). All share [`Params`], report [`Info`], fail
//! with [`QpError`], stop on the same criterion `‖r̃_ρ(λ)‖ ≤ ε‖b‖` and never print. [`kkt`]
//! measures how well a result satisfies the optimality conditions.

pub mod cg;
pub mod gimssn;
pub mod kkt;
pub mod lambda;
pub mod mpgp;
pub mod sets;
pub mod ssn;
pub mod tssn;

use serde::{Deserialize, Serialize};

use crate::dual::DualOperator;
use lambda::Lambda;

/// The dual solvers.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Monotone, feasible (CGMfeas), globally convergent symmetrized SSN.
    Gimssn,
    /// Inexact symmetrized SSN: CG to an adaptive tolerance, iterates may leave Λ.
    Imssn,
    /// Symmetrized SSN with exact inner solves.
    Mssn,
    /// Unsymmetrized SSN (full slant derivative), inner systems by BiCGSTAB.
    SsnBicgstab,
    /// Modified proportioning with gradient projections (Dostál–Kozubek).
    Mpgp,
    /// Tangent-symmetric SSN: the exact SSN step as an SPD system, solved by CG (DESIGN §3b).
    Tssn,
}

impl Method {
    pub const ALL: [Method; 6] = [Method::Gimssn, Method::Imssn, Method::Mssn, Method::SsnBicgstab, Method::Mpgp, Method::Tssn];

    /// The scene's (and the command line's) name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Gimssn => "gimssn",
            Method::Imssn => "imssn",
            Method::Mssn => "mssn",
            Method::SsnBicgstab => "ssn-bicgstab",
            Method::Mpgp => "mpgp",
            Method::Tssn => "tssn",
        }
    }

    pub fn from_name(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// What an inner tolerance is relative to.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum CgStop {
    /// ‖g_F‖ ≤ tol·‖b‖ (the faster choice, DESIGN §3a).
    Rhs,
    /// ‖g_F‖ ≤ tol·‖g_F at the start of the inner solve‖ (the paper's).
    InitialGradient,
}

/// Settings shared by all solvers (each reads the ones it needs).
#[derive(Clone, Debug)]
pub struct Params {
    pub method: Method,
    /// ε: stop when ‖r̃_ρ(λ)‖ ≤ ε‖b‖.
    pub eps: f64,
    /// ρ = rho_factor / (1.1 σ_est) (also MPGP's fixed step ᾱ); below 2 for the monotone theory.
    pub rho_factor: f64,
    /// Adaptive inner tolerance `tol_{k+1} = min(rtol·err_k/err_0, cfact·tol_k)`.
    pub rtol: f64,
    pub cfact: f64,
    /// TSSN's forcing exponent θ: inner tolerance `rtol·(err_k/err_0)^θ` (θ > 1: superlinear).
    pub forcing: f64,
    /// A fixed relative inner tolerance instead of the adaptive one (SSN-BiCGSTAB; the paper's
    /// baseline needs about 1e-6).
    pub inner_tol: Option<f64>,
    pub cg_stop: CgStop,
    /// No inner solve is asked for less than `inner_floor·ε·‖b‖` (0: no floor, as in the
    /// paper; the inner solves then go far below what the outer test can see).
    pub inner_floor: f64,
    /// Outer iterations at most (MPGP: steps).
    pub max_outer: usize,
    /// Inner iterations per outer step at most.
    pub max_inner: usize,
    /// A-products (power iterations excluded) at most: a budget checked between outer steps.
    pub max_products: usize,
    pub power_iterations: usize,
    /// σ_max(A) when already known (no power iterations then): a caller solving a sequence of
    /// QPs with the same A (SMALSE-M's outer loop) measures it once.
    pub sigma: Option<f64>,
    /// MPGP's proportioning constant Γ.
    pub gamma: f64,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            method: Method::SsnBicgstab,
            eps: 1e-6,
            rho_factor: 1.9,
            rtol: 0.5,
            cfact: 0.9,
            forcing: 1.0,
            inner_tol: None,
            cg_stop: CgStop::Rhs,
            inner_floor: 0.1,
            max_outer: 1000,
            max_inner: 10_000,
            max_products: usize::MAX,
            power_iterations: 30,
            sigma: None,
            gamma: 1.0,
        }
    }
}

/// One outer iteration (MPGP: one step).
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// ‖r̃_ρ‖ / ‖b‖ after the step.
    pub err: f64,
    /// Inner tolerance used (0 where there is none).
    pub tol: f64,
    pub q: f64,
    /// Active normals (pairs in contact) at the start of the step.
    pub normal_active: usize,
    pub stick: usize,
    pub slip: usize,
    /// Inner (CG / BiCGSTAB) iterations of this step.
    pub inner: usize,
    /// A-products so far (without the power iterations).
    pub n_a: usize,
    /// What kind of step (MPGP: 'c' CG, 'e' expansion, 'p' proportioning; Newton methods: 'n').
    pub kind: char,
}

/// Counters of a solve.
#[derive(Clone, Debug, Default)]
pub struct Info {
    pub iterations: usize,
    /// A-products, the power iterations excluded.
    pub n_a: usize,
    /// A-products of the power iterations for σ_max.
    pub n_a_power: usize,
    pub inner_iterations: usize,
    /// Applications of the preconditioner M (TSSN with a preconditioner; 0 otherwise).
    pub preconditioner_applications: usize,
    pub sigma_est: f64,
    pub rho: f64,
    /// Final ‖r̃_ρ(λ)‖/‖b‖ from a fresh product.
    pub err: f64,
    pub q: f64,
    pub history: Vec<Step>,
}

/// Why a solve failed.
#[derive(Clone, Debug, thiserror::Error)]
pub enum QpError {
    #[error("no convergence in {} outer iterations, {} A-products (‖r̃‖/‖b‖ = {:.3e}, ε = {eps:.1e})", info.iterations, info.n_a, info.err)]
    NoConvergence { info: Box<Info>, eps: f64 },
    #[error("breakdown: dᵀAd = {p_ap:.3e} ≤ 0 at outer iteration {outer} (A not positive definite on the free set)")]
    Breakdown { outer: usize, p_ap: f64 },
    #[error("BiCGSTAB breakdown ({what}) at outer iteration {outer} before any progress")]
    BicgstabBreakdown { outer: usize, what: &'static str },
    #[error("non-finite value (NaN or infinity) in {what} at outer iteration {outer}")]
    NotFinite { what: &'static str, outer: usize },
}

/// The result of a QP solve.
#[derive(Clone, Debug)]
pub struct QpSolution {
    /// λ ∈ Λ.
    pub lambda: Vec<f64>,
    /// r(λ) = Aλ − b from a fresh product (= −(Bu − c)).
    pub gradient: Vec<f64>,
    pub info: Info,
}

/// Solves min ½λᵀAλ − λᵀb over Λ from λ0 (projected onto Λ first) with `p.method`.
pub fn solve<A: DualOperator>(a: &A, b: &[f64], set: &Lambda, lambda0: &[f64], p: &Params) -> Result<QpSolution, QpError> {
    match p.method {
        Method::Gimssn | Method::Imssn | Method::Mssn => gimssn::solve(a, b, set, lambda0, p),
        Method::SsnBicgstab => ssn::solve(a, b, set, lambda0, p),
        Method::Mpgp => mpgp::solve(a, b, set, lambda0, p),
        Method::Tssn => tssn::solve(a, b, set, lambda0, p),
    }
}

/// σ_max(A) by `iterations` power iterations from a fixed start vector.
pub fn power_sigma<A: DualOperator>(a: &A, iterations: usize) -> f64 {
    let n = a.dim();
    // the same vector for every distribution of the components
    let mut x: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * ((a.global_index(i) * 7919) % 13) as f64).collect();
    let nx = a.norm(&x);
    x.iter_mut().for_each(|v| *v /= nx);
    let mut y = vec![0.0; n];
    let mut sigma = 0.0;
    for _ in 0..iterations {
        a.apply(&x, &mut y);
        sigma = a.norm(&y);
        if sigma == 0.0 || !sigma.is_finite() {
            break;
        }
        for (xi, yi) in x.iter_mut().zip(&y) {
            *xi = yi / sigma;
        }
    }
    sigma
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
    pub fn new<A: DualOperator>(a: &A, b: &[f64], p: &Params) -> Result<Setup, QpError> {
        let n0 = a.products();
        let sigma = p.sigma.unwrap_or_else(|| power_sigma(a, p.power_iterations));
        let n_power = a.products() - n0;
        if !(sigma.is_finite() && sigma > 0.0) {
            return Err(QpError::NotFinite { what: "the σ_max estimate", outer: 0 });
        }
        let rho = p.rho_factor / (1.1 * sigma);
        let bnorm = a.norm(b).max(f64::MIN_POSITIVE);
        Ok(Setup { n0, n_power, sigma, rho, bnorm })
    }

    /// A-products since the start, the power iterations excluded.
    pub fn products<A: DualOperator>(&self, a: &A) -> usize {
        a.products() - self.n0 - self.n_power
    }

    pub fn info(&self) -> Info {
        Info { sigma_est: self.sigma, rho: self.rho, n_a_power: self.n_power, ..Default::default() }
    }
}

/// r = A x − b.
pub(crate) fn residual<A: DualOperator>(a: &A, b: &[f64], x: &[f64], r: &mut [f64]) {
    a.apply(x, r);
    r.iter_mut().zip(b).for_each(|(ri, bi)| *ri -= bi);
}

/// ad = A d and the curvature dᵀAd, which must be positive (else a breakdown or NaN error).
pub(crate) fn curvature<A: DualOperator>(a: &A, d: &[f64], ad: &mut [f64], outer: usize) -> Result<f64, QpError> {
    a.apply(d, ad);
    let dad = a.dot(d, ad);
    if dad > 0.0 && dad.is_finite() {
        Ok(dad)
    } else if !dad.is_finite() {
        Err(QpError::NotFinite { what: "the curvature dᵀAd", outer })
    } else {
        Err(QpError::Breakdown { outer, p_ap: dad })
    }
}

impl Step {
    /// A Newton step's record with the sets it started from (counted over all ranks).
    pub(crate) fn newton<A: DualOperator>(a: &A, err: f64, tol: f64, q: f64, sets: &lambda::ActiveSets, inner: usize, n_a: usize) -> Step {
        let (normal_active, stick, slip) = (a.count(sets.normal_active), a.count(sets.stick), a.count(sets.slip));
        Step { err, tol, q, normal_active, stick, slip, inner, n_a, kind: 'n' }
    }
}

/// q(λ) = ½λᵀAλ − λᵀb = ½λᵀ(r − b) with r = Aλ − b.
pub(crate) fn q_of<A: DualOperator>(a: &A, lambda: &[f64], r: &[f64], b: &[f64]) -> f64 {
    let rb: Vec<f64> = r.iter().zip(b).map(|(x, y)| x - y).collect();
    0.5 * a.dot(lambda, &rb)
}

/// The stop test of a solver whose iterate x need not lie in Λ (SSN, TSSN), once its own
/// ‖r̃_ρ(x)‖ ≤ ε‖b‖: confirm at P_Λ(x) with a fresh product. Returns the solution when it holds
/// there; otherwise x, r become P_Λ(x) and its gradient (the solver goes on from there) and the
/// error there is returned. `z`, `rz` are workspace.
#[allow(clippy::too_many_arguments)]
pub(crate) fn confirm_projected<A: DualOperator>(
    a: &A,
    b: &[f64],
    set: &Lambda,
    st: &Setup,
    eps: f64,
    k: usize,
    x: &mut Vec<f64>,
    r: &mut Vec<f64>,
    z: &mut Vec<f64>,
    rz: &mut Vec<f64>,
    rt: &mut [f64],
    info: &mut Info,
) -> Result<QpSolution, f64> {
    set.project(x, z);
    residual(a, b, z, rz);
    let ez = err_of(a, set, z, rz, st, rt);
    if ez <= eps {
        info.iterations = k;
        info.err = ez;
        info.q = q_of(a, z, rz, b);
        info.n_a = st.products(a);
        return Ok(QpSolution { lambda: std::mem::take(z), gradient: std::mem::take(rz), info: std::mem::take(info) });
    }
    std::mem::swap(x, z);
    std::mem::swap(r, rz);
    Err(ez)
}

/// ‖r̃_ρ(λ)‖/‖b‖, with r̃ written to `rt`.
pub(crate) fn err_of<A: DualOperator>(a: &A, set: &Lambda, lambda: &[f64], r: &[f64], s: &Setup, rt: &mut [f64]) -> f64 {
    set.reduced_gradient(lambda, r, s.rho, rt);
    a.norm(rt) / s.bnorm
}
