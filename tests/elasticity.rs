//! Finite-element correctness: patch tests (a linear field is reproduced exactly, under
//! Dirichlet-only and mixed Dirichlet/traction conditions, on distorted meshes) and convergence
//! to an analytic solution of the Navier equations at the rates of trilinear elements.

use tresca_feti::fem::assembly::{add_traction, assemble_body, DofMap};
use tresca_feti::fem::element::{hex_gradients, hex_shape};
use tresca_feti::fem::material::Lame;
use tresca_feti::linalg::cholesky::{Cholesky, Ordering};
use tresca_feti::linalg::ordering::{expand_to_dofs, nested_dissection};
use tresca_feti::mesh::{boxgen, Mesh};

/// A unit-cube mesh with `n` nodes per edge; interior nodes moved pseudo-randomly by up to
/// `jitter`·h.
fn cube(n: usize, jitter: f64) -> Mesh {
    let mut g = boxgen::generate([0.0; 3], [1.0; 3], [n; 3]);
    let h = 1.0 / (n - 1) as f64;
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    for p in &mut g.nodes {
        let interior = p.iter().all(|&c| c > 1e-12 && c < 1.0 - 1e-12);
        if interior {
            for c in p.iter_mut() {
                *c += jitter * h * rnd();
            }
        }
    }
    let mut m = Mesh::default();
    m.push_body("cube", g);
    m
}

fn solve(mesh: &Mesh, lame: Lame, constraints: &[(usize, usize, f64)], loads: &[f64]) -> Vec<[f64; 3]> {
    let body = &mesh.bodies[0];
    let dofs = DofMap::new(body.nodes.clone(), constraints);
    let sys = assemble_body(mesh, 0, lame, &dofs, loads).unwrap();
    let perm = nested_dissection(&sys.graph.0, &sys.graph.1).unwrap();
    let perm = expand_to_dofs(&perm, dofs.nfree, |v| dofs.node_dofs(v));
    let chol = Cholesky::factorize(&sys.k, Ordering::Custom(perm)).unwrap();
    let mut x = sys.f.clone();
    chol.solve_in_place(&mut x);
    dofs.expand(&x)
}

const A: [f64; 3] = [1e-3, -2e-3, 5e-4];
const H: [[f64; 3]; 3] = [[1e-3, 2e-4, -3e-4], [5e-4, -2e-3, 1e-4], [0.0, 7e-4, 1.5e-3]];

fn linear(p: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| A[i] + (0..3).map(|j| H[i][j] * p[j]).sum::<f64>())
}

fn max_rel_error(mesh: &Mesh, u: &[[f64; 3]], exact: impl Fn([f64; 3]) -> [f64; 3]) -> f64 {
    let mut err: f64 = 0.0;
    let mut scale: f64 = 0.0;
    for (p, ui) in mesh.nodes.iter().zip(u) {
        let e = exact(*p);
        for c in 0..3 {
            err = err.max((ui[c] - e[c]).abs());
            scale = scale.max(e[c].abs());
        }
    }
    err / scale
}

#[test]
fn patch_test_dirichlet_reproduces_linear_field() {
    let mesh = cube(6, 0.25);
    let lame = Lame::from_young_poisson(50_000.0, 0.3);
    let mut cons = Vec::new();
    for (v, p) in mesh.nodes.iter().enumerate() {
        if p.iter().any(|&c| c.abs() < 1e-12 || (c - 1.0).abs() < 1e-12) {
            let u = linear(*p);
            cons.extend((0..3).map(|c| (v, c, u[c])));
        }
    }
    let u = solve(&mesh, lame, &cons, &vec![0.0; 3 * mesh.nodes.len()]);
    let e = max_rel_error(&mesh, &u, linear);
    assert!(e <= 1e-12, "patch test error {e:e}");
}

#[test]
fn patch_test_traction_reproduces_linear_field() {
    // Dirichlet on the three faces through the origin, the exact constant traction σ·n on the
    // three others: the consistent face loads must reproduce the field exactly.
    let mesh = cube(6, 0.25);
    let lame = Lame::from_young_poisson(50_000.0, 0.3);
    let eps = [H[0][0], H[1][1], H[2][2], H[0][1] + H[1][0], H[1][2] + H[2][1], H[2][0] + H[0][2]];
    let s = lame.stress(&eps);
    let sigma = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];
    let mut cons = Vec::new();
    for (v, p) in mesh.nodes.iter().enumerate() {
        if p.iter().any(|&c| c.abs() < 1e-12) {
            let u = linear(*p);
            cons.extend((0..3).map(|c| (v, c, u[c])));
        }
    }
    let mut loads = vec![0.0; 3 * mesh.nodes.len()];
    for (name, axis) in [("cube.xmax", 0), ("cube.ymax", 1), ("cube.zmax", 2)] {
        let t: [f64; 3] = std::array::from_fn(|i| sigma[i][axis]);
        add_traction(&mesh, mesh.face(name).unwrap(), t, 0, &mut loads);
    }
    let u = solve(&mesh, lame, &cons, &loads);
    let e = max_rel_error(&mesh, &u, linear);
    assert!(e <= 1e-12, "traction patch test error {e:e}");
}

/// u = ∇φ with φ = exp(0.6x + 0.8z)·cos y harmonic: div u = 0 and Δu = 0, so u solves the
/// Navier equations without body force for every λ, μ.
fn harmonic(p: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let e = (0.6 * p[0] + 0.8 * p[2]).exp();
    let (s, c) = p[1].sin_cos();
    let u = [0.6 * e * c, -e * s, 0.8 * e * c];
    let g = [
        [0.36 * e * c, -0.6 * e * s, 0.48 * e * c],
        [-0.6 * e * s, -e * c, -0.8 * e * s],
        [0.48 * e * c, -0.8 * e * s, 0.64 * e * c],
    ];
    (u, g)
}

/// (L² error, H¹-seminorm error) of the FE field against [`harmonic`], 3×3×3 Gauss per element.
fn errors(mesh: &Mesh, u: &[[f64; 3]]) -> (f64, f64) {
    let gp = [-(0.6f64).sqrt(), 0.0, (0.6f64).sqrt()];
    let gw = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let (mut l2, mut h1) = (0.0, 0.0);
    for e in 0..mesh.cells.len() {
        let x: [[f64; 3]; 8] = mesh.cell_coords(e).try_into().unwrap();
        let ue: [[f64; 3]; 8] = std::array::from_fn(|a| u[mesh.cells[e].nodes()[a]]);
        for (a, &xa) in gp.iter().enumerate() {
            for (b, &xb) in gp.iter().enumerate() {
                for (c, &xc) in gp.iter().enumerate() {
                    let xi = [xa, xb, xc];
                    let w = gw[a] * gw[b] * gw[c];
                    let n = hex_shape(xi);
                    let (g, det) = hex_gradients(&x, xi);
                    let mut p = [0.0; 3];
                    let mut uh = [0.0; 3];
                    let mut gh = [[0.0; 3]; 3];
                    for k in 0..8 {
                        for i in 0..3 {
                            p[i] += n[k] * x[k][i];
                            uh[i] += n[k] * ue[k][i];
                            for j in 0..3 {
                                gh[i][j] += ue[k][i] * g[k][j];
                            }
                        }
                    }
                    let (ux, gx) = harmonic(p);
                    for i in 0..3 {
                        l2 += w * det * (uh[i] - ux[i]).powi(2);
                        for j in 0..3 {
                            h1 += w * det * (gh[i][j] - gx[i][j]).powi(2);
                        }
                    }
                }
            }
        }
    }
    (l2.sqrt(), h1.sqrt())
}

#[test]
fn converges_at_the_rates_of_trilinear_elements() {
    let lame = Lame::from_young_poisson(50_000.0, 0.3);
    let mut prev: Option<(f64, f64)> = None;
    let mut rates = Vec::new();
    for n in [5, 9, 17] {
        let mesh = cube(n, 0.0);
        let mut cons = Vec::new();
        for (v, p) in mesh.nodes.iter().enumerate() {
            if p.iter().any(|&c| c.abs() < 1e-12 || (c - 1.0).abs() < 1e-12) {
                let u = harmonic(*p).0;
                cons.extend((0..3).map(|c| (v, c, u[c])));
            }
        }
        let u = solve(&mesh, lame, &cons, &vec![0.0; 3 * mesh.nodes.len()]);
        let (l2, h1) = errors(&mesh, &u);
        if let Some((pl2, ph1)) = prev {
            rates.push(((pl2 / l2).log2(), (ph1 / h1).log2()));
        }
        prev = Some((l2, h1));
    }
    // h halves at each step: L² error ~ h², H¹ error ~ h
    for (rl2, rh1) in &rates {
        assert!((1.9..=2.1).contains(rl2), "L2 rate {rl2} (all: {rates:?})");
        assert!((0.95..=1.05).contains(rh1), "H1 rate {rh1} (all: {rates:?})");
    }
    eprintln!("rates (L2, H1) under refinement h = 1/4 → 1/8 → 1/16: {rates:?}");
    // |u| ≈ 1…4 on the cube: at h = 1/16 the L² error is a few 1e-4
    let (l2, _) = prev.unwrap();
    assert!(l2 < 1e-3, "finest L2 error {l2:e}");
}
