//! TFETI against the monolithic dual: the same u (within 1e-8 relative at ε = 1e-12), the same
//! open/stick/slip status, glued copies equal (jumps ≤ 1e-10) and Dirichlet values held, for
//! the seed scene at N = 8 and 12 with S = 1, 2, 4, 8 subdomains per body, for a Gmsh-imported
//! mesh, and without contact (CG on the dual against the direct solve).

use std::path::Path;

use tresca_feti::comm::SerialComm;
use tresca_feti::model::{self, Model};
use tresca_feti::pipeline::{self, ContactOutcome, Solution, Timings};
use tresca_feti::scene::{self, LoadedScene};

fn load(scene: &str, sets: &[String]) -> (LoadedScene, Model) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
    let ls = scene::load(&path, sets).unwrap();
    let model = model::build(&ls).unwrap();
    (ls, model)
}

/// Monolithic (`parts` = 0) or TFETI with `parts` subdomains per body.
fn solve(scene: &str, sets: &[String], parts: usize) -> (Solution, Option<ContactOutcome>) {
    let mut sets = sets.to_vec();
    if parts > 0 {
        sets.push(format!("decomposition.subdomains={parts}"));
        sets.push("decomposition.tfeti=true".into());
    }
    let (ls, model) = load(scene, &sets);
    let mut t = Timings::default();
    if parts == 0 {
        match model.pairs {
            Some(_) => pipeline::solve_contact(&SerialComm, &ls, &model, &mut t).map(|(s, o)| (s, Some(o))).unwrap(),
            None => (pipeline::solve_elastic(&SerialComm, &model, ls.scene.factorization.ordering, &mut t).unwrap(), None),
        }
    } else {
        pipeline::tfeti::solve(&SerialComm, &ls, &model, &mut t).unwrap()
    }
}

fn max_abs(u: &[[f64; 3]]) -> f64 {
    u.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()))
}

/// Compares every decomposition with the monolithic solution (u within 1e-8 relative, jumps
/// and Dirichlet values within 1e-10); returns the worst relative difference in u.
fn equivalence(scene: &str, sets: &[String], parts: &[usize]) -> f64 {
    equivalence_within(scene, sets, parts, 1e-8, 1e-10)
}

fn equivalence_within(scene: &str, sets: &[String], parts: &[usize], tol_u: f64, tol_jump: f64) -> f64 {
    let (mono, mono_c) = solve(scene, sets, 0);
    let umax = max_abs(&mono.displacement);
    let (_, model) = load(scene, sets);
    let mut worst: f64 = 0.0;
    for &s in parts {
        let (sol, out) = solve(scene, sets, s);
        let f = sol.tfeti.as_ref().expect("TFETI figures");
        assert_eq!(f.subdomains.len(), s * model.mesh.bodies.len());
        let du = mono
            .displacement
            .iter()
            .zip(&sol.displacement)
            .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
            .fold(0.0f64, f64::max)
            / umax;
        eprintln!(
            "{scene} {sets:?} S={s}: max|Δu|/max|u| = {du:.2e}, gluing jump {:.2e}, ‖Gλ−e‖/‖e‖ {:.2e}, nA {:?}",
            f.gluing_jump,
            f.feasibility,
            out.as_ref().map(|o| o.info.n_a)
        );
        assert!(du <= tol_u, "S = {s}: u differs from the monolithic solution by {du:.2e} (relative)");
        assert!(f.gluing_jump <= tol_jump, "S = {s}: gluing jump {:.2e}", f.gluing_jump);
        assert!(f.feasibility <= 1e-10, "S = {s}: ‖Gλ − e‖/‖e‖ = {:.2e}", f.feasibility);
        // Dirichlet values: every constrained DOF holds its value (all copies: the jumps above)
        for &(v, c, val) in &model.constraints {
            let e = (sol.displacement[v][c] - val).abs() / umax;
            assert!(e <= tol_jump, "S = {s}: Dirichlet DOF ({v}, {c}) off by {e:.2e}");
        }
        if let (Some(a), Some(b)) = (&mono_c, &out) {
            assert_eq!(a.state.status, b.state.status, "S = {s}: open/stick/slip status differs");
            assert!(b.kkt.worst() <= 1e-8, "S = {s}: KKT {:?}", b.kkt);
        }
        worst = worst.max(du);
    }
    worst
}

fn seed(n: usize, extra: &[&str]) -> Vec<String> {
    let mut v = vec![format!("mesh.n={n}"), "solver.eps=1e-12".to_string()];
    v.extend(extra.iter().map(|s| s.to_string()));
    v
}

#[test]
fn seed_n8_matches_the_monolithic_dual_for_1_2_4_8_subdomains() {
    equivalence("run/seed.toml", &seed(8, &[]), &[1, 2, 4, 8]);
}

#[test]
fn seed_n12_matches_the_monolithic_dual_for_1_2_4_8_subdomains() {
    equivalence("run/seed.toml", &seed(12, &[]), &[1, 2, 4, 8]);
}

#[test]
fn prescribed_nonzero_displacement_orthotropic_friction_and_chain_gluing() {
    // non-zero Dirichlet values exercise c_E; an ellipse the orthotropic sets; the ±1 gluing
    let extra = ["dirichlet.1.value=[1e-5, -2e-5, 3e-6]", "contact.pair.0.friction={type=\"orthotropic\", g1=0.09, g2=0.03, direction=[1.0, 0.0, 0.0]}"];
    equivalence("run/seed.toml", &seed(8, &extra), &[4]);
    let mut chain = seed(8, &extra);
    chain.push("decomposition.gluing=\"chain\"".into());
    equivalence("run/seed.toml", &chain, &[4]);
}

#[test]
fn gmsh_mesh_matches_the_monolithic_dual() {
    equivalence("run/gmsh_blocks.toml", &["solver.eps=1e-12".to_string()], &[1, 2, 4]);
}

#[test]
fn without_contact_cg_on_the_dual_matches_the_direct_solve() {
    equivalence("run/seed.toml", &seed(8, &["contact.enabled=false"]), &[1, 4]);
}

#[test]
fn smalse_with_the_orthogonal_projector_matches_too() {
    let sets = seed(8, &["decomposition.projector=\"orthogonal\""]);
    equivalence("run/seed.toml", &sets, &[1, 4]);
}

#[test]
fn all_five_solvers_run_unchanged_on_the_tfeti_dual() {
    for method in ["gimssn", "imssn", "mssn", "mpgp", "ssn-bicgstab"] {
        let sets = vec!["mesh.n=6".to_string(), "solver.eps=1e-9".to_string(), format!("solver.method=\"{method}\"")];
        let worst = equivalence_within("run/seed.toml", &sets, &[4], 1e-6, 1e-7);
        eprintln!("{method}: max|Δu|/max|u| = {worst:.2e}");
    }
}
