//! The TFETI path of the pipeline: phases `decompose` (METIS, constraint rows), `factorize`
//! (assemble K_s and factorize K_s with its fixing DOFs, this rank's subdomains only), `coarse`
//! (G, e, C), `dual` (b̃), `iterate`, `recover` (λ, α, u), `stress` and `gather`. Subdomains go
//! to ranks by size (largest first to the least loaded rank); the dual vectors are distributed
//! (`feti::distribution`), each rank holding the multipliers its subdomains own.

use super::{BodyStats, ContactOutcome, LocalFields, Solution, Timings};
use crate::comm::Comm;
use crate::decomposition::{decompose_each, Decomposition};
use crate::dual::{DualOperator, Preconditioner};
use crate::error::{Error, Result};
use crate::feti::coarse::Coarse;
use crate::feti::constraints;
use crate::feti::distribution::Distribution;
use crate::feti::dual::TfetiDual;
use crate::feti::smalse::{self, SmalseInfo};
use crate::feti::subdomain::SubdomainSystem;
use crate::feti::{assign_ranks, subdomain_loads};
use crate::fem::element::hex8_center_stress;
use crate::fem::material::von_mises;
use crate::model::Model;
use crate::qp::{self, lambda::Lambda};
use crate::recovery::contact_state;
use crate::scene::{LoadedScene, Projector};

/// Figures of one subdomain.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SubdomainStats {
    pub body: usize,
    pub nodes: usize,
    pub elements: usize,
    pub interface_nodes: usize,
    pub nnz_k: usize,
    pub nnz_l: usize,
    /// ‖K_s u_s − (f_s − B_sᵀλ)‖ / ‖f_s − B_sᵀλ‖.
    pub residual: f64,
    pub rank: usize,
}

/// What the TFETI path adds to a [`Solution`].
#[derive(Clone, Debug, Default)]
pub struct TfetiInfo {
    pub subdomains: Vec<SubdomainStats>,
    /// Subdomain of every element.
    pub element_subdomain: Vec<usize>,
    /// Multipliers: contact, gluing, Dirichlet.
    pub contact_rows: usize,
    pub gluing_rows: usize,
    pub dirichlet_rows: usize,
    pub coarse_dim: usize,
    pub nnz_c: usize,
    /// max over nodes and copies of |u_copy − u_first| / max |u|.
    pub gluing_jump: f64,
    /// ‖Gλ − e‖/‖e‖ at the solution.
    pub feasibility: f64,
    /// SMALSE-M's outer loop (orthogonal projector only).
    pub smalse: Option<SmalseInfo>,
    /// How the dual vectors and the work of an A-product are spread over the ranks.
    pub distribution: DistributionStats,
}

/// The distribution of the multipliers and the time in each part of the A-products (max over
/// the ranks; times summed over the solve, power iterations included).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct DistributionStats {
    pub owned_rows_min: usize,
    pub owned_rows_max: usize,
    pub ghost_rows_max: usize,
    pub neighbours_max: usize,
    /// Values sent per A-product (all ranks): two ghost exchanges and one of contributions.
    pub values_sent_per_product: usize,
    pub apply_s: f64,
    pub pinv_s: f64,
    pub exchange_s: f64,
    pub reduce_s: f64,
    pub coarse_solve_s: f64,
    /// The least loaded rank's K⁺ time (load balance: pinv_min_s / pinv_s).
    pub pinv_min_s: f64,
}

impl DistributionStats {
    fn new<C: Comm>(dist: &Distribution<'_, C>) -> Self {
        let comm = dist.comm();
        let (owned, ghosts) = (dist.owned.len(), dist.local_len() - dist.owned.len());
        let (fwd, rev, nbrs) = dist.message_sizes();
        let c = &dist.clock;
        let mut mx = [owned as f64, -(owned as f64), ghosts as f64, nbrs as f64, c.apply.get(), c.pinv.get(), c.exchange.get(), c.reduce.get(), c.coarse_solve.get(), -c.pinv.get()];
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
        }
    }
}

/// The TFETI dual problem of a scene, ready to iterate: the decomposition, the constraint rows,
/// the operator F (with the preconditioner TSSN asks for) and b̃, this rank's part of Λ.
pub struct TfetiProblem<'c, C: Comm> {
    pub decomposition: Decomposition,
    pub constraints: constraints::Constraints,
    /// Rank of every subdomain.
    pub owner: Vec<usize>,
    pub dual: TfetiDual<'c, C>,
    pub b: Vec<f64>,
    pub set: Lambda,
    pub coarse_dim: usize,
    pub nnz_c: usize,
}

/// Phases `decompose`, `factorize`, `coarse`, `dual` (and `preconditioner` when TSSN runs with
/// one on a contact scene): everything before the iterations.
pub fn setup<'c, C: Comm>(comm: &'c C, ls: &LoadedScene, model: &Model, t: &mut Timings) -> Result<TfetiProblem<'c, C>> {
    let mesh = &model.mesh;
    let dec = &ls.scene.decomposition;
    let contact = model.pairs.as_ref();
    let (d, cons, owner) = t.phase(comm, "decompose", || {
        let parts: Vec<usize> = mesh.bodies.iter().map(|b| dec.parts(3 * b.nodes.len())).collect();
        let d = decompose_each(mesh, &parts)?;
        let cons = constraints::build(&d, &model.constraints, contact, dec.gluing);
        let owner = assign_ranks(&d, comm.size());
        Ok((d, cons, owner))
    })?;
    let dist = Distribution::new(comm, &cons, &owner);
    let loads = subdomain_loads(&d, &model.loads);
    let subs = t.phase(comm, "factorize", || {
        (0..d.subdomains.len())
            .filter(|&s| owner[s] == comm.rank())
            .map(|s| {
                let sd = &d.subdomains[s];
                SubdomainSystem::new(mesh, sd, s, model.lame[sd.body], ls.scene.factorization.ordering, loads[s].clone())
            })
            .collect::<Result<Vec<_>>>()
    })?;
    let orthogonal = dec.projector == Projector::Orthogonal;
    let coarse = t.phase(comm, "coarse", || Coarse::new(mesh, &d, &cons, &loads, orthogonal))?;
    let (coarse_dim, nnz_c) = (coarse.dim(), coarse.nnz_c);
    let (mut dual, b) = t.phase(comm, "dual", || Ok(TfetiDual::new(dist, &cons, subs, coarse)))?;
    let s = &ls.scene.solver;
    // only TSSN's CG uses the preconditioner (the oblique projector's operator only)
    if contact.is_some() && !orthogonal && s.method == qp::Method::Tssn && s.preconditioner != Preconditioner::None {
        t.phase(comm, "preconditioner", || dual.set_preconditioner(s.preconditioner))?;
    }
    // this rank's part of Λ: its pairs, its λ_E
    let set = match contact {
        Some(c) => Lambda::new(c).restrict(&dual.dist.pairs),
        None => Lambda { layout: crate::dual::Layout::contact(0, false), tangent: vec![] },
    }
    .with_free(dual.layout.free);
    Ok(TfetiProblem { decomposition: d, constraints: cons, owner, dual, b, set, coarse_dim, nnz_c })
}

/// Decomposes, factorizes, solves (contact or not) and recovers on the TFETI dual.
pub fn solve<C: Comm>(comm: &C, ls: &LoadedScene, model: &Model, t: &mut Timings) -> Result<(Solution, Option<ContactOutcome>)> {
    let mesh = &model.mesh;
    let dec = &ls.scene.decomposition;
    let contact = model.pairs.as_ref();
    let orthogonal = dec.projector == Projector::Orthogonal;
    let s = &ls.scene.solver;
    let TfetiProblem { decomposition: d, constraints: cons, owner, dual, b, set, coarse_dim, nnz_c } = setup(comm, ls, model, t)?;
    let params = super::solver_params(s);
    let name = if contact.is_some() { s.method.name() } else { "cg" };
    let (sol, smalse) = t.phase(comm, "iterate", || {
        let y0 = vec![0.0; dual.dim()];
        let r = match (orthogonal, contact.is_some()) {
            (true, _) => smalse::solve(&dual, &set, &params, dec.penalty).map(|(s, i)| (s, Some(i))),
            (false, true) => qp::solve(&dual, &b, &set, &y0, &params).map(|s| (s, None)),
            (false, false) => qp::cg::solve(&dual, &b, &y0, &params).map(|s| (s, None)),
        };
        r.map_err(|e| Error::numerical(if orthogonal { format!("SMALSE-M ({name})") } else { name.to_uppercase() }, e.to_string()))
    })?;
    let rec = t.phase(comm, "recover", || {
        // SMALSE-M's λ̃ satisfies Gλ̃ = 0 to ε: λ̂ + P̃ᵀλ̃ closes it exactly (E rows only)
        Ok(dual.recover(&sol.lambda))
    })?;
    let feasibility = rec.feasibility;
    let distribution = DistributionStats::new(&dual.dist);
    let mut solution = finish(comm, model, &d, &dual, &rec.u, &rec.rhs, &owner, t)?;
    // finish filled the gathered figures (subdomains, gluing jump); add the global ones
    let f = solution.tfeti.get_or_insert_with(TfetiInfo::default);
    f.element_subdomain = d.elem_subdomain(mesh.hexes.len());
    f.contact_rows = cons.e_start();
    f.gluing_rows = cons.gluing_rows;
    f.dirichlet_rows = cons.dirichlet_rows;
    f.coarse_dim = coarse_dim;
    f.nnz_c = nnz_c;
    f.feasibility = feasibility;
    f.smalse = smalse;
    f.distribution = distribution;
    let outcome = contact.map(|c| {
        let set_i = Lambda::new(c);
        // the contact multipliers and the gap c − Bu from the recovered u (= the solvers'
        // gradient on the I rows), whole on every rank
        let ni = set_i.layout.dim();
        let (li, ri) = (dual.dist.all_rows(&rec.lambda, ni), dual.dist.all_rows(&rec.gap, ni));
        let bnorm = dual.norm(&b);
        let state = contact_state(c, &set_i, &li, &ri, s.eps.max(1e-9), bnorm);
        let kkt = qp::kkt::residuals(&set_i, &li, &ri, bnorm);
        ContactOutcome { dim: dual.count(dual.dim()), state, info: sol.info.clone(), bnorm, kkt }
    });
    Ok((solution, outcome))
}

/// Checks K_s u_s = f_s − B_sᵀλ, computes the element stresses (phase `stress`) and gathers u,
/// the stresses and the figures on rank 0 (phase `gather`), with the gluing jumps.
#[allow(clippy::too_many_arguments)]
fn finish<C: Comm>(
    comm: &C,
    model: &Model,
    d: &Decomposition,
    dual: &TfetiDual<'_, C>,
    u: &[Vec<f64>],
    rhs: &[Vec<f64>],
    owner: &[usize],
    t: &mut Timings,
) -> Result<Solution> {
    let mesh = &model.mesh;
    let (packed, local) = t.phase(comm, "stress", || {
        let mut buf = Vec::new();
        let mut local = LocalFields::default();
        for ((ls, us), f) in dual.subs.iter().zip(u).zip(rhs) {
            let s = ls.sys.index;
            let sd = &d.subdomains[s];
            let ku = ls.sys.k.mul(us);
            let rn = ku.iter().zip(f).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
            let fnorm = f.iter().map(|v| v * v).sum::<f64>().sqrt();
            let residual = if fnorm > 0.0 { rn / fnorm } else { rn };
            if !residual.is_finite() || residual > 1e-6 {
                return Err(Error::numerical(
                    format!("subdomain {s} (body \"{}\")", mesh.bodies[sd.body].name),
                    format!("recovered u does not satisfy K_s u_s = f_s − B_sᵀλ (relative residual {residual:.1e})"),
                ));
            }
            buf.extend(us);
            // this rank's rows for the file: a node from the subdomain of its first copy
            for (l, &v) in sd.nodes.iter().enumerate().filter(|(_, &v)| d.copies[v][0].0 == s) {
                local.nodes.push(v);
                local.displacement.push([us[3 * l], us[3 * l + 1], us[3 * l + 2]]);
            }
            for &e in &sd.elems {
                let ue = mesh.hexes[e].map(|v| {
                    let l = sd.local(v).expect("element node in subdomain");
                    [us[3 * l], us[3 * l + 1], us[3 * l + 2]]
                });
                let vm = von_mises(&hex8_center_stress(&mesh.hex_coords(e), &ue, model.lame[sd.body]));
                buf.push(vm);
                local.cells.push(e);
                local.von_mises.push(vm);
            }
            buf.extend([ls.sys.k.nnz() as f64, ls.sys.nnz_l() as f64, residual]);
        }
        Ok((buf, local))
    })?;
    let mut sol = t.phase(comm, "gather", || {
        let Some(all) = comm.gather_f64(0, &packed) else {
            return Ok(Solution::default());
        };
        let mut cursor = vec![0usize; comm.size()];
        let mut sol = Solution {
            displacement: vec![[0.0; 3]; mesh.nodes.len()],
            von_mises: vec![0.0; mesh.hexes.len()],
            ..Default::default()
        };
        let mut seen = vec![false; mesh.nodes.len()];
        let mut copies_u: Vec<(usize, [f64; 3])> = Vec::new();
        let mut stats = Vec::with_capacity(d.subdomains.len());
        // subdomains in the order each rank packed them (ascending index per rank)
        for (s, sd) in d.subdomains.iter().enumerate() {
            let r = owner[s];
            let data = &all[r];
            let mut p = cursor[r];
            for &v in &sd.nodes {
                let uv = [data[p], data[p + 1], data[p + 2]];
                if seen[v] {
                    copies_u.push((v, uv));
                } else {
                    sol.displacement[v] = uv;
                    seen[v] = true;
                }
                p += 3;
            }
            for &e in &sd.elems {
                sol.von_mises[e] = data[p];
                p += 1;
            }
            stats.push(SubdomainStats {
                body: sd.body,
                nodes: sd.nodes.len(),
                elements: sd.elems.len(),
                interface_nodes: sd.nodes.iter().filter(|&&v| d.copies[v].len() > 1).count(),
                nnz_k: data[p] as usize,
                nnz_l: data[p + 1] as usize,
                residual: data[p + 2],
                rank: r,
            });
            cursor[r] = p + 3;
        }
        let umax = sol.displacement.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs())).max(f64::MIN_POSITIVE);
        let jump = copies_u
            .iter()
            .map(|(v, uv)| (0..3).map(|c| (uv[c] - sol.displacement[*v][c]).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        sol.bodies = mesh
            .bodies
            .iter()
            .enumerate()
            .map(|(b, body)| {
                let mine = stats.iter().filter(|x| x.body == b);
                BodyStats {
                    name: body.name.clone(),
                    nodes: body.nodes.len(),
                    elements: body.elems.len(),
                    free_dofs: mine.clone().map(|x| 3 * x.nodes).sum(),
                    nnz_k: mine.clone().map(|x| x.nnz_k).sum(),
                    nnz_l: mine.clone().map(|x| x.nnz_l).sum(),
                    residual: mine.clone().map(|x| x.residual).fold(0.0, f64::max),
                    rank: mine.map(|x| x.rank).min().unwrap_or(0),
                }
            })
            .collect();
        sol.tfeti = Some(TfetiInfo { subdomains: stats, gluing_jump: jump / umax, ..Default::default() });
        Ok(sol)
    })?;
    sol.local = local;
    sol.element_rank = d.elem_subdomain(mesh.hexes.len()).into_iter().map(|s| owner[s]).collect();
    Ok(sol)
}
