//! Checkpoint and resume of a load path (`output.checkpoint`, `solve --resume`): checkpointing
//! changes nothing; a run stopped by SIGTERM after step 3 of 6 and resumed (same or another
//! rank count) ends with the uninterrupted run's result set; a checkpoint of another scene or a
//! truncated one is refused with one line and nothing written.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{fields, mpirun_cmd, root, tmpdir, BIN};
use tresca_feti::output::{OutputData, Values};

/// The 6-step seed on TFETI (4 subdomains) and on the monolithic dual.
// a value with quotes and spaces: the resume line must quote it for the shell
const TFETI: [&str; 4] = ["mesh.n=6", "load.steps=6", "decomposition.subdomains=4", "title=\"seed, stopped and resumed\""];
const MONOLITHIC: [&str; 3] = ["mesh.n=6", "load.steps=6", "title=\"seed, stopped and resumed\""];

/// `tresca-feti solve run/seed.toml --set … --out out EXTRA` on `ranks` ranks (0: no mpirun).
fn solve(ranks: usize, sets: &[&str], out: &Path, extra: &[&str], env: &[(&str, &str)]) -> Output {
    let scene = root().join("run/seed.toml");
    let mut args = vec!["solve", scene.to_str().unwrap(), "-q", "--out", out.to_str().unwrap()];
    for s in sets {
        args.extend(["--set", s]);
    }
    args.extend(extra);
    let mut cmd = if ranks == 0 {
        let mut c = std::process::Command::new(BIN);
        c.args(&args);
        c
    } else {
        mpirun_cmd(ranks, &args)
    };
    cmd.envs(env.iter().copied()).env("HDF5_USE_FILE_LOCKING", "FALSE").output().unwrap()
}

fn ok(o: &Output, what: &str) {
    assert!(o.status.success(), "{what}: {}", String::from_utf8_lossy(&o.stderr));
}

/// Every f64 of the result (the last state's fields and every step's), in order.
fn all_f64(d: &OutputData) -> Vec<(String, Vec<f64>)> {
    let mut v = Vec::new();
    let mut add = |tag: String, fs: &[tresca_feti::output::Field], rows: &std::collections::BTreeMap<String, Vec<usize>>| {
        for f in fs {
            if let Values::F64(x) = &f.values {
                // by row, so that the ranks' order of writing does not matter
                let r = rows.get(&f.name).cloned().unwrap_or_else(|| (0..x.len() / f.ncomp).collect());
                let mut by: Vec<(usize, &[f64])> = r.into_iter().zip(x.chunks(f.ncomp)).collect();
                by.sort_by_key(|p| p.0);
                v.push((format!("{tag}/{}", f.name), by.into_iter().flat_map(|p| p.1.to_vec()).collect()));
            }
        }
    };
    add("fields".into(), &d.fields, &d.rows);
    for (i, s) in d.steps.iter().enumerate() {
        add(format!("steps/{i}"), &s.fields, &s.rows);
    }
    v
}

fn displacement(d: &OutputData) -> Vec<f64> {
    all_f64(d).into_iter().find(|p| p.0 == "fields/displacement").expect("displacement").1
}

/// The stopped run's one line names the step and the resume command (the scene, every `--set`
/// shell-quoted, `--out`, `--checkpoint`, `--resume`); the checkpoint is there, the result is
/// not. Returns the checkpoint and the command's words after the program's name.
fn stop_after_3(ranks: usize, sets: &[&str], dir: &Path) -> (PathBuf, Vec<String>) {
    let out = dir.join("stopped.h5");
    let o = solve(ranks, sets, &out, &["--checkpoint"], &[("TRESCA_FETI_STOP_AFTER", "3")]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "the stopped run must fail");
    let ck = dir.join("stopped.checkpoint.h5");
    let seed = root().join("run/seed.toml");
    let mut words = vec!["tresca-feti".to_string(), "solve".into(), seed.display().to_string()];
    for s in sets {
        words.extend(["--set".into(), s.to_string()]);
    }
    words.extend(["--out".into(), out.display().to_string(), "--checkpoint".into(), "--resume".into(), ck.display().to_string()]);
    let line = err.lines().find(|l| l.starts_with("stopped by")).unwrap_or_else(|| panic!("no stop line: {err}"));
    let command = line.strip_prefix("stopped by SIGTERM after step 3 of 6; resume with: ").unwrap_or_else(|| panic!("{line}"));
    assert_eq!(shell_words::split(command).unwrap(), words, "{line}");
    assert!(command.contains("'title=\"seed, stopped and resumed\"'"), "quoted for the shell: {line}");
    assert!(ck.exists() && dir.join("stopped.checkpoint.prev.h5").exists());
    assert!(!out.exists(), "no result after a stop");
    (ck, words[1..].to_vec())
}

#[test]
fn checkpointing_changes_nothing_and_a_stopped_run_resumes_to_the_same_result() {
    for (name, sets, ranks) in [("tfeti", &TFETI[..], 2), ("monolithic", &MONOLITHIC[..], 0)] {
        let dir = tmpdir(&format!("resume-{name}"));
        let plain = dir.join("plain.h5");
        ok(&solve(ranks, sets, &plain, &[], &[]), "uninterrupted");
        let with = dir.join("with.h5");
        ok(&solve(ranks, sets, &with, &["--checkpoint"], &[]), "with checkpoints");
        let reference = all_f64(&fields(&plain));
        assert_eq!(reference.iter().filter(|p| p.0.ends_with("/displacement")).count(), 7, "{name}: u of the last state and of every step");
        assert_eq!(all_f64(&fields(&with)), reference, "{name}: checkpointing changed the result");
        assert!(dir.join("with.checkpoint.h5").exists());

        let (ck, resume) = stop_after_3(ranks, sets, &dir);
        let resumed = dir.join("stopped.h5");
        // the printed command as it stands
        let args: Vec<&str> = resume.iter().map(String::as_str).collect();
        let mut cmd = if ranks == 0 {
            let mut c = std::process::Command::new(BIN);
            c.args(&args);
            c
        } else {
            mpirun_cmd(ranks, &args)
        };
        ok(&cmd.env("HDF5_USE_FILE_LOCKING", "FALSE").output().unwrap(), "resume");
        assert_eq!(all_f64(&fields(&resumed)), reference, "{name}: the resumed run differs from the uninterrupted one");
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("stopped.json")).unwrap()).unwrap();
        assert_eq!(report["load_path"].as_array().map(Vec::len), Some(6), "{name}: the report lists every step");

        // on another rank count: within 10 ε of the uninterrupted run
        let other = dir.join("other.h5");
        ok(&solve(if ranks == 0 { 2 } else { 0 }, sets, &other, &["--resume", ck.to_str().unwrap()], &[]), "resume elsewhere");
        let (u, u0) = (displacement(&fields(&other)), displacement(&fields(&plain)));
        let scale = u0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let d = u.iter().zip(&u0).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / scale;
        eprintln!("{name}: resumed on another rank count: max |Δu| / max |u| = {d:.2e}");
        assert!(d <= 10.0 * f64::EPSILON, "{name}: {d:.2e}");
    }
}

/// A refused resume: exit 1, one line naming `expect`, no result written.
fn refused(sets: &[&str], ck: &Path, out: &Path, expect: &str) {
    let o = solve(0, sets, out, &["--resume", ck.to_str().unwrap()], &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains(&ck.display().to_string()) && err.contains(expect), "{err}");
    assert!(!out.exists(), "a refusal writes nothing");
}

#[test]
fn a_foreign_or_truncated_checkpoint_is_refused() {
    let dir = tmpdir("refuse");
    let (ck, _) = stop_after_3(0, &MONOLITHIC, &dir);
    let before = std::fs::read(&ck).unwrap();
    let mut other = MONOLITHIC.to_vec();
    other.push("contact.pair.0.friction={type=\"tresca\", g=0.05}");
    refused(&other, &ck, &dir.join("friction.h5"), "the scene (after --set) differs");
    assert_eq!(std::fs::read(&ck).unwrap(), before, "a refusal leaves the checkpoint as it was");
    let cut = dir.join("cut.checkpoint.h5");
    std::fs::write(&cut, &before[..before.len() / 2]).unwrap();
    refused(&MONOLITHIC, &cut, &dir.join("cut.h5"), "truncated or corrupt");
}
