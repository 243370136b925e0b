//! The slave side's dual (biorthogonal) basis: per slave facet ψᵢ = Σ_j a_ij φ_j with
//! A = D M⁻¹ on the whole facet or, for a partly covered facet, on its covered part; the modified
//! quadratic basis φ̃ = T φ; and the small dense n × n algebra (n ≤ 9) that builds them,
//! including the hand-written Gauss–Jordan inverse (nalgebra is not a dependency).

use super::assemble::fan_points;
use super::clip::{is_convex, polygon_area};
use super::{Facet, Mat, MortarError, Plane, ALPHA, V2, V3};
use crate::fem::facet::{cross, dot, edges, fine_rule, norm, scale, shape, Shape, MAX_NODES};
use crate::mesh::FacetKind;

/// The modified slave basis φ̃ = T φ of Popp et al. (2012): per edge node e between corners
/// a, b: φ̃_a += α φ_e, φ̃_b += α φ_e, φ̃_e = (1 − 2α) φ_e on tri6 and quad8 ([`is_modified`]);
/// identity for linear facets and quad9.
pub(super) fn transformation(kind: FacetKind) -> Mat {
    let mut t = [[0.0; MAX_NODES]; MAX_NODES];
    for (i, row) in t.iter_mut().enumerate().take(kind.len()) {
        row[i] = 1.0;
    }
    if !is_modified(kind) {
        return t;
    }
    for &(e, a, b) in edges(kind) {
        t[a][e] += ALPHA;
        t[b][e] += ALPHA;
        t[e][e] = 1.0 - 2.0 * ALPHA;
    }
    t
}

/// Whether the slave basis is modified (φ̃ = T φ): tri6 and quad8, whose standard D_e has a
/// zero (tri6 corners) or negative (quad8 corners, −1/12 of the area) entry. quad9 keeps the
/// standard dual basis: its ∫ φᵢ are all positive (corners 1/36, edges 1/9, centre 4/9 of the
/// area on a parallelogram), and its dual basis is the tensor product of the 1D quadratic one
/// (Wohlmuth, Popp, Gee, Wall 2012, Comput. Mech. 49; Popp et al. 2012 modify only the bases
/// whose integrals are not positive).
pub(super) fn is_modified(kind: FacetKind) -> bool {
    matches!(kind, FacetKind::Tri6 | FacetKind::Quad8)
}

/// A slave facet with its auxiliary plane and dual basis.
pub(super) struct SlaveFacet {
    pub(super) f: Facet,
    pub(super) plane: Plane,
    /// Dual coefficients of the whole facet: ψᵢ = Σ_j a[i][j] φ_j.
    pub(super) a: Mat,
    /// ∫_e φ̃_j dA (φ̃ = φ for linear facets).
    pub(super) d: [f64; MAX_NODES],
    /// Unit normal at the centre, times the facet area.
    pub(super) weighted_normal: V3,
    /// Area of the projected corner polygon.
    pub(super) plane_area: f64,
}

impl SlaveFacet {
    pub(super) fn new(f: Facet, facet: usize) -> Result<SlaveFacet, MortarError> {
        let bad = MortarError::Degenerate { side: "slave", facet };
        let n0 = f.centre_normal().ok_or(bad.clone())?;
        let plane = Plane::of(&f, n0);
        let poly = plane.polygon(&f);
        if !is_convex(&poly) {
            return Err(bad);
        }
        let (a, d) = dual_coefficients(&f).ok_or(bad)?;
        let weighted_normal = scale(n0, f.area());
        Ok(SlaveFacet { plane_area: polygon_area(&poly), f, plane, a, d, weighted_normal })
    }

    /// ψᵢ = Σ_j a_ij φ_j at a point, from the shape functions there.
    pub(super) fn psi(&self, a: &Mat, s: &Shape) -> [f64; MAX_NODES] {
        let mut psi = [0.0; MAX_NODES];
        let n = self.f.n();
        for (i, p) in psi.iter_mut().enumerate().take(n) {
            *p = (0..n).map(|j| a[i][j] * s.phi[j]).sum();
        }
        psi
    }

    /// Slave area per plane area at a point: |x_ξ × x_η| / |(x_ξ × x_η)·n₀|.
    pub(super) fn jacobian_ratio(&self, s: &Shape) -> f64 {
        let (_, t) = self.f.map(s);
        let j = cross(t[0], t[1]);
        norm(j) / dot(j, self.plane.n).abs()
    }

    /// The dual coefficients for the covered part `segs` of a partly covered facet:
    /// A = D̂ M̂⁻¹ with D̂, M̂ integrated over the segments only, or None when M̂ is singular.
    pub(super) fn partial_dual(&self, segs: &[(usize, Vec<V2>)], id: usize) -> Result<Option<Mat>, MortarError> {
        let mut samples = Vec::new();
        for (master, poly) in segs {
            for (p, w) in fan_points(poly) {
                let fail = MortarError::Projection { slave: id, master: *master, side: "slave" };
                let sh = shape(self.f.kind, self.plane.invert(&self.f, p).ok_or(fail)?);
                let wj = w * self.jacobian_ratio(&sh);
                samples.push((sh, wj));
            }
        }
        let t = transformation(self.f.kind);
        Ok(dual_from(&samples, &t, self.f.n()).map(|(a, _)| a))
    }
}

/// The dual coefficients of a whole facet (in the standard basis, see [`dual_from`]) and
/// D_e = (∫_e φ̃_j dA), or None when M_e is singular.
pub(super) fn dual_coefficients(f: &Facet) -> Option<(Mat, [f64; MAX_NODES])> {
    let samples: Vec<(Shape, f64)> = fine_rule(f.kind).into_iter().map(|(xi, w)| (shape(f.kind, xi), w * norm(f.jacobian(xi)))).collect();
    dual_from(&samples, &transformation(f.kind), f.n())
}

/// From (shape functions, weight) samples of a region: D = diag(∫ φ̃), M = (∫ φ̃ᵢ φ̃_j) with
/// φ̃ = T φ, A = D M⁻¹, so ψᵢ = Σ_j (A T)_ij φ_j; returns A T and the diagonal of D.
fn dual_from(samples: &[(Shape, f64)], t: &Mat, n: usize) -> Option<(Mat, [f64; MAX_NODES])> {
    let (mut m, mut d) = ([[0.0; MAX_NODES]; MAX_NODES], [0.0; MAX_NODES]);
    for (s, w) in samples {
        let b = mat_vec(t, &s.phi, n);
        add_scaled(&mut d, *w, &b[..n]);
        add_outer(&mut m, *w, &b[..n], &b[..n]);
    }
    let a = scale_rows(&invert(m, n)?, &d, n);
    Some((mat_mul(&a, t, n), d))
}

/// T v on the leading n entries.
pub(super) fn mat_vec(t: &Mat, v: &[f64; MAX_NODES], n: usize) -> [f64; MAX_NODES] {
    let mut out = [0.0; MAX_NODES];
    for (o, row) in out.iter_mut().zip(t).take(n) {
        *o = row[..n].iter().zip(&v[..n]).map(|(a, b)| a * b).sum();
    }
    out
}

/// A B on the leading n×n blocks.
fn mat_mul(a: &Mat, b: &Mat, n: usize) -> Mat {
    let mut out = [[0.0; MAX_NODES]; MAX_NODES];
    for (o, arow) in out.iter_mut().zip(a).take(n) {
        for (k, &aik) in arow[..n].iter().enumerate() {
            add_scaled(&mut o[..n], aik, &b[k][..n]);
        }
    }
    out
}

/// d_i += w a_i.
pub(super) fn add_scaled(d: &mut [f64], w: f64, a: &[f64]) {
    for (di, ai) in d.iter_mut().zip(a) {
        *di += w * ai;
    }
}

/// m_ij += w a_i b_j.
pub(super) fn add_outer(m: &mut Mat, w: f64, a: &[f64], b: &[f64]) {
    for (row, ai) in m.iter_mut().zip(a) {
        for (mij, bj) in row.iter_mut().zip(b) {
            *mij += w * ai * bj;
        }
    }
}

/// diag(d) · m on the leading n×n block.
fn scale_rows(m: &Mat, d: &[f64; MAX_NODES], n: usize) -> Mat {
    let mut a = [[0.0; MAX_NODES]; MAX_NODES];
    for i in 0..n {
        for j in 0..n {
            a[i][j] = d[i] * m[i][j];
        }
    }
    a
}

/// Inverse of the leading n×n block (Gauss–Jordan, partial pivoting).
fn invert(mut m: [[f64; MAX_NODES]; MAX_NODES], n: usize) -> Option<[[f64; MAX_NODES]; MAX_NODES]> {
    let mut inv = [[0.0; MAX_NODES]; MAX_NODES];
    for (i, row) in inv.iter_mut().enumerate().take(n) {
        row[i] = 1.0;
    }
    let size = (0..n).map(|i| m[i][i].abs()).fold(0.0, f64::max);
    for c in 0..n {
        let p = (c..n).max_by(|&a, &b| m[a][c].abs().total_cmp(&m[b][c].abs()))?;
        let pivot_ok = m[p][c].abs() > 1e-12 * size;
        if !pivot_ok {
            return None;
        }
        m.swap(c, p);
        inv.swap(c, p);
        let piv = m[c][c];
        for k in 0..n {
            m[c][k] /= piv;
            inv[c][k] /= piv;
        }
        for r in (0..n).filter(|&r| r != c) {
            let f = m[r][c];
            for k in 0..n {
                m[r][k] -= f * m[c][k];
                inv[r][k] -= f * inv[c][k];
            }
        }
    }
    Some(inv)
}
