//! One pipeline of named, timed phases (scene → mesh → assemble → factorize → solve → stress →
//! gather → output), generic over the communicator. Bodies are distributed over the ranks
//! (body b on rank b mod P); each rank assembles and factorizes only its own bodies, rank 0
//! gathers the fields for the report, and all ranks write the HDF5 file together, each its own
//! rows (`output::hdf5::write_collective`). Every phase ends with [`Comm::agree`], so an error on
//! any rank stops all ranks with the same message.
//!
//! Two paths share the phases: the monolithic dual (one piece per body, Dirichlet eliminated,
//! the paper's setting) and TFETI ([`tfeti`]: METIS subdomains, gluing and Dirichlet
//! multipliers, coarse problem), chosen by the scene's `[decomposition]`.

pub mod tfeti;

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;

use crate::comm::Comm;
use crate::error::{Error, Result};
use crate::fem::assembly::{assemble_body, BodySystem, DofMap};
use crate::fem::element::hex8_center_stress;
use crate::fem::material::von_mises;
use crate::linalg::cholesky::{Cholesky, Ordering};
use crate::linalg::ordering::{expand_to_dofs, nested_dissection};
use crate::model::{self, Model};
use crate::output::{self, Center, Field, OutputData, Values};
use crate::dual::monolithic::MonolithicDual;
use crate::dual::DualOperator;
use crate::qp;
use crate::qp::lambda::Lambda;
use crate::recovery::{contact_fields, contact_state, ContactState, OPEN, SLIP, STICK};
use crate::scene::{LoadedScene, OrderingKind, SolverSettings};

/// Wall time of each phase, the maximum over the ranks.
#[derive(Clone, Debug, Default)]
pub struct Timings {
    pub phases: Vec<(String, f64)>,
}

impl Timings {
    /// Runs one phase on every rank, records its time (max over ranks) and makes its result
    /// collective.
    pub fn phase<C: Comm, T>(&mut self, comm: &C, name: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
        let t0 = Instant::now();
        let r = f().and_then(|v| injected_fault(comm, name).map_or(Ok(v), Err));
        let mut t = [t0.elapsed().as_secs_f64()];
        let r = comm.agree(r);
        comm.max_f64(&mut t);
        self.phases.push((name.to_string(), t[0]));
        r
    }

    pub fn total(&self) -> f64 {
        self.phases.iter().map(|p| p.1).sum()
    }

    pub fn to_json(&self) -> serde_json::Value {
        let mut m = serde_json::Map::new();
        for (k, v) in &self.phases {
            m.insert(k.clone(), json!(v));
        }
        m.insert("total".into(), json!(self.total()));
        serde_json::Value::Object(m)
    }
}

/// `TRESCA_FETI_FAULT=<phase>@<rank>` makes that phase fail on that rank after it ran (to
/// test that an error on one rank stops all of them; meant for rank-local phases such as
/// `factorize`).
fn injected_fault<C: Comm>(comm: &C, phase: &str) -> Option<Error> {
    let spec = std::env::var("TRESCA_FETI_FAULT").ok()?;
    let (p, r) = spec.split_once('@')?;
    (p == phase && r.parse::<usize>().ok() == Some(comm.rank()))
        .then(|| Error::numerical("injected fault", format!("phase {phase} on rank {}", comm.rank())))
}

/// Figures of one body's linear solve.
#[derive(Clone, Debug, Default)]
pub struct BodyStats {
    pub name: String,
    pub nodes: usize,
    pub elements: usize,
    pub free_dofs: usize,
    pub nnz_k: usize,
    pub nnz_l: usize,
    /// ‖K u − f‖ / ‖f‖ of the free DOFs.
    pub residual: f64,
    pub rank: usize,
}

/// The fields on rank 0 (empty on other ranks).
#[derive(Clone, Debug, Default)]
pub struct Solution {
    pub displacement: Vec<[f64; 3]>,
    pub von_mises: Vec<f64>,
    pub bodies: Vec<BodyStats>,
    /// Subdomains, interface and coarse figures when solved by TFETI.
    pub tfeti: Option<tfeti::TfetiInfo>,
    /// This rank's own rows of the fields, as it writes them to the file (every rank).
    pub local: LocalFields,
    /// Rank that computed each element (every rank).
    pub element_rank: Vec<usize>,
}

/// The rows of the distributed fields one rank holds: the nodes it writes (each node once over
/// all ranks) with their displacements, its elements with their von Mises stress.
#[derive(Clone, Debug, Default)]
pub struct LocalFields {
    pub nodes: Vec<usize>,
    pub displacement: Vec<[f64; 3]>,
    pub cells: Vec<usize>,
    pub von_mises: Vec<f64>,
}

/// What `solve` reports back to the command line.
#[derive(Clone, Debug)]
pub struct Summary {
    pub report: serde_json::Value,
    pub files: Vec<PathBuf>,
    /// The computed fields (on rank 0).
    pub solution: Solution,
}

/// Rank that owns body `b`.
pub fn owner(b: usize, size: usize) -> usize {
    b % size
}

struct BodyResult {
    u: Vec<[f64; 3]>,
    vm: Vec<f64>,
    stats: BodyStats,
}

/// One body owned by this rank: assembled and factorized.
pub struct LocalBody {
    pub body: usize,
    pub dofs: DofMap,
    pub sys: BodySystem,
    pub chol: Cholesky,
}

/// Assembles and factorizes the bodies this rank owns (phases `assemble`, `factorize`).
pub fn assemble_and_factorize<C: Comm>(comm: &C, model: &Model, ordering: OrderingKind, t: &mut Timings) -> Result<Vec<LocalBody>> {
    let mesh = &model.mesh;
    let mine: Vec<usize> = (0..mesh.bodies.len()).filter(|&b| owner(b, comm.size()) == comm.rank()).collect();
    let systems = t.phase(comm, "assemble", || {
        mine.iter()
            .map(|&b| {
                let body = &mesh.bodies[b];
                let dofs = DofMap::new(body.nodes.clone(), &model.constraints);
                let loads = &model.loads[3 * body.nodes.start..3 * body.nodes.end];
                assemble_body(mesh, b, model.lame[b], &dofs, loads).map(|s| (b, dofs, s))
            })
            .collect::<Result<Vec<_>>>()
    })?;
    t.phase(comm, "factorize", || {
        systems
            .into_iter()
            .map(|(b, dofs, sys)| {
                let body = &mesh.bodies[b];
                let ord = match ordering {
                    OrderingKind::Metis => {
                        let (xadj, adj) = &sys.graph;
                        let node_perm = nested_dissection(xadj, adj)?;
                        Ordering::Custom(expand_to_dofs(&node_perm, dofs.nfree, |v| dofs.node_dofs(body.nodes.start + v)))
                    }
                    OrderingKind::Amd => Ordering::Amd,
                };
                let chol = Cholesky::factorize(&sys.k, ord)
                    .map_err(|e| Error::numerical(format!("body \"{}\"", body.name), e.to_string()))?;
                Ok(LocalBody { body: b, dofs, sys, chol })
            })
            .collect::<Result<Vec<_>>>()
    })
}

/// Assembles, factorizes and solves this rank's bodies, computes their stresses and gathers
/// everything on rank 0.
pub fn solve_elastic<C: Comm>(comm: &C, model: &Model, ordering: OrderingKind, t: &mut Timings) -> Result<Solution> {
    let bodies = assemble_and_factorize(comm, model, ordering, t)?;
    let u = t.phase(comm, "solve", || {
        Ok(bodies
            .iter()
            .map(|lb| {
                let mut x = lb.sys.f.clone();
                lb.chol.solve_in_place(&mut x);
                x
            })
            .collect::<Vec<_>>())
    })?;
    let refs: Vec<&LocalBody> = bodies.iter().collect();
    let rhs: Vec<&[f64]> = bodies.iter().map(|lb| lb.sys.f.as_slice()).collect();
    finish_bodies(comm, model, &refs, &u, &rhs, t)
}

/// Checks K u = rhs on each local body, expands u, computes the element stresses (phase
/// `stress`) and gathers all bodies on rank 0 (phase `gather`).
fn finish_bodies<C: Comm>(comm: &C, model: &Model, bodies: &[&LocalBody], u: &[Vec<f64>], rhs: &[&[f64]], t: &mut Timings) -> Result<Solution> {
    let mesh = &model.mesh;
    let results = t.phase(comm, "stress", || {
        bodies
            .iter()
            .zip(u)
            .zip(rhs)
            .map(|((lb, x), f)| {
                let b = lb.body;
                let body = &mesh.bodies[b];
                let kx = lb.sys.k.mul(x);
                let fnorm = norm(f);
                let rnorm = norm(&kx.iter().zip(*f).map(|(a, b)| a - b).collect::<Vec<_>>());
                let residual = if fnorm > 0.0 { rnorm / fnorm } else { rnorm };
                if !residual.is_finite() || residual > 1e-6 {
                    return Err(Error::numerical(
                        format!("body \"{}\"", body.name),
                        format!("linear solve is inaccurate (relative residual {residual:.1e}): the stiffness is singular or ill-conditioned; is the body held against rigid motion?"),
                    ));
                }
                let stats = BodyStats {
                    name: body.name.clone(),
                    nodes: body.nodes.len(),
                    elements: body.elems.len(),
                    free_dofs: lb.dofs.nfree,
                    nnz_k: lb.sys.k.nnz(),
                    nnz_l: lb.chol.nnz_l(),
                    residual,
                    rank: comm.rank(),
                };
                let u = lb.dofs.expand(x);
                let vm = body
                    .elems
                    .clone()
                    .map(|e| {
                        let ue = mesh.hexes[e].map(|v| u[v - body.nodes.start]);
                        von_mises(&hex8_center_stress(&mesh.hex_coords(e), &ue, model.lame[b]))
                    })
                    .collect();
                Ok(BodyResult { u, vm, stats })
            })
            .collect::<Result<Vec<_>>>()
    })?;
    let mut sol = t.phase(comm, "gather", || Ok(gather(comm, model, &results)))?;
    for (lb, r) in bodies.iter().zip(&results) {
        let body = &mesh.bodies[lb.body];
        sol.local.nodes.extend(body.nodes.clone());
        sol.local.displacement.extend(&r.u);
        sol.local.cells.extend(body.elems.clone());
        sol.local.von_mises.extend(&r.vm);
    }
    sol.element_rank = mesh.elem_body().into_iter().map(|b| owner(b, comm.size())).collect();
    Ok(sol)
}

/// The contact solve on the monolithic dual: factorize, build A and b (phase `dual`), solve the
/// QP (phase `iterate`), recover u (phase `recover`), then stresses and gather as for elasticity.
pub fn solve_contact<C: Comm>(comm: &C, ls: &LoadedScene, model: &Model, t: &mut Timings) -> Result<(Solution, ContactOutcome)> {
    let contact = model.pairs.as_ref().expect("contact is active");
    let s = &ls.scene.solver;
    let bodies = assemble_and_factorize(comm, model, ls.scene.factorization.ordering, t)?;
    let (dual, b) = t.phase(comm, "dual", || Ok(MonolithicDual::new(comm, contact, bodies)))?;
    let set = Lambda::new(contact);
    let params = solver_params(s);
    let name = s.method.name();
    let qp = t.phase(comm, "iterate", || {
        qp::solve(&dual, &b, &set, &vec![0.0; dual.dim()], &params).map_err(|e| Error::numerical(name.to_uppercase(), e.to_string()))
    })?;
    let (u, rhs) = t.phase(comm, "recover", || Ok(dual.recover(&qp.lambda)))?;
    let refs: Vec<&LocalBody> = dual.blocks.iter().map(|blk| &blk.local).collect();
    let rhs_refs: Vec<&[f64]> = rhs.iter().map(Vec::as_slice).collect();
    let sol = finish_bodies(comm, model, &refs, &u, &rhs_refs, t)?;
    // the status cannot be sharper than the solution: classify at the solver's tolerance
    let bnorm = dual.norm(&b);
    let state = contact_state(contact, &set, &qp.lambda, &qp.gradient, s.eps.max(1e-9), bnorm);
    let kkt = qp::kkt::residuals(&set, &qp.lambda, &qp.gradient, bnorm);
    Ok((sol, ContactOutcome { dim: dual.dim(), state, info: qp.info, bnorm, kkt }))
}

/// What the contact solve adds to the elastic fields.
#[derive(Clone, Debug)]
pub struct ContactOutcome {
    /// Length of the solvers' dual vector.
    pub dim: usize,
    pub state: ContactState,
    pub info: qp::Info,
    pub bnorm: f64,
    pub kkt: qp::kkt::Kkt,
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

const STATS_LEN: usize = 5;

/// Packs each rank's bodies into one f64 message and unpacks all of them on rank 0.
fn gather<C: Comm>(comm: &C, model: &Model, mine: &[BodyResult]) -> Solution {
    let mut buf = Vec::new();
    for r in mine {
        buf.extend(r.u.iter().flatten());
        buf.extend(&r.vm);
        let s = &r.stats;
        buf.extend([s.free_dofs as f64, s.nnz_k as f64, s.nnz_l as f64, s.residual, s.rank as f64]);
    }
    let Some(all) = comm.gather_f64(0, &buf) else {
        return Solution::default();
    };
    let mesh = &model.mesh;
    let mut sol = Solution {
        displacement: vec![[0.0; 3]; mesh.nodes.len()],
        von_mises: vec![0.0; mesh.hexes.len()],
        bodies: vec![BodyStats::default(); mesh.bodies.len()],
        ..Default::default()
    };
    let mut cursor = vec![0usize; comm.size()];
    for (b, body) in mesh.bodies.iter().enumerate() {
        let r = owner(b, comm.size());
        let data = &all[r];
        let mut p = cursor[r];
        for v in body.nodes.clone() {
            sol.displacement[v] = [data[p], data[p + 1], data[p + 2]];
            p += 3;
        }
        sol.von_mises[body.elems.clone()].copy_from_slice(&data[p..p + body.elems.len()]);
        p += body.elems.len();
        let s = &data[p..p + STATS_LEN];
        sol.bodies[b] = BodyStats {
            name: body.name.clone(),
            nodes: body.nodes.len(),
            elements: body.elems.len(),
            free_dofs: s[0] as usize,
            nnz_k: s[1] as usize,
            nnz_l: s[2] as usize,
            residual: s[3],
            rank: s[4] as usize,
        };
        cursor[r] = p + STATS_LEN;
    }
    sol
}

/// The solver parameters of the scene's `[solver]` table.
pub fn solver_params(s: &SolverSettings) -> qp::Params {
    qp::Params {
        method: s.method,
        eps: s.eps,
        rho_factor: s.rho_factor,
        rtol: s.rtol,
        cfact: s.cfact,
        forcing: s.forcing,
        inner_tol: s.inner_tol,
        cg_stop: s.cg_stop,
        inner_floor: s.inner_floor,
        max_outer: s.max_outer,
        max_inner: s.max_inner,
        max_products: usize::MAX,
        power_iterations: s.power_iterations,
        sigma: None,
        gamma: s.gamma,
    }
}

/// `tresca-feti solve`: the whole pipeline, files written by rank 0.
pub fn run_solve<C: Comm>(comm: &C, scene_path: &std::path::Path, overrides: &[String], out: Option<PathBuf>) -> Result<Summary> {
    let mut t = Timings::default();
    let ls = t.phase(comm, "scene", || {
        let mut ls = crate::scene::load(scene_path, overrides)?;
        if let Some(o) = out {
            ls.scene.output.path = Some(o);
        }
        Ok(ls)
    })?;
    let model = t.phase(comm, "mesh", || model::build(&ls))?;
    let (sol, outcome) = match &model.pairs {
        _ if ls.scene.decomposition.is_tfeti(&body_dofs(&model)) => tfeti::solve(comm, &ls, &model, &mut t)?,
        Some(_) => solve_contact(comm, &ls, &model, &mut t).map(|(s, o)| (s, Some(o)))?,
        None => (solve_elastic(comm, &model, ls.scene.factorization.ordering, &mut t)?, None),
    };
    let h5 = ls.output_path();
    let mut report = report(comm, &ls, &model, &sol, outcome.as_ref(), &t);
    let (mut peak_sum, mut peak_max) = ([peak_rss_bytes()], [peak_rss_bytes()]);
    comm.sum_f64(&mut peak_sum);
    comm.max_f64(&mut peak_max);
    report["memory"] = json!({"peak_rss_bytes_sum_over_ranks": peak_sum[0], "peak_rss_bytes_max_rank": peak_max[0]});
    let before_output = t.clone();
    // every rank writes its rows; the root attributes carry rank 0's report
    let mut text = report.to_string().into_bytes();
    comm.broadcast_bytes(0, &mut text);
    let report_text = String::from_utf8_lossy(&text).into_owned();
    let data = output_data(comm, &ls, &model, &sol, outcome.as_ref(), &before_output, &report_text);
    let files = t.phase(comm, "output", || output::write_all(comm, &h5, &data, ls.scene.output.xdmf, ls.scene.output.report.then_some(&report)))?;
    if ls.scene.output.verify {
        let checked = t.phase(comm, "verify", || output::hdf5::verify(&h5, &data))?;
        let mut total = [checked as u64];
        comm.sum_u64(&mut total);
        report["output_verified_values"] = json!(total[0]);
    }
    report["timings"] = t.to_json();
    Ok(Summary { report, files, solution: sol })
}

/// DOFs of every body (3 per node).
pub fn body_dofs(model: &Model) -> Vec<usize> {
    model.mesh.bodies.iter().map(|b| 3 * b.nodes.len()).collect()
}

/// This process's peak resident memory (VmHWM), 0 where /proc is not available.
pub fn peak_rss_bytes() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok()))
        .map_or(0.0, |kb| kb * 1024.0)
}

fn report<C: Comm>(comm: &C, ls: &LoadedScene, model: &Model, sol: &Solution, outcome: Option<&ContactOutcome>, t: &Timings) -> serde_json::Value {
    let mesh = &model.mesh;
    let (umax, at) = sol
        .displacement
        .iter()
        .enumerate()
        .map(|(v, u)| ((u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt(), v))
        .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
    let body_of_node = mesh.bodies.iter().position(|b| b.nodes.contains(&at)).unwrap_or(0);
    let vm_max = sol.von_mises.iter().fold(0.0f64, |a, &b| a.max(b));
    json!({
        "scene": ls.path.display().to_string(),
        "title": ls.scene.title,
        "ranks": comm.size(),
        "mpi": comm.library(),
        "problem": match (outcome.is_some(), sol.tfeti.is_some()) {
            (true, false) => "contact with Tresca friction (monolithic dual)",
            (true, true) => "contact with Tresca friction (TFETI dual)",
            (false, false) => "linear elasticity (no contact)",
            (false, true) => "linear elasticity (no contact, TFETI dual)",
        },
        "tfeti": sol.tfeti.as_ref().map(|f| json!({
            "subdomains_per_body": mesh.bodies.iter().enumerate().map(|(b, _)| f.subdomains.iter().filter(|s| s.body == b).count()).collect::<Vec<_>>(),
            "gluing": ls.scene.decomposition.gluing,
            "multipliers": {"contact": f.contact_rows, "gluing": f.gluing_rows, "dirichlet": f.dirichlet_rows},
            "coarse_dim": f.coarse_dim,
            "nnz_C_lower": f.nnz_c,
            "gluing_jump_relative": f.gluing_jump,
            "coarse_feasibility": f.feasibility,
            "projector": ls.scene.decomposition.projector,
            "smalse": f.smalse,
            "distribution": f.distribution,
            "subdomains": f.subdomains,
        })),
        "ordering": format!("{:?}", ls.scene.factorization.ordering).to_lowercase(),
        "mesh": {
            "nodes": mesh.nodes.len(),
            "elements": mesh.hexes.len(),
            "dofs": model.ndof(),
            "free_dofs": sol.bodies.iter().map(|b| b.free_dofs).sum::<usize>(),
        },
        "bodies": sol.bodies.iter().map(|b| json!({
            "name": b.name, "nodes": b.nodes, "elements": b.elements, "free_dofs": b.free_dofs,
            "nnz_K_lower": b.nnz_k, "nnz_L": b.nnz_l, "relative_residual": b.residual, "rank": b.rank,
        })).collect::<Vec<_>>(),
        "results": {
            "max_displacement": umax,
            "max_displacement_node": at,
            "max_displacement_body": mesh.bodies.get(body_of_node).map(|b| b.name.clone()),
            "max_von_mises": vm_max,
        },
        "contact": outcome.map(|o| {
            let c = model.pairs.as_ref().expect("contact outcome implies pairs");
            json!({
                "pairs": c.len(),
                "open": o.state.count(OPEN),
                "stick": o.state.count(STICK),
                "slip": o.state.count(SLIP),
                "on_slip_bound": o.state.on_slip_bound,
                "total_force_on_slave": o.state.total_force(c),
            })
        }),
        "solver": outcome.map(|o| {
            let i = &o.info;
            json!({
                "method": ls.scene.solver.method.name(),
                "dual_dim": o.dim,
                "eps": ls.scene.solver.eps,
                "outer_iterations": i.iterations,
                "nA": i.n_a,
                "nA_power": i.n_a_power,
                "inner_iterations": i.inner_iterations,
                "preconditioner_applications": i.preconditioner_applications,
                "final_relative_reduced_gradient": i.err,
                "q": i.q,
                "sigma_est": i.sigma_est,
                "rho": i.rho,
                "norm_b": o.bnorm,
                "kkt": o.kkt,
                "kkt_worst": o.kkt.worst(),
            })
        }),
        "timings": t.to_json(),
        "versions": crate::versions(),
    })
}

fn history_json(info: &qp::Info) -> serde_json::Value {
    json!(info
        .history
        .iter()
        .map(|h| json!({"kind": h.kind.to_string(), "err": h.err, "tol": h.tol, "q": h.q, "nA": h.n_a, "inner": h.inner, "normal_active": h.normal_active, "stick": h.stick, "slip": h.slip}))
        .collect::<Vec<_>>())
}

/// This rank's share of the result file: its rows of u and of the stresses, the replicated
/// fields whole.
fn output_data<C: Comm>(comm: &C, ls: &LoadedScene, model: &Model, sol: &Solution, outcome: Option<&ContactOutcome>, t: &Timings, report: &str) -> OutputData {
    let mesh = &model.mesh;
    let want = |f: &str| ls.scene.output.fields.iter().any(|x| x == f);
    let mut fields = Vec::new();
    let mut rows = std::collections::BTreeMap::new();
    let local = &sol.local;
    if want("displacement") {
        fields.push(Field {
            name: "displacement".into(),
            center: Center::Node,
            ncomp: 3,
            values: Values::F64(local.displacement.iter().flatten().copied().collect()),
        });
        rows.insert("displacement".to_string(), local.nodes.clone());
    }
    if want("von_mises") {
        fields.push(Field { name: "von_mises".into(), center: Center::Cell, ncomp: 1, values: Values::F64(local.von_mises.clone()) });
        rows.insert("von_mises".to_string(), local.cells.clone());
    }
    if want("rank") {
        fields.push(Field { name: "rank".into(), center: Center::Cell, ncomp: 1, values: Values::I32(sol.element_rank.iter().map(|&r| r as i32).collect()) });
    }
    if let (true, Some(f)) = (want("subdomain"), &sol.tfeti) {
        fields.push(Field {
            name: "subdomain".into(),
            center: Center::Cell,
            ncomp: 1,
            values: Values::I32(f.element_subdomain.iter().map(|&s| s as i32).collect()),
        });
    }
    if want("body") {
        fields.push(Field {
            name: "body".into(),
            center: Center::Cell,
            ncomp: 1,
            values: Values::I32(mesh.elem_body().into_iter().map(|b| b as i32).collect()),
        });
    }
    let mut attributes = vec![
        ("scene".into(), ls.scene.to_toml()),
        ("versions".into(), crate::versions().to_string()),
        ("timings".into(), t.to_json().to_string()),
        ("report".into(), report.to_string()),
        ("ranks".into(), comm.size().to_string()),
    ];
    if let (Some(o), Some(c)) = (outcome, &model.pairs) {
        fields.extend(contact_fields(mesh.nodes.len(), c, &o.state, want));
        attributes.push(("solver_history".into(), history_json(&o.info).to_string()));
    }
    OutputData { coordinates: mesh.nodes.clone(), hexahedra: mesh.hexes.clone(), fields, attributes, rows }
}

/// `tresca-feti check`: validates the scene and builds the mesh; returns the text to print
/// (the resolved scene, mesh sizes, DOF counts).
pub fn run_check(scene_path: &std::path::Path, overrides: &[String]) -> Result<String> {
    use std::fmt::Write;
    let ls = crate::scene::load(scene_path, overrides)?;
    let model = model::build(&ls)?;
    let mesh = &model.mesh;
    let mut s = String::new();
    let _ = writeln!(s, "# resolved scene {}\n{}", ls.path.display(), ls.scene.to_toml());
    let _ = writeln!(s, "mesh: {} bodies, {} nodes, {} hexahedra", mesh.bodies.len(), mesh.nodes.len(), mesh.hexes.len());
    let mut free_total = 0;
    for body in &mesh.bodies {
        let dofs = DofMap::new(body.nodes.clone(), &model.constraints);
        free_total += dofs.nfree;
        let _ = writeln!(
            s,
            "  body {}: {} nodes, {} elements, {} DOFs ({} free, {} Dirichlet)",
            body.name,
            body.nodes.len(),
            body.elems.len(),
            3 * body.nodes.len(),
            dofs.nfree,
            3 * body.nodes.len() - dofs.nfree
        );
    }
    let _ = writeln!(s, "faces:");
    for f in &mesh.faces {
        let _ = writeln!(s, "  {}: {} quadrilaterals, {} nodes", f.name, f.quads.len(), f.nodes().len());
    }
    let load: [f64; 3] = std::array::from_fn(|c| model.loads.iter().skip(c).step_by(3).sum());
    let _ = writeln!(s, "total applied load: ({:.6e}, {:.6e}, {:.6e})", load[0], load[1], load[2]);
    let _ = writeln!(s, "DOFs: n = {} ({} free after Dirichlet elimination)", model.ndof(), free_total);
    for (i, &(sl, ma)) in model.contact.iter().enumerate() {
        let _ = writeln!(
            s,
            "contact pair {i}: slave {} ({} nodes) against master {} ({} nodes){}",
            mesh.faces[sl].name,
            mesh.faces[sl].nodes().len(),
            mesh.faces[ma].name,
            mesh.faces[ma].nodes().len(),
            if ls.scene.contact.enabled { "" } else { " — disabled" }
        );
    }
    if let Some(c) = &model.pairs {
        let (gmin, gmax) = c.gap.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &g| (a.min(g), b.max(g)));
        let tangential = if c.has_friction() { 2 * c.len() } else { 0 };
        let _ = writeln!(
            s,
            "contact: m = {} node-to-node pairs, Σw = {:.6e}, gaps in [{gmin:.3e}, {gmax:.3e}], multipliers: {} normal + {} tangential",
            c.len(),
            c.area.iter().sum::<f64>(),
            c.len(),
            tangential
        );
    }
    let dec = &ls.scene.decomposition;
    if dec.is_tfeti(&body_dofs(&model)) {
        let parts: Vec<usize> = mesh.bodies.iter().map(|b| dec.parts(3 * b.nodes.len())).collect();
        let d = crate::decomposition::decompose_each(mesh, &parts)?;
        let _ = writeln!(s, "TFETI: {} subdomains ({} per body), {} interface nodes", d.subdomains.len(), parts.iter().map(|p| p.to_string()).collect::<Vec<_>>().join(", "), d.interface_nodes());
        for (i, sd) in d.subdomains.iter().enumerate() {
            let iface = sd.nodes.iter().filter(|&&v| d.copies[v].len() > 1).count();
            let _ = writeln!(s, "  subdomain {i} (body {}): {} elements, {} nodes, {} DOFs, {iface} interface nodes", mesh.bodies[sd.body].name, sd.elems.len(), sd.nodes.len(), 3 * sd.nodes.len());
        }
    }
    let _ = write!(s, "dual: {}", if dec.is_tfeti(&body_dofs(&model)) { "TFETI" } else { "monolithic" });
    Ok(s)
}
