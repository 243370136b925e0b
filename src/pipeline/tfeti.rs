//! The TFETI path of the pipeline: phases `decompose` (METIS, constraint rows), `factorize`
//! (assemble K_s and factorize K_s with its fixing DOFs, this rank's subdomains only), `coarse`
//! (G, e, C), `dual` (b̃), `iterate`, `recover` (λ, α, u), `stress` and `gather`. Subdomains go
//! to ranks by a partition of the subdomain graph (`feti::assign_ranks`); the dual vectors are distributed
//! (`feti::distribution`), each rank holding the multipliers its subdomains own. The mesh and
//! the decomposition are whole on every rank only until each has taken its [`Share`].

use super::accuracy::{self, Verdict};
use super::finish::{finish, PieceLayout, PieceSolution, PieceStats};
use super::monitor::{self, Live};
use super::steps::{self, Solved, StepDual};
use super::{BodyStats, ContactOutcome, Solution, Timings};
use crate::comm::Comm;
use crate::contact::pairing::Contact;
use crate::contact::state::contact_state;
use crate::dual::Recovered;
use crate::error::{Error, Result};
use crate::feti::cluster::{ClusterSystem, Clustering};
use crate::feti::coarse::{self, Coarse};
use crate::feti::constraints::{self, LocalRhs};
use crate::feti::decomposition::{decompose_shared, Decomposition, DualGraphs};
use crate::feti::distribution::Distribution;
use crate::feti::dual::TfetiDual;
use crate::feti::restricted;
use crate::feti::smalse::{self, SmalseInfo};
use crate::feti::subdomain::{SubdomainMesh, SubdomainSystem};
use crate::feti::{assign_ranks, eliminated, subdomain_loads};
use crate::model::Model;
use crate::qp::{self, cone::Coefficient, Lambda, Operator, Params, Qp, QpError, QpSolution, Space};
use crate::scene::{CoarseSolve, LoadedScene, Precision, Projector};

/// Figures of one subdomain: those of every piece, and its interface.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct SubdomainStats {
    /// The figures every piece has (nodes, elements, DOFs, factor).
    #[serde(flatten)]
    pub piece: PieceStats,
    /// Nodes shared with other subdomains.
    pub interface_nodes: usize,
}

/// What the TFETI path adds to a [`Solution`].
#[derive(Clone, Debug, Default)]
pub struct TfetiInfo {
    /// Figures of each subdomain.
    pub subdomains: Vec<SubdomainStats>,
    /// Multipliers: contact, gluing, Dirichlet.
    pub contact_rows: usize,
    /// Gluing rows of B.
    pub gluing_rows: usize,
    /// Dirichlet rows of B.
    pub dirichlet_rows: usize,
    /// Rows of tied interfaces (`[[tie]]`).
    pub tie_rows: usize,
    /// DOFs held inside their subdomains (hybrid Dirichlet), over all copies.
    pub eliminated_dofs: usize,
    /// H-TFETI: clusters and the gluing rows of their corner nodes (held inside the clusters,
    /// not in `gluing_rows`); as many clusters as subdomains and no corner rows without.
    pub clusters: usize,
    /// Gluing rows of the clusters' corner nodes.
    pub corner_rows: usize,
    /// Size of the coarse problem: the rows of G (k_s per piece).
    pub coarse_dim: usize,
    /// Nonzeros of the lower triangle of the coarse matrix C.
    pub nnz_c: usize,
    /// Bytes of explicit coarse-inverse rows (`decomposition.coarse_solve = "explicit"`; max
    /// over the ranks; 0 with the factor).
    pub coarse_explicit_bytes: usize,
    /// max over nodes and copies of |u_copy − u_first| / max |u|.
    pub gluing_jump: f64,
    /// ‖Gλ − e‖/‖e‖ at the solution.
    pub feasibility: f64,
    /// SMALSE-M's outer loop (orthogonal projector only).
    pub smalse: Option<SmalseInfo>,
    /// How the dual vectors and the work of an A-product are spread over the ranks.
    pub distribution: DistributionStats,
    /// Without contact: the plain CG's counters, the dual's length, ‖b‖ and the accuracy
    /// guard's tightenings of ε (with contact they are the [`ContactOutcome`]'s).
    pub cg: Option<(qp::Info, usize, f64, Vec<accuracy::Tightening>)>,
}

/// The distribution of the multipliers and the time in each part of the A-products (max over
/// the ranks; times summed over the solve, power iterations included).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct DistributionStats {
    /// Fewest multipliers a rank owns.
    pub owned_rows_min: usize,
    /// Most multipliers a rank owns.
    pub owned_rows_max: usize,
    /// Most ghost rows of a rank (rows its subdomains read that neighbours own).
    pub ghost_rows_max: usize,
    /// Most neighbours a rank exchanges with.
    pub neighbours_max: usize,
    /// Values sent per A-product (all ranks): two ghost exchanges and one of contributions.
    pub values_sent_per_product: usize,
    /// Whole A-products, in seconds.
    pub apply_s: f64,
    /// K_s⁺ solves, in seconds.
    pub pinv_s: f64,
    /// Neighbour exchanges (waiting included), in seconds.
    pub exchange_s: f64,
    /// Reductions (coarse vectors and dot products), in seconds.
    pub reduce_s: f64,
    /// C⁻¹ solves (the A-products' P̃; SMALSE-M's P).
    pub coarse_solve_s: f64,
    /// The inner solves' projections onto Ker G ∩ W and GΠGᵀ's factorizations (outside the
    /// A-products).
    #[serde(default)]
    pub restricted_s: f64,
    /// The part of `restricted_s` spent factorizing GΠGᵀ.
    #[serde(default)]
    pub restricted_factor_s: f64,
    /// The least loaded rank's K⁺ time (load balance: pinv_min_s / pinv_s).
    pub pinv_min_s: f64,
    /// H-TFETI: the part of `pinv_s` spent in the clusters' corner problems (outside the
    /// subdomains' K_s⁺ solves).
    #[serde(default)]
    pub corner_s: f64,
}

impl DistributionStats {
    fn new<C: Comm>(dual: &TfetiDual<'_, C>) -> Self {
        let dist = &dual.dist;
        let comm = dist.comm();
        let corner: f64 = dual.pieces.iter().map(|p| p.sys.corner_s.get()).sum();
        let (owned, ghosts) = (dist.owned.len(), dist.local_len() - dist.owned.len());
        let (fwd, rev, nbrs) = dist.message_sizes();
        let c = &dist.clock;
        let mut mx = [
            owned as f64,
            -(owned as f64),
            ghosts as f64,
            nbrs as f64,
            c.apply.get(),
            c.pinv.get(),
            c.exchange.get(),
            c.reduce.get(),
            c.coarse_solve.get(),
            -c.pinv.get(),
            c.restricted.get(),
            c.restricted_factor.get(),
            corner,
        ];
        comm.max_f64(&mut mx);
        let mut sent = [(2 * fwd + rev) as u64];
        comm.sum_u64(&mut sent);
        DistributionStats {
            owned_rows_max: mx[0] as usize,
            owned_rows_min: (-mx[1]) as usize,
            ghost_rows_max: mx[2] as usize,
            neighbours_max: mx[3] as usize,
            values_sent_per_product: sent[0] as usize,
            apply_s: mx[4],
            pinv_s: mx[5],
            exchange_s: mx[6],
            reduce_s: mx[7],
            coarse_solve_s: mx[8],
            pinv_min_s: -mx[9],
            restricted_s: mx[10],
            restricted_factor_s: mx[11],
            corner_s: mx[12],
        }
    }
}

/// The TFETI dual problem of a scene, ready to iterate: the decomposition, the constraint rows,
/// the operator F (with the preconditioner TSSN asks for) and b̃, this rank's part of Λ.
pub struct TfetiProblem<'c, C: Comm> {
    /// The subdomains' clusters (one subdomain each unless H-TFETI).
    pub clusters: Clustering,
    /// The outer dual's rows of B, per cluster (B without the corner rows).
    pub constraints: constraints::Constraints,
    /// Rank of every cluster.
    pub owner: Vec<usize>,
    /// The dual operator F.
    pub dual: TfetiDual<'c, C>,
    /// The dual right-hand side b̃ on this rank's rows.
    pub b: Vec<f64>,
    /// This rank's part of Λ: its pairs' sets, its free λ_E.
    pub set: Lambda,
    /// This rank's share of the mesh and the decomposition: what the solve reads of them after
    /// the setup.
    pub share: Share,
    /// Δ per piece ([`piece_weights`]), what a preconditioner set later takes.
    pub weights: Vec<f64>,
    /// Size of the coarse problem: the rows of G.
    pub coarse_dim: usize,
    /// Nonzeros of the lower triangle of the coarse matrix C.
    pub nnz_c: usize,
    /// Bytes of explicit coarse-inverse rows (0 with the factor).
    pub coarse_explicit_bytes: usize,
}

/// Phases `decompose`, `factorize`, `coarse`, `dual` (and `preconditioner` when TSSN runs with
/// one on a contact scene): everything before the iterations. The decomposition is whole on
/// every rank until each rank has taken its share of it ([`Share`]) and the kernels of the
/// pieces it reads; then the model's whole mesh is released and the rest reads the share.
pub fn setup<'c, C: Comm>(comm: &'c C, ls: &LoadedScene, model: &mut Model, t: &mut Timings) -> Result<TfetiProblem<'c, C>> {
    let dec = &ls.scene.decomposition;
    // the plan's partition of the chosen count, when it made one
    let planned = model.partition.take();
    let mut split: Vec<(&'static str, f64)> = Vec::new();
    let (clusters, cons, owner, dist, share, loads, halo, weights, names) = t.phase(comm, "decompose", || {
        let (mesh, contact) = (&model.mesh, model.pairs.as_ref());
        let parts: Vec<usize> = mesh.bodies.iter().map(|b| dec.parts(3 * b.nodes.len())).collect();
        let clock = std::time::Instant::now();
        let d = match planned {
            Some((p, d)) if p == parts => d,
            _ => decompose_shared(comm, &DualGraphs::new(mesh), &parts)?,
        };
        split.push(("decompose partition", clock.elapsed().as_secs_f64()));
        let clock = std::time::Instant::now();
        let elim = eliminated(mesh, &d, &model.constraints, dec.dirichlet);
        let sub_cons = constraints::build(&d, &model.constraints, contact, &model.ties, dec.gluing, &elim);
        split.push(("decompose B", clock.elapsed().as_secs_f64()));
        let clusters = Clustering::new(mesh, &d, &sub_cons, dec.subdomains_per_cluster)?;
        let cons = clusters.outer(sub_cons);
        let dofs: Vec<usize> = clusters.members.iter().map(|m| m.iter().map(|&s| 3 * d.subdomains[s].nodes.len()).sum()).collect();
        let owner = assign_ranks(&dofs, &cons, comm.size());
        let dist = Distribution::new(comm, &cons, &owner);
        // this rank's subdomains: their share of the mesh and their loads (empty for the others)
        let own: Vec<usize> = (0..clusters.len()).filter(|&c| owner[c] == comm.rank()).flat_map(|c| clusters.members[c].iter().copied()).collect();
        let share = Share::new(model, &d, &elim, &own, &cons, &dist);
        let loads = subdomain_loads(&d, &model.loads, &own);
        // the coordinates and held DOFs of the other ranks' pieces whose blocks of G this rank
        // reads (its halo): their kernels
        let halo: std::collections::HashMap<usize, (Vec<[f64; 3]>, Vec<usize>)> = Coarse::pieces_read(&dist)
            .into_iter()
            .filter(|&c| owner[c] != comm.rank())
            .flat_map(|c| clusters.members[c].iter().map(|&s| (s, (d.subdomains[s].nodes.iter().map(|&v| mesh.nodes[v]).collect(), elim[s].clone()))))
            .collect();
        let weights = piece_weights(model, &d, &clusters);
        let names: Vec<String> = clusters.members.iter().map(|m| mesh.bodies[d.subdomains[m[0]].body].name.clone()).collect();
        Ok((clusters, cons, owner, dist, share, loads, halo, weights, names))
    })?;
    t.split(comm, "decompose", &split);
    // every rank holds its share: the whole mesh goes before the factors come
    model.release_mesh();
    let model = &*model;
    let contact = model.pairs.as_ref();
    // rank 0 shows its own share (no collective for the monitor)
    let unit = monitor::Unit::Items(if comm.size() > 1 { "subdomains of rank 0" } else { "subdomains" });
    let pieces = t.phase_with(comm, "factorize", Some(unit), |progress| {
        let held = share.held(&model.constraints.iter().map(|c| c.2).collect::<Vec<_>>());
        let mine: Vec<usize> = (0..clusters.len()).filter(|&c| owner[c] == comm.rank()).collect();
        let total: usize = mine.iter().map(|&c| clusters.members[c].len()).sum();
        let done = std::cell::Cell::new(0);
        progress.set(0, total as u64);
        mine.into_iter()
            .map(|c| {
                let subs = clusters.members[c]
                    .iter()
                    .map(|&s| {
                        let p = share.position(s);
                        let pl = &share.layout[p];
                        let body = &model.mesh.bodies[pl.body];
                        let part =
                            SubdomainMesh { coords: &pl.coords, cells: &pl.cells, elems: &pl.elems, body: &body.name, body_elems_start: body.elems.start };
                        SubdomainSystem::from_part(
                            &part,
                            s,
                            model.lame[pl.body],
                            ls.scene.factorization.ordering,
                            loads[s].clone(),
                            share.eliminated[p].clone(),
                            held[p].clone(),
                        )
                        .inspect(|_| {
                            done.set(done.get() + 1);
                            progress.set(done.get(), total as u64);
                        })
                    })
                    .collect::<Result<Vec<_>>>()?;
                ClusterSystem::new(c, subs, clusters.bc[c].0.clone(), clusters.bc[c].1)
            })
            .collect::<Result<Vec<_>>>()
    })?;
    let orthogonal = dec.projector == Projector::Orthogonal;
    let kind = match (orthogonal, model.floating.is_empty()) {
        (false, _) => coarse::Kind::Oblique,
        (true, true) => coarse::Kind::Orthogonal,
        (true, false) => coarse::Kind::ContactHeld,
    };
    let (coarse, explicit_bytes) = t.phase(comm, "coarse", || {
        // the kernels of the pieces whose blocks of G this rank reads: its own and its halo
        let part = |s: usize| match halo.get(&s) {
            Some((coords, held)) => (coords.clone(), held.as_slice()),
            None => {
                let p = share.position(s);
                (share.layout[p].coords.clone(), share.eliminated[p].as_slice())
            }
        };
        let kernels = clusters.kernels_of(&Coarse::pieces_read(&dist), part);
        let mut coarse = Coarse::new(&dist, &kernels, &cons, &clusters.concat(&loads), kind, &|c: usize| names[c].clone())?;
        let bytes = match dec.coarse_solve {
            CoarseSolve::Factor => 0,
            CoarseSolve::Explicit => coarse.make_explicit(&dist, coarse::MAX_EXPLICIT_BYTES)?,
        };
        Ok((coarse, bytes))
    })?;
    drop((halo, loads));
    let (coarse_dim, nnz_c) = (coarse.dim(), coarse.nnz_c);
    let s = &super::solver_for(ls, model);
    let (mut dual, b) = t.phase(comm, "dual", || {
        let (mut dual, mut b) = TfetiDual::new(dist, &cons, pieces, coarse);
        dual.set_null(&clusters.null, &mut b);
        // the inner solves of a contact solve use them; the plain CG of a scene without
        // contact does not (measured slower: docs/performance.md, "Mixed precision")
        if s.precision != Precision::Double && contact.is_some() {
            dual.keep_single();
        }
        Ok((dual, b))
    })?;
    if let Some(m) = super::preconditioner(s.params.method(), s.preconditioner, super::DualKind::of(ls, model))? {
        t.phase(comm, "preconditioner", || dual.set_preconditioner(m, &cons, weights.clone()))?;
    }
    // this rank's part of Λ: its pairs, its λ_E
    let set = match contact {
        Some(c) => c.constraint_set().restrict(&dual.dist.pairs).with_free(dual.layout.free),
        None => Lambda::unconstrained(dual.layout.free),
    };
    Ok(TfetiProblem { clusters, constraints: cons, owner, dual, b, set, share, weights, coarse_dim, nnz_c, coarse_explicit_bytes: explicit_bytes })
}

/// This rank's share of the mesh and the decomposition, taken right after the partition: all
/// that the factorization, the load steps and the post-solve path read of them, so that the
/// whole mesh and decomposition can go before the factors are built.
pub struct Share {
    /// This rank's subdomains (the members of its clusters), ascending: their nodes,
    /// coordinates, elements and which nodes they write.
    pub layout: Vec<PieceLayout>,
    /// Per subdomain of `layout`: the DOFs held inside it (hybrid Dirichlet, ascending) and the
    /// entry of the constraint list holding each.
    pub eliminated: Vec<Vec<usize>>,
    held_entry: Vec<Vec<usize>>,
    /// Load paths: the nodes carrying traction whose first copy is in this rank's subdomains:
    /// (position in `layout`, local index).
    loaded: std::collections::HashMap<usize, (usize, usize)>,
    /// c on the owned rows at a step's prescribed values.
    rhs: LocalRhs,
    /// Subdomains over all ranks, and their held DOFs.
    pub subdomains: usize,
    /// DOFs held inside the subdomains (hybrid Dirichlet), over all ranks and copies.
    pub eliminated_dofs: usize,
}

impl Share {
    /// The share of the subdomains `own` and of the owned rows of `dist`.
    fn new<C: Comm>(
        model: &Model,
        d: &Decomposition,
        elim: &[Vec<usize>],
        own: &[usize],
        cons: &constraints::Constraints,
        dist: &Distribution<'_, C>,
    ) -> Share {
        let mesh = &model.mesh;
        let mut own = own.to_vec();
        own.sort_unstable();
        let layout = own
            .iter()
            .map(|&s| {
                let sd = &d.subdomains[s];
                PieceLayout {
                    index: s,
                    body: sd.body,
                    nodes: sd.nodes.clone(),
                    coords: sd.nodes.iter().map(|&v| mesh.nodes[v]).collect(),
                    writes: sd.nodes.iter().map(|&v| d.copies[v][0].0 == s).collect(),
                    elems: sd.elems.clone(),
                    cells: sd.elems.iter().map(|&e| mesh.cells[e].map(|v| sd.local(v).expect("element node in its subdomain"))).collect(),
                    interface_nodes: sd.nodes.iter().filter(|&&v| d.copies[v].len() > 1).count(),
                    name: format!("subdomain {s} (body \"{}\")", mesh.bodies[sd.body].name),
                }
            })
            .collect();
        // a later entry for the same DOF wins (as in `constraints::build`)
        let entry: std::collections::HashMap<(usize, usize), usize> = model.constraints.iter().enumerate().map(|(i, &(v, k, _))| ((v, k), i)).collect();
        let held_entry = own.iter().map(|&s| elim[s].iter().map(|&dof| entry[&(d.subdomains[s].nodes[dof / 3], dof % 3)]).collect()).collect();
        let mut loaded = std::collections::HashMap::new();
        if model.path.is_path() {
            for (dof, _) in model.path.forces(1) {
                let (s, l) = d.copies[dof / 3][0];
                if let Ok(p) = own.binary_search(&s) {
                    loaded.insert(dof / 3, (p, l));
                }
            }
        }
        let eliminated = own.iter().map(|&s| elim[s].clone()).collect();
        Share {
            layout,
            eliminated,
            held_entry,
            loaded,
            rhs: LocalRhs::new(cons, &dist.owned),
            subdomains: d.subdomains.len(),
            eliminated_dofs: elim.iter().map(Vec::len).sum(),
        }
    }

    /// The position of subdomain `s` (one of this rank's) in `layout`.
    pub fn position(&self, s: usize) -> usize {
        self.layout.binary_search_by_key(&s, |pl| pl.index).expect("a subdomain of this rank")
    }

    /// g_s of every subdomain of `layout` from the constraints' values `values`.
    pub fn held(&self, values: &[f64]) -> Vec<Vec<f64>> {
        self.held_entry.iter().map(|h| h.iter().map(|&e| values[e]).collect()).collect()
    }

    /// Load step k of `model`'s path on this rank's pieces: f_s and the held values g_s of every
    /// member of `dual`'s pieces, e = Rᵀf and c on the owned rows — what
    /// [`TfetiDual::set_load`] takes.
    #[allow(clippy::type_complexity)]
    fn step<C: Comm>(&self, model: &Model, k: usize, dual: &TfetiDual<'_, C>, clusters: &Clustering) -> (Vec<Vec<(Vec<f64>, Vec<f64>)>>, Vec<f64>, Vec<f64>) {
        let values = model.constraint_values(k);
        let mut f: Vec<Vec<f64>> = self.layout.iter().map(|pl| vec![0.0; 3 * pl.nodes.len()]).collect();
        for (dof, x) in model.path.forces(k) {
            if let Some(&(p, l)) = self.loaded.get(&(dof / 3)) {
                f[p][3 * l + dof % 3] += x;
            }
        }
        let g = self.held(&values);
        let mut fc = vec![Vec::new(); clusters.len()];
        let mut kernels: Vec<&[f64]> = vec![&[]; clusters.len()];
        for p in &dual.pieces {
            let c = p.sys.index;
            fc[c] = clusters.members[c].iter().flat_map(|&s| f[self.position(s)].iter().copied()).collect();
            kernels[c] = p.sys.kernel().0;
        }
        let e = dual.coarse.rigid_loads(&dual.dist, &|c| kernels[c], &fc);
        let mine = dual
            .dist
            .subs
            .iter()
            .map(|sr| clusters.members[sr.index].iter().map(|&s| (f[self.position(s)].clone(), g[self.position(s)].clone())).collect())
            .collect();
        (mine, e, self.rhs.at(&values))
    }
}

/// Δ_s = μ_min/μ_s per piece (a cluster lies in one body): the preconditioner's stiffness
/// weighting (1 for one material).
pub fn piece_weights(model: &Model, d: &Decomposition, clusters: &Clustering) -> Vec<f64> {
    let mu = |s: &crate::feti::decomposition::Subdomain| model.lame[s.body].mu;
    let min = d.subdomains.iter().map(mu).fold(f64::INFINITY, f64::min);
    clusters.members.iter().map(|m| min / mu(&d.subdomains[m[0]])).collect()
}

/// Decomposes, factorizes, then walks the load path (one step without `[load]`) on the TFETI
/// dual ([`steps::walk`]): contact or not, warm-started from the last step. The outcome is the
/// last step's, with every step's record.
pub fn solve<C: Comm>(comm: &C, ls: &LoadedScene, model: &mut Model, t: &mut Timings) -> Result<(Solution, Option<ContactOutcome>)> {
    solve_from(comm, ls, model, None, t)
}

/// [`solve`] from the step after checkpoint `resume`'s where given.
pub(crate) fn solve_from<C: Comm>(
    comm: &C,
    ls: &LoadedScene,
    model: &mut Model,
    resume: Option<&super::checkpoint::Checkpoint>,
    t: &mut Timings,
) -> Result<(Solution, Option<ContactOutcome>)> {
    let s = &super::solver_for(ls, model);
    let TfetiProblem { clusters, constraints: cons, owner, mut dual, b, set, share, coarse_dim, nnz_c, coarse_explicit_bytes, .. } = setup(comm, ls, model, t)?;
    let model = &*model;
    // B's rows are each rank's pieces' entries in `dual` now: only their counts are kept
    let rows = [cons.e_start(), cons.gluing_rows, cons.dirichlet_rows, cons.tie_rows];
    drop((cons, owner));
    let contact = model.pairs.as_ref();
    let orthogonal = ls.scene.decomposition.projector == Projector::Orthogonal;
    let mu = contact.filter(|c| c.is_coulomb()).map(|c| c.coefficients(&dual.dist.pairs));
    let name = if contact.is_some() { s.params.method().name() } else { "cg" };
    let restricted = ls.scene.decomposition.restricted && !model.floating.is_empty() && contact.is_some();
    let what = match (orthogonal, restricted) {
        (true, true) => "TSSN (Gλ = e kept on each Newton step)".to_string(),
        (true, false) => format!("SMALSE-M ({name})"),
        _ => name.to_string(),
    };
    let projected = super::projected(s.params.method(), super::DualKind::of(ls, model));
    let dim = dual.dim();
    let figures = Figures { rows, clusters: clusters.len(), corner_rows: clusters.corner_rows(), coarse_dim, nnz_c, coarse_explicit_bytes };
    let mut steps = Steps {
        comm,
        model,
        contact,
        dual: &mut dual,
        set,
        mu,
        share: &share,
        clusters: &clusters,
        figures,
        orthogonal,
        projected,
        penalty: ls.scene.decomposition.penalty,
        restricted: ls.scene.decomposition.restricted,
        what,
    };
    steps::walk(comm, ls, model, &s.params, &mut steps, b, dim, resume, t)
}

/// The global figures of the decomposition the report carries.
struct Figures {
    /// The rows of B: equality start, gluing, Dirichlet, ties.
    rows: [usize; 4],
    clusters: usize,
    corner_rows: usize,
    coarse_dim: usize,
    nnz_c: usize,
    coarse_explicit_bytes: usize,
}

/// The TFETI dual along a load path ([`StepDual`]).
struct Steps<'a, 'c, C: Comm> {
    comm: &'c C,
    model: &'a Model,
    contact: Option<&'a Contact>,
    dual: &'a mut TfetiDual<'c, C>,
    /// This rank's part of Λ.
    set: Lambda,
    /// The Coulomb coefficients of this rank's pairs.
    mu: Option<Vec<Coefficient>>,
    share: &'a Share,
    clusters: &'a Clustering,
    figures: Figures,
    /// SMALSE-M with the orthogonal projector (else the oblique P̃).
    orthogonal: bool,
    /// The solver runs on the projected system (the dual is its coarse space).
    projected: bool,
    penalty: f64,
    /// `decomposition.restricted`: bodies held by contact alone by TSSN with Gλ = e on each
    /// Newton step's subspace (SMALSE-M where a step's rows cannot hold them).
    restricted: bool,
    what: String,
}

/// The contact judgement of one solve: Λ with Coulomb's bounds cut at the solution, λ and the
/// gap c − Bu on the contact rows (whole on every rank), their KKT residuals.
type Judged = Option<(Lambda, Vec<f64>, Vec<f64>, qp::kkt::Kkt)>;

impl<C: Comm> StepDual for Steps<'_, '_, C> {
    type Extra = Option<SmalseInfo>;
    type Judged = Judged;

    fn what(&self) -> String {
        self.what.clone()
    }

    fn norm(&self, b: &[f64]) -> f64 {
        self.dual.space().norm(b)
    }

    fn set_load(&mut self, k: usize, jump: &[f64]) -> Result<Vec<f64>> {
        let (mine, e, c) = self.share.step(self.model, k, self.dual, self.clusters);
        Ok(self.dual.set_load(mine, e, c, jump))
    }

    fn iterate(
        &self,
        b: &[f64],
        x0: &[f64],
        first: bool,
        warm: Option<&Self::Extra>,
        params: &Params,
        monitor: &mut Live,
    ) -> std::result::Result<(QpSolution, Self::Extra), QpError> {
        let dual = &*self.dual;
        let m = dual.preconditioner();
        let qp = Qp::new(dual, b, &self.set).with_preconditioner(m.as_ref().map(|m| m as &dyn qp::Preconditioner)).with_coarse(if self.projected {
            Some(dual as &dyn qp::Coarse)
        } else {
            None
        });
        match (self.orthogonal, self.contact.is_some()) {
            (true, _) => {
                // the first step starts from λ̂ (Gλ̂ = e); where a body is held by contact
                // alone, from the least-norm equilibrium on the touching pairs (gap ≤ 0), else
                // on every row (λ_e: its normal components give Coulomb's first bounds
                // something to carry the load with); Coulomb is solved inside
                // each augmented-Lagrangian step (`qp::solve_friction`)
                let owned;
                let x0 = if first {
                    owned = (!dual.coarse.held()).then(|| dual.touching_start()).flatten().unwrap_or_else(|| dual.dist.owned_part(&dual.lambda_hat));
                    &owned
                } else {
                    x0
                };
                // `decomposition.restricted`: TSSN keeps Gλ = e on each Newton step's W; where a
                // step's rows cannot hold the body (GΠGᵀ singular, also to round-off: Coulomb
                // pairs whose tangents are all fixed), SMALSE-M takes over
                if self.restricted && !dual.coarse.held() && self.contact.is_some() {
                    match restricted::solve(dual, &self.set, self.mu.as_deref(), x0, params, monitor) {
                        Err(QpError::SingularCoarse { .. }) => {}
                        other => return other.map(|s| (s, None)),
                    }
                }
                smalse::solve(dual, qp.preconditioner, &self.set, self.mu.as_deref(), x0, warm.and_then(Option::as_ref), params, self.penalty, monitor)
                    .map(|(s, i)| (s, Some(i)))
            }
            (false, true) => qp::solve_friction(&qp, self.mu.as_deref(), x0, params, monitor).map(|s| (s, None)),
            (false, false) => qp::cg::solve(&qp, x0, &params.common, monitor).map(|s| (s, None)),
        }
    }

    fn recover(&self, sol: &QpSolution) -> Result<Recovered> {
        // a body held by contact alone: α closes the E rows and the contact rows the pairs'
        // states fix (in contact: the normal; sticking: both tangents; sliding: across the slip)
        let pi = (!self.dual.coarse.held()).then(|| {
            let set_k = match &self.mu {
                Some(mu) => qp::cone::bounds(&self.set, mu, &sol.lambda),
                None => self.set.clone(),
            };
            held_rows(&set_k, &sol.lambda)
        });
        self.dual.recover_with(&sol.lambda, pi.as_ref().map(|(f, s)| (f.as_slice(), s.as_slice()))).ok_or_else(|| {
            Error::numerical(
                "TFETI recovery",
                "a body held by contact alone keeps a rigid motion at this solution that no sticking or pressed pair holds (frictionless sliding freedom, or a body that lifts off)",
            )
        })
    }

    fn judge(&self, rec: &Recovered, sol: &QpSolution, bnorm: f64, eps: f64) -> (Verdict, Judged) {
        let dual = &*self.dual;
        // with contact: the contact multipliers and the gap c − Bu from the recovered u (= the
        // solvers' gradient on the I rows), whole on every rank, and their KKT residuals
        let judged = self.contact.map(|c| {
            let set_i = c.constraint_set();
            let ni = set_i.layout.dim();
            let (li, ri) = (dual.dist.all_rows(&rec.lambda, ni), dual.dist.all_rows(&rec.gap, ni));
            // Coulomb: the cones cut at the solution's λν (the bounds it was solved with, to ε)
            let set_i = if c.is_coulomb() { qp::cone::bounds(&set_i, &c.coulomb, &li) } else { set_i };
            // gaps relative to the displacements as well as to ‖b‖: where the equality Gλ = e
            // alone carries the load (a body held by contact alone, pressed uniformly) b is
            // round-off and would make round-off gaps look like penetration
            let mut umax = [rec.u.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()))];
            self.comm.max_f64(&mut umax);
            let gap_scale = bnorm.max(umax[0]);
            let kkt = qp::kkt::residuals_scaled(&set_i, &li, &ri, gap_scale, accuracy::force_scale(gap_scale, sol.info.sigma_est));
            (set_i, li, ri, kkt)
        });
        let kkt = judged.as_ref().map_or(0.0, |j| j.3.worst());
        (Verdict::new(self.comm, &equilibria(dual, &rec.u, &rec.rhs), kkt, eps), judged)
    }

    fn rows(&self) -> Vec<usize> {
        // the owned rows: global ids fixed by the decomposition, not by the rank count
        self.dual.dist.owned.clone()
    }

    fn kept_sigma(&self, sigma: f64) -> Option<f64> {
        // σ_max of SMALSE-M's penalized operator is its own business: measured every solve
        (!self.orthogonal).then_some(sigma)
    }

    fn finish(&mut self, _last: bool, _b: &[f64], step: &Solved<Self>, t: &mut Timings) -> Result<(Solution, Option<ContactOutcome>, Vec<f64>)> {
        let (dual, sol, rec, fig) = (&*self.dual, &step.sol, &step.rec, &self.figures);
        let mut solution = finish_subdomains(self.comm, self.model, self.share, dual, &rec.u, &rec.rhs, t)?;
        solution.single_precision_error = dual.single_error();
        // finish filled the gathered figures (subdomains, gluing jump); add the global ones
        let f = solution.tfeti.get_or_insert_with(TfetiInfo::default);
        [f.contact_rows, f.gluing_rows, f.dirichlet_rows, f.tie_rows] = fig.rows;
        f.eliminated_dofs = self.share.eliminated_dofs;
        f.clusters = fig.clusters;
        f.corner_rows = fig.corner_rows;
        f.coarse_dim = fig.coarse_dim;
        f.nnz_c = fig.nnz_c;
        f.coarse_explicit_bytes = fig.coarse_explicit_bytes;
        f.feasibility = rec.feasibility;
        f.smalse = step.extra.clone();
        f.distribution = DistributionStats::new(dual);
        let bnorm = step.bnorm;
        if self.contact.is_none() {
            f.cg = Some((sol.info.clone(), dual.space().count(dual.dim()), bnorm, step.tightenings.clone()));
        }
        let outcome = self.contact.zip(step.judged.as_ref()).map(|(c, (set_i, li, ri, kkt))| {
            let state = contact_state(c, set_i, li, ri, step.params.common.eps.max(1e-9), bnorm, accuracy::force_scale(bnorm, sol.info.sigma_est));
            ContactOutcome {
                dim: dual.space().count(dual.dim()),
                state,
                info: sol.info.clone(),
                bnorm,
                kkt: *kkt,
                steps: vec![],
                tightenings: step.tightenings.clone(),
            }
        });
        Ok((solution, outcome, dual.jump(&rec.gap)))
    }
}

/// The contact components that fix a rigid motion at the solution λ (this rank's pairs, owned
/// indices): the normal of every pair in contact (λν > 0), both tangents of a sticking one and,
/// of a sliding one (λτ on the bound of its set), the direction across the slip.
fn held_rows(set: &Lambda, lambda: &[f64]) -> (Vec<bool>, Vec<(usize, [f64; 2])>) {
    let l = set.layout;
    let lmax = (0..l.m).map(|i| lambda[l.normal(i)]).fold(0.0, f64::max);
    let mut free = vec![false; l.contact_dim()];
    let mut slides = Vec::new();
    for i in (0..l.m).filter(|&i| lambda[l.normal(i)] > 1e-9 * lmax) {
        free[l.normal(i)] = true;
        if !l.friction {
            continue;
        }
        let (k, lt) = (l.tangent(i, 0), [lambda[l.tangent(i, 0)], lambda[l.tangent(i, 1)]]);
        let outward = [lt[0] * (1.0 + 1e-6), lt[1] * (1.0 + 1e-6)];
        if set.tangent[i].frame(&outward).is_some() {
            slides.push((k, set.tangent[i].boundary_tangent(&lt)));
        } else {
            (free[k], free[k + 1]) = (true, true);
        }
    }
    (free, slides)
}

/// A member subdomain of this rank's pieces with its u_s and right-hand side.
type Member<'a> = (&'a SubdomainSystem, &'a [f64], &'a [f64]);

/// The subdomains of this rank's pieces, ascending like the share, with their u_s and f̂_s −
/// B_sᵀλ, and u_s − g_s zero on the held DOFs (whose rows, reactions, are not checked).
fn members<'a, C: Comm>(dual: &'a TfetiDual<'_, C>, u: &'a [Vec<f64>], rhs: &'a [Vec<f64>]) -> (Vec<Member<'a>>, Vec<Vec<f64>>) {
    let mut members: Vec<Member<'a>> = dual
        .pieces
        .iter()
        .zip(u)
        .zip(rhs)
        .flat_map(|((p, us), f)| p.sys.subs.iter().enumerate().map(move |(m, sub)| (sub, p.sys.part(us, m), p.sys.part(f, m))))
        .collect();
    members.sort_by_key(|x| x.0.index);
    let w = members
        .iter()
        .map(|(sub, us, _)| {
            let mut w = us.to_vec();
            sub.held.iter().for_each(|&d| w[d] = 0.0);
            w
        })
        .collect();
    (members, w)
}

/// The recovered equilibrium of every subdomain of this rank ([`accuracy::Equilibrium`], as
/// [`finish`] checks it).
fn equilibria<C: Comm>(dual: &TfetiDual<'_, C>, u: &[Vec<f64>], rhs: &[Vec<f64>]) -> Vec<accuracy::Equilibrium> {
    let (members, w) = members(dual, u, rhs);
    members.iter().zip(&w).map(|(&(sub, _, f), ws)| accuracy::Equilibrium::of(&sub.k, ws, f, &sub.held)).collect()
}

/// The post-solve path of the subdomains ([`finish`], one piece per subdomain, this rank's
/// share): checks K_s u_s = f_s − B_sᵀλ on the free DOFs (u_s − g_s against f̂_s − B_sᵀλ),
/// stresses, gather on rank 0 with the gluing jump; the bodies' figures summed over their
/// subdomains.
fn finish_subdomains<C: Comm>(
    comm: &C,
    model: &Model,
    share: &Share,
    dual: &TfetiDual<'_, C>,
    u: &[Vec<f64>],
    rhs: &[Vec<f64>],
    t: &mut Timings,
) -> Result<Solution> {
    let mesh = &model.mesh;
    let (members, w) = members(dual, u, rhs);
    let mine: Vec<PieceSolution<'_>> = members
        .iter()
        .zip(&w)
        .map(|(&(sub, us, f), ws)| PieceSolution {
            k: &sub.k,
            nnz_l: sub.nnz_l(),
            x: ws,
            rhs: f,
            held: &sub.held,
            nodal: us.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        })
        .collect();
    let (mut sol, stats, jump) = finish(comm, &model.lame, model.size, share.subdomains, &share.layout, &mine, "the recovered u is inaccurate", t)?;
    if comm.is_root() {
        sol.bodies = mesh
            .bodies
            .iter()
            .enumerate()
            .map(|(b, body)| {
                let mine = stats.iter().map(|x| &x.0).filter(|x| x.body == b);
                BodyStats {
                    name: body.name.clone(),
                    nodes: body.nodes.len(),
                    elements: body.elems.len(),
                    free_dofs: mine.clone().map(|x| x.dofs).sum(),
                    nnz_k: mine.clone().map(|x| x.nnz_k).sum(),
                    nnz_l: mine.clone().map(|x| x.nnz_l).sum(),
                    residual: mine.clone().map(|x| x.residual).fold(0.0, f64::max),
                    rank: mine.map(|x| x.rank).min().unwrap_or(0),
                }
            })
            .collect();
        let subdomains = stats.into_iter().map(|(piece, interface_nodes)| SubdomainStats { piece, interface_nodes }).collect();
        sol.tfeti = Some(TfetiInfo { subdomains, gluing_jump: jump, ..Default::default() });
    }
    Ok(sol)
}
