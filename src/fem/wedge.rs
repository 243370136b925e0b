//! The linear wedge (6-node prism) kernel: N_a = L_a(ξ, η)·(1 ∓ ζ)/2 on the reference prism
//! {ξ, η ≥ 0, ξ + η ≤ 1} × [−1, 1] with L = (1 − ξ − η, ξ, η); bottom nodes 0–2 (ζ = −1), top
//! 3–5 above them (Gmsh's order). Six points: the three-point triangle rule of degree 2 times
//! two Gauss points in ζ. Pure functions of the node coordinates.

use super::element::{add_stiffness, physical_gradients, strain, GAUSS2};
use super::material::Lame;

const DL: [[f64; 2]; 3] = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];

/// Shape functions at `xi`.
pub fn wedge6_shape(xi: [f64; 3]) -> [f64; 6] {
    let l = [1.0 - xi[0] - xi[1], xi[0], xi[1]];
    let (b, t) = (0.5 * (1.0 - xi[2]), 0.5 * (1.0 + xi[2]));
    [l[0] * b, l[1] * b, l[2] * b, l[0] * t, l[1] * t, l[2] * t]
}

fn ref_gradients(xi: [f64; 3]) -> [[f64; 3]; 6] {
    let l = [1.0 - xi[0] - xi[1], xi[0], xi[1]];
    let mut d = [[0.0; 3]; 6];
    for a in 0..3 {
        for (k, s) in [(a, -1.0), (a + 3, 1.0)] {
            let h = 0.5 * (1.0 + s * xi[2]);
            d[k] = [DL[a][0] * h, DL[a][1] * h, 0.5 * s * l[a]];
        }
    }
    d
}

/// The six quadrature points and weights (summing to the reference volume 1).
pub fn wedge_rule_6() -> [([f64; 3], f64); 6] {
    let tri = [[1.0 / 6.0, 1.0 / 6.0], [2.0 / 3.0, 1.0 / 6.0], [1.0 / 6.0, 2.0 / 3.0]];
    std::array::from_fn(|q| {
        let (t, z) = (tri[q % 3], GAUSS2[q / 3]);
        ([t[0], t[1], z], 1.0 / 6.0)
    })
}

/// Physical gradients and det J at `xi`.
pub fn wedge6_gradients(x: &[[f64; 3]; 6], xi: [f64; 3]) -> ([[f64; 3]; 6], f64) {
    physical_gradients(x, &ref_gradients(xi))
}

/// Stiffness (18 × 18, DOF order 3a + i).
pub fn wedge6_stiffness(x: &[[f64; 3]; 6], m: Lame) -> [[f64; 18]; 18] {
    let mut k = [[0.0; 18]; 18];
    for (xi, w) in wedge_rule_6() {
        let (g, det) = wedge6_gradients(x, xi);
        add_stiffness(&g, det * w, m, |r, c, v| k[r][c] += v);
    }
    k
}

/// Smallest det J over the quadrature points and the corners.
pub fn wedge6_min_jacobian(x: &[[f64; 3]; 6]) -> f64 {
    let corners = [[0.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 1.0, -1.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]];
    wedge_rule_6().iter().map(|p| p.0).chain(corners).map(|xi| wedge6_gradients(x, xi).1).fold(f64::INFINITY, f64::min)
}

/// Strain at `xi` from the nodal displacements.
pub fn wedge6_strain(x: &[[f64; 3]; 6], u: &[[f64; 3]; 6], xi: [f64; 3]) -> [f64; 6] {
    strain(&wedge6_gradients(x, xi).0, u)
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    fn skewed() -> [[f64; 3]; 6] {
        [[0.0, 0.0, 0.0], [1.2, 0.1, 0.05], [0.1, 0.9, -0.05], [0.05, 0.1, 1.0], [1.1, 0.05, 1.2], [0.2, 1.0, 0.9]]
    }

    #[test]
    fn partition_of_unity_and_volume() {
        for (xi, _) in wedge_rule_6() {
            assert!((wedge6_shape(xi).iter().sum::<f64>() - 1.0).abs() < 1e-15);
        }
        // the unit right prism: volume 1/2
        let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]];
        let v: f64 = wedge_rule_6().iter().map(|&(xi, w)| w * wedge6_gradients(&x, xi).1).sum();
        assert!((v - 0.5).abs() < 1e-14, "{v}");
        assert!(wedge6_min_jacobian(&skewed()) > 0.0);
        let mut inv = skewed();
        inv.swap(1, 2);
        inv.swap(4, 5);
        assert!(wedge6_min_jacobian(&inv) < 0.0);
    }

    /// Symmetric, positive semi-definite with exactly six zero eigenvalues (the rigid motions),
    /// and a linear displacement field gives its constant strain at every point (patch test).
    #[test]
    fn rigid_modes_and_linear_fields() {
        let x = skewed();
        let k = wedge6_stiffness(&x, Lame::from_young_poisson(1.0, 0.3));
        let m = Mat::<f64>::from_fn(18, 18, |i, j| k[i][j]);
        for (i, row) in k.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                assert!((v - k[j][i]).abs() < 1e-14);
            }
        }
        let ev = m.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
        let max = ev.iter().cloned().fold(0.0, f64::max);
        let zero = ev.iter().filter(|&&e| e.abs() < 1e-10 * max).count();
        assert_eq!(zero, 6, "{ev:?}");
        assert!(ev.iter().all(|&e| e > -1e-12 * max));
        let grad = [[0.1, -0.3, 0.2], [0.05, 0.4, -0.1], [0.3, 0.0, 0.25]];
        let u: [[f64; 3]; 6] = x.map(|p| std::array::from_fn(|i| grad[i][0] * p[0] + grad[i][1] * p[1] + grad[i][2] * p[2]));
        let exact = [grad[0][0], grad[1][1], grad[2][2], grad[0][1] + grad[1][0], grad[1][2] + grad[2][1], grad[2][0] + grad[0][2]];
        for xi in [[0.2, 0.3, -0.7], [0.6, 0.1, 0.4]] {
            let e = wedge6_strain(&x, &u, xi);
            for c in 0..6 {
                assert!((e[c] - exact[c]).abs() < 1e-13, "{e:?}");
            }
        }
    }
}
