//! Total FETI (DESIGN §2): every body split into floating subdomains (the METIS partition,
//! [`decomposition`]; [`subdomain`]: K_s, R_s, K_s⁺), the constraint rows B = [B_I; B_E] and c
//! ([`constraints`]), the natural coarse space G = RᵀBᵀ, e = Rᵀf and the projectors
//! ([`coarse`]; also the inner solves' coarse space restricted to a Newton step), the dual
//! operator on which the QP solvers run unchanged ([`dual`]) and the FETI preconditioner of the
//! whole dual ([`precond`]). It is a
//! transform of the QP: λ = λ̂ + P̃ᵀy maps the solvers' variable y ∈ Ker G_E × Λ onto the
//! feasible multipliers, and `DualProblem::recover` of [`dual::TfetiDual`] maps the solution back to λ, α and u.

pub mod coarse;
pub mod constraints;
pub mod decomposition;
pub mod distribution;
pub mod dual;
pub mod precond;
pub mod smalse;
pub mod subdomain;

use crate::feti::decomposition::Decomposition;
use crate::mesh::Mesh;
use crate::scene::DirichletMode;

/// f_s for every subdomain (per local DOF 3·l + c): each node's load goes to its first copy.
pub fn subdomain_loads(d: &Decomposition, loads: &[f64]) -> Vec<Vec<f64>> {
    let mut f: Vec<Vec<f64>> = d.subdomains.iter().map(|sd| vec![0.0; 3 * sd.nodes.len()]).collect();
    for (v, copies) in d.copies.iter().enumerate() {
        let (s, l) = copies[0];
        f[s][3 * l..3 * l + 3].copy_from_slice(&loads[3 * v..3 * v + 3]);
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
            let interface: Vec<usize> = (0..3 * sd.nodes.len()).filter(|&dof| d.copies[sd.nodes[dof / 3]].len() > 1 && held.binary_search(&dof).is_err()).collect();
            if subdomain::held_kernel(&coords, held).is_none() || subdomain::hold_ratio(&coords, held, &interface) < subdomain::HOLD_RATIO {
                held.clear();
            }
        }
    }
    out
}

/// The values g of the held DOFs `eliminated` (per subdomain, as [`eliminated`] gives them)
/// from the prescribed list `dirichlet` (a later entry for the same DOF winning).
pub fn held_values(d: &Decomposition, eliminated: &[Vec<usize>], dirichlet: &[(usize, usize, f64)]) -> Vec<Vec<f64>> {
    let value: std::collections::HashMap<(usize, usize), f64> = dirichlet.iter().map(|&(v, k, x)| ((v, k), x)).collect();
    eliminated
        .iter()
        .zip(&d.subdomains)
        .map(|(held, sd)| held.iter().map(|&dof| value[&(sd.nodes[dof / 3], dof % 3)]).collect())
        .collect()
}

/// Rank of every subdomain: largest first onto the least loaded rank (by DOFs), deterministic.
pub fn assign_ranks(d: &Decomposition, ranks: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..d.subdomains.len()).collect();
    order.sort_by_key(|&s| (std::cmp::Reverse(d.subdomains[s].nodes.len()), s));
    let mut load = vec![0usize; ranks];
    let mut owner = vec![0; d.subdomains.len()];
    for s in order {
        let r = (0..ranks).min_by_key(|&r| (load[r], r)).expect("at least one rank");
        owner[s] = r;
        load[r] += d.subdomains[s].nodes.len();
    }
    owner
}

/// The seed scene at N = `n`, `parts` subdomains per body, and its constraint rows (orthonormal
/// gluing): the fixture of the TFETI unit tests.
#[cfg(test)]
pub(crate) fn seed_fixture(n: usize, parts: usize) -> (crate::model::Model, decomposition::Decomposition, constraints::Constraints) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("run/seed.toml");
    let ls = crate::scene::load(&path, &[format!("mesh.n={n}")]).unwrap();
    let model = crate::model::build(&ls).unwrap();
    let d = decomposition::decompose(&model.mesh, parts).unwrap();
    let cons = constraints::build(&d, &model.constraints, model.pairs.as_ref(), crate::scene::Gluing::Orthonormal, &[]);
    (model, d, cons)
}
