//! Helpers shared by the integration tests: paths, scratch folders, `mpirun`, a serial solve
//! of a scene through the library, and reading result files back.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use tresca_feti::output::{self, OutputData};

pub const BIN: &str = env!("CARGO_BIN_EXE_tresca-feti");

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh, empty scratch folder, named after the test binary, the process and `name`.
pub fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tresca-feti-{}-{}-{name}", env!("CARGO_CRATE_NAME"), std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn mpirun_cmd(n: usize, args: &[&str]) -> Command {
    let mut c = Command::new("mpirun");
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
