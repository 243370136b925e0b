//! The solvers' settings, each with its defaults in one place (its `Default`): [`Common`] to
//! every method, and one struct per method for what only it reads ([`MethodParams`]). Each
//! deserializes with unknown keys refused, so a scene that sets a key its method does not read
//! fails instead of being silently ignored.

use serde::{Deserialize, Serialize};

/// The dual solvers.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Monotone, feasible (CGMfeas), globally convergent symmetrized SSN.
    Gimssn,
    /// Inexact symmetrized SSN: CG to an adaptive tolerance, iterates may leave Λ.
    Imssn,
    /// Symmetrized SSN with exact inner solves.
    Mssn,
    /// Unsymmetrized SSN (full slant derivative), inner systems by BiCGSTAB. The default: the
    /// fastest to ε = 1e-6 and to every error in u from 1e-4 to 1e-8 on the seed scene (docs/performance.md, "Against peer methods: work–precision").
    #[default]
    SsnBicgstab,
    /// Modified proportioning with gradient projections (Dostál–Kozubek).
    Mpgp,
    /// Tangent-symmetric SSN: the exact SSN step as an SPD system, solved by CG (docs/method.md, "The solvers").
    Tssn,
}

impl Method {
    /// Every method, in the order they are listed.
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

    /// The method of a scene's (or the command line's) name; none for an unknown name.
    pub fn from_name(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// What an inner tolerance is relative to.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum CgStop {
    /// ‖g_F‖ ≤ tol·‖b‖ (the faster choice, docs/method.md, "The solvers").
    #[default]
    Rhs,
    /// ‖g_F‖ ≤ tol·‖g_F at the start of the inner solve‖ (the paper's).
    InitialGradient,
}

/// How σ_max(A) (for ρ) is estimated.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SigmaEstimate {
    /// The power method from a fixed start vector.
    Power,
    /// Lanczos from the same vector: the largest Ritz value (the default, 10 steps: chosen on
    /// the benchmark set, docs/performance.md).
    #[default]
    Lanczos,
}

/// TSSN's ρ in the active-set decision yᵢ = λᵢ − ρᵢ rᵢ of the normal rows (the Newton system and the
/// stop test keep the scalar ρ).
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum RhoRule {
    /// One ρ = rho_factor/(1.1 σ_est) for every row (the default).
    #[default]
    Scalar,
    /// ρᵢ = ρ · max_j dⱼ / dᵢ with dᵢ = Σ_j Bᵢⱼ² / K_jj, the operator's estimate of Aᵢᵢ
    /// ([`super::Operator::diagonal_estimate`]; no product): rows of small compliance get a larger ρᵢ.
    /// Scalar where the operator has no estimate.
    Diagonal,
}

impl RhoRule {
    /// Whether this is the default rule (not written out).
    pub fn is_scalar(&self) -> bool {
        *self == RhoRule::Scalar
    }
}

/// How Coulomb friction is solved.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum CoulombSolve {
    /// Newton where the inner solves have no coarse projector (the monolithic dual); with one
    /// (TFETI), TSSN with lagged bounds when TSSN is the method, else the fixed point with the
    /// method: what won on the Coulomb benchmark set (docs/performance.md, "Coulomb friction: lagged bounds").
    #[default]
    Auto,
    /// The semi-smooth Newton method on the Coulomb law itself, the bound's dependence on λν in
    /// the slant derivative, BiCGSTAB inner solves (`qp::coulomb::newton`). Isotropic μ;
    /// orthotropic pairs and SMALSE-M take the fixed point.
    Newton,
    /// A fixed point on the slip bounds, each step a Tresca solve with the method
    /// (`qp::coulomb::solve`).
    FixedPoint,
    /// TSSN with lagged bounds: each Newton step takes the cones cut at the iterate's normals as
    /// fixed (a symmetric system: CG, the FETI preconditioner, the coarse projector), so the
    /// bounds settle inside one Newton loop (`qp::coulomb::lagged`). TSSN's settings when that
    /// is the method, else their defaults.
    Lagged,
}

/// Settings every method reads.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct Common {
    /// ε: stop when ‖r̃_ρ(λ)‖ ≤ ε‖b‖.
    pub eps: f64,
    /// ρ = rho_factor / (1.1 σ_est) (also MPGP's fixed step ᾱ); below 2 for the monotone theory.
    pub rho_factor: f64,
    /// Outer iterations at most (MPGP: steps).
    pub max_outer: usize,
    /// Inner iterations per outer step at most.
    pub max_inner: usize,
    /// Steps of the estimate of σ_max(A) (power iterations or Lanczos steps).
    pub power_iterations: usize,
    /// How σ_max(A) is estimated.
    pub sigma_estimate: SigmaEstimate,
    /// How a Coulomb problem is solved.
    pub coulomb: CoulombSolve,
    /// A-products (power iterations excluded) at most: a budget checked between outer steps.
    #[serde(skip)]
    pub max_products: usize,
    /// σ_max(A) when already known (no power iterations then): a caller solving a sequence of
    /// QPs with the same A (SMALSE-M's outer loop) measures it once.
    #[serde(skip)]
    pub sigma: Option<f64>,
}

impl Default for Common {
    fn default() -> Self {
        Common {
            eps: 1e-8,
            rho_factor: 1.9,
            max_outer: 1000,
            max_inner: 10_000,
            power_iterations: 10,
            sigma_estimate: SigmaEstimate::Lanczos,
            coulomb: CoulombSolve::Auto,
            max_products: usize::MAX,
            sigma: None,
        }
    }
}

/// GIMSSN and IMSSN: the adaptive inner tolerance `tol_{k+1} = min(rtol·err_k/err_0, cfact·tol_k)`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct Inexact {
    /// rtol in `tol_{k+1} = min(rtol·err_k/err_0, cfact·tol_k)`.
    pub rtol: f64,
    /// cfact in `tol_{k+1} = min(rtol·err_k/err_0, cfact·tol_k)`: each inner tolerance at most cfact times the last.
    pub cfact: f64,
    /// What inner tolerances are relative to: "rhs" (‖b‖) or "initial-gradient" (the paper's).
    pub cg_stop: CgStop,
    /// No inner solve is asked for less than inner_floor·ε·‖b‖ (0: none, as in the paper; the
    /// inner solves then go far below what the outer test can see).
    pub inner_floor: f64,
}

impl Default for Inexact {
    fn default() -> Self {
        Inexact { rtol: 0.5, cfact: 0.9, cg_stop: CgStop::Rhs, inner_floor: 0.1 }
    }
}

/// MSSN: the inner systems are solved to round-off; nothing to set.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Exact {}

/// SSN-BiCGSTAB: the adaptive tolerance of [`Inexact`], or a fixed one.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct Ssn {
    /// rtol of the adaptive tolerance ([`Inexact::rtol`]).
    pub rtol: f64,
    /// cfact of the adaptive tolerance ([`Inexact::cfact`]).
    pub cfact: f64,
    /// What inner tolerances are relative to ([`Inexact::cg_stop`]).
    pub cg_stop: CgStop,
    /// Floor of the inner tolerances (as [`Inexact::inner_floor`]).
    pub inner_floor: f64,
    /// A fixed relative inner tolerance instead of the adaptive one (the paper's baseline needs
    /// about 1e-6).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inner_tol: Option<f64>,
}

impl Default for Ssn {
    fn default() -> Self {
        let Inexact { rtol, cfact, cg_stop, inner_floor } = Inexact::default();
        Ssn { rtol, cfact, cg_stop, inner_floor, inner_tol: None }
    }
}

/// TSSN: CG to the forcing tolerance `rtol·(err_k/err_0)^θ`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct Tssn {
    /// rtol in the forcing tolerance `rtol·(err_k/err_0)^θ`.
    pub rtol: f64,
    /// The forcing exponent θ (θ > 1: superlinear).
    pub forcing: f64,
    /// Floor of the inner tolerances, relative to ε·‖b‖ ([`Inexact::inner_floor`]).
    pub inner_floor: f64,
    /// A sliding pair whose cᵢ exceeds this multiple of σ_max(A) is held at its tangent point
    /// for the step (σᵢ = 0, the paper's symmetrized MSSN for that pair): a large cᵢ is a stiff
    /// spring the FETI preconditioner knows nothing of. Infinite (`inf`): the exact Newton
    /// step. Default 0.5 (cᵢρ ≤ 0.86 at the default ρ).
    pub slide_cap: f64,
    /// The safeguard fires when q at the Newton start rose above the last accepted start's at
    /// this many starts in a row (1: at every rise, the monotone rule); 0, the default: never
    /// (chosen on the benchmark set, docs/performance.md).
    pub patience: usize,
    /// Krylov recycling: while a Newton step's system has the same structure as the last one's
    /// (the same components free, the same pairs sliding), its CG is deflated by up to this
    /// many directions of the earlier steps' solves. 0: off.
    pub recycle: usize,
    /// Damped active set, θ ∈ [0, 1): a normal row changes between the free and the fixed set
    /// of the last Newton step only where |yᵢ| = |λᵢ − ρrᵢ| is at least θ times the largest
    /// |yᵢ| of the rows that would change (that one always changes: no stall). 0, the default: off.
    pub damping: f64,
    /// ρ in the active-set decision: one scalar (the default) or one per normal row.
    #[serde(skip_serializing_if = "RhoRule::is_scalar")]
    pub rho: RhoRule,
}

impl Default for Tssn {
    fn default() -> Self {
        let Inexact { rtol, inner_floor, .. } = Inexact::default();
        Tssn { rtol, forcing: 1.0, inner_floor, slide_cap: 0.5, patience: 0, recycle: 0, damping: 0.0, rho: RhoRule::Scalar }
    }
}

/// MPGP.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct Mpgp {
    /// The proportioning constant Γ.
    pub gamma: f64,
}

impl Default for Mpgp {
    fn default() -> Self {
        Mpgp { gamma: 1.0 }
    }
}

/// The method and what only it reads.
#[derive(Clone, Debug, Serialize, PartialEq)]
#[serde(untagged)]
pub enum MethodParams {
    /// GIMSSN's settings.
    Gimssn(Inexact),
    /// IMSSN's settings.
    Imssn(Inexact),
    /// MSSN's (none).
    Mssn(Exact),
    /// SSN-BiCGSTAB's settings.
    SsnBicgstab(Ssn),
    /// MPGP's settings.
    Mpgp(Mpgp),
    /// TSSN's settings.
    Tssn(Tssn),
}

impl MethodParams {
    /// `method` with its defaults.
    pub fn new(method: Method) -> Self {
        match method {
            Method::Gimssn => MethodParams::Gimssn(Inexact::default()),
            Method::Imssn => MethodParams::Imssn(Inexact::default()),
            Method::Mssn => MethodParams::Mssn(Exact::default()),
            Method::SsnBicgstab => MethodParams::SsnBicgstab(Ssn::default()),
            Method::Mpgp => MethodParams::Mpgp(Mpgp::default()),
            Method::Tssn => MethodParams::Tssn(Tssn::default()),
        }
    }

    /// `method`'s own settings from `d` (unknown keys refused).
    pub fn deserialize<'de, D: serde::Deserializer<'de>>(method: Method, d: D) -> Result<Self, D::Error> {
        Ok(match method {
            Method::Gimssn => MethodParams::Gimssn(Inexact::deserialize(d)?),
            Method::Imssn => MethodParams::Imssn(Inexact::deserialize(d)?),
            Method::Mssn => MethodParams::Mssn(Exact::deserialize(d)?),
            Method::SsnBicgstab => MethodParams::SsnBicgstab(Ssn::deserialize(d)?),
            Method::Mpgp => MethodParams::Mpgp(Mpgp::deserialize(d)?),
            Method::Tssn => MethodParams::Tssn(Tssn::deserialize(d)?),
        })
    }

    /// The method these settings are for.
    pub fn method(&self) -> Method {
        match self {
            MethodParams::Gimssn(_) => Method::Gimssn,
            MethodParams::Imssn(_) => Method::Imssn,
            MethodParams::Mssn(_) => Method::Mssn,
            MethodParams::SsnBicgstab(_) => Method::SsnBicgstab,
            MethodParams::Mpgp(_) => Method::Mpgp,
            MethodParams::Tssn(_) => Method::Tssn,
        }
    }
}

/// Everything a solve reads: the common settings and the method's own.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    /// The settings every method reads.
    pub common: Common,
    /// The method and its own settings.
    pub method: MethodParams,
}

impl Default for Params {
    fn default() -> Self {
        Params::new(Method::default())
    }
}

impl Params {
    /// `method` with every default.
    pub fn new(method: Method) -> Self {
        Params { common: Common::default(), method: MethodParams::new(method) }
    }

    /// The same with ε = `eps`.
    pub fn with_eps(mut self, eps: f64) -> Self {
        self.common.eps = eps;
        self
    }

    /// Another method with these common settings and its own defaults.
    pub fn with_method(&self, method: Method) -> Self {
        Params { common: self.common.clone(), method: MethodParams::new(method) }
    }

    /// The method of the solve.
    pub fn method(&self) -> Method {
        self.method.method()
    }
}

/// A setting out of its range: the key and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Invalid {
    /// The setting's key.
    pub key: &'static str,
    /// Why its value is refused.
    pub msg: String,
}

fn positive(key: &'static str, v: f64) -> Result<(), Invalid> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Invalid { key, msg: format!("must be finite and > 0, got {v}") })
    }
}

fn fraction(key: &'static str, v: f64) -> Result<(), Invalid> {
    if v > 0.0 && v < 1.0 {
        Ok(())
    } else {
        Err(Invalid { key, msg: format!("must lie in (0, 1), got {v}") })
    }
}

fn floor(v: f64) -> Result<(), Invalid> {
    if v >= 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(Invalid { key: "inner_floor", msg: format!("must be finite and ≥ 0, got {v}") })
    }
}

impl Params {
    /// Checks every value against its range.
    pub fn validate(&self) -> Result<(), Invalid> {
        let c = &self.common;
        positive("eps", c.eps)?;
        positive("rho_factor", c.rho_factor)?;
        for (key, v) in [("max_outer", c.max_outer), ("max_inner", c.max_inner), ("power_iterations", c.power_iterations)] {
            if v == 0 {
                return Err(Invalid { key, msg: "must be at least 1".into() });
            }
        }
        match &self.method {
            MethodParams::Gimssn(m) | MethodParams::Imssn(m) => {
                fraction("rtol", m.rtol)?;
                fraction("cfact", m.cfact)?;
                floor(m.inner_floor)
            }
            MethodParams::SsnBicgstab(m) => {
                fraction("rtol", m.rtol)?;
                fraction("cfact", m.cfact)?;
                floor(m.inner_floor)?;
                m.inner_tol.map_or(Ok(()), |t| fraction("inner_tol", t))
            }
            MethodParams::Tssn(m) => {
                fraction("rtol", m.rtol)?;
                positive("forcing", m.forcing)?;
                if !(m.slide_cap > 0.0) {
                    return Err(Invalid { key: "slide_cap", msg: format!("must be > 0 (inf: never), got {}", m.slide_cap) });
                }
                if !(0.0..1.0).contains(&m.damping) {
                    return Err(Invalid { key: "damping", msg: format!("must lie in [0, 1), got {}", m.damping) });
                }
                floor(m.inner_floor)
            }
            MethodParams::Mpgp(m) => positive("gamma", m.gamma),
            MethodParams::Mssn(_) => Ok(()),
        }
    }
}
