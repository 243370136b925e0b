//! What every returned result must satisfy (`pipeline::accuracy`) and the loads no solution
//! exists for (`contact::hold`): a load path whose last step carries no force solves at the
//! default ε (the recovered equilibrium judged against the rounding of the whole problem); a
//! result that misses its check at a loose ε is continued at a tighter one and says so; the
//! KKT residual of an all-open step is measured at the problem's force scale and judged; a body
//! held by contact alone and pushed beyond what friction holds is refused before any solve,
//! naming the body and the direction.

mod common;

use std::process::Command;

use common::{root, solve, tmpdir, BIN};

#[test]
fn a_coulomb_load_path_that_lifts_off_solves_at_the_default_eps() {
    // before: "subdomain 0 (body "upper"): K u = f − Bᵀλ does not hold (relative residual
    // 2.1e-6)" at the default ε, 6.9e-6 at ε = 1e-9 (and a NaN in the fixed point first)
    let scene = root().join("run/stress/coulomb_lift_off_path.toml");
    let dir = tmpdir("lift-off-path");
    for (i, sets) in [vec![], vec!["solver.eps=1e-9"], vec!["decomposition.subdomains=1"]].iter().enumerate() {
        let r = solve(&scene, sets, &dir.join(format!("r{i}.h5")));
        let steps = r.report.load_path.as_ref().expect("a load path");
        let last = steps.last().unwrap();
        assert_eq!((last.open, last.stick, last.slip), (81, 0, 0), "{sets:?}: the last step lifts off");
        assert!(last.total_force_on_slave.iter().all(|f| f.abs() <= 1e-9), "{sets:?}: no force: {:?}", last.total_force_on_slave);
        // the exact last state: the upper block 2 mm up, rigidly; the lower one at rest
        // bodies in scene order, 9³ nodes each: the upper one first
        let u = &r.solution.displacement;
        assert_eq!(u.len(), 2 * 729);
        let err = u.iter().enumerate().map(|(v, d)| d[0].abs().max(d[1].abs()).max((d[2] - if v < 729 { 0.002 } else { 0.0 }).abs())).fold(0.0, f64::max);
        assert!(err <= 1e-9, "{sets:?}: u differs from the rigid lift by {err:.1e}");
        let kkt = r.report.solver.as_ref().unwrap().kkt_worst;
        assert!(kkt <= 1e-8, "{sets:?}: KKT {kkt:.1e} (every pair open: 0 at the problem's force scale)");
        for s in steps {
            assert!(s.kkt_worst <= 100.0 * 1e-8, "{sets:?}: step {} KKT {:.1e}", s.step, s.kkt_worst);
        }
    }
}

#[test]
fn a_loose_eps_is_tightened_until_the_result_passes_its_check_and_the_summary_says_so() {
    // before: at ε = 1e-3 "subdomain 1 (body "upper"): K u = f − Bᵀλ does not hold (relative
    // residual 8.9e-5)": SMALSE-M's Gλ = e holds to ε only, and the user had to tune ε
    // (SMALSE-M asked for: the restricted TSSN path, the default, keeps Gλ = e to round-off)
    let scene = root().join("run/validation/floating_block.toml");
    let dir = tmpdir("tightened");
    let out = dir.join("r.h5");
    let o = Command::new(BIN)
        .args([
            "solve",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
            "--set",
            "solver.eps=1e-3",
            "--set",
            "decomposition.subdomains=2",
            "--set",
            "decomposition.restricted=false",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("accuracy guard: ε tightened 1.0e-3 →"), "{stdout}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.with_extension("json")).unwrap()).unwrap();
    let t = &report["solver"]["eps_tightened"];
    assert!(t.as_array().is_some_and(|a| !a.is_empty()) && t[0]["reason"].as_str().unwrap().contains("K u = f − Bᵀλ"), "{t}");
    // and the answer is the equilibrium: the contact balances the load (2 down, 0.3 along x)
    let f = &report["contact"]["total_force_on_slave"];
    let f: Vec<f64> = (0..3).map(|i| f[i].as_f64().unwrap()).collect();
    assert!((f[0] + 0.3).abs() <= 1e-5 && f[1].abs() <= 1e-5 && (f[2] - 2.0).abs() <= 1e-5, "{f:?}");
    // at the default ε nothing is tightened: the same counters as without the guard
    let r = solve(&scene, &["decomposition.subdomains=2"], &dir.join("d.h5"));
    assert!(r.report.solver.as_ref().unwrap().eps_tightened.is_empty());
}

/// The floating block of `run/validation/floating_block.toml` pushed sideways by `push` (its
/// xmin face's traction; the normal load is 2) under `friction`.
fn pushed(push: f64, friction: &str) -> String {
    let base = std::fs::read_to_string(root().join("run/validation/floating_block.toml")).unwrap();
    let s = base.replace("p = [0.3, 0.0, 0.0]", &format!("p = [{push}, 0.0, 0.0]")).replace("friction = { type = \"coulomb\", mu = 0.3 }", friction);
    assert_ne!(s, base);
    s
}

#[test]
fn a_load_no_friction_can_hold_is_refused_before_the_solve_naming_body_and_direction() {
    // before: "SMALSE-M (SSN-BICGSTAB): no convergence in 10 outer iterations, 2015 A-products"
    let dir = tmpdir("unheld");
    let cases = [("coulomb", pushed(0.7, "friction = { type = \"coulomb\", mu = 0.3 }")), ("tresca", pushed(0.7, "friction = { type = \"tresca\", g = 0.3 }"))];
    for (name, scene) in &cases {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, scene).unwrap();
        let out = dir.join(format!("out-{name}")).join("r.h5");
        for verb in ["solve", "check"] {
            let t0 = std::time::Instant::now();
            let mut args = vec![verb, path.to_str().unwrap()];
            if verb == "solve" {
                args.extend(["--out", out.to_str().unwrap()]);
            }
            let o = Command::new(BIN).args(&args).output().unwrap();
            let stderr = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(1), "{name} {verb}: {stderr}");
            let lines: Vec<&str> = stderr.lines().collect();
            assert_eq!(lines.len(), 1, "{name} {verb}: {stderr}");
            for want in ["body \"upper\"", "no equilibrium exists", "translation along x", "slide away"] {
                assert!(lines[0].contains(want), "{name} {verb}: `{want}` not in {}", lines[0]);
            }
            assert!(t0.elapsed().as_secs_f64() < 20.0, "{name} {verb}: {:.1} s", t0.elapsed().as_secs_f64());
        }
        assert!(!out.exists() && !out.parent().unwrap().exists(), "{name}: no result");
    }
    // Tresca: the numbers are the forces along x (T = 0.7 against Σg = 0.3 · 2 = 0.6)
    let path = dir.join("tresca.toml");
    let o = Command::new(BIN).args(["check", path.to_str().unwrap()]).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains(
            "the applied force along x is 7.0000e-1; with its other components as applied, contact and friction hold at most 6.0000e-1 along it, 1.000e-1 less"
        ),
        "{stderr}"
    );
    // below the limit both solve (T = 0.55 < 0.6)
    for (name, friction) in [("coulomb", "friction = { type = \"coulomb\", mu = 0.3 }"), ("tresca", "friction = { type = \"tresca\", g = 0.3 }")] {
        let path = dir.join(format!("{name}-held.toml"));
        std::fs::write(&path, pushed(0.55, friction)).unwrap();
        let r = solve(&path, &[], &dir.join(format!("{name}-held.h5")));
        let f = r.report.contact.as_ref().unwrap().total_force_on_slave;
        assert!((f[0] + 0.55).abs() <= 1e-7 && (f[2] - 2.0).abs() <= 1e-7, "{name}: {f:?}");
    }
}

/// The guard's refusal end to end (a result that misses its check, injected on one rank with
/// `TRESCA_FETI_FAULT=accuracy@<rank>`): exit 1 on every rank, one line naming the solver and
/// the check, no result file — on one process (monolithic dual) and under mpirun -n 2 with the
/// miss on rank 1 (TFETI).
#[test]
fn a_result_that_fails_its_check_is_refused_with_one_line_and_no_file() {
    let dir = common::tmpdir("guard-refusal");
    let seed = common::root().join("run/seed.toml");
    for (name, ranks, fault, sets) in
        [("mono", 1, "accuracy@0", vec!["mesh.n=6"]), ("tfeti", 2, "accuracy@1", vec!["mesh.n=6", "decomposition.subdomains=2", "decomposition.tfeti=true"])]
    {
        let out = dir.join(name).join("r.h5");
        let mut args = vec!["solve", seed.to_str().unwrap(), "-q", "--out", out.to_str().unwrap()];
        for s in &sets {
            args.extend(["--set", s]);
        }
        let o = if ranks == 1 {
            std::process::Command::new(common::BIN).args(&args).env("TRESCA_FETI_FAULT", fault).output().unwrap()
        } else {
            common::mpirun_cmd(ranks, &args).env("TRESCA_FETI_FAULT", fault).output().unwrap()
        };
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{name}: {stderr}");
        if ranks == 1 {
            assert_eq!(o.status.code(), Some(1), "{name}: {stderr}");
        }
        let ours: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
        assert_eq!(ours.len(), 1, "{name}: {stderr}");
        assert!(ours[0].contains("the result fails its accuracy check") && ours[0].contains("the recovered equilibrium"), "{name}: {}", ours[0]);
        let left: Vec<_> = std::fs::read_dir(dir.join(name)).map(|d| d.flatten().map(|e| e.path()).collect()).unwrap_or_default();
        assert!(left.is_empty(), "{name}: files left behind: {left:?}");
    }
}
