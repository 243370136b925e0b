//! `tresca-feti bench-tfeti`: the TFETI benchmark of a scene over mesh sizes N, subdomain
//! counts S (S = 0: the monolithic dual), projectors and rank counts P, and the strong and weak
//! scaling studies built on it. Every case is a fresh `LAUNCHER -n P EXEC solve` — `mpirun -n P
//! tresca-feti solve`, `srun --mpi=pmix -n P ch-run img -- tresca-feti solve` (so that each has
//! its own peak memory), bounded by a time limit — whose JSON report gives nA, the
//! iterations, the time of each phase, the peak memory and Σ nnz(L). The time of one A-product,
//! t_A = iterate / (nA + power iterations), is set against its memory-bound floor
//! 2·8·Σ nnz(L) / bandwidth (both triangular solves stream every factor once). Weak scaling:
//! the sizes and subdomain counts are those of 1 rank, and P ranks get N_P = round(N₁·P^{1/3})
//! and S_P = S₁·P (DOFs ∝ N³: constant work per rank), whether or not 1 is in the rank list.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use crate::error::{Error, Result};
use crate::pipeline::report::Report;
use crate::scene::Projector;

/// What to run.
#[derive(Clone, Debug)]
pub struct Args {
    /// The command that runs the solver (program and its arguments, e.g. `ch-run img -- tresca-feti`),
    /// followed by `solve …`.
    pub exec: Vec<String>,
    /// The scene file.
    pub scene: PathBuf,
    /// `--set KEY=VALUE` overrides passed to every case.
    pub sets: Vec<String>,
    /// Mesh sizes N (`mesh.n`).
    pub sizes: Vec<usize>,
    /// Subdomains per body; 0 = monolithic.
    pub subdomains: Vec<usize>,
    /// Projectors of the TFETI cases (`decomposition.projector`).
    pub projectors: Vec<Projector>,
    /// Rank counts; every case runs on each.
    pub ranks: Vec<usize>,
    /// Weak scaling: `sizes` and `subdomains` are those of 1 rank.
    pub weak: bool,
    /// The launcher and its own arguments (`mpirun`, `srun --mpi=pmix`, a path), called as
    /// `LAUNCHER… -n P ARGS… EXEC… solve …`.
    pub launcher: Vec<String>,
    /// The option that set the launcher (`--mpirun` or `--launcher`), named in errors.
    pub launcher_key: String,
    /// Extra launcher arguments, before the executable.
    pub mpirun_args: Vec<String>,
    /// Runs of each case; the fastest (least total) is kept, against other load on the machine.
    pub repeat: usize,
    /// The solver tolerance ε (`solver.eps`).
    pub eps: f64,
    /// Memory bandwidth in GB/s for the floor.
    pub bandwidth: f64,
    /// The CSV file the rows are written to (rewritten after each case).
    pub csv: Option<PathBuf>,
    /// Seconds a case may run before its launcher (and every process it started) is stopped.
    pub timeout: f64,
}

/// The phases, as they appear in the CSV (`<name>_s`); `factorize` includes the monolithic
/// dual's assembly, `total` leaves out the output.
pub const PHASES: [&str; 9] = ["decompose", "factorize", "coarse", "dual", "iterate", "recover", "stress", "gather", "total"];

/// One measured case.
#[derive(Clone, Debug, Default)]
pub struct Row {
    /// `strong` (the same problem on every rank count) or `weak`.
    pub mode: String,
    /// The case a scaling curve follows: `n16_s32_oblique`, `n16_mono`; for weak scaling N and S
    /// are those of 1 rank.
    pub case: String,
    /// MPI ranks P.
    pub ranks: usize,
    /// Runs this row is the fastest of.
    pub runs: usize,
    /// Mesh size N (`mesh.n`).
    pub n: usize,
    /// Subdomains per body S (0: the monolithic dual).
    pub s: usize,
    /// The projector (`oblique`, `orthogonal`; `-` on the monolithic dual).
    pub projector: String,
    /// DOFs of the mesh.
    pub dofs: u64,
    /// Length of the dual vector.
    pub multipliers: u64,
    /// Size of the coarse problem (0 on the monolithic dual).
    pub coarse_dim: u64,
    /// Outer iterations.
    pub outer: u64,
    /// Inner iterations, summed.
    pub inner: u64,
    /// A-products, the power iterations excluded.
    pub n_a: u64,
    /// A-products of the power iterations.
    pub n_a_power: u64,
    /// Seconds, in the order of [`PHASES`].
    pub phases: [f64; 9],
    /// Peak resident memory summed over the ranks, in GB.
    pub peak_gb_sum: f64,
    /// The largest peak resident memory of a rank, in GB.
    pub peak_gb_max: f64,
    /// Σ nnz(L) over the bodies or subdomains.
    pub nnz_l: f64,
    /// Time of one A-product t_A = iterate / (nA + power iterations), in seconds.
    pub t_a: f64,
    /// The memory-bound floor of t_A: 2·8·Σ nnz(L) / bandwidth, in seconds.
    pub floor: f64,
    /// The largest KKT residual.
    pub kkt: f64,
    /// Largest displacement magnitude ‖u‖.
    pub max_u: f64,
}

/// The CSV header, the columns of [`Row::csv`].
pub const HEADER: &str = "mode,case,ranks,runs,N,S,projector,dofs,multipliers,coarse_dim,outer,inner,nA,nA_power,decompose_s,factorize_s,coarse_s,dual_s,iterate_s,recover_s,stress_s,gather_s,total_s,peak_GB_sum,peak_GB_max,nnz_L,tA_ms,floor_ms,tA_over_floor,kkt,max_u";

impl Row {
    /// The row as a CSV line (columns of [`HEADER`]; t_A and floor in ms).
    pub fn csv(&self) -> String {
        let phases: Vec<String> = self.phases.iter().map(|t| format!("{t:.4}")).collect();
        format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.4},{:.4},{},{:.3},{:.3},{:.3},{:.2e},{:.6e}",
            self.mode,
            self.case,
            self.ranks,
            self.runs,
            self.n,
            self.s,
            self.projector,
            self.dofs,
            self.multipliers,
            self.coarse_dim,
            self.outer,
            self.inner,
            self.n_a,
            self.n_a_power,
            phases.join(","),
            self.peak_gb_sum,
            self.peak_gb_max,
            self.nnz_l,
            self.t_a * 1e3,
            self.floor * 1e3,
            self.t_a / self.floor,
            self.kkt,
            self.max_u
        )
    }

    /// The row as a line of the Markdown table of [`table_header`] (times in s, t_A and floor in ms).
    pub fn table(&self) -> String {
        let p = &self.phases;
        let s = if self.s == 0 { "mono".to_string() } else { self.s.to_string() };
        format!(
            "| {:>3} | {:>3} | {:>4} | {:<10} | {:>7} | {:>4} | {:>5} | {:>6.2} | {:>6.2} | {:>6.2} | {:>6.2} | {:>7.2} | {:>7.2} | {:>6.2} | {:>6.2} | {:>7.2} | {:>6.3} | {:>6.3} | {:>7.1} | {:>7.1} | {:>4.2} |",
            self.ranks, self.n, s, self.projector, self.multipliers, self.outer, self.n_a, p[0], p[1], p[2], p[3], p[4], p[5],
            p[6], p[7], p[8], self.peak_gb_sum, self.peak_gb_max, self.t_a * 1e3, self.floor * 1e3, self.t_a / self.floor
        )
    }
}

/// Header of the Markdown table of [`Row::table`].
pub fn table_header() -> String {
    "| ranks |   N |    S | projector  | dual dim | iter |    nA | decomp | factor | coarse |   dual | iterate | recover | stress | gather |   total | mem GB Σ | mem GB max | tA ms | floor ms | tA/floor |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|".into()
}

/// Mesh size and subdomains per body on `p` ranks of a case given for 1 rank: the same for
/// strong scaling; for weak scaling round(N·p^{1/3}) and S·p (S = 0 stays monolithic).
pub fn scaled(weak: bool, n: usize, s: usize, p: usize) -> (usize, usize) {
    if !weak {
        return (n, s);
    }
    (((n as f64) * (p as f64).cbrt()).round() as usize, s * p)
}

/// One run: `case` names the curve, (n, s) the problem solved on `ranks` ranks.
struct Case<'a> {
    name: &'a str,
    ranks: usize,
    n: usize,
    s: usize,
    projector: Projector,
}

/// Runs one case and reads its report.
fn case(a: &Args, c: &Case, dir: &std::path::Path) -> Result<Row> {
    let Case { ranks, n, s, projector, .. } = *c;
    let name = format!("N{n}_S{s}_{projector:?}_P{ranks}").to_lowercase();
    let out = dir.join(format!("{name}.h5"));
    let mut cmd = Command::new(&a.launcher[0]);
    cmd.args(&a.launcher[1..]).arg("-n").arg(ranks.to_string()).args(&a.mpirun_args).args(&a.exec).arg("solve").arg(&a.scene);
    let mut sets = a.sets.clone();
    sets.push(format!("mesh.n={n}"));
    sets.push(format!("solver.eps={:e}", a.eps));
    sets.push("output.fields=[]".into());
    sets.push("output.xdmf=false".into());
    if s == 0 {
        // the monolithic dual at every size (not the automatic decomposition)
        sets.push("decomposition.subdomains=1".into());
        sets.push("decomposition.tfeti=false".into());
    } else {
        sets.push(format!("decomposition.subdomains={s}"));
        sets.push("decomposition.tfeti=true".into());
        sets.push(format!("decomposition.projector=\"{}\"", if projector == Projector::Oblique { "oblique" } else { "orthogonal" }));
    }
    for x in &sets {
        cmd.arg("--set").arg(x);
    }
    cmd.arg("--out").arg(&out).arg("--quiet");
    if let Some((err, status)) = bounded(a, cmd, &dir.join(format!("{name}.stderr")), &name)? {
        return Err(failure(a, &name, ranks, status, &err));
    }
    let json = out.with_extension("json");
    let text = std::fs::read_to_string(&json).map_err(|e| Error::io(json.display().to_string(), e))?;
    let r: Report = serde_json::from_str(&text).map_err(|e| Error::Parse { file: json.display().to_string(), msg: e.to_string() })?;
    // a launcher that starts P separate 1-rank programs (srun without PMI support) shows here
    if r.ranks != ranks {
        return Err(Error::launch(
            format!("case {name}"),
            format!("the report says {} rank(s), not {ranks}: does {} {} start one MPI job?", r.ranks, a.launcher_key, a.launcher.join(" ")),
        ));
    }
    let t = &r.timings;
    let sv = r.solver.clone().unwrap_or_default();
    let nnz_l: f64 = match &r.tfeti {
        Some(tf) => tf.subdomains.iter().map(|x| x.piece.nnz_l as f64).sum(),
        None => r.bodies.iter().map(|x| x.nnz_l as f64).sum(),
    };
    let (n_a, n_a_power) = (sv.info.n_a as u64, sv.info.n_a_power as u64);
    let phases = [
        t.get("decompose"),
        t.get("assemble") + t.get("factorize"),
        t.get("coarse"),
        t.get("dual"),
        t.get("iterate"),
        t.get("recover"),
        t.get("stress"),
        t.get("gather"),
        t.total() - t.get("output"),
    ];
    let t_a = phases[4] / (n_a + n_a_power).max(1) as f64;
    let memory = r.memory.clone().unwrap_or_default();
    Ok(Row {
        mode: if a.weak { "weak" } else { "strong" }.into(),
        case: c.name.into(),
        ranks,
        runs: 1,
        n,
        s,
        projector: if s == 0 { "-".into() } else { format!("{projector:?}").to_lowercase() },
        dofs: r.mesh.dofs as u64,
        multipliers: sv.dual_dim as u64,
        coarse_dim: r.tfeti.as_ref().map_or(0, |tf| tf.coarse_dim as u64),
        outer: sv.info.iterations as u64,
        inner: sv.info.inner_iterations as u64,
        n_a,
        n_a_power,
        phases,
        peak_gb_sum: memory.peak_rss_bytes_sum_over_ranks / 1e9,
        peak_gb_max: memory.peak_rss_bytes_max_rank / 1e9,
        nnz_l,
        t_a,
        floor: 2.0 * 8.0 * nnz_l / (a.bandwidth * 1e9),
        kkt: sv.kkt_worst,
        max_u: r.results.max_displacement,
    })
}

/// Runs `cmd` with its stderr in the file `log`, its stdout discarded, in a process group of its
/// own, for at most `a.timeout` seconds: past it the group is stopped (SIGTERM, then SIGKILL) and
/// the case fails. Returns `None` on success, else the stderr and the status of the failed run.
fn bounded(a: &Args, mut cmd: Command, log: &Path, name: &str) -> Result<Option<(String, ExitStatus)>> {
    use std::os::unix::process::CommandExt;
    let file = std::fs::File::create(log).map_err(|e| Error::io(log.display().to_string(), e))?;
    cmd.stdin(Stdio::null()).stdout(Stdio::null()).stderr(file).process_group(0);
    let launcher = || format!("{} {}", a.launcher_key, a.launcher.join(" "));
    let mut child = cmd.spawn().map_err(|e| Error::io(launcher(), e))?;
    let start = Instant::now();
    let pgid = child.id() as libc::pid_t;
    let group = |sig| {
        // SAFETY: kill(2) on the child's own process group, which it leads (process_group(0))
        unsafe { libc::kill(-pgid, sig) };
    };
    let status = loop {
        if let Some(status) = child.try_wait().map_err(|e| Error::io(launcher(), e))? {
            break status;
        }
        if start.elapsed().as_secs_f64() > a.timeout {
            group(libc::SIGTERM);
            let grace = Instant::now();
            while child.try_wait().ok().flatten().is_none() && grace.elapsed() < Duration::from_secs(5) {
                std::thread::sleep(Duration::from_millis(50));
            }
            group(libc::SIGKILL);
            let _ = child.wait();
            return Err(Error::launch(format!("case {name}"), format!("no result after {} s (--case-timeout): stopped {}", a.timeout, launcher())));
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    // whatever the launcher left behind in the group goes with it
    group(libc::SIGKILL);
    if status.success() {
        return Ok(None);
    }
    Ok(Some((std::fs::read_to_string(log).unwrap_or_default(), status)))
}

/// The one line a failed case ends with: the solver's own `error: …` line where it wrote one
/// (its own section link kept); else the launcher's exit status, the command (launcher and
/// exec) and the launcher's most telling line ([`telling_line`]), not its whole banner.
fn failure(a: &Args, name: &str, ranks: usize, status: ExitStatus, stderr: &str) -> Error {
    if let Some(own) = stderr.lines().find_map(|l| l.strip_prefix("error: ")) {
        return Error::Remote(format!("case {name}: {own}"));
    }
    use std::os::unix::process::ExitStatusExt;
    let exit = match (status.code(), status.signal()) {
        (Some(c), _) => format!("exit {c}"),
        (None, Some(s)) => format!("signal {s}"),
        (None, None) => "exit ?".into(),
    };
    let command = shell_words::join([&a.launcher[..], &["-n".into(), ranks.to_string()], &a.mpirun_args, &a.exec].concat());
    let line = telling_line(stderr).unwrap_or("no message on stderr");
    Error::launch(format!("case {name}"), format!("the launcher failed ({exit}; {command} solve …): {line}"))
}

/// What names a launcher's failure, most telling first: the failing system call of a missing
/// program (`ch-run`, `execve`), a host that does not resolve or answer (ssh under Open MPI's
/// rsh launcher), then any error line (`srun: error: …` of an absent MPI plugin), then Open
/// MPI's own words about its daemons and hosts.
const CAUSES: [&str; 13] = [
    "no such file",
    "could not resolve",
    "no route to host",
    "connection refused",
    "connection timed out",
    "ssh:",
    "error",
    "unable to",
    "orte",
    "host",
    "pmix",
    "plugin",
    "not found",
];

/// The most telling line of a failed launcher's stderr: the first line holding the earliest of
/// [`CAUSES`] (case-insensitive); else its first line that is neither blank nor a rule of dashes.
pub fn telling_line(stderr: &str) -> Option<&str> {
    let lines = || stderr.lines().map(str::trim).filter(|l| !l.is_empty() && !l.chars().all(|c| c == '-' || c == '='));
    CAUSES.iter().find_map(|key| lines().find(|l| l.to_lowercase().contains(key))).or_else(|| lines().next())
}

/// Whether `program` can be started: a path to a file, or a name found on `PATH`.
pub fn found(program: &str) -> bool {
    if program.contains('/') {
        return Path::new(program).is_file();
    }
    std::env::var_os("PATH").is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join(program).is_file()))
}

/// Runs every case (projectors only for S > 0) on every rank count, `repeat` times keeping the
/// fastest, calling `each` after each;
/// the CSV is written after each case, so an interrupted study keeps what it measured.
pub fn run(a: &Args, mut each: impl FnMut(&Row)) -> Result<Vec<Row>> {
    // a program that is not there fails now, in one line, not as a launcher's banner per case
    if !found(&a.launcher[0]) {
        return Err(Error::scene(format!("{} {}", a.launcher_key, a.launcher[0]), "program not found (not a file, not on PATH)"));
    }
    if !found(&a.exec[0]) {
        return Err(Error::scene(format!("--exec {}", a.exec[0]), "program not found (not a file, not on PATH)"));
    }
    let dir = std::env::temp_dir().join(format!("tresca-feti-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(dir.display().to_string(), e))?;
    let mut rows = Vec::new();
    let result = (|| {
        for &n in &a.sizes {
            for &s in &a.subdomains {
                let projectors: Vec<Projector> = if s == 0 { vec![Projector::Oblique] } else { a.projectors.clone() };
                for projector in projectors {
                    let name = if s == 0 { format!("n{n}_mono") } else { format!("n{n}_s{s}_{projector:?}").to_lowercase() };
                    for &ranks in &a.ranks {
                        let (n, s) = scaled(a.weak, n, s, ranks);
                        let c = Case { name: &name, ranks, n, s, projector };
                        let mut row = case(a, &c, &dir)?;
                        for _ in 1..a.repeat {
                            let again = case(a, &c, &dir)?;
                            if again.phases[8] < row.phases[8] {
                                row = again;
                            }
                        }
                        row.runs = a.repeat.max(1);
                        each(&row);
                        rows.push(row);
                        write_csv(a, &rows)?;
                    }
                }
            }
        }
        Ok(())
    })();
    let _ = std::fs::remove_dir_all(&dir);
    result.map(|()| rows)
}

fn write_csv(a: &Args, rows: &[Row]) -> Result<()> {
    let Some(path) = &a.csv else { return Ok(()) };
    let mut text = String::from(HEADER);
    text.push('\n');
    for r in rows {
        text.push_str(&r.csv());
        text.push('\n');
    }
    crate::output::write_atomically(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weak_scaling_keeps_the_work_per_rank() {
        assert_eq!(scaled(false, 16, 32, 8), (16, 32));
        assert_eq!(scaled(true, 10, 4, 1), (10, 4));
        assert_eq!(scaled(true, 10, 4, 2), (13, 8));
        assert_eq!(scaled(true, 10, 4, 8), (20, 32));
        assert_eq!(scaled(true, 10, 4, 16), (25, 64));
        assert_eq!(scaled(true, 16, 0, 64), (64, 0));
    }

    #[test]
    fn header_and_row_have_the_same_columns() {
        let r = Row { floor: 1.0, ..Row::default() };
        assert_eq!(r.csv().split(',').count(), HEADER.split(',').count());
        assert_eq!(table_header().lines().next().unwrap().matches('|').count(), r.table().matches('|').count());
    }
}
