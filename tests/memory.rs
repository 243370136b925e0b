//! A run that would not fit in memory is refused before it allocates, with the estimate and the
//! memory available (`pipeline::memory`); `--max-memory` sets the limit; `check` prints the
//! estimate.

mod common;

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use common::{mpirun, root, tmpdir, BIN};

fn seed() -> String {
    root().join("run/seed.toml").display().to_string()
}

/// The one `error: ` line of a failed run (exit 1, no panic, no result file under `out`).
fn one_line_failure(name: &str, o: &Output, out: &Path) -> String {
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{name}: {stderr}");
    assert!(!stderr.contains("panicked") && !stderr.contains("memory allocation of"), "{name}: {stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error: ")).collect();
    assert_eq!(lines.len(), 1, "{name}: not one error line: {stderr}");
    assert!(!out.exists(), "{name}: {} written", out.display());
    lines[0].to_string()
}

/// Peak resident memory (kB) of a command run under `/usr/bin/time` (Debian's `time`, which
/// run/install-deps installs; without it the test fails rather than skip its check).
fn with_peak(args: &[&str]) -> (Output, u64) {
    assert!(Path::new("/usr/bin/time").exists(), "/usr/bin/time is missing: install Debian's `time` (run/install-deps)");
    let o = Command::new("/usr/bin/time").args(["-f", "peak-kb %M", BIN]).args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    let peak = stderr.lines().find_map(|l| l.strip_prefix("peak-kb ")?.trim().parse().ok()).unwrap_or_else(|| panic!("no peak from /usr/bin/time: {stderr}"));
    // leave the command's own stderr
    let rest: String = stderr.lines().filter(|l| !l.starts_with("peak-kb ") && !l.starts_with("Command exited")).map(|l| format!("{l}\n")).collect();
    (Output { stderr: rest.into_bytes(), ..o }, peak)
}

#[test]
fn mesh_n_500_is_refused_with_the_estimate_before_allocating() {
    // 2 × 125 M nodes: the mesh alone is tens of GB; it used to abort (exit 134) in the box
    // generator with `memory allocation of 7952095936 bytes failed`
    let dir = tmpdir("n500");
    let out = dir.join("r.h5");
    let t0 = Instant::now();
    let (o, peak) = with_peak(&["solve", &seed(), "--set", "mesh.n=500", "-q", "--out", out.to_str().unwrap()]);
    let took = t0.elapsed();
    let line = one_line_failure("n500", &o, &out);
    for want in ["mesh.n: the run needs about", "GB", "mesh ", "setup ", "on rank 0", "are available", "MemAvailable", "--max-memory"] {
        assert!(line.contains(want), "expected `{want}` in: {line}");
    }
    assert!(took < Duration::from_secs(5), "took {took:?}");
    assert!(peak < 200_000, "peak RSS {peak} kB: the huge arrays were allocated");
}

#[test]
fn max_memory_sets_the_limit_and_names_itself() {
    let dir = tmpdir("max");
    let out = dir.join("r.h5");
    let o = Command::new(BIN).args(["solve", &seed(), "--set", "mesh.n=8", "-q", "--max-memory", "1M", "--out", out.to_str().unwrap()]).output().unwrap();
    let line = one_line_failure("1M", &o, &out);
    for want in ["mesh.n: the run needs about", "MB", "but 1.0 MB are available (--max-memory)"] {
        assert!(line.contains(want), "expected `{want}` in: {line}");
    }
    // the environment variable, when no flag is given
    let o = Command::new(BIN)
        .args(["solve", &seed(), "--set", "mesh.n=8", "-q", "--out", out.to_str().unwrap()])
        .env("TRESCA_FETI_MAX_MEMORY", "2M")
        .output()
        .unwrap();
    let line = one_line_failure("env", &o, &out);
    assert!(line.contains("2.1 MB are available (TRESCA_FETI_MAX_MEMORY)"), "{line}");
    // a size that is no size: a usage error
    let o = Command::new(BIN).args(["solve", &seed(), "--max-memory", "lots"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not a size"));
    let o = Command::new(BIN).args(["solve", &seed(), "--max-memory", "8GBBBB"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "8GBBBB is no size");
    assert!(String::from_utf8_lossy(&o.stderr).contains("--max-memory"));
    // a variable that is no size: one line naming it, for solve and check, no result file
    for bad in ["lots", "0", "-1", "8GBBBB"] {
        let o = Command::new(BIN)
            .args(["solve", &seed(), "--set", "mesh.n=4", "-q", "--out", out.to_str().unwrap()])
            .env("TRESCA_FETI_MAX_MEMORY", bad)
            .output()
            .unwrap();
        let line = one_line_failure(bad, &o, &out);
        assert!(line.contains("TRESCA_FETI_MAX_MEMORY") && line.contains(bad), "{line}");
        let o = Command::new(BIN).args(["check", &seed(), "--set", "mesh.n=4"]).env("TRESCA_FETI_MAX_MEMORY", bad).output().unwrap();
        assert_eq!(o.status.code(), Some(1), "check with TRESCA_FETI_MAX_MEMORY={bad}");
        assert!(String::from_utf8_lossy(&o.stderr).contains("TRESCA_FETI_MAX_MEMORY"));
    }
    // enough memory: the run goes through
    let o = Command::new(BIN).args(["solve", &seed(), "--set", "mesh.n=4", "-q", "--max-memory", "4G", "--out", out.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.exists());
}

#[test]
fn the_estimate_with_the_plans_factors_refuses_before_assembly() {
    // N = 16: the mesh and setup fit in 100 MB, the plan's factors (≈ 100 MB) do not
    let dir = tmpdir("plan");
    let out = dir.join("r.h5");
    let o = Command::new(BIN).args(["solve", &seed(), "--set", "mesh.n=16", "--max-memory", "100M", "--out", out.to_str().unwrap()]).output().unwrap();
    let line = one_line_failure("plan", &o, &out);
    assert!(line.contains("factors") && line.contains("(--max-memory)"), "{line}");
    // the live phases: refused after the plan, before anything is assembled
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("plan") && !stdout.contains("assemble") && !stdout.contains("factorize"), "{stdout}");
}

#[test]
fn check_prints_the_estimate_and_the_available_memory() {
    let o = Command::new(BIN).args(["check", &seed(), "--set", "mesh.n=16"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text.lines().find(|l| l.starts_with("memory: about")).unwrap_or_else(|| panic!("no estimate in: {text}"));
    for want in ["per rank", "process", "mesh", "setup", "stiffness", "factors", "dual", "the plan's nnz(L)"] {
        assert!(line.contains(want), "expected `{want}` in: {line}");
    }
    assert!(text.contains("available on this host"), "{text}");
    // with a limit below the estimate, check says that solve refuses it
    let o = Command::new(BIN).args(["check", &seed(), "--set", "mesh.n=16", "--max-memory", "100M", "--ranks", "2"]).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("for 2 ranks on one host") && text.contains("(--max-memory); does not fit"), "{text}");
}

#[test]
fn the_mesh_count_comes_from_the_scene_and_the_gmsh_headers() {
    use tresca_feti::pipeline::memory::{before_mesh, MeshCount};
    let ls = tresca_feti::scene::load(&root().join("run/seed.toml"), &["mesh.n=10".into()]).unwrap();
    let c = MeshCount::of(&ls);
    assert_eq!((c.nodes, c.elements, c.key.as_str()), (2000.0, 1458.0, "mesh.n"));
    assert_eq!(c.body_dofs, vec![3000.0, 3000.0]);
    // the same figures as the built model
    let model = tresca_feti::model::build(&ls).unwrap();
    let m = MeshCount::of_model(&ls, &model);
    assert_eq!((m.nodes, m.elements), (c.nodes, c.elements));
    let e = before_mesh(&c, &ls.scene.decomposition, 1);
    assert!(e.part("mesh") > 0.0 && e.part("setup") > 0.0 && e.part("factors") == 0.0);
    // Gmsh: the $Nodes and $Elements headers, ASCII and binary, of the whole file
    for f in ["two_blocks.msh", "two_blocks_binary.msh"] {
        let (nodes, elements, bytes) = tresca_feti::mesh::gmsh::header_counts(&root().join("mesh").join(f)).unwrap_or_else(|| panic!("{f}"));
        assert_eq!((nodes, elements), (224, 189), "{f}");
        assert_eq!(bytes, std::fs::metadata(root().join("mesh").join(f)).unwrap().len());
    }
    let ls = tresca_feti::scene::load(&root().join("run/gmsh_blocks.toml"), &[]).unwrap();
    let c = MeshCount::of(&ls);
    assert_eq!((c.nodes, c.key.as_str()), (2.0 * 224.0, "body[0].gmsh.file"));
    assert!(c.files > 0.0);
}

#[test]
fn under_mpirun_every_rank_refuses_and_one_prints() {
    let dir = tmpdir("mpi");
    let out = dir.join("r.h5");
    let o = mpirun(2, &["solve", &seed(), "--set", "mesh.n=500", "-q", "--out", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    let lines: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error: ")).collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(lines[0].contains("for the 2 ranks on this host") && lines[0].contains("are available"), "{}", lines[0]);
    assert!(!stderr.contains("memory allocation of"), "{stderr}");
    assert!(!out.exists());
}

/// Trust round four, 8: under `ulimit -v` (RLIMIT_AS) the estimate is held against what the
/// limit leaves of the address space, not MemAvailable: the seed at N = 150 under 4 GB is one
/// line naming mesh.n and the limit, before any mesh is made (before, METIS failed inside with
/// status −3 after four lines of its own).
#[test]
fn ulimit_v_is_the_limit_where_it_is_smaller() {
    let dir = tmpdir("ulimit");
    let out = dir.join("r.h5");
    let cmd = format!("ulimit -v 4000000 && exec {BIN} solve {} --set mesh.n=150 -q --out {}", seed(), out.display());
    let t0 = Instant::now();
    let o = Command::new("bash").args(["-c", &cmd]).output().unwrap();
    let line = one_line_failure("ulimit", &o, &out);
    for want in ["mesh.n: the run needs about", "ulimit -v (RLIMIT_AS)"] {
        assert!(line.contains(want), "expected `{want}` in: {line}");
    }
    assert!(t0.elapsed() < Duration::from_secs(10), "refused before the mesh: {:?}", t0.elapsed());
}
