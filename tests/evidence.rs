//! The evidence commands as a user runs them: `work-precision` (every row measured against the
//! reference, errors falling with ε, Clarabel agreeing, the CSV the plot script reads, the plot)
//! and `stability` (converged, stopped-with-a-reason and wrong runs told apart, exit codes; also
//! through its alias `stress`).

mod common;

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use common::{root, tmpdir, BIN};

fn csv(path: &Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines.map(|l| head.iter().cloned().zip(l.split(',').map(String::from)).collect()).collect()
}

fn num(r: &HashMap<String, String>, k: &str) -> f64 {
    r[k].parse().unwrap_or_else(|_| panic!("{k} = {:?}", r[k]))
}

#[test]
fn work_precision_measures_every_row_against_the_reference() {
    let dir = tmpdir("wp");
    let path = dir.join("wp.csv");
    let o = Command::new(BIN)
        .args(["work-precision", "--scene", root().join("run/seed.toml").to_str().unwrap(), "--sizes", "5", "--eps", "1e-3,1e-6,1e-9"])
        .args(["--clarabel-eps", "1e-4,1e-9", "--solvers", "gimssn,ssn-bicgstab,tssn,mpgp,clarabel", "--csv", path.to_str().unwrap()])
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("err(u) ≤ 1e-6") && out.contains("tssn (default)"), "{out}");
    let rows = csv(&path);
    assert_eq!(rows.len(), 4 * 3 + 2, "{rows:?}");
    for solver in ["gimssn", "ssn-bicgstab", "mpgp"] {
        let r: Vec<_> = rows.iter().filter(|r| r["solver"] == solver).collect();
        assert!(r.iter().all(|r| r["status"] == "ok"), "{solver}: {r:?}");
        let err: Vec<f64> = r.iter().map(|r| num(r, "err_u")).collect();
        // the sweep runs loose → tight; the error follows ε (within two orders) and falls
        for (r, e) in r.iter().zip(&err) {
            let eps = num(r, "eps");
            assert!(*e <= 100.0 * eps && num(r, "kkt") <= 10.0 * eps && num(r, "residual") <= eps, "{solver} at ε = {eps}: {r:?}");
        }
        assert!(err[2] < err[1] && err[1] < err[0], "{solver}: {err:?}");
    }
    // Clarabel solves the primal SOCP: at its tight tolerance it agrees with the dual reference
    // (to its own accuracy: an interior-point solution is good to about 1e-6 in u here)
    let c: Vec<_> = rows.iter().filter(|r| r["solver"] == "clarabel").collect();
    assert_eq!(c.len(), 2);
    assert!(c.iter().all(|r| r["status"] == "ok" && num(r, "nA") == 0.0), "{c:?}");
    assert!(num(c[1], "err_u") < 1e-5 && num(c[1], "err_lambda") < 1e-5 && num(c[1], "kkt") < 1e-6, "{:?}", c[1]);
    assert!(num(c[1], "err_u") < num(c[0], "err_u"));
    // the plot script reads the CSV
    if Command::new("gnuplot").arg("--version").output().is_ok() {
        let p = Command::new(root().join("run/work-precision-plot")).args([path.to_str().unwrap(), dir.to_str().unwrap()]).output().unwrap();
        assert!(p.status.success(), "{}", String::from_utf8_lossy(&p.stderr));
        let png = std::fs::read(dir.join("work_precision_N5.png")).unwrap();
        assert_eq!(&png[1..4], b"PNG");
    }
}

/// The dual solvers on the TFETI dual beside the monolithic one: every row against the same
/// monolithic reference (u of every subdomain copy), the preconditioned TSSN rows on TFETI only,
/// one plot per dual.
#[test]
fn work_precision_runs_the_dual_solvers_on_tfeti_too() {
    let dir = tmpdir("wp_tfeti");
    let path = dir.join("wp.csv");
    let o = Command::new(BIN)
        .args(["work-precision", "--scene", root().join("run/seed.toml").to_str().unwrap(), "--sizes", "5", "--subdomains", "0,2", "--eps", "1e-4,1e-8"])
        .args(["--solvers", "ssn-bicgstab,tssn,tssn:dirichlet", "--csv", path.to_str().unwrap()])
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("N = 5, TFETI S = 2 (") && out.contains("N = 5, monolithic ("), "{out}");
    let rows = csv(&path);
    let on = |s: &str| rows.iter().filter(|r| r["S"] == s).count();
    // tssn:dirichlet has no monolithic row
    assert_eq!((on("0"), on("2")), (4, 6), "{rows:?}");
    assert!(!rows.iter().any(|r| r["S"] == "0" && r["solver"] == "tssn:dirichlet"));
    for r in &rows {
        let eps = num(r, "eps");
        assert!(r["status"] == "ok" && num(r, "err_u") <= 100.0 * eps && num(r, "kkt") <= 10.0 * eps, "{r:?}");
        assert!(num(r, "nA") > 0.0, "{r:?}");
    }
    // the preconditioned TSSN takes fewer products than plain TSSN on the same TFETI dual
    let na = |solver: &str| rows.iter().filter(|r| r["S"] == "2" && r["solver"] == solver && r["eps"] == "1e-8").map(|r| num(r, "nA")).sum::<f64>();
    assert!(na("tssn:dirichlet") < na("tssn"), "{rows:?}");
    if Command::new("gnuplot").arg("--version").output().is_ok() {
        let p = Command::new(root().join("run/work-precision-plot")).args([path.to_str().unwrap(), dir.to_str().unwrap()]).output().unwrap();
        assert!(p.status.success(), "{}", String::from_utf8_lossy(&p.stderr));
        for png in ["work_precision_N5.png", "work_precision_N5_S2.png"] {
            assert_eq!(&std::fs::read(dir.join(png)).unwrap()[1..4], b"PNG", "{png}");
        }
    }
}

#[test]
fn work_precision_bad_arguments_give_one_line() {
    for (args, key) in [
        (&["--eps", "0"][..], "--eps"),
        (&["--sizes", "1"], "--sizes"),
        (&["--solvers", "newton"], "newton"),
        (&["--solvers", "imssn:dirichlet"], "imssn takes no preconditioner"),
        (&["--subdomains", "2", "--set", "decomposition.projector=\"orthogonal\""], "--subdomains"),
        (&["--max-seconds=-1"], "--max-seconds"),
        (&["--csv", "/proc/no-such-dir/x.csv"], "/proc/no-such-dir"),
    ] {
        let o = Command::new(BIN).arg("work-precision").args(args).output().unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        // errors in values: one line, exit 1; usage errors as clap prints them, exit 2
        let one_line = o.status.code() == Some(1) && e.lines().count() == 1;
        let usage = o.status.code() == Some(2) && e.starts_with("error: ") && e.contains("'--help'");
        assert!((one_line || usage) && e.contains(key), "{args:?}: {e}");
    }
}

/// A stability-suite folder: one scene that converges and one that cannot in its iterations.
fn stability_dir(name: &str) -> std::path::PathBuf {
    let dir = tmpdir(name);
    let scenes = dir.join("scenes");
    std::fs::create_dir_all(&scenes).unwrap();
    let seed = std::fs::read_to_string(root().join("run/seed.toml")).unwrap().replace("n = 16", "n = 5");
    std::fs::write(scenes.join("a_fine.toml"), &seed).unwrap();
    std::fs::write(scenes.join("b_short.toml"), seed.replace("eps = 1e-8", "eps = 1e-8\nmax_outer = 2")).unwrap();
    dir
}

#[test]
fn stability_tells_converged_stopped_and_wrong_apart() {
    let dir = stability_dir("stability");
    let run = |extra: &[&str]| {
        Command::new(BIN)
            .args(["stability", "--dir", dir.join("scenes").to_str().unwrap(), "--out", dir.join("out").to_str().unwrap()])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run(&[]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.starts_with("stability suite: "), "{out}");
    assert!(line_of(&out, "a_fine").ends_with("converged"), "{out}");
    assert!(line_of(&out, "b_short").contains("stopped: TSSN: no convergence in 2 outer iterations"), "{out}");
    assert!(out.contains("2 scenes: 1 converged, 1 stopped with a reason, 0 wrong"), "{out}");
    assert!(dir.join("out/a_fine.h5").exists() && !dir.join("out/b_short.h5").exists());
    let rows = csv(&dir.join("out/stability.csv"));
    assert_eq!(rows.len(), 2);
    assert!(num(&rows[0], "kkt") <= 100.0 * 1e-8 && num(&rows[0], "residual") <= 1e-8, "{rows:?}");
    // a KKT bound no run can meet turns a converged run into a wrong one: exit 1, one error line
    let o = run(&["--kkt-factor", "1e-6"]);
    let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(line_of(&out, "a_fine").contains("WRONG: KKT residual"), "{out}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("the stability suite: 1 scene(s) returned a result that fails its checks"), "{err}");
    // an empty folder is a clear error (through the alias `stress`)
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let o = Command::new(BIN).args(["stress", "--dir", empty.to_str().unwrap(), "--out", dir.join("o2").to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("holds no *.toml scene") && err.lines().count() == 1, "{err}");
}

fn line_of(out: &str, name: &str) -> String {
    out.lines().find(|l| l.starts_with(name)).unwrap_or_else(|| panic!("{out}")).to_string()
}

#[test]
fn siconos_solves_the_exported_coulomb_problem_to_our_solution() {
    // the peer check: tresca-feti exports the Coulomb problem it solved on the monolithic dual
    // (W = B K⁻¹ Bᵀ, q, μ per contact, its r); Siconos' fc3d NSGS solves it from zero and must
    // land on tresca-feti's r (partial slip: some pairs stick, some slide)
    let dir = tmpdir("siconos");
    let dual = dir.join("dual.h5");
    let o = Command::new(BIN)
        .args(["solve", root().join("run/stress/coulomb_partial_slip.toml").to_str().unwrap(), "--quiet", "--out", dir.join("r.h5").to_str().unwrap()])
        .args(["--set", "mesh.n=6", "--set", "solver.eps=1e-12", "--set", &format!("output.export_dual=\"{}\"", dual.display())])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let check = Command::new("/usr/bin/python3")
        .arg(root().join("run/peer/siconos_check.py"))
        .arg(&dual)
        .arg("3e-11")
        .output()
        .expect("python3 (run/install-deps installs python3-siconos)");
    let out = String::from_utf8_lossy(&check.stdout);
    assert!(check.status.success(), "{out}{}", String::from_utf8_lossy(&check.stderr));
    assert!(out.contains("in contact") && out.contains("max|r_siconos - r_tresca_feti|"), "{out}");
}

#[test]
fn siconos_global_solver_solves_our_fclib_export_to_our_solution() {
    // `--export-fclib` writes the solved problem in the FCLIB global format (M = K, H = −Bᵀ, f,
    // w = c, μ, our v and r as the guess); Siconos' gfc3d (NSGS_WR) solves it from zero on the
    // file's arrays alone and must land on our v and r — under mpirun -n 2 too (gathered)
    let dir = tmpdir("fclib");
    for ranks in [1, 2] {
        let file = dir.join(format!("fclib{ranks}.h5"));
        let out = dir.join(format!("r{ranks}.h5"));
        let scene = root().join("run/stress/coulomb_partial_slip.toml");
        let args = [
            "solve",
            scene.to_str().unwrap(),
            "--quiet",
            "--out",
            out.to_str().unwrap(),
            "--set",
            "mesh.n=6",
            "--set",
            "solver.eps=1e-12",
            "--set",
            "decomposition.subdomains=1",
            "--export-fclib",
            file.to_str().unwrap(),
        ];
        let o = if ranks == 1 { Command::new(BIN).args(args).output().unwrap() } else { common::mpirun(2, &args) };
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let check = Command::new("/usr/bin/python3")
            .arg(root().join("run/peer/fclib_check.py"))
            .arg(&file)
            .arg("3e-11")
            .output()
            .expect("python3 (run/install-deps installs python3-siconos)");
        let text = String::from_utf8_lossy(&check.stdout);
        assert!(check.status.success(), "{ranks} rank(s): {text}{}", String::from_utf8_lossy(&check.stderr));
        assert!(text.contains("max|v_siconos - v_ours|"), "{text}");
    }
}

#[test]
fn work_precision_has_coulomb_rows() {
    // every solve of a Coulomb scene (the reference too) is the fixed point; the error follows ε
    let dir = tmpdir("wp_coulomb");
    let path = dir.join("wp.csv");
    let scene = root().join("run/stress/coulomb_partial_slip.toml");
    let o = Command::new(BIN)
        .args([
            "work-precision",
            "--scene",
            scene.to_str().unwrap(),
            "--sizes",
            "6",
            "--subdomains",
            "0,2",
            "--eps",
            "1e-5,1e-9",
            "--solvers",
            "tssn",
            "--csv",
            path.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = csv(&path);
    assert_eq!(rows.len(), 4, "{rows:?}");
    for r in &rows {
        let eps = num(r, "eps");
        assert!(r["status"] == "ok" && num(r, "err_u") <= 100.0 * eps && num(r, "kkt") <= 10.0 * eps, "{r:?}");
    }
    // Clarabel's SOCP is the Tresca problem: refused for a Coulomb scene
    let o = Command::new(BIN).args(["work-precision", "--scene", scene.to_str().unwrap(), "--sizes", "4", "--solvers", "tssn,clarabel"]).output().unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("--solvers"));
}

#[test]
fn getfem_solves_the_same_discrete_problem_to_our_solution() {
    // run/peer/getfem_compare builds the seed in GetFEM (Q1, 2×2×2 Gauss, our node-to-node pairs
    // as the basic contact brick's BN/BT; Tresca through an auxiliary Coulomb brick) and compares
    // it node by node with tresca-feti on 1 and 2 ranks and with Siconos' gfc3d on the FCLIB
    // export: at tight tolerances all agree to 1e-9, Tresca and Coulomb
    let script = root().join("run/peer/getfem_compare");
    let o = Command::new(&script)
        .args(["--n", "5", "--ranks", "1,2", "--siconos", "--eps", "1e-12", "--getfem-res", "1e-12", "--tol", "1e-9", "--bin", BIN])
        .output()
        .expect("run/peer/getfem_compare (/usr/bin/python3 with python3-getfem, python3-siconos: run/install-deps)");
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}{}", String::from_utf8_lossy(&o.stderr));
    for (friction, code, rows) in
        [("tresca", "GetFEM", 1), ("tresca", "tresca-feti", 2), ("coulomb", "GetFEM", 1), ("coulomb", "tresca-feti", 2), ("coulomb", "Siconos", 1)]
    {
        let n = out.lines().filter(|l| l.split_whitespace().take(3).eq(["5", friction, code])).count();
        assert_eq!(n, rows, "{friction} {code}: {out}");
    }
    assert!(out.contains("agree") && !out.contains("NOT CONVERGED"), "{out}");
    // and it tells a disagreement: at the default tolerances the solutions differ by about 1e-8
    let o = Command::new(&script).args(["--n", "4", "--ranks", "1", "--friction", "tresca", "--tol", "1e-13", "--bin", BIN]).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{out}{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("DISAGREE"), "{out}");
}
