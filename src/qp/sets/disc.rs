//! [`Disc`]: `{‖x‖ ≤ g}`, the isotropic Tresca set.

use super::frame::{rank_one, scale_dir, unit_ball_step, write2, write4, BoundaryFrame, IDENTITY, ZERO};
use super::{nonneg, ConvexSet};

/// `{x ∈ R² : ‖x‖ ≤ radius}`, the isotropic Tresca set (`radius = gᵢ`; a negative radius is
/// read as its absolute value, 0 gives the point set {0}).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disc {
    /// The radius, the slip bound gᵢ.
    pub radius: f64,
}

impl Disc {
    /// The disc of radius `radius`.
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
