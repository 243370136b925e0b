//! 3D Hertz and Cattaneo–Mindlin on non-matching meshes (dual mortar), CI-sized versions of
//! run/validation/hertz3d.{toml,py} and cattaneo_mindlin3d.{toml,py}: a spherical cap
//! (`box.sphere`) on a flat block of the same material, the cap hexahedral with 17 nodes per unit
//! length, the flat block with 15 (the faces never match). At this level a ≈ 4h; the scripts show
//! the finer levels (the 2 % peak-pressure goal is met from 6 elements across a).

mod common;

use std::f64::consts::PI;
use std::path::Path;

use common::{fields, root, solve, tmpdir};
use tresca_feti::contact::state::{OPEN, STICK};
use tresca_feti::output::Values;

const E: f64 = 50000.0;
const NU: f64 = 0.3;
const R: f64 = 10.0;

/// The slave nodes: (x, y, status, pressure, shear traction x) from the last step.
fn slave_nodes(h5: &Path) -> Vec<(f64, f64, i32, f64, f64)> {
    let f = fields(h5);
    let get = |name: &str| f.fields.iter().find(|x| x.name == name).unwrap_or_else(|| panic!("field {name}")).values.clone();
    let (Values::I32(status), Values::F64(p), Values::F64(q)) = (get("contact_status"), get("contact_pressure"), get("contact_traction")) else {
        panic!("field types")
    };
    (0..f.coordinates.len()).filter(|&v| status[v] > 0).map(|v| (f.coordinates[v][0], f.coordinates[v][1], status[v], p[v], q[3 * v])).collect()
}

/// Hertz (a, p₀) of a full sphere carrying `force`; identical materials: 1/E* = 2(1 − ν²)/E.
fn hertz(force: f64) -> (f64, f64) {
    let es = E / (2.0 * (1.0 - NU * NU));
    let a = (3.0 * force * R / (4.0 * es)).cbrt();
    (a, 3.0 * force / (2.0 * PI * a * a))
}

#[test]
fn hertz3d_peak_pressure_and_contact_radius_on_non_matching_meshes() {
    let scene = root().join("run/validation/hertz3d.toml");
    let dir = tmpdir("hertz3d");
    let s = solve(&scene, &["body.0.box.nodes=[17, 17, 9]", "body.1.box.nodes=[15, 15, 8]"], &dir.join("h.h5"));
    let h = 1.0 / 16.0;
    assert!(s.report.contact.is_some());
    // the quarter model carries a quarter of the load
    let force = 4.0 * s.report.contact.as_ref().unwrap().total_force_on_slave[2];
    let (a, p0) = hertz(force);
    let nodes = slave_nodes(&dir.join("h.h5"));
    let pole = nodes.iter().find(|n| n.0 == 0.0 && n.1 == 0.0).expect("the pole is a slave node");
    let err = (pole.3 - p0) / p0;
    // the contact radius along the x axis: between the last closed node and the first open one
    let mut axis: Vec<_> = nodes.iter().filter(|n| n.1 == 0.0).collect();
    axis.sort_by(|u, v| u.0.total_cmp(&v.0));
    let last = axis.iter().rposition(|n| n.2 != OPEN).unwrap();
    assert!(axis[..last].iter().all(|n| n.2 != OPEN), "one contact zone along the axis");
    let (closed, open) = (axis[last].0, axis[last + 1].0);
    let mid = 0.5 * (closed + open);
    eprintln!("4F = {force:.3}, a = {a:.4} ({:.2} h), p0 = {p0:.2}, p(pole) = {:.2} ({:+.2} %), contact radius between {closed:.4} and {open:.4}: midpoint {:+.2} h from a", a / h, pole.3, 100.0 * err, (mid - a) / h);
    assert!(a > 3.0 * h && a < 0.35, "a = {a} is not the sized a ≈ 1/4");
    // measured 2.9 % at this level (1.2 % at 6 elements across a, 0.7 % at 8)
    assert!(err.abs() <= 0.04, "peak pressure {:.2} vs Hertz p0 = {p0:.2}: {:+.2} %", pole.3, 100.0 * err);
    assert!((mid - a).abs() <= h, "contact radius {mid:.4} vs a = {a:.4}: more than one element (h = {h})");
    // frictionless: every closed pair slips, no tangential traction
    assert!(nodes.iter().all(|n| n.2 != STICK && n.4 == 0.0));
}

/// The same on a linear-tetrahedral cap (Kuhn split of the 33 × 33 × 17 grid, a/h ≈ 8) on the
/// hexahedral flat (28 nodes per edge): the peak (largest nodal) pressure within 2 % of p₀ and
/// the contact radius within one element. The pole itself reads ≈ 5 % low: on the symmetry planes
/// the quarter model's Kuhn mesh is not symmetric, and the nodes there read ≈ 3 % below the
/// profile at every level, while the nodes off the planes converge to it (run/validation/hertz3d.py).
#[test]
fn hertz3d_on_a_tetrahedral_cap() {
    let scene = root().join("run/validation/hertz3d.toml");
    let dir = tmpdir("hertz3d-tet4");
    let out = dir.join("t.h5");
    let s = solve(&scene, &["body.0.box.nodes=[33, 33, 17]", "body.1.box.nodes=[28, 28, 15]", "body.0.box.cells=\"tet4\""], &out);
    let h = 1.0 / 32.0;
    let force = 4.0 * s.report.contact.as_ref().unwrap().total_force_on_slave[2];
    let (a, p0) = hertz(force);
    let nodes = slave_nodes(&out);
    let peak = nodes.iter().map(|n| n.3).fold(0.0f64, f64::max);
    let err = (peak - p0) / p0;
    let mut axis: Vec<_> = nodes.iter().filter(|n| n.1 == 0.0).collect();
    axis.sort_by(|u, v| u.0.total_cmp(&v.0));
    let last = axis.iter().rposition(|n| n.2 != OPEN).unwrap();
    let mid = 0.5 * (axis[last].0 + axis[last + 1].0);
    eprintln!(
        "tet4 cap: a = {a:.4} ({:.2} h), p0 = {p0:.2}, peak {peak:.2} ({:+.2} %), contact radius midpoint {:+.2} h from a",
        a / h,
        100.0 * err,
        (mid - a) / h
    );
    assert!(a > 7.0 * h && a < 9.0 * h, "a = {a} is not the sized a ≈ 8h");
    // measured +1.76 % at this level
    assert!(err.abs() <= 0.02, "peak pressure {peak:.2} vs Hertz p0 = {p0:.2}: {:+.2} %", 100.0 * err);
    assert!((mid - a).abs() <= h, "contact radius {mid:.4} vs a = {a:.4}: more than one element (h = {h})");
}

#[test]
fn cattaneo_mindlin3d_stick_radius_on_non_matching_meshes() {
    let scene = root().join("run/validation/cattaneo_mindlin3d.toml");
    let dir = tmpdir("cattaneo-mindlin3d");
    let s = solve(&scene, &["body.0.box.nodes=[33, 17, 9]", "body.1.box.nodes=[29, 15, 8]"], &dir.join("cm.h5"));
    let (h, mu) = (1.0 / 16.0, 0.3);
    // the half model carries half of the loads
    let force = s.report.contact.as_ref().unwrap().total_force_on_slave;
    let (p, q) = (2.0 * force[2], 2.0 * force[0].abs());
    assert!(q < mu * p, "partial slip needs Q < μP");
    let (a, _) = hertz(p);
    let c = a * (1.0 - q / (mu * p)).cbrt();
    let nodes = slave_nodes(&dir.join("cm.h5"));
    // the stick zone along the x axis: its ends halfway between the outermost sticking node and the next
    let stick: Vec<f64> = nodes.iter().filter(|n| n.1 == 0.0 && n.2 == STICK).map(|n| n.0).collect();
    let (lo, hi) = stick.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &x| (l.min(x), u.max(x)));
    let (lo, hi) = (lo - h / 2.0, hi + h / 2.0);
    let half = (hi - lo) / 2.0;
    eprintln!(
        "P = {p:.3}, Q/(μP) = {:.3}, a = {a:.4}, c = {c:.4} ({:.2} h), stick zone along x [{lo:.4}, {hi:.4}]: half-width {half:.4} ({:+.2} h from c)",
        q / (mu * p),
        c / h,
        (half - c) / h
    );
    assert!((0.3..0.7).contains(&(q / (mu * p))), "the shear is sized for Q ≈ μP/2");
    assert!(nodes.iter().filter(|n| n.1 == 0.0 && n.2 != OPEN && n.0 > lo && n.0 < hi).all(|n| n.2 == STICK), "one stick zone along x");
    // measured 2026-12-05: +0.27 h (docs/validation.md: within 0.35 h at three levels)
    assert!((half - c).abs() <= 0.5 * h, "stick half-width {half:.4} vs c = {c:.4}: more than half an element (h = {h})");
}

/// Pressing alone (equal materials: no relative slip in theory), either body as slave: no node
/// slips and the spurious shear stays below a tenth of μ max p, and the stick zone of the
/// sheared step is centred. Before, with the curved cap as slave its frame tilted by r/R and the
/// closing gap read as a tangential slip: 3 of 29 closed nodes slipped, the shear reached 0.30 of
/// μ max p, and the sheared stick zone sat half an element off centre; with the flat block as slave it was refused as overlapping by 1.2e-5.
#[test]
fn cattaneo_mindlin3d_pressing_alone_slips_nowhere_with_either_body_as_slave() {
    let scene = root().join("run/validation/cattaneo_mindlin3d.toml");
    let dir = tmpdir("cattaneo-mindlin3d-either");
    let mesh = ["body.0.box.nodes=[33, 17, 9]", "body.1.box.nodes=[29, 15, 8]"];
    let press = ["load.steps=1", "dirichlet.1.factors=[1.0]", "dirichlet.2.factors=[0.0]"];
    let swap = ["contact.pair.0.slave=\"flat.zmax\"", "contact.pair.0.master=\"cap.zmin\""];
    for (name, flat) in [("cap", false), ("flat", true)] {
        let mut sets: Vec<&str> = mesh.iter().chain(&press).copied().collect();
        if flat {
            sets.extend(swap);
        }
        let out = dir.join(format!("{name}.h5"));
        let r = solve(&scene, &sets, &out);
        let c = r.report.contact.as_ref().unwrap();
        let f = fields(&out);
        let get = |n: &str| f.fields.iter().find(|x| x.name == n).unwrap().values.clone();
        let (Values::I32(st), Values::F64(p), Values::F64(q)) = (get("contact_status"), get("contact_pressure"), get("contact_traction")) else {
            panic!("field types")
        };
        let closed: Vec<usize> = (0..st.len()).filter(|&v| st[v] > OPEN).collect();
        let p0 = closed.iter().map(|&v| p[v]).fold(0.0, f64::max);
        let worst = closed.iter().map(|&v| q[3 * v].hypot(q[3 * v + 1])).fold(0.0, f64::max) / (0.3 * p0);
        eprintln!("{name} as slave: {} stick, {} slip, max |q|/(μ max p) {worst:.3}", c.stick, c.slip);
        assert_eq!(c.slip, 0, "{name} as slave: pressing alone slips nowhere");
        // measured 2026-12-05: 0.036 (cap as slave), 0.024 (flat as slave)
        assert!(worst < 0.06, "{name} as slave: the spurious shear reaches {worst:.3} of μ max p");
    }
    // the sheared step: the stick zone along x centred on the axis (within a tenth of h)
    let s = dir.join("sheared.h5");
    solve(&scene, &mesh, &s);
    let stick: Vec<f64> = slave_nodes(&s).iter().filter(|n| n.1 == 0.0 && n.2 == STICK).map(|n| n.0).collect();
    let (lo, hi) = stick.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &x| (l.min(x), u.max(x)));
    assert!((lo + hi).abs() / 2.0 <= 0.1 / 16.0, "stick zone [{lo}, {hi}] off centre");
}

/// Friction on a quarter model by TFETI: the symmetry planes' rollers hold the slave nodes
/// there along one tangent, whose mortar rows (held entries moved to c, small entries left on
/// master nodes off the plane) make B rank-deficient — "the FETI preconditioner's scaling: BBᵀ
/// is singular" before its semi-definite blocks were shifted (`feti::precond::REGULARIZATION`).
/// Tresca on 2 subdomains per body solves, and the same scene on the monolithic dual gives the
/// same u.
#[test]
fn tresca_on_a_quarter_model_by_tfeti_keeps_b_of_full_rank() {
    let scene = root().join("run/validation/hertz3d.toml");
    let dir = tmpdir("hertz3d-tfeti");
    let base = ["body.0.box.nodes=[9, 9, 5]", "body.1.box.nodes=[8, 8, 5]", "contact.pair.0.friction={type=\"tresca\", g=10.0}", "solver.eps=1e-10"];
    let mut u = Vec::new();
    for extra in ["decomposition.subdomains=2", "decomposition.subdomains=1"] {
        let out = dir.join(format!("{}.h5", extra.len()));
        let sets: Vec<&str> = base.iter().copied().chain([extra]).collect();
        solve(&scene, &sets, &out);
        let f = fields(&out);
        let d = f.fields.iter().find(|x| x.name == "displacement").unwrap();
        let Values::F64(v) = &d.values else { panic!() };
        u.push(v.clone());
    }
    let scale = u[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = u[0].iter().zip(&u[1]).map(|(a, b)| (a - b).abs()).fold(0.0f64, f64::max);
    assert!(diff <= 1e-6 * scale, "TFETI vs monolithic: max|Δu| {diff:.2e} of {scale:.2e}");
}

/// Hertz on unstructured tet4 meshes (`run/validation/hertz3d_tet4.toml`, a/h ≈ 8): the nodal
/// multipliers λ/D scatter by ±4 % about Hertz's profile on an unstructured face (their peak
/// +3.4 %); `contact_pressure_smooth`, the area-weighted average over each node's facets, has
/// its peak within 3 % of p₀ and a scatter under 2 % (measured 2026-12-05: −0.72 % and 1.04 %,
/// against +3.42 % and 4.34 % for λ/D; at a/h = 5.6 / 12.5 the smoothed scatter is 1.24 / 0.84 %,
/// `run/validation/hertz3d_unstructured.py`). Before: no such field.
#[test]
fn the_smoothed_pressure_of_unstructured_tet4_hertz() {
    let dir = tmpdir("hertz-tet4");
    let out = dir.join("hertz.h5");
    let r = solve(
        &root().join("run/validation/hertz3d_tet4.toml"),
        &["output.fields=[\"contact_status\", \"contact_pressure\", \"contact_pressure_smooth\"]"],
        &out,
    );
    let f = fields(&out);
    let get = |name: &str| match &f.fields.iter().find(|x| x.name == name).unwrap_or_else(|| panic!("field {name}")).values {
        Values::F64(v) => v.clone(),
        Values::I32(v) => v.iter().map(|&i| i as f64).collect(),
    };
    let (st, raw, smooth) = (get("contact_status"), get("contact_pressure"), get("contact_pressure_smooth"));
    let (a, p0) = hertz(4.0 * r.report.contact.as_ref().unwrap().total_force_on_slave[2].abs());
    let x = &f.coordinates;
    let r_of = |v: usize| x[v][0].hypot(x[v][1]);
    // within a/2 of the pole, off the symmetry planes
    let inner: Vec<usize> = (0..st.len()).filter(|&v| st[v] > 1.0 && r_of(v) < 0.5 * a && x[v][0] > 1e-9 && x[v][1] > 1e-9).collect();
    let scatter =
        |p: &[f64]| (inner.iter().map(|&v| (p[v] / (p0 * (1.0 - (r_of(v) / a).powi(2)).sqrt()) - 1.0).powi(2)).sum::<f64>() / inner.len() as f64).sqrt();
    let peak = |p: &[f64]| (0..st.len()).filter(|&v| st[v] > 0.0).map(|v| p[v]).fold(0.0, f64::max) / p0 - 1.0;
    eprintln!(
        "tet4 Hertz, {} nodes within a/2: λ/D peak {:+.2} %, scatter {:.2} %; smoothed peak {:+.2} %, scatter {:.2} %",
        inner.len(),
        100.0 * peak(&raw),
        100.0 * scatter(&raw),
        100.0 * peak(&smooth),
        100.0 * scatter(&smooth)
    );
    assert!(inner.len() >= 10);
    assert!(peak(&smooth).abs() <= 0.03, "smoothed peak {:+.2} %", 100.0 * peak(&smooth));
    assert!(
        scatter(&smooth) <= 0.02 && scatter(&smooth) < 0.5 * scatter(&raw),
        "scatter {:.2} % (λ/D {:.2} %)",
        100.0 * scatter(&smooth),
        100.0 * scatter(&raw)
    );
}

/// Hex20 bodies (Quad8 contact faces) at a/h ≈ 4 cells (17 × 17 × 9 nodes of cell corners): the
/// written `contact_pressure_smooth` (on quadratic mortar faces the corner hats' moments
/// ∫ N¹_c p = λ_c + ½ Σ_e λ_e over ∫ N¹_c, edge nodes the mean of their corners) peaks within 3 % of
/// p₀ and is never negative, where the nodal λ/w (`contact_pressure`) alternates corner / edge and
/// peaks ≈ 21 % high; over the slave nodes its L2 distance to the Hertz profile is half λ/w's.
#[test]
fn hertz3d_hex20_vertex_recovered_pressure() {
    let scene = root().join("run/validation/hertz3d.toml");
    let dir = tmpdir("hertz3d-hex20");
    let out = dir.join("q.h5");
    let sets = [
        "body.0.box.nodes=[17, 17, 9]",
        "body.1.box.nodes=[15, 15, 8]",
        "body.0.box.cells=\"hex20\"",
        "body.1.box.cells=\"hex20\"",
        "output.fields=[\"contact_status\", \"contact_pressure\", \"contact_pressure_smooth\", \"contact_traction\"]",
    ];
    let s = solve(&scene, &sets, &out);
    let force = 4.0 * s.report.contact.as_ref().unwrap().total_force_on_slave[2];
    let (a, p0) = hertz(force);
    let f = fields(&out);
    let get = |name: &str| match &f.fields.iter().find(|x| x.name == name).unwrap_or_else(|| panic!("field {name}")).values {
        Values::F64(v) => v.clone(),
        Values::I32(v) => v.iter().map(|&s| f64::from(s)).collect(),
    };
    let (status, raw, smooth) = (get("contact_status"), get("contact_pressure"), get("contact_pressure_smooth"));
    let slave: Vec<usize> = (0..f.coordinates.len()).filter(|&v| status[v] > 0.0).collect();
    let exact = |v: usize| p0 * (1.0 - (f.coordinates[v][0].powi(2) + f.coordinates[v][1].powi(2)) / (a * a)).max(0.0).sqrt();
    let l2 = |p: &[f64]| (slave.iter().map(|&v| (p[v] - exact(v)).powi(2)).sum::<f64>() / slave.iter().map(|&v| exact(v).powi(2)).sum::<f64>()).sqrt();
    let peak = |p: &[f64]| slave.iter().map(|&v| p[v]).fold(f64::MIN, f64::max);
    let (e_raw, e_smooth) = ((peak(&raw) - p0) / p0, (peak(&smooth) - p0) / p0);
    eprintln!(
        "hex20 cap: a = {a:.4}, p0 = {p0:.2}; peak λ/w {:+.2} %, recovered {:+.2} %; L2 {:.4} / {:.4}",
        100.0 * e_raw,
        100.0 * e_smooth,
        l2(&raw),
        l2(&smooth)
    );
    // measured: λ/w +20.87 %, L2 0.208; recovered −1.64 %, L2 0.100
    assert!(e_raw > 0.1, "λ/w peak {:+.2} %: the alternation this test is about is gone", 100.0 * e_raw);
    assert!(e_smooth.abs() <= 0.03, "recovered peak {:.2} vs p0 = {p0:.2}: {:+.2} %", peak(&smooth), 100.0 * e_smooth);
    assert!(l2(&smooth) < 0.6 * l2(&raw), "L2 error {:.4} not below 0.6 × λ/w's {:.4}", l2(&smooth), l2(&raw));
    assert!(slave.iter().all(|&v| smooth[v] >= 0.0), "a negative recovered pressure");
}
