//! The plan's machine rates from the cache `tresca-feti calibrate` writes: a calibrated cache is
//! used and named by `check`; a corrupt cache or one from another CPU is ignored with one
//! warning; a cached rate changes the priced times.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use common::BIN;

/// This host's CPU model, read here independently of the program.
fn cpu() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    info.lines().find(|l| l.starts_with("model name")).and_then(|l| l.split_once(':')).map_or("unknown".into(), |(_, v)| v.trim().to_string())
}

/// `tresca-feti ARGS` with the rates cache in `cache`.
fn with_cache(cache: &str, args: &[&str]) -> Output {
    Command::new(BIN).env("TRESCA_FETI_CACHE", cache).args(args).output().unwrap()
}

/// `check` of the seed scene at N = 14 (the monolithic dual and three TFETI counts priced).
fn check(cache: &str) -> Output {
    let seed = common::root().join("run/seed.toml");
    let o = with_cache(cache, &["check", seed.to_str().unwrap(), "--set", "mesh.n=14"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

/// The rates line and the (candidate, setup s, total s) of every row of `check`'s plan table.
fn plan(o: &Output) -> (String, Vec<(String, f64, f64)>) {
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text.lines().find(|l| l.starts_with("rates: ")).expect("a rates line").to_string();
    let rows = text
        .lines()
        .skip_while(|l| !l.starts_with("decomposition by cost"))
        .skip(2)
        .take_while(|l| !l.starts_with("  ("))
        .map(|l| {
            let w: Vec<&str> = l.trim_end_matches("  ← chosen").split_whitespace().collect();
            let n = w.len();
            (w[..n - 10].join(" "), w[n - 2].parse().unwrap(), w[n - 1].parse().unwrap())
        })
        .collect();
    (line, rows)
}

/// Writes a cache with `cpu` and the rates `rates` (nnz, dense, row, flop, dof) into `dir`.
fn write_cache(dir: &Path, cpu: &str, rates: [f64; 5]) -> String {
    let [nnz, dense, row, flop, dof] = rates;
    let json = serde_json::json!({
        "format": 1, "program": "0", "cpu": cpu, "host": "elsewhere", "date": "2026-01-02 03:04:05",
        "rates": { "nnz": nnz, "dense": dense, "row": row, "flop": flop, "dof": dof }
    });
    let file = dir.join("rates.json");
    std::fs::write(&file, json.to_string()).unwrap();
    file.display().to_string()
}

/// The built-in rates (src/pipeline/plan.rs), in the order of [`write_cache`].
const BUILT_IN: [f64; 5] = [1.05e-9, 1.0e-9, 0.5e-6, 2.5e-11, 1.0e-5];

#[test]
fn calibrate_writes_a_cache_that_check_uses() {
    let dir = common::tmpdir("calibrate");
    let d = dir.to_str().unwrap();
    let o = with_cache(d, &["calibrate"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let file = dir.join("rates.json");
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains(&format!("wrote {}", file.display())), "{text}");
    let cache: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!((cache["format"].as_u64(), cache["cpu"].as_str()), (Some(1), Some(cpu().as_str())));
    assert_eq!(cache["program"].as_str(), Some(env!("CARGO_PKG_VERSION")));
    for k in ["nnz", "dense", "row", "flop", "dof"] {
        let v = cache["rates"][k].as_f64().unwrap();
        assert!(v.is_finite() && v > 0.0, "{k} = {v}");
    }
    // no temporary file left beside it
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    let o = check(d);
    let (line, _) = plan(&o);
    assert_eq!(line, format!("rates: calibrated on CPU {} at {} ({})", cpu(), cache["date"].as_str().unwrap(), file.display()));
    assert!(o.stderr.is_empty(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn a_corrupt_or_foreign_cache_is_ignored_with_one_warning() {
    let (line, built_in) = plan(&check("off"));
    assert_eq!(line, "rates: built-in");
    assert_eq!(built_in.len(), 4, "{built_in:?}");
    let dir = common::tmpdir("ignored");
    let file = dir.join("rates.json").display().to_string();
    let mut bad_rate = BUILT_IN;
    bad_rate[2] = f64::NAN;
    let cases: [(&dyn Fn() -> String, &str); 4] = [
        (&|| std::fs::write(dir.join("rates.json"), "{ \"format\": 1, \"cpu\": ").map(|()| file.clone()).unwrap(), "not a rates cache"),
        (&|| write_cache(&dir, "Another CPU 9000", BUILT_IN), "calibrated on another CPU (Another CPU 9000; this host has"),
        (&|| write_cache(&dir, &cpu(), [1e-9, 1e-9, -1e-6, 1e-11, 1e-5]), "SECONDS_PER_ROW = -0.000001 is not a positive number"),
        (&|| write_cache(&dir, &cpu(), bad_rate), "not a rates cache"),
    ];
    for (write, why) in cases {
        let f = write();
        let o = check(dir.to_str().unwrap());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.starts_with(&format!("warning: rates cache {f} ignored: ")) && err.contains(why), "{err}");
        assert_eq!(plan(&o), ("rates: built-in".to_string(), built_in.clone()));
    }
}

#[test]
fn a_cached_rate_prices_the_plan() {
    let dir = common::tmpdir("priced");
    let d = dir.to_str().unwrap();
    let (_, built_in) = plan(&check("off"));
    // the built-in rates cached: the same table
    let file = write_cache(&dir, &cpu(), BUILT_IN);
    let (line, same) = plan(&check(d));
    assert_eq!(line, format!("rates: calibrated on CPU {} at 2026-01-02 03:04:05 ({file})", cpu()));
    assert_eq!(same, built_in);
    // seconds per unit of Σ (column count)² × 1000: every setup grows, by far
    let mut slow = BUILT_IN;
    slow[3] *= 1000.0;
    write_cache(&dir, &cpu(), slow);
    let (_, priced) = plan(&check(d));
    assert_eq!(priced.len(), built_in.len());
    for (a, b) in built_in.iter().zip(&priced) {
        assert_eq!(a.0, b.0);
        assert!(b.1 > 10.0 * a.1.max(0.01), "{a:?} → {b:?}");
        assert!(b.2 > a.2, "{a:?} → {b:?}");
    }
}

#[test]
fn every_rank_prices_with_the_rates_of_rank_0() {
    // rank 0 has the factorization 1000× slower (TFETI 8/8 is chosen on 2 ranks, the monolithic
    // dual with the built-in rates), rank 1 a corrupt cache: were the ranks to price with their
    // own, they would decompose differently and the run fail
    let dir = common::tmpdir("ranks");
    let (slow, bad) = (dir.join("slow"), dir.join("bad"));
    std::fs::create_dir_all(&slow).unwrap();
    std::fs::create_dir_all(&bad).unwrap();
    let mut rates = BUILT_IN;
    rates[3] *= 1000.0;
    write_cache(&slow, &cpu(), rates);
    std::fs::write(bad.join("rates.json"), "garbage").unwrap();
    let seed = common::root().join("run/seed.toml");
    let out = dir.join("seed.h5");
    let solve = ["solve", seed.to_str().unwrap(), "--set", "mesh.n=14", "--out", out.to_str().unwrap(), "-q"];
    let rank1 = format!("TRESCA_FETI_CACHE={}", bad.display());
    let mut args: Vec<&str> = solve.to_vec();
    args.extend([":", "-n", "1", "-x", &rank1, BIN]);
    args.extend(solve);
    let o = common::mpirun_cmd(1, &args).env("TRESCA_FETI_CACHE", &slow).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(!err.contains("warning: rates cache"), "{err}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.with_extension("json")).unwrap()).unwrap();
    assert_eq!(report["ranks"].as_u64(), Some(2));
    let chosen =
        report["decomposition_plan"].as_array().unwrap().iter().min_by(|a, b| a["time"].as_f64().unwrap().total_cmp(&b["time"].as_f64().unwrap())).unwrap();
    assert_eq!((chosen["tfeti"].as_bool(), chosen["parts"].as_array().map(|p| p.len())), (Some(true), Some(2)), "{chosen}");
    assert!(report.get("tfeti").is_some_and(|t| !t.is_null()), "solved by TFETI");
}
