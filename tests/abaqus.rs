//! Bodies read from Abaqus input files (`body.mesh`, `format = "abaqus"` or a `.inp` file):
//! the two-block contact model read from `mesh/two_blocks.inp` (Gmsh's own Abaqus export of
//! `mesh/two_blocks.msh`, its coordinates written in full precision) solves bit for bit as the same model read from the `.msh`; a hand-written
//! 10-node tetrahedron comes out in the program's node order; malformed inputs are one-line
//! errors naming the file and the line. The same model written as Abaqus/CAE writes parts and
//! an assembly (`mesh/two_blocks_assembly.inp`, made by `mesh/make_two_blocks_assembly.py`)
//! solves bit for bit as the plain input, and `check` lists the keywords it skipped.

mod common;

use std::path::Path;

use common::{assert_clean_failure, root, solve, tmpdir};

const GMSH: &str = include_str!("../run/gmsh_blocks.toml");

/// `run/gmsh_blocks.toml` with its bodies read through `body.mesh` from `mesh` (absolute).
fn abaqus_scene(mesh: &Path) -> String {
    let from = |v: &str| format!("gmsh = {{ file = \"../mesh/two_blocks.msh\", volume = \"{v}\" }}");
    let to = |v: &str| format!("mesh = {{ file = \"{}\", volume = \"{v}\" }}", mesh.display());
    assert!(GMSH.contains(&from("upper")) && GMSH.contains(&from("lower")));
    GMSH.replace(&from("upper"), &to("upper")).replace(&from("lower"), &to("lower"))
}

#[test]
fn two_blocks_from_abaqus_solve_as_from_gmsh() {
    let dir = tmpdir("same");
    let gmsh = solve(&root().join("run/gmsh_blocks.toml"), &[], &dir.join("gmsh.h5"));
    let scene = dir.join("abaqus.toml");
    std::fs::write(&scene, abaqus_scene(&root().join("mesh/two_blocks.inp"))).unwrap();
    let abaqus = solve(&scene, &[], &dir.join("abaqus.h5"));
    // the same nodes (full-precision coordinates), cells and faces: the same solution, bit for bit
    assert!(common::max_abs(&gmsh.solution.displacement) > 0.0);
    assert_eq!(abaqus.solution.displacement, gmsh.solution.displacement);
    assert_eq!(abaqus.report.results.max_von_mises, gmsh.report.results.max_von_mises);
    let (ca, cg) = (abaqus.report.contact.as_ref().unwrap(), gmsh.report.contact.as_ref().unwrap());
    assert_eq!((ca.contact, ca.stick, ca.slip), (cg.contact, cg.stick, cg.slip));
}

/// A node set is a face (what Abaqus/CAE writes for the set a boundary condition names): the
/// model with its clamped face `lower_left` given as an `*NSET` of that face's nodes (no surface
/// of the name) solves bit for bit as the model with the surface.
#[test]
fn a_node_set_holds_a_body_as_its_surface_does() {
    let dir = tmpdir("nset");
    let text = std::fs::read_to_string(root().join("mesh/two_blocks.inp")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let labels = |line: &str| -> Vec<u64> { line.split(',').filter_map(|t| t.trim().parse().ok()).collect() };
    // the surface elements of the element set lower_left, and their nodes
    let at = lines.iter().position(|l| l.eq_ignore_ascii_case("*ELSET,ELSET=lower_left")).expect("the set");
    let elems: Vec<u64> = labels(lines[at + 1]);
    assert_eq!(elems.len(), 9);
    let mut nodes: Vec<u64> = lines
        .iter()
        .filter(|l| !l.starts_with('*'))
        .map(|l| labels(l))
        .filter(|v| v.len() == 5 && elems.contains(&v[0]))
        .flat_map(|v| v[1..].to_vec())
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    assert_eq!(nodes.len(), 16, "a 3 × 3 face");
    let mut edited: Vec<String> = lines.iter().enumerate().filter(|(i, _)| *i != at && *i != at + 1).map(|(_, l)| l.to_string()).collect();
    edited.push("*NSET, NSET=fixed_nodes".into());
    edited.extend(nodes.chunks(8).map(|c| c.iter().map(u64::to_string).collect::<Vec<_>>().join(", ")));
    let mesh = dir.join("nset.inp");
    std::fs::write(&mesh, edited.join("\n") + "\n").unwrap();
    let with_surface = dir.join("surface.toml");
    std::fs::write(&with_surface, abaqus_scene(&root().join("mesh/two_blocks.inp"))).unwrap();
    let with_nset = dir.join("nset.toml");
    let scene = abaqus_scene(&mesh);
    assert!(scene.contains("\"lower.lower_left\""));
    std::fs::write(&with_nset, scene.replace("\"lower.lower_left\"", "\"lower.fixed_nodes\"")).unwrap();
    let a = solve(&with_surface, &[], &dir.join("surface.h5"));
    let b = solve(&with_nset, &[], &dir.join("nset.h5"));
    assert!(common::max_abs(&a.solution.displacement) > 0.0);
    assert_eq!(a.solution.displacement, b.solution.displacement);
}

/// Pyramids from Abaqus (`C3D5`): `mesh/hex_pyr_tet.inp`, Gmsh's Abaqus export of the
/// hexahedral-dominant `mesh/hex_pyr_tet.msh` (hexahedra, pyramids, tetrahedra; full-precision
/// coordinates), reads as the same nodes, cells and faces as the `.msh` for each volume, and a
/// body of it clamped and pressed solves bit for bit as from the `.msh`.
#[test]
fn pyramids_read_and_solve_as_from_gmsh() {
    use tresca_feti::mesh::{abaqus, gmsh, CellKind};
    for volume in ["upper", "lower"] {
        let a = abaqus::read(&root().join("mesh/hex_pyr_tet.inp"), Some(volume)).unwrap();
        let g = gmsh::read(&root().join("mesh/hex_pyr_tet.msh"), Some(volume)).unwrap();
        assert_eq!(a.nodes, g.nodes, "{volume}: nodes");
        let cells = |b: &tresca_feti::mesh::BodyGeometry| b.cells.iter().map(|c| (c.kind, c.nodes().to_vec())).collect::<Vec<_>>();
        assert_eq!(cells(&a), cells(&g), "{volume}: cells");
        assert_eq!(a.cells.iter().filter(|c| c.kind == CellKind::Pyr5).count(), 16, "{volume}: pyramids");
        for (name, facets) in &g.faces {
            let other = a.faces.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("{volume}: no face {name} from the .inp"));
            let keys = |f: &[tresca_feti::mesh::Facet]| {
                let mut k: Vec<[usize; 4]> = f.iter().map(|q| q.key()).collect();
                k.sort_unstable();
                k
            };
            assert_eq!(keys(&other.1), keys(facets), "{volume}: face {name}");
        }
    }
    let dir = tmpdir("pyramids");
    let scene = |mesh: &str| {
        format!(
            "[[material]]\nname = \"m\"\nE = 1000.0\nnu = 0.3\n[[body]]\nname = \"b\"\nmaterial = \"m\"\nmesh = {{ file = \"{}\", volume = \"upper\" }}\n\
             [[dirichlet]]\nface = \"b.upper_bottom\"\n[[traction]]\nface = \"b.upper_top\"\np = [0.1, 0.0, -1.0]\n",
            root().join(mesh).display()
        )
    };
    let (inp, msh) = (dir.join("inp.toml"), dir.join("msh.toml"));
    std::fs::write(&inp, scene("mesh/hex_pyr_tet.inp")).unwrap();
    std::fs::write(&msh, scene("mesh/hex_pyr_tet.msh")).unwrap();
    let (a, g) = (solve(&inp, &[], &dir.join("inp.h5")), solve(&msh, &[], &dir.join("msh.h5")));
    assert!(common::max_abs(&g.solution.displacement) > 0.0);
    assert_eq!(a.solution.displacement, g.solution.displacement);
}

#[test]
fn format_key_and_extension() {
    let dir = tmpdir("format");
    // a copy without the .inp extension needs `format`
    let copy = tmpdir("format-mesh").join("blocks.txt");
    std::fs::copy(root().join("mesh/two_blocks.inp"), &copy).unwrap();
    let scene = abaqus_scene(&copy);
    assert_clean_failure("unknown-extension", &scene, &[], &["body[0].mesh.file", "abaqus", "gmsh"]);
    let with_format = scene
        .replace("volume = \"upper\" }", "volume = \"upper\", format = \"abaqus\" }")
        .replace("volume = \"lower\" }", "volume = \"lower\", format = \"abaqus\" }");
    let path = dir.join("scene.toml");
    std::fs::write(&path, with_format).unwrap();
    let s = solve(&path, &[], &dir.join("r.h5"));
    assert!(s.report.results.max_displacement > 0.0);
    // an unknown element set is named with the known ones
    let bad = abaqus_scene(&root().join("mesh/two_blocks.inp")).replace("volume = \"lower\"", "volume = \"nowhere\"");
    assert_clean_failure("unknown-elset", &bad, &[], &["two_blocks.inp", "nowhere", "\"upper\""]);
}

#[test]
fn malformed_inputs_are_one_line_errors_naming_file_and_line() {
    let full = std::fs::read_to_string(root().join("mesh/two_blocks.inp")).unwrap();
    let line_of = |needle: &str| full.lines().position(|l| l.starts_with(needle)).unwrap() + 1;
    let first_hex = "82, 89, 17, 2, 23, 185, 97, 33, 117";
    let cases: Vec<(&str, String, String)> = vec![
        ("absent-node", full.replacen(first_hex, "82, 89, 17, 2, 23, 185, 97, 33, 9999", 1), format!("line {}", line_of(first_hex))),
        (
            "unknown-type",
            full.replacen("*ELEMENT, type=C3D8, ELSET=Volume1", "*ELEMENT, type=XQ7, ELSET=Volume1", 1),
            format!("line {}", line_of("*ELEMENT, type=C3D8, ELSET=Volume1")),
        ),
        ("no-node", full.replacen("*NODE", "*NOTNODE", 1), "*NODE".to_string()),
        ("part", full.replacen("*Heading", "*Part, name=p", 1), "line 1".to_string()),
        (
            "bad-surface",
            full.replacen("*ELSET,ELSET=upper_top", "*SURFACE, NAME=s\nghost, S1\n*ELSET,ELSET=upper_top", 1),
            format!("line {}", line_of("*ELSET,ELSET=upper_top") + 1),
        ),
    ];
    for (name, text, at) in cases {
        let dir = tmpdir(&format!("{name}-mesh"));
        let mesh = dir.join("bad.inp");
        std::fs::write(&mesh, text).unwrap();
        assert_clean_failure(name, &abaqus_scene(&mesh), &[], &["bad.inp", &at]);
    }
}

#[test]
fn tet10_edge_nodes_come_in_our_order() {
    // Abaqus C3D10: nodes 5-10 on edges 1-2, 2-3, 3-1, 1-4, 2-4, 3-4
    let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let edges = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];
    let mut text = "*NODE\n".to_string();
    for (i, p) in x.iter().enumerate() {
        text += &format!("{}, {}, {}, {}\n", i + 1, p[0], p[1], p[2]);
    }
    for (k, [a, b]) in edges.iter().enumerate() {
        let m: Vec<f64> = (0..3).map(|d| 0.5 * (x[*a][d] + x[*b][d])).collect();
        text += &format!("{}, {}, {}, {}\n", k + 5, m[0], m[1], m[2]);
    }
    text += "*ELEMENT, TYPE=C3D10, ELSET=tet\n1, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10\n*SURFACE, NAME=base\ntet, S1\n";
    let dir = tmpdir("tet10");
    let path = dir.join("tet10.inp");
    std::fs::write(&path, text).unwrap();
    let g = tresca_feti::mesh::abaqus::read(&path, Some("tet")).unwrap();
    let c = &g.cells[0];
    // ours (Gmsh's): 4:(0,1) 5:(1,2) 6:(2,0) 7:(3,0) 8:(3,2) 9:(3,1)
    let ours = [[0, 1], [1, 2], [2, 0], [3, 0], [3, 2], [3, 1]];
    let p = |i: usize| g.nodes[c.nodes()[i]];
    for (k, [a, b]) in ours.iter().enumerate() {
        for d in 0..3 {
            assert!((p(4 + k)[d] - 0.5 * (p(*a)[d] + p(*b)[d])).abs() < 1e-15, "edge node {}", 4 + k);
        }
    }
    let base = &g.faces.iter().find(|(n, _)| n == "base").unwrap().1;
    assert_eq!(base.len(), 1);
    assert!(base[0].nodes().iter().all(|&v| g.nodes[v][2] == 0.0));
}

#[test]
fn two_blocks_as_parts_and_instances_solve_as_the_plain_input() {
    let dir = tmpdir("assembly");
    let plain = dir.join("plain.toml");
    std::fs::write(&plain, abaqus_scene(&root().join("mesh/two_blocks.inp"))).unwrap();
    let plain = solve(&plain, &[], &dir.join("plain.h5"));
    // instances "upper" (its part written one unit down, translated by (0, 0, 1)) and "lower";
    // the named faces are assembly-level element surfaces over `instance=` element sets
    let mesh = root().join("mesh/two_blocks_assembly.inp");
    let scene = dir.join("assembly.toml");
    std::fs::write(&scene, abaqus_scene(&mesh)).unwrap();
    let asm = solve(&scene, &[], &dir.join("assembly.h5"));
    assert!(common::max_abs(&plain.solution.displacement) > 0.0);
    assert_eq!(asm.solution.displacement, plain.solution.displacement);
    assert_eq!(asm.report.results.max_von_mises, plain.report.results.max_von_mises);
    // the instance's part-level element set, by `instance.set`, is the same body
    let by_set = dir.join("by_set.toml");
    std::fs::write(&by_set, abaqus_scene(&mesh).replace("volume = \"upper\"", "volume = \"upper.upper_all\"")).unwrap();
    let by_set = solve(&by_set, &[], &dir.join("by_set.h5"));
    assert_eq!(by_set.solution.displacement, plain.solution.displacement);
    // check names the skipped keywords once per file, with their counts
    let o = common::run(&["check", scene.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    let lines: Vec<&str> = text.lines().filter(|l| l.starts_with("abaqus: skipped keywords")).collect();
    assert_eq!(lines.len(), 1, "{text}");
    for k in ["*PREPRINT (1)", "*SOLID SECTION (2)", "*MATERIAL (2)", "*ELASTIC (2)", "*STEP (1)", "*STATIC (1)", "*END STEP (1)"] {
        assert!(lines[0].contains(k), "{k} not in {}", lines[0]);
    }
    assert!(!lines[0].contains("*PART") && !lines[0].contains("*NODE"), "{}", lines[0]);
}

#[test]
fn part_and_instance_errors_name_file_and_line() {
    let full = std::fs::read_to_string(root().join("mesh/two_blocks_assembly.inp")).unwrap();
    let line_of = |needle: &str| full.lines().position(|l| l.starts_with(needle)).unwrap() + 1;
    let upper = line_of("*Instance, name=upper");
    let cases: Vec<(&str, String, String, &str)> = vec![
        ("undefined-part", full.replacen("*Instance, name=upper, part=upper", "*Instance, name=upper, part=ghost", 1), format!("line {upper}"), "ghost"),
        (
            "empty-part",
            full.replacen("*Part, name=upper", "*Part, name=empty\n*Node\n1, 0, 0, 0\n*End Part\n*Part, name=upper", 1).replacen(
                "*Instance, name=upper, part=upper",
                "*Instance, name=upper, part=empty",
                1,
            ),
            format!("line {}", upper + 4),
            "no volume elements",
        ),
        (
            "unknown-instance",
            full.replacen("internal, instance=upper", "internal, instance=nowhere", 1),
            format!("line {}", line_of("*Elset, elset=_upper_top_S3")),
            "nowhere",
        ),
        ("open-part", full[..full.rfind("*End Part").unwrap()].to_string(), format!("line {}", line_of("*Part, name=upper")), "*END PART"),
        ("bad-translation", full.replacen("          0.,           0.,          1.0", "0., 1.0", 1), format!("line {}", upper + 1), "translation"),
    ];
    for (name, text, at, what) in cases {
        let dir = tmpdir(&format!("{name}-mesh"));
        let mesh = dir.join("bad.inp");
        std::fs::write(&mesh, text).unwrap();
        assert_clean_failure(name, &abaqus_scene(&mesh), &[], &["bad.inp", &at, what]);
    }
}
