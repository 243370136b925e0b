//! [`HalfLine`]: `{x ≥ 0}`, the set of a pair's normal multiplier λν,ᵢ.

use super::{nonneg, ConvexSet};

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
