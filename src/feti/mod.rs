//! Total FETI (docs/method.md, "TFETI and H-TFETI"): every body split into floating subdomains (the METIS partition,
//! [`decomposition`]; [`subdomain`]: K_s, R_s, K_s⁺), optionally grouped into H-TFETI clusters
//! that the outer dual treats as its pieces ([`cluster`]: K_c⁺, R_c), the constraint rows
//! B = [B_I; B_E] and c ([`constraints`]), the natural coarse space G = RᵀBᵀ, e = Rᵀf and the projectors
//! ([`coarse`]; also the inner solves' coarse space restricted to a Newton step), the dual
//! operator on which the QP solvers run unchanged ([`dual`]) and the FETI preconditioner of the
//! whole dual ([`precond`]). It is a
//! transform of the QP: λ = λ̂ + P̃ᵀy maps the solvers' variable y ∈ Ker G_E × Λ onto the
//! feasible multipliers, and [`dual::TfetiDual::recover_with`] maps the solution back to λ, α and u.

pub(crate) mod cluster;
pub(crate) mod coarse;
pub(crate) mod constraints;
pub(crate) mod decomposition;
pub(crate) mod distribution;
pub(crate) mod dual;
pub(crate) mod precond;
pub(crate) mod restricted;
pub(crate) mod smalse;
pub(crate) mod subdomain;

use crate::feti::decomposition::Decomposition;
use crate::mesh::Mesh;
use crate::scene::DirichletMode;

/// f_s of the subdomains `subs` (per local DOF 3·l + c; empty for the others): each node's load
/// goes to its first copy.
pub fn subdomain_loads(d: &Decomposition, loads: &[f64], subs: &[usize]) -> Vec<Vec<f64>> {
    let mut f: Vec<Vec<f64>> = vec![Vec::new(); d.subdomains.len()];
    for &s in subs {
        let sd = &d.subdomains[s];
        f[s] = vec![0.0; 3 * sd.nodes.len()];
        for (l, &v) in sd.nodes.iter().enumerate() {
            if d.copies[v][0].0 == s {
                f[s][3 * l..3 * l + 3].copy_from_slice(&loads[3 * v..3 * v + 3]);
            }
        }
    }
    f
}

/// Per subdomain, the local DOFs (ascending) held inside it: with [`DirichletMode::Eliminated`]
/// every prescribed DOF (`dirichlet`: node, component, value) of a subdomain whose held DOFs
/// leave its rigid motions either free or firmly held ([`subdomain::held_kernel`]); none with
/// [`DirichletMode::Multipliers`] or elsewhere (those copies keep their rows).
pub fn eliminated(mesh: &Mesh, d: &Decomposition, dirichlet: &[(usize, usize, f64)], mode: DirichletMode) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new(); d.subdomains.len()];
    if mode == DirichletMode::Multipliers {
        return out;
    }
    for &(v, k, _) in dirichlet {
        for &(s, l) in &d.copies[v] {
            out[s].push(3 * l + k);
        }
    }
    for (held, sd) in out.iter_mut().zip(&d.subdomains) {
        held.sort_unstable();
        held.dedup();
        if !held.is_empty() {
            let coords: Vec<[f64; 3]> = sd.nodes.iter().map(|&v| mesh.nodes[v]).collect();
            let interface: Vec<usize> =
                (0..3 * sd.nodes.len()).filter(|&dof| d.copies[sd.nodes[dof / 3]].len() > 1 && held.binary_search(&dof).is_err()).collect();
            if subdomain::held_kernel(&coords, held).is_none() || subdomain::hold_ratio(&coords, held, &interface) < subdomain::HOLD_RATIO {
                held.clear();
            }
        }
    }
    out
}

/// Rank of every piece (subdomain, or cluster of them) with `dofs[s]` DOFs and the rows `cons`:
/// a METIS k-way partition of the piece graph (an edge where rows of B couple two pieces,
/// weighted by their number; vertices weighted by DOFs), so that a rank's pieces lie together
/// and its ghost rows are the ones across rank borders; the greedy assignment (largest first
/// onto the least loaded rank) where METIS balances the DOFs worse than 1.05× of it, or there
/// are fewer pieces than ranks. Deterministic.
pub fn assign_ranks(dofs: &[usize], cons: &constraints::Constraints, ranks: usize) -> Vec<usize> {
    let ns = dofs.len();
    let greedy = greedy_ranks(dofs, ranks);
    if ranks <= 1 || ns <= ranks {
        return greedy;
    }
    let max_load = |owner: &[usize]| {
        let mut load = vec![0usize; ranks];
        owner.iter().zip(dofs).for_each(|(&r, &n)| load[r] += n);
        load.into_iter().max().unwrap_or(0)
    };
    match graph_ranks(ns, cons, dofs, ranks) {
        Some(owner) if (max_load(&owner) as f64) <= 1.05 * max_load(&greedy) as f64 => owner,
        _ => greedy,
    }
}

/// Largest first onto the least loaded rank (by DOFs).
fn greedy_ranks(dofs: &[usize], ranks: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..dofs.len()).collect();
    order.sort_by_key(|&s| (std::cmp::Reverse(dofs[s]), s));
    let mut load = vec![0usize; ranks.max(1)];
    let mut owner = vec![0; dofs.len()];
    for s in order {
        let r = (0..ranks.max(1)).min_by_key(|&r| (load[r], r)).expect("at least one rank");
        owner[s] = r;
        load[r] += dofs[s];
    }
    owner
}

/// METIS k-way parts of the subdomain graph; `None` if METIS fails or leaves a rank empty.
fn graph_ranks(ns: usize, cons: &constraints::Constraints, dofs: &[usize], ranks: usize) -> Option<Vec<usize>> {
    // (row, subdomain) pairs, sorted: each row's subdomains together (one flat array)
    let mut pairs: Vec<(usize, usize)> = cons.rows.iter().enumerate().flat_map(|(s, rows)| rows.iter().map(move |&(r, _, _)| (r, s))).collect();
    pairs.sort_unstable();
    pairs.dedup();
    let mut weight: std::collections::BTreeMap<(usize, usize), usize> = Default::default();
    for group in pairs.chunk_by(|x, y| x.0 == y.0) {
        for (i, &(_, a)) in group.iter().enumerate() {
            for &(_, b) in &group[i + 1..] {
                *weight.entry((a, b)).or_default() += 1;
            }
        }
    }
    drop(pairs);
    let mut adj: Vec<Vec<(usize, usize)>> = vec![Vec::new(); ns];
    for (&(a, b), &w) in &weight {
        adj[a].push((b, w));
        adj[b].push((a, w));
    }
    let owner = kway(adj, dofs, ranks, false)?;
    let mut used = vec![false; ranks];
    owner.iter().for_each(|&r| used[r] = true);
    used.iter().all(|&u| u).then_some(owner)
}

/// METIS k-way parts of a weighted graph (`adj[v]`: (neighbour, edge weight); `vwgt`: vertex
/// weights), `contig`: connected parts; `None` if METIS fails. Serialized and seeded: the same
/// parts on every rank.
pub(crate) fn kway(mut adj: Vec<Vec<(usize, usize)>>, vwgt: &[usize], parts: usize, contig: bool) -> Option<Vec<usize>> {
    let idx = |v: usize| metis::Idx::try_from(v).ok();
    let (mut xadj, mut adjncy, mut adjwgt) = (vec![0], Vec::new(), Vec::new());
    for list in &mut adj {
        list.sort_unstable();
        for &(b, w) in list.iter() {
            adjncy.push(idx(b)?);
            adjwgt.push(idx(w)?);
        }
        xadj.push(idx(adjncy.len())?);
    }
    let vwgt: Vec<metis::Idx> = vwgt.iter().map(|&n| idx(n)).collect::<Option<_>>()?;
    let mut part = vec![0; adj.len()];
    let nparts = idx(parts)?;
    crate::linalg::ordering::metis_exclusive(|| {
        metis::Graph::new(1, nparts, &xadj, &adjncy)
            .ok()?
            .set_vwgt(&vwgt)
            .set_adjwgt(&adjwgt)
            .set_option(metis::option::Contig(contig))
            .set_option(metis::option::Seed(1))
            .part_kway(&mut part)
            .ok()
    })?;
    Some(part.into_iter().map(|p| p as usize).collect())
}

/// The seed scene at N = `n`, `parts` subdomains per body, and its constraint rows (orthonormal
/// gluing): the fixture of the TFETI unit tests.
#[cfg(test)]
pub(crate) fn seed_fixture(n: usize, parts: usize) -> (crate::model::Model, decomposition::Decomposition, constraints::Constraints) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("run/seed.toml");
    let ls = crate::scene::load(&path, &[format!("mesh.n={n}")]).unwrap();
    let model = crate::model::build(&ls).unwrap();
    let d = decomposition::decompose(&model.mesh, parts).unwrap();
    let cons = constraints::build(&d, &model.constraints, model.pairs.as_ref(), &model.ties, crate::scene::Gluing::Orthonormal, &[]);
    (model, d, cons)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows of B whose subdomains lie on more than one rank, and the largest rank load (DOFs).
    fn crossing_and_load(d: &Decomposition, cons: &constraints::Constraints, owner: &[usize], ranks: usize) -> (usize, usize) {
        let mut rank_of_row: std::collections::HashMap<usize, std::collections::BTreeSet<usize>> = Default::default();
        for (s, rows) in cons.rows.iter().enumerate() {
            for &(r, _, _) in rows {
                rank_of_row.entry(r).or_default().insert(owner[s]);
            }
        }
        let mut load = vec![0; ranks];
        d.subdomains.iter().zip(owner).for_each(|(sd, &r)| load[r] += 3 * sd.nodes.len());
        (rank_of_row.values().filter(|v| v.len() > 1).count(), load.into_iter().max().unwrap())
    }

    #[test]
    fn ranks_hold_neighbouring_subdomains_with_balanced_dofs() {
        let (_, d, cons) = seed_fixture(8, 8);
        let dofs: Vec<usize> = d.subdomains.iter().map(|s| 3 * s.nodes.len()).collect();
        for ranks in [2, 3, 4] {
            let owner = assign_ranks(&dofs, &cons, ranks);
            let (cross, load) = crossing_and_load(&d, &cons, &owner, ranks);
            let (cross_greedy, load_greedy) = crossing_and_load(&d, &cons, &greedy_ranks(&dofs, ranks), ranks);
            // two ranks: one body each, only the contact rows cross
            let factor = if ranks == 2 { 2 } else { 1 };
            assert!(factor * cross < cross_greedy, "{ranks} ranks: {cross} rows cross ranks, greedy {cross_greedy}");
            assert!(load as f64 <= 1.05 * load_greedy as f64, "{ranks} ranks: load {load} against {load_greedy}");
            assert_eq!(owner, assign_ranks(&dofs, &cons, ranks), "deterministic");
        }
        assert_eq!(assign_ranks(&dofs, &cons, 1), vec![0; 16]);
        // more ranks than subdomains: one subdomain per rank, the largest first
        let owner = assign_ranks(&dofs, &cons, 20);
        assert_eq!(owner.iter().collect::<std::collections::BTreeSet<_>>().len(), 16);
    }
}
