//! Bodies held by contact alone (TFETI with the orthogonal projector, Gλ = e over every row):
//! a floating block pressed and pushed below the friction limit sticks with the contact force
//! balancing the load exactly, on several decompositions; a block dragged by one face (free in
//! the other directions) sticks below μN and slides at μN above, also far beyond (both ways of
//! solving Coulomb); a frictionless floating block
//! is refused with its free motions named.

mod common;

use common::{max_abs, root, solve, tmpdir};

#[test]
fn a_floating_block_sticks_and_the_contact_balances_its_load() {
    let scene = root().join("run/validation/floating_block.toml");
    let dir = tmpdir("floating");
    let one = solve(&scene, &[], &dir.join("s1.h5"));
    assert!(one.report.problem.contains("TFETI"), "a body held by contact alone goes to TFETI: {}", one.report.problem);
    let u1 = &one.solution.displacement;
    for s in [1, 4] {
        let sets = [format!("decomposition.subdomains={s}")];
        let r = solve(&scene, &sets.iter().map(String::as_str).collect::<Vec<_>>(), &dir.join(format!("s{s}.h5")));
        let c = r.report.contact.as_ref().unwrap();
        // the upper block's load: 2 down on its top, 0.3 along x on its side
        let f = c.total_force_on_slave;
        eprintln!(
            "S = {s}: contact force on the floating block ({:.6e}, {:.2e}, {:.6e}), {} stick, {} slip, KKT {:.1e}",
            f[0],
            f[1],
            f[2],
            c.stick,
            c.slip,
            r.report.solver.as_ref().unwrap().kkt_worst
        );
        assert!((f[0] + 0.3).abs() <= 1e-8 && f[1].abs() <= 1e-8 && (f[2] - 2.0).abs() <= 1e-8, "the contact force balances the load: {f:?}");
        assert_eq!((c.stick, c.slip, c.open), (49, 0, 0), "T = 0.3 < μN = 0.6: every pair sticks");
        assert!(r.report.solver.as_ref().unwrap().kkt_worst <= 1e-8);
        let d = r.solution.displacement.iter().flatten().zip(u1.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(d <= 1e-7 * max_abs(u1), "S = {s} differs from S = 1 by {:.1e} relative", d / max_abs(u1));
    }
}

#[test]
fn a_block_dragged_by_one_face_sticks_below_mu_n_and_slides_at_mu_n_above() {
    // the upper block is held in x by its xmin face only (moved by δ); y, z and the rotation
    // about x are held by contact and friction
    let base = std::fs::read_to_string(root().join("run/validation/floating_block.toml")).unwrap();
    let scene = base.replace(
        "[[traction]]\nface = \"upper.xmin\"\np = [0.3, 0.0, 0.0]\n",
        "[[dirichlet]]\nface = \"upper.xmin\"\ncomponents = [\"x\"]\nvalue = [0.00001, 0.0, 0.0]\n",
    );
    assert_ne!(scene, base);
    let dir = tmpdir("dragged-floating");
    let path = dir.join("dragged.toml");
    std::fs::write(&path, scene).unwrap();
    let mu = 0.3;
    let small = solve(&path, &[], &dir.join("a.h5"));
    let large = solve(&path, &["dirichlet.1.value=[0.0001, 0.0, 0.0]"], &dir.join("b.h5"));
    // a deep slide (100× the stick limit's displacement), by each way of solving Coulomb
    for how in ["newton", "fixed-point", "lagged"] {
        let deep = solve(&path, &["dirichlet.1.value=[0.001, 0.0, 0.0]", &format!("solver.coulomb=\"{how}\"")], &dir.join("c.h5"));
        let c = deep.report.contact.as_ref().unwrap();
        let f = c.total_force_on_slave;
        eprintln!("δ = 1e-3 ({how}): Fx {:.6} vs μFz {:.6}, {} slip, {} products", f[0], mu * f[2], c.slip, deep.report.solver.as_ref().unwrap().info.n_a);
        assert!(c.slip == 49 && (f[0].abs() - mu * f[2]).abs() <= 1e-3 * mu * f[2], "{how}: deep slide Fx = {}", f[0]);
    }
    let (a, b) = (small.report.contact.as_ref().unwrap(), large.report.contact.as_ref().unwrap());
    let (fa, fb) = (a.total_force_on_slave, b.total_force_on_slave);
    eprintln!("δ = 1e-5: Fx {:.5}, {} stick / {} slip; δ = 1e-4: Fx {:.5} vs μFz {:.5}, {} slip", fa[0], a.stick, a.slip, fb[0], mu * fb[2], b.slip);
    assert!(a.stick > 0 && fa[0].abs() < 0.9 * mu * fa[2], "a small drag sticks (partly)");
    assert_eq!(b.slip, 49, "a large drag slides everywhere");
    assert!((fb[0].abs() - mu * fb[2]).abs() <= 1e-3 * mu * fb[2], "sliding: |Fx| = {} vs μFz = {}", fb[0].abs(), mu * fb[2]);
    for f in [fa, fb] {
        assert!((f[2] - 2.0).abs() <= 1e-8 && f[1].abs() <= 1e-8, "z and y balance the pressing load: {f:?}");
    }
}

/// A washer tied to a plate that friction alone holds on a clamped plate (the lap joint): the
/// tied pair is one rigid group held by contact, solved on 1 and 2 subdomains per body and along
/// a 3-step path with the contact force balancing the load on every step; `check` names the
/// group and what holds it, and a pull beyond μN is refused naming the group. Before, tied
/// nodes counted as fixed and the solve failed with "C = G_E G_Eᵀ is singular".
#[test]
fn a_tied_group_held_by_contact_alone_solves_and_balances_its_load() {
    let scene = root().join("run/validation/tied_lap_joint.toml");
    let dir = tmpdir("tied-group");
    let one = solve(&scene, &[], &dir.join("s1.h5"));
    let u1 = &one.solution.displacement;
    for (s, sets) in
        [(1, vec![]), (2, vec!["decomposition.subdomains=2", "load.steps=3", "traction.1.factors=[0.0, 0.5, 1.0]", "traction.0.factors=[0.5, 1.0, 1.0]"])]
    {
        let r = solve(&scene, &sets, &dir.join(format!("p{s}.h5")));
        assert!(r.report.problem.contains("TFETI"), "{}", r.report.problem);
        let c = r.report.contact.as_ref().unwrap();
        let f = c.total_force_on_slave;
        eprintln!(
            "S = {s}: force on the plate ({:.6e}, {:.2e}, {:.6e}), {} stick, {} slip, KKT {:.1e}",
            f[0],
            f[1],
            f[2],
            c.stick,
            c.slip,
            r.report.solver.as_ref().unwrap().kkt_worst
        );
        assert!((f[0] + 0.3).abs() <= 1e-8 && f[1].abs() <= 1e-8 && (f[2] - 2.0).abs() <= 1e-8, "the contact force balances the load: {f:?}");
        assert_eq!((c.stick, c.open), (25, 0), "T = 0.3 < μN = 0.6: every pair sticks");
        if let Some(steps) = r.report.load_path.as_ref() {
            for (k, (fx, fz)) in [(0.0, 1.0), (-0.15, 2.0), (-0.3, 2.0)].into_iter().enumerate() {
                let f = steps[k].total_force_on_slave;
                assert!((f[0] - fx).abs() <= 1e-8 && f[1].abs() <= 1e-8 && (f[2] - fz).abs() <= 1e-8, "step {}: {f:?}", k + 1);
            }
        }
        let d = r.solution.displacement.iter().flatten().zip(u1.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(d <= 1e-6 * max_abs(u1), "S = {s} differs from S = 1 by {:.1e} relative", d / max_abs(u1));
    }
    let o = common::run(&["check", scene.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("bodies \"washer\", \"upper\" (tied): held by contact alone (pair 0) in all six rigid motions"), "{out}");
    let o = common::run(&["check", scene.to_str().unwrap(), "--set", "traction.1.p=[0.7, 0.0, 0.0]"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    for want in ["bodies \"washer\", \"upper\" (tied): no equilibrium exists", "translation along x", "the group would slide away"] {
        assert!(err.contains(want), "`{want}` not in {err}");
    }
}

/// Three bodies, one tie: the middle plate tied to the clamped base is held by Dirichlet
/// conditions through it (the group), and the top block on it is held by contact alone.
#[test]
fn a_block_on_a_tied_stack_is_held_by_contact_and_the_tie_group_by_its_base() {
    let base = std::fs::read_to_string(root().join("run/validation/tied_lap_joint.toml")).unwrap();
    // washer → a block pressed onto "upper" by contact; "upper" tied to the clamped "lower"
    let scene = base
        .replace("[[tie]]\nslave = \"washer.zmin\"\nmaster = \"upper.zmax\"\n", "[[tie]]\nslave = \"upper.zmin\"\nmaster = \"lower.zmax\"\n")
        .replace("[[contact.pair]]\nslave = \"upper.zmin\"\nmaster = \"lower.zmax\"\n", "[[contact.pair]]\nslave = \"washer.zmin\"\nmaster = \"upper.zmax\"\n")
        .replace("face = \"upper.xmin\"\np = [0.3, 0.0, 0.0]", "face = \"washer.xmin\"\np = [0.3, 0.0, 0.0]");
    let dir = tmpdir("tied-stack");
    let path = dir.join("stack.toml");
    std::fs::write(&path, &scene).unwrap();
    let o = common::run(&["check", path.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("bodies \"upper\", \"lower\" (tied): held by Dirichlet conditions on \"lower\""), "{out}");
    assert!(out.contains("body \"washer\": held by contact alone"), "{out}");
    let r = solve(&path, &["contact.pair.0.discretization=\"mortar\""], &dir.join("r.h5"));
    let f = r.report.contact.as_ref().unwrap().total_force_on_slave;
    // N = 4 · 0.5, T = 0.3 · 0.15 (the washer's xmin face: 0.5 × 0.3)
    assert!((f[0] + 0.045).abs() <= 1e-8 && f[1].abs() <= 1e-8 && (f[2] - 2.0).abs() <= 1e-8, "{f:?}");
}

/// Trust round four, 2: a body of one hexahedron (2 nodes per edge, the least the docs allow)
/// on rollers, frictionless, held in z by contact alone and pressed by p = 1 over its 2 × 1
/// top: its four contact nodes carry 0.5 each. Before, the projected rhs was round-off (Gλ = e
/// alone carries the load) and SMALSE-M's relative test and the KKT check against it failed
/// ("KKT residual 1.4e-1" after tightening ε to 1e-14; 1 000 iterations at ε 3.8e-18).
#[test]
fn a_one_hexahedron_body_held_by_contact_alone_is_solved() {
    let dir = tmpdir("one-hex");
    let scene = std::fs::read_to_string(root().join("run/validation/floating_block.toml"))
        .unwrap()
        .replace("friction = { type = \"coulomb\", mu = 0.3 }", "")
        .replace("p = [0.3, 0.0, 0.0]", "p = [0.0, 0.0, 0.0]")
        + "[[dirichlet]]\nface = \"upper.xmin\"\ncomponents = [\"x\"]\n[[dirichlet]]\nface = \"upper.ymin\"\ncomponents = [\"y\"]\n";
    let path = dir.join("one_hex.toml");
    std::fs::write(&path, scene).unwrap();
    for (nodes, pairs) in [("[2, 2, 2]", 4), ("[2, 2, 3]", 4), ("[3, 3, 3]", 9)] {
        let sets = [format!("body.0.box.nodes={nodes}")];
        let r = solve(&path, &sets.iter().map(String::as_str).collect::<Vec<_>>(), &dir.join("r.h5"));
        let c = r.report.contact.as_ref().unwrap();
        let f = c.total_force_on_slave;
        assert!(f[0].abs() <= 1e-8 && f[1].abs() <= 1e-8 && (f[2] - 2.0).abs() <= 1e-8, "{nodes}: {f:?}");
        assert_eq!((c.pairs, c.open), (pairs, 0), "{nodes}");
        assert!(r.report.solver.as_ref().unwrap().kkt_worst <= 1e-8, "{nodes}");
    }
}

/// The accuracy guard's re-solve of a body held by contact alone continues SMALSE-M from the
/// loose solve's λ and ν (the quarter Hertz sphere of run/bench pressed by a traction, 3 030
/// DOFs: its ε = 1e-8 result misses the equilibrium check and ε is tightened to 3.0e-10). The
/// warm re-solve is compared with a cold solve straight at the tightened ε: u within 10 ε
/// relative to max |u| (measured: the same to the last bit, both end on the same four pairs in
/// contact), and the warm re-solve takes a fraction of the cold one's products (48 against 256).
/// Before, the re-solve restarted ν at 0 and repeated the cold solve step for step.
#[test]
fn the_guards_re_solve_continues_smalse_from_its_multipliers() {
    let scene = root().join("run/bench/hertz_sphere_traction.toml");
    let dir = tmpdir("warm-guard");
    // SMALSE-M asked for: the restricted TSSN path (the default) has no outer loop to continue
    let coarse = ["body.0.box.nodes=[11, 11, 5]", "body.1.box.nodes=[9, 9, 5]", "decomposition.restricted=false"];
    let warm = solve(&scene, &coarse, &dir.join("warm.h5"));
    let ws = warm.report.solver.as_ref().unwrap();
    let eps = ws.eps_tightened.last().expect("ε = 1e-8 misses the equilibrium check here").to_eps;
    let tight = format!("solver.eps={eps}");
    let cold = solve(&scene, &[coarse[0], coarse[1], coarse[2], &tight], &dir.join("cold.h5"));
    let cs = cold.report.solver.as_ref().unwrap();
    assert!(cs.eps_tightened.is_empty(), "the cold solve at ε = {eps:.1e} passes its checks");
    let products = |r: &tresca_feti::pipeline::Summary| r.report.tfeti.as_ref().unwrap().smalse.as_ref().unwrap().n_a;
    let (nw, nc) = (products(&warm), products(&cold));
    let (uw, uc) = (&warm.solution.displacement, &cold.solution.displacement);
    let d = uw.iter().flatten().zip(uc.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / max_abs(uc);
    eprintln!("ε = {eps:.2e}: warm re-solve {nw} products (the whole solve {}), cold {nc}; u differs by {d:.1e} relative", ws.info.n_a);
    assert!(d <= 10.0 * eps, "warm and cold u differ by {d:.1e} relative to max |u|");
    assert!(2 * nw <= nc, "the warm re-solve takes {nw} products, the cold solve {nc}");
}

/// `decomposition.restricted`: TSSN keeping Gλ = e on each Newton step's subspace solves the
/// same discrete problem as SMALSE-M's augmented Lagrangian. Frictionless bodies held by contact
/// alone (one hexahedron pressed on rollers, its 3 × 3 × 3-node twin, the quarter Hertz sphere
/// of run/bench pressed by a traction at 3 030 DOFs) are solved by the restricted path at
/// ε = 1e-10 and by SMALSE-M at ε = 1e-12 (the reference: SMALSE-M at 1e-10 is itself 3.2e-8
/// off it on the sphere, the restricted path 2.3e-10): u agrees within 10 ε relative to max |u|,
/// and the restricted path ran (no SMALSE-M counters: it did not hand over).
#[test]
fn the_restricted_tssn_path_agrees_with_smalse() {
    let dir = tmpdir("restricted");
    let hex = std::fs::read_to_string(root().join("run/validation/floating_block.toml"))
        .unwrap()
        .replace("friction = { type = \"coulomb\", mu = 0.3 }", "")
        .replace("p = [0.3, 0.0, 0.0]", "p = [0.0, 0.0, 0.0]")
        + "[[dirichlet]]\nface = \"upper.xmin\"\ncomponents = [\"x\"]\n[[dirichlet]]\nface = \"upper.ymin\"\ncomponents = [\"y\"]\n";
    let hex_path = dir.join("one_hex.toml");
    std::fs::write(&hex_path, hex).unwrap();
    let sphere = root().join("run/bench/hertz_sphere_traction.toml");
    let eps = 1e-10;
    let cases: [(&std::path::Path, Vec<&str>); 3] = [
        (&hex_path, vec!["body.0.box.nodes=[2, 2, 2]"]),
        (&hex_path, vec!["body.0.box.nodes=[3, 3, 3]"]),
        (&sphere, vec!["body.0.box.nodes=[11, 11, 5]", "body.1.box.nodes=[9, 9, 5]"]),
    ];
    for (k, (scene, sets)) in cases.into_iter().enumerate() {
        let with = |flag: &str, eps: f64| {
            let tight = format!("solver.eps={eps}");
            let mut s = sets.clone();
            s.push(&tight);
            s.push(flag);
            solve(scene, &s, &dir.join(format!("{k}_{}.h5", flag.len())))
        };
        let (smalse, restricted) = (with("decomposition.restricted=false", 1e-2 * eps), with("decomposition.restricted=true", eps));
        let tf = |r: &tresca_feti::pipeline::Summary| r.report.tfeti.as_ref().unwrap().smalse.is_some();
        assert!(tf(&smalse) && !tf(&restricted), "case {k}: SMALSE-M, then the restricted TSSN path");
        let (us, ur) = (&smalse.solution.displacement, &restricted.solution.displacement);
        let d = us.iter().flatten().zip(ur.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / max_abs(us);
        let n = |r: &tresca_feti::pipeline::Summary| r.report.solver.as_ref().unwrap().info.n_a;
        eprintln!("case {k}: SMALSE-M {} products, restricted TSSN {}; u differs by {d:.1e} relative", n(&smalse), n(&restricted));
        assert!(d <= 10.0 * eps, "case {k}: u differs by {d:.1e} relative to max |u|");
        assert!(restricted.report.solver.as_ref().unwrap().kkt_worst <= 1e-8, "case {k}");
    }
}

/// The restricted path's first Newton step takes W from the pairs the start presses (the
/// touching start's), not every row: on the quarter Hertz sphere pressed by a traction at
/// 3 030 DOFs it takes at most 12 products at ε = 1e-8 (16 with every row, 10 with the pressed
/// pairs; run/results/floating_restricted2.txt), and u stays within 10 ε of SMALSE-M's at 1e-12.
#[test]
fn the_restricted_path_starts_from_the_pressed_pairs() {
    let dir = tmpdir("restricted_start");
    let sphere = root().join("run/bench/hertz_sphere_traction.toml");
    let coarse = ["body.0.box.nodes=[11, 11, 5]", "body.1.box.nodes=[9, 9, 5]"];
    let with = |extra: &[&str], name: &str| {
        let mut s = coarse.to_vec();
        s.extend_from_slice(extra);
        solve(&sphere, &s, &dir.join(name))
    };
    let reference = with(&["decomposition.restricted=false", "solver.eps=1e-12"], "ref.h5");
    let restricted = with(&["decomposition.restricted=true", "solver.eps=1e-8"], "restricted.h5");
    assert!(restricted.report.tfeti.as_ref().unwrap().smalse.is_none(), "the restricted path ran");
    let n = restricted.report.solver.as_ref().unwrap().info.n_a;
    let (us, ur) = (&reference.solution.displacement, &restricted.solution.displacement);
    let d = us.iter().flatten().zip(ur.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / max_abs(us);
    eprintln!("restricted TSSN {n} products; u differs by {d:.1e} relative");
    assert!(n <= 12, "the restricted path takes {n} products");
    assert!(d <= 10.0 * 1e-8, "u differs by {d:.1e} relative to max |u|");
}

/// Coulomb bodies held by contact alone go through the restricted path with TSSN's lagged bounds:
/// the floating block of run/validation and the tied lap joint take fewer products than
/// SMALSE-M at ε = 1e-8 (72 → 37 and 65 → 39; run/results/floating_restricted2.txt) and u stays
/// within 10 ε of SMALSE-M's at 1e-12. The block dragged by a displacement, whose first Newton
/// step fixes every pair's tangents (GΠGᵀ singular to round-off: the CG broke down on it), hands
/// over to SMALSE-M.
#[test]
fn coulomb_bodies_held_by_contact_alone_take_the_restricted_path() {
    let dir = tmpdir("restricted_coulomb");
    let block = root().join("run/validation/floating_block.toml");
    let lap = root().join("run/validation/tied_lap_joint.toml");
    for (k, scene) in [&block, &lap].into_iter().enumerate() {
        let reference = solve(scene, &["decomposition.restricted=false", "solver.eps=1e-12"], &dir.join(format!("{k}_ref.h5")));
        let smalse = solve(scene, &["decomposition.restricted=false"], &dir.join(format!("{k}_smalse.h5")));
        let restricted = solve(scene, &[], &dir.join(format!("{k}_restricted.h5")));
        assert!(restricted.report.tfeti.as_ref().unwrap().smalse.is_none(), "case {k}: the restricted path ran");
        let n = |r: &tresca_feti::pipeline::Summary| r.report.solver.as_ref().unwrap().info.n_a;
        let (us, ur) = (&reference.solution.displacement, &restricted.solution.displacement);
        let d = us.iter().flatten().zip(ur.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / max_abs(us);
        eprintln!("case {k}: SMALSE-M {} products, restricted TSSN {}; u differs by {d:.1e} relative", n(&smalse), n(&restricted));
        assert!(n(&restricted) < n(&smalse), "case {k}: restricted {} products, SMALSE-M {}", n(&restricted), n(&smalse));
        assert!(d <= 10.0 * 1e-8, "case {k}: u differs by {d:.1e} relative to max |u|");
    }
    let dragged = std::fs::read_to_string(&block).unwrap().replace(
        "[[traction]]\nface = \"upper.xmin\"\np = [0.3, 0.0, 0.0]\n",
        "[[dirichlet]]\nface = \"upper.xmin\"\ncomponents = [\"x\"]\nvalue = [0.001, 0.0, 0.0]\n",
    );
    let path = dir.join("dragged.toml");
    std::fs::write(&path, dragged).unwrap();
    let r = solve(&path, &[], &dir.join("dragged.h5"));
    assert!(r.report.tfeti.as_ref().unwrap().smalse.is_some(), "the dragged block hands over to SMALSE-M");
}
