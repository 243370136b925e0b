//! The convex blocks of the dual feasible set `Λ = R₊ᵐ × Π_i Λτ,ᵢ` (docs/method.md, "The problem" and "The solvers"): one small
//! closed convex set in R^d (d = 1 or 2) per contact pair and direction.
//!
//! * [`HalfLine`] (d = 1): `{x ≥ 0}` for the normal multiplier λν,ᵢ. `P(y) = max(0, y)`; slant
//!   derivative 1 for `y ≥ 0`, 0 for `y < 0` — the paper's convention `A_ν = {y ≥ 0}` (12): y = 0
//!   counts as free.
//! * [`Disc`] (d = 2): `{‖x‖ ≤ g}` for isotropic Tresca. The projection is the radial scaling
//!   `ψ_g(y) = y` if `‖y‖ ≤ g`, else `g·y/‖y‖`; its slant derivative is `I` for `‖y‖ ≤ g`
//!   (stick, `A_τ` of (13)) and `ψ°_g(y) = (g/‖y‖)(I − ŷŷᵀ)`, `ŷ = y/‖y‖`, for `‖y‖ > g` (slip).
//!   Radius 0 is allowed: `ψ_0 ≡ 0`, slant 0.
//! * [`Ellipse`] (d = 2): `{(x₁/a)² + (x₂/b)² ≤ 1}` for orthotropic Tresca (semi-axes a along the
//!   first, b along the second tangential direction). For y outside, the Euclidean projection is
//!   `x_k = a_k² y_k/(a_k² + t)` with `t > 0` the root of the secular equation
//!   `Σ_k (a_k y_k/(a_k² + t))² = 1`. It is solved by Newton's method on
//!   `φ(t) = 1/‖w(t)‖ − 1`, `w_k = a_k y_k/(a_k² + t)`: φ is increasing and concave (1/‖w‖ is a
//!   power mean of order −2 of the affine `a_k² + t`), so Newton from either side lands at or
//!   below the root, and started below it climbs monotonically and quadratically (exact in one
//!   step for a disc or y on an axis). Start: the largest of the lower bounds `‖a∘y‖ − a_max²`,
//!   `a_k|y_k| − a_k²` (from here on `|w_k| ≤ 1`) and, for thin ellipses, a bound from the
//!   cubic `(a_min² + t)²t ≈ a_min² y_min² a_max²/4` valid near the major vertex, where Newton
//!   would otherwise creep up from `t ≈ a_min²` by a factor ~1.5 per step (18 steps at axis
//!   ratio 1e4, 42 at 1e20; with the bound at most 6 at any ratio up to 1e99). Stop when
//!   `|‖w‖ − 1| ≤ 2ε` (rounding level); safeguarded by the bracket `[t₀, ‖a∘y‖ − a_min²]`
//!   and at most 64 steps (NaN). The result is normalized, `x_k = a_k w_k/‖w‖`, so it lies on
//!   the boundary to rounding. Everything runs in variables scaled by `max(a, b)`.
//!
//!   The slant derivative outside is the exact Jacobian from implicit differentiation of the
//!   secular equation, `ψ°(y) = D − D n nᵀ D/(nᵀ D n)`, `D = diag(a_k²/(a_k² + t))`,
//!   `n ∝ x_k/a_k²` the outward normal; in 2-D this is the rank-one `μ·t tᵀ` with t the unit
//!   tangent at x and `μ = D₁D₂/(n₁²D₁ + n₂²D₂) = 1/(1 + κ·dist(y))` (κ the boundary's
//!   curvature at x). For `a = b = g`, `D = (g/‖y‖)I` and this is `ψ°_g` (both are evaluated
//!   as `μ·t tᵀ`: exactly symmetric and rank one, no cancellation in `1 − ŷ₁²`). Inside: `I`.
//!   An ellipse whose axis ratio is at most [`DEGENERATE_RATIO`] (e.g. b = 0) is the segment
//!   `[−a, a] × {0}` (projection `(clamp(y₁, −a, a), 0)`, slant `e₁e₁ᵀ` for `|y₁| ≤ a`, else
//!   0: on the segment itself the projection is not the identity); a = b = 0 is the point {0}.
//!
//! [`TangentSet`] dispatches statically between the disc and the ellipse (one per contact pair)
//! and adds the local boundary geometry a tangent-symmetric Newton step needs (docs/method.md, "The solvers"):
//! [`TangentSet::boundary_tangent`], [`TangentSet::curvature`] and, for a sliding pair,
//! [`TangentSet::frame`] (projection, normal, tangent, distance, curvature and slant factor μ at
//! once; the term `cᵢ = (1/μ − 1)/ρ` of §3b is best computed as `κ·dist/ρ`).
//!
//! Everything here is allocation-free and panic-free for finite input (slices of
//! the wrong length aside); NaN input gives NaN (or arbitrary) output but never loops.

// `!(a > b)` is used on purpose: it is true for NaN, which must stop loops and pick fallbacks.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// Axis ratio `min(a, b)/max(a, b)` at or below which an [`Ellipse`] is treated as the segment
/// along its longer axis (the difference is below 1e-100 of its size; it keeps `a_k²` and the
/// secular equation's terms far from underflow and overflow).
pub const DEGENERATE_RATIO: f64 = 1e-100;

/// Most Newton steps on the secular equation (a handful are needed; this only bounds NaN input).
const MAX_NEWTON: u32 = 64;

/// A point farther than this (relative to the ellipse's size) is projected by the asymptotic
/// formula `x_k = a_k² y_k/‖a∘y‖`, exact to ~1e-300 relative there.
const FAR: f64 = 1e300;

const EPS: f64 = f64::EPSILON;

/// A closed convex set in R^d (d = 1 or 2): the block of one contact pair in `Λ`.
pub trait ConvexSet {
    /// The dimension d.
    fn dim(&self) -> usize;
    /// Euclidean projection of y onto the set, into `out`.
    fn project(&self, y: &[f64], out: &mut [f64]);
    /// Whether x lies in the set up to `tol` (absolute, in the units of x): dist(x, set) ≤ tol.
    fn contains(&self, x: &[f64], tol: f64) -> bool;
    /// For x in the set: the largest α ≥ 0 with x − α·d in the set (`f64::INFINITY` if
    /// unbounded, e.g. d = 0). (CGMfeas' feasibility test and step to the boundary.) For x
    /// outside by rounding: 0 if −d points outward, else where the ray leaves the set.
    fn max_step(&self, x: &[f64], d: &[f64]) -> f64;
    /// A slant (generalized Jacobian) derivative of the projection at y, row-major d×d, into
    /// `out`.
    fn slant(&self, y: &[f64], out: &mut [f64]);
    /// Whether the projection of y lies on the boundary with y outside (the pair is
    /// "active"/"sliding"): y ∉ set. Exactly the points that `project` moves.
    fn is_outside(&self, y: &[f64]) -> bool;
}

/// `if a < 0 { 0 } else { a }`, letting NaN through.
#[inline]
fn nonneg(a: f64) -> f64 {
    if a < 0.0 {
        0.0
    } else {
        a
    }
}

// ---------------------------------------------------------------------------------------------
// Half-line

/// `{x ∈ R : x ≥ 0}`, the normal multiplier's set.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HalfLine;

impl ConvexSet for HalfLine {
    #[inline]
    fn dim(&self) -> usize {
        1
    }

    #[inline]
    fn project(&self, y: &[f64], out: &mut [f64]) {
        out[0] = nonneg(y[0]);
    }

    #[inline]
    fn contains(&self, x: &[f64], tol: f64) -> bool {
        x[0] >= -tol
    }

    /// `x/d` for d > 0, `∞` for d ≤ 0 (NaN for NaN d).
    #[inline]
    fn max_step(&self, x: &[f64], d: &[f64]) -> f64 {
        let d = d[0];
        if d > 0.0 {
            nonneg(x[0] / d)
        } else if d.is_nan() {
            f64::NAN
        } else {
            f64::INFINITY
        }
    }

    /// 1 for y ≥ 0 (y = 0 counts as free, `A_ν` of (12)), 0 for y < 0.
    #[inline]
    fn slant(&self, y: &[f64], out: &mut [f64]) {
        out[0] = if y[0] >= 0.0 { 1.0 } else { 0.0 };
    }

    #[inline]
    fn is_outside(&self, y: &[f64]) -> bool {
        y[0] < 0.0
    }
}

// ---------------------------------------------------------------------------------------------
// Shared 2-D helpers

/// Local boundary geometry at `x = P(y)` for a point y outside a tangent set (a sliding pair).
///
/// `y = point + distance·normal`, and the slant derivative of the projection at y is
/// `mu·tangent·tangentᵀ`, `mu = 1/(1 + curvature·distance)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundaryFrame {
    /// The projection x = P(y), on the boundary.
    pub point: [f64; 2],
    /// Unit outward normal at x, `(y − x)/‖y − x‖`.
    pub normal: [f64; 2],
    /// Unit tangent at x: the normal turned by +90°, `(−n₂, n₁)`.
    pub tangent: [f64; 2],
    /// `‖y − x‖ > 0`, computed without cancellation where possible.
    pub distance: f64,
    /// Curvature κ of the boundary at x: `1/g` on a disc, `ab/(b²cos²θ + a²sin²θ)^{3/2}` on an
    /// ellipse at `x = (a cosθ, b sinθ)`; 0 on the flat side of a segment, `∞` at a segment's end
    /// and for the point set.
    pub curvature: f64,
    /// Slant factor μ ∈ [0, 1]: `ψ°(y) = μ·t tᵀ` (`g/‖y‖` on a disc).
    pub mu: f64,
}

impl BoundaryFrame {
    /// The frame with tangent `(−n₂, n₁)` from the other fields.
    #[inline]
    fn new(point: [f64; 2], normal: [f64; 2], distance: f64, curvature: f64, mu: f64) -> Self {
        BoundaryFrame { point, normal, tangent: [-normal[1], normal[0]], distance, curvature, mu }
    }

    /// The slant derivative `μ·t tᵀ`, row-major.
    #[inline]
    pub fn slant(&self) -> [f64; 4] {
        rank_one(self.mu, self.tangent)
    }
}

/// `mu·t tᵀ`, row-major 2×2.
#[inline]
fn rank_one(mu: f64, t: [f64; 2]) -> [f64; 4] {
    let off = mu * t[0] * t[1];
    [mu * t[0] * t[0], off, off, mu * t[1] * t[1]]
}

#[inline]
fn write2(out: &mut [f64], v: [f64; 2]) {
    out[0] = v[0];
    out[1] = v[1];
}

#[inline]
fn write4(out: &mut [f64], m: [f64; 4]) {
    out[..4].copy_from_slice(&m);
}

const IDENTITY: [f64; 4] = [1.0, 0.0, 0.0, 1.0];
const ZERO: [f64; 4] = [0.0; 4];

/// The largest α ≥ 0 with `‖p − α·q‖ ≤ 1`, for ‖p‖ ≤ 1 (up to rounding) and q ≠ 0 of moderate
/// size: the larger root of `‖q‖²α² − 2(p·q)α + ‖p‖² − 1 = 0`, computed without cancellation
/// (with q normalized first). 0 when p is on or outside the boundary and q points outward.
#[inline]
fn unit_ball_step(p: [f64; 2], q: [f64; 2]) -> f64 {
    let qn = q[0].hypot(q[1]);
    let qh = [q[0] / qn, q[1] / qn];
    let beta = p[0] * qh[0] + p[1] * qh[1];
    let pn = p[0].hypot(p[1]);
    let c = (pn - 1.0) * (pn + 1.0); // ‖p‖² − 1 ≤ 0 inside
    let a = if beta > 0.0 {
        beta + nonneg(beta * beta - c).sqrt()
    } else if c < 0.0 {
        // β ≤ 0: the positive root without cancellation, −c/(√(β² − c) − β).
        -c / ((beta * beta - c).sqrt() - beta)
    } else if c.is_nan() || beta.is_nan() {
        f64::NAN
    } else {
        0.0 // on (or just outside) the boundary, moving outward or tangentially
    };
    a / qn
}

/// Max-abs scaling of a direction: `(d/m, m)` with `m = max_k |d_k|`.
#[inline]
fn scale_dir(d: &[f64]) -> ([f64; 2], f64) {
    let m = d[0].abs().max(d[1].abs());
    ([d[0] / m, d[1] / m], m)
}

// ---------------------------------------------------------------------------------------------
// Disc

/// `{x ∈ R² : ‖x‖ ≤ radius}`, the isotropic Tresca set (`radius = gᵢ`; a negative radius is
/// read as its absolute value, 0 gives the point set {0}).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disc {
    pub radius: f64,
}

impl Disc {
    pub const fn new(radius: f64) -> Self {
        Disc { radius }
    }

    #[inline]
    fn g(&self) -> f64 {
        self.radius.abs()
    }

    /// Unit tangent `(−x₂, x₁)/‖x‖` (counterclockwise) of the circle through x; `(0, 1)` at x = 0.
    pub fn boundary_tangent(&self, x: &[f64]) -> [f64; 2] {
        let n = x[0].hypot(x[1]);
        if n > 0.0 {
            [-x[1] / n, x[0] / n]
        } else {
            [0.0, 1.0]
        }
    }

    /// Curvature `1/g` (∞ for radius 0), the same at every boundary point.
    pub fn curvature(&self, _x: &[f64]) -> f64 {
        1.0 / self.g()
    }

    /// Boundary geometry at `ψ_g(y)` for y outside (`None` inside): point `gŷ`, normal ŷ,
    /// distance `‖y‖ − g`, curvature `1/g`, μ = `g/‖y‖`.
    pub fn frame(&self, y: &[f64]) -> Option<BoundaryFrame> {
        let g = self.g();
        let n = y[0].hypot(y[1]);
        if !(n > g) {
            return None;
        }
        let yh = [y[0] / n, y[1] / n];
        Some(BoundaryFrame::new([g * yh[0], g * yh[1]], yh, n - g, 1.0 / g, g / n))
    }
}

impl ConvexSet for Disc {
    #[inline]
    fn dim(&self) -> usize {
        2
    }

    #[inline]
    fn project(&self, y: &[f64], out: &mut [f64]) {
        let g = self.g();
        let n = y[0].hypot(y[1]);
        if n <= g {
            write2(out, [y[0], y[1]]);
        } else {
            write2(out, [g * (y[0] / n), g * (y[1] / n)]);
        }
    }

    #[inline]
    fn contains(&self, x: &[f64], tol: f64) -> bool {
        x[0].hypot(x[1]) <= self.g() + tol
    }

    fn max_step(&self, x: &[f64], d: &[f64]) -> f64 {
        let (dh, m) = scale_dir(d);
        if m == 0.0 {
            return f64::INFINITY;
        }
        let g = self.g();
        if g == 0.0 {
            return if m.is_nan() { f64::NAN } else { 0.0 };
        }
        // x − αd ∈ disc ⇔ ‖x/g − (αm/g)·dh‖ ≤ 1.
        nonneg(unit_ball_step([x[0] / g, x[1] / g], dh) * (g / m))
    }

    /// `I` for `‖y‖ ≤ g` (g > 0), `ψ°_g(y) = (g/‖y‖)(I − ŷŷᵀ)` outside, 0 for g = 0.
    #[inline]
    fn slant(&self, y: &[f64], out: &mut [f64]) {
        let g = self.g();
        if g == 0.0 {
            write4(out, ZERO);
            return;
        }
        let n = y[0].hypot(y[1]);
        if n <= g {
            write4(out, IDENTITY);
        } else {
            // (g/‖y‖)(I − ŷŷᵀ) = (g/‖y‖) t tᵀ, t = (−ŷ₂, ŷ₁) (no cancellation in 1 − ŷ₁²).
            write4(out, rank_one(g / n, [-y[1] / n, y[0] / n]));
        }
    }

    #[inline]
    fn is_outside(&self, y: &[f64]) -> bool {
        y[0].hypot(y[1]) > self.g()
    }
}

// ---------------------------------------------------------------------------------------------
// Ellipse

/// `{x ∈ R² : (x₁/a)² + (x₂/b)² ≤ 1}`, the orthotropic Tresca set (semi-axes `a = g₁ᵢ` along the
/// first, `b = g₂ᵢ` along the second tangential direction). Negative semi-axes are read as their
/// absolute values; `a = b` is a disc, an axis ratio ≤ [`DEGENERATE_RATIO`] (e.g. b = 0) a
/// segment, `a = b = 0` the point {0}.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipse {
    pub a: f64,
    pub b: f64,
}

/// What an ellipse is, numerically.
#[derive(Clone, Copy, Debug)]
enum Shape {
    /// `{0}`.
    Point,
    /// `[−half, half]·e_axis` (half > 0).
    Segment { axis: usize, half: f64 },
    /// A proper ellipse: semi-axes `ax = [a, b]`, size `s = max(a, b)`, `ah = ax/s`.
    Proper { ax: [f64; 2], s: f64, ah: [f64; 2] },
}

/// The root of the secular equation for a point outside a proper ellipse, in scaled units.
#[derive(Clone, Copy, Debug)]
struct Secular {
    /// y/s.
    yh: [f64; 2],
    /// â_k².
    a2: [f64; 2],
    /// τ = t/s².
    tau: f64,
    /// â_k² + τ.
    u: [f64; 2],
    /// x_k/a_k, a unit vector.
    v: [f64; 2],
    iters: u32,
}

/// The projection of a point y outside a proper ellipse, with its local geometry.
#[derive(Clone, Copy, Debug)]
struct Outside {
    x: [f64; 2],
    normal: [f64; 2],
    distance: f64,
    curvature: f64,
    mu: f64,
    /// Newton steps taken (tests).
    #[cfg_attr(not(test), allow(dead_code))]
    iters: u32,
}

impl Ellipse {
    pub const fn new(a: f64, b: f64) -> Self {
        Ellipse { a, b }
    }

    fn shape(&self) -> Shape {
        let ax = [self.a.abs(), self.b.abs()];
        let s = ax[0].max(ax[1]);
        let m = ax[0].min(ax[1]);
        if !(s > 0.0) {
            Shape::Point
        } else if m <= DEGENERATE_RATIO * s {
            Shape::Segment { axis: if ax[0] >= ax[1] { 0 } else { 1 }, half: s }
        } else {
            Shape::Proper { ax, s, ah: [ax[0] / s, ax[1] / s] }
        }
    }

    /// y outside the proper ellipse with semi-axes `ax`: `(y₁/a)² + (y₂/b)² > 1`.
    #[inline]
    fn proper_outside(ax: [f64; 2], y: &[f64]) -> bool {
        (y[0] / ax[0]).hypot(y[1] / ax[1]) > 1.0
    }

    /// Curvature at the boundary point `(a v₁, b v₂)`, ‖v‖ = 1: `ab/‖(b v₁, a v₂)‖³`, in units
    /// `1/s` via the scaled semi-axes.
    #[inline]
    fn proper_curvature(s: f64, ah: [f64; 2], v: [f64; 2]) -> f64 {
        let h = (ah[1] * v[0]).hypot(ah[0] * v[1]);
        ah[0] * ah[1] / (h * h * h) / s
    }

    /// The secular root for y outside the proper ellipse: Newton on `φ(τ) = 1/‖w(τ)‖ − 1` in
    /// the scaled variables `â = ax/s`, `ŷ = y/s`, `τ = t/s²`, `w_k = â_k ŷ_k/(â_k² + τ)`.
    /// `None` for ‖y‖ > FAR·s (or NaN): use [`Self::far`].
    #[inline]
    fn secular(s: f64, ah: [f64; 2], y: &[f64]) -> Option<Secular> {
        let yh = [y[0] / s, y[1] / s];
        if !(yh[0].abs().max(yh[1].abs()) <= FAR) || yh[0].is_nan() || yh[1].is_nan() {
            return None;
        }
        let a2 = [ah[0] * ah[0], ah[1] * ah[1]];
        let p = [ah[0] * yh[0], ah[1] * yh[1]];
        let rho = p[0].hypot(p[1]);
        // Lower bounds: S(τ) ≥ ρ²/(1 + τ)² and ≥ p_k²/(â_k² + τ)² (so |w_k| ≤ 1 from here on),
        // and the vertex bound; upper bound: S(τ) ≤ ρ²/(â_min² + τ)².
        let mut tau = nonneg((rho - 1.0).max(p[0].abs() - a2[0]).max(p[1].abs() - a2[1]));
        if a2[0].min(a2[1]) < 0.0625 {
            tau = tau.max(Self::vertex_bound(a2, p));
        }
        let mut lo = tau;
        let mut hi = (rho - a2[0].min(a2[1])) * (1.0 + 4.0 * EPS);
        let mut u;
        let mut w;
        let mut r;
        let mut iters = 0;
        loop {
            u = [a2[0] + tau, a2[1] + tau];
            let iu = [1.0 / u[0], 1.0 / u[1]];
            w = [p[0] * iu[0], p[1] * iu[1]];
            let sq = w[0] * w[0] + w[1] * w[1]; // |w_k| ≤ 1: no overflow
            r = sq.sqrt();
            // Newton: Δτ = (r − 1)/Σ_k v_k²/u_k, v = w/r; from either side it lands at or
            // below the root (φ concave), so from the lower bound it climbs monotonically.
            let delta = (r - 1.0) * sq / (w[0] * w[0] * iu[0] + w[1] * w[1] * iu[1]);
            if r > 1.0 {
                lo = tau;
            } else {
                hi = tau;
            }
            // Converged: residual at rounding level (r is accurate to ~2 eps), step below
            // rounding, or bracket exhausted; or NaN.
            if !((r - 1.0).abs() > 2.0 * EPS) || !(delta.abs() > 4.0 * EPS * tau) || !(hi - lo > 4.0 * EPS * hi) || iters >= MAX_NEWTON {
                break;
            }
            let newton = tau + delta;
            // The bracket only guards against rounding.
            tau = if newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
            iters += 1;
        }
        Some(Secular { yh, a2, tau, u, v: [w[0] / r, w[1] / r], iters })
    }

    /// The projection of y (outside) onto the proper ellipse.
    #[inline]
    fn proper_point(ax: [f64; 2], s: f64, ah: [f64; 2], y: &[f64]) -> [f64; 2] {
        match Self::secular(s, ah, y) {
            Some(r) => [ax[0] * r.v[0], ax[1] * r.v[1]],
            None => Self::far(ax, s, ah, y).x,
        }
    }

    /// The projection of y (outside) onto the proper ellipse, with its local geometry.
    fn proper_project_outside(ax: [f64; 2], s: f64, ah: [f64; 2], y: &[f64]) -> Outside {
        let Some(Secular { yh, a2, tau, u, v, iters }) = Self::secular(s, ah, y) else {
            return Self::far(ax, s, ah, y);
        };
        let x = [ax[0] * v[0], ax[1] * v[1]];
        // Outward normal ∝ (y − x)_k = ŷ_k τ/u_k ∝ x_k/a_k² (|ŷ_k/u_k| ≤ 1/â_k).
        let z = [yh[0] / u[0], yh[1] / u[1]];
        let zn = z[0].hypot(z[1]);
        let normal = [z[0] / zn, z[1] / zn];
        let distance = s * tau * zn;
        // ψ° = D − DnnᵀD/(nᵀDn) = μ t tᵀ, μ = det D/(nᵀDn) ≤ 1.
        let d = [a2[0] / u[0], a2[1] / u[1]];
        let mu = d[0] * d[1] / (normal[0] * normal[0] * d[0] + normal[1] * normal[1] * d[1]);
        let curvature = Self::proper_curvature(s, ah, v);
        Outside { x, normal, distance, curvature, mu: mu.min(1.0), iters }
    }

    /// A lower bound on the secular root for y near the major vertex of a thin ellipse, where
    /// the minor term `p_m²/(B + τ)²` (B = â_m², tiny) has τ* ≫ B and Newton from the other
    /// bounds would creep. With the major term linearized from below (`1/(1 + τ)² ≥ 1 − 2τ`,
    /// â_M = 1, `c = p_M²`): `S(τ) ≥ c(1 − 2τ) + p_m²/(B + τ)² ≥ 1` holds wherever
    /// `(B + τ)²τ ≤ p_m²/(4c)` and, for c < 1, `(B + τ)² ≤ p_m²/(2(1 − c))`.
    #[inline]
    fn vertex_bound(a2: [f64; 2], p: [f64; 2]) -> f64 {
        let (m, big) = if a2[0] <= a2[1] { (0, 1) } else { (1, 0) };
        let b = a2[m];
        let c = p[big] * p[big];
        // k = p_m²/(4c); the largest τ found with (B + τ)²τ ≤ k is (k/4)^{1/3} if that is ≥ B,
        // else min(B, k/(4B²)) (written without squaring the possibly tiny p_m).
        let pm = p[m].abs();
        let t = if pm > 1e-150 { (pm * pm / (16.0 * c)).cbrt() } else { pm.cbrt().powi(2) / (16.0 * c).cbrt() };
        let cubic = if t >= b { t } else { b.min((pm / b).powi(2) / (16.0 * c)) };
        let t2 = if c < 1.0 { pm / (2.0 * (1.0 - c)).sqrt() - b } else { f64::INFINITY };
        nonneg(cubic.min(t2))
    }

    /// ‖y‖ > FAR·s: `t = ‖a∘y‖(1 + O(s/‖y‖))`, so `x_k = a_k (â_k d_k)/‖â∘d‖` with `d = y/max|y_k|`.
    #[cold]
    fn far(ax: [f64; 2], s: f64, ah: [f64; 2], y: &[f64]) -> Outside {
        let (d, m) = scale_dir(y);
        let q = [ah[0] * d[0], ah[1] * d[1]];
        let qn = q[0].hypot(q[1]);
        let v = [q[0] / qn, q[1] / qn];
        let x = [ax[0] * v[0], ax[1] * v[1]];
        let dn = d[0].hypot(d[1]);
        let normal = [d[0] / dn, d[1] / dn];
        let distance = m * dn - (x[0] * normal[0] + x[1] * normal[1]);
        let curvature = Self::proper_curvature(s, ah, v);
        let mu = 1.0 / (1.0 + curvature * distance);
        Outside { x, normal, distance, curvature, mu, iters: 0 }
    }

    /// Unit tangent of the boundary at a boundary point x, counterclockwise: `∝ (−a x₂/b, b x₁/a)`.
    /// For x off the boundary, the tangent of the scaled ellipse through x; at x = 0 the tangent
    /// at `(a, 0)`, i.e. `(0, 1)`. On a segment: the segment's direction `e_axis`; the point set:
    /// `(0, 1)`.
    pub fn boundary_tangent(&self, x: &[f64]) -> [f64; 2] {
        match self.shape() {
            Shape::Point => [0.0, 1.0],
            Shape::Segment { axis, .. } => {
                let mut t = [0.0; 2];
                t[axis] = 1.0;
                t
            }
            Shape::Proper { ax, .. } => {
                let c = [x[0] / ax[0], x[1] / ax[1]];
                let t = [-ax[0] * c[1], ax[1] * c[0]];
                let n = t[0].hypot(t[1]);
                if n > 0.0 {
                    [t[0] / n, t[1] / n]
                } else {
                    [0.0, 1.0]
                }
            }
        }
    }

    /// Curvature κ of the boundary at the boundary point x (`(a cosθ, b sinθ)`):
    /// `ab/(b²cos²θ + a²sin²θ)^{3/2}`; x off the boundary is first scaled radially onto it
    /// (x = 0: the value at `(a, 0)`, `a/b²`). Segment: 0 in its relative interior, ∞ at its
    /// ends; point set: ∞.
    pub fn curvature(&self, x: &[f64]) -> f64 {
        match self.shape() {
            Shape::Point => f64::INFINITY,
            Shape::Segment { axis, half } => {
                if x[axis].abs() < half {
                    0.0
                } else {
                    f64::INFINITY
                }
            }
            Shape::Proper { ax, s, ah } => {
                let c = [x[0] / ax[0], x[1] / ax[1]];
                let n = c[0].hypot(c[1]);
                let v = if n > 0.0 { [c[0] / n, c[1] / n] } else { [1.0, 0.0] };
                Self::proper_curvature(s, ah, v)
            }
        }
    }

    /// Boundary geometry at P(y) for y outside (`None` inside); see [`BoundaryFrame`].
    pub fn frame(&self, y: &[f64]) -> Option<BoundaryFrame> {
        match self.shape() {
            Shape::Point => {
                let n = y[0].hypot(y[1]);
                if !(n > 0.0) {
                    return None;
                }
                Some(BoundaryFrame::new([0.0; 2], [y[0] / n, y[1] / n], n, f64::INFINITY, 0.0))
            }
            Shape::Segment { axis, half } => {
                let o = 1 - axis;
                if y[o] == 0.0 && !(y[axis].abs() > half) {
                    return None;
                }
                let mut point = [0.0; 2];
                if y[axis].abs() <= half {
                    // Flat side: slant e_axis e_axisᵀ.
                    point[axis] = y[axis];
                    let mut normal = [0.0; 2];
                    normal[o] = y[o].signum();
                    Some(BoundaryFrame::new(point, normal, y[o].abs(), 0.0, 1.0))
                } else {
                    point[axis] = half.copysign(y[axis]);
                    let e = [y[0] - point[0], y[1] - point[1]];
                    let n = e[0].hypot(e[1]);
                    Some(BoundaryFrame::new(point, [e[0] / n, e[1] / n], n, f64::INFINITY, 0.0))
                }
            }
            Shape::Proper { ax, s, ah } => {
                if !Self::proper_outside(ax, y) {
                    return None;
                }
                let o = Self::proper_project_outside(ax, s, ah, y);
                Some(BoundaryFrame::new(o.x, o.normal, o.distance, o.curvature, o.mu))
            }
        }
    }

    /// Newton steps the projection of y takes (0 inside or degenerate).
    #[cfg(test)]
    fn newton_iters(&self, y: &[f64]) -> u32 {
        match self.shape() {
            Shape::Proper { ax, s, ah } if Self::proper_outside(ax, y) => Self::proper_project_outside(ax, s, ah, y).iters,
            _ => 0,
        }
    }
}

impl ConvexSet for Ellipse {
    #[inline]
    fn dim(&self) -> usize {
        2
    }

    fn project(&self, y: &[f64], out: &mut [f64]) {
        match self.shape() {
            Shape::Point => write2(out, [0.0, 0.0]),
            Shape::Segment { axis, half } => {
                let mut x = [0.0; 2];
                x[axis] = y[axis].clamp(-half, half);
                write2(out, x);
            }
            Shape::Proper { ax, s, ah } => {
                if Self::proper_outside(ax, y) {
                    write2(out, Self::proper_point(ax, s, ah, y));
                } else {
                    write2(out, [y[0], y[1]]);
                }
            }
        }
    }

    fn contains(&self, x: &[f64], tol: f64) -> bool {
        match self.shape() {
            Shape::Point => x[0].hypot(x[1]) <= tol,
            Shape::Segment { axis, half } => nonneg(x[axis].abs() - half).hypot(x[1 - axis]) <= tol,
            Shape::Proper { ax, s, ah } => {
                if !Self::proper_outside(ax, x) {
                    return true;
                }
                let p = Self::proper_point(ax, s, ah, x);
                (x[0] - p[0]).hypot(x[1] - p[1]) <= tol
            }
        }
    }

    fn max_step(&self, x: &[f64], d: &[f64]) -> f64 {
        let (dh, m) = scale_dir(d);
        if m == 0.0 {
            return f64::INFINITY;
        }
        match self.shape() {
            Shape::Point => {
                if m.is_nan() {
                    f64::NAN
                } else {
                    0.0
                }
            }
            Shape::Segment { axis, half } => {
                let o = 1 - axis;
                let (xa, da) = (x[axis], d[axis]);
                if d[o] != 0.0 {
                    if d[o].is_nan() {
                        f64::NAN
                    } else {
                        0.0
                    }
                } else if da > 0.0 {
                    nonneg((xa + half) / da)
                } else if da < 0.0 {
                    nonneg((xa - half) / da)
                } else {
                    f64::NAN
                }
            }
            Shape::Proper { ax, s, ah } => {
                // x − αd ∈ E ⇔ ‖x/a − (αm/s)·(dh/â)‖ ≤ 1.
                let p = [x[0] / ax[0], x[1] / ax[1]];
                let q = [dh[0] / ah[0], dh[1] / ah[1]];
                nonneg(unit_ball_step(p, q) * (s / m))
            }
        }
    }

    /// Identity inside; the exact Jacobian `μ·t tᵀ` outside (see the module docs); segment:
    /// `e e_axisᵀ` for `|y_axis| ≤ half`, else 0; point: 0.
    fn slant(&self, y: &[f64], out: &mut [f64]) {
        match self.shape() {
            Shape::Point => write4(out, ZERO),
            Shape::Segment { axis, half } => {
                let mut m = ZERO;
                if y[axis].abs() <= half {
                    m[3 * axis] = 1.0;
                }
                write4(out, m);
            }
            Shape::Proper { ax, s, ah } => {
                if Self::proper_outside(ax, y) {
                    let o = Self::proper_project_outside(ax, s, ah, y);
                    write4(out, rank_one(o.mu, [-o.normal[1], o.normal[0]]));
                } else {
                    write4(out, IDENTITY);
                }
            }
        }
    }

    fn is_outside(&self, y: &[f64]) -> bool {
        match self.shape() {
            Shape::Point => y[0] != 0.0 || y[1] != 0.0,
            Shape::Segment { axis, half } => y[1 - axis] != 0.0 || y[axis].abs() > half,
            Shape::Proper { ax, .. } => Self::proper_outside(ax, y),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The tangential set of one pair

/// The tangential set of one contact pair: a disc (isotropic Tresca) or an ellipse
/// (orthotropic). Static dispatch for the product set `Λ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TangentSet {
    Disc(Disc),
    Ellipse(Ellipse),
}

impl From<Disc> for TangentSet {
    fn from(d: Disc) -> Self {
        TangentSet::Disc(d)
    }
}

impl From<Ellipse> for TangentSet {
    fn from(e: Ellipse) -> Self {
        TangentSet::Ellipse(e)
    }
}

impl TangentSet {
    /// See [`Disc::boundary_tangent`], [`Ellipse::boundary_tangent`].
    #[inline]
    pub fn boundary_tangent(&self, x: &[f64]) -> [f64; 2] {
        match self {
            TangentSet::Disc(s) => s.boundary_tangent(x),
            TangentSet::Ellipse(s) => s.boundary_tangent(x),
        }
    }

    /// See [`Disc::curvature`], [`Ellipse::curvature`].
    #[inline]
    pub fn curvature(&self, x: &[f64]) -> f64 {
        match self {
            TangentSet::Disc(s) => s.curvature(x),
            TangentSet::Ellipse(s) => s.curvature(x),
        }
    }

    /// See [`BoundaryFrame`]; `None` for y in the set.
    #[inline]
    pub fn frame(&self, y: &[f64]) -> Option<BoundaryFrame> {
        match self {
            TangentSet::Disc(s) => s.frame(y),
            TangentSet::Ellipse(s) => s.frame(y),
        }
    }
}

impl ConvexSet for TangentSet {
    #[inline]
    fn dim(&self) -> usize {
        2
    }

    #[inline]
    fn project(&self, y: &[f64], out: &mut [f64]) {
        match self {
            TangentSet::Disc(s) => s.project(y, out),
            TangentSet::Ellipse(s) => s.project(y, out),
        }
    }

    #[inline]
    fn contains(&self, x: &[f64], tol: f64) -> bool {
        match self {
            TangentSet::Disc(s) => s.contains(x, tol),
            TangentSet::Ellipse(s) => s.contains(x, tol),
        }
    }

    #[inline]
    fn max_step(&self, x: &[f64], d: &[f64]) -> f64 {
        match self {
            TangentSet::Disc(s) => s.max_step(x, d),
            TangentSet::Ellipse(s) => s.max_step(x, d),
        }
    }

    #[inline]
    fn slant(&self, y: &[f64], out: &mut [f64]) {
        match self {
            TangentSet::Disc(s) => s.slant(y, out),
            TangentSet::Ellipse(s) => s.slant(y, out),
        }
    }

    #[inline]
    fn is_outside(&self, y: &[f64]) -> bool {
        match self {
            TangentSet::Disc(s) => s.is_outside(y),
            TangentSet::Ellipse(s) => s.is_outside(y),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Deterministic LCG (Knuth's MMIX constants), uniform in [0, 1).
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn sym(&mut self) -> f64 {
            2.0 * self.next() - 1.0
        }
        fn angle(&mut self) -> f64 {
            2.0 * PI * self.next()
        }
    }

    fn norm(v: [f64; 2]) -> f64 {
        v[0].hypot(v[1])
    }

    fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
        [a[0] - b[0], a[1] - b[1]]
    }

    fn proj(set: &impl ConvexSet, y: [f64; 2]) -> [f64; 2] {
        let mut x = [0.0; 2];
        set.project(&y, &mut x);
        x
    }

    fn slant(set: &impl ConvexSet, y: [f64; 2]) -> [f64; 4] {
        let mut j = [0.0; 4];
        set.slant(&y, &mut j);
        j
    }

    /// Test points for the set with semi-axes (a, b) (a disc: a = b): inside, near the boundary
    /// on both sides, uniform in a box, on and near the axes, and far away.
    fn points(a: f64, b: f64, rng: &mut Lcg) -> Vec<[f64; 2]> {
        let s = if a.max(b) > 0.0 { a.max(b) } else { 1.0 };
        let mut v = Vec::new();
        for _ in 0..120 {
            v.push([3.0 * s * rng.sym(), 3.0 * s * rng.sym()]);
        }
        for _ in 0..60 {
            let (t, r) = (rng.angle(), rng.next());
            v.push([r * a * t.cos(), r * b * t.sin()]);
        }
        for k in 0..60 {
            let t = rng.angle();
            let f = 1.0 + if k % 2 == 0 { 1.0 } else { -1.0 } * 10f64.powi(-(3 + k % 10));
            v.push([f * a * t.cos(), f * b * t.sin()]);
        }
        for &t in &[0.0, 0.3, 0.999, 1.0, 1.0 + 1e-9, 1.5, 3.0, 1e3] {
            for &sg in &[1.0, -1.0] {
                v.push([sg * t * a, 0.0]);
                v.push([0.0, sg * t * b]);
                v.push([sg * t * s, 0.0]);
                v.push([0.0, sg * t * s]);
                v.push([sg * t * s, 1e-9 * s]);
                v.push([1e-12 * s, sg * t * s]);
            }
        }
        for k in 1..=12 {
            let t = rng.angle();
            let r = 10f64.powi(k) * s;
            v.push([r * t.cos(), r * t.sin()]);
        }
        v
    }

    const NS: usize = 100_000;

    /// Brute-force distance from y to the ellipse (a, b) (or disc, segment, point): minimum over
    /// NS boundary samples, refined by golden-section search on the angle (in units scaled by
    /// max(a, b), to avoid overflow). Zero inside a proper ellipse.
    fn brute_distance(a: f64, b: f64, y: [f64; 2], cs: &[(f64, f64)]) -> f64 {
        let s = if a.max(b) > 0.0 { a.max(b) } else { 1.0 };
        let (ah, bh) = (a / s, b / s);
        let yh = [y[0] / s, y[1] / s];
        if ah > 0.0 && bh > 0.0 && (yh[0] / ah).hypot(yh[1] / bh) <= 1.0 {
            return 0.0;
        }
        let d2 = |c: f64, sn: f64| (yh[0] - ah * c).powi(2) + (yh[1] - bh * sn).powi(2);
        let mut best = (f64::INFINITY, 0usize);
        for (j, &(c, sn)) in cs.iter().enumerate() {
            let d = d2(c, sn);
            if d < best.0 {
                best = (d, j);
            }
        }
        let h = 2.0 * PI / NS as f64;
        let th = best.1 as f64 * h;
        let f = |t: f64| d2(t.cos(), t.sin());
        let (mut lo, mut hi) = (th - 1.5 * h, th + 1.5 * h);
        let gr = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..120 {
            let m1 = hi - gr * (hi - lo);
            let m2 = lo + gr * (hi - lo);
            if f(m1) < f(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        best.0.min(f(0.5 * (lo + hi))).sqrt() * s
    }

    fn samples() -> Vec<(f64, f64)> {
        (0..NS)
            .map(|j| {
                let t = 2.0 * PI * j as f64 / NS as f64;
                (t.cos(), t.sin())
            })
            .collect()
    }

    /// Kind of the tangent set, for the checks that depend on it.
    fn is_proper(a: f64, b: f64) -> bool {
        a.min(b) > DEGENERATE_RATIO * a.max(b)
    }

    /// Every check except finite differences, for one tangent set with semi-axes (a, b).
    fn check_tangent_set(set: TangentSet, a: f64, b: f64, seed: u64, cs: &[(f64, f64)]) {
        let mut rng = Lcg(seed);
        let s = if a.max(b) > 0.0 { a.max(b) } else { 1.0 };
        let proper = is_proper(a, b);
        let ys = points(a, b, &mut rng);
        for &y in &ys {
            let x = proj(&set, y);
            let ny = norm(y);
            let e = sub(y, x);
            let dp = norm(e);
            let db = brute_distance(a, b, y, cs);
            let tol = 1e-14 * (s + ny);
            assert!(dp <= db + tol, "{set:?} y={y:?}: |y-P(y)|={dp:e} > brute {db:e}");
            assert!(db <= dp + 1e-9 * (s + ny), "{set:?} y={y:?}: brute {db:e} << {dp:e}");
            assert!(set.contains(&x, 1e-12 * s), "{set:?} y={y:?}: P(y)={x:?} not in set");
            let outside = set.is_outside(&y);
            if !outside {
                assert_eq!(x, y, "{set:?}: inside point moved");
            } else if proper {
                let q = (x[0] / a).hypot(x[1] / b);
                assert!((q - 1.0).abs() <= 1e-12, "{set:?} y={y:?}: P(y) off boundary {q}");
            }
            // Idempotence.
            let xx = proj(&set, x);
            assert!(norm(sub(xx, x)) <= 1e-14 * s, "{set:?} y={y:?}: P(P(y)) != P(y)");
            // Variational inequality (y − x)·(z − x) ≤ 0 for z in the set (boundary samples).
            for &(c, sn) in cs.iter().step_by(97) {
                let z = [a * c, b * sn];
                let vi = (e[0] / s) * ((z[0] - x[0]) / s) + (e[1] / s) * ((z[1] - x[1]) / s);
                assert!(vi <= 1e-12 * (1.0 + ny / s), "{set:?} y={y:?}: VI {vi:e}");
            }
            if outside && proper && dp > 1e-6 * s {
                // y − x parallel to the constraint's gradient (x₁/a², x₂/b²) (scaled units).
                let g = [x[0] / s / (a / s).powi(2), x[1] / s / (b / s).powi(2)];
                let (gn, en) = (norm(g), dp);
                let cross = (e[0] * g[1] - e[1] * g[0]) / (gn * en);
                let dot = (e[0] * g[0] + e[1] * g[1]) / (gn * en);
                assert!(cross.abs() <= 1e-12 + 1e-15 * ny / dp, "{set:?} y={y:?}: cross {cross:e}");
                assert!(dot > 0.0, "{set:?} y={y:?}: inward normal");
            }
            // Frame and slant consistency.
            match set.frame(&y) {
                None => assert!(!outside),
                Some(f) => {
                    assert!(outside);
                    assert_eq!(f.point, x);
                    let en = norm(e);
                    assert!((f.distance - en).abs() <= 1e-10 * en + 1e-14 * (s + ny), "{set:?} y={y:?}: distance {} vs {en}", f.distance);
                    assert!((norm(f.normal) - 1.0).abs() < 1e-15);
                    assert!(f.tangent[0] * f.normal[0] + f.tangent[1] * f.normal[1] == 0.0);
                    if en > 1e-6 * s {
                        let c = (e[0] * f.normal[1] - e[1] * f.normal[0]) / en;
                        assert!(c.abs() <= 1e-12 + 1e-15 * ny / en, "{set:?} y={y:?}: normal");
                    }
                    assert_eq!(f.slant(), slant(&set, y), "{set:?} y={y:?}");
                    let mu2 = 1.0 / (1.0 + f.curvature * f.distance);
                    assert!((f.mu - mu2).abs() <= 1e-12 * f.mu.max(mu2) + 1e-300, "{set:?} y={y:?}: mu {} vs 1/(1+κd) {mu2}", f.mu);
                    assert!((0.0..=1.0).contains(&f.mu));
                    if proper {
                        let k = set.curvature(&x);
                        assert!((k - f.curvature).abs() <= 1e-12 * k, "{set:?} y={y:?}: κ");
                    }
                }
            }
            let j = slant(&set, y);
            assert!(j.iter().all(|v| v.is_finite()) && j[1] == j[2], "{set:?}: slant {j:?}");
        }
        check_max_step(set, a, b, &mut rng, &ys);
    }

    fn check_max_step(set: TangentSet, a: f64, b: f64, rng: &mut Lcg, ys: &[[f64; 2]]) {
        let s = if a.max(b) > 0.0 { a.max(b) } else { 1.0 };
        let proper = is_proper(a, b);
        assert_eq!(set.max_step(&[0.0, 0.0], &[0.0, 0.0]), f64::INFINITY);
        for (k, &y) in ys.iter().enumerate() {
            // A point in the set: P(y), or strictly inside.
            let strict = k % 2 == 0;
            let mut x = proj(&set, y);
            if strict {
                x = [0.9 * x[0], 0.9 * x[1]];
            }
            let mag = 10f64.powi((k % 7) as i32 - 3);
            let t = rng.angle();
            let d = match k % 5 {
                0 => [mag, 0.0],
                1 => [0.0, -mag],
                _ => [mag * t.cos(), mag * t.sin()],
            };
            let alpha = set.max_step(&x, &d);
            assert!(alpha >= 0.0 && alpha.is_finite(), "{set:?} x={x:?} d={d:?}: {alpha}");
            let at = |al: f64| [x[0] - al * d[0], x[1] - al * d[1]];
            assert!(set.contains(&at(alpha), 1e-12 * s), "{set:?} x={x:?} d={d:?}: {alpha}");
            if alpha > 0.0 {
                assert!(set.contains(&at(0.5 * alpha), 1e-12 * s));
            }
            let scale = s / norm(d);
            if alpha > 1e-6 * scale {
                assert!(set.is_outside(&at(alpha * (1.0 + 1e-9) + 1e-12 * scale)));
                if proper {
                    let q = (at(alpha)[0] / a).hypot(at(alpha)[1] / b);
                    assert!((q - 1.0).abs() <= 1e-12, "{set:?}: x − αd off boundary ({q})");
                }
            }
            if strict && proper {
                // Bisection along the ray.
                let mut hi = scale;
                while !set.is_outside(&at(hi)) {
                    hi *= 2.0;
                }
                let mut lo = 0.0;
                for _ in 0..200 {
                    let m = 0.5 * (lo + hi);
                    if set.is_outside(&at(m)) {
                        hi = m;
                    } else {
                        lo = m;
                    }
                }
                assert!((alpha - lo).abs() <= 1e-10 * lo, "{set:?} x={x:?} d={d:?}: max_step {alpha:e} vs bisection {lo:e}");
            }
        }
    }

    /// Sets tested against brute force: (a, b) and the scale factor.
    fn ellipses() -> Vec<(f64, f64)> {
        let base = [
            (1.0, 1.0),
            (3.0, 1.0),
            (1.0, 3.0),
            (100.0, 1.0),
            (1.0, 100.0),
            (1e4, 1.0),
            (1.0, 1e4),
            (1.0, 1e-6),
            (2.0, 0.0),
            (0.0, 2.0),
            (0.0, 0.0),
            (1.0, 1e-101),
        ];
        let mut v: Vec<(f64, f64)> = base.to_vec();
        for &f in &[1e-150, 1e150, 0.37] {
            for &(a, b) in &[(3.0, 1.0), (1e4, 1.0), (2.0, 0.0), (1.0, 1.0)] {
                v.push((a * f, b * f));
            }
        }
        v
    }

    #[test]
    fn ellipse_against_brute_force() {
        let cs = samples();
        for (i, (a, b)) in ellipses().into_iter().enumerate() {
            check_tangent_set(Ellipse::new(a, b).into(), a, b, 17 + i as u64, &cs);
        }
    }

    #[test]
    fn disc_against_brute_force() {
        let cs = samples();
        for (i, &g) in [1.0, 0.37, 0.09, 1e-150, 1e150, 0.0].iter().enumerate() {
            check_tangent_set(Disc::new(g).into(), g, g, 5 + i as u64, &cs);
        }
    }

    /// Central differences with one Richardson extrapolation (error O(h⁴)).
    fn fd_jacobian(set: &impl ConvexSet, y: [f64; 2], h: f64) -> [f64; 4] {
        let mut j = [0.0; 4];
        for c in 0..2 {
            let diff = |h: f64| {
                let mut yp = y;
                let mut ym = y;
                yp[c] += h;
                ym[c] -= h;
                let (p, m) = (proj(set, yp), proj(set, ym));
                [(p[0] - m[0]) / (2.0 * h), (p[1] - m[1]) / (2.0 * h)]
            };
            let (d1, d2) = (diff(h), diff(0.5 * h));
            for r in 0..2 {
                j[2 * r + c] = (4.0 * d2[r] - d1[r]) / 3.0;
            }
        }
        j
    }

    fn check_slant_fd(set: TangentSet, a: f64, b: f64, seed: u64) -> usize {
        let mut rng = Lcg(seed);
        let s = if a.max(b) > 0.0 { a.max(b) } else { 1.0 };
        let mut checked = 0;
        for y in points(a, b, &mut rng) {
            let ny = norm(y);
            let (h, away) = match set.frame(&y) {
                // J varies on the scale distance + radius of curvature (or faster, where the
                // curvature varies; the step is refined below).
                Some(f) => (1e-3 * f.distance.min(1.0 / f.curvature), f.distance > 1e-4 * s),
                None => {
                    let m = a.min(b);
                    let q = if m > 0.0 { (y[0] / a).hypot(y[1] / b) } else { 1.0 };
                    (1e-3 * m, q < 0.5)
                }
            };
            if !away || !(h > 0.0) {
                continue;
            }
            // Refine h until two Richardson estimates agree (or rounding dominates).
            let mut h = h;
            let rounding = |h: f64| 20.0 * EPS * (s + ny) / h;
            for _ in 0..20 {
                let (j1, j2) = (fd_jacobian(&set, y, h), fd_jacobian(&set, y, 0.25 * h));
                let jm = j2.iter().fold(0f64, |m, v| m.max(v.abs()));
                let d = j1.iter().zip(&j2).fold(0f64, |m, (p, q)| m.max((p - q).abs()));
                if d <= 1e-8 * jm + rounding(0.25 * h) {
                    break;
                }
                h *= 0.25;
            }
            let j = slant(&set, y);
            let jf = fd_jacobian(&set, y, h);
            let jmax = j.iter().fold(0f64, |m, v| m.max(v.abs()));
            let err = j.iter().zip(&jf).fold(0f64, |m, (p, q)| m.max((p - q).abs()));
            // Truncation ~1e-12·‖J‖; rounding ~eps·(s + |y|)/h.
            let tol = 1e-6 * jmax + rounding(h);
            assert!(err <= tol, "{set:?} y={y:?}: slant {j:?} vs FD {jf:?} (err {err:e})");
            checked += 1;
        }
        checked
    }

    #[test]
    fn slant_against_finite_differences() {
        let mut n = 0;
        for (i, (a, b)) in ellipses().into_iter().enumerate() {
            n += check_slant_fd(Ellipse::new(a, b).into(), a, b, 100 + i as u64);
        }
        for (i, &g) in [1.0, 0.09, 1e-150, 1e150].iter().enumerate() {
            n += check_slant_fd(Disc::new(g).into(), g, g, 200 + i as u64);
        }
        assert!(n > 3000, "only {n} points checked");
    }

    #[test]
    fn ellipse_with_equal_axes_is_the_disc() {
        let mut rng = Lcg(3);
        for &g in &[1.0, 0.09, 7.5, 1e-150, 1e150] {
            let (e, d) = (Ellipse::new(g, g), Disc::new(g));
            for y in points(g, g, &mut rng) {
                let (xe, xd) = (proj(&e, y), proj(&d, y));
                assert!(norm(sub(xe, xd)) <= 1e-14 * g, "g={g} y={y:?}: {xe:?} vs {xd:?}");
                let (je, jd) = (slant(&e, y), slant(&d, y));
                for k in 0..4 {
                    assert!((je[k] - jd[k]).abs() <= 1e-14, "g={g} y={y:?}: {je:?} vs {jd:?}");
                }
                if (norm(y) - g).abs() > 4.0 * EPS * g {
                    assert_eq!(e.is_outside(&y), d.is_outside(&y));
                }
                if let (Some(fe), Some(fd)) = (e.frame(&y), d.frame(&y)) {
                    assert!((fe.mu - fd.mu).abs() <= 1e-14);
                    assert!((fe.curvature - fd.curvature).abs() <= 1e-14 * fd.curvature);
                    assert!((fe.distance - fd.distance).abs() <= 1e-14 * (g + norm(y)));
                }
            }
        }
    }

    #[test]
    fn ellipse_newton_is_fast_and_scale_covariant() {
        let mut rng = Lcg(11);
        let mut worst = (0, 0.0, 0.0, [0.0; 2]);
        let mut sets = ellipses();
        sets.extend([(1.0, 1e-8), (1.0, 1e-20), (1.0, 1e-50), (1.0, 1e-99), (1e-99, 1.0)]);
        for (a, b) in sets {
            let e = Ellipse::new(a, b);
            let mut ys = points(a, b, &mut rng);
            ys.extend(vertex_points(a, b));
            for y in ys {
                let it = e.newton_iters(&y);
                if it > worst.0 {
                    worst = (it, a, b, y);
                }
                // The projection is on the boundary, and y − x is along the normal x_k/a_k².
                let x = proj(&e, y);
                if is_proper(a, b) && e.is_outside(&y) {
                    let q = (x[0] / a).hypot(x[1] / b);
                    assert!((q - 1.0).abs() <= 1e-14, "({a}, {b}) y={y:?}: {q}");
                    let f = e.frame(&y).unwrap();
                    let g = [x[0] / a / (a / a.max(b)), x[1] / b / (b / a.max(b))];
                    let c = (f.normal[0] * g[1] - f.normal[1] * g[0]) / norm(g);
                    assert!(c.abs() <= 1e-13, "({a}, {b}) y={y:?}: normal off by {c:e}");
                }
                if is_proper(a, b) && e.is_outside(&y) {
                    // y − x (by subtraction) along the normal at x.
                    let s = a.max(b);
                    let ed = [(y[0] - x[0]) / s, (y[1] - x[1]) / s];
                    let g = [x[0] / a / (a / s), x[1] / b / (b / s)];
                    let (en, gn) = (norm(ed), norm(g));
                    if en > 1e-6 {
                        let c = (ed[0] * g[1] - ed[1] * g[0]) / (en * gn);
                        let tol = 1e-12 + 1e-15 * norm(y) / s / en;
                        assert!(c.abs() <= tol, "({a}, {b}) y={y:?}: y − x off normal {c:e}");
                    }
                }
                // P_{cE}(c y) = c P_E(y), c a power of two (exact) or not.
                for &c in &[0.5f64.powi(40), 1e-3, 7.0] {
                    let ec = Ellipse::new(c * a, c * b);
                    let xc = proj(&ec, [c * y[0], c * y[1]]);
                    let s = a.max(b).max(1e-300);
                    assert!(norm(sub(xc, [c * x[0], c * x[1]])) <= 1e-14 * c * s);
                }
            }
        }
        assert!(worst.0 <= 6, "Newton needed {worst:?} steps");
    }

    /// Points near the major vertex of thin ellipses, where a plain Newton iteration from below
    /// creeps.
    fn vertex_points(a: f64, b: f64) -> Vec<[f64; 2]> {
        let mut v = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                let d1 = 10f64.powf(-16.0 + 0.45 * i as f64);
                let d2 = 10f64.powf(-16.0 + 0.45 * j as f64);
                v.push([a * (1.0 + d1), b * d2]);
                v.push([a * (1.0 - d1), b * (1.0 + d2)]);
                v.push([a * d1, b * (1.0 + d2)]);
            }
        }
        v
    }

    // Cost per call (`cargo test --release --lib qp::sets::tests::timing -- --ignored
    // --nocapture`): about 8 ns for a disc, 70–90 ns for an ellipse (2/3 of the points outside).

    /// Random ellipses (axis ratio up to 1e8, size 1e-100…1e100) and points at all distances:
    /// the projection satisfies the optimality conditions that characterize it (on the boundary,
    /// y − x along the outward normal), in few Newton steps; slant = frame's μ t tᵀ, μ ≤ 1.
    #[test]
    fn random_ellipses_optimality() {
        let mut rng = Lcg(2024);
        let mut worst = 0;
        for _ in 0..200_000 {
            let size = 10f64.powf(200.0 * rng.next() - 100.0);
            let ratio = 10f64.powf(8.0 * rng.next());
            let (a, b) = if rng.next() < 0.5 { (size, size / ratio) } else { (size / ratio, size) };
            let e = Ellipse::new(a, b);
            let t = rng.angle();
            let f = match (rng.next() * 4.0) as u32 {
                0 => 1.0 + 10f64.powf(-15.0 * rng.next()),
                1 => 10f64.powf(12.0 * rng.next()),
                2 => 1.0 + 1e-3 * rng.next(),
                _ => 2.0 * rng.next(),
            };
            let mut y = [f * a * t.cos(), f * b * t.sin()];
            if rng.next() < 0.1 {
                y[(rng.next() * 2.0) as usize] = 0.0;
            }
            if !e.is_outside(&y) {
                assert_eq!(proj(&e, y), y);
                continue;
            }
            worst = worst.max(e.newton_iters(&y));
            let x = proj(&e, y);
            let q = (x[0] / a).hypot(x[1] / b);
            assert!((q - 1.0).abs() <= 4.0 * EPS, "({a:e}, {b:e}) y={y:?}: off boundary {q}");
            let s = a.max(b);
            let ed = [(y[0] - x[0]) / s, (y[1] - x[1]) / s];
            let g = [x[0] / a / (a / s), x[1] / b / (b / s)];
            let (en, gn) = (norm(ed), norm(g));
            if en > 1e-8 {
                let c = (ed[0] * g[1] - ed[1] * g[0]) / (en * gn);
                let dot = (ed[0] * g[0] + ed[1] * g[1]) / (en * gn);
                let tol = 1e-12 + 4.0 * EPS * norm(y) / s / en;
                assert!(c.abs() <= tol && dot > 0.0, "({a:e}, {b:e}) y={y:?}: normal {c:e}");
            }
            let fr = e.frame(&y).unwrap();
            assert_eq!(fr.slant(), slant(&e, y));
            assert!(fr.mu >= 0.0 && fr.mu <= 1.0 && fr.distance >= 0.0);
        }
        assert!(worst <= 6, "Newton needed {worst} steps");
    }

    #[test]
    fn thin_ellipse_tends_to_the_segment() {
        let mut rng = Lcg(23);
        let (thin, seg) = (Ellipse::new(1.0, 1e-99), Ellipse::new(1.0, 1e-101));
        let flat = Ellipse::new(1.0, 0.0);
        for y in points(1.0, 1.0, &mut rng) {
            let x = proj(&thin, y);
            assert!(norm(sub(x, proj(&seg, y))) <= 1e-15 + 1e-98, "y={y:?}");
            assert_eq!(proj(&seg, y), proj(&flat, y));
            assert!((x[0] / 1.0).hypot(x[1] / 1e-99) <= 1.0 + 1e-12);
        }
    }

    #[test]
    fn boundary_tangent_and_curvature() {
        for &(a, b) in &[(1.0, 1.0), (3.0, 1.0), (1.0, 100.0), (1e4, 1.0), (2e-150, 1e-150)] {
            let set = TangentSet::Ellipse(Ellipse::new(a, b));
            for k in 0..1000 {
                let t = 2.0 * PI * k as f64 / 1000.0 + 0.1;
                let x = [a * t.cos(), b * t.sin()];
                // Parametrization derivatives: x' = (−a sin, b cos), x'' = −x.
                let d1 = [-a * t.sin(), b * t.cos()];
                let sp = norm(d1);
                let tt = set.boundary_tangent(&x);
                assert!(norm(sub(tt, [d1[0] / sp, d1[1] / sp])) <= 1e-14, "{a} {b} {t}");
                let kappa = (d1[0] * (-x[1]) - d1[1] * (-x[0])).abs() / sp.powi(3);
                let k2 = set.curvature(&x);
                assert!((k2 - kappa).abs() <= 1e-12 * kappa, "{a} {b} {t}: {k2} vs {kappa}");
            }
        }
        let d = TangentSet::Disc(Disc::new(2.0));
        assert_eq!(d.boundary_tangent(&[2.0, 0.0]), [0.0, 1.0]);
        assert_eq!(d.curvature(&[2.0, 0.0]), 0.5);
        let seg = Ellipse::new(2.0, 0.0);
        assert_eq!(seg.boundary_tangent(&[1.0, 0.0]), [1.0, 0.0]);
        assert_eq!(seg.curvature(&[1.0, 0.0]), 0.0);
        assert_eq!(seg.curvature(&[2.0, 0.0]), f64::INFINITY);
        assert_eq!(Ellipse::new(3.0, 1.0).boundary_tangent(&[0.0, 0.0]), [0.0, 1.0]);
    }

    #[test]
    fn degenerate_sets() {
        // Segment [−2, 2] × {0}.
        let seg = Ellipse::new(2.0, 0.0);
        assert_eq!(proj(&seg, [1.0, 5.0]), [1.0, 0.0]);
        assert_eq!(proj(&seg, [-7.0, 5.0]), [-2.0, 0.0]);
        assert_eq!(slant(&seg, [1.0, 5.0]), [1.0, 0.0, 0.0, 0.0]);
        assert_eq!(slant(&seg, [1.0, 0.0]), [1.0, 0.0, 0.0, 0.0]);
        assert_eq!(slant(&seg, [3.0, 0.0]), [0.0; 4]);
        assert!(!seg.is_outside(&[1.0, 0.0]) && seg.is_outside(&[1.0, 1e-300]));
        assert_eq!(seg.max_step(&[1.0, 0.0], &[1.0, 0.0]), 3.0);
        assert_eq!(seg.max_step(&[1.0, 0.0], &[-2.0, 0.0]), 0.5);
        assert_eq!(seg.max_step(&[1.0, 0.0], &[1.0, 1.0]), 0.0);
        let seg_y = Ellipse::new(0.0, 2.0);
        assert_eq!(proj(&seg_y, [5.0, 1.0]), [0.0, 1.0]);
        assert_eq!(slant(&seg_y, [5.0, 1.0]), [0.0, 0.0, 0.0, 1.0]);
        // Point {0}: the disc of radius 0 and the ellipse (0, 0).
        for set in [TangentSet::Disc(Disc::new(0.0)), TangentSet::Ellipse(Ellipse::new(0.0, 0.0))] {
            assert_eq!(proj(&set, [3.0, -4.0]), [0.0, 0.0]);
            assert_eq!(slant(&set, [3.0, -4.0]), [0.0; 4]);
            assert_eq!(slant(&set, [0.0, 0.0]), [0.0; 4]);
            assert_eq!(set.max_step(&[0.0, 0.0], &[1.0, 2.0]), 0.0);
            assert!(!set.is_outside(&[0.0, 0.0]) && set.is_outside(&[1e-300, 0.0]));
            let f = set.frame(&[3.0, -4.0]).unwrap();
            assert_eq!((f.distance, f.mu, f.curvature), (5.0, 0.0, f64::INFINITY));
            assert!(set.frame(&[0.0, 0.0]).is_none());
        }
    }

    #[test]
    fn half_line() {
        let h = HalfLine;
        assert_eq!(h.dim(), 1);
        let mut rng = Lcg(99);
        let mut ys: Vec<f64> = (0..500).map(|_| 10f64.powf(6.0 * rng.sym()) * rng.sym()).collect();
        ys.extend([0.0, -0.0, 1e-300, -1e-300, 1e300, -1e300]);
        let grid: Vec<f64> = (0..NS).map(|j| j as f64 / NS as f64).collect();
        for &y in &ys {
            let mut x = [0.0];
            h.project(&[y], &mut x);
            let x = x[0];
            // Brute force over a dense grid of [0, 2|y|] (plus 0).
            let r = 2.0 * y.abs();
            let db = grid.iter().fold(y.abs(), |m, &g| m.min((y - g * r).abs()));
            assert!((y - x).abs() <= db + 1e-15 * y.abs(), "y={y}");
            assert!(h.contains(&[x], 0.0) && x >= 0.0);
            assert_eq!(h.is_outside(&[y]), y < 0.0);
            let mut xx = [0.0];
            h.project(&[x], &mut xx);
            assert_eq!(xx[0], x);
            // (y − x)(z − x) ≤ 0 for z ≥ 0: y − x ≤ 0, and = 0 unless x = 0.
            assert!(y - x <= 0.0 && (x == 0.0 || y == x));
            // Slant vs central differences away from 0.
            let mut j = [0.0];
            h.slant(&[y], &mut j);
            assert_eq!(j[0], if y >= 0.0 { 1.0 } else { 0.0 });
            if y != 0.0 {
                let e = 1e-3 * y.abs();
                let (mut p, mut m) = ([0.0], [0.0]);
                h.project(&[y + e], &mut p);
                h.project(&[y - e], &mut m);
                assert!(((p[0] - m[0]) / (2.0 * e) - j[0]).abs() <= 1e-12);
            }
            // max_step from x ≥ 0.
            for &d in &[y, -y, 0.0, 1.0, -1.0, 1e-8] {
                let al = h.max_step(&[x], &[d]);
                if d <= 0.0 {
                    assert_eq!(al, f64::INFINITY);
                } else if x == 0.0 {
                    assert_eq!(al, 0.0);
                } else if al > 1e200 {
                    assert!((al / x - 1.0 / d).abs() <= 1e-15 / d);
                } else {
                    assert!(al >= 0.0 && (x - al * d).abs() <= 1e-15 * x);
                    // Bisection on the ray.
                    let (mut lo, mut hi) = (0.0, 1.0);
                    while x - hi * d >= 0.0 {
                        hi *= 2.0;
                    }
                    for _ in 0..2000 {
                        let m = 0.5 * (lo + hi);
                        if m == lo || m == hi {
                            break;
                        }
                        if x - m * d >= 0.0 {
                            lo = m;
                        } else {
                            hi = m;
                        }
                    }
                    assert!((al - lo).abs() <= 1e-14 * lo.max(1e-300), "x={x} d={d}");
                }
            }
        }
        assert!(h.contains(&[-1e-10], 1e-9) && !h.contains(&[-1e-8], 1e-9));
        assert_eq!(h.max_step(&[-1e-20], &[1.0]), 0.0);
    }

    #[test]
    fn nan_input_terminates() {
        let nan = f64::NAN;
        let sets = [
            TangentSet::Disc(Disc::new(1.0)),
            TangentSet::Ellipse(Ellipse::new(3.0, 1.0)),
            TangentSet::Ellipse(Ellipse::new(3.0, 0.0)),
            TangentSet::Ellipse(Ellipse::new(0.0, 0.0)),
        ];
        for set in sets {
            for y in [[nan, 0.0], [0.0, nan], [nan, nan], [f64::INFINITY, 1.0]] {
                let _ = proj(&set, y);
                let _ = slant(&set, y);
                let _ = set.frame(&y);
                let _ = set.contains(&y, 0.0);
                let _ = set.max_step(&[0.0, 0.0], &y);
                let _ = set.max_step(&y, &[1.0, 0.0]);
                let _ = set.curvature(&y);
                let _ = set.boundary_tangent(&y);
            }
        }
        let mut x = [0.0];
        HalfLine.project(&[nan], &mut x);
        assert!(x[0].is_nan());
        assert!(HalfLine.max_step(&[0.0], &[nan]).is_nan());
    }

    #[test]
    fn tangent_set_delegates() {
        let mut rng = Lcg(5);
        let (d, e) = (Disc::new(0.7), Ellipse::new(0.7, 0.2));
        let (td, te) = (TangentSet::from(d), TangentSet::from(e));
        assert_eq!((td.dim(), te.dim()), (2, 2));
        for y in points(0.7, 0.2, &mut rng) {
            let dir = [rng.sym(), rng.sym()];
            let x = proj(&e, y);
            assert_eq!(proj(&td, y), proj(&d, y));
            assert_eq!(proj(&te, y), x);
            assert_eq!(slant(&td, y), slant(&d, y));
            assert_eq!(slant(&te, y), slant(&e, y));
            assert_eq!(td.is_outside(&y), d.is_outside(&y));
            assert_eq!(te.contains(&y, 1e-3), e.contains(&y, 1e-3));
            assert_eq!(te.max_step(&x, &dir), e.max_step(&x, &dir));
            assert_eq!(td.max_step(&x, &dir), d.max_step(&x, &dir));
            assert_eq!(te.frame(&y), e.frame(&y));
        }
    }
}
