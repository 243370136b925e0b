//! Determinism of the whole program under `mpirun`: the decomposition and the rank count change
//! the answer only within the solver tolerance (S = 4 subdomains per body on 2 ranks against
//! S = 8 on 1 rank, at ε = 1e-10), and the same run repeated gives the same file to the last
//! bit. (Subdomain-count independence against the monolithic dual is in `tests/tfeti.rs`;
//! bitwise identity across 1, 2 and 3 ranks at a fixed S in `tests/cli.rs`.)

mod common;

use common::{f64_field, fields, i32_field, mpirun, root, tmpdir};
use tresca_feti::output::{OutputData, Values};

/// One `mpirun -n ranks tresca-feti solve run/seed.toml --set …` into `dir/name.h5`; returns its
/// stdout and the result file's contents.
fn solve(dir: &std::path::Path, name: &str, ranks: usize, sets: &[&str]) -> (String, OutputData) {
    let out = dir.join(format!("{name}.h5"));
    let scene = root().join("run/seed.toml");
    let mut args = vec!["solve", scene.to_str().unwrap(), "--out", out.to_str().unwrap()];
    for s in sets {
        args.extend(["--set", s]);
    }
    let o = mpirun(ranks, &args);
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "{name} on {ranks} ranks: {}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains(&format!("{ranks} rank(s)")), "{stdout}");
    (stdout, fields(&out))
}

/// The line of stdout starting with `prefix` (the solver's counters, the contact summary).
fn line<'a>(stdout: &'a str, prefix: &str) -> &'a str {
    stdout.lines().find(|l| l.starts_with(prefix)).unwrap_or_else(|| panic!("no `{prefix}` line in: {stdout}"))
}

/// max|a − b| / max|a|.
fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0f64, f64::max) / scale
}

const SEED_N8: [&str; 3] = ["mesh.n=8", "solver.eps=1e-10", "decomposition.tfeti=true"];

/// S = 4 subdomains per body on 2 ranks against S = 8 on 1 rank: different decompositions,
/// different rank counts, one answer. Stated tolerances: max|Δu|/max|u| ≤ 1e-7 and
/// max|Δp|/max|p| ≤ 1e-7 for the contact pressure; the contact status identical node by node
/// (hence the same open/stick/slip counts).
#[test]
fn four_subdomains_on_two_ranks_match_eight_on_one_rank() {
    let dir = tmpdir("s4-s8");
    let (out4, s4) = solve(&dir, "s4-2ranks", 2, &[SEED_N8.as_slice(), &["decomposition.subdomains=4"]].concat());
    let (out8, s8) = solve(&dir, "s8-1rank", 1, &[SEED_N8.as_slice(), &["decomposition.subdomains=8"]].concat());
    assert_eq!(s4.coordinates, s8.coordinates, "the same mesh");
    let du = rel_diff(f64_field(&s8, "displacement"), f64_field(&s4, "displacement"));
    let dp = rel_diff(f64_field(&s8, "contact_pressure"), f64_field(&s4, "contact_pressure"));
    eprintln!("S = 4 on 2 ranks vs S = 8 on 1 rank: max|Δu|/max|u| = {du:.2e}, max|Δp|/max|p| = {dp:.2e}");
    eprintln!("  {}\n  {}", line(&out4, "solver "), line(&out8, "solver "));
    assert!(du <= 1e-7, "max|Δu|/max|u| = {du:.2e} > 1e-7");
    assert!(dp <= 1e-7, "max|Δp|/max|p| = {dp:.2e} > 1e-7");
    assert_eq!(i32_field(&s4, "contact_status"), i32_field(&s8, "contact_status"), "contact status differs");
    // "contact: 64 pairs — 32 open, 0 stick, 32 slip; …": the counts, before the forces
    let counts = |s: &str| line(s, "contact: ").split(';').next().unwrap().to_string();
    assert_eq!(counts(&out4), counts(&out8));
    // the two runs did split differently
    let parts = |d: &OutputData| i32_field(d, "subdomain").iter().max().copied();
    assert_ne!(parts(&s4), parts(&s8));
}

/// The same command twice gives the same iteration counters and the same file contents to the
/// last bit (mesh, every field), for TFETI on 2 ranks with SSN-BiCGSTAB and with GIMSSN, and
/// for the monolithic dual on 1 rank.
#[test]
fn the_same_run_twice_gives_bitwise_identical_output() {
    let dir = tmpdir("repeat");
    let ssn = [SEED_N8.as_slice(), &["decomposition.subdomains=4"]].concat();
    let gimssn = ["mesh.n=6", "solver.eps=1e-9", "decomposition.tfeti=true", "decomposition.subdomains=4", "solver.method=\"gimssn\""];
    let mono = ["mesh.n=8", "solver.eps=1e-10", "decomposition.subdomains=1"];
    for (case, ranks, sets) in [("ssn-s4-2ranks", 2, ssn.as_slice()), ("gimssn-s4-2ranks", 2, gimssn.as_slice()), ("monolithic-1rank", 1, mono.as_slice())] {
        let (out_a, a) = solve(&dir, &format!("{case}-a"), ranks, sets);
        let (out_b, b) = solve(&dir, &format!("{case}-b"), ranks, sets);
        for prefix in ["solver ", "contact: "] {
            assert_eq!(line(&out_a, prefix), line(&out_b, prefix), "{case}");
        }
        assert_eq!(a.coordinates, b.coordinates, "{case}");
        assert_eq!(a.cells, b.cells, "{case}");
        assert_eq!(a.fields.len(), b.fields.len(), "{case}");
        for (fa, fb) in a.fields.iter().zip(&b.fields) {
            assert_eq!(fa.name, fb.name, "{case}");
            // bitwise: compare the bit patterns, so that even a NaN would have to repeat
            let bits = |v: &Values| match v {
                Values::F64(x) => x.iter().map(|f| f.to_bits()).collect::<Vec<u64>>(),
                Values::I32(x) => x.iter().map(|&i| i as u64).collect(),
            };
            assert!(bits(&fa.values) == bits(&fb.values), "{case}: field {} differs between two identical runs", fa.name);
        }
    }
}

/// A process not started by an MPI launcher runs without MPI (no singleton start of Open MPI's
/// orted): the same result file, bitwise, as `mpirun -n 1`, TFETI and the monolithic dual alike.
#[test]
fn a_plain_run_equals_mpirun_with_one_rank_bitwise() {
    let dir = tmpdir("plain-vs-mpirun");
    let scene = root().join("run/seed.toml");
    for (name, extra) in [("tfeti", "decomposition.subdomains=4"), ("mono", "decomposition.subdomains=1")] {
        let (_, mpi) = solve(&dir, &format!("{name}-mpirun"), 1, &["mesh.n=8", extra]);
        let out = dir.join(format!("{name}-plain.h5"));
        let o = common::run(&["solve", scene.to_str().unwrap(), "--set", "mesh.n=8", "--set", extra, "--out", out.to_str().unwrap()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let plain = fields(&out);
        assert_eq!(f64_field(&plain, "displacement"), f64_field(&mpi, "displacement"), "{name}: u differs");
        assert_eq!(i32_field(&plain, "contact_status"), i32_field(&mpi, "contact_status"), "{name}: status differs");
    }
}

/// The gather of the solution to rank 0, the all-gather and the all-to-all go in rounds of at
/// most (2³¹ − 1)/p values per rank and message (MPI's counts are i32; before, a length above
/// 2³¹ wrapped or stopped the run): forced to rounds of 7 values (`TRESCA_FETI_GATHER_CHUNK=7`),
/// TFETI on 2 ranks reports and writes the same results to the last bit.
#[test]
fn the_solution_gather_in_rounds_gives_the_same_report() {
    let dir = tmpdir("gather-rounds");
    let scene = root().join("run/seed.toml");
    let report = |name: &str, chunk: Option<&str>| {
        let out = dir.join(format!("{name}.h5"));
        let args = ["solve", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--set", "mesh.n=4", "--set", "decomposition.subdomains=2"];
        let mut cmd = common::mpirun_cmd(2, &args);
        if let Some(c) = chunk {
            cmd.env("TRESCA_FETI_GATHER_CHUNK", c);
        }
        let o = cmd.output().unwrap();
        assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.with_extension("json")).unwrap()).unwrap();
        // the file's rows travel by all-to-all (also in rounds), the coarse problem's blocks by
        // all-gather: the fields must come back the same
        let data = common::fields(&out);
        let fields: Vec<(String, Vec<f64>)> = ["displacement", "von_mises"].iter().map(|&f| (f.to_string(), common::f64_field(&data, f).to_vec())).collect();
        (json["results"].clone(), json["tfeti"]["subdomains"].clone(), fields)
    };
    let (whole, rounds) = (report("whole", None), report("rounds", Some("7")));
    assert!(whole.0["max_displacement"].as_f64().unwrap() > 0.0, "{:?}", whole.0);
    assert!(whole.2.iter().all(|(_, v)| v.len() > 7), "more than one round");
    assert_eq!(whole, rounds);
}
