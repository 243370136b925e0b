//! `tresca-feti bench-coarse`: what one C⁻¹ solve costs as the pieces (subdomains, or H-TFETI
//! clusters) grow in number — C factorized and solved whole on every rank, against the explicit
//! inverse's rows of one rank's pieces (`decomposition.coarse_solve = "explicit"`) — on the
//! scene's own decomposition, one process. The inputs of the plan's cost model (`pipeline::plan`).

use std::time::Instant;

use crate::error::{Error, Result};
use crate::feti::cluster::Clustering;
use crate::feti::coarse::{Coarse, Kind};
use crate::feti::decomposition::decompose_each;
use crate::feti::distribution::Distribution;
use crate::feti::{constraints, eliminated, subdomain_loads};

/// What `bench-coarse` is asked to do.
#[derive(Clone, Debug)]
pub struct Args {
    /// The scene file.
    pub scene: std::path::PathBuf,
    /// `--set KEY=VALUE` overrides.
    pub sets: Vec<String>,
    /// Subdomains per body, one row each.
    pub subdomains: Vec<usize>,
    /// Pieces one rank holds (its explicit rows), one column group each.
    pub pieces: Vec<usize>,
    /// Solves timed (the fastest counts).
    pub repeat: usize,
}

/// One row: a decomposition's coarse problem and what a solve costs.
#[derive(Clone, Debug)]
pub struct Row {
    /// Subdomains of the decomposition.
    pub subdomains: usize,
    /// Pieces (clusters) of the decomposition.
    pub pieces: usize,
    /// Size of the coarse problem: the rows of G.
    pub dim: usize,
    /// Nonzeros of the lower triangle of C.
    pub nnz_c: usize,
    /// Nonzeros of C's Cholesky factor.
    pub nnz_l: usize,
    /// G, C and its factorization.
    pub build_s: f64,
    /// One solve with C's factor (the fastest of `repeat`), in seconds.
    pub factor_solve_s: f64,
    /// Per entry of `Args::pieces`: (setup s, one product s, bytes).
    pub rows: Vec<(f64, f64, usize)>,
}

/// Builds each decomposition's coarse problem as the pipeline does (hybrid Dirichlet and
/// clusters as the scene says) and times its solves.
pub fn run(args: &Args, mut each: impl FnMut(&Row)) -> Result<Vec<Row>> {
    let mut out = Vec::new();
    for &s in &args.subdomains {
        let mut sets = args.sets.clone();
        sets.push(format!("decomposition.subdomains={s}"));
        let ls = crate::scene::load(&args.scene, &sets)?;
        let model = crate::model::build(&ls)?;
        let dec = &ls.scene.decomposition;
        let parts: Vec<usize> = model.mesh.bodies.iter().map(|b| dec.parts(3 * b.nodes.len())).collect();
        let d = decompose_each(&model.mesh, &parts)?;
        let elim = eliminated(&model.mesh, &d, &model.constraints, dec.dirichlet);
        let sub_cons = constraints::build(&d, &model.constraints, model.pairs.as_ref(), &model.ties, dec.gluing, &elim);
        let clusters = Clustering::new(&model.mesh, &d, &sub_cons, dec.subdomains_per_cluster)?;
        let cons = clusters.outer(sub_cons);
        let loads = subdomain_loads(&d, &model.loads, &(0..d.subdomains.len()).collect::<Vec<_>>());
        let t = Instant::now();
        // one process holding every piece
        let comm = crate::comm::SerialComm;
        let dist = Distribution::new(&comm, &cons, &vec![0; clusters.len()]);
        let kernels: Vec<_> = clusters.kernels(&model.mesh, &d, &elim).into_iter().map(Some).collect();
        let coarse = Coarse::new(&dist, &kernels, &cons, &clusters.concat(&loads), Kind::Oblique, &|_| String::new())?;
        let build_s = t.elapsed().as_secs_f64();
        let mut row = Row {
            subdomains: d.subdomains.len(),
            pieces: clusters.len(),
            dim: coarse.dim(),
            nnz_c: coarse.nnz_c,
            nnz_l: 0,
            build_s,
            factor_solve_s: 0.0,
            rows: vec![],
        };
        for &m in &args.pieces {
            let c =
                coarse.inverse_costs(m, args.repeat).ok_or_else(|| Error::numerical("bench-coarse", "C is singular: every body needs Dirichlet conditions"))?;
            row.nnz_l = c.nnz_l;
            row.factor_solve_s = c.factor_solve_s;
            row.rows.push((c.rows_setup_s, c.rows_solve_s, c.rows_bytes));
        }
        each(&row);
        out.push(row);
    }
    Ok(out)
}
