//! Unit tests of the quadratic hexahedra and wedge: partition of unity, Kronecker property,
//! derivatives against finite differences, rigid modes, volume, and the patch test on
//! distorted cells.

use super::*;
use crate::fem::facet::{facet_area_vector, facet_shape};
use crate::mesh::{Cell, CellKind};
use faer::Mat;

const ALL: [(Quadratic, CellKind); 3] = [(Quadratic::Hex20, CellKind::Hex20), (Quadratic::Hex27, CellKind::Hex27), (Quadratic::Wedge15, CellKind::Wedge15)];

/// Interior reference points of each cell.
fn points(q: Quadratic) -> Vec<[f64; 3]> {
    match q {
        Quadratic::Wedge15 => vec![[0.2, 0.3, -0.7], [0.6, 0.1, 0.4], [0.1, 0.1, 0.0]],
        _ => vec![[0.3, -0.2, 0.7], [-0.8, 0.45, 0.1], [0.0, 0.0, 0.0]],
    }
}

/// A distorted cell: corners moved off the reference shape, edge (and face, centre) nodes
/// where the corners' trilinear (or linear × linear) map puts them, plus a small bulge of the
/// mid-nodes when `curved`.
fn distorted(q: Quadratic, curved: bool) -> Vec<[f64; 3]> {
    let r = q.nodes();
    let corners: Vec<[f64; 3]> = match q {
        Quadratic::Wedge15 => vec![[0.0, 0.0, 0.0], [1.2, 0.1, 0.05], [0.1, 0.9, -0.05], [0.05, 0.1, 1.0], [1.1, 0.05, 1.2], [0.2, 1.0, 0.9]],
        _ => vec![[0.0, 0.0, 0.0], [1.3, 0.1, -0.05], [1.1, 0.9, 0.1], [-0.1, 1.2, 0.0], [0.05, -0.1, 0.8], [1.2, 0.0, 1.1], [1.4, 1.3, 1.2], [0.1, 1.0, 0.9]],
    };
    let nc = corners.len();
    r.iter()
        .enumerate()
        .map(|(a, &xi)| {
            // the linear cell's map (the hex8's / wedge6's shape functions)
            let w: Vec<f64> = match q {
                Quadratic::Wedge15 => crate::fem::wedge::wedge6_shape(xi).to_vec(),
                _ => crate::fem::element::hex_shape(xi).to_vec(),
            };
            let mut p: [f64; 3] = std::array::from_fn(|k| (0..nc).map(|c| w[c] * corners[c][k]).sum());
            if curved && a >= nc {
                p[0] += 0.03 * (a as f64).sin();
                p[2] += 0.02 * (a as f64).cos();
            }
            p
        })
        .collect()
}

#[test]
fn partition_of_unity_kronecker_and_derivatives() {
    for (q, _) in ALL {
        let r = q.nodes();
        for (a, &p) in r.iter().enumerate() {
            let n = q.shape(p).0;
            for (b, v) in n.iter().enumerate() {
                assert!((v - f64::from(u8::from(a == b))).abs() < 1e-14, "{q:?} N{b} at node {a}: {v}");
            }
        }
        for xi in points(q) {
            let (n, d) = q.shape(xi);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14, "{q:?}");
            for k in 0..3 {
                assert!(d.iter().map(|g| g[k]).sum::<f64>().abs() < 1e-13, "{q:?}");
            }
            let h = 1e-6;
            for k in 0..3 {
                let (mut pp, mut pm) = (xi, xi);
                pp[k] += h;
                pm[k] -= h;
                let (np, nm) = (q.shape(pp).0, q.shape(pm).0);
                for a in 0..n.len() {
                    let fd = (np[a] - nm[a]) / (2.0 * h);
                    assert!((fd - d[a][k]).abs() < 1e-8, "{q:?} dN{a}/dξ{k}: {fd} against {}", d[a][k]);
                }
            }
            // the reference coordinates are reproduced (isoparametric map of the reference cell)
            for k in 0..3 {
                let x: f64 = n.iter().zip(&r).map(|(w, p)| w * p[k]).sum();
                assert!((x - xi[k]).abs() < 1e-14, "{q:?}");
            }
        }
    }
}

#[test]
fn volume_rigid_modes_and_inversion() {
    for (q, _) in ALL {
        // the reference cell scaled by ½: volume 1 (hexahedra) or 1/8 (wedge: ½ · ½ · ½ · 2)
        let x: Vec<[f64; 3]> = q.nodes().iter().map(|p| p.map(|v| 0.5 * v)).collect();
        let vol: f64 = q.rule().iter().map(|&(xi, w)| w * q.gradients(&x, xi).1).sum();
        let exact = if q == Quadratic::Wedge15 { 0.125 } else { 1.0 };
        assert!((vol - exact).abs() < 1e-14, "{q:?} {vol}");
        let x = distorted(q, true);
        assert!(q.min_jacobian(&x) > 0.0, "{q:?}");
        let n = 3 * q.len();
        let k = q.stiffness(&x, Lame::from_young_poisson(1.0, 0.3));
        let m = Mat::<f64>::from_fn(n, n, |i, j| k[i * n + j]);
        for i in 0..n {
            for j in 0..n {
                assert!((m[(i, j)] - m[(j, i)]).abs() < 1e-14, "{q:?}");
            }
        }
        let ev = m.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
        let max = ev.iter().cloned().fold(0.0, f64::max);
        assert_eq!(ev.iter().filter(|&&e| e.abs() < 1e-10 * max).count(), 6, "{q:?} {ev:?}");
        assert!(ev.iter().all(|&e| e > -1e-12 * max), "{q:?}");
        // mirrored: the corners' order flipped makes det J negative
        let mut bad = x.clone();
        let perm = mirror(q);
        for (a, &b) in perm.iter().enumerate() {
            bad[a] = x[b];
        }
        assert!(q.min_jacobian(&bad) < 0.0, "{q:?}");
    }
}

/// The node permutation of swapping ξ and η (a mirror).
fn mirror(q: Quadratic) -> Vec<usize> {
    let r = q.nodes();
    r.iter().map(|p| r.iter().position(|s| s[0] == p[1] && s[1] == p[0] && s[2] == p[2]).unwrap()).collect()
}

/// The patch test: a linear displacement field gives its constant strain at every point, and
/// K u equals the consistent nodal forces ∫ N_a σ·n dA of the constant stress σ on the
/// cell's faces (equilibrium of one cell under a constant stress).
#[test]
fn patch_test_on_distorted_cells() {
    let m = Lame::from_young_poisson(200.0, 0.3);
    let grad = [[0.1, -0.3, 0.2], [0.05, 0.4, -0.1], [0.3, 0.0, 0.25]];
    let exact = [grad[0][0], grad[1][1], grad[2][2], grad[0][1] + grad[1][0], grad[1][2] + grad[2][1], grad[2][0] + grad[0][2]];
    let s = m.stress(&exact);
    let sigma = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];
    for (q, kind) in ALL {
        for curved in [false, true] {
            let x = distorted(q, curved);
            let u: Vec<[f64; 3]> = x.iter().map(|p| std::array::from_fn(|i| grad[i][0] * p[0] + grad[i][1] * p[1] + grad[i][2] * p[2])).collect();
            for xi in points(q) {
                let e = q.strain(&x, &u, xi);
                for c in 0..6 {
                    assert!((e[c] - exact[c]).abs() < 1e-13, "{q:?} curved {curved}: {e:?}");
                }
            }
            if curved {
                continue;
            }
            // K u against the surface integral of σ·n over the faces (straight-edged cell:
            // the facet rules integrate these exactly)
            let n = 3 * q.len();
            let k = q.stiffness(&x, m);
            let flat: Vec<f64> = u.iter().flatten().copied().collect();
            let ku: Vec<f64> = (0..n).map(|r| (0..n).map(|c| k[r * n + c] * flat[c]).sum()).collect();
            let mut f = vec![0.0; n];
            let cell = Cell::new(kind, &(0..q.len()).collect::<Vec<_>>());
            for face in 0..kind.faces().len() {
                let fc = cell.facet(0, face);
                let xf: Vec<[f64; 3]> = fc.nodes().iter().map(|&v| x[v]).collect();
                for (xi, w) in crate::fem::facet::fine_rule(fc.kind) {
                    let (phi, d) = facet_shape(fc.kind, xi);
                    let a = facet_area_vector(&xf, &d);
                    for (b, &v) in fc.nodes().iter().enumerate() {
                        for i in 0..3 {
                            f[3 * v + i] += w * phi[b] * (0..3).map(|j| sigma[i][j] * a[j]).sum::<f64>();
                        }
                    }
                }
            }
            let scale = f.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for r in 0..n {
                assert!((ku[r] - f[r]).abs() < 1e-11 * scale, "{q:?} row {r}: K u {} against ∫ N σn dA {}", ku[r], f[r]);
            }
        }
    }
}
