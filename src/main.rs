//! `tresca-feti`: the command line. Parses arguments (clap) before MPI starts, initializes MPI,
//! runs the pipeline on every rank, and lets only rank 0 print. Errors: one line on stderr from
//! rank 0, exit code 1 on every rank.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use tresca_feti::comm::{Comm, MpiComm};
use tresca_feti::pipeline;

#[derive(Parser)]
#[command(name = "tresca-feti", version, about = "TFETI solver for 3D contact with Tresca friction")]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Solve a scene and write HDF5 + XDMF + JSON results.
    Solve {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Override a scene value, e.g. `--set mesh.n=16` or `--set solver.eps=1e-8`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// HDF5 output path (the .xdmf and .json go beside it).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Validate a scene and print the resolved scene, mesh sizes and DOF counts.
    Check {
        scene: PathBuf,
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let Some(universe) = mpi::initialize() else {
        eprintln!("error: MPI could not be initialized");
        return ExitCode::FAILURE;
    };
    let comm = MpiComm::new(universe.world());
    if comm.size() > 1 {
        // one rank per core: faer must not start threads of its own
        faer::set_global_parallelism(faer::Par::Seq);
    }
    let result = match cli.cmd {
        Cmd::Solve { scene, set, out } => pipeline::run_solve(&comm, &scene, &set, out).map(|s| {
            if comm.is_root() {
                print_summary(&s);
            }
        }),
        Cmd::Check { scene, set } => {
            // validation is cheap and deterministic: every rank does it, rank 0 prints
            let r = comm.agree(pipeline::run_check(&scene, &set));
            r.map(|text| {
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
                eprintln!("error: {e}");
            }
            ExitCode::FAILURE
        }
    }
}

fn print_summary(s: &pipeline::Summary) {
    let r = &s.report;
    println!("tresca-feti {} — {} ({}), {} rank(s)", env!("CARGO_PKG_VERSION"), r["title"].as_str().unwrap_or(""), r["scene"].as_str().unwrap_or(""), r["ranks"]);
    println!("problem: {}", r["problem"].as_str().unwrap_or(""));
    let m = &r["mesh"];
    println!("mesh: {} nodes, {} hexahedra, n = {} DOFs ({} free)", m["nodes"], m["elements"], m["dofs"], m["free_dofs"]);
    for b in r["bodies"].as_array().into_iter().flatten() {
        println!(
            "  {:<10} {:>8} free DOFs  nnz(L) {:>11}  ‖Ku−f‖/‖f‖ {:.1e}  rank {}",
            b["name"].as_str().unwrap_or(""),
            b["free_dofs"],
            b["nnz_L"],
            b["relative_residual"].as_f64().unwrap_or(f64::NAN),
            b["rank"]
        );
    }
    if let Some(sv) = r["solver"].as_object() {
        println!(
            "solver {}: {} outer iterations, nA = {} (+{} power iterations), {} inner iterations, ‖r̃_ρ‖/‖b‖ = {:.2e} (ε = {:.0e}), KKT residual {:.1e}",
            sv["method"].as_str().unwrap_or(""),
            sv["outer_iterations"],
            sv["nA"],
            sv["nA_power"],
            sv["inner_iterations"],
            sv["final_relative_reduced_gradient"].as_f64().unwrap_or(f64::NAN),
            sv["eps"].as_f64().unwrap_or(f64::NAN),
            sv["kkt_worst"].as_f64().unwrap_or(f64::NAN)
        );
        let c = &r["contact"];
        println!(
            "contact: {} pairs — {} open, {} stick, {} slip; {} on the slip bound; contact force on the slave body ({:.4e}, {:.4e}, {:.4e})",
            c["pairs"], c["open"], c["stick"], c["slip"], c["on_slip_bound"],
            c["total_force_on_slave"][0].as_f64().unwrap_or(0.0),
            c["total_force_on_slave"][1].as_f64().unwrap_or(0.0),
            c["total_force_on_slave"][2].as_f64().unwrap_or(0.0)
        );
    }
    let res = &r["results"];
    println!(
        "max |u| = {:.4e} m (body {}), max von Mises = {:.4e} MPa",
        res["max_displacement"].as_f64().unwrap_or(0.0),
        res["max_displacement_body"].as_str().unwrap_or("?"),
        res["max_von_mises"].as_f64().unwrap_or(0.0)
    );
    let phases: Vec<String> = r["timings"]
        .as_object()
        .into_iter()
        .flatten()
        .filter(|(k, _)| k.as_str() != "total")
        .map(|(k, v)| format!("{k} {:.3}", v.as_f64().unwrap_or(0.0)))
        .collect();
    println!("time [s]: {} | total {:.3}", phases.join(", "), r["timings"]["total"].as_f64().unwrap_or(0.0));
    let files: Vec<String> = s.files.iter().map(|p| p.display().to_string()).collect();
    println!("wrote {}", files.join(", "));
}
