//! `tresca-feti table1`: the paper's Table 1 (docs/validation.md, "The paper's benchmark") — iter/nA of the dual solvers on the
//! seed scene for growing N — with our figures beside the paper's, the wall time of each solve,
//! the KKT residual and the error in u against a tight reference, printed as a table (rank 0)
//! and written as CSV.
//!
//! A column is a solver with a parameter preset: `default` (the scene's `[solver]` table) or
//! `paper` (the settings that reproduce the paper's counts, docs/method.md, "The solvers": ρ = 1.9/σ_est, rtol 0.1,
//! cfact 0.6, inner tolerance relative to the gradient at the start of the inner solve and no
//! floor under it; for SSN-BiCGSTAB ρ = 1/σ_est and near-exact inner solves, 1e-6). The reference u is SSN-BiCGSTAB
//! at ε = 1e-11 (validated against Clarabel in tests/clarabel.rs).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::comm::Comm;
use crate::dual::monolithic::MonolithicDual;
use crate::dual::DualProblem;
use crate::error::{Error, Result};
use crate::pipeline::{assemble_and_factorize, preconditioner, DualKind, Timings};
use crate::qp::{self, kkt, CgStop, Method, MethodParams, Operator, Params, Qp, Silent, Space};
use crate::scene::Preconditioner;

/// The paper's Table 1 (IMSSN, SSN-BiCGSTAB iter/nA) by N.
pub const PAPER: [(usize, [usize; 2], [usize; 2]); 6] = [
    (16, [10, 161], [9, 1180]),
    (21, [9, 143], [9, 1428]),
    (26, [10, 185], [11, 2506]),
    (31, [10, 190], [10, 2162]),
    (36, [9, 167], [10, 2298]),
    (41, [10, 216], [10, 2586]),
];

/// Parameter presets of a column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// The method's own defaults, with the scene's common settings.
    Default,
    /// The paper's settings (ρ, σ_est by 30 power iterations, the inner tolerances).
    Paper,
    /// TSSN with the FETI lumped preconditioner (TFETI only).
    Lumped,
    /// TSSN with the FETI Dirichlet preconditioner (TFETI only).
    Dirichlet,
}

/// One column of the table: a solver and its preset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Column {
    /// The solver.
    pub method: Method,
    /// Its parameter preset.
    pub preset: Preset,
}

impl Column {
    /// `name`, `name:paper`, or `tssn:lumped` / `tssn:dirichlet` (TSSN's CG preconditioned on
    /// the TFETI gluing block).
    pub fn parse(s: &str) -> std::result::Result<Column, String> {
        let (name, preset) = match s.split_once(':') {
            Some((n, "paper")) => (n, Preset::Paper),
            Some((n, "default")) => (n, Preset::Default),
            Some((n, "lumped")) => (n, Preset::Lumped),
            Some((n, "dirichlet")) => (n, Preset::Dirichlet),
            Some((_, p)) => return Err(format!("unknown preset \"{p}\" (use paper, default, lumped or dirichlet)")),
            None => (s, Preset::Default),
        };
        let known = Method::ALL.map(Method::name).join(", ");
        let method = Method::from_name(name).ok_or_else(|| format!("unknown solver \"{name}\" (known: {known})"))?;
        if method == Method::Tssn && preset == Preset::Paper {
            return Err("tssn has no paper preset (the paper does not have the method)".into());
        }
        let column = Column { method, preset };
        // on the dual that takes one most widely, so that only the method can refuse
        if preconditioner(method, column.preconditioner(), DualKind::Tfeti { orthogonal: false, contact: true, projected: true }).is_err() {
            let takes: Vec<&str> = Method::ALL.iter().filter(|m| m.takes_preconditioner()).map(|m| m.name()).collect();
            return Err(format!("{name} takes no preconditioner (only {}: e.g. tssn:lumped, tssn:dirichlet)", takes.join(", ")));
        }
        Ok(column)
    }

    /// The column's name: `name`, or `name:preset` for a preset other than the default.
    pub fn label(&self) -> String {
        let name = self.method.name();
        match self.preset {
            Preset::Default => name.to_string(),
            Preset::Paper => format!("{name}:paper"),
            Preset::Lumped => format!("{name}:lumped"),
            Preset::Dirichlet => format!("{name}:dirichlet"),
        }
    }

    /// The preconditioner the column's dual operator must carry.
    pub fn preconditioner(&self) -> Preconditioner {
        match self.preset {
            Preset::Lumped => Preconditioner::Lumped,
            Preset::Dirichlet => Preconditioner::Dirichlet,
            Preset::Default | Preset::Paper => Preconditioner::None,
        }
    }

    /// The solver parameters of this column from the scene's: the scene's own when the column
    /// runs the scene's method, else its common settings with the method's defaults.
    pub fn params(&self, base: &Params, eps: f64) -> Params {
        let mut p = if base.method() == self.method { base.clone() } else { base.with_method(self.method) };
        p.common.eps = eps;
        if self.preset == Preset::Paper {
            // ρ = 1/σ_est for SSN, 1.9/σ_est for the others; σ_est by 30 power iterations
            p.common.rho_factor = if self.method == Method::SsnBicgstab { 1.0 } else { 1.9 } * qp::SIGMA_SAFETY;
            p.common.sigma_estimate = qp::SigmaEstimate::Power;
            p.common.power_iterations = 30;
            match &mut p.method {
                MethodParams::SsnBicgstab(m) => {
                    m.inner_tol = Some(1e-6);
                    m.cg_stop = CgStop::InitialGradient;
                    m.inner_floor = 0.0;
                }
                MethodParams::Gimssn(m) | MethodParams::Imssn(m) => {
                    m.rtol = 0.1;
                    m.cfact = 0.6;
                    m.cg_stop = CgStop::InitialGradient;
                    m.inner_floor = 0.0;
                }
                MethodParams::Mssn(_) | MethodParams::Mpgp(_) | MethodParams::Tssn(_) => {}
            }
        }
        p
    }
}

/// What `table1` is asked to do.
#[derive(Clone, Debug)]
pub struct Args {
    /// The scene file (with contact).
    pub scene: PathBuf,
    /// `--set KEY=VALUE` overrides applied at every N.
    pub sets: Vec<String>,
    /// Mesh sizes N (`mesh.n`), one row each.
    pub sizes: Vec<usize>,
    /// The solvers' tolerance ε.
    pub eps: f64,
    /// The columns, in order.
    pub columns: Vec<Column>,
    /// The CSV file to write the table to.
    pub csv: Option<PathBuf>,
    /// Compute the reference u and report the error of each column against it.
    pub error: bool,
}

/// One cell: a solve of one column at one N.
#[derive(Clone, Debug)]
pub struct Cell {
    /// Mesh size N.
    pub n: usize,
    /// The column solved.
    pub column: Column,
    /// The solver's counters, or its error message.
    pub outcome: std::result::Result<qp::Info, String>,
    /// Wall time of the solve (max over the ranks), in seconds.
    pub seconds: f64,
    /// The largest KKT residual (NaN when the solve failed).
    pub kkt: f64,
    /// max|u − u_ref| / max|u_ref| against the reference solve (with `error` only).
    pub u_error: Option<f64>,
}

/// One row: the problem at one N.
#[derive(Clone, Debug)]
pub struct Row {
    /// Mesh size N.
    pub n: usize,
    /// DOFs of the mesh.
    pub dofs: usize,
    /// Contact pairs.
    pub pairs: usize,
    /// Assembly and factorization time, in seconds.
    pub factorize_s: f64,
    /// One cell per column.
    pub cells: Vec<Cell>,
}

/// max|u − u_ref| / max|u_ref| over all bodies and ranks.
pub fn u_error<C: Comm>(comm: &C, u: &[Vec<f64>], reference: &[Vec<f64>]) -> f64 {
    let mut v = [0.0f64, 0.0];
    for (a, b) in u.iter().zip(reference) {
        for (x, y) in a.iter().zip(b) {
            v[0] = v[0].max((x - y).abs());
            v[1] = v[1].max(y.abs());
        }
    }
    comm.max_f64(&mut v);
    v[0] / v[1].max(f64::MIN_POSITIVE)
}

/// The columns table1 can run: none with a preconditioner (the monolithic dual has none).
pub fn check_columns(columns: &[Column]) -> Result<()> {
    match columns.iter().find(|c| preconditioner(c.method, c.preconditioner(), DualKind::Monolithic).is_err()) {
        Some(c) => Err(Error::scene(
            "--solvers",
            format!("table1 runs on the monolithic dual, which has no preconditioner: {} needs TFETI (work-precision --subdomains)", c.label()),
        )),
        None => Ok(()),
    }
}

/// Runs the table; `each` sees every solve as it finishes, `progress` every finished row (rank
/// 0 prints them).
pub fn run<C: Comm>(comm: &C, args: &Args, mut each: impl FnMut(&Cell), mut progress: impl FnMut(&Row)) -> Result<Vec<Row>> {
    check_columns(&args.columns)?;
    let mut rows = Vec::new();
    for &n in &args.sizes {
        let mut sets = vec![format!("mesh.n={n}")];
        sets.extend(args.sets.iter().cloned());
        let ls = comm.agree(crate::scene::load(&args.scene, &sets))?;
        let model = comm.agree(crate::model::build(&ls))?;
        let contact = model.pairs.as_ref().ok_or_else(|| Error::scene("contact", "table1 needs a scene with contact"))?;
        if contact.is_coulomb() {
            // its rows time one QP solve per tolerance; Coulomb's fixed point runs in `solve`
            return Err(Error::scene(
                "contact.pair.friction",
                "table1 times Tresca solves; Coulomb friction is solved by `tresca-feti solve` (its fixed point)",
            ));
        }
        let mut t = Timings::default();
        let bodies = assemble_and_factorize(comm, &model, ls.scene.factorization.ordering, true, &mut t)?;
        let (dual, b) = MonolithicDual::new(comm, contact, bodies);
        let set = contact.constraint_set();
        let qp = Qp::new(&dual, &b, &set);
        let base = &ls.scene.solver.params;
        let zero = vec![0.0; dual.dim()];
        let reference = if args.error {
            let mut p = Params::new(Method::SsnBicgstab).with_eps(1e-11);
            p.common = qp::Common { eps: 1e-11, max_outer: 10_000, ..base.common.clone() };
            let sol = qp::solve(&qp, &zero, &p, &mut Silent).map_err(|e| Error::solver("the reference solve (SSN-BiCGSTAB, ε = 1e-11)", e))?;
            Some(dual.recover(&sol.lambda).u)
        } else {
            None
        };
        let bnorm = dual.space().norm(&b);
        let mut cells = Vec::new();
        for &column in &args.columns {
            let p = column.params(base, args.eps);
            comm.barrier();
            let t0 = Instant::now();
            let r = qp::solve(&qp, &zero, &p, &mut Silent);
            let mut secs = [t0.elapsed().as_secs_f64()];
            comm.max_f64(&mut secs);
            let (outcome, kkt, u_err) = match r {
                Ok(sol) => {
                    let k = kkt::residuals(&set, &sol.lambda, &sol.gradient, bnorm).worst();
                    let e = reference.as_ref().map(|rf| u_error(comm, &dual.recover(&sol.lambda).u, rf));
                    (Ok(sol.info), k, e)
                }
                Err(e) => (Err(e.to_string()), f64::NAN, None),
            };
            let cell = Cell { n, column, outcome, seconds: secs[0], kkt, u_error: u_err };
            each(&cell);
            cells.push(cell);
        }
        let mut dofs = [model.mesh.nodes.len() as f64 * 3.0];
        comm.max_f64(&mut dofs);
        let row = Row { n, dofs: dofs[0] as usize, pairs: contact.len(), factorize_s: t.phases.iter().map(|p| p.1).sum(), cells };
        progress(&row);
        rows.push(row);
    }
    Ok(rows)
}

/// One solve as it finishes: `N = 16 gimssn: 10/161 (+30) 1.23 s`.
pub fn format_cell(c: &Cell) -> String {
    match &c.outcome {
        Ok(i) => format!("N = {} {}: {}/{} (+{}) {:.2} s", c.n, c.column.label(), i.iterations, i.n_a, i.n_a_power, c.seconds),
        Err(e) => format!("N = {} {}: {e}", c.n, c.column.label()),
    }
}

/// The header lines of the printed table.
pub fn header(args: &Args, ranks: usize) -> String {
    let mut s = format!(
        "Table 1 — {}, ε = {:.1e} (‖r̃_ρ‖ ≤ ε‖b‖), {ranks} rank(s); cells: iter/nA (+ power iterations) time [s] KKT{}\n",
        args.scene.display(),
        args.eps,
        if args.error { " err(u)" } else { "" }
    );
    s += &format!("{:>3} {:>14} {:>8}", "N", "n/m", "factor");
    for c in &args.columns {
        s += &format!(" | {:<34}", c.label());
    }
    s += " | paper IMSSN | paper SSN";
    s
}

/// One printed line for a row.
pub fn format_row(row: &Row) -> String {
    let mut s = format!("{:>3} {:>14} {:>7.2}s", row.n, format!("{}/{}", row.dofs, row.pairs), row.factorize_s);
    for c in &row.cells {
        let cell = match &c.outcome {
            Ok(i) => {
                let err = c.u_error.map(|e| format!(" {e:.0e}")).unwrap_or_default();
                format!("{}/{} (+{}) {:.2}s {:.0e}{err}", i.iterations, i.n_a, i.n_a_power, c.seconds, c.kkt)
            }
            Err(_) => "failed (see below)".to_string(),
        };
        s += &format!(" | {cell:<34}");
    }
    match PAPER.iter().find(|p| p.0 == row.n) {
        Some((_, im, ssn)) => s += &format!(" | {:>11} | {:>9}", format!("{}/{}", im[0], im[1]), format!("{}/{}", ssn[0], ssn[1])),
        None => s += " | — | —",
    }
    for c in &row.cells {
        if let Err(e) = &c.outcome {
            s += &format!("\n    N = {}, {}: {e}", row.n, c.column.label());
        }
    }
    s
}

/// Writes the CSV (one line per N and column).
pub fn write_csv(path: &Path, args: &Args, rows: &[Row]) -> Result<()> {
    let mut bytes = Vec::new();
    write_rows(&mut bytes, args, rows).map_err(|e| Error::io(path.display().to_string(), e))?;
    crate::output::write_atomically(path, &bytes)
}

fn write_rows(f: &mut Vec<u8>, args: &Args, rows: &[Row]) -> std::io::Result<()> {
    writeln!(f, "N,n,m,solver,preset,eps,iter,nA,nA_power,inner,time_s,err,kkt,u_error,factorize_s,paper_iter,paper_nA,status")?;
    for r in rows {
        for c in &r.cells {
            let paper = PAPER.iter().find(|p| p.0 == r.n).and_then(|p| match c.column.method {
                Method::Imssn => Some(p.1),
                Method::SsnBicgstab => Some(p.2),
                _ => None,
            });
            let (pi, pn) = paper.map(|p| (p[0].to_string(), p[1].to_string())).unwrap_or_default();
            let preset = if c.column.preset == Preset::Paper { "paper" } else { "default" };
            let ue = c.u_error.map(|e| format!("{e:e}")).unwrap_or_default();
            match &c.outcome {
                Ok(i) => writeln!(
                    f,
                    "{},{},{},{},{preset},{:e},{},{},{},{},{:.4},{:e},{:e},{ue},{:.3},{pi},{pn},ok",
                    r.n,
                    r.dofs,
                    r.pairs,
                    c.column.method.name(),
                    args.eps,
                    i.iterations,
                    i.n_a,
                    i.n_a_power,
                    i.inner_iterations,
                    c.seconds,
                    i.err,
                    c.kkt,
                    r.factorize_s
                ),
                Err(e) => writeln!(
                    f,
                    "{},{},{},{},{preset},{:e},,,,,{:.4},,,,{:.3},{pi},{pn},\"{}\"",
                    r.n,
                    r.dofs,
                    r.pairs,
                    c.column.method.name(),
                    args.eps,
                    c.seconds,
                    r.factorize_s,
                    e.replace('"', "'")
                ),
            }?;
        }
    }
    f.flush()
}
