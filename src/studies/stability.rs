//! `tresca-feti stability` (alias `stress`): the numerical-stability suite. Solves every scene
//! of a folder (`run/stress/*.toml`: stiffness contrast, near incompressibility, flat elements,
//! extreme slip bounds, open gaps, lift-off, thin ellipses, tiny subdomains, 10⁴ pairs) through
//! the whole pipeline and sorts each run into one of three outcomes:
//!
//! - **converged**: the solver met ε, the KKT residuals (measured independently of the solver's
//!   stopping test) and, under TFETI, the relative jump of u across the subdomain interfaces are
//!   at most `kkt_factor·ε`, and every reported number is finite;
//! - **stopped**: the pipeline refused with a stated reason (no convergence, breakdown, bad
//!   input) — an honest outcome;
//! - **wrong**: it returned a result that fails those checks — a silent wrong answer, the one
//!   outcome the suite exists to exclude (the command exits non-zero).

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::comm::Comm;
use crate::error::{Error, Result};
use crate::pipeline;
use crate::pipeline::report::Report;

/// What `stability` is asked to do.
#[derive(Clone, Debug)]
pub struct Args {
    /// The scenes: every `*.toml` in this folder, by name.
    pub dir: PathBuf,
    /// Overrides applied to every scene (e.g. `solver.method="gimssn"`).
    pub sets: Vec<String>,
    /// Results go to `<out>/<scene>.h5` (+ .xdmf, .json); the table to `<out>/stability.csv`.
    pub out: PathBuf,
    /// A converged run's worst KKT residual must be at most `kkt_factor·ε`.
    pub kkt_factor: f64,
}

/// How a scene ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// The result passed every check.
    Converged,
    /// The run stopped with this error.
    Stopped(String),
    /// The run returned a result that failed a check: which, and by how much.
    Wrong(String),
}

/// One scene's line of the table.
#[derive(Clone, Debug)]
pub struct Row {
    /// The scene's file stem.
    pub scene: String,
    /// How it ended.
    pub outcome: Outcome,
    /// The report of a run that returned a result.
    pub report: Option<Report>,
}

/// The `*.toml` files of `dir`, sorted.
pub fn scenes(dir: &Path) -> Result<Vec<PathBuf>> {
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir.display().to_string(), e))?;
    let mut v: Vec<PathBuf> = rd.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|x| x == "toml")).collect();
    v.sort();
    if v.is_empty() {
        return Err(Error::scene(dir.display().to_string(), "holds no *.toml scene"));
    }
    Ok(v)
}

/// Sorts a returned report into converged or wrong.
pub fn judge(r: &Report, kkt_factor: f64) -> Outcome {
    let Some(sv) = &r.solver else {
        return Outcome::Wrong("no solver report (no contact in the scene?)".into());
    };
    let (eps, err, kkt) = (sv.eps, sv.info.err, sv.kkt_worst);
    let umax = r.results.max_displacement;
    if !(err.is_finite() && kkt.is_finite() && umax.is_finite() && r.bodies.iter().all(|b| b.residual.is_finite())) {
        return Outcome::Wrong("a non-finite number in the result".into());
    }
    if err > eps {
        return Outcome::Wrong(format!("‖r̃‖/‖b‖ = {err:.1e} above ε = {eps:.0e}"));
    }
    if kkt > kkt_factor * eps {
        return Outcome::Wrong(format!("KKT residual {kkt:.1e} above {kkt_factor}·ε"));
    }
    // TFETI: the subdomains must be glued (the gluing rows are part of the dual gradient)
    if let Some(tf) = &r.tfeti {
        let jump = tf.gluing_jump;
        if !(jump <= kkt_factor * eps) {
            return Outcome::Wrong(format!("relative gluing jump {jump:.1e} above {kkt_factor}·ε"));
        }
    }
    Outcome::Converged
}

/// Runs every scene (collectively: all ranks run every scene); `progress` sees each row.
pub fn run<C: Comm>(comm: &C, args: &Args, mut progress: impl FnMut(&Row)) -> Result<Vec<Row>> {
    let paths = scenes(&args.dir)?;
    let mut rows = Vec::new();
    for path in paths {
        let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let out = args.out.join(format!("{stem}.h5"));
        let row = match pipeline::run_solve(comm, &path, &args.sets, Some(out), true) {
            Ok(s) => Row { scene: stem, outcome: judge(&s.report, args.kkt_factor), report: Some(s.report) },
            Err(e) => Row { scene: stem, outcome: Outcome::Stopped(e.to_string()), report: None },
        };
        progress(&row);
        rows.push(row);
    }
    Ok(rows)
}

/// Cells of a row: scene, n, m, dual, outer, nA, time, ‖r̃‖/‖b‖, KKT, open/stick/slip, max|u|, status.
fn cells(row: &Row) -> Vec<String> {
    let status = match &row.outcome {
        Outcome::Converged => "converged".to_string(),
        Outcome::Stopped(e) => format!("stopped: {e}"),
        Outcome::Wrong(e) => format!("WRONG: {e}"),
    };
    let Some(r) = &row.report else {
        return [row.scene.clone()].into_iter().chain(std::iter::repeat_n("—".to_string(), 10)).chain([status]).collect();
    };
    let dual = match &r.tfeti {
        Some(tf) => format!("TFETI S={}", tf.subdomains_per_body.iter().sum::<usize>()),
        None => "monolithic".to_string(),
    };
    let (sv, c) = (r.solver.clone().unwrap_or_default(), r.contact.clone().unwrap_or_default());
    vec![
        row.scene.clone(),
        r.mesh.dofs.to_string(),
        c.pairs.to_string(),
        dual,
        sv.info.iterations.to_string(),
        sv.info.n_a.to_string(),
        format!("{:.2}", r.timings.total()),
        format!("{:.1e}", sv.info.err),
        format!("{:.1e}", sv.kkt_worst),
        format!("{}/{}/{}", c.open, c.stick, c.slip),
        format!("{:.3e}", r.results.max_displacement),
        status,
    ]
}

const HEADER: [&str; 12] = ["scene", "n", "m", "dual", "outer", "nA", "time [s]", "‖r̃‖/‖b‖", "KKT", "open/stick/slip", "max |u| [m]", "status"];
const WIDTH: [usize; 11] = [22, 7, 6, 12, 5, 6, 8, 8, 8, 16, 11];

/// The printed table's header line.
pub fn header() -> String {
    format_cells(&HEADER.map(String::from))
}

fn format_cells(c: &[String]) -> String {
    let mut s = String::new();
    for (i, v) in c.iter().enumerate() {
        match WIDTH.get(i) {
            Some(&w) if i == 0 || i == 3 => s += &format!("{v:<w$} "),
            Some(&w) => s += &format!("{v:>w$} "),
            None => s += v,
        }
    }
    s
}

/// One printed line.
pub fn format_row(row: &Row) -> String {
    format_cells(&cells(row))
}

/// Writes the table as CSV.
pub fn write_csv(path: &Path, rows: &[Row]) -> Result<()> {
    let mut f = Vec::new();
    let io = |e| Error::io(path.display().to_string(), e);
    writeln!(f, "scene,n,m,dual,outer,nA,time_s,residual,kkt,open_stick_slip,max_u,status").map_err(io)?;
    for r in rows {
        let c: Vec<String> = cells(r).into_iter().map(|v| v.replace([',', '"'], ";")).collect();
        writeln!(f, "{}", c.join(",")).map_err(io)?;
    }
    crate::output::write_atomically(path, &f)
}
