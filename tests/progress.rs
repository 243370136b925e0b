//! The progress lines of long phases: with stderr not a terminal, rank 0 writes plain lines
//! (`factorize: 3 of 8 subdomains, 0.40 s`) at most once per `TRESCA_FETI_PROGRESS_PERIOD`
//! seconds; `--quiet` writes none; the results are the same bit for bit with and without them.

mod common;

use common::{f64_field, fields, mpirun_cmd, root, tmpdir};
use std::path::Path;
use std::process::Output;

/// The seed at N = 17 split into 8 subdomains: its factorization lasts several periods of
/// 0.02 s even on 2 ranks of an idle host (at N = 13 rank 0's four subdomains took one period
/// there); the times are printed to 0.01 s.
fn solve(ranks: usize, out: &Path, quiet: bool) -> Output {
    let scene = root().join("run/seed.toml");
    let mut args = vec!["solve", scene.to_str().unwrap(), "--set", "mesh.n=17", "--set", "decomposition.subdomains=8", "--out", out.to_str().unwrap()];
    if quiet {
        args.push("--quiet");
    }
    let o = mpirun_cmd(ranks, &args).env("TRESCA_FETI_PROGRESS_PERIOD", "0.02").output().expect("mpirun runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

/// `(phase, time)` of each progress line of `stderr`: `name: …, 1.2 s`.
fn progress_lines(stderr: &str) -> Vec<(String, f64)> {
    stderr
        .lines()
        .filter_map(|l| {
            let (name, rest) = l.split_once(": ")?;
            let secs = rest.rsplit(' ').nth(1)?.parse::<f64>().ok()?;
            (l.ends_with(" s") && !name.contains(' ')).then(|| (name.to_string(), secs))
        })
        .collect()
}

#[test]
fn progress_lines_are_periodic_rate_limited_and_change_no_result() {
    let dir = tmpdir("progress");
    for ranks in [1, 2] {
        let (loud, quiet) = (dir.join(format!("loud{ranks}.h5")), dir.join(format!("quiet{ranks}.h5")));
        let o = solve(ranks, &loud, false);
        let err = String::from_utf8_lossy(&o.stderr);
        let lines = progress_lines(&err);
        let share = if ranks > 1 { "subdomains of rank 0" } else { "subdomains" };
        let counted: Vec<&str> = err.lines().filter(|l| l.starts_with("factorize: ") && l.contains(share)).collect();
        assert!(counted.len() >= 2, "{ranks} rank(s): fewer than two factorize lines counting {share}: {err}");
        // one printer per phase, on rank 0 only: the lines of a phase are a period apart
        for name in ["factorize", "iterate"] {
            let t: Vec<f64> = lines.iter().filter(|l| l.0 == name).map(|l| l.1).collect();
            assert!(t.windows(2).all(|w| w[1] - w[0] >= 0.0099), "{ranks} rank(s), {name}: lines closer than the period: {t:?}\n{err}");
        }
        assert!(lines.iter().all(|l| l.0 != "iterate"), "iterate shows its outer iterations instead: {err}");
        let q = solve(ranks, &quiet, true);
        assert!(progress_lines(&String::from_utf8_lossy(&q.stderr)).is_empty(), "--quiet: {}", String::from_utf8_lossy(&q.stderr));
        let (a, b) = (fields(&loud), fields(&quiet));
        for name in ["displacement", "contact_pressure", "von_mises"] {
            let bits = |d| f64_field(d, name).iter().map(|v| v.to_bits()).collect::<Vec<u64>>();
            assert_eq!(bits(&a), bits(&b), "{ranks} rank(s): {name} differs with progress shown");
        }
    }
}
