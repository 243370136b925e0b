//! The machine rates that price the plan ([`Rates`]): the built-in constants of
//! [`super::plan`], or rates calibrated on this kind of CPU by `tresca-feti calibrate` and cached
//! in `rates.json` (with the program and format versions, the CPU model, the host and the date).
//! Rank 0 reads the cache once and broadcasts what it chose ([`install`]), so ranks on hosts with
//! different caches price alike; a corrupt cache or one from another CPU is ignored with one
//! warning. `TRESCA_FETI_CACHE=off` (or empty) turns the cache off.
//!
//! The calibration times the project's own kernels on a clamped box — assembly, METIS ordering
//! and symbolic analysis per DOF; faer's numeric Cholesky per Σ (column count)²; the forward and
//! backward solves per nnz(L); the two dense triangular solves of the explicit products per
//! (block size)²; a B-apply with the Krylov vector updates per dual row — the median of a few
//! repetitions each. The built-in rates were fitted end to end on the development machine and
//! hold overheads no kernel shows (the exchange, the coarse projection), so a kernel's time is
//! not a rate: each rate is the built-in one times the ratio of the kernel's time here to its
//! time on the development machine ([`REFERENCE`]).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Instant;

use super::plan::{SECONDS_PER_DENSE, SECONDS_PER_DOF, SECONDS_PER_FLOP, SECONDS_PER_NNZ, SECONDS_PER_ROW};
use crate::comm::Comm;
use crate::error::{Error, Result};

/// The format of `rates.json` this program reads and writes.
pub const FORMAT: u32 = 1;
/// The cache file's name in the cache directory.
pub const FILE: &str = "rates.json";
/// The kernels' times on the development machine (where the built-in rates were fitted), in the
/// units of [`Rates`]: `tresca-feti calibrate` there.
pub const REFERENCE: Rates = Rates { nnz: 1.05e-9, dense: 2.8e-10, row: 4.8e-9, flop: 5.9e-11, dof: 5.9e-6 };

/// Seconds per unit of each quantity the plan prices.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Rates {
    /// Per entry of L per A-product (forward and backward solve).
    pub nnz: f64,
    /// Per (contact DOFs of a body)² per explicit A-product.
    pub dense: f64,
    /// Per dual row per A-product, outside the solves.
    pub row: f64,
    /// Per unit of Σ (column count)² of the numeric factorization.
    pub flop: f64,
    /// Per DOF before the solve (assembly, ordering, kernels, rows of B).
    pub dof: f64,
}

impl Default for Rates {
    /// The built-in constants of [`super::plan`].
    fn default() -> Self {
        Rates { nnz: SECONDS_PER_NNZ, dense: SECONDS_PER_DENSE, row: SECONDS_PER_ROW, flop: SECONDS_PER_FLOP, dof: SECONDS_PER_DOF }
    }
}

impl Rates {
    /// The rates with their names, in the order of the table.
    fn named(&self) -> [(&'static str, f64); 5] {
        [
            ("SECONDS_PER_NNZ", self.nnz),
            ("SECONDS_PER_DENSE", self.dense),
            ("SECONDS_PER_ROW", self.row),
            ("SECONDS_PER_FLOP", self.flop),
            ("SECONDS_PER_DOF", self.dof),
        ]
    }

    /// Each rate of `self` times the ratio of `here` to `reference`.
    fn scaled(&self, here: &Rates, reference: &Rates) -> Rates {
        let r = |a: f64, h: f64, f: f64| a * h / f;
        Rates {
            nnz: r(self.nnz, here.nnz, reference.nnz),
            dense: r(self.dense, here.dense, reference.dense),
            row: r(self.row, here.row, reference.row),
            flop: r(self.flop, here.flop, reference.flop),
            dof: r(self.dof, here.dof, reference.dof),
        }
    }
}

/// The cache file's contents.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Cache {
    /// [`FORMAT`] of the program that wrote it.
    pub format: u32,
    /// The version of the program that wrote it.
    pub program: String,
    /// The CPU model it was calibrated on ([`cpu_model`]).
    pub cpu: String,
    /// The host it was calibrated on.
    pub host: String,
    /// When (UTC, `YYYY-MM-DD HH:MM:SS`).
    pub date: String,
    /// The calibrated rates.
    pub rates: Rates,
}

/// The rates that price the plan and where they came from.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Priced {
    /// The rates.
    pub rates: Rates,
    /// `check`'s line: "rates: built-in" or "rates: calibrated on CPU … at DATE (FILE)".
    pub line: String,
}

impl Default for Priced {
    fn default() -> Self {
        Priced { rates: Rates::default(), line: "rates: built-in".into() }
    }
}

static CURRENT: OnceLock<Priced> = OnceLock::new();

/// The rates that price the plan: those [`install`] chose, else the built-in ones (a library
/// caller that installs none, the tests among them, prices with the built-in rates).
pub fn current() -> &'static Priced {
    CURRENT.get_or_init(Priced::default)
}

/// Chooses the rates once for the run (collective): rank 0 reads the cache and prints its one
/// warning where it is ignored, every rank takes rank 0's choice. Returns the rates installed.
pub fn install<C: Comm>(comm: &C) -> &'static Priced {
    let mut bytes = Vec::new();
    if comm.is_root() {
        let (priced, warning) = match cache_dir() {
            Some(dir) => choose(&dir.join(FILE), &cpu_model()),
            None => (Priced::default(), None),
        };
        if let Some(w) = warning {
            eprintln!("{w}");
        }
        bytes = serde_json::to_vec(&priced).unwrap_or_default();
    }
    comm.broadcast_bytes(0, &mut bytes);
    let priced = serde_json::from_slice(&bytes).unwrap_or_default();
    let _ = CURRENT.set(priced);
    current()
}

/// The cache directory: `$TRESCA_FETI_CACHE` (none where `off` or empty), else
/// `$XDG_CACHE_HOME/tresca-feti`, else `~/.cache/tresca-feti`.
pub fn cache_dir() -> Option<PathBuf> {
    match std::env::var_os("TRESCA_FETI_CACHE") {
        Some(v) if v.is_empty() || v == "off" => None,
        Some(v) => Some(PathBuf::from(v)),
        None => match std::env::var_os("XDG_CACHE_HOME").filter(|v| !v.is_empty()) {
            Some(x) => Some(PathBuf::from(x).join("tresca-feti")),
            None => std::env::var_os("HOME").filter(|v| !v.is_empty()).map(|h| PathBuf::from(h).join(".cache").join("tresca-feti")),
        },
    }
}

/// The rates of the cache `file` for a host with the CPU `cpu`: the cached ones where the file
/// exists, parses, has [`FORMAT`], positive finite rates and the same CPU; else the built-in
/// ones, with the warning line where a file exists but is not used.
pub fn choose(file: &Path, cpu: &str) -> (Priced, Option<String>) {
    let warn = |why: String| (Priced::default(), Some(format!("warning: rates cache {} ignored: {why}; the built-in rates price the plan", file.display())));
    let text = match std::fs::read_to_string(file) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return (Priced::default(), None),
        Err(e) => return warn(format!("cannot be read ({e})")),
    };
    let cache: Cache = match serde_json::from_str(&text) {
        Ok(c) => c,
        Err(e) => return warn(format!("not a rates cache ({e})")),
    };
    if cache.format != FORMAT {
        return warn(format!("format {}, this program reads format {FORMAT}", cache.format));
    }
    if let Some((name, v)) = cache.rates.named().into_iter().find(|(_, v)| !(v.is_finite() && *v > 0.0)) {
        return warn(format!("{name} = {v} is not a positive number"));
    }
    if cache.cpu != cpu {
        return warn(format!("calibrated on another CPU ({}; this host has {cpu}): run `tresca-feti calibrate` here", cache.cpu));
    }
    let line = format!("rates: calibrated on CPU {} at {} ({})", cache.cpu, cache.date, file.display());
    (Priced { rates: cache.rates, line }, None)
}

/// This host's CPU model: the first "model name" of /proc/cpuinfo, or "unknown".
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with("model name")).and_then(|l| l.split_once(':')).map(|(_, v)| v.trim().to_string()))
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

/// This host's name, or "unknown".
fn host_name() -> String {
    ["/proc/sys/kernel/hostname", "/etc/hostname"]
        .iter()
        .find_map(|p| std::fs::read_to_string(p).ok().map(|s| s.trim().to_string()).filter(|s| !s.is_empty()))
        .unwrap_or_else(|| "unknown".into())
}

/// Now, UTC, as `YYYY-MM-DD HH:MM:SS`.
fn utc_now() -> String {
    civil(std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs()) as i64)
}

/// `secs` after 1970-01-01 00:00 UTC as `YYYY-MM-DD HH:MM:SS` (the civil date from the days,
/// Hinnant's algorithm).
fn civil(secs: i64) -> String {
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02}", rem / 3600, rem / 60 % 60, rem % 60)
}

/// Writes `cache` to `dir`/[`FILE`] atomically (a temporary file renamed over it); returns the
/// file.
pub fn write(dir: &Path, cache: &Cache) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display().to_string(), e))?;
    let file = dir.join(FILE);
    let tmp = dir.join(format!(".{FILE}.{}.tmp", std::process::id()));
    let text = serde_json::to_string_pretty(cache).map_err(|e| Error::output(file.display().to_string(), e.to_string()))?;
    std::fs::write(&tmp, text + "\n").map_err(|e| Error::io(tmp.display().to_string(), e))?;
    std::fs::rename(&tmp, &file).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(file.display().to_string(), e)
    })?;
    Ok(file)
}

/// `tresca-feti calibrate`: times the kernels ([`kernels`]), writes the cache to `dir` (none:
/// the cache is off, nothing written) and returns the table of the kernels' times and the
/// rates, calibrated against built-in.
pub fn calibrate(dir: Option<&Path>) -> Result<String> {
    let here = kernels()?;
    let built_in = Rates::default();
    let rates = built_in.scaled(&here, &REFERENCE);
    let cache = Cache { format: FORMAT, program: env!("CARGO_PKG_VERSION").into(), cpu: cpu_model(), host: host_name(), date: utc_now(), rates };
    let wrote = match dir {
        Some(d) => format!("wrote {}", write(d, &cache)?.display()),
        None => "not written: the rates cache is off (TRESCA_FETI_CACHE)".into(),
    };
    Ok(table(&cache, &here) + &wrote)
}

/// The table `calibrate` prints.
fn table(cache: &Cache, here: &Rates) -> String {
    use std::fmt::Write;
    let mut s = format!("rates calibrated on CPU {} (host {}) at {}:\n", cache.cpu, cache.host, cache.date);
    let _ = writeln!(s, "  {:<18} {:>12} {:>12} {:>7} {:>12} {:>12}", "rate", "kernel here", "kernel ref", "ratio", "built-in", "calibrated");
    for (((name, h), (_, r)), ((_, b), (_, c))) in
        here.named().into_iter().zip(REFERENCE.named()).zip(Rates::default().named().into_iter().zip(cache.rates.named()))
    {
        let _ = writeln!(s, "  {name:<18} {h:>12.3e} {r:>12.3e} {:>7.2} {b:>12.3e} {c:>12.3e}", h / r);
    }
    let _ = writeln!(s, "  (kernel: seconds per unit of the kernel alone, here and on the development machine; calibrated = built-in × ratio)");
    s
}

/// Seconds per call of `f`: called until 20 ms have passed, the median of three such runs.
fn seconds_per(mut f: impl FnMut()) -> f64 {
    let mut runs: Vec<f64> = (0..3)
        .map(|_| {
            let (clock, mut calls) = (Instant::now(), 0u32);
            while calls == 0 || clock.elapsed().as_secs_f64() < 0.02 {
                f();
                calls += 1;
            }
            clock.elapsed().as_secs_f64() / f64::from(calls)
        })
        .collect();
    runs.sort_by(f64::total_cmp);
    runs[1]
}

/// The kernels' seconds per unit on this machine (one core), fitted through the origin over a
/// few clamped boxes: Σ seconds / Σ units.
pub fn kernels() -> Result<Rates> {
    let mut sums = [[0.0f64; 2]; 5];
    for n in [9, 12, 15] {
        for (s, (t, q)) in sums.iter_mut().zip(box_kernels(n)?) {
            s[0] += t;
            s[1] += q;
        }
    }
    let r = |i: usize| sums[i][0] / sums[i][1];
    Ok(Rates { nnz: r(0), dense: r(1), row: r(2), flop: r(3), dof: r(4) })
}

/// (seconds, units) of each kernel, in the order of [`Rates`], on a unit box of n³ nodes clamped
/// at z = 0: its top face's free DOFs are the dense block and the dual rows.
fn box_kernels(n: usize) -> Result<[(f64, f64); 5]> {
    use crate::fem::assembly::{assemble_body, DofMap};
    use crate::linalg::cholesky::{Cholesky, Ordering, Symbolic};
    use crate::linalg::ordering::{expand_to_dofs, order_last_if_cheap};
    let mut mesh = crate::mesh::Mesh::default();
    mesh.try_push_body("calibration box", crate::mesh::boxgen::try_generate([0.0; 3], [1.0; 3], [n; 3])?)?;
    let nodes = mesh.bodies[0].nodes.clone();
    let clamped: Vec<(usize, usize, f64)> = (0..n * n).flat_map(|v| (0..3).map(move |c| (v, c, 0.0))).collect();
    let lame = crate::fem::material::Lame::from_young_poisson(1.0, 0.3);
    let loads = vec![0.0; 3 * nodes.len()];
    // setup: assembly, the METIS order, the symbolic analysis
    let mut setup = None;
    let t_setup = seconds_per(|| {
        let dofs = DofMap::new(nodes.clone(), &clamped);
        let run = assemble_body(&mesh, 0, lame, &dofs, &loads).and_then(|sys| {
            let free: Vec<u8> = (0..nodes.len()).map(|v| dofs.node_dofs(v).iter().flatten().count() as u8).collect();
            let order = order_last_if_cheap(&sys.graph.0, &sys.graph.1, &[], &free)?;
            let perm = expand_to_dofs(&order.perm, dofs.nfree, |v| dofs.node_dofs(v));
            let symbolic = Symbolic::analyze(&sys.k, Ordering::Custom(perm))?;
            Ok((dofs, sys, order.fill, symbolic))
        });
        setup = Some(run);
    });
    let (dofs, sys, fill, symbolic) = setup.expect("timed at least once")?;
    let mut factor = None;
    let t_flop = seconds_per(|| factor = Some(Cholesky::with_symbolic(symbolic.clone(), &sys.k)));
    let chol = factor.expect("timed at least once")?;
    let mut x = vec![1.0; dofs.nfree];
    let t_nnz = seconds_per(|| chol.solve_in_place(&mut x));
    // the top face's free DOFs: the trailing block's size and the dual rows
    let top: Vec<usize> = (n * n * (n - 1)..n * n * n).flat_map(|v| dofs.node_dofs(v).into_iter().flatten()).collect();
    let nb = top.len();
    let l = chol.trailing_block(nb);
    let mut z = faer::Mat::<f64>::from_fn(nb, 1, |i, _| 1.0 + i as f64 * 1e-3);
    let t_dense = seconds_per(|| {
        use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
        solve_lower_triangular_in_place(l.as_ref(), z.as_mut(), faer::Par::Seq);
        solve_upper_triangular_in_place(l.transpose(), z.as_mut(), faer::Par::Seq);
    });
    let t_row = row_seconds(&top, dofs.nfree);
    Ok([(t_nnz, fill.nnz_l), (t_dense, (nb * nb) as f64), (t_row, nb as f64), (t_flop, fill.flops), (t_setup, 3.0 * nodes.len() as f64)])
}

/// Seconds of one A-product's work outside the solves on the rows B = ± the unit rows of `dofs`
/// (of `ndof` unknowns): Bᵀλ scattered, Bu gathered and the Krylov updates of the dual vectors
/// (three axpys and two dot products).
fn row_seconds(dofs: &[usize], ndof: usize) -> f64 {
    let m = dofs.len();
    let b: Vec<(usize, usize, f64)> = dofs.iter().enumerate().map(|(r, &j)| (r, j, if r % 2 == 0 { 1.0 } else { -1.0 })).collect();
    let (mut u, mut lambda, mut y, mut p, mut g) = (vec![0.0; ndof], vec![1.0; m], vec![0.0; m], vec![0.5; m], vec![0.25; m]);
    let mut acc = 0.0;
    let t = seconds_per(|| {
        for &(r, j, c) in &b {
            u[j] += c * lambda[r];
        }
        y.iter_mut().for_each(|v| *v = 0.0);
        for &(r, j, c) in &b {
            y[r] += c * u[j];
        }
        let py: f64 = p.iter().zip(&y).map(|(a, b)| a * b).sum();
        let alpha = 1e-9 / (1.0 + py.abs());
        lambda.iter_mut().zip(&p).for_each(|(l, p)| *l -= alpha * p);
        g.iter_mut().zip(&y).for_each(|(g, y)| *g -= alpha * y);
        let gg: f64 = g.iter().map(|v| v * v).sum();
        p.iter_mut().zip(&g).for_each(|(p, g)| *p = g + 1e-3 * *p);
        acc += gg;
    });
    std::hint::black_box(acc);
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("tresca-feti-rates-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    fn cache(cpu: &str) -> Cache {
        Cache { format: FORMAT, program: "0".into(), cpu: cpu.into(), host: "h".into(), date: utc_now(), rates: REFERENCE }
    }

    #[test]
    fn a_written_cache_is_read_back_and_a_foreign_or_broken_one_ignored() {
        let dir = tmp("choose");
        let file = write(&dir, &cache("CPU A")).unwrap();
        let (p, w) = choose(&file, "CPU A");
        assert_eq!((p.rates, w), (REFERENCE, None));
        assert!(p.line.starts_with("rates: calibrated on CPU CPU A at "), "{}", p.line);
        let (p, w) = choose(&file, "CPU B");
        assert_eq!(p, Priced::default());
        assert!(w.unwrap().contains("another CPU (CPU A; this host has CPU B)"));
        let mut bad = cache("CPU A");
        bad.rates.flop = -1.0;
        write(&dir, &bad).unwrap();
        assert!(choose(&file, "CPU A").1.unwrap().contains("SECONDS_PER_FLOP = -1 is not a positive number"));
        std::fs::write(&file, "{ not json").unwrap();
        let (p, w) = choose(&file, "CPU A");
        assert_eq!(p, Priced::default());
        assert!(w.unwrap().starts_with(&format!("warning: rates cache {} ignored: not a rates cache", file.display())));
        assert_eq!(choose(&dir.join("none.json"), "CPU A"), (Priced::default(), None));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_date_is_the_civil_date() {
        // days after 1970-01-01: 11017 to 2000-03-01, 19782 to 2024-02-29 (a leap day)
        assert_eq!(civil(0), "1970-01-01 00:00:00");
        assert_eq!(civil(11_017 * 86_400), "2000-03-01 00:00:00");
        assert_eq!(civil(19_782 * 86_400 + 12 * 3600 + 34 * 60 + 56), "2024-02-29 12:34:56");
        assert_eq!(civil(19_782 * 86_400 - 1), "2024-02-28 23:59:59");
    }
}
