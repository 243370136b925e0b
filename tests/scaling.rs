//! The scaling-study driver `bench-tfeti` as run/scaling uses it: every case on every rank count
//! (strong: the same problem and the same solver counters; weak: N·P^{1/3} and S·P), one CSV row
//! each, and bad arguments as one line on stderr.

use std::collections::HashMap;
use std::path::PathBuf;
use std::process::{Command, Output};

use tresca_feti::studies::bench::PHASES;

const BIN: &str = env!("CARGO_BIN_EXE_tresca-feti");

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tresca-feti-scaling-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `tresca-feti bench-tfeti` on the seed scene, with mpirun allowed as root and oversubscribed.
fn bench(args: &[&str]) -> Output {
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("run/seed.toml");
    Command::new(BIN)
        .args(["bench-tfeti", "--scene", scene.to_str().unwrap(), "--projectors", "oblique"])
        .args(args)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_rmaps_base_oversubscribe", "1")
        .env("OMPI_MCA_btl_base_warn_component_unused", "0")
        .output()
        .unwrap()
}

/// The CSV as rows of column name → value.
fn read_csv(path: &PathBuf) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            assert_eq!(v.len(), header.len(), "{l}");
            header.iter().zip(v).map(|(k, v)| (k.to_string(), v.to_string())).collect()
        })
        .collect()
}

fn num(row: &HashMap<String, String>, k: &str) -> f64 {
    row[k].parse().unwrap_or_else(|e| panic!("{k} = {}: {e}", row[k]))
}

#[test]
fn strong_scaling_runs_every_rank_count() {
    let csv = tmpdir("strong").join("s.csv");
    let o = bench(&["--sizes", "4", "--subdomains", "2", "--ranks", "1,2", "--repeat", "2", "--csv", csv.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}\n{stdout}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("ranks 1,2 (mpirun)"), "{stdout}");
    let rows = read_csv(&csv);
    assert_eq!(rows.len(), 2);
    for (row, p) in rows.iter().zip(["1", "2"]) {
        assert_eq!((row["ranks"].as_str(), row["runs"].as_str()), (p, "2"));
        assert_eq!((row["mode"].as_str(), row["case"].as_str(), row["N"].as_str(), row["S"].as_str()), ("strong", "n4_s2_oblique", "4", "2"));
        assert!(num(row, "nA") > 0.0 && num(row, "outer") > 0.0 && num(row, "inner") > 0.0 && num(row, "coarse_dim") > 0.0, "{row:?}");
        assert!(num(row, "total_s") > 0.0 && num(row, "iterate_s") > 0.0 && num(row, "peak_GB_max") > 0.0, "{row:?}");
        // the phases but the total add up to at most the total
        let phases: f64 = PHASES[..8].iter().map(|p| num(row, &format!("{p}_s"))).sum();
        assert!(phases <= num(row, "total_s") + 1e-3, "{row:?}");
        assert!(num(row, "peak_GB_sum") >= num(row, "peak_GB_max"), "{row:?}");
    }
    // the same problem, the same solver counters on any rank count
    for k in ["dofs", "multipliers", "coarse_dim", "outer", "nA", "nA_power", "nnz_L"] {
        assert_eq!(rows[0][k], rows[1][k], "{k}");
    }
    // and run/scaling-plot draws it, where gnuplot is installed (run/packages.txt)
    if Command::new("gnuplot").arg("--version").output().is_ok_and(|o| o.status.success()) {
        let dir = csv.parent().unwrap().join("plots");
        let o = Command::new(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("run/scaling-plot")).arg(&csv).arg(&dir).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        for png in ["speedup.png", "efficiency.png", "phases_n4_s2_oblique.png"] {
            let bytes = std::fs::read(dir.join(png)).unwrap_or_else(|e| panic!("{png}: {e}"));
            assert!(bytes.starts_with(b"\x89PNG") && bytes.len() > 10_000, "{png}");
        }
    }
}

#[test]
fn weak_scaling_grows_the_problem_with_the_ranks() {
    let csv = tmpdir("weak").join("w.csv");
    let o = bench(&["--weak", "--sizes", "3", "--subdomains", "1", "--ranks", "1,2", "--mpirun-args", "--oversubscribe", "--csv", csv.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = read_csv(&csv);
    let got: Vec<(&str, &str, &str, &str, &str)> =
        rows.iter().map(|r| (r["mode"].as_str(), r["case"].as_str(), r["ranks"].as_str(), r["N"].as_str(), r["S"].as_str())).collect();
    // round(3·2^{1/3}) = 4, 1·2 subdomains per body
    assert_eq!(got, [("weak", "n3_s1_oblique", "1", "3", "1"), ("weak", "n3_s1_oblique", "2", "4", "2")]);
    assert!(num(&rows[1], "dofs") > num(&rows[0], "dofs"));
}

#[test]
fn bad_arguments_give_one_line() {
    let csv = tmpdir("bad").join("b.csv");
    let csv = csv.to_str().unwrap();
    for (args, code, expect) in [
        (&["--ranks", "0"][..], 2, "error: invalid value '0' for '--ranks <RANKS>': must be at least 1"),
        (&["--ranks", "1,0,2"], 2, "error: invalid value '0' for '--ranks"),
        (&["--ranks", "1,two"], 2, "error: invalid value 'two' for '--ranks"),
        (&["--sizes", "1"], 2, "error: invalid value '1' for '--sizes <SIZES>': every N must be at least 2"),
        (&["--repeat", "0"], 2, "error: invalid value '0' for '--repeat"),
        (&["--mpirun", "/nonexistent/mpirun", "--sizes", "3", "--subdomains", "1", "--ranks", "1"], 1, "error: --mpirun /nonexistent/mpirun"),
        (&["--mpirun-args", "--no-such-mpirun-option", "--sizes", "3", "--subdomains", "1", "--ranks", "1"], 1, "error: case n3_s1_oblique_p1"),
    ] {
        let o = bench(&[args, &["--csv", csv]].concat());
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{args:?}: {stderr}");
        // a value the program refuses: one line; a usage error: clap's message and its hint
        if code == 1 {
            assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        } else {
            assert!(stderr.contains("'--help'"), "{args:?}: {stderr}");
        }
        assert!(stderr.starts_with(expect), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}
