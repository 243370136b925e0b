//! The Gmsh importer on every cell type it reads: the tetrahedral, quadratic and mixed
//! (wedge + tetrahedron) fixtures of `mesh/` (made by `mesh/make_fixtures.py`), in ASCII and
//! binary. Each body must come back as Gmsh wrote it (cell counts per type), every cell with a
//! positive Jacobian, every 10-node tetrahedron with its edge nodes midway between the corners
//! they name, and every face made of outward facets of its own cells that cover exactly the
//! geometric area of the face. End to end, results on tetrahedral and mixed meshes are written
//! (HDF5 + XDMF) and read back, on one rank and under mpirun.

mod common;

use std::path::PathBuf;

use common::{fields, mpirun, root, run, tmpdir};

use tresca_feti::fem::cell::{cell_min_jacobian, facet_normal_area};
use tresca_feti::mesh::{gmsh, BodyGeometry, CellKind, FacetKind};

fn mesh_file(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("mesh").join(name)
}

/// Reads `<stem>.msh` and `<stem>_binary.msh` and checks they give the same body: the same
/// cells and faces exactly, coordinates to the 16 digits the ASCII file carries.
fn read_both(stem: &str, volume: Option<&str>) -> BodyGeometry {
    let a = gmsh::read(&mesh_file(&format!("{stem}.msh")), volume).unwrap_or_else(|e| panic!("{e}"));
    let b = gmsh::read(&mesh_file(&format!("{stem}_binary.msh")), volume).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(a.nodes.len(), b.nodes.len(), "{stem}");
    for (p, q) in a.nodes.iter().zip(&b.nodes) {
        assert!((0..3).all(|d| (p[d] - q[d]).abs() <= 1e-15 * p[d].abs().max(1.0)), "{stem}: {p:?} {q:?}");
    }
    assert_eq!(a.cells, b.cells, "{stem}: cells");
    assert_eq!(a.faces.len(), b.faces.len(), "{stem}: faces");
    for (fa, fb) in a.faces.iter().zip(&b.faces) {
        assert_eq!(fa, fb, "{stem}: face {}", fa.0);
    }
    a
}

fn counts(g: &BodyGeometry) -> Vec<(CellKind, usize)> {
    tresca_feti::mesh::cell_counts(&g.cells)
}

fn centroid(x: &[[f64; 3]]) -> [f64; 3] {
    let n = x.len() as f64;
    x.iter().fold([0.0; 3], |s, p| [s[0] + p[0] / n, s[1] + p[1] / n, s[2] + p[2] / n])
}

/// Positive Jacobians, tet10 edge nodes at their midpoints, no unused node.
fn check_cells(g: &BodyGeometry, what: &str) {
    let mut used = vec![false; g.nodes.len()];
    for (e, c) in g.cells.iter().enumerate() {
        let x = c.coords(&g.nodes);
        assert!(cell_min_jacobian(c.kind, &x) > 0.0, "{what}: cell {e} ({:?}) not positive", c.kind);
        if c.kind == CellKind::Tet10 {
            for (k, [a, b]) in tresca_feti::fem::tet::TET10_EDGES.into_iter().enumerate() {
                let mid: [f64; 3] = std::array::from_fn(|d| 0.5 * (x[a][d] + x[b][d]));
                assert!((0..3).all(|d| (x[4 + k][d] - mid[d]).abs() < 1e-12), "{what}: cell {e} edge node {} not on ({a},{b})", 4 + k);
            }
        }
        // quadratic hexahedra and wedges: each edge (and hex27 face, centre) node where the
        // cell's own map of the straight-edged fixture puts it: midway between its corners
        let mids: Vec<(usize, Vec<usize>)> = match c.kind {
            CellKind::Hex20 | CellKind::Hex27 => {
                let mut m: Vec<(usize, Vec<usize>)> = tresca_feti::mesh::HEX20_EDGES.iter().enumerate().map(|(k, e)| (8 + k, e.to_vec())).collect();
                if c.kind == CellKind::Hex27 {
                    m.extend(tresca_feti::mesh::HEX27_FACES.iter().enumerate().map(|(k, f)| (20 + k, f.to_vec())));
                    m.push((26, (0..8).collect()));
                }
                m
            }
            CellKind::Wedge15 => tresca_feti::mesh::WEDGE15_EDGES.iter().enumerate().map(|(k, e)| (6 + k, e.to_vec())).collect(),
            _ => vec![],
        };
        for (node, corners) in mids {
            let mid: [f64; 3] = std::array::from_fn(|d| corners.iter().map(|&a| x[a][d]).sum::<f64>() / corners.len() as f64);
            assert!((0..3).all(|d| (x[node][d] - mid[d]).abs() < 1e-12), "{what}: cell {e} node {node} not amid {corners:?}");
        }
        c.nodes().iter().for_each(|&v| used[v] = true);
    }
    assert!(used.iter().all(|&u| u), "{what}: a node no cell uses");
}

/// Face `name`: `n` facets, each one of its cell's own outward facets (normal away from the
/// cell's centroid), of the kinds `kinds`, their area vectors summing to `area` × `normal`.
fn check_face(g: &BodyGeometry, name: &str, n: usize, kinds: &[FacetKind], area: f64, normal: [f64; 3]) {
    let (_, facets) = g.faces.iter().find(|(f, _)| f == name).unwrap_or_else(|| panic!("no face {name}"));
    assert_eq!(facets.len(), n, "{name}: facets");
    let mut total = [0.0; 3];
    let mut sum_area = 0.0;
    for q in facets {
        let cell = &g.cells[q.elem];
        let own = (0..cell.kind.faces().len()).map(|f| cell.facet(q.elem, f)).any(|f| f == *q);
        assert!(own, "{name}: facet {:?} is not a face of its cell {}", q.nodes(), q.elem);
        assert!(kinds.contains(&q.kind), "{name}: {:?}", q.kind);
        let x: Vec<[f64; 3]> = q.nodes().iter().map(|&v| g.nodes[v]).collect();
        let na = facet_normal_area(q.kind, &x);
        let away: [f64; 3] = std::array::from_fn(|d| centroid(&x[..q.kind.corners()])[d] - centroid(&cell.coords(&g.nodes))[d]);
        assert!(na.iter().zip(away).map(|(a, b)| a * b).sum::<f64>() > 0.0, "{name}: facet of cell {} points inward", q.elem);
        sum_area += na.iter().map(|v| v * v).sum::<f64>().sqrt();
        (0..3).for_each(|d| total[d] += na[d]);
    }
    assert!((sum_area - area).abs() < 1e-12, "{name}: area {sum_area}, expected {area}");
    assert!((0..3).all(|d| (total[d] - area * normal[d]).abs() < 1e-12), "{name}: ∫n dA = {total:?}");
}

const X: [f64; 3] = [1.0, 0.0, 0.0];
const Z: [f64; 3] = [0.0, 0.0, 1.0];
const MX: [f64; 3] = [-1.0, 0.0, 0.0];
const MZ: [f64; 3] = [0.0, 0.0, -1.0];

#[test]
fn tetrahedral_blocks_read_with_outward_faces() {
    let tri = [FacetKind::Tri3];
    let upper = read_both("two_tet_blocks", Some("upper"));
    assert_eq!(counts(&upper), [(CellKind::Tet4, 266)]);
    check_cells(&upper, "upper");
    assert!(upper.nodes.iter().all(|p| (1.0..=2.0).contains(&p[2])));
    let names: Vec<&str> = upper.faces.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["upper_top", "upper_bottom", "upper_left", "upper_right"]);
    check_face(&upper, "upper_top", 38, &tri, 2.0, Z);
    check_face(&upper, "upper_bottom", 38, &tri, 2.0, MZ);
    check_face(&upper, "upper_left", 26, &tri, 1.0, MX);
    check_face(&upper, "upper_right", 26, &tri, 1.0, X);

    let lower = read_both("two_tet_blocks", Some("lower"));
    assert_eq!(counts(&lower), [(CellKind::Tet4, 266)]);
    check_cells(&lower, "lower");
    check_face(&lower, "lower_top", 38, &tri, 2.0, Z);
    check_face(&lower, "lower_left", 26, &tri, 1.0, MX);

    let all = read_both("two_tet_blocks", None);
    assert_eq!(counts(&all), [(CellKind::Tet4, 532)]);
    assert_eq!(all.faces.len(), 6);
}

/// Order 2: 6-node triangles of the file become the tet10's own 6-node facets (edge nodes
/// included), Gmsh's edge order being ours.
#[test]
fn quadratic_tetrahedra_read_with_six_node_facets() {
    let tri6 = [FacetKind::Tri6];
    let upper = read_both("two_tet10_blocks", Some("upper"));
    assert_eq!(counts(&upper), [(CellKind::Tet10, 144)]);
    check_cells(&upper, "upper");
    check_face(&upper, "upper_top", 22, &tri6, 2.0, Z);
    check_face(&upper, "upper_bottom", 22, &tri6, 2.0, MZ);
    check_face(&upper, "upper_left", 14, &tri6, 1.0, MX);
    check_face(&upper, "upper_right", 14, &tri6, 1.0, X);
    let lower = read_both("two_tet10_blocks", Some("lower"));
    assert_eq!(counts(&lower), [(CellKind::Tet10, 145)]);
    check_cells(&lower, "lower");
    check_face(&lower, "lower_top", 22, &tri6, 2.0, Z);
    check_face(&lower, "lower_left", 14, &tri6, 1.0, MX);
}

/// Wedges under tetrahedra in one body: the side x = 0 is quadrilaterals of the wedges and
/// triangles of the tetrahedra; each sub-volume reads alone too.
#[test]
fn wedge_layer_and_tetrahedra_read_as_one_body() {
    let body = read_both("wedge_layer", Some("body"));
    assert_eq!(counts(&body), [(CellKind::Tet4, 83), (CellKind::Wedge6, 28)]);
    check_cells(&body, "body");
    assert_eq!(body.nodes.len(), 64);
    let names: Vec<&str> = body.faces.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["bottom", "top", "xmin"]);
    check_face(&body, "bottom", 14, &[FacetKind::Tri3], 1.0, MZ);
    check_face(&body, "top", 14, &[FacetKind::Tri3], 1.0, Z);
    check_face(&body, "xmin", 16, &[FacetKind::Tri3, FacetKind::Quad4], 1.0, MX);
    let (_, xmin) = &body.faces[2];
    assert_eq!(xmin.iter().filter(|q| q.kind == FacetKind::Quad4).count(), 4);
    assert!(xmin.iter().filter(|q| q.kind == FacetKind::Quad4).all(|q| body.cells[q.elem].kind == CellKind::Wedge6));

    let layer = read_both("wedge_layer", Some("layer"));
    assert_eq!(counts(&layer), [(CellKind::Wedge6, 28)]);
    check_cells(&layer, "layer");
    check_face(&layer, "bottom", 14, &[FacetKind::Tri3], 1.0, MZ);
    // the layer's own x = 0 side: its quadrilaterals only (the core's triangles bound no cell)
    check_face(&layer, "xmin", 4, &[FacetKind::Quad4], 0.2, MX);
    assert!(layer.faces.iter().all(|(n, _)| n != "top"), "top bounds no wedge");
    let core = read_both("wedge_layer", Some("core"));
    assert_eq!(counts(&core), [(CellKind::Tet4, 83)]);
    check_cells(&core, "core");
    check_face(&core, "xmin", 12, &[FacetKind::Tri3], 0.8, MX);
}

/// `mesh/tet.msh` (24 tetrahedra of a unit cube), formerly refused, reads.
#[test]
fn small_tetrahedral_cube_reads() {
    let g = gmsh::read(&mesh_file("tet.msh"), Some("body")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(counts(&g), [(CellKind::Tet4, 24)]);
    check_cells(&g, "tet.msh");
    let (_, top) = &g.faces[0];
    check_face(&g, "top", top.len(), &[FacetKind::Tri3], 1.0, Z);
}

/// The quadratic hexahedra and wedges of `mesh/make_quadratic_fixtures.py` (Gmsh types 17,
/// 12, 18 and their 8-/9-node quadrangle and 6-node triangle faces): read in Gmsh's node
/// order, every node where its cell's map puts it, the top face outward and of area 1 (½ for
/// the prism).
#[test]
fn quadratic_hexahedra_and_wedges_are_read() {
    const Z: [f64; 3] = [0.0, 0.0, 1.0];
    for (file, kind, cells, facet, n, area) in [
        ("cube_hex20.msh", CellKind::Hex20, 8, FacetKind::Quad8, 4, 1.0),
        ("cube_hex27.msh", CellKind::Hex27, 8, FacetKind::Quad9, 4, 1.0),
        ("prism_wedge15.msh", CellKind::Wedge15, 12, FacetKind::Tri6, 6, 0.5),
    ] {
        let g = gmsh::read(&mesh_file(file), Some("body")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(counts(&g), [(kind, cells)], "{file}");
        check_cells(&g, file);
        check_face(&g, "top", n, &[facet], area, Z);
    }
}

/// The seed scene on tetrahedral box meshes (`mesh.cells`): the result file holds the cells as
/// generated (`/mesh/tetrahedra`, `/mesh/tetrahedra10`), checked against memory by the run
/// itself (`output.verify`), and the XDMF sidecar names their topology.
#[test]
fn seed_on_tetrahedra_writes_results_that_read_back() {
    let dir = tmpdir("seed-tet");
    for (cells, n, kind, count, topology, dataset) in [
        ("tet4", "5", CellKind::Tet4, 768, "Tetrahedron", "tetrahedra"),
        ("tet10", "3", CellKind::Tet10, 96, "Tetrahedron_10", "tetrahedra10"),
        ("hex20", "3", CellKind::Hex20, 16, "Hexahedron_20", "hexahedra20"),
    ] {
        let out = dir.join(format!("{cells}.h5"));
        let c = format!("mesh.cells=\"{cells}\"");
        let m = format!("mesh.n={n}");
        let seed = root().join("run/seed.toml");
        let o = run(&["solve", seed.to_str().unwrap(), "--set", &c, "--set", &m, "--set", "output.verify=true", "--out", out.to_str().unwrap()]);
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{cells}: {}", String::from_utf8_lossy(&o.stderr));
        assert!(stdout.contains("match the fields in memory"), "{stdout}");
        let data = fields(&out);
        assert_eq!(data.cells.len(), count, "{cells}");
        assert!(data.cells.iter().all(|c| c.kind == kind), "{cells}");
        let xdmf = std::fs::read_to_string(out.with_extension("xdmf")).unwrap();
        assert!(xdmf.contains(&format!("<Topology TopologyType=\"{topology}\" NumberOfElements=\"{count}\">")), "{xdmf}");
        assert!(
            xdmf.contains(&format!("Dimensions=\"{count} {}\" NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">{cells}.h5:/mesh/{dataset}<", kind.len())),
            "{xdmf}"
        );
    }
}

/// The wedge layer under tetrahedra as one body, clamped at the bottom and pressed on top,
/// TFETI with 4 subdomains on 1 and on 2 ranks: both files hold the same `Mixed` cells (each
/// rank writing its cells at their offset), the XDMF sidecar a `Mixed` topology of
/// 83 × (1 + 4) + 28 × (1 + 6) = 611 values, and the same displacements.
#[test]
fn mixed_mesh_results_on_one_and_two_ranks() {
    let dir = tmpdir("mixed");
    let scene = dir.join("wedge.toml");
    let mesh = mesh_file("wedge_layer.msh");
    std::fs::write(
        &scene,
        format!(
            r#"title = "wedges under tetrahedra"
[[material]]
name = "m"
E = 50000.0
nu = 0.3
[[body]]
name = "cube"
material = "m"
gmsh = {{ file = "{}", volume = "body" }}
[[dirichlet]]
face = "cube.bottom"
[[traction]]
face = "cube.top"
p = [0.1, 0.0, -1.0]
"#,
            mesh.display()
        ),
    )
    .unwrap();
    let mut runs = Vec::new();
    for n in [1, 2] {
        let out = dir.join(format!("r{n}.h5"));
        let args = ["solve", scene.to_str().unwrap(), "--set", "decomposition.subdomains=4", "--set", "output.verify=true", "--out", out.to_str().unwrap()];
        let o = if n == 1 { run(&args) } else { mpirun(n, &args) };
        assert!(o.status.success(), "{n} ranks: {}", String::from_utf8_lossy(&o.stderr));
        assert!(String::from_utf8_lossy(&o.stdout).contains("match the fields in memory"));
        let xdmf = std::fs::read_to_string(out.with_extension("xdmf")).unwrap();
        assert!(xdmf.contains(r#"<Topology TopologyType="Mixed" NumberOfElements="111">"#), "{xdmf}");
        assert!(xdmf.contains(&format!(r#"Dimensions="611" NumberType="Int" Precision="8" Format="HDF">r{n}.h5:/mesh/mixed<"#)), "{xdmf}");
        runs.push(fields(&out));
    }
    let body = gmsh::read(&mesh, Some("body")).unwrap();
    assert_eq!(tresca_feti::mesh::cell_counts(&runs[0].cells), [(CellKind::Tet4, 83), (CellKind::Wedge6, 28)]);
    assert_eq!(runs[0].cells, body.cells);
    assert_eq!(runs[1].cells, runs[0].cells);
    assert_eq!(runs[1].coordinates, runs[0].coordinates);
    let u = |d: &tresca_feti::output::OutputData| match &d.fields.iter().find(|f| f.name == "displacement").expect("displacement").values {
        tresca_feti::output::Values::F64(v) => v.clone(),
        _ => panic!("displacement is not f64"),
    };
    let (a, b) = (u(&runs[0]), u(&runs[1]));
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(scale > 0.0 && a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= 1e-9 * scale), "displacements differ between 1 and 2 ranks");
}

/// The hexahedral-dominant two blocks of `mesh/make_pyramid_fixture.py` (Gmsh type 7
/// pyramids between structured hexahedra and tetrahedra): each body holds hex8, pyr5 and tet4
/// cells (Gmsh counted 128 hexahedra, 32 pyramids and 842 tetrahedra in the file), every cell
/// positive, the faces at z = 1 — quadrangles of hexahedra, triangles of tetrahedra and
/// pyramids — outward and of area 2. Then solved end to end as the seed's block on a block
/// (run/gmsh_blocks.toml on this mesh): it runs, writes a `Mixed` XDMF topology holding the
/// pyramids (type 7), and the contact force is near the hexahedral mesh's.
#[test]
fn hexahedra_pyramids_and_tetrahedra_are_read_and_solved_in_contact() {
    let file = mesh_file("hex_pyr_tet.msh");
    let mut total = std::collections::BTreeMap::new();
    for (body, face, normal) in [("upper", "upper_bottom", MZ), ("lower", "lower_top", Z)] {
        let g = gmsh::read(&file, Some(body)).unwrap_or_else(|e| panic!("{e}"));
        check_cells(&g, body);
        let c = counts(&g);
        for kind in [CellKind::Hex8, CellKind::Tet4, CellKind::Pyr5] {
            assert!(c.iter().any(|&(k, n)| k == kind && n > 0), "{body}: no {kind:?} in {c:?}");
        }
        c.iter().for_each(|&(k, n)| *total.entry(k).or_insert(0) += n);
        let n = g.faces.iter().find(|(f, _)| f == face).unwrap().1.len();
        check_face(&g, face, n, &[FacetKind::Quad4, FacetKind::Tri3], 2.0, normal);
        let (_, facets) = g.faces.iter().find(|(f, _)| f == face).unwrap();
        assert!(facets.iter().any(|q| q.kind == FacetKind::Quad4) && facets.iter().any(|q| q.kind == FacetKind::Tri3), "{face}");
    }
    assert_eq!(total.into_iter().collect::<Vec<_>>(), [(CellKind::Hex8, 128), (CellKind::Tet4, 842), (CellKind::Pyr5, 32)]);
    let dir = tmpdir("hex-pyr-tet");
    let gmsh_toml = std::fs::read_to_string(root().join("run/gmsh_blocks.toml")).unwrap();
    let mut force = Vec::new();
    for (name, mesh) in [("hex", mesh_file("two_blocks.msh")), ("pyr", file.clone())] {
        let scene = dir.join(format!("{name}.toml"));
        std::fs::write(&scene, gmsh_toml.replace("\"../mesh/two_blocks.msh\"", &format!("\"{}\"", mesh.display()))).unwrap();
        let out = dir.join(format!("{name}.h5"));
        let o = run(&["solve", scene.to_str().unwrap(), "--set", "output.verify=true", "--out", out.to_str().unwrap(), "--quiet"]);
        assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.with_extension("json")).unwrap()).unwrap();
        force.push(report["contact"]["total_force_on_slave"][2].as_f64().unwrap());
        if name == "pyr" {
            let data = fields(&out);
            assert_eq!(data.cells.iter().filter(|c| c.kind == CellKind::Pyr5).count(), 32);
            let xdmf = std::fs::read_to_string(out.with_extension("xdmf")).unwrap();
            assert!(xdmf.contains(r#"<Topology TopologyType="Mixed" NumberOfElements="1002">"#), "{xdmf}");
        }
    }
    eprintln!("contact force F_z: hexahedra {:.5}, hex/pyr/tet {:.5} ({:+.2} %)", force[0], force[1], 100.0 * (force[1] / force[0] - 1.0));
    assert!((force[1] / force[0] - 1.0).abs() < 0.05, "{force:?}");
}
