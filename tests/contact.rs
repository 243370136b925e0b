//! The contact solvers on the seed scene (monolithic dual): KKT conditions of the result,
//! GIMSSN's monotonicity and feasibility, and the sanity figures of docs/validation.md, "The paper's benchmark".

use std::path::Path;

use tresca_feti::comm::SerialComm;
use tresca_feti::dual::monolithic::MonolithicDual;
use tresca_feti::dual::DualProblem;
use tresca_feti::model::{self, Model};
use tresca_feti::pipeline::{assemble_and_factorize, Timings};
use tresca_feti::qp::sets::ConvexSet;
use tresca_feti::qp::{self, kkt, Method, Operator, Params, Qp, Silent, Space};
use tresca_feti::scene::{self, OrderingKind};

/// The seed scene at N = n with extra `--set` overrides.
fn seed(n: usize, sets: &[&str]) -> Model {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("run/seed.toml");
    let mut all = vec![format!("mesh.n={n}")];
    all.extend(sets.iter().map(|s| s.to_string()));
    model::build(&scene::load(&path, &all).unwrap()).unwrap()
}

#[test]
fn gimssn_seed_kkt_monotone_and_sanity_figures() {
    let model = seed(8, &[]);
    let contact = model.pairs.as_ref().unwrap();
    let bodies = assemble_and_factorize(&SerialComm, &model, OrderingKind::Metis, true, &mut Timings::default()).unwrap();
    let (dual, b) = MonolithicDual::new(&SerialComm, contact, bodies);
    let set = contact.constraint_set();
    let params = Params::new(Method::Gimssn).with_eps(1e-10);
    let sol = qp::solve(&Qp::new(&dual, &b, &set), &vec![0.0; dual.dim()], &params, &mut Silent).unwrap();
    let (lam, info) = (sol.lambda, sol.info);
    eprintln!(
        "GIMSSN N=8 ε=1e-10: {} outer, nA {} (+{} power), inner {}, err {:.2e}",
        info.iterations, info.n_a, info.n_a_power, info.inner_iterations, info.err
    );
    assert!(info.err <= 1e-10);
    // every iterate in Λ (the last one checked here; CGMfeas keeps them all there) and q monotone
    assert!(set.contains(&lam, 1e-14));
    for w in info.history.windows(2) {
        assert!(w[1].q <= w[0].q + 1e-14 * w[0].q.abs(), "q increased: {} → {}", w[0].q, w[1].q);
    }
    // KKT with a fresh residual r = Aλ − b = −(Bu − c)
    let m = contact.len();
    let mut r = vec![0.0; dual.dim()];
    dual.apply(&lam, &mut r);
    r.iter_mut().zip(&b).for_each(|(ri, bi)| *ri -= bi);
    assert_eq!(r, sol.gradient, "the returned gradient is a fresh Aλ − b");
    let k = kkt::residuals(&set, &lam, &r, dual.space().norm(&b));
    assert!(k.worst() <= 1e-9, "KKT residuals {k:?}");
    let bn = dual.space().norm(&b);
    let lmax = lam.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let (mut carrying, mut sliding) = (0, 0);
    for i in 0..m {
        // non-penetration Nu − d ≤ 0 ⇔ r ≥ 0, λν ≥ 0, complementarity
        assert!(r[i] >= -1e-8 * bn, "penetration at {i}: {}", r[i]);
        assert!(lam[i] * r[i].abs() <= 1e-8 * bn * lmax, "complementarity at {i}");
        if lam[i] > 1e-8 * lmax {
            carrying += 1;
        }
        let g = match set.tangent[i] {
            tresca_feti::qp::sets::TangentSet::Disc(d) => d.radius,
            _ => unreachable!(),
        };
        let k = set.layout.tangent(i, 0);
        let (lt, rt) = ([lam[k], lam[k + 1]], [r[k], r[k + 1]]);
        let nl = lt[0].hypot(lt[1]);
        assert!(nl <= g * (1.0 + 1e-12), "friction bound at {i}");
        if nl >= g * (1.0 - 1e-9) {
            // slip: ūτ = −rτ = c λτ with c ≥ 0 → rτ·λτ ≤ 0 and rτ ∥ λτ
            sliding += 1;
            assert!(rt[0] * lt[0] + rt[1] * lt[1] <= 1e-8 * bn * g);
            assert!((rt[0] * lt[1] - rt[1] * lt[0]).abs() <= 1e-8 * bn * g);
        } else {
            // stick: ūτ = 0
            assert!(rt[0].hypot(rt[1]) <= 1e-8 * bn, "stick pair {i} moves: {rt:?}");
        }
        assert!(set.tangent[i].contains(&lt, 1e-14 * g));
    }
    // the paper's sanity figures (docs/validation.md, "The paper's benchmark") for N = 8
    assert_eq!((carrying, sliding), (32, 48));
    let u = dual.recover(&lam).u;
    let umax =
        dual.blocks.iter().zip(&u).flat_map(|(blk, ub)| blk.local.dofs.expand(ub)).map(|v| v.iter().fold(0.0f64, |a, c| a.max(c.abs()))).fold(0.0, f64::max);
    // the largest displacement component (the paper's "max |u|" is the max-norm of u ∈ Rⁿ)
    assert!((umax - 8.7e-5).abs() < 0.05e-5, "max |u| = {umax:e}");
}

/// u of the seed scene with the given `--set` overrides, solved by GIMSSN at ε.
fn solve_u(n: usize, sets: &[&str], eps: f64) -> Vec<[f64; 3]> {
    solve_u_with(n, sets, eps, Method::Gimssn).0
}

/// u of the seed scene solved by `method` at ε, with the KKT residuals of the result.
fn solve_u_with(n: usize, sets: &[&str], eps: f64, method: Method) -> (Vec<[f64; 3]>, kkt::Kkt) {
    let model = seed(n, sets);
    let contact = model.pairs.as_ref().unwrap();
    let bodies = assemble_and_factorize(&SerialComm, &model, OrderingKind::Metis, true, &mut Timings::default()).unwrap();
    let (dual, b) = MonolithicDual::new(&SerialComm, contact, bodies);
    let set = contact.constraint_set();
    let sol = qp::solve(&Qp::new(&dual, &b, &set), &vec![0.0; dual.dim()], &Params::new(method).with_eps(eps), &mut Silent).unwrap();
    assert!(set.contains(&sol.lambda, 1e-14), "{method:?} returned λ ∉ Λ");
    if matches!(method, Method::Gimssn | Method::Mpgp) {
        // the monotone methods: q never increases
        for w in sol.info.history.windows(2) {
            assert!(w[1].q <= w[0].q + 1e-13 * w[0].q.abs(), "{method:?} {sets:?}: q increased {} → {}", w[0].q, w[1].q);
        }
    }
    let k = kkt::residuals(&set, &sol.lambda, &sol.gradient, dual.space().norm(&b));
    let u = dual.recover(&sol.lambda).u;
    (dual.blocks.iter().zip(&u).flat_map(|(blk, ub)| blk.local.dofs.expand(ub)).collect(), k)
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> (f64, f64) {
    let d = a.iter().zip(b).flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs())).fold(0.0, f64::max);
    let s = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    (d, s)
}

#[test]
fn orthotropic_with_equal_bounds_is_isotropic() {
    let iso = solve_u(6, &[], 1e-11);
    for dir in ["[1.0, 0.0, 0.0]", "[0.3, -0.8, 0.2]"] {
        let f = format!("contact.pair.0.friction={{type=\"orthotropic\", g1=0.09, g2=0.09, direction={dir}}}");
        let ortho = solve_u(6, &[&f], 1e-11);
        let (d, s) = max_diff(&iso, &ortho);
        assert!(d <= 1e-8 * s, "direction {dir}: max difference {d:e} of {s:e}");
    }
    // a genuinely orthotropic law changes the answer
    let f = "contact.pair.0.friction={type=\"orthotropic\", g1=0.09, g2=0.01, direction=[0.0, 1.0, 0.0]}";
    let (d, s) = max_diff(&iso, &solve_u(6, &[f], 1e-11));
    assert!(d > 1e-4 * s, "g2 ≠ g1 should matter: {d:e}");
}

/// A block pressed onto a fixed block and dragged along x by a prescribed displacement of its
/// top face, in plane strain (two nodes across y, u_y = 0 on both y faces) so that every slip is
/// exactly along x. Returns (pairs, the contact report).
fn dragged_block(drag: f64) -> (usize, tresca_feti::pipeline::report::ContactReport) {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("tresca-feti-drag-{}-{drag:e}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("drag.toml");
    std::fs::write(
        &scene,
        format!(
            r#"
[[material]]
name = "steel"
E = 50000.0
nu = 0.3
[[body]]
name = "top"
material = "steel"
box = {{ min = [0.0, 0.0, 1.0], max = [2.0, 1.0, 1.5], nodes = [9, 2, 4] }}
[[body]]
name = "base"
material = "steel"
box = {{ min = [0.0, 0.0, 0.5], max = [2.0, 1.0, 1.0], nodes = [9, 2, 4] }}
[[dirichlet]]
face = "top.zmax"
value = [{drag}, 0.0, -1e-4]
[[dirichlet]]
face = "base.zmin"
[[dirichlet]]
face = "top.ymin"
components = ["y"]
[[dirichlet]]
face = "top.ymax"
components = ["y"]
[[dirichlet]]
face = "base.ymin"
components = ["y"]
[[dirichlet]]
face = "base.ymax"
components = ["y"]
[[contact.pair]]
slave = "top.zmin"
master = "base.zmax"
friction = {{ type = "tresca", g = 0.09 }}
[solver]
eps = 1e-10
"#
        ),
    )
    .unwrap();
    let s = tresca_feti::pipeline::run_solve(&SerialComm, &scene, &[], Some(dir.join("drag.h5")), true).unwrap();
    let c = s.report.contact.expect("a contact report");
    (c.pairs, c)
}

#[test]
fn dragged_block_slides_above_the_slip_bound_and_sticks_below() {
    // area 2 m², g = 0.09 MPa: the friction force cannot exceed g·A = 0.18 MN
    let (m, c) = dragged_block(1e-3);
    assert_eq!(m, 18);
    assert_eq!(c.slip, m, "{c:?}");
    let fx = c.total_force_on_slave[0];
    assert!((fx.abs() - 0.09 * 2.0).abs() <= 1e-8, "friction force {fx} ≠ g·A");
    assert!(fx < 0.0, "friction must oppose the drag: {fx}");
    let (_, c) = dragged_block(1e-7);
    assert_eq!(c.stick, m, "{c:?}");
    let fx = c.total_force_on_slave[0];
    assert!(fx.abs() < 0.5 * 0.18, "sticking friction force {fx} should be well below g·A");
}

#[test]
fn all_five_solvers_agree_and_satisfy_kkt() {
    // isotropic Tresca (the seed), frictionless (no tangential multipliers), and orthotropic
    let cases: [&[&str]; 3] =
        [&[], &["contact.pair.0.friction={type=\"none\"}"], &["contact.pair.0.friction={type=\"orthotropic\", g1=0.09, g2=0.03, direction=[1.0, 0.0, 0.0]}"]];
    for sets in cases {
        let (reference, _) = solve_u_with(6, sets, 1e-11, Method::Gimssn);
        for m in Method::ALL {
            let (u, k) = solve_u_with(6, sets, 1e-11, m);
            let (d, s) = max_diff(&reference, &u);
            eprintln!("{sets:?} {m:?}: max |u − u_GIMSSN| = {d:.2e} of {s:.2e}, KKT {:.1e}", k.worst());
            assert!(d <= 1e-8 * s, "{sets:?} {m:?}: max difference {d:e} of {s:e}");
            assert!(k.worst() <= 1e-8, "{sets:?} {m:?}: KKT residuals {k:?}");
        }
    }
}

#[test]
fn coulomb_equals_tresca_with_the_bounds_at_its_solution() {
    // the Coulomb solution λ* is a fixed point: the Tresca problem with gᵢ = μ·λν,ᵢ* fixed has
    // the same solution (a Tresca solve from zero, not warm-started)
    let model = seed(6, &["contact.pair.0.friction={type=\"coulomb\", mu=0.3}"]);
    let contact = model.pairs.as_ref().unwrap();
    let bodies = assemble_and_factorize(&SerialComm, &model, OrderingKind::Metis, true, &mut Timings::default()).unwrap();
    let (dual, b) = MonolithicDual::new(&SerialComm, contact, bodies);
    let set = contact.constraint_set();
    let mut params = Params::new(Method::Tssn).with_eps(1e-11);
    params.common.coulomb = qp::params::CoulombSolve::FixedPoint;
    let zero = vec![0.0; dual.dim()];
    let coulomb = qp::solve_friction(&Qp::new(&dual, &b, &set), Some(&contact.coulomb), &zero, &params, &mut Silent).unwrap();
    let fixed = qp::cone::bounds(&set, &contact.coulomb, &coulomb.lambda);
    let tresca = qp::solve(&Qp::new(&dual, &b, &fixed), &zero, &params, &mut Silent).unwrap();
    let (uc, ut) = (dual.recover(&coulomb.lambda).u, dual.recover(&tresca.lambda).u);
    let (mut d, mut m) = (0.0f64, 0.0f64);
    for (a, b) in uc.iter().flatten().zip(ut.iter().flatten()) {
        d = d.max((a - b).abs());
        m = m.max(a.abs());
    }
    eprintln!("Coulomb ({} fixed-point steps) vs Tresca at its bounds: max|Δu|/max|u| = {:.2e}", coulomb.info.fixed_point_iterations, d / m);
    assert!(coulomb.info.fixed_point_iterations >= 2, "a real fixed point");
    assert!(d <= 1e-8 * m, "u differs by {:.2e} relative", d / m);
    // the Newton method on the Coulomb law lands on the same solution
    params.common.coulomb = qp::params::CoulombSolve::Newton;
    let newton = qp::solve_friction(&Qp::new(&dual, &b, &set), Some(&contact.coulomb), &zero, &params, &mut Silent).unwrap();
    let un = dual.recover(&newton.lambda).u;
    let dn = un.iter().flatten().zip(uc.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    eprintln!("Newton on the Coulomb law: {} products against the fixed point's {}, max|Δu|/max|u| = {:.2e}", newton.info.n_a, coulomb.info.n_a, dn / m);
    assert!(newton.info.fixed_point_iterations == 0 && dn <= 1e-8 * m, "Newton vs fixed point {:.2e}", dn / m);
    // and so does TSSN with lagged bounds
    params.common.coulomb = qp::params::CoulombSolve::Lagged;
    let lagged = qp::solve_friction(&Qp::new(&dual, &b, &set), Some(&contact.coulomb), &zero, &params, &mut Silent).unwrap();
    let ul = dual.recover(&lagged.lambda).u;
    let dl = ul.iter().flatten().zip(uc.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    eprintln!("TSSN with lagged bounds: {} products, max|Δu|/max|u| = {:.2e}", lagged.info.n_a, dl / m);
    assert!(lagged.info.coulomb == Some(qp::params::CoulombSolve::Lagged) && dl <= 1e-8 * m, "lagged vs fixed point {:.2e}", dl / m);
    // and it is not a Tresca solution for any other bound: with g from λν of the elastic guess it differs
    let slip = qp::solve(&Qp::new(&dual, &b, &qp::cone::bounds(&set, &contact.coulomb, &zero)), &zero, &params, &mut Silent).unwrap();
    let us = dual.recover(&slip.lambda).u;
    let ds = us.iter().flatten().zip(uc.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(ds > 1e-4 * m, "frictionless bounds give a different u ({:.1e})", ds / m);
}

/// What the output says matches what was solved: a frictionless seed is "frictionless contact"
/// with its closed pairs "in contact" (status 4, neither stick nor slip) in the report and the
/// result file; two pairs of different laws are named each; the iteration table's stick and slip
/// columns count closed pairs only (a Tresca bound acts on open pairs too); DOF counts agree with
/// `check` under TFETI; the scene's units are printed. Before: "contact with Tresca friction",
/// status 3 (slip), slip counts over open pairs, "free DOFs" over the DOFs under TFETI, "m".
#[test]
fn the_report_names_the_law_the_states_and_the_units_as_solved() {
    let seed = Path::new(env!("CARGO_MANIFEST_DIR")).join("run/seed.toml");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("tresca-feti-contact-{}-truth", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let run = |sets: &[&str], name: &str| {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        tresca_feti::pipeline::run_solve(&SerialComm, &seed, &sets, Some(dir.join(name)), true).unwrap()
    };
    let free = run(&["mesh.n=6", "contact.pair.0.friction={type=\"none\"}"], "free.h5");
    let c = free.report.contact.as_ref().unwrap();
    assert_eq!(free.report.problem, "frictionless contact (monolithic dual)");
    assert!(c.contact > 0 && c.stick == 0 && c.slip == 0 && c.open + c.contact == c.pairs, "{c:?}");
    let f = tresca_feti::output::hdf5::read(&dir.join("free.h5")).unwrap();
    let Some(tresca_feti::output::Values::I32(st)) = f.fields.iter().find(|x| x.name == "contact_status").map(|x| x.values.clone()) else {
        panic!("contact_status")
    };
    assert_eq!(st.iter().filter(|&&s| s == tresca_feti::contact::state::CONTACT).count(), c.contact);
    assert!(!st.contains(&tresca_feti::contact::state::SLIP));
    // Tresca: stick + slip ≤ closed at every outer iteration, and the last step's slip ≤ closed
    let tresca = run(&["mesh.n=6"], "tresca.h5");
    let sv = tresca.report.solver.as_ref().unwrap();
    assert!(
        sv.info.history.iter().all(|h| h.stick + h.slip <= h.normal_active),
        "{:?}",
        sv.info.history.iter().map(|h| (h.normal_active, h.stick, h.slip)).collect::<Vec<_>>()
    );
    assert!(sv.info.history.iter().any(|h| h.slip > 0));
    assert_eq!(tresca.report.problem, "contact with Tresca friction (monolithic dual)");
    // units from the scene, in the JSON and the summary
    let u = tresca.report.units.as_ref().expect("the seed names its units");
    assert_eq!((u.length.as_deref(), u.force.as_deref(), u.stress.as_deref()), (Some("m"), Some("MN"), Some("MPa")));
    let mm = run(&["mesh.n=4", "units={length=\"mm\", force=\"N\"}"], "mm.h5");
    assert_eq!(mm.report.units.as_ref().and_then(|u| u.stress.clone()).as_deref(), Some("MPa"));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tresca-feti"))
        .args([
            "solve",
            seed.to_str().unwrap(),
            "--quiet",
            "--set",
            "mesh.n=4",
            "--set",
            "units={length=\"mm\", force=\"N\"}",
            "--out",
            dir.join("p.h5").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains(" mm (body ") && text.contains(") N\n") && text.contains(" MPa\n"), "{text}");
    // TFETI DOF counts consistent with check
    let two = run(&["mesh.n=4", "decomposition.subdomains=2"], "tfeti.h5");
    let m = &two.report.mesh;
    assert!(m.free_dofs < m.dofs && m.subdomain_dofs.is_some_and(|s| s > m.dofs), "{m:?}");
    let check = std::process::Command::new(env!("CARGO_BIN_EXE_tresca-feti"))
        .args(["check", seed.to_str().unwrap(), "--set", "mesh.n=4", "--set", "decomposition.subdomains=2"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(text.contains(&format!("({} free after Dirichlet elimination)", m.free_dofs)), "{text}");
    let bad =
        std::process::Command::new(env!("CARGO_BIN_EXE_tresca-feti")).args(["check", seed.to_str().unwrap(), "--set", "units.length=\"\""]).output().unwrap();
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.lines().count() == 1 && err.contains("units.length"), "{err}");
}
