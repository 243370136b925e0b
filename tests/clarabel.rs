//! The dual solvers against an independent one: the primal SOCP of the same discrete problem,
//!
//!     min ½uᵀKu − fᵀu + Σᵢ gᵢ‖Tᵢu − cτ,ᵢ‖   s.t.  Nu ≤ cν,
//!
//! (u = the free DOFs of both bodies, Dirichlet eliminated) solved by the interior-point solver
//! Clarabel with tᵢ ≥ ‖Tᵢu − cτ,ᵢ‖ as second-order cones. Its multipliers are λν (the
//! non-negative cone) and −λ̄τ (the second-order cones).

use std::path::Path;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SecondOrderConeT, SolverStatus};
use tresca_feti::dual::DualOperator;
use tresca_feti::comm::SerialComm;
use tresca_feti::dual::monolithic::MonolithicDual;
use tresca_feti::model;
use tresca_feti::pipeline::{assemble_and_factorize, Timings};
use tresca_feti::qp::lambda::Lambda;
use tresca_feti::qp::{self, Method, Params};
use tresca_feti::recovery::{contact_state, OPEN, SLIP, STICK};
use tresca_feti::scene::{self, OrderingKind};

struct Compared {
    u_rel: f64,
    force_rel: f64,
    counts: ([usize; 3], [usize; 3]),
}

fn compare(n: usize, method: Method) -> Compared {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("run/seed.toml");
    let model = model::build(&scene::load(&path, &[format!("mesh.n={n}")]).unwrap()).unwrap();
    let contact = model.pairs.as_ref().unwrap();
    let bodies = assemble_and_factorize(&SerialComm, &model, OrderingKind::Metis, &mut Timings::default()).unwrap();
    let (dual, b) = MonolithicDual::new(&SerialComm, contact, bodies);
    let set = Lambda::new(contact);
    let layout = dual.layout;
    let (m, nd) = (layout.m, layout.dim());
    let g: Vec<f64> = set
        .tangent
        .iter()
        .map(|t| match t {
            tresca_feti::qp::sets::TangentSet::Disc(d) => d.radius,
            _ => panic!("the seed scene is isotropic"),
        })
        .collect();

    // ours, at a tight tolerance (the symmetrized methods converge only linearly there: room)
    let sol = qp::solve(&dual, &b, &set, &vec![0.0; nd], &Params { eps: 1e-11, method, max_outer: 5000, ..Params::default() }).unwrap();
    let (u_ours, _) = dual.recover(&sol.lambda);

    // the primal data: K, f, B and c = B K⁻¹ f − b
    let offsets: Vec<usize> = dual.blocks.iter().scan(0, |o, blk| {
        let s = *o;
        *o += blk.local.dofs.nfree;
        Some(s)
    }).collect();
    let nu: usize = dual.blocks.iter().map(|blk| blk.local.dofs.nfree).sum();
    let mut bkf = vec![0.0; nd];
    let (mut pi, mut pj, mut pv) = (vec![], vec![], vec![]);
    let mut q = vec![0.0; nu + m];
    let mut brows: Vec<Vec<(usize, f64)>> = vec![vec![]; nd];
    for (blk, &o) in dual.blocks.iter().zip(&offsets) {
        let k = &blk.local.sys.k;
        for j in 0..k.n {
            for p in k.col_ptr[j]..k.col_ptr[j + 1] {
                // Clarabel takes the upper triangle
                pi.push(o + j);
                pj.push(o + k.row_idx[p]);
                pv.push(k.values[p]);
            }
        }
        for (j, f) in blk.local.sys.f.iter().enumerate() {
            q[o + j] = -f;
        }
        let mut kf = blk.local.sys.f.clone();
        blk.local.chol.solve_in_place(&mut kf);
        for &(row, j, coef) in &blk.b {
            bkf[row] += coef * kf[j];
            brows[row].push((o + j, coef));
        }
    }
    let c: Vec<f64> = bkf.iter().zip(&b).map(|(x, y)| x - y).collect();
    // scaled to O(1): u = s·v with s = F/max Kⱼⱼ, F = max|f|, the objective divided by s·F
    let fmax = q.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let kmax = dual.blocks.iter().flat_map(|blk| {
        let k = &blk.local.sys.k;
        (0..k.n).map(move |j| k.values[k.col_ptr[j]].abs())
    }).fold(0.0f64, f64::max);
    let scale = fmax / kmax;
    pv.iter_mut().for_each(|v| *v /= kmax);
    q.iter_mut().for_each(|v| *v /= fmax);
    for i in 0..m {
        q[nu + i] = g[i] / fmax;
    }
    let c_scaled: Vec<f64> = c.iter().map(|v| v / scale).collect();
    // A x + s = h: rows 0..m the normal rows (s = cν − Nu ≥ 0), then per pair
    // (tᵢ, Tᵢu − cτ,ᵢ) ∈ SOC: s = (tᵢ, Tᵢu − cτ,ᵢ) = h − A x with A = −(e_t; T), h = (0; −cτ)
    let (mut ai, mut aj, mut av) = (vec![], vec![], vec![]);
    let mut h = vec![0.0; 4 * m];
    for i in 0..m {
        for &(col, coef) in &brows[layout.normal(i)] {
            ai.push(i);
            aj.push(col);
            av.push(coef);
        }
        h[i] = c_scaled[layout.normal(i)];
        let r0 = m + 3 * i;
        ai.push(r0);
        aj.push(nu + i);
        av.push(-1.0);
        for kk in 0..2 {
            let row = layout.tangent(i, kk);
            for &(col, coef) in &brows[row] {
                ai.push(r0 + 1 + kk);
                aj.push(col);
                av.push(-coef);
            }
            h[r0 + 1 + kk] = -c_scaled[row];
        }
    }
    let nx = nu + m;
    let p_mat = CscMatrix::new_from_triplets(nx, nx, pi, pj, pv);
    let a_mat = CscMatrix::new_from_triplets(4 * m, nx, ai, aj, av);
    let mut cones = vec![NonnegativeConeT(m)];
    cones.extend((0..m).map(|_| SecondOrderConeT(3)));
    let settings = DefaultSettings { verbose: false, tol_gap_abs: 1e-12, tol_gap_rel: 1e-12, tol_feas: 1e-12, max_iter: 200, ..DefaultSettings::default() };
    let mut solver = DefaultSolver::new(&p_mat, &q, &a_mat, &h, &cones, settings).unwrap();
    solver.solve();
    let status = solver.solution.status;
    assert!(matches!(status, SolverStatus::Solved | SolverStatus::AlmostSolved), "Clarabel: {status:?}");
    let x: Vec<f64> = solver.solution.x.iter().map(|v| v * scale).collect();
    let z: Vec<f64> = solver.solution.z.iter().map(|v| v * fmax).collect();

    // u: max-norm relative difference
    let mut du = 0.0f64;
    let mut su = 0.0f64;
    for (ub, &o) in u_ours.iter().zip(&offsets) {
        for (j, v) in ub.iter().enumerate() {
            du = du.max((v - x[o + j]).abs());
            su = su.max(v.abs());
        }
    }
    // multipliers: λν = z_ν, λ̄τ = −(z₁, z₂) of each cone
    let mut lam_ref = vec![0.0; nd];
    for i in 0..m {
        lam_ref[layout.normal(i)] = z[i];
        lam_ref[layout.tangent(i, 0)] = -z[m + 3 * i + 1];
        lam_ref[layout.tangent(i, 1)] = -z[m + 3 * i + 2];
    }
    let total = |lam: &[f64]| -> [f64; 3] {
        let mut f = [0.0; 3];
        for i in 0..m {
            for k in 0..3 {
                f[k] += lam[layout.normal(i)] * contact.normal[i][k]
                    + lam[layout.tangent(i, 0)] * contact.t1[i][k]
                    + lam[layout.tangent(i, 1)] * contact.t2[i][k];
            }
        }
        f
    };
    let (fo, fr) = (total(&sol.lambda), total(&lam_ref));
    let fnorm = fr.iter().map(|v| v * v).sum::<f64>().sqrt();
    let force_rel = (0..3).map(|k| (fo[k] - fr[k]).powi(2)).sum::<f64>().sqrt() / fnorm;
    // the same classifier on both: r = −(Bu − c) from Clarabel's u
    let mut r_ref = vec![0.0; nd];
    for row in 0..nd {
        r_ref[row] = c[row] - brows[row].iter().map(|&(col, coef)| coef * x[col]).sum::<f64>();
    }
    let bnorm = dual.norm(&b);
    let ours = contact_state(contact, &set, &sol.lambda, &sol.gradient, 1e-6, bnorm);
    let reference = contact_state(contact, &set, &lam_ref, &r_ref, 1e-6, bnorm);
    let counts = |s: &tresca_feti::recovery::ContactState| [s.count(OPEN), s.count(STICK), s.count(SLIP)];
    eprintln!(
        "N = {n}, {method:?}: Clarabel {status:?} in {} iterations; max|Δu|/max|u| = {:.2e}, |ΔF|/|F| = {force_rel:.2e}, open/stick/slip {:?} vs {:?}",
        solver.info.iterations,
        du / su,
        counts(&ours),
        counts(&reference)
    );
    Compared { u_rel: du / su, force_rel, counts: (counts(&ours), counts(&reference)) }
}

#[test]
fn dual_solvers_match_clarabel_on_the_primal_socp() {
    for n in [6, 8] {
        for method in Method::ALL {
            let c = compare(n, method);
            assert!(c.u_rel <= 1e-6, "N = {n} {method:?}: u differs by {:.2e}", c.u_rel);
            assert!(c.force_rel <= 1e-6, "N = {n} {method:?}: total contact force differs by {:.2e}", c.force_rel);
            assert_eq!(c.counts.0, c.counts.1, "N = {n} {method:?}: open/stick/slip counts differ");
        }
    }
}
