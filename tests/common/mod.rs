//! Helpers shared by the integration tests: paths, scratch folders, `mpirun`, a serial solve
//! of a scene through the library, and reading result files back.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use tresca_feti::output::{self, OutputData, Values};

pub const BIN: &str = env!("CARGO_BIN_EXE_tresca-feti");

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh, empty scratch folder, named after the test binary, the process and `name`, under
/// cargo's `target/tmp` (what the tests leave there goes with `cargo clean`, not into /tmp).
pub fn tmpdir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("tresca-feti-{}-{}-{name}", env!("CARGO_CRATE_NAME"), std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `mpirun -n N BIN ARGS` for a test. Each launch gets its own Open MPI session folder:
/// Open MPI 4.1 creates `/tmp/ompi.HOST.UID` with a racy mkdir, and two `mpirun`s started at
/// the same instant (tests run in parallel threads) fail one of them with "File exists".
pub fn mpirun_cmd(n: usize, args: &[&str]) -> Command {
    static LAUNCH: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = LAUNCH.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let session = std::env::temp_dir().join("tresca-feti-ompi").join(format!("{}-{k}", std::process::id()));
    std::fs::create_dir_all(&session).unwrap();
    let mut c = Command::new("mpirun");
    c.env("OMPI_MCA_orte_tmpdir_base", &session);
    // a rank waiting on a collective the others skipped fails the test instead of hanging it
    c.args(["-n", &n.to_string(), "--oversubscribe", "--timeout", "300", BIN])
        .args(args)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_btl_base_warn_component_unused", "0");
    c
}

pub fn mpirun(n: usize, args: &[&str]) -> Output {
    mpirun_cmd(n, args).output().expect("mpirun must be installed (openmpi-bin, see run/packages.txt)")
}

/// The fields of a result file.
pub fn fields(path: &Path) -> OutputData {
    output::hdf5::read(path).unwrap_or_else(|e| panic!("{e}"))
}

/// `tresca-feti solve` through the library on one rank, quiet; panics with the error.
pub fn solve(scene: &Path, sets: &[&str], out: &Path) -> tresca_feti::pipeline::Summary {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    tresca_feti::pipeline::run_solve(&tresca_feti::comm::SerialComm, scene, &sets, Some(out.to_path_buf()), true).unwrap_or_else(|e| panic!("{e}"))
}

/// max |uᵢ| over every node and component.
pub fn max_abs(u: &[[f64; 3]]) -> f64 {
    u.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// `tresca-feti ARGS` on one process, its output.
pub fn run(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// Writes `scene` into a fresh directory, solves it there and checks the failure is clean:
/// exit code 1, one line on stderr starting `error: ` holding every `expect`, no result file.
pub fn assert_clean_failure(name: &str, scene: &str, extra: &[&str], expect: &[&str]) {
    let dir = tmpdir(name);
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    let out = dir.join("out").join("result.h5");
    let mut args = vec!["solve", path.to_str().unwrap(), "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = run(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{name}: succeeded; stdout {}", String::from_utf8_lossy(&o.stdout));
    assert_eq!(o.status.code(), Some(1), "{name}: {stderr}");
    assert!(!stderr.contains("panicked"), "{name}: panic: {stderr}");
    // a phase that runs past 2 s (a loaded machine) shows its plain progress lines on stderr
    // ("scene: 2.01 s"): they are not part of the error
    let progress = |l: &str| {
        !l.starts_with("error: ") && l.ends_with(" s") && l.split_once(": ").is_some_and(|(p, _)| p.chars().all(|c| c.is_ascii_lowercase() || c == ' '))
    };
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty() && !progress(l)).collect();
    assert_eq!(lines.len(), 1, "{name}: not one line: {stderr}");
    assert!(lines[0].starts_with("error: "), "{name}: {stderr}");
    for e in expect {
        assert!(lines[0].contains(e), "{name}: expected `{e}` in: {}", lines[0]);
    }
    let left: Vec<_> = std::fs::read_dir(dir.join("out")).map(|d| d.flatten().map(|e| e.path()).collect()).unwrap_or_default();
    assert!(left.is_empty(), "{name}: files left behind: {left:?}");
}

/// The values of a floating-point field of a result; panics naming a missing or integer field.
pub fn f64_field<'a>(data: &'a OutputData, name: &str) -> &'a [f64] {
    let f = data.fields.iter().find(|f| f.name == name).unwrap_or_else(|| panic!("no field {name}"));
    match &f.values {
        Values::F64(v) => v,
        Values::I32(_) => panic!("field {name} is not floating point"),
    }
}

/// The values of an integer field of a result.
pub fn i32_field<'a>(data: &'a OutputData, name: &str) -> &'a [i32] {
    let f = data.fields.iter().find(|f| f.name == name).unwrap_or_else(|| panic!("no field {name}"));
    match &f.values {
        Values::I32(v) => v,
        Values::F64(_) => panic!("field {name} is not integer"),
    }
}
