//! Bodies read from Salome / code_aster MED files (`body.mesh`, `format = "med"` or a `.med`
//! file): the fixtures `mesh/*.med` are Gmsh's own MED export of the `.msh` beside them
//! (`mesh/make_med.py`, written through the MED library, MED's node orders); read, they give
//! the same nodes, cells (node for node, in the program's order) and named faces as the
//! `.msh`, and the two-block models (hex8, tet10) solve bit for bit as from the `.msh`.
//! Broken inputs are one-line errors naming the file.

mod common;

use std::path::Path;

use common::{assert_clean_failure, root, solve, tmpdir};
use tresca_feti::mesh::{gmsh, med};

const GMSH: &str = include_str!("../run/gmsh_blocks.toml");

/// `run/gmsh_blocks.toml` with its bodies read through `body.mesh` from `mesh` (absolute).
fn scene_from(mesh: &Path) -> String {
    let from = |v: &str| format!("gmsh = {{ file = \"../mesh/two_blocks.msh\", volume = \"{v}\" }}");
    let to = |v: &str| format!("mesh = {{ file = \"{}\", volume = \"{v}\" }}", mesh.display());
    assert!(GMSH.contains(&from("upper")) && GMSH.contains(&from("lower")));
    GMSH.replace(&from("upper"), &to("upper")).replace(&from("lower"), &to("lower"))
}

/// Solves the two-block scene from `msh` and from `med` and requires the same displacements,
/// bit for bit.
fn same_solution(tag: &str, msh: &str, med: &str) {
    let dir = tmpdir(tag);
    let (a, b) = (dir.join("msh.toml"), dir.join("med.toml"));
    std::fs::write(&a, scene_from(&root().join(msh))).unwrap();
    std::fs::write(&b, scene_from(&root().join(med))).unwrap();
    let from_msh = solve(&a, &[], &dir.join("msh.h5"));
    let from_med = solve(&b, &[], &dir.join("med.h5"));
    assert!(common::max_abs(&from_msh.solution.displacement) > 0.0);
    assert_eq!(from_med.solution.displacement, from_msh.solution.displacement, "{tag}");
    assert_eq!(from_med.report.results.max_von_mises, from_msh.report.results.max_von_mises);
    let (cm, cg) = (from_med.report.contact.as_ref().unwrap(), from_msh.report.contact.as_ref().unwrap());
    assert_eq!((cm.contact, cm.stick, cm.slip), (cg.contact, cg.stick, cg.slip));
}

/// Groups of nodes are faces (code_aster's GROUP_NO): `mesh/two_blocks_node_groups.med`
/// (`mesh/make_med_node_groups.py`: the two-block model written again by meshio, MED 3.0, with
/// the node groups "clamp" = the nodes of face lower_left and "press_nodes" = those of
/// upper_top) clamped on `lower.clamp` and pressed on `upper.press_nodes` solves bit for bit as
/// the model on its face groups.
#[test]
fn groups_of_nodes_are_faces() {
    let dir = tmpdir("med-node-groups");
    let faces = dir.join("faces.toml");
    std::fs::write(&faces, scene_from(&root().join("mesh/two_blocks.msh"))).unwrap();
    let nodes = dir.join("nodes.toml");
    let scene = scene_from(&root().join("mesh/two_blocks_node_groups.med"));
    assert!(scene.contains("\"lower.lower_left\"") && scene.contains("\"upper.upper_top\""));
    std::fs::write(&nodes, scene.replace("\"lower.lower_left\"", "\"lower.clamp\"").replace("\"upper.upper_top\"", "\"upper.press_nodes\"")).unwrap();
    let a = solve(&faces, &[], &dir.join("faces.h5"));
    let b = solve(&nodes, &[], &dir.join("nodes.h5"));
    assert!(common::max_abs(&a.solution.displacement) > 0.0);
    assert_eq!(b.solution.displacement, a.solution.displacement);
    let g = med::read(&root().join("mesh/two_blocks_node_groups.med"), Some("lower")).unwrap();
    let count = |n: &str| g.faces.iter().find(|(f, _)| f == n).map(|(_, q)| q.len());
    assert_eq!((count("clamp"), count("lower_left")), (Some(9), Some(9)));
}

#[test]
fn two_blocks_from_med_solve_as_from_gmsh() {
    same_solution("hex8", "mesh/two_blocks.msh", "mesh/two_blocks.med");
}

#[test]
fn two_tet10_blocks_from_med_solve_as_from_gmsh() {
    same_solution("tet10", "mesh/two_tet10_blocks.msh", "mesh/two_tet10_blocks.med");
}

#[test]
fn every_cell_type_reads_as_from_gmsh() {
    let cases = [
        ("two_blocks", vec![Some("upper"), Some("lower"), None]),
        ("two_tet_blocks", vec![Some("upper"), Some("lower")]),
        ("two_tet10_blocks", vec![Some("upper"), Some("lower")]),
        ("wedge_layer", vec![Some("body"), Some("layer"), Some("core")]),
    ];
    for (name, volumes) in cases {
        for v in volumes {
            let g = gmsh::read(&root().join(format!("mesh/{name}.msh")), v).unwrap();
            let m = med::read(&root().join(format!("mesh/{name}.med")), v).unwrap();
            assert_eq!(m.nodes, g.nodes, "{name} {v:?}");
            // the cells node for node (MED stores them by type, so a mixed mesh's come in
            // another order: compared sorted), and each face's facets with their cells
            let cells = |c: &[tresca_feti::mesh::Cell]| c.iter().map(|h| (h.kind, h.nodes().to_vec())).collect::<Vec<_>>();
            let (mut cm, mut cg) = (cells(&m.cells), cells(&g.cells));
            cm.sort();
            cg.sort();
            assert_eq!(cm, cg, "{name} {v:?}");
            let mut gf = g.faces.clone();
            gf.sort_by(|a, b| a.0.cmp(&b.0));
            assert!(!gf.is_empty());
            assert_eq!(m.faces.len(), gf.len(), "{name} {v:?}");
            for ((na, fa), (nb, fb)) in m.faces.iter().zip(&gf) {
                assert_eq!(na, nb);
                let key = |f: &[tresca_feti::mesh::Facet], c: &[tresca_feti::mesh::Cell]| {
                    let mut k: Vec<(Vec<usize>, Vec<usize>)> = f.iter().map(|q| (c[q.elem].nodes().to_vec(), q.nodes().to_vec())).collect();
                    k.sort();
                    k
                };
                assert_eq!(key(fa, &m.cells), key(fb, &g.cells), "{name} {v:?} face {na}");
            }
        }
    }
}

/// A copy of `mesh/two_blocks.med` changed by `edit`, in a fresh folder.
fn edited(tag: &str, edit: impl FnOnce(&hdf5::File)) -> std::path::PathBuf {
    let path = tmpdir(&format!("med-{tag}-mesh")).join("bad.med");
    std::fs::copy(root().join("mesh/two_blocks.med"), &path).unwrap();
    let f = hdf5::File::open_rw(&path).unwrap();
    edit(&f);
    drop(f);
    path
}

#[test]
fn broken_inputs_are_one_line_errors_naming_the_file() {
    let mai = "ENS_MAA/two_blocks/-0000000000000000001-0000000000000000001/MAI";
    // a cell type the program does not have
    let h20 = edited("h20", |f| f.group(mai).unwrap().relink("HE8", "H20").unwrap());
    assert_clean_failure("med-type", &scene_from(&h20), &[], &["bad.med", "H20"]);
    // a group that is not there
    let good = root().join("mesh/two_blocks.med");
    let missing = scene_from(&good).replace("volume = \"lower\"", "volume = \"nowhere\"");
    assert_clean_failure("med-group", &missing, &[], &["two_blocks.med", "nowhere", "\"upper\""]);
    // a face group is no body
    let face = scene_from(&good).replace("volume = \"lower\"", "volume = \"lower_top\"");
    assert_clean_failure("med-face-group", &face, &[], &["two_blocks.med", "lower_top"]);
    // not HDF5 at all
    let dir = tmpdir("med-text-mesh");
    let text = dir.join("bad.med");
    std::fs::write(&text, "not a mesh\n").unwrap();
    assert_clean_failure("med-text", &scene_from(&text), &[], &["bad.med", "not a readable MED file"]);
    // HDF5, but no MED mesh in it
    let plain = edited("plain", |f| f.unlink("ENS_MAA").unwrap());
    assert_clean_failure("med-plain", &scene_from(&plain), &[], &["bad.med", "not a MED file"]);
    // cut short
    let bytes = std::fs::read(&good).unwrap();
    let cut = tmpdir("med-cut-mesh").join("bad.med");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    assert_clean_failure("med-cut", &scene_from(&cut), &[], &["bad.med"]);
    // a node reference out of range
    let far = edited("far", |f| {
        let d = f.dataset(&format!("{mai}/HE8/NOD")).unwrap();
        let mut v: Vec<i64> = d.read_raw().unwrap();
        v[0] = 9999;
        d.write_raw(&v).unwrap();
    });
    assert_clean_failure("med-node", &scene_from(&far), &[], &["bad.med", "9999"]);
}

#[test]
fn format_key_and_extension() {
    let copy = tmpdir("med-format-mesh").join("blocks.dat");
    std::fs::copy(root().join("mesh/two_blocks.med"), &copy).unwrap();
    let scene = scene_from(&copy);
    assert_clean_failure("med-unknown-extension", &scene, &[], &["body[0].mesh.file", "med"]);
    let with_format = scene
        .replace("volume = \"upper\" }", "volume = \"upper\", format = \"med\" }")
        .replace("volume = \"lower\" }", "volume = \"lower\", format = \"med\" }");
    let dir = tmpdir("med-format");
    let path = dir.join("scene.toml");
    std::fs::write(&path, with_format).unwrap();
    assert!(solve(&path, &[], &dir.join("r.h5")).report.results.max_displacement > 0.0);
    let (n, e, _) = med::counts(&root().join("mesh/two_blocks.med")).unwrap();
    assert_eq!((n, e), (224, 108 + 81));
}

#[test]
fn med_orders_corners_the_other_way_round() {
    // the file's raw HE8/T10 node lists have det(x1 - x0, x_a - x0, x_b - x0) < 0 on every cell
    // (a = 1, b = 3 for HE8's edges from node 0 with its top node 4; T10: its corners 1, 2, 3),
    // so reading them unconverted would give cells of the wrong orientation
    for (name, ty, k, edges) in [("two_blocks", "HE8", 8, [1, 3, 4]), ("two_tet10_blocks", "T10", 10, [1, 2, 3])] {
        let f = hdf5::File::open(root().join(format!("mesh/{name}.med"))).unwrap();
        let step = format!("ENS_MAA/{name}/-0000000000000000001-0000000000000000001");
        let x: Vec<f64> = f.dataset(&format!("{step}/NOE/COO")).unwrap().read_raw().unwrap();
        let nod: Vec<i64> = f.dataset(&format!("{step}/MAI/{ty}/NOD")).unwrap().read_raw().unwrap();
        let (n, cells) = (x.len() / 3, nod.len() / k);
        let p = |c: usize, j: usize| {
            let v = (nod[j * cells + c] - 1) as usize;
            [x[v], x[n + v], x[2 * n + v]]
        };
        for c in 0..cells {
            let o = p(c, 0);
            let d: Vec<[f64; 3]> = edges.iter().map(|&j| p(c, j)).map(|q| [q[0] - o[0], q[1] - o[1], q[2] - o[2]]).collect();
            let det = d[0][0] * (d[1][1] * d[2][2] - d[1][2] * d[2][1]) - d[0][1] * (d[1][0] * d[2][2] - d[1][2] * d[2][0])
                + d[0][2] * (d[1][0] * d[2][1] - d[1][1] * d[2][0]);
            assert!(det < 0.0, "{name} {ty} cell {c}: {det}");
        }
    }
}
