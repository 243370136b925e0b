//! The XDMF sidecar of every cell type that needs a node-order table — 20- and 27-node
//! hexahedra (box generator), 15-node wedges (`mesh/prism_wedge15.msh`), pyramids alone (a
//! cube cut into six pyramids, written here) and hexahedra + pyramids + tetrahedra
//! (`mesh/hex_pyr_tet.msh`) — opened by a reader of its own, meshio (Debian python3-meshio,
//! run/install-deps), and checked by geometry against VTK's node orders written out below from
//! VTK's cell documentation (not from the program's tables): every edge node at the midpoint of
//! its two corners, every Hex27 face node at the mean of its four corners and the centre node at
//! the mean of the eight, every cell right-handed in VTK's isoparametric map (a positive
//! Jacobian at its centre), as many cells and points as the solver has, the points and the
//! displacement bit for bit those of the HDF5 file and of the solver's memory.

mod common;

use std::path::Path;

use common::{f64_field, fields, root, solve, tmpdir};
use tresca_feti::mesh::{cell_counts, gmsh, CellKind};

/// VTK_QUADRATIC_HEXAHEDRON (and the first 20 nodes of VTK_TRIQUADRATIC_HEXAHEDRON): the
/// corners of the edge nodes 8..20 — bottom ring, top ring, then the vertical edges.
const VTK_HEX20_EDGES: [[usize; 2]; 12] = [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4], [0, 4], [1, 5], [2, 6], [3, 7]];
/// VTK_TRIQUADRATIC_HEXAHEDRON: the corners of the face nodes 20..26 (faces x−, x+, y−, y+, z−,
/// z+ of the parametric cube); node 26 is the centre.
const VTK_HEX27_FACES: [[usize; 4]; 6] = [[0, 3, 7, 4], [1, 2, 6, 5], [0, 1, 5, 4], [3, 2, 6, 7], [0, 1, 2, 3], [4, 5, 6, 7]];
/// VTK_QUADRATIC_WEDGE: the corners of the edge nodes 6..15 — triangle (0,1,2), triangle
/// (3,4,5), then the edges between them.
const VTK_WEDGE15_EDGES: [[usize; 2]; 9] = [[0, 1], [1, 2], [2, 0], [3, 4], [4, 5], [5, 3], [0, 3], [1, 4], [2, 5]];

/// meshio's name of a cell block: (corners, edge-node table, Hex27 face and centre nodes).
fn vtk_cell(kind: &str) -> (usize, &'static [[usize; 2]], bool) {
    match kind {
        "tetra" => (4, &[], false),
        "pyramid" => (5, &[], false),
        "wedge" => (6, &[], false),
        "wedge15" => (6, &VTK_WEDGE15_EDGES, false),
        "hexahedron" => (8, &[], false),
        "hexahedron20" => (8, &VTK_HEX20_EDGES, false),
        "hexahedron27" => (8, &VTK_HEX20_EDGES, true),
        other => panic!("no check for meshio cell type {other}"),
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|d| a[d] - b[d])
}

fn add(vs: &[[f64; 3]]) -> [f64; 3] {
    vs.iter().fold([0.0; 3], |s, v| std::array::from_fn(|d| s[d] + v[d]))
}

fn det(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// The Jacobian determinant of VTK's isoparametric map of the corners `x` at the cell's centre
/// (up to a positive factor): VTK's parametric corners are, for the tetrahedron (0,0,0),
/// (1,0,0), (0,1,0), (0,0,1); the pyramid the unit square then the apex above it; the wedge
/// (0,0,0), (1,0,0), (0,1,0) then the same at ζ = 1; the hexahedron the unit square at ζ = 0
/// counter-clockwise, then at ζ = 1. For the pyramid the smaller of the two tetrahedra
/// (0,1,2,4) and (0,2,3,4). (vtkWedge's class comment has the base's normal pointing away from
/// the other triangle; its parametric coordinates, which interpolation uses, are these.)
fn jacobian(x: &[[f64; 3]]) -> f64 {
    let d = |i: usize, j: usize| sub(x[i], x[j]);
    match x.len() {
        4 => det(d(1, 0), d(2, 0), d(3, 0)),
        5 => det(d(1, 0), d(2, 0), d(4, 0)).min(det(d(2, 0), d(3, 0), d(4, 0))),
        6 => det(add(&[d(1, 0), d(4, 3)]), add(&[d(2, 0), d(5, 3)]), add(&[d(3, 0), d(4, 1), d(5, 2)])),
        _ => det(add(&[d(1, 0), d(2, 3), d(5, 4), d(6, 7)]), add(&[d(3, 0), d(2, 1), d(7, 4), d(6, 5)]), add(&[d(4, 0), d(5, 1), d(6, 2), d(7, 3)])),
    }
}

/// What meshio read from an XDMF file: the points, the cell blocks (meshio's type name, the
/// cells' nodes) and the point field "displacement" (flattened).
struct ReadBack {
    points: Vec<[f64; 3]>,
    blocks: Vec<(String, Vec<Vec<usize>>)>,
    displacement: Vec<f64>,
}

/// Opens `xdmf` with meshio under /usr/bin/python3; floats come back as their 64 bits, so
/// exactly. (Debian's meshio 5.0 maps Wedge_15 to "wedge15" without a dimension for it — a
/// KeyError in CellBlock — so the script gives it one where missing.)
fn meshio_read(xdmf: &Path) -> ReadBack {
    const SCRIPT: &str = "import sys, json, meshio, numpy as np\n\
        from meshio import _mesh\n\
        _mesh.topological_dimension.setdefault('wedge15', 3)\n\
        m = meshio.read(sys.argv[1])\n\
        bits = lambda a: np.ascontiguousarray(a, dtype=np.float64).view(np.uint64).ravel().tolist()\n\
        print(json.dumps({'points': bits(m.points), 'blocks': [[b.type, b.data.tolist()] for b in m.cells],\n\
                          'displacement': bits(m.point_data['displacement'])}))\n";
    let o = std::process::Command::new("/usr/bin/python3")
        .args(["-c", SCRIPT])
        .arg(xdmf)
        .output()
        .expect("/usr/bin/python3 with meshio (run/install-deps installs python3-meshio)");
    assert!(o.status.success(), "{}: meshio failed (run/install-deps installs python3-meshio): {}", xdmf.display(), String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let floats = |key: &str| -> Vec<f64> { v[key].as_array().unwrap().iter().map(|b| f64::from_bits(b.as_u64().unwrap())).collect() };
    let p = floats("points");
    let blocks = v["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            let cells = b[1].as_array().unwrap().iter().map(|c| c.as_array().unwrap().iter().map(|i| i.as_u64().unwrap() as usize).collect()).collect();
            (b[0].as_str().unwrap().to_string(), cells)
        })
        .collect();
    ReadBack { points: p.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(), blocks, displacement: floats("displacement") }
}

/// Solves `scene` into `dir/name.h5` and checks its XDMF as meshio reads it: the cell blocks
/// (meshio's type, count) are `expect`, the points `nodes` — the counts from the mesh itself,
/// not from the result — and the geometry as the module says.
fn check(dir: &Path, name: &str, scene: &str, expect: &[(&str, usize)], nodes: usize) {
    let toml = dir.join(format!("{name}.toml"));
    std::fs::write(&toml, scene).unwrap();
    let out = dir.join(format!("{name}.h5"));
    let summary = solve(&toml, &[], &out);
    let data = fields(&out);
    let m = meshio_read(&out.with_extension("xdmf"));
    // counts: meshio's, the mesh's, the solver's
    let mut blocks = std::collections::BTreeMap::new();
    m.blocks.iter().for_each(|(k, c)| *blocks.entry(k.as_str()).or_insert(0) += c.len());
    assert_eq!(blocks, expect.iter().copied().collect(), "{name}: cells of each type");
    let ncells: usize = expect.iter().map(|e| e.1).sum();
    assert_eq!(summary.solution.von_mises.len(), ncells, "{name}: the solver's cells");
    assert_eq!(m.points.len(), nodes, "{name}: points");
    assert_eq!(summary.solution.displacement.len(), nodes, "{name}: the solver's nodes");
    // points and displacement bit for bit
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
    assert_eq!(bits(&m.points.concat()), bits(&data.coordinates.concat()), "{name}: points differ from /mesh/coordinates");
    assert_eq!(bits(&m.displacement), bits(f64_field(&data, "displacement")), "{name}: displacement differs from the HDF5 dataset");
    assert_eq!(bits(&m.displacement), bits(&summary.solution.displacement.concat()), "{name}: displacement differs from the solver's");
    assert!(common::max_abs(&summary.solution.displacement) > 0.0, "{name}: nothing moved");
    // geometry in VTK's node order
    let h = data.coordinates.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|d| (a[d] - b[d]).abs() <= 1e-12 * h);
    let mean = |x: &[[f64; 3]]| add(x).map(|s| s / x.len() as f64);
    let (mut jmin, mut jmax) = (f64::INFINITY, 0.0f64);
    for (kind, cells) in &m.blocks {
        let (corners, edges, faces) = vtk_cell(kind);
        for (c, nodes) in cells.iter().enumerate() {
            let x: Vec<[f64; 3]> = nodes.iter().map(|&i| m.points[i]).collect();
            for (e, [a, b]) in edges.iter().enumerate() {
                assert!(close(x[corners + e], mean(&[x[*a], x[*b]])), "{name}: {kind} {c}: node {} not midway on ({a},{b})", corners + e);
            }
            if faces {
                for (f, q) in VTK_HEX27_FACES.iter().enumerate() {
                    assert!(close(x[20 + f], mean(&q.map(|k| x[k]))), "{name}: {kind} {c}: node {} not the centre of face {q:?}", 20 + f);
                }
                assert!(close(x[26], mean(&x[..8])), "{name}: {kind} {c}: node 26 not the body centre");
            }
            let j = jacobian(&x[..corners]);
            assert!(j > 0.0, "{name}: {kind} {c}: not right-handed in VTK's order (Jacobian {j:e})");
            (jmin, jmax) = (jmin.min(j), jmax.max(j));
        }
    }
    eprintln!("{name}: {blocks:?}, {nodes} points; Jacobians in VTK's order from {jmin:.3e} to {jmax:.3e}");
}

/// One body of `mesh` (TOML of the body's mesh) of material E = 1000, ν = 0.3, held on
/// `held` and pulled by p = (0.1, 0.2, 1) on `pulled`, with `faces` defining them.
fn scene(mesh: &str, held: &str, pulled: &str, faces: &str) -> String {
    format!(
        "title = \"xdmf read-back\"\n[[material]]\nname = \"m\"\nE = 1000.0\nnu = 0.3\n[[body]]\nname = \"b\"\nmaterial = \"m\"\n{mesh}\n{faces}\
         [[dirichlet]]\nface = \"b.{held}\"\n[[traction]]\nface = \"b.{pulled}\"\np = [0.1, 0.2, 1.0]\n"
    )
}

/// Faces `clamp` (x < `x`) and `pull` (x > `x`) cut from the mesh's face `from`.
fn halves(from: &str, x: f64) -> String {
    let face = |name: &str, lo: f64, hi: f64| {
        format!("[[face]]\nname = \"{name}\"\nbody = \"b\"\nfrom = \"{from}\"\nmin = [{lo:?}, -10.0, -10.0]\nmax = [{hi:?}, 10.0, 10.0]\n")
    };
    face("clamp", -10.0, x) + &face("pull", x, 10.0)
}

/// A Gmsh 4.1 mesh of the box [0,2]×[0,1]×[0,1] as two unit cubes, each cut into six pyramids
/// (a cube face as base, the cube's centre as apex, Gmsh type 7), with the physical volume
/// "body" and the physical surface "ends" (the quadrangles at x = 0 and x = 2, outward).
fn pyramid_mesh() -> String {
    let mut x: Vec<[f64; 3]> = Vec::new();
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..3 {
                x.push([i as f64, j as f64, k as f64]);
            }
        }
    }
    x.extend([[0.5, 0.5, 0.5], [1.5, 0.5, 0.5]]);
    let id = |i: usize, j: usize, k: usize| k * 6 + j * 3 + i;
    let mut pyramids = Vec::new();
    let mut ends = Vec::new();
    for cube in 0..2 {
        let apex = 12 + cube;
        // the six faces, each counter-clockwise seen from outside the cube
        let c = |i: usize, j: usize, k: usize| id(cube + i, j, k);
        let faces = [
            [c(0, 0, 0), c(0, 0, 1), c(0, 1, 1), c(0, 1, 0)],
            [c(1, 0, 0), c(1, 1, 0), c(1, 1, 1), c(1, 0, 1)],
            [c(0, 0, 0), c(1, 0, 0), c(1, 0, 1), c(0, 0, 1)],
            [c(0, 1, 0), c(0, 1, 1), c(1, 1, 1), c(1, 1, 0)],
            [c(0, 0, 0), c(0, 1, 0), c(1, 1, 0), c(1, 0, 0)],
            [c(0, 0, 1), c(1, 0, 1), c(1, 1, 1), c(0, 1, 1)],
        ];
        for (f, q) in faces.iter().enumerate() {
            // Gmsh's pyramid: the base counter-clockwise seen from the apex (inside)
            pyramids.push([q[3], q[2], q[1], q[0], apex]);
            if (cube, f) == (0, 0) || (cube, f) == (1, 1) {
                ends.push(*q);
            }
        }
    }
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n2 5 \"ends\"\n3 7 \"body\"\n$EndPhysicalNames\n");
    s += "$Entities\n0 0 1 1\n1 0 0 0 2 1 1 1 5 0\n1 0 0 0 2 1 1 1 7 1 1\n$EndEntities\n";
    s += &format!("$Nodes\n1 {n} 1 {n}\n3 1 0 {n}\n", n = x.len());
    s += &(1..=x.len()).map(|t| format!("{t}\n")).collect::<String>();
    s += &x.iter().map(|p| format!("{} {} {}\n", p[0], p[1], p[2])).collect::<String>();
    let line = |tag: usize, nodes: &[usize]| format!("{tag}{}\n", nodes.iter().map(|v| format!(" {}", v + 1)).collect::<String>());
    s += &format!("$EndNodes\n$Elements\n2 {} 1 {}\n2 1 3 {}\n", ends.len() + pyramids.len(), ends.len() + pyramids.len(), ends.len());
    s += &ends.iter().enumerate().map(|(e, q)| line(e + 1, q)).collect::<String>();
    s += &format!("3 1 7 {}\n", pyramids.len());
    s += &pyramids.iter().enumerate().map(|(e, p)| line(ends.len() + e + 1, p)).collect::<String>();
    s + "$EndElements\n"
}

/// The box generator's quadratic hexahedra: a 2 × 1 × 1 box of 3 × 2 × 2 cells (sides of
/// different lengths, so that a swapped axis shows), held at x = 0 and pulled at x = 2.
#[test]
fn quadratic_hexahedra_read_back_by_meshio() {
    let dir = tmpdir("xdmf-readback-hex");
    // nodes of the 27-node grid, 7 × 5 × 5; the 20-node cells lack the face and centre nodes
    let (cx, cy, cz) = (3usize, 2usize, 2usize);
    let all = (2 * cx + 1) * (2 * cy + 1) * (2 * cz + 1);
    let face_nodes = cx * cy * (cz + 1) + cx * (cy + 1) * cz + (cx + 1) * cy * cz;
    for (cells, meshio_type, nodes) in [("hex20", "hexahedron20", all - face_nodes - cx * cy * cz), ("hex27", "hexahedron27", all)] {
        let mesh = format!("box = {{ min = [0.0, 0.0, 0.0], max = [2.0, 1.0, 1.0], nodes = [{}, {}, {}], cells = \"{cells}\" }}", cx + 1, cy + 1, cz + 1);
        check(&dir, cells, &scene(&mesh, "xmin", "xmax", ""), &[(meshio_type, cx * cy * cz)], nodes);
    }
}

/// The Gmsh fixtures of 27-node hexahedra and 15-node wedges, held on half their top and
/// pulled on the other half; cells and nodes counted by the Gmsh reader.
#[test]
fn quadratic_gmsh_fixtures_read_back_by_meshio() {
    let dir = tmpdir("xdmf-readback-fixtures");
    for (name, meshio_type) in [("cube_hex27", "hexahedron27"), ("prism_wedge15", "wedge15")] {
        let file = root().join(format!("mesh/{name}.msh"));
        let g = gmsh::read(&file, Some("body")).unwrap_or_else(|e| panic!("{e}"));
        let mesh = format!("mesh = {{ file = \"{}\", volume = \"body\" }}", file.display());
        check(&dir, name, &scene(&mesh, "clamp", "pull", &halves("top", 0.4)), &[(meshio_type, g.cells.len())], g.nodes.len());
    }
}

/// Pyramids alone (`/mesh/pyramids`, XDMF `Pyramid`) and with hexahedra and tetrahedra (a
/// `Mixed` topology: the upper block of `mesh/hex_pyr_tet.msh`), cells counted by the Gmsh
/// reader.
#[test]
fn pyramids_alone_and_mixed_read_back_by_meshio() {
    let dir = tmpdir("xdmf-readback-pyramids");
    let file = dir.join("pyramids.msh");
    std::fs::write(&file, pyramid_mesh()).unwrap();
    let g = gmsh::read(&file, Some("body")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(cell_counts(&g.cells), [(CellKind::Pyr5, 12)]);
    let mesh = format!("mesh = {{ file = \"{}\", volume = \"body\" }}", file.display());
    check(&dir, "pyramids", &scene(&mesh, "clamp", "pull", &halves("ends", 1.0)), &[("pyramid", 12)], 14);
    let xdmf = std::fs::read_to_string(dir.join("pyramids.xdmf")).unwrap();
    assert!(xdmf.contains(r#"<Topology TopologyType="Pyramid" NumberOfElements="12">"#), "{xdmf}");

    let file = root().join("mesh/hex_pyr_tet.msh");
    let g = gmsh::read(&file, Some("upper")).unwrap_or_else(|e| panic!("{e}"));
    let count = |k: CellKind| g.cells.iter().filter(|c| c.kind == k).count();
    let expect = [("tetra", count(CellKind::Tet4)), ("pyramid", count(CellKind::Pyr5)), ("hexahedron", count(CellKind::Hex8))];
    assert!(expect.iter().all(|e| e.1 > 0), "{expect:?}");
    let mesh = format!("mesh = {{ file = \"{}\", volume = \"upper\" }}", file.display());
    check(&dir, "hex_pyr_tet", &scene(&mesh, "upper_right", "upper_top", ""), &expect, g.nodes.len());
}
