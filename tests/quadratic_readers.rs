//! Quadratic hexahedra and wedges read from Abaqus, MED and Exodus II files: the Gmsh
//! fixtures `mesh/cube_hex20.msh`, `cube_hex27.msh`, `prism_wedge15.msh` converted by Gmsh's
//! own exports (`mesh/make_quadratic_conversions.py`: `.inp` with C3D20/C3D15 and surface
//! elements, `.med` with H20/H27/P15 and QU8/QU9/TR6) and written from the Exodus
//! documentation by geometry (`mesh/make_quadratic_exodus.py`: HEX20/HEX27/WEDGE15, a side
//! set and a node set) read as the same nodes, cells (kind and nodes, in the program's order)
//! and face "top" (facets with their edge and face nodes) as the `.msh`; every edge, face and
//! centre node lies where the program's node order puts it (a wrong permutation fails this even
//! where two readers agree); and a solve of each converted file gives the `.msh`'s
//! displacements, bit for bit.

mod common;

use std::path::Path;

use common::{root, solve, tmpdir};
use tresca_feti::mesh::{abaqus, exodus, gmsh, med, BodyGeometry, Cell, CellKind, Facet, HEX20_EDGES, HEX27_FACES, WEDGE15_EDGES};

/// The fixtures and the converted files of each.
const CASES: [(&str, &[&str]); 3] = [("cube_hex20", &["inp", "med", "exo"]), ("cube_hex27", &["med", "exo"]), ("prism_wedge15", &["inp", "med", "exo"])];

fn read(name: &str, ext: &str) -> BodyGeometry {
    let path = root().join(format!("mesh/{name}.{ext}"));
    let r = match ext {
        "msh" => gmsh::read(&path, Some("body")),
        "inp" => abaqus::read(&path, Some("body")),
        "med" => med::read(&path, Some("body")),
        _ => exodus::read(&path, Some("body")),
    };
    r.unwrap_or_else(|e| panic!("{name}.{ext}: {e}"))
}

/// A face's facets as (its cell's nodes, its own nodes), sorted.
fn facets(g: &BodyGeometry, face: &str) -> Vec<(Vec<usize>, Vec<usize>)> {
    let f: &[Facet] = &g.faces.iter().find(|(n, _)| n == face).unwrap_or_else(|| panic!("no face {face}")).1;
    let mut k: Vec<(Vec<usize>, Vec<usize>)> = f.iter().map(|q| (g.cells[q.elem].nodes().to_vec(), q.nodes().to_vec())).collect();
    k.sort();
    k
}

fn cells(c: &[Cell]) -> Vec<(CellKind, Vec<usize>)> {
    let mut v: Vec<(CellKind, Vec<usize>)> = c.iter().map(|h| (h.kind, h.nodes().to_vec())).collect();
    v.sort();
    v
}

/// The mean of the points `at` of `x`.
fn mean(x: &[[f64; 3]], at: &[usize]) -> [f64; 3] {
    let n = at.len() as f64;
    let mut s = [0.0; 3];
    for &v in at {
        for k in 0..3 {
            s[k] += x[v][k] / n;
        }
    }
    s
}

/// Every edge node at the midpoint of its corners, every hex27 face node at its face's centre
/// and the centre node at the cell's (the fixtures' cells are straight-sided).
fn check_geometry(g: &BodyGeometry, what: &str) {
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-12);
    for (c, cell) in g.cells.iter().enumerate() {
        let n = cell.nodes();
        let nc = cell.kind.corners();
        let edges: &[[usize; 2]] = if nc == 8 { &HEX20_EDGES } else { &WEDGE15_EDGES };
        for (e, pair) in edges.iter().enumerate() {
            let p = mean(&g.nodes, &[n[pair[0]], n[pair[1]]]);
            assert!(close(g.nodes[n[nc + e]], p), "{what}: cell {c} edge node {}", nc + e);
        }
        if cell.kind == CellKind::Hex27 {
            for (f, face) in HEX27_FACES.iter().enumerate() {
                let p = mean(&g.nodes, &face.map(|k| n[k]));
                assert!(close(g.nodes[n[20 + f]], p), "{what}: cell {c} face node {}", 20 + f);
            }
            assert!(close(g.nodes[n[26]], mean(&g.nodes, &n[..8])), "{what}: cell {c} centre");
        }
    }
}

#[test]
fn converted_quadratic_meshes_read_as_from_gmsh() {
    for (name, exts) in CASES {
        let g = read(name, "msh");
        check_geometry(&g, name);
        for ext in exts {
            let what = format!("{name}.{ext}");
            let m = read(name, ext);
            assert_eq!(m.nodes, g.nodes, "{what}");
            assert_eq!(cells(&m.cells), cells(&g.cells), "{what}");
            check_geometry(&m, &what);
            let top = facets(&g, "top");
            assert!(!top.is_empty());
            assert_eq!(facets(&m, "top"), top, "{what}");
            if *ext == "exo" {
                assert_eq!(facets(&m, "top_nodes"), top, "{what}: the node set");
            }
        }
    }
}

/// One body read from `mesh`, clamped on the half of its top with x < 0.4 and pulled on the
/// rest.
fn scene(mesh: &Path) -> String {
    format!(
        r#"title = "quadratic cells from another format"
[[material]]
name = "m"
E = 1000.0
nu = 0.3
[[body]]
name = "b"
material = "m"
mesh = {{ file = "{}", volume = "body" }}
[[face]]
name = "clamp"
body = "b"
from = "top"
min = [-1.0, -1.0, 0.9]
max = [0.4, 2.0, 1.1]
[[face]]
name = "pull"
body = "b"
from = "top"
min = [0.4, -1.0, 0.9]
max = [2.0, 2.0, 1.1]
[[dirichlet]]
face = "b.clamp"
[[traction]]
face = "b.pull"
p = [0.1, 0.2, 1.0]
"#,
        mesh.display()
    )
}

#[test]
fn converted_quadratic_meshes_solve_as_from_gmsh() {
    let dir = tmpdir("quadratic-readers");
    for (name, exts) in CASES {
        let run = |ext: &str| {
            let toml = dir.join(format!("{name}_{ext}.toml"));
            std::fs::write(&toml, scene(&root().join(format!("mesh/{name}.{ext}")))).unwrap();
            solve(&toml, &[], &dir.join(format!("{name}_{ext}.h5")))
        };
        let from_msh = run("msh");
        assert!(common::max_abs(&from_msh.solution.displacement) > 0.0, "{name}");
        for ext in exts {
            let other = run(ext);
            assert_eq!(other.solution.displacement, from_msh.solution.displacement, "{name}.{ext}");
        }
    }
}

/// The XDMF written beside a solve of the Hex27 and Wedge15 fixtures (`.msh` and each
/// conversion) opened by a reader of its own, meshio: one cell block of the type meshio names
/// (`hexahedron27`, `wedge15`) with as many cells as the mesh file holds, and as many points as
/// its nodes. Skipped, with the reason printed, where /usr/bin/python3 has no meshio. (Debian's
/// meshio 5.0 lacks the dimension of `wedge15`, which the script adds before reading.)
#[test]
fn quadratic_results_read_back_from_xdmf_by_meshio() {
    let probe = std::process::Command::new("/usr/bin/python3").args(["-c", "import meshio"]).output();
    if !probe.as_ref().is_ok_and(|o| o.status.success()) {
        eprintln!("skipped: /usr/bin/python3 cannot import meshio (run/install-deps installs python3-meshio)");
        return;
    }
    let dir = tmpdir("quadratic-xdmf");
    let cases: [(&str, &[&str], &str); 2] =
        [("cube_hex27", &["msh", "med", "exo"], "hexahedron27"), ("prism_wedge15", &["msh", "inp", "med", "exo"], "wedge15")];
    for (name, exts, meshio_type) in cases {
        for ext in exts {
            let what = format!("{name}.{ext}");
            let g = read(name, ext);
            let toml = dir.join(format!("{name}_{ext}.toml"));
            std::fs::write(&toml, scene(&root().join(format!("mesh/{name}.{ext}")))).unwrap();
            let out = dir.join(format!("{name}_{ext}.h5"));
            solve(&toml, &[], &out);
            // meshio 5.0 (Debian) maps XDMF's Wedge_15 to "wedge15" but has no dimension for
            // it (a KeyError in CellBlock): the script gives it one when missing
            let script = "import sys, meshio\nfrom meshio import _mesh\n_mesh.topological_dimension.setdefault('wedge15', 3)\n\
                          m = meshio.read(sys.argv[1])\nprint(len(m.points))\nfor b in m.cells:\n    print(b.type, len(b.data), b.data.shape[1])";
            let o = std::process::Command::new("/usr/bin/python3").args(["-c", script]).arg(out.with_extension("xdmf")).output().unwrap();
            let text = String::from_utf8_lossy(&o.stdout);
            assert!(o.status.success(), "{what}: meshio failed: {}", String::from_utf8_lossy(&o.stderr));
            let lines: Vec<&str> = text.lines().collect();
            assert_eq!(lines[0].parse::<usize>().unwrap(), g.nodes.len(), "{what}: points");
            let kind = g.cells[0].kind;
            assert!(g.cells.iter().all(|c| c.kind == kind), "{what}: one cell type");
            assert_eq!(lines[1..], [format!("{meshio_type} {} {}", g.cells.len(), kind.len())], "{what}: cell blocks");
        }
    }
}
