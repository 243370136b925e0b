//! `tresca-feti bench-tfeti`: the TFETI benchmark of a scene over mesh sizes N and subdomain
//! counts S (S = 0: the monolithic dual) and projectors. Every case is a fresh
//! `mpirun -n P tresca-feti solve` (so that each has its own peak memory), whose JSON report
//! gives nA, outer iterations, the time of each phase, the peak memory and Σ nnz(L). The time
//! of one A-product, t_A = iterate / (nA + power iterations), is set against its memory-bound
//! floor 2·8·Σ nnz(L) / bandwidth (both triangular solves stream every factor once).

use std::path::PathBuf;
use std::process::Command;

use crate::error::{Error, Result};
use crate::scene::Projector;

/// What to run.
#[derive(Clone, Debug)]
pub struct Args {
    pub exe: PathBuf,
    pub scene: PathBuf,
    pub sets: Vec<String>,
    pub sizes: Vec<usize>,
    /// Subdomains per body; 0 = monolithic.
    pub subdomains: Vec<usize>,
    pub projectors: Vec<Projector>,
    pub ranks: usize,
    pub eps: f64,
    /// Memory bandwidth in GB/s for the floor.
    pub bandwidth: f64,
    pub csv: Option<PathBuf>,
}

/// One measured case.
#[derive(Clone, Debug, Default)]
pub struct Row {
    pub n: usize,
    pub s: usize,
    pub projector: String,
    pub dofs: u64,
    pub multipliers: u64,
    pub outer: u64,
    pub n_a: u64,
    pub n_a_power: u64,
    /// decompose, factorize (assembly included), coarse + dual setup, iterate, recover, total.
    pub phases: [f64; 6],
    pub peak_gb: f64,
    pub nnz_l: f64,
    pub t_a: f64,
    pub floor: f64,
    pub kkt: f64,
    pub max_u: f64,
}

pub const HEADER: &str = "N,S,projector,dofs,multipliers,outer,nA,nA_power,decompose_s,factorize_s,setup_s,iterate_s,recover_s,total_s,peak_GB,nnz_L,tA_ms,floor_ms,tA_over_floor,kkt,max_u";

impl Row {
    pub fn csv(&self) -> String {
        let p = &self.phases;
        format!(
            "{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{},{:.2},{:.2},{:.2},{:.2e},{:.6e}",
            self.n, self.s, self.projector, self.dofs, self.multipliers, self.outer, self.n_a, self.n_a_power,
            p[0], p[1], p[2], p[3], p[4], p[5], self.peak_gb, self.nnz_l, self.t_a * 1e3, self.floor * 1e3,
            self.t_a / self.floor, self.kkt, self.max_u
        )
    }

    pub fn table(&self) -> String {
        let p = &self.phases;
        let s = if self.s == 0 { "mono".to_string() } else { self.s.to_string() };
        format!(
            "| {:>3} | {:>4} | {:<10} | {:>7} | {:>4} | {:>5} | {:>6.2} | {:>7.2} | {:>6.2} | {:>7.2} | {:>6.2} | {:>7.2} | {:>5.2} | {:>7.1} | {:>7.1} | {:>4.2} |",
            self.n, s, self.projector, self.multipliers, self.outer, self.n_a, p[0], p[1], p[2], p[3], p[4], p[5],
            self.peak_gb, self.t_a * 1e3, self.floor * 1e3, self.t_a / self.floor
        )
    }
}

pub fn table_header() -> String {
    "|   N |    S | projector  | dual dim | iter |    nA | decomp | factor | setup | iterate | recover |   total | mem GB | tA ms | floor ms | tA/floor |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|".into()
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or(0.0)
}

/// Runs one case and reads its report.
fn case(a: &Args, n: usize, s: usize, projector: Projector, dir: &std::path::Path) -> Result<Row> {
    let name = format!("N{n}_S{s}_{projector:?}").to_lowercase();
    let out = dir.join(format!("{name}.h5"));
    let mut cmd = Command::new("mpirun");
    cmd.arg("-n").arg(a.ranks.to_string()).arg(&a.exe).arg("solve").arg(&a.scene);
    let mut sets = a.sets.clone();
    sets.push(format!("mesh.n={n}"));
    sets.push(format!("solver.eps={:e}", a.eps));
    sets.push("output.fields=[]".into());
    sets.push("output.xdmf=false".into());
    if s > 0 {
        sets.push(format!("decomposition.subdomains={s}"));
        sets.push("decomposition.tfeti=true".into());
        sets.push(format!("decomposition.projector=\"{}\"", if projector == Projector::Oblique { "oblique" } else { "orthogonal" }));
    }
    for x in &sets {
        cmd.arg("--set").arg(x);
    }
    cmd.arg("--out").arg(&out);
    let o = cmd.output().map_err(|e| Error::io("mpirun", e))?;
    if !o.status.success() {
        let err = String::from_utf8_lossy(&o.stderr);
        // our one-line error, not mpirun's banner after it
        let line = err.lines().find_map(|l| l.strip_prefix("error: ")).unwrap_or("failed without an error message");
        return Err(Error::numerical(format!("case {name}"), line.to_string()));
    }
    let json = out.with_extension("json");
    let text = std::fs::read_to_string(&json).map_err(|e| Error::io(json.display().to_string(), e))?;
    let r: serde_json::Value = serde_json::from_str(&text).map_err(|e| Error::Parse { file: json.display().to_string(), msg: e.to_string() })?;
    let t = &r["timings"];
    let sv = &r["solver"];
    let nnz_l = match r["tfeti"].as_object() {
        Some(tf) => tf["subdomains"].as_array().into_iter().flatten().map(|x| f(&x["nnz_l"])).sum(),
        None => r["bodies"].as_array().into_iter().flatten().map(|x| f(&x["nnz_L"])).sum(),
    };
    let mult = sv["dual_dim"].as_u64().unwrap_or(0);
    let (n_a, n_a_power) = (sv["nA"].as_u64().unwrap_or(0), sv["nA_power"].as_u64().unwrap_or(0));
    let phases = [
        f(&t["decompose"]),
        f(&t["assemble"]) + f(&t["factorize"]),
        f(&t["coarse"]) + f(&t["dual"]),
        f(&t["iterate"]),
        f(&t["recover"]),
        f(&t["total"]) - f(&t["output"]),
    ];
    let t_a = phases[3] / (n_a + n_a_power).max(1) as f64;
    Ok(Row {
        n,
        s,
        projector: if s == 0 { "-".into() } else { format!("{projector:?}").to_lowercase() },
        dofs: r["mesh"]["dofs"].as_u64().unwrap_or(0),
        multipliers: mult,
        outer: sv["outer_iterations"].as_u64().unwrap_or(0),
        n_a,
        n_a_power,
        phases,
        peak_gb: f(&r["memory"]["peak_rss_bytes_sum_over_ranks"]) / 1e9,
        nnz_l,
        t_a,
        floor: 2.0 * 8.0 * nnz_l / (a.bandwidth * 1e9),
        kkt: f(&sv["kkt_worst"]),
        max_u: f(&r["results"]["max_displacement"]),
    })
}

/// Runs every case (projectors only for S > 0), calling `each` after each.
pub fn run(a: &Args, mut each: impl FnMut(&Row)) -> Result<Vec<Row>> {
    let dir = std::env::temp_dir().join(format!("tresca-feti-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(dir.display().to_string(), e))?;
    let mut rows = Vec::new();
    for &n in &a.sizes {
        for &s in &a.subdomains {
            let projectors: Vec<Projector> = if s == 0 { vec![Projector::Oblique] } else { a.projectors.clone() };
            for p in projectors {
                let row = case(a, n, s, p, &dir)?;
                each(&row);
                rows.push(row);
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    if let Some(path) = &a.csv {
        let mut text = String::from(HEADER);
        text.push('\n');
        for r in &rows {
            text.push_str(&r.csv());
            text.push('\n');
        }
        crate::output::write_atomically(path, text.as_bytes())?;
    }
    Ok(rows)
}
