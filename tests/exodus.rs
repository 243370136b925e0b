//! Bodies read from Exodus II files (`body.mesh`, `format = "exodus"` or a `.exo`/`.e` file):
//! the two-block contact model read from `mesh/two_blocks.exo` (netCDF-4) and
//! `mesh/two_blocks_classic.exo` (netCDF-3, 64-bit offset), both written from
//! `mesh/two_blocks.msh` by `mesh/make_exodus.py` with side sets of (hexahedron, Exodus side
//! number), solves bit for bit as the same model read from the `.msh` — which checks the side
//! numbering independently; a node set gives the same facets as the side set of the same
//! surface; a 10-node tetrahedron written here comes out in the program's node order; bad
//! files are one-line errors naming the file.

mod common;

use std::path::{Path, PathBuf};

use common::{assert_clean_failure, root, solve, tmpdir};
use tresca_feti::mesh::exodus;

const GMSH: &str = include_str!("../run/gmsh_blocks.toml");

/// `run/gmsh_blocks.toml` with its bodies read through `body.mesh` from `mesh` (absolute).
fn exodus_scene(mesh: &Path) -> String {
    let from = |v: &str| format!("gmsh = {{ file = \"../mesh/two_blocks.msh\", volume = \"{v}\" }}");
    let to = |v: &str| format!("mesh = {{ file = \"{}\", volume = \"{v}\" }}", mesh.display());
    assert!(GMSH.contains(&from("upper")) && GMSH.contains(&from("lower")));
    GMSH.replace(&from("upper"), &to("upper")).replace(&from("lower"), &to("lower"))
}

#[test]
fn two_blocks_from_exodus_solve_as_from_gmsh() {
    let dir = tmpdir("exo-same");
    let gmsh = solve(&root().join("run/gmsh_blocks.toml"), &[], &dir.join("gmsh.h5"));
    assert!(common::max_abs(&gmsh.solution.displacement) > 0.0);
    for file in ["two_blocks.exo", "two_blocks_classic.exo"] {
        let scene = dir.join(format!("{file}.toml"));
        std::fs::write(&scene, exodus_scene(&root().join("mesh").join(file))).unwrap();
        let exo = solve(&scene, &[], &dir.join(format!("{file}.h5")));
        // the same nodes, cells and faces: the same solution, bit for bit
        assert_eq!(exo.solution.displacement, gmsh.solution.displacement, "{file}");
        assert_eq!(exo.report.results.max_von_mises, gmsh.report.results.max_von_mises, "{file}");
        let (ce, cg) = (exo.report.contact.as_ref().unwrap(), gmsh.report.contact.as_ref().unwrap());
        assert_eq!((ce.contact, ce.stick, ce.slip), (cg.contact, cg.stick, cg.slip), "{file}");
    }
}

/// A face's facets as (cell, sorted corners), sorted.
fn keys(g: &tresca_feti::mesh::BodyGeometry, name: &str) -> Vec<(usize, [usize; 4])> {
    let f = &g.faces.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no face {name}")).1;
    let mut k: Vec<(usize, [usize; 4])> = f.iter().map(|q| (q.elem, q.key())).collect();
    k.sort_unstable();
    k
}

#[test]
fn both_containers_read_alike_and_node_sets_make_faces() {
    let nc4 = exodus::read(&root().join("mesh/two_blocks.exo"), Some("upper")).unwrap();
    let nc3 = exodus::read(&root().join("mesh/two_blocks_classic.exo"), Some("UPPER")).unwrap();
    let msh = tresca_feti::mesh::gmsh::read(&root().join("mesh/two_blocks.msh"), Some("upper")).unwrap();
    for g in [&nc4, &nc3] {
        assert_eq!(g.nodes, msh.nodes);
        assert_eq!(g.cells, msh.cells);
        let names: Vec<&str> = g.faces.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["upper_top", "upper_bottom", "upper_left", "upper_right", "upper_top_nodes"]);
        for (name, facets) in &msh.faces {
            assert_eq!(&g.faces.iter().find(|(n, _)| n == name).unwrap().1, facets, "{name}");
        }
        // the node set of upper_top's nodes: exactly the facets of the side set
        assert_eq!(keys(g, "upper_top_nodes"), keys(g, "upper_top"));
        assert_eq!(keys(g, "upper_top").len(), 18);
    }
    // blocks by id; every volume block when no volume is named
    let by_id = exodus::read(&root().join("mesh/two_blocks.exo"), Some("block_2")).unwrap();
    assert_eq!(by_id.cells.len(), 54);
    assert!(by_id.nodes.iter().all(|p| p[2] <= 1.0));
    assert_eq!(exodus::read(&root().join("mesh/two_blocks.exo"), None).unwrap().cells.len(), 108);
    let c = exodus::counts(&root().join("mesh/two_blocks_classic.exo")).unwrap();
    assert_eq!((c.0, c.1), (224, 108));
    assert_eq!(exodus::counts(&root().join("mesh/two_blocks.exo")).map(|c| (c.0, c.1)), Some((224, 108)));
}

/// Writes a netCDF-3 Exodus file of one block of `elem_type` (`conn`: 1-based nodes) with a side
/// set "base" of `(element, side)` pairs and a node set "corner" of `ns`.
fn write_classic(path: &Path, x: &[[f64; 3]], elem_type: &str, conn: &[Vec<i32>], ss: &[(i32, i32)], ns: &[i32]) {
    use netcdf3::{DataSet, FileWriter, Version};
    let mut d = DataSet::new();
    d.add_fixed_dim("len_name", 33).unwrap();
    d.add_fixed_dim("num_dim", 3).unwrap();
    d.add_fixed_dim("num_nodes", x.len()).unwrap();
    d.add_fixed_dim("num_el_blk", 1).unwrap();
    d.add_fixed_dim("num_el_in_blk1", conn.len()).unwrap();
    d.add_fixed_dim("num_nod_per_el1", conn[0].len()).unwrap();
    d.add_fixed_dim("num_side_sets", 1).unwrap();
    d.add_fixed_dim("num_side_ss1", ss.len()).unwrap();
    d.add_fixed_dim("num_node_sets", 1).unwrap();
    d.add_fixed_dim("num_nod_ns1", ns.len()).unwrap();
    for c in ["coordx", "coordy", "coordz"] {
        d.add_var_f64(c, &["num_nodes"]).unwrap();
    }
    d.add_var_u8("eb_names", &["num_el_blk", "len_name"]).unwrap();
    d.add_var_i32("eb_prop1", &["num_el_blk"]).unwrap();
    d.add_var_i32("connect1", &["num_el_in_blk1", "num_nod_per_el1"]).unwrap();
    d.add_var_attr_string("connect1", "elem_type", elem_type).unwrap();
    d.add_var_u8("ss_names", &["num_side_sets", "len_name"]).unwrap();
    d.add_var_i32("ss_prop1", &["num_side_sets"]).unwrap();
    d.add_var_i32("elem_ss1", &["num_side_ss1"]).unwrap();
    d.add_var_i32("side_ss1", &["num_side_ss1"]).unwrap();
    d.add_var_u8("ns_names", &["num_node_sets", "len_name"]).unwrap();
    d.add_var_i32("node_ns1", &["num_nod_ns1"]).unwrap();
    let name = |s: &str| {
        let mut b = s.as_bytes().to_vec();
        b.resize(33, 0);
        b
    };
    let mut w = FileWriter::open(path).unwrap();
    w.set_def(&d, Version::Offset64Bit, 0).unwrap();
    for (k, c) in ["coordx", "coordy", "coordz"].iter().enumerate() {
        w.write_var_f64(c, &x.iter().map(|p| p[k]).collect::<Vec<_>>()).unwrap();
    }
    w.write_var_u8("eb_names", &name("solid")).unwrap();
    w.write_var_i32("eb_prop1", &[7]).unwrap();
    w.write_var_i32("connect1", &conn.concat()).unwrap();
    w.write_var_u8("ss_names", &name("base")).unwrap();
    w.write_var_i32("ss_prop1", &[1]).unwrap();
    w.write_var_i32("elem_ss1", &ss.iter().map(|s| s.0).collect::<Vec<_>>()).unwrap();
    w.write_var_i32("side_ss1", &ss.iter().map(|s| s.1).collect::<Vec<_>>()).unwrap();
    w.write_var_u8("ns_names", &name("corner")).unwrap();
    w.write_var_i32("node_ns1", ns).unwrap();
    w.close().unwrap();
}

/// The unit tetrahedron as Exodus TETRA10 (edge nodes 5-10 on edges 1-2, 2-3, 3-1, 1-4, 2-4,
/// 3-4), its side 4 (1-3-2, the base z = 0) a side set and the base's six nodes a node set.
fn tet10(dir: &Path, elem_type: &str) -> PathBuf {
    let c = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let edges = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];
    let mut x = c.to_vec();
    for [a, b] in edges {
        x.push([0.5 * (c[a][0] + c[b][0]), 0.5 * (c[a][1] + c[b][1]), 0.5 * (c[a][2] + c[b][2])]);
    }
    let path = dir.join("tet10.e");
    write_classic(&path, &x, elem_type, &[(1..=10).collect()], &[(1, 4)], &[1, 2, 3, 5, 6, 7]);
    path
}

#[test]
fn tet10_edge_nodes_come_in_our_order() {
    let dir = tmpdir("exo-tet10");
    let g = exodus::read(&tet10(&dir, "TETRA10"), Some("solid")).unwrap();
    let c = &g.cells[0];
    // ours (Gmsh's): 4:(0,1) 5:(1,2) 6:(2,0) 7:(3,0) 8:(3,2) 9:(3,1)
    let ours = [[0, 1], [1, 2], [2, 0], [3, 0], [3, 2], [3, 1]];
    let p = |i: usize| g.nodes[c.nodes()[i]];
    for (k, [a, b]) in ours.iter().enumerate() {
        for d in 0..3 {
            assert!((p(4 + k)[d] - 0.5 * (p(*a)[d] + p(*b)[d])).abs() < 1e-15, "edge node {}", 4 + k);
        }
    }
    for face in ["base", "corner"] {
        let f = &g.faces.iter().find(|(n, _)| n == face).unwrap().1;
        assert_eq!(f.len(), 1, "{face}");
        assert!(f[0].nodes().iter().all(|&v| g.nodes[v][2] == 0.0), "{face}");
    }
    assert_eq!(keys(&g, "base"), keys(&g, "corner"));
    // the block by its id
    assert_eq!(exodus::read(&dir.join("tet10.e"), Some("block_7")).unwrap().cells.len(), 1);
}

#[test]
fn bad_files_are_one_line_errors_naming_the_file() {
    let upper = |mesh: &Path| exodus_scene(mesh);
    // an element type not read, named with its block
    let dir = tmpdir("exo-bad-type-mesh");
    let path = tet10(&dir, "TETRA14");
    let scene = upper(&path).replace("volume = \"upper\"", "volume = \"solid\"");
    assert_clean_failure("exo-type", &scene, &[], &["tet10.e", "\"solid\"", "TETRA14", "HEX8"]);
    // an unknown block, named with the known ones
    let bad = upper(&root().join("mesh/two_blocks.exo")).replace("volume = \"lower\"", "volume = \"nowhere\"");
    assert_clean_failure("exo-block", &bad, &[], &["two_blocks.exo", "nowhere", "\"upper\" (id 1)"]);
    // not an Exodus file: a Gmsh mesh and an HDF5 file of another kind
    let dir = tmpdir("exo-bad-files");
    let msh = dir.join("blocks.exo");
    std::fs::copy(root().join("mesh/two_blocks.msh"), &msh).unwrap();
    assert_clean_failure("exo-not", &upper(&msh), &[], &["blocks.exo", "not an Exodus II file"]);
    let h5 = dir.join("other.e");
    hdf5::File::create(&h5).unwrap().new_dataset::<f64>().shape(3).create("x").unwrap();
    assert_clean_failure("exo-h5", &upper(&h5), &[], &["other.e", "no node coordinates"]);
    // truncated files, of both containers
    for file in ["two_blocks.exo", "two_blocks_classic.exo"] {
        let bytes = std::fs::read(root().join("mesh").join(file)).unwrap();
        let cut = dir.join(format!("cut_{file}"));
        std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
        assert_clean_failure(&format!("exo-cut-{file}"), &upper(&cut), &[], &[&format!("cut_{file}"), "truncated"]);
    }
    // CDF-5 is refused with the conversion
    let cdf5 = dir.join("cdf5.exo");
    let mut bytes = std::fs::read(root().join("mesh/two_blocks_classic.exo")).unwrap();
    bytes[3] = 5;
    std::fs::write(&cdf5, bytes).unwrap();
    assert_clean_failure("exo-cdf5", &upper(&cdf5), &[], &["cdf5.exo", "nccopy -k nc4"]);
}

#[test]
fn format_key_and_extension() {
    let dir = tmpdir("exo-format");
    let copy = tmpdir("exo-format-mesh").join("blocks.data");
    std::fs::copy(root().join("mesh/two_blocks.exo"), &copy).unwrap();
    let scene = exodus_scene(&copy);
    assert_clean_failure("exo-unknown-extension", &scene, &[], &["body[0].mesh.file", ".exo/.e/.ex2 for exodus", "\"exodus\""]);
    let with_format = scene.replace("\" }", "\", format = \"exodus\" }");
    let path = dir.join("scene.toml");
    std::fs::write(&path, with_format).unwrap();
    assert!(solve(&path, &[], &dir.join("r.h5")).report.results.max_displacement > 0.0);
}
