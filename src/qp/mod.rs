//! Quadratic programs with separable convex constraints — the solver layer, the floor of the
//! crate: it imports nothing from the rest of the crate and knows no meshes, scenes or FETI.
//!
//! The problem ([`Qp`]) is `min q(λ) = ½ λᵀAλ − λᵀb` over a product `Λ = Π_i Λ_i` of small
//! closed convex blocks ([`sets`]; their product and the multiplier layout in [`lambda`]),
//! with A seen only through [`Operator`] (its reductions through [`Space`]), an optional
//! [`Preconditioner`] and an optional [`Coarse`] space G δ = 0 for the inner corrections
//! ([`operator`]). The solvers — the symmetrized semi-smooth Newton family
//! ([`gimssn`]: GIMSSN, IMSSN, MSSN), SSN with BiCGSTAB ([`ssn`]), TSSN ([`tssn`]), MPGP
//! ([`mpgp`]) and plain CG for Λ = Rⁿ ([`cg`]) — each read their own settings ([`params`]),
//! share one outer loop ([`driver`]: stop test `‖r̃_ρ(λ)‖ ≤ ε‖b‖`, budgets, [`Info`], the
//! [`Monitor`]) and the Krylov kernels ([`krylov`]), fail with [`QpError`] and never print.
//! [`kkt`] measures how well a result satisfies the optimality conditions.

pub(crate) mod cg;
pub mod cone;
pub(crate) mod coulomb;
pub(crate) mod driver;
pub(crate) mod gimssn;
pub mod kkt;
pub(crate) mod krylov;
pub(crate) mod lambda;
pub(crate) mod mpgp;
pub(crate) mod operator;
pub mod params;
pub mod sets;
pub(crate) mod ssn;
pub(crate) mod tssn;

pub use driver::{estimate_sigma, lanczos_sigma, power_sigma, Monitor, Silent, SIGMA_SAFETY};
pub use lambda::{Lambda, Layout};
pub use operator::{Coarse, CoarseProjector, Operator, Preconditioner, ProductCounter, Replicated, Space};
pub use params::{CgStop, Common, Method, MethodParams, Params, RhoRule, SigmaEstimate};

/// The QP: A, b, Λ and, for the solvers that take one, a preconditioner of A.
pub struct Qp<'a, A: Operator> {
    /// The operator A.
    pub a: &'a A,
    /// The right-hand side b.
    pub b: &'a [f64],
    /// The feasible set Λ.
    pub set: &'a Lambda,
    /// M ≈ A⁻¹ on a block of the components (the methods of
    /// [`Method::takes_preconditioner`] use it).
    pub preconditioner: Option<&'a dyn Preconditioner>,
    /// G δ = 0 on the inner corrections (TSSN's CG and plain CG project onto Ker G ∩ W;
    /// SSN-BiCGSTAB its preconditioner).
    pub coarse: Option<&'a dyn Coarse>,
    /// A point λ ∈ Λ with its gradient Aλ − b, known already (SMALSE-M's outer loop: the last
    /// inner solve's result, its gradient shifted by the ν update): SSN-BiCGSTAB starting from
    /// exactly this λ takes the gradient instead of a product.
    pub start: Option<(&'a [f64], &'a [f64])>,
}

impl<'a, A: Operator> Qp<'a, A> {
    /// The QP of A, b and Λ, without preconditioner or coarse space.
    pub fn new(a: &'a A, b: &'a [f64], set: &'a Lambda) -> Self {
        Qp { a, b, set, preconditioner: None, coarse: None, start: None }
    }

    /// The same QP with the coarse space G (none: without).
    pub fn with_coarse(self, g: Option<&'a dyn Coarse>) -> Self {
        Qp { coarse: g, ..self }
    }

    /// The same QP with the preconditioner M (none: without).
    pub fn with_preconditioner(self, m: Option<&'a dyn Preconditioner>) -> Self {
        Qp { preconditioner: m, ..self }
    }

    /// The same QP with λ and its gradient Aλ − b known (see [`Qp::start`]).
    pub fn with_start(self, start: Option<(&'a [f64], &'a [f64])>) -> Self {
        Qp { start, ..self }
    }

    /// The same QP over another Λ.
    pub fn with_set<'b>(&self, set: &'b Lambda) -> Qp<'b, A>
    where
        'a: 'b,
    {
        Qp { a: self.a, b: self.b, set, preconditioner: self.preconditioner, coarse: self.coarse, start: None }
    }
}

/// How a Coulomb problem is solved with the method `method`: the Newton method on the Coulomb
/// law (asked for, or `Auto` without a coarse projector; isotropic μ only), TSSN with lagged
/// bounds (asked for, or `Auto` with a coarse projector when TSSN is the method), or the fixed
/// point on the bounds.
pub fn coulomb_solve<A: Operator>(qp: &Qp<'_, A>, mu: &[cone::Coefficient], how: params::CoulombSolve, method: Method) -> params::CoulombSolve {
    use params::CoulombSolve::*;
    let isotropic = !mu.iter().any(|c| matches!(c, cone::Coefficient::Orthotropic(..)));
    match how {
        Newton if isotropic => Newton,
        Auto if isotropic && qp.coarse.is_none() => Newton,
        Lagged => Lagged,
        Auto if qp.coarse.is_some() && method == Method::Tssn => Lagged,
        _ => FixedPoint,
    }
}

/// Solves the QP, or — with Coulomb coefficients per pair of its Λ — the Coulomb problem from
/// `lambda0` as [`coulomb_solve`] says: by the semi-smooth Newton method on the Coulomb law
/// ([`coulomb::newton`]), by TSSN with lagged bounds ([`coulomb::lagged`]) or by the fixed point
/// of [`coulomb::solve`] (default settings) with the method of `p`.
pub fn solve_friction<A: Operator>(
    qp: &Qp<'_, A>,
    coulomb: Option<&[cone::Coefficient]>,
    lambda0: &[f64],
    p: &Params,
    monitor: &mut dyn Monitor,
) -> Result<QpSolution, QpError> {
    match coulomb {
        Some(mu) => {
            let how = coulomb_solve(qp, mu, p.common.coulomb, p.method());
            let mut sol = match how {
                params::CoulombSolve::Newton => coulomb::newton(qp, mu, lambda0, p, monitor),
                params::CoulombSolve::Lagged => coulomb::lagged(qp, mu, lambda0, p, monitor),
                _ => coulomb::solve(qp.a.space(), qp.set, mu, lambda0, p, &Default::default(), |s, x, p| solve(&qp.with_set(s), x, p, monitor)).map(|r| r.0),
            }?;
            sol.info.coulomb = Some(how);
            Ok(sol)
        }
        None => solve(qp, lambda0, p, monitor),
    }
}

impl Method {
    /// Whether the method's inner solve takes a preconditioner: TSSN's CG, SSN's BiCGSTAB
    /// (right-preconditioned), GIMSSN's CGMfeas and MPGP's CG steps (in face). IMSSN and MSSN
    /// take none.
    pub fn takes_preconditioner(self) -> bool {
        matches!(self, Method::Tssn | Method::SsnBicgstab | Method::Gimssn | Method::Mpgp)
    }
}

/// What kind of outer step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StepKind {
    /// A semi-smooth Newton step (GIMSSN, IMSSN, MSSN, SSN-BiCGSTAB).
    Newton,
    /// TSSN's tangent-symmetric Newton step.
    Tangent,
    /// TSSN's safeguard: a GIMSSN step.
    Safeguard,
    /// MPGP's conjugate gradient step; a plain CG iteration.
    Cg,
    /// MPGP's expansion step.
    Expansion,
    /// MPGP's proportioning step.
    Proportioning,
}

/// One outer iteration (MPGP: one step; plain CG: one iteration).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Step {
    /// ‖r̃_ρ‖ / ‖b‖ after the step.
    pub err: f64,
    /// Inner tolerance used (0 where there is none).
    pub tol: f64,
    /// The objective q(λ) = ½λᵀAλ − λᵀb after the step.
    pub q: f64,
    /// Active normals (pairs in contact) at the start of the step (MPGP: free normals).
    pub normal_active: usize,
    /// Sticking pairs (MPGP: free tangential pairs).
    pub stick: usize,
    /// Sliding pairs (MPGP: tangential pairs on the bound).
    pub slip: usize,
    /// Inner (CG / BiCGSTAB) iterations of this step.
    pub inner: usize,
    /// A-products so far (without the power iterations).
    #[serde(rename = "nA")]
    pub n_a: usize,
    /// Which kind of step it was.
    pub kind: StepKind,
    /// Seconds since the solve started (power iterations included).
    pub time: f64,
}

/// Counters of a solve.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Info {
    /// Outer iterations.
    #[serde(rename = "outer_iterations")]
    pub iterations: usize,
    /// A-products, the power iterations excluded.
    #[serde(rename = "nA")]
    pub n_a: usize,
    /// A-products of the power iterations for σ_max.
    #[serde(rename = "nA_power")]
    pub n_a_power: usize,
    /// Inner (CG / BiCGSTAB) iterations, summed.
    pub inner_iterations: usize,
    /// Applications of the preconditioner M (0 without one).
    pub preconditioner_applications: usize,
    /// A-products of n_a the operator made inexactly ([`Operator::allow_error`]: single-precision
    /// factors).
    #[serde(default)]
    pub inexact_products: usize,
    /// The estimate σ_est of A's largest eigenvalue σ_max.
    pub sigma_est: f64,
    /// The step parameter ρ.
    pub rho: f64,
    /// Final ‖r̃_ρ(λ)‖/‖b‖ from a fresh product.
    #[serde(rename = "final_relative_reduced_gradient")]
    pub err: f64,
    /// The final objective q(λ) = ½λᵀAλ − λᵀb.
    pub q: f64,
    /// Steps of the Coulomb fixed point (each a Tresca solve; 0: not Coulomb).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub fixed_point_iterations: usize,
    /// How a Coulomb problem was solved (None: not Coulomb).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coulomb: Option<params::CoulombSolve>,
    /// Every outer step.
    pub history: Vec<Step>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl Info {
    /// Adds the counters of `later`, a solve continued from this one's λ: the sums, its history
    /// after this one's (its products counted on from here), its final figures.
    pub fn absorb(&mut self, later: &Info) {
        let n_a_before = self.n_a;
        self.iterations += later.iterations;
        self.n_a += later.n_a;
        self.n_a_power += later.n_a_power;
        self.inner_iterations += later.inner_iterations;
        self.preconditioner_applications += later.preconditioner_applications;
        self.inexact_products += later.inexact_products;
        self.fixed_point_iterations += later.fixed_point_iterations;
        self.coulomb = later.coulomb.or(self.coulomb);
        self.history.extend(later.history.iter().cloned().map(|mut s| {
            s.n_a += n_a_before;
            s
        }));
        (self.sigma_est, self.rho, self.err, self.q) = (later.sigma_est, later.rho, later.err, later.q);
    }
}

/// Why a solve failed.
#[derive(Clone, Debug, thiserror::Error)]
pub enum QpError {
    /// No convergence to ε within the budgets.
    #[error("no convergence in {} outer iterations, {} A-products (‖r̃‖/‖b‖ = {:.3e}, ε = {eps:.1e})", info.iterations, info.n_a, info.err)]
    NoConvergence {
        /// The counters and history of the solve so far.
        info: Box<Info>,
        /// The tolerance ε it missed.
        eps: f64,
    },
    /// Nonpositive curvature dᵀAd ≤ 0: A not positive definite on the free set.
    #[error("breakdown: dᵀAd = {p_ap:.3e} ≤ 0 at outer iteration {outer} (A not positive definite on the free set)")]
    Breakdown {
        /// Outer iteration of the breakdown.
        outer: usize,
        /// The curvature dᵀAd found ≤ 0.
        p_ap: f64,
    },
    /// BiCGSTAB broke down before any progress.
    #[error("BiCGSTAB breakdown ({what}) at outer iteration {outer} before any progress")]
    BicgstabBreakdown {
        /// Outer iteration of the breakdown.
        outer: usize,
        /// Which quantity of BiCGSTAB vanished.
        what: &'static str,
    },
    /// The restricted coarse problem GΠGᵀ of the inner corrections is singular.
    #[error("the coarse problem GΠGᵀ is singular at outer iteration {outer}")]
    SingularCoarse {
        /// Outer iteration where GΠGᵀ was factorized.
        outer: usize,
    },
    /// A NaN or infinity appeared.
    #[error("non-finite value (NaN or infinity) in {what} at outer iteration {outer}")]
    NotFinite {
        /// The quantity that was not finite.
        what: &'static str,
        /// Outer iteration where it appeared.
        outer: usize,
    },
    /// The Coulomb fixed point did not converge.
    #[error("the Coulomb fixed point did not converge in {iterations} steps (λν changed by {change:.3e} relative in the last, ε = {eps:.1e}); large μ can make the solution non-unique")]
    FixedPoint {
        /// Steps of the fixed point made.
        iterations: usize,
        /// Relative change of λν in the last step.
        change: f64,
        /// The tolerance ε it missed.
        eps: f64,
    },
}

/// The result of a QP solve.
#[derive(Clone, Debug)]
pub struct QpSolution {
    /// λ ∈ Λ.
    pub lambda: Vec<f64>,
    /// r(λ) = Aλ − b from a fresh product (= −(Bu − c)).
    pub gradient: Vec<f64>,
    /// The solver's counters and history.
    pub info: Info,
}

/// Solves min ½λᵀAλ − λᵀb over Λ from λ0 (projected onto Λ first) with the method of `p`,
/// showing every outer step to `monitor`.
pub fn solve<A: Operator>(qp: &Qp<'_, A>, lambda0: &[f64], p: &Params, monitor: &mut dyn Monitor) -> Result<QpSolution, QpError> {
    match &p.method {
        MethodParams::Gimssn(m) => gimssn::solve(qp, lambda0, &p.common, gimssn::Variant::Feasible(m), monitor),
        MethodParams::Imssn(m) => gimssn::solve(qp, lambda0, &p.common, gimssn::Variant::Inexact(m), monitor),
        MethodParams::Mssn(_) => gimssn::solve(qp, lambda0, &p.common, gimssn::Variant::Exact, monitor),
        MethodParams::SsnBicgstab(m) => ssn::solve(qp, lambda0, &p.common, m, monitor),
        MethodParams::Mpgp(m) => mpgp::solve(qp, lambda0, &p.common, m, monitor),
        MethodParams::Tssn(m) => tssn::solve(qp, lambda0, &p.common, m, monitor),
    }
}
