//! [`Ellipse`] (d = 2): `{(x₁/a)² + (x₂/b)² ≤ 1}` for orthotropic Tresca (semi-axes a along the
//! first, b along the second tangential direction). For y outside, the Euclidean projection is
//! `x_k = a_k² y_k/(a_k² + t)` with `t > 0` the root of the secular equation
//! `Σ_k (a_k y_k/(a_k² + t))² = 1`. It is solved by Newton's method on
//! `φ(t) = 1/‖w(t)‖ − 1`, `w_k = a_k y_k/(a_k² + t)`: φ is increasing and concave (1/‖w‖ is a
//! power mean of order −2 of the affine `a_k² + t`), so Newton from either side lands at or
//! below the root, and started below it climbs monotonically and quadratically (exact in one
//! step for a disc or y on an axis). Start: the largest of the lower bounds `‖a∘y‖ − a_max²`,
//! `a_k|y_k| − a_k²` (from here on `|w_k| ≤ 1`) and, for thin ellipses, a bound from the
//! cubic `(a_min² + t)²t ≈ a_min² y_min² a_max²/4` valid near the major vertex, where Newton
//! would otherwise creep up from `t ≈ a_min²` by a factor ~1.5 per step (18 steps at axis
//! ratio 1e4, 42 at 1e20; with the bound at most 6 at any ratio up to 1e99). Stop when
//! `|‖w‖ − 1| ≤ 2ε` (rounding level); safeguarded by the bracket `[t₀, ‖a∘y‖ − a_min²]`
//! and at most 64 steps (NaN). The result is normalized, `x_k = a_k w_k/‖w‖`, so it lies on
//! the boundary to rounding. Everything runs in variables scaled by `max(a, b)`.
//!
//! The slant derivative outside is the exact Jacobian from implicit differentiation of the
//! secular equation, `ψ°(y) = D − D n nᵀ D/(nᵀ D n)`, `D = diag(a_k²/(a_k² + t))`,
//! `n ∝ x_k/a_k²` the outward normal; in 2-D this is the rank-one `μ·t tᵀ` with t the unit
//! tangent at x and `μ = D₁D₂/(n₁²D₁ + n₂²D₂) = 1/(1 + κ·dist(y))` (κ the boundary's
//! curvature at x). For `a = b = g`, `D = (g/‖y‖)I` and this is `ψ°_g` (both are evaluated
//! as `μ·t tᵀ`: exactly symmetric and rank one, no cancellation in `1 − ŷ₁²`). Inside: `I`.
//! An ellipse whose axis ratio is at most [`DEGENERATE_RATIO`] (e.g. b = 0) is the segment
//! `[−a, a] × {0}` (projection `(clamp(y₁, −a, a), 0)`, slant `e₁e₁ᵀ` for `|y₁| ≤ a`, else
//! 0: on the segment itself the projection is not the identity); a = b = 0 is the point {0}.

use super::frame::{rank_one, scale_dir, unit_ball_step, write2, write4, BoundaryFrame, IDENTITY, ZERO};
use super::{nonneg, ConvexSet, DEGENERATE_RATIO, EPS};

/// Most Newton steps on the secular equation (a handful are needed; this only bounds NaN input).
const MAX_NEWTON: u32 = 64;

/// A point farther than this (relative to the ellipse's size) is projected by the asymptotic
/// formula `x_k = a_k² y_k/‖a∘y‖`, exact to ~1e-300 relative there.
const FAR: f64 = 1e300;

/// `{x ∈ R² : (x₁/a)² + (x₂/b)² ≤ 1}`, the orthotropic Tresca set (semi-axes `a = g₁ᵢ` along the
/// first, `b = g₂ᵢ` along the second tangential direction). Negative semi-axes are read as their
/// absolute values; `a = b` is a disc, an axis ratio ≤ [`DEGENERATE_RATIO`] (e.g. b = 0) a
/// segment, `a = b = 0` the point {0}.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipse {
    /// Semi-axis along the first tangential direction, g₁ᵢ.
    pub a: f64,
    /// Semi-axis along the second tangential direction, g₂ᵢ.
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
    /// The ellipse of semi-axes `a` and `b`.
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
    pub(super) fn newton_iters(&self, y: &[f64]) -> u32 {
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
