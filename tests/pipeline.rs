//! The whole pipeline on scene files: an analytic bar through scene, traction and roller
//! conditions; the Gmsh-imported seed geometry against the generated one; HDF5 read-back of the
//! written file against the computed fields.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use tresca_feti::comm::SerialComm;
use tresca_feti::output::{self, Values};
use tresca_feti::pipeline::{run_solve, Summary};
use tresca_feti::{model, scene};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("tresca-feti-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn solve(scene: &Path, sets: &[&str], out: &Path) -> Summary {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    run_solve(&SerialComm, scene, &sets, Some(out.to_path_buf()), true).unwrap()
}

#[test]
fn bar_under_uniform_traction_is_exact() {
    // [0,3]×[0,1]×[0,1], rollers on the three faces through the origin, p on x = 3:
    // u = (p x / E, −ν p y / E, −ν p z / E) exactly.
    let dir = tmpdir("bar");
    let scene = dir.join("bar.toml");
    std::fs::write(
        &scene,
        r#"
[[material]]
name = "steel"
E = 210000.0
nu = 0.3
[[body]]
name = "bar"
material = "steel"
box = { min = [0.0, 0.0, 0.0], max = [3.0, 1.0, 1.0], nodes = [7, 3, 4] }
[[dirichlet]]
face = "bar.xmin"
components = ["x"]
[[dirichlet]]
face = "bar.ymin"
components = ["y"]
[[dirichlet]]
face = "bar.zmin"
components = ["z"]
[[traction]]
face = "bar.xmax"
p = [12.0, 0.0, 0.0]
"#,
    )
    .unwrap();
    let s = solve(&scene, &[], &dir.join("bar.h5"));
    let ls = scene::load(&scene, &[]).unwrap();
    let m = model::build(&ls).unwrap();
    let (e, nu, p) = (210000.0, 0.3, 12.0);
    let mut err: f64 = 0.0;
    for (x, u) in m.mesh.nodes.iter().zip(&s.solution.displacement) {
        let exact = [p * x[0] / e, -nu * p * x[1] / e, -nu * p * x[2] / e];
        for c in 0..3 {
            err = err.max((u[c] - exact[c]).abs());
        }
    }
    assert!(err <= 1e-12 * (3.0 * p / e), "bar error {err:e}");
    for vm in &s.solution.von_mises {
        assert!((vm - p).abs() <= 1e-10 * p, "von Mises {vm} ≠ {p}");
    }
}

/// Displacements keyed by (body, rounded coordinates).
fn by_position(body_of: &[usize], nodes: &[[f64; 3]], u: &[[f64; 3]]) -> HashMap<(usize, [i64; 3]), [f64; 3]> {
    nodes.iter().zip(u).zip(body_of).map(|((x, u), &b)| ((b, x.map(|c| (c * 1e9).round() as i64)), *u)).collect()
}

fn node_bodies(m: &model::Model) -> Vec<usize> {
    let mut out = vec![0; m.mesh.nodes.len()];
    for (b, body) in m.mesh.bodies.iter().enumerate() {
        out[body.nodes.clone()].fill(b);
    }
    out
}

#[test]
fn gmsh_seed_geometry_counts_and_matches_the_generated_box() {
    let dir = tmpdir("gmsh");
    let gscene = root().join("run/gmsh_blocks.toml");
    let ls = scene::load(&gscene, &["contact.enabled=false".into()]).unwrap();
    let gm = model::build(&ls).unwrap();
    assert_eq!(gm.mesh.nodes.len(), 2 * 7 * 4 * 4);
    assert_eq!(gm.mesh.cells.len(), 2 * 54);
    let counts: Vec<(String, usize)> = gm.mesh.faces.iter().map(|f| (f.name.clone(), f.facets.len())).collect();
    for (name, n) in [
        ("upper.upper_top", 18),
        ("upper.upper_bottom", 18),
        ("upper.upper_left", 9),
        ("upper.upper_right", 9),
        ("lower.lower_top", 18),
        ("lower.lower_left", 9),
    ] {
        assert!(counts.contains(&(name.to_string(), n)), "{name}: {counts:?}");
    }
    assert_eq!(gm.contact.len(), 1);
    let total_z: f64 = gm.loads.iter().skip(2).step_by(3).sum();
    assert!((total_z + 3.0).abs() < 1e-12, "total load {total_z}");

    let gs = solve(&gscene, &["contact.enabled=false"], &dir.join("g.h5"));
    let bscene = root().join("run/seed.toml");
    let sets = ["contact.enabled=false", "body.0.box.nodes=[7,4,4]", "body.1.box.nodes=[7,4,4]"];
    let bs = solve(&bscene, &sets, &dir.join("b.h5"));
    let bm = model::build(&scene::load(&bscene, &sets.map(String::from)).unwrap()).unwrap();
    let g = by_position(&node_bodies(&gm), &gm.mesh.nodes, &gs.solution.displacement);
    let b = by_position(&node_bodies(&bm), &bm.mesh.nodes, &bs.solution.displacement);
    assert_eq!(g.len(), b.len());
    let scale = b.values().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(scale > 1e-4);
    for (k, ub) in &b {
        let ug = g.get(k).unwrap_or_else(|| panic!("no Gmsh node at {k:?}"));
        for c in 0..3 {
            assert!((ug[c] - ub[c]).abs() <= 1e-10 * scale, "at {k:?}: {ug:?} vs {ub:?}");
        }
    }
}

#[test]
fn written_file_reads_back_as_computed() {
    let dir = tmpdir("readback");
    let h5 = dir.join("seed.h5");
    let scene_path = root().join("run/seed.toml");
    let sets = ["contact.enabled=false", "mesh.n=5"];
    let s = solve(&scene_path, &sets, &h5);
    assert_eq!(s.files, vec![h5.clone(), dir.join("seed.xdmf"), dir.join("seed.json")]);
    for f in &s.files {
        assert!(f.exists());
    }
    let temps: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().filter(|e| e.file_name().to_string_lossy().ends_with(".tmp")).collect();
    assert!(temps.is_empty(), "temporary files left: {temps:?}");
    let m = model::build(&scene::load(&scene_path, &sets.map(String::from)).unwrap()).unwrap();
    let back = output::hdf5::read(&h5).unwrap();
    assert_eq!(back.coordinates, m.mesh.nodes);
    assert_eq!(back.cells, m.mesh.cells);
    let field = |name: &str| back.fields.iter().find(|f| f.name == name).unwrap_or_else(|| panic!("no field {name}"));
    assert_eq!(field("displacement").values, Values::F64(s.solution.displacement.iter().flatten().copied().collect()));
    assert_eq!(field("von_mises").values, Values::F64(s.solution.von_mises.clone()));
    assert_eq!(field("body").values, Values::I32(m.mesh.elem_body().iter().map(|&b| b as i32).collect()));
    let attr = |name: &str| back.attributes.iter().find(|a| a.0 == name).map(|a| a.1.clone()).unwrap_or_else(|| panic!("no attribute {name}"));
    // the stored scene is the resolved one and parses back to the same scene
    let stored = scene::parse(&attr("scene"), "stored", &[]).unwrap();
    let mut expect = scene::load(&scene_path, &sets.map(String::from)).unwrap().scene;
    expect.output.path = Some(h5.clone()); // --out is part of the resolved scene
                                           // so are the automatic choices: the decomposition by cost (this small seed: monolithic)
                                           // and the method for that dual
    assert!(expect.solver.auto && expect.decomposition.subdomains.is_none());
    assert!(!stored.solver.auto && stored.decomposition.subdomains == Some(1));
    expect.decomposition.subdomains = Some(1);
    tresca_feti::pipeline::resolve_method(&mut expect.solver, tresca_feti::pipeline::DualKind::Monolithic);
    assert_eq!(stored.solver.params.method(), tresca_feti::qp::Method::Tssn);
    assert_eq!(stored.to_toml(), expect.to_toml());
    let versions: serde_json::Value = serde_json::from_str(&attr("versions")).unwrap();
    assert_eq!(versions["tresca-feti"], env!("CARGO_PKG_VERSION"));
    let timings: serde_json::Value = serde_json::from_str(&attr("timings")).unwrap();
    assert!(timings["factorize"].as_f64().unwrap() >= 0.0);
    // the JSON report agrees with the fields
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("seed.json")).unwrap()).unwrap();
    let umax = s.solution.displacement.iter().map(|u| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt()).fold(0.0, f64::max);
    assert_eq!(report["results"]["max_displacement"].as_f64().unwrap(), umax);
    assert_eq!(report["mesh"]["dofs"], 6 * 125);
    // the JSON file is written after the output phase: it times it, and the peak memory per phase
    assert!(report["timings"]["output"].as_f64().unwrap() > 0.0);
    let total = report["timings"]["total"].as_f64().unwrap();
    let sum: f64 = report["timings"].as_object().unwrap().iter().filter(|(k, _)| *k != "total").map(|(_, v)| v.as_f64().unwrap()).sum();
    assert!((total - sum).abs() <= 1e-9 * total);
    let peaks = report["memory"]["peak_rss_bytes_max_rank_after_phase"].as_array().unwrap();
    assert!(peaks.iter().any(|p| p["phase"] == "factorize" && p["bytes"].as_f64().unwrap() > 0.0));
    // only the requested fields are written
    let h5b = dir.join("only_u.h5");
    solve(&scene_path, &["contact.enabled=false", "mesh.n=3", "output.fields=[\"displacement\"]", "output.xdmf=false", "output.report=false"], &h5b);
    let back = output::hdf5::read(&h5b).unwrap();
    assert_eq!(back.fields.iter().map(|f| f.name.as_str()).collect::<Vec<_>>(), ["displacement"]);
    assert!(!dir.join("only_u.xdmf").exists() && !dir.join("only_u.json").exists());
}

/// The typed report: the JSON file and the HDF5 `report` attribute read back into
/// `pipeline::report::Report`, with the solver history (one step per outer iteration, A-products
/// non-decreasing up to the final count) in both.
#[test]
fn the_report_and_the_solver_history_read_back_typed() {
    use tresca_feti::pipeline::report::Report;
    let dir = tmpdir("report");
    let h5 = dir.join("seed.h5");
    let s = solve(&root().join("run/seed.toml"), &["mesh.n=5", "solver.method=\"gimssn\""], &h5);
    let file: Report = serde_json::from_str(&std::fs::read_to_string(dir.join("seed.json")).unwrap()).unwrap();
    let back = output::hdf5::read(&h5).unwrap();
    let attr = |name: &str| back.attributes.iter().find(|a| a.0 == name).map(|a| a.1.clone()).unwrap_or_else(|| panic!("no attribute {name}"));
    let stored: Report = serde_json::from_str(&attr("report")).unwrap();
    let history: Vec<tresca_feti::qp::Step> = serde_json::from_str(&attr("solver_history")).unwrap();
    let sv = s.report.solver.as_ref().expect("a contact solve reports its solver");
    for r in [&file, &stored] {
        let rs = r.solver.as_ref().unwrap();
        assert_eq!(
            (rs.method.as_str(), rs.info.iterations, rs.info.n_a, rs.info.inner_iterations),
            ("gimssn", sv.info.iterations, sv.info.n_a, sv.info.inner_iterations)
        );
        assert_eq!(rs.info.history, sv.info.history);
        assert_eq!(r.contact.as_ref().unwrap().pairs, 25);
    }
    assert_eq!(history, sv.info.history);
    assert_eq!(history.len(), sv.info.iterations);
    assert!(history.windows(2).all(|w| w[0].n_a <= w[1].n_a && w[0].time <= w[1].time));
    assert!(history.last().unwrap().n_a <= sv.info.n_a);
    assert_eq!(history.iter().map(|h| h.inner).sum::<usize>(), sv.info.inner_iterations);
    assert!(history.last().unwrap().err <= 1e-6);
}

#[test]
fn a_curved_face_pairs_as_slave_and_as_master() {
    // the cylindrical punch on the flat block, once with the curved side as the slave face and
    // once as the master: the same pairs, the same contact force (opposite on the other body),
    // the same displacements
    let dir = tmpdir("curved");
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("run/bench/cylinder_on_flat.toml");
    let text = std::fs::read_to_string(&base).unwrap();
    let swapped = text
        .replace("slave = \"upper.zmin\"", "slave = \"X\"")
        .replace("master = \"lower.zmax\"", "master = \"upper.zmin\"")
        .replace("slave = \"X\"", "slave = \"lower.zmax\"");
    assert_ne!(text, swapped);
    let other = dir.join("swapped.toml");
    std::fs::write(&other, swapped).unwrap();
    let a = solve(&base, &[], &dir.join("a.h5"));
    let b = solve(&other, &[], &dir.join("b.h5"));
    let (ca, cb) = (a.report.contact.as_ref().unwrap(), b.report.contact.as_ref().unwrap());
    assert_eq!((ca.pairs, ca.open, ca.stick, ca.slip), (cb.pairs, cb.open, cb.stick, cb.slip));
    assert!(ca.open < ca.pairs && ca.pairs == 17 * 3, "{ca:?}");
    for d in 0..3 {
        assert!((ca.total_force_on_slave[d] + cb.total_force_on_slave[d]).abs() <= 1e-8 * ca.total_force_on_slave[2].abs(), "{ca:?} {cb:?}");
    }
    assert!(ca.total_force_on_slave[2] > 0.0);
    let du = a.solution.displacement.iter().zip(&b.solution.displacement).flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs())).fold(0.0, f64::max);
    assert!(du <= 1e-9, "displacements differ by {du:e}");
}
