use super::*;
use crate::fem::facet::{cross, facet_nodal_areas, sub};
use crate::mesh::{Cell, CellKind};
use faer::Mat;

/// A pyramid on a planar trapezoid base (not a parallelogram: the map is not affine) with its
/// apex off the base's centre.
fn skewed() -> [[f64; 3]; 5] {
    [[0.0, 0.0, 0.0], [1.4, 0.1, 0.0], [1.1, 1.0, 0.0], [0.2, 0.9, 0.0], [0.5, 0.3, 0.8]]
}

#[test]
fn partition_of_unity_kronecker_and_derivatives() {
    for (a, r) in PYR5_REF.iter().enumerate() {
        let n = pyr5_shape(*r);
        for (b, v) in n.iter().enumerate() {
            assert!((v - if a == b { 1.0 } else { 0.0 }).abs() < 1e-15, "N_{b} at node {a}: {v}");
        }
    }
    let h = 1e-6;
    for xi in [[0.1, -0.2, 0.3], [-0.5, 0.4, 0.1], [0.05, 0.02, 0.9], [0.7, -0.6, 0.05]] {
        assert!((pyr5_shape(xi).iter().sum::<f64>() - 1.0).abs() < 1e-15);
        let d = pyr5_ref_gradients(xi);
        for k in 0..3 {
            let mut p = xi;
            let mut m = xi;
            p[k] += h;
            m[k] -= h;
            let (np, nm) = (pyr5_shape(p), pyr5_shape(m));
            for a in 0..5 {
                let fd = (np[a] - nm[a]) / (2.0 * h);
                assert!((fd - d[a][k]).abs() < 1e-8, "∂N_{a}/∂ξ_{k} at {xi:?}: {} vs {fd}", d[a][k]);
            }
        }
    }
}

/// ∫ ξ^p η^q ζ^r over the reference pyramid = 4/((p+1)(q+1)) · B(r + 1, p + q + 3) for even p,
/// q (0 for odd): exact for p, q ≤ 3 and p + q + r ≤ 3.
#[test]
fn the_rule_integrates_monomials_and_volumes_exactly() {
    let fact = |n: usize| (1..=n).map(|k| k as f64).product::<f64>();
    let beta = |m: usize, n: usize| fact(m - 1) * fact(n - 1) / fact(m + n - 1);
    for (p, q, r) in [(0, 0, 0), (2, 0, 0), (0, 2, 1), (0, 0, 3), (2, 0, 1), (1, 1, 1), (0, 0, 1)] {
        let exact = if p % 2 == 1 || q % 2 == 1 { 0.0 } else { 4.0 / ((p + 1) * (q + 1)) as f64 * beta(r + 1, p + q + 3) };
        let s: f64 = pyr_rule_8().iter().map(|(x, w)| w * x[0].powi(p as i32) * x[1].powi(q as i32) * x[2].powi(r as i32)).sum();
        assert!((s - exact).abs() < 1e-15, "ξ^{p} η^{q} ζ^{r}: {s} vs {exact}");
    }
    // a straight-sided pyramid's volume is ⅓ · base area · height, whatever the base
    let x = skewed();
    let base = 0.5 * cross(sub(x[2], x[0]), sub(x[3], x[1]))[2];
    let v: f64 = pyr_rule_8().iter().map(|&(xi, w)| w * pyr5_gradients(&x, xi).1).sum();
    assert!((v - base * 0.8 / 3.0).abs() < 1e-14, "{v} vs {}", base * 0.8 / 3.0);
}

#[test]
fn det_j_is_positive_and_negative_when_mirrored() {
    assert!(pyr5_min_jacobian(&skewed()) > 0.0);
    let mut inv = skewed();
    inv.swap(1, 3);
    assert!(pyr5_min_jacobian(&inv) < 0.0);
    // the apex pushed through the base
    let mut flat = skewed();
    flat[4][2] = -0.8;
    assert!(pyr5_min_jacobian(&flat) < 0.0);
}

/// Symmetric, positive semi-definite with exactly six zero eigenvalues (the rigid motions).
#[test]
fn six_rigid_modes() {
    let k = pyr5_stiffness(&skewed(), Lame::from_young_poisson(1.0, 0.3));
    for (i, row) in k.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            assert!((v - k[j][i]).abs() < 1e-14);
        }
    }
    let ev = Mat::<f64>::from_fn(15, 15, |i, j| k[i][j]).self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
    let max = ev.iter().cloned().fold(0.0, f64::max);
    assert_eq!(ev.iter().filter(|&&e| e.abs() < 1e-10 * max).count(), 6, "{ev:?}");
    assert!(ev.iter().all(|&e| e > -1e-12 * max));
}

/// Patch test: for a linear field u = G x the strain is G's symmetric part at every point, and
/// K·u equals the nodal forces ∫_∂Ω N_a σ·n dA of the constant stress σ on the five (planar)
/// faces — the base's bilinear quad4 and the sides' tri3 weights.
#[test]
fn patch_test_k_u_equals_the_face_integrals_of_sigma_n() {
    let x = skewed();
    let lame = Lame::from_young_poisson(1000.0, 0.25);
    let grad = [[0.1, -0.3, 0.2], [0.05, 0.4, -0.1], [0.3, 0.0, 0.25]];
    let u: [[f64; 3]; 5] = x.map(|p| std::array::from_fn(|i| grad[i][0] * p[0] + grad[i][1] * p[1] + grad[i][2] * p[2] + 0.01 * i as f64));
    let eps = [grad[0][0], grad[1][1], grad[2][2], grad[0][1] + grad[1][0], grad[1][2] + grad[2][1], grad[2][0] + grad[0][2]];
    for xi in [[0.2, 0.3, 0.1], [-0.4, 0.1, 0.5], PYR5_CENTRE] {
        let e = pyr5_strain(&x, &u, xi);
        for c in 0..6 {
            assert!((e[c] - eps[c]).abs() < 1e-13, "{e:?}");
        }
    }
    let s = lame.stress(&eps);
    let sigma = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];
    let k = pyr5_stiffness(&x, lame);
    let mut f = [0.0; 15];
    let cell = Cell::new(CellKind::Pyr5, &[0, 1, 2, 3, 4]);
    for face in 0..5 {
        let fc = cell.facet(0, face);
        let p: Vec<[f64; 3]> = fc.nodes().iter().map(|&v| x[v]).collect();
        let nrm = cross(sub(p[1], p[0]), sub(p[2], p[0]));
        let len = (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]).sqrt();
        let n = nrm.map(|c| c / len);
        for (&v, w) in fc.nodes().iter().zip(facet_nodal_areas(fc.kind, &p)) {
            for i in 0..3 {
                f[3 * v + i] += w * (0..3).map(|j| sigma[i][j] * n[j]).sum::<f64>();
            }
        }
    }
    let fmax = f.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for r in 0..15 {
        let ku: f64 = (0..15).map(|c| k[r][c] * u[c / 3][c % 3]).sum();
        assert!((ku - f[r]).abs() < 1e-12 * fmax, "row {r}: K·u {ku} vs ∮ N σ·n {}", f[r]);
    }
}
