//! One pipeline of named, timed phases (scene → mesh → assemble → factorize → solve → stress →
//! gather → output), generic over the communicator. Bodies are distributed over the ranks
//! (body b on rank b mod P); each rank assembles and factorizes only its own bodies, rank 0
//! gathers the fields for the report, and all ranks write the HDF5 file together, each its own
//! rows (`output::hdf5::write_collective`). Every phase ends with [`Comm::agree`], so an error on
//! any rank stops all ranks with the same message.
//!
//! Two paths share the phases: the monolithic dual (one piece per body, Dirichlet eliminated,
//! the paper's setting) and TFETI ([`tfeti`]: METIS subdomains, gluing and Dirichlet
//! multipliers, coarse problem), chosen by the scene's `[decomposition]`; both end in the one
//! post-solve path ([`finish`]) and the typed [`report`]. Where the FETI preconditioner applies
//! is decided here, once ([`preconditioner`]). Rank 0 shows progress live ([`monitor`]).

pub(crate) mod accuracy;
mod check;
mod checkpoint;
pub(crate) mod finish;
pub mod forecast;
pub mod inspect;
pub mod memory;
pub(crate) mod monitor;
mod monolithic;
pub(crate) mod path;
pub mod plan;
pub mod rates;
pub mod report;
mod steps;
pub mod tfeti;

pub use check::{prepare, run_check, Prepared};
pub use monolithic::solve_contact;

use std::path::PathBuf;
use std::time::Instant;

use crate::comm::Comm;
use crate::contact::state::{contact_fields, ContactState, CONTACT, OPEN, SLIP, STICK};
use crate::error::{Error, Result};
use crate::fem::assembly::{assemble_body, DofMap};
use crate::linalg::cholesky::{Cholesky, Ordering};
use crate::linalg::ordering::{expand_to_dofs, order_last_if_cheap, NodeOrder};
use crate::model::{self, Model};
use crate::output::{self, Center, Field, MeshRows, OutputData, Values};
use crate::qp::params::CoulombSolve;
use crate::qp::{self, Method};
use crate::scene::{LoadedScene, OrderingKind, Preconditioner};

pub use crate::dual::monolithic::LocalBody;

/// Wall time of each phase, the maximum over the ranks, and the live monitor.
#[derive(Clone, Debug, Default)]
pub struct Timings {
    /// Wall time of each phase (max over the ranks, summed over repeated runs), in seconds, in the order they first ran.
    pub phases: Vec<(String, f64)>,
    /// Peak resident memory (VmHWM) at the end of each phase, the maximum over the ranks.
    pub peaks: Vec<(String, f64)>,
    /// The live monitor.
    pub live: monitor::Live,
}

impl Timings {
    /// Timings that print each phase as it starts (and hand out a monitor that prints each
    /// outer iteration) when `live`: rank 0 of a run without `--quiet`.
    pub fn live(live: bool) -> Self {
        Timings { phases: vec![], peaks: vec![], live: monitor::Live::new(live) }
    }

    /// The solvers' monitor: prints each outer iteration when live.
    pub fn monitor(&self) -> monitor::Live {
        self.live
    }

    /// Runs one phase on every rank, records its time (max over ranks) and makes its result
    /// collective.
    /// A phase that runs 2 s shows its time on rank 0 ([`monitor::Progress`]); `iterate` does not:
    /// its outer iterations are shown as they end.
    pub fn phase<C: Comm, T>(&mut self, comm: &C, name: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
        let unit = (name != "iterate").then_some(monitor::Unit::Time);
        self.phase_with(comm, name, unit, |_| f())
    }

    /// [`Timings::phase`] whose body counts its work in `unit` on the [`monitor::Progress`] it is
    /// handed (`None`: nothing shown but the phase's start line).
    pub fn phase_with<C: Comm, T>(&mut self, comm: &C, name: &str, unit: Option<monitor::Unit>, f: impl FnOnce(&monitor::Progress) -> Result<T>) -> Result<T> {
        self.live.phase(name);
        let t0 = Instant::now();
        let r = {
            let progress = unit.map_or_else(monitor::Progress::default, |u| monitor::Progress::start(&self.live, name, u));
            f(&progress)
        };
        let r = r.and_then(|v| injected_fault(comm, name).map_or(Ok(v), Err));
        let mut t = [t0.elapsed().as_secs_f64(), peak_rss_bytes()];
        let r = comm.agree(r);
        comm.max_f64(&mut t);
        // a phase run once per load step: its total (and its highest peak)
        match self.phases.iter_mut().find(|p| p.0 == name) {
            Some(p) => p.1 += t[0],
            None => self.phases.push((name.to_string(), t[0])),
        }
        match self.peaks.iter_mut().find(|p| p.0 == name) {
            Some(p) => p.1 = p.1.max(t[1]),
            None => self.peaks.push((name.to_string(), t[1])),
        }
        r
    }

    /// Splits `parts` off the time of phase `name` (it ran on every rank and succeeded there,
    /// so every rank calls this): each part becomes its own line (max over the ranks) before
    /// `name`, which keeps the rest. Totals are unchanged but for the max over ranks per part.
    pub fn split<C: Comm>(&mut self, comm: &C, name: &str, parts: &[(&'static str, f64)]) {
        let mut t: Vec<f64> = parts.iter().map(|p| p.1).collect();
        comm.max_f64(&mut t);
        let Some(at) = self.phases.iter().position(|p| p.0 == name) else { return };
        self.phases[at].1 = (self.phases[at].1 - t.iter().sum::<f64>()).max(0.0);
        for (part, secs) in parts.iter().map(|p| p.0).zip(t) {
            // a phase run again (a load step, a study's repeat) adds to its parts
            match self.phases.iter_mut().find(|p| p.0 == part) {
                Some(p) => p.1 += secs,
                None => {
                    let at = self.phases.iter().position(|p| p.0 == name).unwrap_or(self.phases.len());
                    self.phases.insert(at, (part.to_string(), secs));
                }
            }
        }
    }

    /// Sum of the phase times, in seconds.
    pub fn total(&self) -> f64 {
        self.phases.iter().map(|p| p.1).sum()
    }

    /// The phase times for the report.
    pub fn times(&self) -> report::PhaseTimes {
        report::PhaseTimes(self.phases.clone())
    }
}

/// `TRESCA_FETI_FAULT=<phase>@<rank>` makes that phase fail on that rank after it ran (to
/// test that an error on one rank stops all of them; meant for rank-local phases such as
/// `factorize`).
fn injected_fault<C: Comm>(comm: &C, phase: &str) -> Option<Error> {
    let spec = std::env::var("TRESCA_FETI_FAULT").ok()?;
    let (p, r) = spec.split_once('@')?;
    (p == phase && r.parse::<usize>().ok() == Some(comm.rank())).then(|| Error::numerical("injected fault", format!("phase {phase} on rank {}", comm.rank())))
}

/// `TRESCA_FETI_PAUSE=<phase>` sleeps 60 s at a point of that phase (`output`: the result
/// set written under its temporary names, not yet renamed; `committed`: renamed into place,
/// before the summary), so a test can signal the run there.
fn pause_for_tests(phase: &str) {
    if std::env::var("TRESCA_FETI_PAUSE").is_ok_and(|p| p == phase) {
        std::thread::sleep(std::time::Duration::from_secs(60));
    }
}

/// Figures of one body's linear solve (TFETI: summed over its subdomains).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct BodyStats {
    /// Name of the body.
    pub name: String,
    /// Nodes of the body.
    pub nodes: usize,
    /// Elements of the body.
    pub elements: usize,
    /// DOFs its K acts on (the free DOFs).
    pub free_dofs: usize,
    /// Nonzeros of the lower triangle of K.
    #[serde(rename = "nnz_K_lower")]
    pub nnz_k: usize,
    /// Nonzeros of the Cholesky factor L.
    #[serde(rename = "nnz_L")]
    pub nnz_l: usize,
    /// ‖K u − f‖ / ‖f‖ of the free DOFs (TFETI: the largest over the subdomains).
    #[serde(rename = "relative_residual")]
    pub residual: f64,
    /// Rank of the body (TFETI: the lowest rank of its subdomains).
    pub rank: usize,
}

/// The fields on rank 0 (empty on other ranks).
#[derive(Clone, Debug, Default)]
pub struct Solution {
    /// Displacement u of every node.
    pub displacement: Vec<[f64; 3]>,
    /// Von Mises stress of every element (at its center).
    pub von_mises: Vec<f64>,
    /// Figures of each body's linear solve.
    pub bodies: Vec<BodyStats>,
    /// Subdomains, interface and coarse figures when solved by TFETI.
    pub tfeti: Option<tfeti::TfetiInfo>,
    /// This rank's own rows of the fields, as it writes them to the file (every rank).
    pub local: LocalFields,
    /// This rank's rows of the mesh (every rank): its pieces' part, what it writes to the file.
    pub local_mesh: LocalMesh,
    /// η of the dual operator's single-precision factors (`solver.precision = "mixed"`).
    pub single_precision_error: Option<f64>,
    /// The monolithic dual's explicit products: the contact DOFs of the factors' trailing blocks.
    pub explicit_products: Option<usize>,
}

/// The rows of the mesh one rank holds, parallel to [`LocalFields`]' nodes and cells: the
/// coordinates of the nodes it writes; its elements' nodes (global numbers), bodies and pieces
/// (TFETI: subdomains).
#[derive(Clone, Debug, Default)]
pub struct LocalMesh {
    /// Coordinates of the nodes it writes.
    pub coordinates: Vec<[f64; 3]>,
    /// Its elements, by the nodes' global numbers.
    pub cells: Vec<crate::mesh::Cell>,
    /// Body of each of its elements.
    pub cell_body: Vec<usize>,
    /// Piece (TFETI: subdomain) of each of its elements.
    pub cell_piece: Vec<usize>,
}

/// The rows of the distributed fields one rank holds: the nodes it writes (each node once over
/// all ranks) with their displacements, its elements with their von Mises stress.
#[derive(Clone, Debug, Default)]
pub struct LocalFields {
    /// The nodes it writes (global numbers).
    pub nodes: Vec<usize>,
    /// Displacement u of each of those nodes.
    pub displacement: Vec<[f64; 3]>,
    /// Its elements (global numbers).
    pub cells: Vec<usize>,
    /// Von Mises stress of each of those elements.
    pub von_mises: Vec<f64>,
}

/// What `solve` reports back to the command line.
#[derive(Clone, Debug)]
pub struct Summary {
    /// The typed report (what the JSON file holds).
    pub report: report::Report,
    /// The files written.
    pub files: Vec<PathBuf>,
    /// The computed fields (on rank 0).
    pub solution: Solution,
}

/// Rank that owns body `b`.
pub fn owner(b: usize, size: usize) -> usize {
    b % size
}

/// The nodes of body `b` that the contact rows touch (by the body's local node index; empty
/// without contact).
pub fn contact_nodes(model: &Model, b: usize) -> Vec<bool> {
    let Some(c) = &model.pairs else { return vec![] };
    let nodes = &model.mesh.bodies[b].nodes;
    let mut last = vec![false; nodes.len()];
    for i in 0..c.len() {
        for &(v, _) in c.row(i) {
            if nodes.contains(&v) {
                last[v - nodes.start] = true;
            }
        }
    }
    last
}

/// Body `b`'s node order for its factor: METIS nested dissection, with `contact_last` the
/// contact nodes ([`contact_nodes`]) last where that costs little fill ([`order_last_if_cheap`]).
/// Computed once per process — the plan counts its fill, the factorization of the same rank
/// (body b is priced and factorized by rank b mod size) uses it; `graph` is the body's node
/// graph and `free` its free DOFs per node, asked for only the first time.
pub fn body_order(model: &Model, b: usize, contact_last: bool, graph: impl FnOnce() -> ((Vec<usize>, Vec<usize>), Vec<u8>)) -> Result<&NodeOrder> {
    let memo = &model.orders[b][contact_last as usize];
    if let Some(o) = memo.get() {
        return Ok(o);
    }
    let ((xadj, adj), free) = graph();
    let last = if contact_last { contact_nodes(model, b) } else { vec![] };
    let o = order_last_if_cheap(&xadj, &adj, &last, &free)?;
    Ok(memo.get_or_init(|| o))
}

/// Assembles and factorizes the bodies this rank owns (phases `assemble`, `factorize`).
///
/// With `contact_last`, the nodes the contact rows touch are ordered last (METIS ordering only):
/// the factor's trailing block then holds (K⁻¹) on them ([`LocalBody::trailing`]).
pub fn assemble_and_factorize<C: Comm>(comm: &C, model: &Model, ordering: OrderingKind, contact_last: bool, t: &mut Timings) -> Result<Vec<LocalBody>> {
    let mesh = &model.mesh;
    let mine: Vec<usize> = (0..mesh.bodies.len()).filter(|&b| owner(b, comm.size()) == comm.rank()).collect();
    let systems = t.phase(comm, "assemble", || {
        let by_body = model::constraints_by_body(mesh, &model.constraints);
        mine.iter()
            .map(|&b| {
                let body = &mesh.bodies[b];
                let dofs = DofMap::new(body.nodes.clone(), &by_body[b]);
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
                let mut trailing = vec![];
                let ord = match ordering {
                    OrderingKind::Metis => {
                        let dofs_of = |v: usize| dofs.node_dofs(body.nodes.start + v);
                        let free = || (0..body.nodes.len()).map(|l| dofs_of(l).iter().flatten().count() as u8).collect();
                        let order = body_order(model, b, contact_last, || (sys.graph.clone(), free()))?;
                        if order.last {
                            let last = contact_nodes(model, b);
                            let first_last = order.perm.iter().position(|&v| last[v]).unwrap_or(order.perm.len());
                            trailing = expand_to_dofs(&order.perm[first_last..], dofs.nfree, dofs_of);
                        }
                        Ordering::Custom(expand_to_dofs(&order.perm, dofs.nfree, dofs_of))
                    }
                    OrderingKind::Amd => Ordering::Amd,
                };
                let chol = Cholesky::factorize(&sys.k, ord).map_err(|e| Error::numerical(format!("body \"{}\"", body.name), e.to_string()))?;
                Ok(LocalBody { body: b, dofs, sys, chol, trailing })
            })
            .collect::<Result<Vec<_>>>()
    })
}

/// Assembles, factorizes and solves this rank's bodies, computes their stresses and gathers
/// everything on rank 0.
pub fn solve_elastic<C: Comm>(comm: &C, model: &Model, ordering: OrderingKind, t: &mut Timings) -> Result<Solution> {
    let bodies = assemble_and_factorize(comm, model, ordering, false, t)?;
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

/// The post-solve path of the bodies ([`finish::finish`], one piece per body): checks K u = rhs,
/// stresses, gather on rank 0.
fn finish_bodies<C: Comm>(comm: &C, model: &Model, bodies: &[&LocalBody], u: &[Vec<f64>], rhs: &[&[f64]], t: &mut Timings) -> Result<Solution> {
    let mesh = &model.mesh;
    let layout: Vec<finish::PieceLayout> = bodies.iter().map(|lb| finish::PieceLayout::body(mesh, lb.body)).collect();
    let mine: Vec<finish::PieceSolution<'_>> = bodies
        .iter()
        .zip(u)
        .zip(rhs)
        .map(|((lb, x), f)| finish::PieceSolution { k: &lb.sys.k, nnz_l: lb.chol.nnz_l(), x, rhs: f, held: &[], nodal: lb.dofs.expand(x) })
        .collect();
    let hint = "the stiffness is singular or ill-conditioned; is the body held against rigid motion?";
    let (mut sol, stats, _) = finish::finish(comm, &model.lame, model.size, mesh.bodies.len(), &layout, &mine, hint, t)?;
    sol.bodies = stats
        .iter()
        .zip(&mesh.bodies)
        .map(|((s, _), body)| BodyStats {
            name: body.name.clone(),
            nodes: s.nodes,
            elements: s.elements,
            free_dofs: s.dofs,
            nnz_k: s.nnz_k,
            nnz_l: s.nnz_l,
            residual: s.residual,
            rank: s.rank,
        })
        .collect();
    Ok(sol)
}

/// Which dual problem a scene is solved on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DualKind {
    /// The monolithic dual (one block per body).
    Monolithic,
    /// TFETI with the oblique projector P̃ (`orthogonal`: SMALSE-M's penalized operator);
    /// `contact`: with contact rows (else plain CG on the gluing and Dirichlet rows);
    /// `projected`: `decomposition.projected_cg`.
    Tfeti {
        /// SMALSE-M's orthogonal projector P (else the oblique P̃).
        orthogonal: bool,
        /// With contact rows.
        contact: bool,
        /// `decomposition.projected_cg`.
        projected: bool,
    },
}

impl DualKind {
    /// The dual the scene is solved on.
    pub fn of(ls: &LoadedScene, model: &Model) -> DualKind {
        let dec = &ls.scene.decomposition;
        if dec.is_tfeti(&body_dofs(model)) {
            DualKind::Tfeti { orthogonal: dec.projector == crate::scene::Projector::Orthogonal, contact: model.pairs.is_some(), projected: dec.projected_cg }
        } else {
            DualKind::Monolithic
        }
    }
}

/// Whether the inner solves run projected onto Ker G ∩ W ([`crate::qp::Coarse`]): on TFETI with
/// the oblique projector, in the methods that take a preconditioner
/// ([`Method::takes_preconditioner`]; SSN-BiCGSTAB projects its preconditioner only) or the
/// plain CG of a scene without contact, unless `decomposition.projected_cg = false`.
pub fn projected(method: Method, dual: DualKind) -> bool {
    match dual {
        DualKind::Tfeti { orthogonal: false, contact, projected: true } => !contact || method.takes_preconditioner(),
        _ => false,
    }
}

/// The one place that decides whether the scene's `solver.preconditioner` applies: the FETI
/// preconditioner acts on every row of the TFETI dual in the inner solves of the methods that
/// take one ([`Method::takes_preconditioner`]): projected onto Ker G ∩ W under the oblique
/// projector ([`projected`]), as `P M P + ϱ⁻¹Q` under SMALSE-M. Anything else is refused with
/// the key named. `auto` (the default) is Dirichlet for the plain CG of a TFETI scene without
/// contact (standard PCPG), lumped for TSSN under the oblique projector and none elsewhere
/// (each measured: docs/method.md, "The default choice").
pub fn preconditioner(method: Method, kind: Preconditioner, dual: DualKind) -> Result<Option<Preconditioner>> {
    match kind {
        Preconditioner::None => return Ok(None),
        Preconditioner::Auto => {
            let plain_cg = matches!(dual, DualKind::Tfeti { contact: false, orthogonal: false, .. });
            let auto = if plain_cg { Preconditioner::Dirichlet } else { Preconditioner::Lumped };
            return Ok((projected(method, dual) && (plain_cg || method == Method::Tssn)).then_some(auto));
        }
        _ => {}
    }
    let refuse = |why: String| Err(Error::scene("solver.preconditioner", format!("\"{}\" {why}", kind.name())));
    let takes = || {
        let names: Vec<&str> = Method::ALL.iter().filter(|m| m.takes_preconditioner()).map(|m| m.name()).collect();
        format!("acts in the inner solves of {} only; \"{}\" takes none", names.join(", "), method.name())
    };
    match dual {
        DualKind::Monolithic => {
            refuse("acts on the TFETI dual; this scene is solved on the monolithic dual (set decomposition.subdomains or decomposition.tfeti = true)".into())
        }
        DualKind::Tfeti { orthogonal: true, contact, .. } if !contact || method.takes_preconditioner() => Ok(Some(kind)),
        DualKind::Tfeti { orthogonal: false, projected: false, .. } => refuse("acts in the projected inner solves (decomposition.projected_cg = true)".into()),
        _ if projected(method, dual) => Ok(Some(kind)),
        DualKind::Tfeti { .. } => refuse(takes()),
    }
}

/// The automatic method (`solver.method` absent or `"auto"`) for the dual the scene is solved
/// on: TSSN (with the FETI preconditioner where its CG runs projected, [`preconditioner`]),
/// except under SMALSE-M's orthogonal projector, whose inner solves stay SSN-BiCGSTAB.
/// Measured on the benchmark set and the stability suite (docs/method.md, "The default
/// choice"; docs/performance.md).
pub fn resolve_method(solver: &mut crate::scene::SolverSettings, dual: DualKind) {
    if !solver.auto {
        return;
    }
    let smalse = matches!(dual, DualKind::Tfeti { orthogonal: true, .. });
    solver.params = solver.params.with_method(if smalse { Method::SsnBicgstab } else { Method::Tssn });
    solver.auto = false;
}

/// The scene's solver settings with the automatic method resolved for its dual (what
/// [`run_solve`] writes into the scene; here for callers of the phases themselves).
pub fn solver_for(ls: &LoadedScene, model: &Model) -> crate::scene::SolverSettings {
    let mut s = ls.scene.solver.clone();
    resolve_method(&mut s, DualKind::of(ls, model));
    s
}

/// What the contact solve adds to the elastic fields.
#[derive(Clone, Debug)]
pub struct ContactOutcome {
    /// Length of the solvers' dual vector.
    pub dim: usize,
    /// The contact state of every pair.
    pub state: ContactState,
    /// The solver's counters and history.
    pub info: qp::Info,
    /// ‖b‖ of the dual right-hand side.
    pub bnorm: f64,
    /// The KKT residuals at the solution.
    pub kkt: qp::kkt::Kkt,
    /// Every step of a load path (empty with one load state).
    pub steps: Vec<path::StepOutput>,
    /// Where the accuracy guard tightened ε (this step's; the last step's outcome holds every
    /// step's once the path is walked).
    pub tightenings: Vec<accuracy::Tightening>,
}

/// `tresca-feti solve`: the whole pipeline, files written by rank 0.
pub fn run_solve<C: Comm>(comm: &C, scene_path: &std::path::Path, overrides: &[String], out: Option<PathBuf>, quiet: bool) -> Result<Summary> {
    run_solve_from(comm, scene_path, overrides, out, quiet, None)
}

/// [`run_solve`], continued from checkpoint `resume` where given (`solve --resume`): it is read
/// and checked against the scene, its mesh files and the program before the solve; a refusal
/// writes nothing.
pub fn run_solve_from<C: Comm>(
    comm: &C,
    scene_path: &std::path::Path,
    overrides: &[String],
    out: Option<PathBuf>,
    quiet: bool,
    resume: Option<&std::path::Path>,
) -> Result<Summary> {
    let mut t = Timings::live(comm.is_root() && !quiet);
    let Prepared { ls, mut model, plan, tfeti } = check::prepare(comm, scene_path, overrides, out, comm.size(), &mut t)?;
    let resume = resume.map(|p| checkpoint::read(comm, &ls, p)).transpose()?;
    let resume = resume.as_ref();
    memory::check_after_plan(comm, &ls, &model, plan.as_deref())?;
    let (sol, outcome) = match &model.pairs {
        _ if tfeti => tfeti::solve_from(comm, &ls, &mut model, resume, &mut t),
        Some(_) => monolithic::solve_contact_from(comm, &ls, &model, resume, &mut t).map(|(s, o)| (s, Some(o))),
        None => solve_elastic(comm, &model, ls.scene.factorization.ordering, &mut t).map(|s| (s, None)),
    }
    .map_err(|e| memory::name_the_mesh(&ls, e))?;
    let h5 = ls.output_path();
    let mut report = report(comm, &ls, &model, &sol, outcome.as_ref(), &t);
    report.decomposition_plan = plan;
    let (mut peak_sum, mut peak_max) = ([peak_rss_bytes()], [peak_rss_bytes()]);
    comm.sum_f64(&mut peak_sum);
    comm.max_f64(&mut peak_max);
    let after_phase = t.peaks.iter().map(|(phase, bytes)| report::PhasePeak { phase: phase.clone(), bytes: *bytes }).collect();
    report.memory = Some(report::Memory {
        peak_rss_bytes_sum_over_ranks: peak_sum[0],
        peak_rss_bytes_max_rank: peak_max[0],
        peak_rss_bytes_max_rank_after_phase: after_phase,
    });
    let before_output = t.clone();
    // every rank writes its rows; the root attributes carry rank 0's report
    // collective: a failure on one rank must stop all of them before the broadcast below
    let json = comm.agree(serde_json::to_value(&report).map_err(|e| Error::output(h5.display().to_string(), format!("report: {e}"))))?;
    let mut text = json.to_string().into_bytes();
    comm.broadcast_bytes(0, &mut text);
    let report_text = String::from_utf8_lossy(&text).into_owned();
    // HDF5 attributes must be the same on every rank: the history's times are rank 0's too
    let mut text = outcome.as_ref().map(|o| serde_json::to_string(&o.info.history).unwrap_or_default()).unwrap_or_default().into_bytes();
    comm.broadcast_bytes(0, &mut text);
    let history_text = String::from_utf8_lossy(&text).into_owned();
    let data = output_data(comm, &ls, &model, &sol, outcome.as_ref(), &before_output, &report_text, &history_text);
    // the set stays under temporary names until it is complete: read back, report rewritten
    let staged = t.phase(comm, "output", || {
        let staged = output::stage(comm, &h5, &data, ls.scene.output.xdmf, ls.scene.output.report.then_some(&json))?;
        pause_for_tests("output");
        Ok(staged)
    })?;
    if ls.scene.output.verify {
        let checked = t.phase(comm, "verify", || output::hdf5::verify(staged.h5_temp(), &data))?;
        let mut total = [checked as u64];
        comm.sum_u64(&mut total);
        report.output_verified_values = Some(total[0]);
    }
    report.timings = t.times();
    if ls.scene.output.report {
        // the sidecar written with the file lacked the output phase's own time
        let json = comm.agree(serde_json::to_value(&report).map_err(|e| Error::output(h5.display().to_string(), format!("report: {e}"))))?;
        staged.rewrite_report(comm, &json)?;
    }
    let files = staged.commit(comm)?;
    pause_for_tests("committed");
    if let Some(stop) = &model.path.stopped {
        let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
        return Err(Error::numerical(
            &stop.what,
            format!("{}; the path stops there: steps 1–{} are solved and written to {}", stop.why, stop.at - 1, names.join(", ")),
        ));
    }
    Ok(Summary { report, files, solution: sol })
}

/// What `check` and the report say of contact entry `i` beyond its faces: its slave nodes
/// outside the contact zone, the warning where some of them lie over the master face, and its
/// initial interference (empty: nothing to say); lengths with the unit suffix `length`.
pub fn pair_notes(c: &crate::contact::pairing::Contact, i: usize, length: &str) -> Vec<String> {
    let mut out = c.outside.get(i).map_or_else(Vec::new, |o| outside_lines(i, o, length));
    if let Some(f) = c.interference.get(i).filter(|f| f.nodes > 0) {
        out.push(format!(
            "  initial interference: {} slave nodes start inside the master, at most {:.3e}{length} deep (the solution removes it)",
            f.nodes, f.depth
        ));
    }
    out
}

/// The lines that say which slave nodes of contact entry `i` are outside its contact zone, and
/// the warning where some of them lie over the master face (empty: none outside).
fn outside_lines(i: usize, o: &crate::contact::pairing::Outside, length: &str) -> Vec<String> {
    let at = |k: usize| {
        let x = o.first[k].unwrap_or([f64::NAN; 3]);
        format!("({:.6}, {:.6}, {:.6}){length}", x[0], x[1], x[2])
    };
    let mut out = Vec::new();
    if let Some(&v) = o.nodes.first() {
        out.push(format!(
            "  {} slave nodes outside the contact zone (no master facet within the search distance {:.3e}{length}: no contact rows), the first node {v} at {}",
            o.nodes.len(),
            o.search,
            at(0)
        ));
    }
    if let Some(&v) = o.over.first() {
        out.push(format!(
            "warning: contact pair {i}: {} slave nodes over the master face (inside its outline, facing it, within half the search distance of it) find no master facet, the first node {v} at {}; is the master face whole, and does it face the slave?",
            o.over.len(),
            at(1)
        ));
    }
    out
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

fn report<C: Comm>(comm: &C, ls: &LoadedScene, model: &Model, sol: &Solution, outcome: Option<&ContactOutcome>, t: &Timings) -> report::Report {
    use report::*;
    let mesh = &model.mesh;
    let (umax, at) =
        sol.displacement
            .iter()
            .enumerate()
            .map(|(v, u)| ((u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt(), v))
            .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
    let body_of_node = mesh.bodies.iter().position(|b| b.nodes.contains(&at)).unwrap_or(0);
    let dec = &ls.scene.decomposition;
    let solver = &ls.scene.solver.params;
    let length = UnitsReport::suffix(UnitsReport::of(&ls.scene.units).as_ref(), 0);
    Report {
        scene: ls.path.display().to_string(),
        title: ls.scene.title.clone(),
        ranks: comm.size(),
        mpi: comm.library(),
        units: UnitsReport::of(&ls.scene.units),
        problem: {
            let dual = if sol.tfeti.is_some() { "TFETI dual" } else { "monolithic dual" };
            let contact = contact_phrase(&model.pairs.as_ref().map(|c| c.laws()).unwrap_or_default());
            match (outcome.is_some(), sol.tfeti.is_some()) {
                (true, _) => format!("{contact} ({dual})"),
                (false, false) => "linear elasticity (no contact)".into(),
                (false, true) => "linear elasticity (no contact, TFETI dual)".into(),
            }
        },
        tfeti: sol.tfeti.as_ref().map(|f| TfetiReport {
            subdomains_per_body: (0..mesh.bodies.len()).map(|b| f.subdomains.iter().filter(|s| s.piece.body == b).count()).collect(),
            gluing: dec.gluing,
            dirichlet: dec.dirichlet,
            multipliers: Multipliers { contact: f.contact_rows, gluing: f.gluing_rows, dirichlet: f.dirichlet_rows, tie: f.tie_rows },
            eliminated_dofs: f.eliminated_dofs,
            clusters: f.clusters,
            corner_rows: f.corner_rows,
            coarse_dim: f.coarse_dim,
            nnz_c: f.nnz_c,
            coarse_solve: dec.coarse_solve,
            coarse_explicit_bytes_max_rank: f.coarse_explicit_bytes,
            gluing_jump: f.gluing_jump,
            feasibility: f.feasibility,
            projector: dec.projector,
            smalse: f.smalse.clone(),
            distribution: f.distribution.clone(),
            subdomains: f.subdomains.clone(),
        }),
        ordering: format!("{:?}", ls.scene.factorization.ordering).to_lowercase(),
        mesh: MeshReport {
            nodes: model.size.nodes,
            elements: model.size.elements,
            cells: model.size.describe(),
            dofs: model.ndof(),
            free_dofs: model.ndof() - model.constraints.iter().map(|&(v, c, _)| (v, c)).collect::<std::collections::HashSet<_>>().len(),
            subdomain_dofs: sol.tfeti.is_some().then(|| sol.bodies.iter().map(|b| b.free_dofs).sum()),
        },
        bodies: sol.bodies.clone(),
        results: Results {
            max_displacement: umax,
            max_displacement_node: at,
            max_displacement_body: mesh.bodies.get(body_of_node).map(|b| b.name.clone()),
            max_von_mises: sol.von_mises.iter().fold(0.0f64, |a, &b| a.max(b)),
        },
        contact: outcome.map(|o| {
            let c = model.pairs.as_ref().expect("contact outcome implies pairs");
            ContactReport {
                pairs: c.len(),
                open: o.state.count(OPEN),
                contact: o.state.count(CONTACT),
                outside: c.outside.iter().map(|o| o.nodes.len()).sum(),
                notes: model
                    .slave_choice
                    .iter()
                    .filter(|w| w.1.starts_with("warning"))
                    .map(|w| w.1.clone())
                    .chain((0..c.outside.len()).flat_map(|i| {
                        pair_notes(c, i, &length)
                            .into_iter()
                            .map(move |l| if l.starts_with("warning") { l } else { format!("contact pair {i}: {}", l.trim_start()) })
                    }))
                    .collect(),
                stick: o.state.count(STICK),
                slip: o.state.count(SLIP),
                on_slip_bound: o.state.on_slip_bound,
                total_force_on_slave: o.state.total_force(c),
            }
        }),
        solver: match (outcome, sol.tfeti.as_ref().and_then(|f| f.cg.as_ref())) {
            (Some(o), _) => Some(SolverReport {
                // a Coulomb solve names its way unless it was the fixed point on the method; a
                // body held by contact alone solved without SMALSE-M's loop ran TSSN itself
                method: match o.info.coulomb {
                    Some(CoulombSolve::Newton) => "coulomb-newton".into(),
                    Some(CoulombSolve::Lagged) => "coulomb-lagged".into(),
                    _ if dec.projector == crate::scene::Projector::Orthogonal && sol.tfeti.as_ref().is_some_and(|f| f.smalse.is_none()) => "tssn".into(),
                    _ => solver.method().name().into(),
                },
                dual_dim: o.dim,
                eps: solver.common.eps,
                info: o.info.clone(),
                norm_b: o.bnorm,
                kkt: o.kkt,
                kkt_worst: o.kkt.worst(),
                eps_tightened: o.tightenings.clone(),
            }),
            // TFETI without contact: CG on the gluing and Dirichlet rows (no KKT beyond Ax = b)
            (None, Some((info, dim, bnorm, tightened))) => Some(SolverReport {
                method: "cg".into(),
                dual_dim: *dim,
                eps: solver.common.eps,
                info: info.clone(),
                norm_b: *bnorm,
                kkt: Default::default(),
                kkt_worst: 0.0,
                eps_tightened: tightened.clone(),
            }),
            (None, None) => None,
        },
        timings: t.times(),
        versions: crate::versions(),
        memory: None,
        decomposition_plan: None,
        load_path: outcome.filter(|o| !o.steps.is_empty()).map(|o| o.steps.iter().map(|s| s.report.clone()).collect()),
        path_stopped: model.path.stopped.as_ref().map(crate::model::Stopped::describe),
        output_verified_values: None,
        single_precision_error: sol.single_precision_error,
        explicit_products: sol.explicit_products,
    }
}

/// This rank's share of the result file: its rows of u and of the stresses, the replicated
/// fields whole.
#[allow(clippy::too_many_arguments)]
fn output_data<C: Comm>(
    comm: &C,
    ls: &LoadedScene,
    model: &Model,
    sol: &Solution,
    outcome: Option<&ContactOutcome>,
    t: &Timings,
    report: &str,
    history: &str,
) -> OutputData {
    let want = |f: &str| ls.scene.output.fields.iter().any(|x| x == f);
    let (mut fields, mut rows) = distributed_fields(&sol.local, &want);
    let lm = &sol.local_mesh;
    let cell_field = |name: &str, v: Vec<i32>| Field { name: name.into(), center: Center::Cell, ncomp: 1, values: Values::I32(v) };
    if want("rank") {
        fields.push(cell_field("rank", vec![comm.rank() as i32; sol.local.cells.len()]));
        rows.insert("rank".into(), sol.local.cells.clone());
    }
    if let (true, Some(_)) = (want("subdomain"), &sol.tfeti) {
        fields.push(cell_field("subdomain", lm.cell_piece.iter().map(|&s| s as i32).collect()));
        rows.insert("subdomain".into(), sol.local.cells.clone());
    }
    if want("body") {
        fields.push(cell_field("body", lm.cell_body.iter().map(|&b| b as i32).collect()));
        rows.insert("body".into(), sol.local.cells.clone());
    }
    let mut attributes = vec![
        ("scene".into(), ls.scene.to_toml()),
        ("versions".into(), crate::versions().to_string()),
        ("timings".into(), serde_json::to_string(&t.times()).unwrap_or_default()),
        ("report".into(), report.to_string()),
        ("ranks".into(), comm.size().to_string()),
    ];
    if let Some(stop) = &model.path.stopped {
        attributes.push(("path_stopped".into(), stop.describe()));
    }
    let mut steps = Vec::new();
    if let (Some(o), Some(c)) = (outcome, &model.pairs) {
        // the contact state is whole on every rank: rank 0 writes its rows
        let pairs: Vec<usize> = if comm.is_root() { (0..c.len()).collect() } else { vec![] };
        let with_contact = |fields: &mut Vec<Field>, rows: &mut Rows, state: &ContactState| {
            let (f, nodes) = contact_fields(c, state, &pairs, want);
            for x in &f {
                rows.insert(x.name.clone(), nodes.clone());
            }
            fields.extend(f);
        };
        with_contact(&mut fields, &mut rows, &o.state);
        attributes.push(("solver_history".into(), history.to_string()));
        for s in &o.steps {
            let (mut fields, mut rows) = distributed_fields(&s.local, &want);
            with_contact(&mut fields, &mut rows, &s.state);
            steps.push(output::Step { time: s.report.step as f64, fields, rows });
        }
    }
    let mesh_rows =
        Some(MeshRows { nodes: model.size.nodes, cells: model.size.elements, node_rows: sol.local.nodes.clone(), cell_rows: sol.local.cells.clone() });
    OutputData { coordinates: lm.coordinates.clone(), cells: lm.cells.clone(), mesh_rows, fields, attributes, rows, steps }
}

type Rows = std::collections::BTreeMap<String, Vec<usize>>;

/// u and the von Mises stress (when `want`ed) on this rank's rows, and the rows.
fn distributed_fields(local: &LocalFields, want: &impl Fn(&str) -> bool) -> (Vec<Field>, Rows) {
    let mut fields = Vec::new();
    let mut rows = std::collections::BTreeMap::new();
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
    (fields, rows)
}
