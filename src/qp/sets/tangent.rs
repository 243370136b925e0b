//! [`TangentSet`]: the tangential set of one contact pair, a [`Disc`] or an [`Ellipse`].

use super::{BoundaryFrame, ConvexSet, Disc, Ellipse};

/// The tangential set of one contact pair: a disc (isotropic Tresca) or an ellipse
/// (orthotropic). Static dispatch for the product set `Λ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TangentSet {
    /// Isotropic Tresca: a disc.
    Disc(Disc),
    /// Orthotropic Tresca: an ellipse.
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
