//! `tresca-feti`: the command line. Parses arguments (clap) before MPI starts, initializes MPI,
//! runs the pipeline on every rank, and lets only rank 0 print. Usage errors: as clap prints
//! them, exit code 2, from the launcher's first rank. Errors in the user's files and keys: one
//! line on stderr from rank 0, exit code 1 on every rank.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use tresca_feti::comm::{Comm, MpiComm, SerialComm};
use tresca_feti::pipeline;

#[derive(Parser)]
#[command(
    name = "tresca-feti",
    version,
    about = "TFETI solver for 3D linear-elastic contact with friction (Tresca, orthotropic, Coulomb)",
    after_help = "A first run:\n  tresca-feti check run/tutorial.toml              validate a scene, print what it builds\n  mpirun -n 2 tresca-feti solve run/tutorial.toml  solve it on 2 MPI ranks\nResults: out/<scene name>.h5 (HDF5), .xdmf (open it in ParaView), .json (the report).\nErrors in a scene or mesh: one line naming the key or file, exit code 1; docs/troubleshooting.md says what to do.\nDocumentation: README.md; docs/tutorial.md, docs/scene-reference.md (every scene key),\ndocs/method.md, docs/validation.md, docs/performance.md."
)]
#[command(arg_required_else_help = true)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

/// The scene of a study (`--scene`, the seed by default) and its overrides.
#[derive(Args)]
struct StudyScene {
    /// The scene (TOML; a study sets its `mesh.n` per row where it sweeps N).
    #[arg(long, default_value = "run/seed.toml")]
    scene: PathBuf,
    /// Override a scene value, e.g. `--set mesh.n=16` or `--set solver.eps=1e-8`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

/// A scene file given as the argument, and its overrides.
#[derive(Args)]
struct SceneFile {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Override a scene value, e.g. `--set mesh.n=16` or `--set solver.eps=1e-8`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

/// The memory a run may use on this host.
#[derive(Args)]
struct MaxMemory {
    /// Memory the run may use on this host (all its ranks there together), e.g. `8G`,
    /// `500M` or bytes, in place of MemAvailable (/proc/meminfo); also TRESCA_FETI_MAX_MEMORY.
    #[arg(long = "max-memory", value_name = "SIZE", value_parser = pipeline::memory::parse_size)]
    max_memory: Option<u64>,
}

impl MaxMemory {
    /// Sets the limit the memory checks read.
    fn apply(&self) {
        if let Some(b) = self.max_memory {
            pipeline::memory::set_limit(b);
        }
    }
}

/// A finite value above 0 (tolerances, factors, times, bandwidths).
/// How `bench-tfeti` starts each case: the launcher with its own arguments, the command that
/// runs the solver, and the time a case may take.
#[derive(clap::Args, Debug)]
struct Launch {
    /// The launcher with its own arguments, split shell-like, e.g. "srun --mpi=pmix" (instead of --mpirun).
    #[arg(long, allow_hyphen_values = true, conflicts_with = "mpirun")]
    launcher: Option<String>,
    /// The command that runs the solver, split shell-like, e.g. "ch-run img -- tresca-feti"
    /// (default: this executable); each case runs `LAUNCHER -n P MPIRUN_ARGS… EXEC… solve …`.
    #[arg(long, allow_hyphen_values = true)]
    exec: Option<String>,
    /// Seconds a case may run before its launcher and everything it started are stopped.
    #[arg(long, value_parser = positive, default_value_t = 86400.0)]
    case_timeout: f64,
}

fn positive(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(format!("must be finite and > 0, got {v}"))
    }
}

/// A mesh size N: at least 2 nodes per edge.
fn mesh_size(s: &str) -> Result<usize, String> {
    let n: usize = s.parse().map_err(|e| format!("{e}"))?;
    if n >= 2 {
        Ok(n)
    } else {
        Err(format!("every N must be at least 2, got {n}"))
    }
}

/// A count of at least 1 (ranks, repeats).
fn at_least_one(s: &str) -> Result<usize, String> {
    let n: usize = s.parse().map_err(|e| format!("{e}"))?;
    if n >= 1 {
        Ok(n)
    } else {
        Err("must be at least 1".into())
    }
}

#[derive(Subcommand)]
enum Cmd {
    /// Time this machine's kernels and cache the rates that price the plan.
    ///
    /// A self-test of about ten seconds on one core: assembly and ordering, the numeric
    /// factorization, the solves, the dense solves of the explicit products and the dual rows'
    /// work, timed on a clamped box. Prints the kernels' times against those of the development
    /// machine and the rates they give, and writes them with this CPU's model to
    /// `$TRESCA_FETI_CACHE/rates.json` (default `$XDG_CACHE_HOME/tresca-feti` or
    /// `~/.cache/tresca-feti`; `TRESCA_FETI_CACHE=off` writes nothing). `solve` and `check` then
    /// price the plan with them on hosts with the same CPU model. Run it once per node type.
    Calibrate,
    /// Solve a scene and write its results: HDF5 + XDMF (ParaView) + JSON report.
    ///
    /// Run it under `mpirun -n P` to spread the bodies or subdomains over P ranks. Prints each phase as it starts and one line per Newton iteration,
    /// then a summary. The results go to `output.path` of the scene (default
    /// `out/<scene name>.h5`, beside it `.xdmf` and `.json`), or `--out`; a load path writes
    /// every step, which ParaView plays as an animation. Scene keys: docs/scene-reference.md.
    Solve {
        #[command(flatten)]
        scene: SceneFile,
        /// HDF5 output path (the .xdmf and .json go beside it).
        #[arg(long)]
        out: Option<PathBuf>,
        /// No live progress (phases as they start, one line per outer iteration): the summary only.
        #[arg(long, short)]
        quiet: bool,
        /// Also write the solved Coulomb problem in the FCLIB global format (HDF5) to this path
        /// (the scene key `output.export_fclib`; monolithic dual, isotropic Coulomb).
        #[arg(long = "export-fclib", value_name = "PATH")]
        export_fclib: Option<PathBuf>,
        /// Write a checkpoint after each completed load step (`output.checkpoint`):
        /// `<name>.checkpoint.h5` beside the result.
        #[arg(long)]
        checkpoint: bool,
        /// Continue a load path from this checkpoint (written by `--checkpoint`): the steps after
        /// its last one, with the same result set an uninterrupted run writes.
        #[arg(long, value_name = "CHECKPOINT")]
        resume: Option<PathBuf>,
        #[command(flatten)]
        memory: MaxMemory,
    },
    /// The paper's Table 1, reproduced on the seed scene.
    ///
    /// iter/nA of the dual solvers for growing N, with
    /// the paper's figures beside ours, wall times, KKT residuals and the error in u; CSV too.
    Table1 {
        #[command(flatten)]
        scene: StudyScene,
        /// Mesh sizes N (nodes per edge of each block).
        #[arg(long, value_parser = mesh_size, value_delimiter = ',', default_value = "16,21,26,31,36,41")]
        sizes: Vec<usize>,
        /// Stopping tolerance ε (relative: ‖r̃_ρ‖ ≤ ε‖b‖); the paper's counts hold at about 2e-4.
        #[arg(long, value_parser = positive, default_value_t = 2e-4)]
        eps: f64,
        /// Columns: solver[:paper], solvers gimssn, imssn, mssn, ssn-bicgstab, mpgp, tssn;
        /// `:paper` takes the paper's settings.
        #[arg(long, value_delimiter = ',', value_parser = tresca_feti::studies::table1::Column::parse,
              default_value = "imssn:paper,gimssn,ssn-bicgstab")]
        solvers: Vec<tresca_feti::studies::table1::Column>,
        /// CSV output (one line per N and solver).
        #[arg(long, default_value = "out/table1.csv")]
        csv: PathBuf,
        /// Skip the reference solve and the error in u.
        #[arg(long)]
        no_error: bool,
    },
    /// TFETI benchmark and scaling study (runs mpirun itself).
    ///
    /// For each N, S (subdomains per body; 0 = monolithic)
    /// and rank count P one `mpirun -n P tresca-feti solve`, tabulating nA, iterations, time per
    /// phase, peak memory and the time of one A-product against its memory-bound floor. Run it
    /// without mpirun.
    BenchTfeti {
        #[command(flatten)]
        scene: StudyScene,
        #[arg(long, value_parser = mesh_size, value_delimiter = ',', default_value = "16,26,41")]
        sizes: Vec<usize>,
        /// Subdomains per body (0: the monolithic dual).
        #[arg(long, value_delimiter = ',', default_value = "0,1,4,8,16,32")]
        subdomains: Vec<usize>,
        /// oblique (P̃) and/or orthogonal (SMALSE-M).
        #[arg(long, value_delimiter = ',', default_value = "oblique")]
        projectors: Vec<String>,
        /// Rank counts: every case runs on each (e.g. 1,2,4,8,16).
        #[arg(long, value_parser = at_least_one, value_delimiter = ',', default_value = "2")]
        ranks: Vec<usize>,
        /// Weak scaling: SIZES and SUBDOMAINS are those of 1 rank; P ranks solve
        /// N = round(N·P^{1/3}) with S·P subdomains per body (constant work per rank).
        #[arg(long)]
        weak: bool,
        /// The launcher, called as `MPIRUN -n P MPIRUN_ARGS… tresca-feti solve …` (`srun` on Slurm).
        #[arg(long, default_value = "mpirun")]
        mpirun: String,
        /// Extra launcher arguments, split at whitespace, e.g. "--oversubscribe" or "--bind-to core".
        #[arg(long, allow_hyphen_values = true, default_value = "")]
        mpirun_args: String,
        #[command(flatten)]
        launch: Launch,
        /// Runs of each case; the row is the fastest (least total time), against other load.
        #[arg(long, value_parser = at_least_one, default_value_t = 1)]
        repeat: usize,
        #[arg(long, value_parser = positive, default_value_t = 1e-6)]
        eps: f64,
        /// Memory bandwidth (GB/s) for the A-product floor (about 15 on the 2-core development machine).
        #[arg(long, value_parser = positive, default_value_t = 15.0)]
        bandwidth: f64,
        #[arg(long, default_value = "out/bench_tfeti.csv")]
        csv: PathBuf,
    },
    /// Run time against error of every solver and Clarabel (the evidence).
    ///
    /// Every solver (and Clarabel on the primal SOCP) at every ε of a
    /// sweep, on the seed scene for each N: time, A-products, the error in u and λ against a
    /// tight reference, KKT residuals; a summary of the time to each target error; CSV. One rank,
    /// one thread (run it without mpirun); plots: `run/work-precision-plot CSV DIR`.
    WorkPrecision {
        #[command(flatten)]
        scene: StudyScene,
        #[arg(long, value_parser = mesh_size, value_delimiter = ',', default_value = "8,16,24")]
        sizes: Vec<usize>,
        /// Duals the dual solvers run on: 0 the monolithic dual, S ≥ 1 TFETI with S subdomains
        /// per body (oblique projector); e.g. 0,1,4,8.
        #[arg(long, value_delimiter = ',', default_value = "0")]
        subdomains: Vec<usize>,
        /// Tolerances ε (the dual solvers' ‖r̃_ρ‖ ≤ ε‖b‖; Clarabel's gap and feasibility tolerances).
        #[arg(long, value_parser = positive, value_delimiter = ',', default_value = "1e-2,1e-3,1e-4,1e-5,1e-6,1e-7,1e-8,1e-9,1e-10")]
        eps: Vec<f64>,
        /// Clarabel's tolerances (its time hardly depends on ε; each solve is long).
        #[arg(long, value_parser = positive, value_delimiter = ',', default_value = "1e-4,1e-6,1e-8,1e-10")]
        clarabel_eps: Vec<f64>,
        /// Rows: gimssn, imssn, mssn, ssn-bicgstab, mpgp (optionally `:paper`), tssn (TFETI also
        /// `tssn:lumped`, `tssn:dirichlet`), clarabel.
        #[arg(long, value_delimiter = ',', value_parser = tresca_feti::studies::work_precision::Solver::parse,
              default_value = "gimssn,imssn,mssn,ssn-bicgstab,mpgp,tssn,clarabel")]
        solvers: Vec<tresca_feti::studies::work_precision::Solver>,
        /// ε of the reference solve (SSN-BiCGSTAB).
        #[arg(long, value_parser = positive, default_value_t = 1e-12)]
        reference_eps: f64,
        /// Errors in u the summary gives the time to.
        #[arg(long, value_parser = positive, value_delimiter = ',', default_value = "1e-4,1e-6,1e-8")]
        targets: Vec<f64>,
        /// A dual solve slower than this (seconds) ends its solver's sweep at that N.
        #[arg(long, value_parser = positive, default_value_t = 120.0)]
        max_seconds: f64,
        /// A-products a dual solve may use.
        #[arg(long, default_value_t = 50_000)]
        max_products: usize,
        #[arg(long, default_value = "out/work_precision.csv")]
        csv: PathBuf,
    },
    /// The numerical-stability suite (run/stress/*.toml).
    ///
    /// Solves every scene of a folder (run/stress/*.toml) and
    /// print a table (iterations, nA, time, residuals, KKT, status). Exit code 1 if a run
    /// returns a result that fails its checks (non-finite, above ε, KKT above KKT_FACTOR·ε);
    /// a run that stops with a stated reason is listed as stopped. `stress` is an alias.
    #[command(alias = "stress")]
    Stability {
        #[arg(long, default_value = "run/stress")]
        dir: PathBuf,
        /// Override a value in every scene, e.g. `--set solver.method="gimssn"`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Folder for the results (<scene>.h5/.xdmf/.json) and stability.csv.
        #[arg(long, default_value = "out/stability")]
        out: PathBuf,
        #[arg(long, value_parser = positive, default_value_t = 100.0)]
        kkt_factor: f64,
    },
    /// The coarse problem's cost as the subdomain count grows.
    ///
    /// For each S, C = G_E G_Eᵀ of the
    /// scene's decomposition (clusters too), one solve with its factor (what every rank pays
    /// with `coarse_solve = "factor"`) against one rank's explicit inverse rows (`decomposition.coarse_solve =
    /// "explicit"`) for each pieces-per-rank; one process. The cost model's inputs.
    BenchCoarse {
        #[command(flatten)]
        scene: StudyScene,
        /// Subdomains per body, one row each.
        #[arg(long, value_delimiter = ',', default_value = "64,256,1024,2048")]
        subdomains: Vec<usize>,
        /// Pieces (subdomains or clusters) one rank holds, one column group each.
        #[arg(long, value_delimiter = ',', default_value = "1,16")]
        pieces: Vec<usize>,
        /// Solves timed; the fastest counts.
        #[arg(long, value_parser = at_least_one, default_value_t = 20)]
        repeat: usize,
    },
    /// What is in a mesh file: the names a scene's `mesh = { file, volume }` and `body.FACE` take.
    ///
    /// Prints the file's format (from its extension, as the scene's `mesh` key takes it, or
    /// --format), its nodes and cells by kind, every volume the `volume` key accepts (Gmsh
    /// physical volumes, Abaqus element sets and instances, MED groups of volume cells, Exodus
    /// element blocks) with its cells and the faces a body made of it gets, and a starter scene
    /// with one [[body]] per volume. Needs no MPI: run it as one process.
    Mesh {
        /// The mesh file: Gmsh .msh, Abaqus .inp, MED .med or Exodus II .exo/.e/.ex2.
        file: PathBuf,
        /// The file's format, where its extension does not name it.
        #[arg(long, value_name = "gmsh|abaqus|med|exodus", value_parser = pipeline::inspect::parse_format)]
        format: Option<tresca_feti::scene::MeshFormat>,
    },
    /// Validate a scene without solving it.
    ///
    /// Prints the resolved scene (every default filled in), the mesh, faces, DOF counts, applied load, contact pairs, the decomposition chosen by
    /// cost and the memory estimate.
    Check {
        #[command(flatten)]
        scene: SceneFile,
        /// Price the automatic decomposition for a run on this many ranks (default: the ranks
        /// `check` runs on).
        #[arg(long, value_parser = at_least_one)]
        ranks: Option<usize>,
        /// Print the scaling forecast of the chosen decomposition on 1 to 4096 ranks, RANKS/HOSTS
        /// of them on each host (the network model: --network).
        #[arg(long, value_parser = at_least_one)]
        hosts: Option<usize>,
        /// The network model of the forecast (TOML: latency and bandwidth between hosts and inside one).
        #[arg(long, default_value = "run/network.toml", requires = "hosts")]
        network: PathBuf,
        #[command(flatten)]
        memory: MaxMemory,
    },
}

fn table1<C: Comm>(comm: &C, args: &tresca_feti::studies::table1::Args) -> tresca_feti::Result<()> {
    use tresca_feti::studies::table1;
    table1::check_columns(&args.columns)?;
    // a CSV that cannot be written fails now, not after the whole run
    let csv_dir = comm.agree(match args.csv.as_ref().and_then(|p| p.parent()).filter(|d| !d.as_os_str().is_empty()) {
        Some(d) if comm.is_root() => std::fs::create_dir_all(d).map_err(|e| tresca_feti::Error::io(d.display().to_string(), e)),
        _ => Ok(()),
    });
    csv_dir?;
    if comm.is_root() {
        println!("{}", table1::header(args, comm.size()));
    }
    // each solve on stderr as it finishes (progress), the table's rows on stdout
    let rows = table1::run(
        comm,
        args,
        |cell| {
            if comm.is_root() {
                eprintln!("  {}", table1::format_cell(cell));
            }
        },
        |row| {
            if comm.is_root() {
                println!("{}", table1::format_row(row));
            }
        },
    )?;
    if let (true, Some(path)) = (comm.is_root(), &args.csv) {
        table1::write_csv(path, args, &rows)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn stability<C: Comm>(comm: &C, args: &tresca_feti::studies::stability::Args) -> tresca_feti::Result<()> {
    use tresca_feti::studies::stability::{self, Outcome};
    let root = comm.is_root();
    if root {
        println!("stability suite: {} ({} rank(s)); converged = ε met and KKT ≤ {}·ε", args.dir.display(), comm.size(), args.kkt_factor);
        println!("{}", stability::header());
    }
    let rows = stability::run(comm, args, |r| {
        if root {
            println!("{}", stability::format_row(r));
        }
    })?;
    let count = |f: fn(&Outcome) -> bool| rows.iter().filter(|r| f(&r.outcome)).count();
    let (ok, stopped, wrong) = (count(|o| *o == Outcome::Converged), count(|o| matches!(o, Outcome::Stopped(_))), count(|o| matches!(o, Outcome::Wrong(_))));
    if root {
        let csv = args.out.join("stability.csv");
        stability::write_csv(&csv, &rows)?;
        println!("{} scenes: {ok} converged, {stopped} stopped with a reason, {wrong} wrong; wrote {}", rows.len(), csv.display());
    }
    if wrong > 0 {
        return Err(tresca_feti::Error::numerical("the stability suite", format!("{wrong} scene(s) returned a result that fails its checks (see the table)")));
    }
    Ok(())
}

fn work_precision<C: Comm>(comm: &C, args: &tresca_feti::studies::work_precision::Args) -> tresca_feti::Result<()> {
    use tresca_feti::studies::work_precision as wp;
    use tresca_feti::Error;
    if let Some(d) = args.csv.as_ref().and_then(|p| p.parent()).filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).map_err(|e| Error::io(d.display().to_string(), e))?;
    }
    // one thread: the dual solvers and Clarabel on equal terms
    faer::set_global_parallelism(faer::Par::Seq);
    let root = comm.is_root();
    let (problems, points) = wp::run(
        comm,
        args,
        |p| {
            if root {
                let setup = if p.subdomains == 0 { "assembly + factorization" } else { "TFETI set-up" };
                println!(
                    "N = {}, {}: n = {}, m = {}, {setup} {:.2} s, reference {}/{} nA",
                    p.n,
                    wp::dual_label(p.subdomains),
                    p.dofs,
                    p.pairs,
                    p.factorize_s,
                    p.reference.iterations,
                    p.reference.n_a
                );
            }
        },
        |pt| {
            if root {
                println!("{}", wp::format_point(pt));
            }
        },
    )?;
    if root {
        println!("\nTime to an error in u (max-norm, relative to the reference), fastest ε of the sweep; one rank, one thread:");
        print!("{}", wp::summary(&problems, &points, &args.solvers, &args.targets));
        if let Some(path) = &args.csv {
            wp::write_csv(path, &problems, &points)?;
            println!("wrote {}", path.display());
        }
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn bench_tfeti(
    scene: PathBuf,
    sets: Vec<String>,
    sizes: Vec<usize>,
    subdomains: Vec<usize>,
    projectors: Vec<String>,
    ranks: Vec<usize>,
    weak: bool,
    mpirun: String,
    mpirun_args: String,
    launch: Launch,
    repeat: usize,
    eps: f64,
    bandwidth: f64,
    csv: PathBuf,
) -> tresca_feti::Result<()> {
    use tresca_feti::scene::Projector;
    use tresca_feti::Error;
    let projectors = projectors
        .iter()
        .map(|p| match p.as_str() {
            "oblique" => Ok(Projector::Oblique),
            "orthogonal" => Ok(Projector::Orthogonal),
            other => Err(Error::scene("--projectors", format!("unknown projector \"{other}\"; known: oblique, orthogonal"))),
        })
        .collect::<tresca_feti::Result<Vec<_>>>()?;
    if ranks.is_empty() {
        return Err(Error::scene("--ranks", "give at least one rank count"));
    }
    if sizes.is_empty() || subdomains.is_empty() {
        return Err(Error::scene(if sizes.is_empty() { "--sizes" } else { "--subdomains" }, "give at least one value"));
    }
    // a command given as one string, split as a shell would (quotes kept together)
    let words = |key: &str, text: &str| match shell_words::split(text) {
        Ok(w) if !w.is_empty() => Ok(w),
        Ok(_) => Err(Error::scene(key, "must name a program")),
        Err(e) => Err(Error::scene(key, format!("\"{text}\": {e}"))),
    };
    let (launcher_key, launcher) = match &launch.launcher {
        Some(l) => ("--launcher", words("--launcher", l)?),
        None if mpirun.trim().is_empty() => return Err(Error::scene("--mpirun", "must name a launcher (mpirun, srun or a path)")),
        None => ("--mpirun", vec![mpirun]),
    };
    let exec = match &launch.exec {
        Some(e) => words("--exec", e)?,
        None => vec![std::env::current_exe().map_err(|e| Error::io("current executable", e))?.display().to_string()],
    };
    // a CSV that cannot be written fails now, not after the whole run
    if let Some(d) = csv.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).map_err(|e| Error::io(d.display().to_string(), e))?;
    }
    let mpirun_args = mpirun_args.split_whitespace().map(String::from).collect();
    let list = ranks.iter().map(|p| p.to_string()).collect::<Vec<_>>().join(",");
    let args = tresca_feti::studies::bench::Args {
        exec,
        scene,
        sets,
        sizes,
        subdomains,
        projectors,
        ranks,
        weak,
        launcher,
        launcher_key: launcher_key.into(),
        mpirun_args,
        repeat,
        eps,
        bandwidth,
        csv: Some(csv.clone()),
        timeout: launch.case_timeout,
    };
    let mode = if weak { "weak scaling (N·P^{1/3}, S·P), " } else { "" };
    let best = if repeat > 1 { format!(", best of {repeat} runs") } else { String::new() };
    println!("TFETI benchmark: {mode}ranks {list} ({}){best}, ε = {eps:e}, floor = 2·8·Σnnz(L)/{bandwidth} GB/s", args.launcher.join(" "));
    println!("{}", tresca_feti::studies::bench::table_header());
    tresca_feti::studies::bench::run(&args, |r| println!("{}", r.table()))?;
    println!("wrote {}", csv.display());
    Ok(())
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // usage errors as clap formats them (the help for a missing command), printed by the
            // first rank only: MPI has not started, the launcher's environment names the rank
            if first_rank(|v| std::env::var(v).ok()) {
                let _ = e.print();
            }
            return ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2));
        }
    };
    if let Cmd::BenchTfeti {
        scene: StudyScene { scene, set },
        sizes,
        subdomains,
        projectors,
        ranks,
        weak,
        mpirun,
        mpirun_args,
        launch,
        repeat,
        eps,
        bandwidth,
        csv,
    } = cli.cmd
    {
        // a driver of mpirun runs, not an MPI program itself
        return match bench_tfeti(scene, set, sizes, subdomains, projectors, ranks, weak, mpirun, mpirun_args, launch, repeat, eps, bandwidth, csv) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("{}", e.line());
                ExitCode::FAILURE
            }
        };
    }
    // one process not started by an MPI launcher runs without MPI: OpenMPI's singleton start
    // (forking orted) alone costs about 0.3 s
    if launched_by_mpi() {
        if let Some((key, value)) = single_host_pml(|v| std::env::var(v).ok()) {
            // before MPI_Init, which reads it; no other thread runs yet
            std::env::set_var(key, value);
        }
        let Some(universe) = mpi::initialize() else {
            eprintln!("error: MPI could not be initialized");
            return ExitCode::FAILURE;
        };
        run(&MpiComm::new(universe.world()), cli.cmd)
    } else {
        run(&SerialComm, cli.cmd)
    }
}

/// Whether this process was started by an MPI launcher — mpirun/mpiexec of Open MPI or MPICH,
/// srun (PMI/PMIx, or a step of several tasks), Cray's aprun — by their environment variables,
/// or `TRESCA_FETI_MPI=1` asks for MPI anyway.
fn launched_by_mpi() -> bool {
    let set = |v: &str| std::env::var_os(v).is_some();
    let several_tasks = std::env::var("SLURM_NTASKS").ok().and_then(|n| n.parse::<usize>().ok()).is_some_and(|n| n > 1) && set("SLURM_PROCID");
    std::env::var("TRESCA_FETI_MPI").is_ok_and(|v| v == "1")
        || several_tasks
        || ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMI_RANK", "PMIX_RANK", "MPI_LOCALNRANKS", "ALPS_APP_PE"].iter().any(|v| set(v))
}

/// Whether this process is the first of its launch (or not launched by MPI at all), from the
/// rank a launcher puts in the environment before MPI starts: Open MPI, MPICH/PMI, PMIx, Slurm.
fn first_rank(var: impl Fn(&str) -> Option<String>) -> bool {
    ["OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK", "SLURM_PROCID"]
        .iter()
        .find_map(|v| var(v))
        .and_then(|r| r.trim().parse::<u64>().ok())
        .is_none_or(|r| r == 0)
}

/// Open MPI's point-to-point layer for a run whose ranks all share one host, unless the user
/// chose one (`OMPI_MCA_pml`): `ob1` (shared memory through the `vader` transport). Open MPI
/// otherwise tries UCX first, whose probe of the network devices in `MPI_Init` cost about 0.2 s
/// of every run on 2 ranks (docs/performance.md, "Start-up"). Every rank sees the same sizes,
/// so all choose alike; across hosts nothing changes.
fn single_host_pml(var: impl Fn(&str) -> Option<String>) -> Option<(&'static str, &'static str)> {
    let size = |v: &str| var(v).and_then(|s| s.parse::<usize>().ok());
    let one_host = matches!((size("OMPI_COMM_WORLD_SIZE"), size("OMPI_COMM_WORLD_LOCAL_SIZE")), (Some(n), Some(l)) if n == l);
    (one_host && var("OMPI_MCA_pml").is_none()).then_some(("OMPI_MCA_pml", "ob1"))
}

/// Runs one command on `comm`; rank 0 prints its error line.
fn run<C: Comm>(comm: &C, cmd: Cmd) -> ExitCode {
    // SIGINT/SIGTERM: the temporary result files are removed, one line says so (rank 0)
    if let Err(e) = tresca_feti::output::tmpfiles::remove_on_signal(comm.is_root()) {
        if comm.is_root() {
            eprintln!("error: cannot watch for signals: {e}");
        }
        return ExitCode::FAILURE;
    }
    if comm.size() > 1 {
        // one rank per core: faer must not start threads of its own
        faer::set_global_parallelism(faer::Par::Seq);
    }
    if matches!(cmd, Cmd::Solve { .. } | Cmd::Check { .. }) {
        // the plan's rates: rank 0 reads the cache, every rank takes its choice
        pipeline::rates::install(comm);
    }
    let result = match cmd {
        Cmd::Calibrate => calibrate(comm),
        Cmd::Mesh { file, format } => {
            // rank 0 reads and prints; every rank exits with its error
            let text = if comm.is_root() { pipeline::inspect::report(&file, format) } else { Ok(String::new()) };
            comm.agree(text).map(|text| {
                if comm.is_root() {
                    print!("{text}");
                }
            })
        }
        Cmd::Solve { scene: SceneFile { scene, mut set }, out, quiet, export_fclib, checkpoint, resume, memory } => {
            memory.apply();
            tresca_feti::output::tmpfiles::note_resume_command(resume_words(&scene, &set, out.as_deref(), export_fclib.as_deref()));
            if let Some(p) = export_fclib {
                set.push(format!("output.export_fclib={}", toml::Value::String(p.display().to_string())));
            }
            if checkpoint {
                set.push("output.checkpoint=true".into());
            }
            pipeline::run_solve_from(comm, &scene, &set, out, quiet, resume.as_deref())
        }
        .map(|s| {
            if comm.is_root() {
                print_summary(&s);
            }
        }),
        Cmd::Table1 { scene: StudyScene { scene, set }, sizes, eps, solvers, csv, no_error } => {
            let args = tresca_feti::studies::table1::Args { scene, sets: set, sizes, eps, columns: solvers, csv: Some(csv), error: !no_error };
            table1(comm, &args)
        }
        Cmd::WorkPrecision {
            scene: StudyScene { scene, set },
            sizes,
            subdomains,
            eps,
            clarabel_eps,
            solvers,
            reference_eps,
            targets,
            max_seconds,
            max_products,
            csv,
        } => {
            let args = tresca_feti::studies::work_precision::Args {
                scene,
                sets: set,
                sizes,
                subdomains,
                eps,
                clarabel_eps,
                solvers,
                csv: Some(csv),
                reference_eps,
                max_products,
                max_seconds,
                targets,
            };
            work_precision(comm, &args)
        }
        Cmd::Stability { dir, set, out, kkt_factor } => stability(comm, &tresca_feti::studies::stability::Args { dir, sets: set, out, kkt_factor }),
        Cmd::BenchTfeti { .. } => unreachable!("handled before MPI starts"),
        Cmd::BenchCoarse { scene: StudyScene { scene, set }, subdomains, pieces, repeat } => {
            let args = tresca_feti::studies::coarse_cost::Args { scene, sets: set, subdomains, pieces, repeat };
            bench_coarse(comm, &args)
        }
        Cmd::Check { scene: SceneFile { scene, set }, ranks, hosts, network, memory } => {
            memory.apply();
            let file = network.display().to_string();
            let text = match hosts.map(|h| pipeline::forecast::Network::read(&network).map(|n| (h, n))).transpose() {
                Ok(forecast) => pipeline::run_check(comm, &scene, &set, ranks.unwrap_or(comm.size()), forecast.as_ref().map(|(h, n)| (*h, n, file.as_str()))),
                Err(e) => Err(e),
            };
            // validation is cheap and deterministic: every rank does it, rank 0 prints
            comm.agree(text).map(|text| {
                if comm.is_root() {
                    println!("{text}");
                }
            })
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if comm.is_root() {
                eprintln!("{}", e.line());
            }
            ExitCode::FAILURE
        }
    }
}

/// `calibrate`: rank 0 times the kernels on one core and writes the cache.
fn calibrate<C: Comm>(comm: &C) -> tresca_feti::Result<()> {
    if !comm.is_root() {
        return Ok(());
    }
    faer::set_global_parallelism(faer::Par::Seq);
    let dir = pipeline::rates::cache_dir();
    println!("{}", pipeline::rates::calibrate(dir.as_deref())?);
    Ok(())
}

/// `bench-coarse`: one table row per subdomain count, printed as it is measured (rank 0 runs it).
fn bench_coarse<C: Comm>(comm: &C, args: &tresca_feti::studies::coarse_cost::Args) -> tresca_feti::Result<()> {
    if !comm.is_root() {
        return Ok(());
    }
    let mut head = "     S  pieces  coarse dim     nnz(C)     nnz(L)  build [s]  factor solve [ms]".to_string();
    for m in &args.pieces {
        head += &format!(" | {m:>3}/rank: rows [MB] setup [s] product [ms]");
    }
    println!("{head}");
    tresca_feti::studies::coarse_cost::run(args, |r| {
        let mut line =
            format!("{:>6} {:>7} {:>11} {:>10} {:>10} {:>10.3} {:>18.3}", r.subdomains, r.pieces, r.dim, r.nnz_c, r.nnz_l, r.build_s, 1e3 * r.factor_solve_s);
        for &(setup, product, bytes) in &r.rows {
            line += &format!(" | {:>19.2} {:>9.3} {:>12.4}", bytes as f64 / 1e6, setup, 1e3 * product);
        }
        println!("{line}");
    })?;
    Ok(())
}

/// The words of `tresca-feti solve` that resume this run from a checkpoint (before `--resume`):
/// the scene, every `--set` as given, `--out`, `--export-fclib` and `--checkpoint` (so the
/// resumed run goes on writing them).
fn resume_words(scene: &std::path::Path, set: &[String], out: Option<&std::path::Path>, fclib: Option<&std::path::Path>) -> Vec<String> {
    let mut w = vec!["tresca-feti".to_string(), "solve".into(), scene.display().to_string()];
    for s in set {
        w.extend(["--set".into(), s.clone()]);
    }
    if let Some(o) = out {
        w.extend(["--out".into(), o.display().to_string()]);
    }
    if let Some(f) = fclib {
        w.extend(["--export-fclib".into(), f.display().to_string()]);
    }
    w.push("--checkpoint".into());
    w
}

fn print_summary(s: &pipeline::Summary) {
    let r = &s.report;
    println!("tresca-feti {} — {} ({}), {} rank(s)", env!("CARGO_PKG_VERSION"), r.title, r.scene, r.ranks);
    println!("problem: {}", r.problem);
    let m = &r.mesh;
    let copies = m.subdomain_dofs.map_or(String::new(), |s| format!("; {s} in the subdomains, interface nodes once per copy"));
    println!("mesh: {} nodes, {}, n = {} DOFs ({} free{copies})", m.nodes, m.cells, m.dofs, m.free_dofs);
    if let Some(tf) = &r.tfeti {
        let nnz_l: f64 = tf.subdomains.iter().map(|x| x.piece.nnz_l as f64).sum();
        let mul = &tf.multipliers;
        println!(
            "TFETI: {} subdomains {:?}{}, multipliers {} contact + {} gluing + {} Dirichlet{} ({} held DOFs eliminated), coarse {} × {}{}, Σnnz(L) {nnz_l:.3e}, gluing jump {:.1e}, ‖Gλ−e‖/‖e‖ {:.1e}, projector {}",
            tf.subdomains.len(),
            tf.subdomains_per_body,
            if tf.corner_rows > 0 { format!(" in {} clusters (H-TFETI, {} corner rows)", tf.clusters, tf.corner_rows) } else { String::new() },
            mul.contact,
            mul.gluing,
            mul.dirichlet,
            if mul.tie > 0 { format!(" + {} tie", mul.tie) } else { String::new() },
            tf.eliminated_dofs,
            tf.coarse_dim,
            tf.coarse_dim,
            if tf.coarse_explicit_bytes_max_rank > 0 { format!(" (explicit inverse rows, {:.2} MB on a rank)", tf.coarse_explicit_bytes_max_rank as f64 / 1e6) } else { String::new() },
            tf.gluing_jump,
            tf.feasibility,
            format!("{:?}", tf.projector).to_lowercase()
        );
    } else {
        for b in &r.bodies {
            println!("  {:<10} {:>8} free DOFs  nnz(L) {:>11}  ‖Ku−f‖/‖f‖ {:.1e}  rank {}", b.name, b.free_dofs, b.nnz_l, b.residual, b.rank);
        }
    }
    if let Some(steps) = &r.load_path {
        let (na, fp): (usize, usize) = steps.iter().fold((0, 0), |a, s| (a.0 + s.n_a, a.1 + s.fixed_point_iterations));
        let fp = if fp > 0 { format!(", {fp} Coulomb fixed-point steps") } else { String::new() };
        println!("load path: {} steps, nA = {na} in all (σ_max included){fp}; the last step:", steps.len());
    }
    if let Some(sv) = &r.solver {
        let i = &sv.info;
        // plain CG (TFETI without contact) solves A x = b: no KKT conditions beyond its residual
        let kkt = if r.contact.is_some() { format!(", KKT residual {:.1e}", sv.kkt_worst) } else { String::new() };
        let fp = if i.fixed_point_iterations > 0 { format!("{} Coulomb fixed-point steps, ", i.fixed_point_iterations) } else { String::new() };
        // announced only where a product was taken in single precision
        let mut mixed = r
            .single_precision_error
            .filter(|_| i.inexact_products > 0)
            .map_or(String::new(), |e| format!(", mixed precision ({} products in single precision, η = {e:.1e})", i.inexact_products));
        if let Some(n) = r.explicit_products {
            mixed += &format!(", explicit products (trailing blocks of {n} contact DOFs)");
        }
        println!(
            "solver {}: {fp}{} outer iterations, nA = {} (+{} for σ_max), {} inner iterations, ‖r̃_ρ‖/‖b‖ = {:.2e} (ε = {:.0e}){kkt}{mixed}",
            sv.method, i.iterations, i.n_a, i.n_a_power, i.inner_iterations, i.err, sv.eps
        );
        for t in &sv.eps_tightened {
            println!("{}", t.line());
        }
    }
    let unit = |which| tresca_feti::pipeline::report::UnitsReport::suffix(r.units.as_ref(), which);
    if let Some(c) = &r.contact {
        let f = c.total_force_on_slave;
        let inside = c.slip.saturating_sub(c.on_slip_bound);
        let bound = match (c.slip, inside) {
            (0, _) => String::new(),
            (_, 0) => "; every slipping pair on the slip bound".to_string(),
            _ => format!("; of the slipping pairs {} on the slip bound, {inside} sliding within ε inside it", c.on_slip_bound),
        };
        println!(
            "contact: {} pairs — {}{bound}; contact force on the slave body ({:.4e}, {:.4e}, {:.4e}){}",
            c.pairs,
            tresca_feti::pipeline::report::counts(c.open, c.contact, c.stick, c.slip),
            f[0],
            f[1],
            f[2],
            unit(1)
        );
        for note in &c.notes {
            println!("{note}");
        }
    }
    let res = &r.results;
    println!(
        "max |u| = {:.4e}{} (body {}), max von Mises = {:.4e}{}",
        res.max_displacement,
        unit(0),
        res.max_displacement_body.as_deref().unwrap_or("?"),
        res.max_von_mises,
        unit(2)
    );
    let phases: Vec<String> = r.timings.0.iter().map(|(k, v)| format!("{k} {v:.3}")).collect();
    println!("time [s]: {} | total {:.3}", phases.join(", "), r.timings.total());
    let files: Vec<String> = s.files.iter().map(|p| p.display().to_string()).collect();
    println!("wrote {}", files.join(", "));
    if let Some(n) = r.output_verified_values {
        println!("read back: {n} values on {} ranks match the fields in memory", r.ranks);
    }
}

#[cfg(test)]
mod tests {
    use super::{first_rank, single_host_pml};

    fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |v| pairs.iter().find(|(k, _)| *k == v).map(|(_, x)| x.to_string())
    }

    #[test]
    fn ob1_only_on_one_host_and_only_when_the_user_chose_no_pml() {
        assert_eq!(single_host_pml(env(&[("OMPI_COMM_WORLD_SIZE", "2"), ("OMPI_COMM_WORLD_LOCAL_SIZE", "2")])), Some(("OMPI_MCA_pml", "ob1")));
        // ranks on two hosts, the user's own choice, no Open MPI launcher: left alone
        assert_eq!(single_host_pml(env(&[("OMPI_COMM_WORLD_SIZE", "4"), ("OMPI_COMM_WORLD_LOCAL_SIZE", "2")])), None);
        assert_eq!(single_host_pml(env(&[("OMPI_COMM_WORLD_SIZE", "2"), ("OMPI_COMM_WORLD_LOCAL_SIZE", "2"), ("OMPI_MCA_pml", "ucx")])), None);
        assert_eq!(single_host_pml(env(&[("PMI_SIZE", "2")])), None);
    }

    #[test]
    fn the_first_rank_from_any_launcher() {
        assert!(first_rank(env(&[])));
        assert!(first_rank(env(&[("OMPI_COMM_WORLD_RANK", "0")])));
        assert!(!first_rank(env(&[("OMPI_COMM_WORLD_RANK", "1")])));
        assert!(!first_rank(env(&[("PMI_RANK", "3")])));
        assert!(!first_rank(env(&[("SLURM_PROCID", "1")])));
        assert!(first_rank(env(&[("PMIX_RANK", "0")])));
    }
}
