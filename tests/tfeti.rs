//! TFETI against the monolithic dual: the same u (within 1e-8 relative at ε = 1e-12), the same
//! open/stick/slip status, glued copies equal (jumps ≤ 1e-10) and Dirichlet values held, for
//! the seed scene at N = 8 and 12 with S = 1, 2, 4, 8 subdomains per body, for a Gmsh-imported
//! mesh, and without contact (CG on the dual against the direct solve); Dirichlet conditions as
//! multiplier rows and eliminated inside the subdomains alike (plane-strain slabs, seed). Subdomain-count
//! independence per solver (SSN-BiCGSTAB, GIMSSN) at stated tolerances: u, the contact normal
//! pressure, and the open/stick/slip counts of S = 1, 2, 4, 8 against the monolithic dual.

use std::path::Path;

use tresca_feti::comm::SerialComm;
use tresca_feti::contact::state;
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
    } else {
        // the FETI preconditioners act on TFETI's gluing rows: the monolithic dual takes none
        sets.retain(|s| !s.starts_with("solver.preconditioner="));
    }
    let (ls, mut model) = load(scene, &sets);
    let mut t = Timings::default();
    if parts == 0 {
        match model.pairs {
            Some(_) => pipeline::solve_contact(&SerialComm, &ls, &model, &mut t).map(|(s, o)| (s, Some(o))).unwrap(),
            None => (pipeline::solve_elastic(&SerialComm, &model, ls.scene.factorization.ordering, &mut t).unwrap(), None),
        }
    } else {
        pipeline::tfeti::solve(&SerialComm, &ls, &mut model, &mut t).unwrap()
    }
}

fn max_abs(u: &[[f64; 3]]) -> f64 {
    u.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()))
}

/// Compares every decomposition with the monolithic solution (u within 3e-10 relative, jumps
/// and Dirichlet values within 1e-10); returns the worst relative difference in u. At
/// ε = 1e-12 the differences measured 2026-12-05 were 5.0e-12 … 1.4e-11 on the seed (N = 8,
/// 12; S = 1 … 8), up to 1.1e-10 on the roller slabs: the bound is about 2× the worst.
fn equivalence(scene: &str, sets: &[String], parts: &[usize]) -> f64 {
    equivalence_within(scene, sets, parts, 3e-10, 1e-10)
}

/// How one decomposition compares with the monolithic solution of the same scene.
#[derive(Debug)]
struct Agreement {
    subdomains: usize,
    /// max|Δu| / max|u_mono|.
    du: f64,
    gluing_jump: f64,
    /// ‖Gλ − e‖/‖e‖.
    feasibility: f64,
    /// Worst constrained DOF off its prescribed value, relative to max|u_mono|.
    dirichlet: f64,
    /// max|Δp| / max|p_mono| over the contact pairs, p = λν/w the normal pressure (0 without contact).
    dp: f64,
    /// (open, stick, slip) counts, monolithic and decomposed (contact only).
    counts: Option<([usize; 3], [usize; 3])>,
    /// The status of every pair is the same.
    same_status: bool,
    /// Worst KKT residual of the decomposed solve (contact only).
    kkt: Option<f64>,
}

fn counts(o: &ContactOutcome) -> [usize; 3] {
    [state::OPEN, state::STICK, state::SLIP].map(|s| o.state.count(s))
}

/// Solves `scene` monolithically and with each of `parts` subdomains per body, and compares.
fn agreement(scene: &str, sets: &[String], parts: &[usize]) -> Vec<Agreement> {
    let (mono, mono_c) = solve(scene, sets, 0);
    let umax = max_abs(&mono.displacement);
    let (_, model) = load(scene, sets);
    let pressure = |o: &ContactOutcome| -> Vec<f64> {
        let c = model.pairs.as_ref().expect("contact pairs");
        o.state.normal_force.iter().zip(&c.area).map(|(f, w)| f / w).collect()
    };
    let mut out = Vec::new();
    for &s in parts {
        let (sol, dec_c) = solve(scene, sets, s);
        let f = sol.tfeti.as_ref().expect("TFETI figures");
        assert_eq!(f.subdomains.len(), s * model.mesh.bodies.len());
        let du = mono.displacement.iter().zip(&sol.displacement).flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs())).fold(0.0f64, f64::max) / umax;
        let dirichlet = model.constraints.iter().map(|&(v, c, val)| (sol.displacement[v][c] - val).abs() / umax).fold(0.0f64, f64::max);
        let (mut dp, mut cnt, mut same_status, mut kkt) = (0.0, None, true, None);
        if let (Some(a), Some(b)) = (&mono_c, &dec_c) {
            let (pa, pb) = (pressure(a), pressure(b));
            let pmax = pa.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            dp = pa.iter().zip(&pb).map(|(x, y)| (x - y).abs()).fold(0.0f64, f64::max) / pmax;
            cnt = Some((counts(a), counts(b)));
            same_status = a.state.status == b.state.status;
            kkt = Some(b.kkt.worst());
        }
        let a = Agreement { subdomains: s, du, gluing_jump: f.gluing_jump, feasibility: f.feasibility, dirichlet, dp, counts: cnt, same_status, kkt };
        eprintln!(
            "{scene} {sets:?} S={s}: max|Δu|/max|u| = {du:.2e}, max|Δp|/max|p| = {dp:.2e}, gluing jump {:.2e}, ‖Gλ−e‖/‖e‖ {:.2e}, (open, stick, slip) {:?}, nA {:?}",
            a.gluing_jump,
            a.feasibility,
            a.counts,
            dec_c.as_ref().map(|o| o.info.n_a)
        );
        out.push(a);
    }
    out
}

fn equivalence_within(scene: &str, sets: &[String], parts: &[usize], tol_u: f64, tol_jump: f64) -> f64 {
    let mut worst: f64 = 0.0;
    for a in agreement(scene, sets, parts) {
        let s = a.subdomains;
        eprintln!("S = {s}: u within {:.2e} of the monolithic solution, gluing jump {:.2e}", a.du, a.gluing_jump);
        assert!(a.du <= tol_u, "S = {s}: u differs from the monolithic solution by {:.2e} (relative)", a.du);
        assert!(a.gluing_jump <= tol_jump, "S = {s}: gluing jump {:.2e}", a.gluing_jump);
        assert!(a.feasibility <= 1e-10, "S = {s}: ‖Gλ − e‖/‖e‖ = {:.2e}", a.feasibility);
        // Dirichlet values: every constrained DOF holds its value (all copies: the jumps above)
        assert!(a.dirichlet <= tol_jump, "S = {s}: a Dirichlet DOF is off by {:.2e}", a.dirichlet);
        assert!(a.same_status, "S = {s}: open/stick/slip status differs");
        if let Some(k) = a.kkt {
            assert!(k <= 1e-8, "S = {s}: KKT {k:.2e}");
        }
        worst = worst.max(a.du);
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
fn coulomb_friction_matches_the_monolithic_dual() {
    // TFETI's default is TSSN with lagged bounds, the monolithic dual's the Newton method on the
    // law (the fixed point for the orthotropic cone); the fixed point on TFETI too: all pairs
    // slide at μ = 0.1, all stick at μ = 0.3 (seed N = 8, measured); the KKT residuals are taken
    // against the cones cut at the solution's λν
    for friction in ["{type=\"coulomb\", mu=0.1}", "{type=\"coulomb\", mu=0.3}", "{type=\"coulomb\", mu1=0.15, mu2=0.05, direction=[1.0, 1.0, 0.0]}"] {
        let f = format!("contact.pair.0.friction={friction}");
        equivalence_within("run/seed.toml", &seed(6, &[f.as_str()]), &[2], 1e-7, 1e-9);
    }
    let fp = ["contact.pair.0.friction={type=\"coulomb\", mu=0.3}", "solver.coulomb=\"fixed-point\""];
    equivalence_within("run/seed.toml", &seed(6, &fp), &[2], 1e-7, 1e-9);
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
fn dirichlet_rows_and_eliminated_dirichlet_dofs_match_alike() {
    // the plane-strain slabs (rollers on every y face: a third of the DOFs held, coarsened) and
    // the seed: with every Dirichlet row kept, and with the held DOFs eliminated inside the
    // subdomains (the default; partly, where the hold is firm enough)
    let slabs = |mode: &str| {
        let mut v: Vec<String> = [
            "body.0.box={min=[0.0, 0.0, 1.0], max=[4.0, 0.1, 2.0], nodes=[21, 2, 6]}",
            "body.1.box={min=[0.0, 0.0, 0.0], max=[4.0, 0.1, 1.0], nodes=[21, 2, 6]}",
            "solver.eps=1e-12",
        ]
        .map(String::from)
        .to_vec();
        v.push(format!("decomposition.dirichlet=\"{mode}\""));
        v
    };
    for mode in ["multipliers", "eliminated"] {
        equivalence("run/bench/plane_strain_rollers.toml", &slabs(mode), &[1, 4]);
        equivalence("run/seed.toml", &seed(8, &[&format!("decomposition.dirichlet=\"{mode}\"")]), &[1, 4]);
    }
    // rows or elimination show in the multiplier count; S = 1: every held DOF eliminated
    let count = |mode: &str, parts: usize| {
        let (sol, _) = solve("run/bench/plane_strain_rollers.toml", &slabs(mode), parts);
        let f = sol.tfeti.expect("TFETI figures");
        (f.dirichlet_rows, f.eliminated_dofs, f.coarse_dim)
    };
    let (_, model) = load("run/bench/plane_strain_rollers.toml", &slabs("eliminated"));
    let held = model.constraints.iter().map(|&(v, c, _)| (v, c)).collect::<std::collections::BTreeSet<_>>().len();
    assert_eq!(count("multipliers", 1), (held, 0, 12));
    assert_eq!(count("eliminated", 1), (0, held, 0));
    let (_, elim, coarse) = count("eliminated", 4);
    assert!(elim >= held && coarse < 48, "S = 4: {elim} eliminated, coarse {coarse}");
    // the seed at S = 4: the subdomains that touch the clamped faces by a patch keep their rows
    let (sol, _) = solve("run/seed.toml", &seed(8, &[]), 4);
    let f = sol.tfeti.expect("TFETI figures");
    assert!(f.dirichlet_rows > 0 && f.eliminated_dofs > 0, "seed S = 4: {} rows, {} eliminated", f.dirichlet_rows, f.eliminated_dofs);
}

/// H-TFETI: 8 subdomains per body in clusters of 4 (two per body) and 8 (one per body; the
/// coarse problem is then six unknowns per floating cluster at most): the monolithic u, with
/// the default TSSN + lumped, with the Dirichlet preconditioner, SMALSE-M's orthogonal
/// projector, and without contact.
#[test]
fn htfeti_clusters_match_the_monolithic_dual() {
    for extra in [
        vec!["decomposition.subdomains_per_cluster=4"],
        vec!["decomposition.subdomains_per_cluster=8", "solver.preconditioner=\"dirichlet\""],
        vec!["decomposition.subdomains_per_cluster=4", "decomposition.projector=\"orthogonal\""],
        vec!["decomposition.subdomains_per_cluster=4", "contact.enabled=false"],
    ] {
        equivalence("run/seed.toml", &seed(8, &extra), &[8]);
    }
    for (per, clusters) in [(1, 16), (4, 4), (8, 2)] {
        let (sol, _) = solve("run/seed.toml", &seed(8, &[&format!("decomposition.subdomains_per_cluster={per}")]), 8);
        let f = sol.tfeti.expect("TFETI figures");
        assert_eq!((f.subdomains.len(), f.clusters), (16, clusters));
        assert!(
            f.coarse_dim <= 6 * clusters && (per == 1) == (f.corner_rows == 0),
            "{per} per cluster: coarse {}, {} corner rows",
            f.coarse_dim,
            f.corner_rows
        );
    }
}

/// The explicit coarse inverse (each rank the rows of C⁻¹ and (GGᵀ)⁻¹ of its pieces) where the
/// coarse problem is solved in the iterations: TSSN on the oblique operator, SMALSE-M, and
/// H-TFETI clusters; the same solution as the monolithic dual.
#[test]
fn explicit_coarse_inverse_matches_the_monolithic_dual() {
    for extra in [
        vec!["decomposition.projected_cg=false"],
        vec!["decomposition.projector=\"orthogonal\""],
        vec!["decomposition.projected_cg=false", "decomposition.subdomains_per_cluster=4"],
    ] {
        let mut sets = seed(8, &extra);
        sets.push("decomposition.coarse_solve=\"explicit\"".into());
        equivalence("run/seed.toml", &sets, &[8]);
        let (sol, _) = solve("run/seed.toml", &sets, 8);
        let f = sol.tfeti.expect("TFETI figures");
        assert!(f.coarse_explicit_bytes >= 8 * f.coarse_dim * f.coarse_dim, "{extra:?}: {} bytes for dimension {}", f.coarse_explicit_bytes, f.coarse_dim);
    }
}

#[test]
fn gmsh_mesh_matches_the_monolithic_dual() {
    equivalence("run/gmsh_blocks.toml", &["solver.eps=1e-12".to_string()], &[1, 2, 4]);
}

#[test]
fn without_contact_cg_on_the_dual_matches_the_direct_solve() {
    equivalence("run/seed.toml", &seed(8, &["contact.enabled=false"]), &[1, 4]);
    // the FETI preconditioners make it PCG: the same solution
    for pc in ["lumped", "dirichlet"] {
        equivalence("run/seed.toml", &seed(8, &["contact.enabled=false", &format!("solver.preconditioner=\"{pc}\"")]), &[4]);
    }
}

#[test]
fn smalse_with_the_orthogonal_projector_matches_too() {
    let sets = seed(8, &["decomposition.projector=\"orthogonal\""]);
    equivalence("run/seed.toml", &sets, &[1, 4]);
    // with P M P + ϱ⁻¹Q preconditioning SSN's (right) and TSSN's inner solves, with and
    // without contact: the same solution
    for (method, pc, contact) in [("ssn-bicgstab", "dirichlet", "false"), ("tssn", "lumped", "true")] {
        let m = format!("solver.method=\"{method}\"");
        let p = format!("solver.preconditioner=\"{pc}\"");
        let c = format!("contact.enabled={contact}");
        equivalence("run/seed.toml", &seed(8, &["decomposition.projector=\"orthogonal\"", &m, &p, &c]), &[4]);
    }
}

#[test]
fn gimssn_and_mpgp_preconditioned_in_face_match_too() {
    for method in ["gimssn", "mpgp"] {
        let m = format!("solver.method=\"{method}\"");
        equivalence("run/seed.toml", &seed(8, &[&m, "solver.preconditioner=\"lumped\"", "solver.max_outer=20000"]), &[4]);
    }
}

#[test]
fn every_solver_runs_unchanged_on_the_tfeti_dual() {
    for method in ["gimssn", "imssn", "mssn", "mpgp", "ssn-bicgstab", "tssn"] {
        let sets = vec!["mesh.n=6".to_string(), "solver.eps=1e-9".to_string(), format!("solver.method=\"{method}\"")];
        // MSSN with interfaces (S ≥ 2) stalls near ‖r̃‖/‖b‖ ≈ 3e-6 since the contact rows left
        // the prescribed DOFs (Dirichlet conditions eliminated in the subdomains): its slip directions converge as a fixed point
        let parts: &[usize] = if method == "mssn" { &[1] } else { &[4] };
        let worst = equivalence_within("run/seed.toml", &sets, parts, 1e-6, 1e-7);
        eprintln!("{method}: max|Δu|/max|u| = {worst:.2e}");
    }
}

/// Subdomain-count independence at a tight tolerance, for `method` on the seed scene at N = `n`
/// and ε = `eps`: monolithic against TFETI with S = 1, 2, 4, 8 subdomains per body. Stated
/// tolerances: max|Δu|/max|u| ≤ 1e-7; max|Δp|/max|p| ≤ 1e-7 for the contact normal pressure
/// p = λν/w; the same open/stick/slip status pair by pair (hence the same counts); gluing jumps
/// and Dirichlet values within 100ε (relative to max|u|); ‖Gλ − e‖/‖e‖ ≤ 1e-10.
fn subdomain_count_independence(method: &str, n: usize, eps: f64) {
    subdomain_count_independence_with(method, n, eps, &[]);
}

fn subdomain_count_independence_with(method: &str, n: usize, eps: f64, extra: &[&str]) {
    let mut sets = vec![format!("mesh.n={n}"), format!("solver.eps={eps:e}"), format!("solver.method=\"{method}\"")];
    sets.extend(extra.iter().map(|s| s.to_string()));
    for a in agreement("run/seed.toml", &sets, &[1, 2, 4, 8]) {
        let s = a.subdomains;
        assert!(a.du <= 1e-7, "{method}, S = {s}: max|Δu|/max|u| = {:.2e} > 1e-7", a.du);
        assert!(a.dp <= 1e-7, "{method}, S = {s}: max|Δp|/max|p| = {:.2e} > 1e-7", a.dp);
        let (mono, dec) = a.counts.expect("contact");
        assert_eq!(mono, dec, "{method}, S = {s}: (open, stick, slip) counts differ");
        assert!(mono[0] > 0 && mono[1] + mono[2] > 0, "{method}: the seed scene has open and closed pairs: {mono:?}");
        assert!(a.same_status, "{method}, S = {s}: the status of some pair differs");
        assert!(a.gluing_jump <= 100.0 * eps, "{method}, S = {s}: gluing jump {:.2e} > 100ε", a.gluing_jump);
        assert!(a.dirichlet <= 100.0 * eps, "{method}, S = {s}: Dirichlet DOF off by {:.2e} > 100ε", a.dirichlet);
        assert!(a.feasibility <= 1e-10, "{method}, S = {s}: ‖Gλ − e‖/‖e‖ = {:.2e}", a.feasibility);
    }
}

#[test]
fn ssn_bicgstab_is_independent_of_the_subdomain_count() {
    subdomain_count_independence("ssn-bicgstab", 8, 1e-10);
}

/// TSSN with the FETI preconditioners on the gluing block (the preconditioner changes the
/// inner solves only, never the solution).
#[test]
fn tssn_with_each_preconditioner_is_independent_of_the_subdomain_count() {
    for pc in ["none", "lumped", "dirichlet"] {
        subdomain_count_independence_with("tssn", 8, 1e-10, &[&format!("solver.preconditioner=\"{pc}\"")]);
    }
}

/// GIMSSN at N = 6 and ε = 1e-9: at N = 8 on the TFETI dual it stalls near ‖r̃‖/‖b‖ ≈ 1e-8
/// (S = 2) and 3e-8 (S = 8) and does not reach ε = 1e-9 in 1000 outer iterations.
#[test]
fn gimssn_is_independent_of_the_subdomain_count() {
    subdomain_count_independence("gimssn", 6, 1e-9);
}

/// Mixed precision (single-precision factors in the inner CG iterations where the iteration
/// allows their error, the default) against double precision at the default ε, seed N = 12:
/// TFETI with contact. u agrees within 1e-6 of max|u| (the default ε's accuracy), η is measured
/// and small, and the single-precision products were used (u differs in round-off). Without
/// contact (plain CG) no single-precision copy is kept; nor on the monolithic dual, whose
/// products go through the factors' trailing blocks (the same u in both precisions).
#[test]
fn mixed_precision_matches_double_precision() {
    let run = |p: &str, parts: usize, extra: &[&str]| {
        let mut s = vec!["mesh.n=12".to_string(), format!("solver.precision=\"{p}\"")];
        s.extend(extra.iter().map(|x| x.to_string()));
        solve("run/seed.toml", &s, parts).0
    };
    let (m, d) = (run("mixed", 0, &[]), run("double", 0, &[]));
    assert!(m.single_precision_error.is_none() && m.explicit_products.is_some(), "monolithic: explicit products, no copies");
    assert_eq!(m.displacement, d.displacement);
    let parts = 4;
    let (m, d) = (run("mixed", parts, &[]), run("double", parts, &[]));
    let eta = m.single_precision_error.expect("η is measured");
    assert!(eta > 1e-9 && eta < 1e-5, "η = {eta:e} ({parts} subdomains per body)");
    assert!(d.single_precision_error.is_none());
    let du = m.displacement.iter().flatten().zip(d.displacement.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / max_abs(&d.displacement);
    assert!(du <= 1e-6, "mixed against double: {du:e} ({parts} subdomains per body)");
    assert!(du > 0.0, "the single-precision products were used ({parts} subdomains per body)");
    assert!(run("mixed", 4, &["contact.enabled=false"]).single_precision_error.is_none(), "no copy without contact");
}
