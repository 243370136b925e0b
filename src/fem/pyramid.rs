//! The linear pyramid (5-node) kernel on the reference pyramid with base [−1, 1]² at ζ = 0 and
//! apex (0, 0, 1), node order Gmsh's (base 0-1-2-3 counter-clockwise seen from the apex, apex
//! 4). Shape functions: the rational ones of Bedrosian (Int. J. Numer. Meth. Eng. 35, 1992;
//! as libMesh's PYRAMID5) N_a = (1 − ζ + ξ_a ξ)(1 − ζ + η_a η) / (4(1 − ζ)) at the base corners
//! (ξ_a, η_a = ±1), N_4 = ζ: bilinear on the base, linear on the four triangles (conforming
//! with hexahedra and tetrahedra). In the collapsed coordinates a = ξ/(1 − ζ), b = η/(1 − ζ)
//! they are ¼(1 − ζ)(1 + ξ_a a)(1 + η_a b), and their derivatives ∂/∂ξ = ¼ξ_a(1 + η_a b),
//! ∂/∂η = ¼η_a(1 + ξ_a a), ∂/∂ζ = ¼(ξ_a η_a ab − 1) are polynomials in (a, b). Quadrature:
//! the collapsed-hexahedron (Duffy) product rule — 2 × 2 Gauss–Legendre in (a, b) times the
//! 2-point Gauss–Jacobi rule of weight (1 − ζ)² on [0, 1] (Stroud's conical product) — exact
//! for the stiffness of a pyramid with a parallelogram base. Pure functions of the node
//! coordinates.

use super::element::{add_stiffness, physical_gradients, strain, GAUSS2};
use super::material::Lame;

/// The signs (ξ_a, η_a) of the base corners.
const BASE: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// Reference coordinates of the five nodes.
pub const PYR5_REF: [[f64; 3]; 5] = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// The collapsed coordinates (a, b) of `xi` (0 at the apex, where the functions' limit along
/// the axis is taken).
fn collapsed(xi: [f64; 3]) -> (f64, f64) {
    let t = 1.0 - xi[2];
    if t.abs() < 1e-14 {
        (0.0, 0.0)
    } else {
        (xi[0] / t, xi[1] / t)
    }
}

/// Shape functions at `xi`.
pub fn pyr5_shape(xi: [f64; 3]) -> [f64; 5] {
    let (a, b) = collapsed(xi);
    let t = 1.0 - xi[2];
    let mut n = [0.0; 5];
    for (k, s) in BASE.iter().enumerate() {
        n[k] = 0.25 * t * (1.0 + s[0] * a) * (1.0 + s[1] * b);
    }
    n[4] = xi[2];
    n
}

/// Reference derivatives ∂N_a/∂(ξ, η, ζ) at `xi`.
pub fn pyr5_ref_gradients(xi: [f64; 3]) -> [[f64; 3]; 5] {
    let (a, b) = collapsed(xi);
    let mut d = [[0.0; 3]; 5];
    for (k, s) in BASE.iter().enumerate() {
        d[k] = [0.25 * s[0] * (1.0 + s[1] * b), 0.25 * s[1] * (1.0 + s[0] * a), 0.25 * (s[0] * s[1] * a * b - 1.0)];
    }
    d[4] = [0.0, 0.0, 1.0];
    d
}

/// The 2-point Gauss–Jacobi rule on [0, 1] of weight (1 − ζ)²: nodes 1/3 ∓ √10/15 (the roots of
/// ζ² − 2ζ/3 + 1/15, orthogonal to 1 and ζ under that weight), weights 1/6 ± 5/(24√10)
/// (summing to ∫(1 − ζ)² = 1/3).
fn jacobi2() -> [(f64, f64); 2] {
    let r = 10f64.sqrt();
    [(1.0 / 3.0 - r / 15.0, 1.0 / 6.0 + 5.0 / (24.0 * r)), (1.0 / 3.0 + r / 15.0, 1.0 / 6.0 - 5.0 / (24.0 * r))]
}

/// The eight quadrature points and weights (summing to the reference volume 4/3).
pub fn pyr_rule_8() -> [([f64; 3], f64); 8] {
    let jz = jacobi2();
    std::array::from_fn(|q| {
        let (a, b, (z, w)) = (GAUSS2[q % 2], GAUSS2[(q / 2) % 2], jz[q / 4]);
        ([a * (1.0 - z), b * (1.0 - z), z], w)
    })
}

/// Physical gradients and det J at `xi`.
pub fn pyr5_gradients(x: &[[f64; 3]; 5], xi: [f64; 3]) -> ([[f64; 3]; 5], f64) {
    physical_gradients(x, &pyr5_ref_gradients(xi))
}

/// Stiffness (15 × 15, DOF order 3a + i).
pub fn pyr5_stiffness(x: &[[f64; 3]; 5], m: Lame) -> [[f64; 15]; 15] {
    let mut k = [[0.0; 15]; 15];
    for (xi, w) in pyr_rule_8() {
        let (g, det) = pyr5_gradients(x, xi);
        add_stiffness(&g, det * w, m, |r, c, v| k[r][c] += v);
    }
    k
}

/// Smallest det J over the quadrature points and the base corners (at the apex det J depends
/// on the direction it is approached from; the base corners' values bound it for a pyramid
/// whose base is planar).
pub fn pyr5_min_jacobian(x: &[[f64; 3]; 5]) -> f64 {
    pyr_rule_8().iter().map(|p| p.0).chain(PYR5_REF[..4].iter().copied()).map(|xi| pyr5_gradients(x, xi).1).fold(f64::INFINITY, f64::min)
}

/// Strain at `xi` from the nodal displacements.
pub fn pyr5_strain(x: &[[f64; 3]; 5], u: &[[f64; 3]; 5], xi: [f64; 3]) -> [f64; 6] {
    strain(&pyr5_gradients(x, xi).0, u)
}

/// The centre of the reference pyramid (its centroid, ζ = ¼).
pub const PYR5_CENTRE: [f64; 3] = [0.0, 0.0, 0.25];

#[cfg(test)]
#[path = "pyramid_tests.rs"]
mod tests;
