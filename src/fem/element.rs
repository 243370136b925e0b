//! Element kernels: trilinear hex8 (2×2×2 Gauss) and the shared isoparametric helpers (physical
//! gradients, stiffness and strain at a point). Pure functions of the corner coordinates; node
//! order VTK (see [`crate::mesh`]). The bilinear quad4 face integral ([`quad4_nodal_areas`])
//! lives with the other reference facets in [`super::facet`] and is re-exported here.

use super::material::Lame;

/// Reference coordinates of the hex8 corners.
pub const HEX_REF: [[f64; 3]; 8] =
    [[-1.0, -1.0, -1.0], [1.0, -1.0, -1.0], [1.0, 1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, 1.0], [-1.0, 1.0, 1.0]];

/// Reference coordinates of the quad4 corners and the two-point Gauss rule (weights 1): see
/// [`super::facet`].
pub use super::facet::{quad4_nodal_areas, GAUSS2, QUAD_REF};

/// The node coordinates of a hex8 element.
pub type HexCoords = [[f64; 3]; 8];
/// A hex8 element matrix, 24 × 24 (DOF order 3a + i).
pub type HexMatrix = [[f64; 24]; 24];

/// Shape function values at reference point `xi`.
pub fn hex_shape(xi: [f64; 3]) -> [f64; 8] {
    HEX_REF.map(|r| 0.125 * (1.0 + r[0] * xi[0]) * (1.0 + r[1] * xi[1]) * (1.0 + r[2] * xi[2]))
}

/// Physical shape-function gradients (8×3) and det J at reference point `xi`.
pub fn hex_gradients(x: &HexCoords, xi: [f64; 3]) -> ([[f64; 3]; 8], f64) {
    let mut dref = [[0.0; 3]; 8];
    for (a, r) in HEX_REF.iter().enumerate() {
        let f = [1.0 + r[0] * xi[0], 1.0 + r[1] * xi[1], 1.0 + r[2] * xi[2]];
        dref[a] = [0.125 * r[0] * f[1] * f[2], 0.125 * f[0] * r[1] * f[2], 0.125 * f[0] * f[1] * r[2]];
    }
    physical_gradients(x, &dref)
}

/// Physical shape-function gradients and det J of an isoparametric element with nodes `x`
/// from the reference gradients `dref` (∂N_a/∂ξ) at one point: ∇N_a = J⁻¹ ∇_ξ N_a.
pub fn physical_gradients<const N: usize>(x: &[[f64; 3]; N], dref: &[[f64; 3]; N]) -> ([[f64; 3]; N], f64) {
    // J[i][j] = ∂x_j/∂ξ_i
    let mut j = [[0.0; 3]; 3];
    for a in 0..N {
        for i in 0..3 {
            for k in 0..3 {
                j[i][k] += dref[a][i] * x[a][k];
            }
        }
    }
    let det = j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1]) - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]);
    let inv_det = 1.0 / det;
    let inv = [
        [
            (j[1][1] * j[2][2] - j[1][2] * j[2][1]) * inv_det,
            (j[0][2] * j[2][1] - j[0][1] * j[2][2]) * inv_det,
            (j[0][1] * j[1][2] - j[0][2] * j[1][1]) * inv_det,
        ],
        [
            (j[1][2] * j[2][0] - j[1][0] * j[2][2]) * inv_det,
            (j[0][0] * j[2][2] - j[0][2] * j[2][0]) * inv_det,
            (j[0][2] * j[1][0] - j[0][0] * j[1][2]) * inv_det,
        ],
        [
            (j[1][0] * j[2][1] - j[1][1] * j[2][0]) * inv_det,
            (j[0][1] * j[2][0] - j[0][0] * j[2][1]) * inv_det,
            (j[0][0] * j[1][1] - j[0][1] * j[1][0]) * inv_det,
        ],
    ];
    // ∇N_a = J⁻¹ ∇_ξ N_a
    let mut g = [[0.0; 3]; N];
    for a in 0..N {
        for i in 0..3 {
            g[a][i] = inv[i][0] * dref[a][0] + inv[i][1] * dref[a][1] + inv[i][2] * dref[a][2];
        }
    }
    (g, det)
}

/// The eight 2×2×2 Gauss points (all weights 1).
pub fn hex_gauss_points() -> [[f64; 3]; 8] {
    let mut p = [[0.0; 3]; 8];
    let mut q = 0;
    for &z in &GAUSS2 {
        for &y in &GAUSS2 {
            for &x in &GAUSS2 {
                p[q] = [x, y, z];
                q += 1;
            }
        }
    }
    p
}

/// Smallest det J over the Gauss points and corners: ≤ 0 means an inverted or degenerate element.
pub fn hex_min_jacobian(x: &HexCoords) -> f64 {
    hex_gauss_points().iter().chain(HEX_REF.iter()).map(|&xi| hex_gradients(x, xi).1).fold(f64::INFINITY, f64::min)
}

/// Element stiffness K_e (24×24, DOF order 3a + i) of isotropic elasticity, 2×2×2 Gauss:
/// K_ab,ij = ∫ λ ∂ᵢN_a ∂ⱼN_b + μ δᵢⱼ ∇N_a·∇N_b + μ ∂ⱼN_a ∂ᵢN_b.
pub fn hex8_stiffness(x: &HexCoords, m: Lame) -> HexMatrix {
    let mut k = [[0.0; 24]; 24];
    for xi in hex_gauss_points() {
        let (g, det) = hex_gradients(x, xi);
        add_stiffness(&g, det, m, |r, c, v| k[r][c] += v);
    }
    k
}

/// One quadrature point's part of an element stiffness: `add(3a + i, 3b + j, v)` for every node
/// pair with v = w (λ ∂ᵢN_a ∂ⱼN_b + μ δᵢⱼ ∇N_a·∇N_b + μ ∂ⱼN_a ∂ᵢN_b), `g` the physical
/// gradients there and `w` the weight times det J.
pub fn add_stiffness(g: &[[f64; 3]], w: f64, m: Lame, mut add: impl FnMut(usize, usize, f64)) {
    for a in 0..g.len() {
        for b in 0..g.len() {
            let dot = g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2];
            for i in 0..3 {
                for j in 0..3 {
                    let mut v = m.lambda * g[a][i] * g[b][j] + m.mu * g[a][j] * g[b][i];
                    if i == j {
                        v += m.mu * dot;
                    }
                    add(3 * a + i, 3 * b + j, v * w);
                }
            }
        }
    }
}

/// Small strain (Voigt, engineering shears) from the physical gradients `g` at a point and the
/// nodal displacements `u`.
pub fn strain(g: &[[f64; 3]], u: &[[f64; 3]]) -> [f64; 6] {
    let mut du = [[0.0; 3]; 3]; // du[i][j] = ∂u_i/∂x_j
    for (ga, ua) in g.iter().zip(u) {
        for i in 0..3 {
            for j in 0..3 {
                du[i][j] += ua[i] * ga[j];
            }
        }
    }
    [du[0][0], du[1][1], du[2][2], du[0][1] + du[1][0], du[1][2] + du[2][1], du[2][0] + du[0][2]]
}

/// Small strain (Voigt, engineering shears) at reference point `xi` from nodal displacements.
pub fn hex8_strain(x: &HexCoords, u: &[[f64; 3]; 8], xi: [f64; 3]) -> [f64; 6] {
    let (g, _) = hex_gradients(x, xi);
    strain(&g, u)
}

/// Stress at the element centre.
pub fn hex8_center_stress(x: &HexCoords, u: &[[f64; 3]; 8], m: Lame) -> [f64; 6] {
    m.stress(&hex8_strain(x, u, [0.0; 3]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    fn distorted() -> HexCoords {
        [[0.0, 0.0, 0.0], [1.3, 0.1, -0.05], [1.1, 0.9, 0.1], [-0.1, 1.2, 0.0], [0.05, -0.1, 0.8], [1.2, 0.0, 1.1], [1.4, 1.3, 1.2], [0.1, 1.0, 0.9]]
    }

    fn rigid_modes(x: &HexCoords) -> Mat<f64> {
        Mat::from_fn(24, 6, |r, c| {
            let (a, i) = (r / 3, r % 3);
            let p = x[a];
            match c {
                0..=2 => f64::from(u8::from(i == c)),
                3 => [-p[1], p[0], 0.0][i],
                4 => [0.0, -p[2], p[1]][i],
                _ => [p[2], 0.0, -p[0]][i],
            }
        })
    }

    #[test]
    fn stiffness_symmetric_six_zero_eigenvalues_rigid_kernel() {
        let m = Lame::from_young_poisson(50_000.0, 0.3);
        for x in [HEX_REF.map(|p| p.map(|v| 0.5 * v + 1.0)), distorted()] {
            let k = hex8_stiffness(&x, m);
            let kmax = k.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
            for i in 0..24 {
                for j in 0..24 {
                    assert!((k[i][j] - k[j][i]).abs() <= 1e-13 * kmax);
                }
            }
            let km = Mat::from_fn(24, 24, |i, j| k[i][j]);
            let eig = km.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
            let lmax = eig.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let zeros = eig.iter().filter(|v| v.abs() < 1e-10 * lmax).count();
            assert_eq!(zeros, 6, "eigenvalues {eig:?}");
            assert!(eig.iter().all(|&v| v > -1e-10 * lmax), "K_e not positive semidefinite");
            // the seventh eigenvalue is well separated from zero
            let mut sorted = eig.clone();
            sorted.sort_by(f64::total_cmp);
            assert!(sorted[6] > 1e-4 * lmax);
            // kernel = rigid-body modes: K R = 0 and R spans 6 dimensions
            let r = rigid_modes(&x);
            let kr = &km * &r;
            assert!(kr.norm_max() <= 1e-11 * lmax * r.norm_max());
            let s = r.singular_values().unwrap();
            assert!(s[5] > 1e-3 * s[0]);
        }
    }

    #[test]
    fn volume_and_face_areas() {
        let x = distorted();
        let vol: f64 = hex_gauss_points().iter().map(|&xi| hex_gradients(&x, xi).1).sum();
        assert!(vol > 0.0);
        // unit cube scaled: volume 8 · 0.125 = 1
        let cube = HEX_REF.map(|p| p.map(|v| 0.5 * v));
        let v: f64 = hex_gauss_points().iter().map(|&xi| hex_gradients(&cube, xi).1).sum();
        assert!((v - 1.0).abs() < 1e-14);
        let w = quad4_nodal_areas(&[[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [2.0, 1.0, 1.0], [0.0, 1.0, 1.0]]);
        for wa in w {
            assert!((wa - 0.5).abs() < 1e-14);
        }
        assert!(hex_min_jacobian(&x) > 0.0);
        let mut inverted = x;
        inverted.swap(1, 3);
        inverted.swap(5, 7);
        assert!(hex_min_jacobian(&inverted) < 0.0);
    }

    #[test]
    fn constant_strain_is_reproduced() {
        let x = distorted();
        let h = [[1e-3, 2e-4, -3e-4], [5e-4, -2e-3, 1e-4], [0.0, 7e-4, 1.5e-3]];
        let u = x.map(|p| {
            let mut v = [0.0; 3];
            for i in 0..3 {
                for j in 0..3 {
                    v[i] += h[i][j] * p[j];
                }
            }
            v
        });
        let eps = hex8_strain(&x, &u, [0.3, -0.2, 0.7]);
        let exact = [h[0][0], h[1][1], h[2][2], h[0][1] + h[1][0], h[1][2] + h[2][1], h[2][0] + h[0][2]];
        for i in 0..6 {
            assert!((eps[i] - exact[i]).abs() < 1e-15);
        }
    }
}
