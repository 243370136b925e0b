//! [`BoundaryFrame`], the local boundary geometry at the projection of a point outside a
//! tangent set, and the small 2-D helpers the [`super::Disc`] and the [`super::Ellipse`] share.

use super::nonneg;

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
    pub(super) fn new(point: [f64; 2], normal: [f64; 2], distance: f64, curvature: f64, mu: f64) -> Self {
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
pub(super) fn rank_one(mu: f64, t: [f64; 2]) -> [f64; 4] {
    let off = mu * t[0] * t[1];
    [mu * t[0] * t[0], off, off, mu * t[1] * t[1]]
}

#[inline]
pub(super) fn write2(out: &mut [f64], v: [f64; 2]) {
    out[0] = v[0];
    out[1] = v[1];
}

#[inline]
pub(super) fn write4(out: &mut [f64], m: [f64; 4]) {
    out[..4].copy_from_slice(&m);
}

pub(super) const IDENTITY: [f64; 4] = [1.0, 0.0, 0.0, 1.0];
pub(super) const ZERO: [f64; 4] = [0.0; 4];

/// The largest α ≥ 0 with `‖p − α·q‖ ≤ 1`, for ‖p‖ ≤ 1 (up to rounding) and q ≠ 0 of moderate
/// size: the larger root of `‖q‖²α² − 2(p·q)α + ‖p‖² − 1 = 0`, computed without cancellation
/// (with q normalized first). 0 when p is on or outside the boundary and q points outward.
#[inline]
pub(super) fn unit_ball_step(p: [f64; 2], q: [f64; 2]) -> f64 {
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
pub(super) fn scale_dir(d: &[f64]) -> ([f64; 2], f64) {
    let m = d[0].abs().max(d[1].abs());
    ([d[0] / m, d[1] / m], m)
}
