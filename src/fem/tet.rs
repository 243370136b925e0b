//! Tetrahedral element kernels, isoparametric on the reference tetrahedron
//! {ξ, η, ζ ≥ 0, ξ + η + ζ ≤ 1} with barycentric L = (1 − ξ − η − ζ, ξ, η, ζ): linear tet4 (one
//! point, exact) and quadratic tet10 (the four-point rule of degree 2: exact for a tet10 with
//! straight edges, whose gradients are linear). Node order Gmsh's: corners 0–3, then the
//! tet10's edge nodes 4:(0,1) 5:(1,2) 6:(2,0) 7:(3,0) 8:(3,2) 9:(3,1). Pure functions of the
//! node coordinates, as the hex8 kernels ([`super::element`]).

use super::element::{add_stiffness, physical_gradients, strain};
use super::material::Lame;

pub use crate::mesh::cell::TET10_EDGES;

/// Reference gradients of the barycentric coordinates L₀…L₃ (∂L/∂ξ).
const DL: [[f64; 3]; 4] = [[-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// The four-point rule of degree 2 on the reference tetrahedron (weights 1/24).
pub fn tet_rule_4() -> [([f64; 3], f64); 4] {
    let (a, b) = (0.585_410_196_624_968_5, 0.138_196_601_125_010_5);
    [([b, b, b], 1.0 / 24.0), ([a, b, b], 1.0 / 24.0), ([b, a, b], 1.0 / 24.0), ([b, b, a], 1.0 / 24.0)]
}

fn barycentric(xi: [f64; 3]) -> [f64; 4] {
    [1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]]
}

/// tet4 shape functions at `xi` (the barycentric coordinates).
pub fn tet4_shape(xi: [f64; 3]) -> [f64; 4] {
    barycentric(xi)
}

/// tet10 shape functions at `xi`: corners L_a(2L_a − 1), edges 4 L_a L_b.
pub fn tet10_shape(xi: [f64; 3]) -> [f64; 10] {
    let l = barycentric(xi);
    let mut n = [0.0; 10];
    for a in 0..4 {
        n[a] = l[a] * (2.0 * l[a] - 1.0);
    }
    for (e, [a, b]) in TET10_EDGES.iter().enumerate() {
        n[4 + e] = 4.0 * l[*a] * l[*b];
    }
    n
}

/// tet10 reference gradients at `xi`.
fn tet10_ref_gradients(xi: [f64; 3]) -> [[f64; 3]; 10] {
    let l = barycentric(xi);
    let mut d = [[0.0; 3]; 10];
    for a in 0..4 {
        d[a] = DL[a].map(|v| (4.0 * l[a] - 1.0) * v);
    }
    for (e, [a, b]) in TET10_EDGES.iter().enumerate() {
        d[4 + e] = std::array::from_fn(|i| 4.0 * (DL[*a][i] * l[*b] + l[*a] * DL[*b][i]));
    }
    d
}

/// tet4 physical gradients (constant) and det J (6 × the volume).
pub fn tet4_gradients(x: &[[f64; 3]; 4]) -> ([[f64; 3]; 4], f64) {
    physical_gradients(x, &DL)
}

/// tet10 physical gradients and det J at `xi`.
pub fn tet10_gradients(x: &[[f64; 3]; 10], xi: [f64; 3]) -> ([[f64; 3]; 10], f64) {
    physical_gradients(x, &tet10_ref_gradients(xi))
}

/// tet4 stiffness (12 × 12, DOF order 3a + i), exact.
pub fn tet4_stiffness(x: &[[f64; 3]; 4], m: Lame) -> [[f64; 12]; 12] {
    let mut k = [[0.0; 12]; 12];
    let (g, det) = tet4_gradients(x);
    add_stiffness(&g, det / 6.0, m, |r, c, v| k[r][c] += v);
    k
}

/// tet10 stiffness (30 × 30, DOF order 3a + i), four-point rule.
pub fn tet10_stiffness(x: &[[f64; 3]; 10], m: Lame) -> [[f64; 30]; 30] {
    let mut k = [[0.0; 30]; 30];
    for (xi, w) in tet_rule_4() {
        let (g, det) = tet10_gradients(x, xi);
        add_stiffness(&g, det * w, m, |r, c, v| k[r][c] += v);
    }
    k
}

/// Smallest det J over the four-point rule and the corners: ≤ 0 means an inverted or
/// degenerate tet10 (for a tet4, det J is constant: [`tet4_gradients`]).
pub fn tet10_min_jacobian(x: &[[f64; 3]; 10]) -> f64 {
    let corners = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    tet_rule_4().iter().map(|p| p.0).chain(corners).map(|xi| tet10_gradients(x, xi).1).fold(f64::INFINITY, f64::min)
}

/// tet4 strain (constant) from the nodal displacements.
pub fn tet4_strain(x: &[[f64; 3]; 4], u: &[[f64; 3]; 4]) -> [f64; 6] {
    strain(&tet4_gradients(x).0, u)
}

/// tet10 strain at `xi` from the nodal displacements.
pub fn tet10_strain(x: &[[f64; 3]; 10], u: &[[f64; 3]; 10], xi: [f64; 3]) -> [f64; 6] {
    strain(&tet10_gradients(x, xi).0, u)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steel() -> Lame {
        Lame::from_young_poisson(2.1e5, 0.3)
    }

    /// A skewed tetrahedron (positive orientation) and its tet10 with straight edges.
    fn tet4() -> [[f64; 3]; 4] {
        [[0.1, -0.2, 0.05], [1.3, 0.1, -0.1], [0.2, 0.9, 0.15], [0.35, 0.25, 1.1]]
    }

    fn tet10_of(c: &[[f64; 3]; 4]) -> [[f64; 3]; 10] {
        let mut x = [[0.0; 3]; 10];
        x[..4].copy_from_slice(c);
        for (e, [a, b]) in TET10_EDGES.iter().enumerate() {
            x[4 + e] = std::array::from_fn(|i| 0.5 * (c[*a][i] + c[*b][i]));
        }
        x
    }

    fn volume(c: &[[f64; 3]; 4]) -> f64 {
        let d = |p: usize| std::array::from_fn::<f64, 3, _>(|i| c[p][i] - c[0][i]);
        let (a, b, e) = (d(1), d(2), d(3));
        (a[0] * (b[1] * e[2] - b[2] * e[1]) - a[1] * (b[0] * e[2] - b[2] * e[0]) + a[2] * (b[0] * e[1] - b[1] * e[0])) / 6.0
    }

    /// u = A x + t at every node, flattened.
    fn linear_field<const N: usize>(x: &[[f64; 3]; N], a: [[f64; 3]; 3], t: [f64; 3]) -> Vec<f64> {
        x.iter().flat_map(|p| (0..3).map(move |i| t[i] + a[i][0] * p[0] + a[i][1] * p[1] + a[i][2] * p[2])).collect()
    }

    fn apply<const R: usize>(k: &[[f64; R]; R], u: &[f64]) -> Vec<f64> {
        k.iter().map(|row| row.iter().zip(u).map(|(a, b)| a * b).sum()).collect()
    }

    fn norm(v: &[f64]) -> f64 {
        v.iter().map(|a| a * a).sum::<f64>().sqrt()
    }

    #[test]
    fn shape_functions_are_a_partition_of_unity_and_interpolate_their_nodes() {
        let xi = [0.2, 0.3, 0.1];
        assert!((tet4_shape(xi).iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert!((tet10_shape(xi).iter().sum::<f64>() - 1.0).abs() < 1e-15);
        let x = tet10_of(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
        for (a, p) in x.iter().enumerate() {
            let n = tet10_shape(*p);
            for (b, v) in n.iter().enumerate() {
                assert!((v - f64::from(u8::from(a == b))).abs() < 1e-15, "N_{b}(x_{a}) = {v}");
            }
        }
    }

    #[test]
    fn the_volume_is_integrated_exactly() {
        let c = tet4();
        let v = volume(&c);
        assert!((tet4_gradients(&c).1 / 6.0 - v).abs() < 1e-14);
        let x = tet10_of(&c);
        let integral: f64 = tet_rule_4().iter().map(|&(xi, w)| w * tet10_gradients(&x, xi).1).sum();
        assert!((integral - v).abs() < 1e-14, "{integral} vs {v}");
        assert!(tet10_min_jacobian(&x) > 0.0);
        // an inverted element (two corners swapped)
        let mut bad = c;
        bad.swap(1, 2);
        assert!(tet4_gradients(&bad).1 < 0.0 && tet10_min_jacobian(&tet10_of(&bad)) < 0.0);
    }

    #[test]
    fn rigid_motions_cost_nothing_and_are_the_whole_kernel() {
        let m = steel();
        let c = tet4();
        // a curved tet10 too: one edge node moved off its edge
        let mut curved = tet10_of(&c);
        curved[5][2] += 0.05;
        let k4 = tet4_stiffness(&c, m);
        let (k10, k10c) = (tet10_stiffness(&tet10_of(&c), m), tet10_stiffness(&curved, m));
        let rot = |w: [f64; 3]| [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]];
        let modes: Vec<([[f64; 3]; 3], [f64; 3])> = (0..3)
            .map(|d| ([[0.0; 3]; 3], std::array::from_fn(|i| f64::from(u8::from(i == d)))))
            .chain((0..3).map(|d| (rot(std::array::from_fn(|i| f64::from(u8::from(i == d)))), [0.0; 3])))
            .collect();
        let scale = m.lambda + 2.0 * m.mu;
        for (a, t) in &modes {
            assert!(norm(&apply(&k4, &linear_field(&c, *a, *t))) < 1e-9 * scale, "tet4");
            assert!(norm(&apply(&k10, &linear_field(&tet10_of(&c), *a, *t))) < 1e-9 * scale, "tet10");
            assert!(norm(&apply(&k10c, &linear_field(&curved, *a, *t))) < 1e-9 * scale, "curved tet10");
        }
        // symmetric, positive semidefinite with exactly six zero eigenvalues
        for (k, n) in [(k4.iter().flatten().copied().collect::<Vec<f64>>(), 12), (k10.iter().flatten().copied().collect(), 30)] {
            let mat = faer::Mat::<f64>::from_fn(n, n, |i, j| k[i * n + j]);
            let asym = (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).map(|(i, j)| (mat[(i, j)] - mat[(j, i)]).abs()).fold(0.0, f64::max);
            assert!(asym < 1e-9 * scale, "asymmetry {asym:e}");
            let eig = mat.self_adjoint_eigen(faer::Side::Lower).unwrap();
            let s = eig.S();
            let top = (0..n).map(|i| s[i]).fold(0.0, f64::max);
            let zero = (0..n).filter(|&i| s[i].abs() <= 1e-10 * top).count();
            assert_eq!(zero, 6, "n = {n}: {zero} zero eigenvalues");
            assert!((0..n).all(|i| s[i] > -1e-10 * top));
        }
    }

    #[test]
    fn a_linear_field_gives_its_constant_strain_and_energy_the_patch_test_of_one_element() {
        let m = steel();
        let c = tet4();
        let a = [[1e-3, 2e-4, -3e-4], [5e-4, -2e-3, 1e-4], [-4e-4, 3e-4, 1.5e-3]];
        let eps = [a[0][0], a[1][1], a[2][2], a[0][1] + a[1][0], a[1][2] + a[2][1], a[2][0] + a[0][2]];
        let sigma = m.stress(&eps);
        let energy = volume(&c) * eps.iter().zip(&sigma).map(|(e, s)| e * s).sum::<f64>();
        let x10 = tet10_of(&c);
        let mut curved = x10;
        curved[8][0] += 0.04;
        let as_nodes = |v: Vec<f64>| -> Vec<[f64; 3]> { v.chunks(3).map(|c| [c[0], c[1], c[2]]).collect() };
        let u4 = linear_field(&c, a, [0.1, 0.0, -0.2]);
        let u10 = linear_field(&x10, a, [0.1, 0.0, -0.2]);
        let n4: [[f64; 3]; 4] = as_nodes(u4.clone()).try_into().unwrap();
        let n10: [[f64; 3]; 10] = as_nodes(u10.clone()).try_into().unwrap();
        let close = |e: [f64; 6]| e.iter().zip(&eps).all(|(x, y)| (x - y).abs() < 1e-15);
        assert!(close(tet4_strain(&c, &n4)));
        assert!(close(tet10_strain(&x10, &n10, [0.1, 0.2, 0.3])));
        // the curved tet10 reproduces the linear field too (isoparametric)
        let uc: [[f64; 3]; 10] = as_nodes(linear_field(&curved, a, [0.0; 3])).try_into().unwrap();
        assert!(close(tet10_strain(&curved, &uc, [0.25, 0.1, 0.4])));
        let e4: f64 = u4.iter().zip(apply(&tet4_stiffness(&c, m), &u4)).map(|(a, b)| a * b).sum();
        let e10: f64 = u10.iter().zip(apply(&tet10_stiffness(&x10, m), &u10)).map(|(a, b)| a * b).sum();
        assert!((e4 - energy).abs() <= 1e-10 * energy && (e10 - energy).abs() <= 1e-10 * energy, "uᵀKu {e4} / {e10} vs ∫σ:ε {energy}");
    }
}
