//! The Gmsh reader's unit tests: ASCII and binary files, volumes, faces, cell kinds, orientation,
//! malformed and truncated files.

use super::*;

fn mesh_file(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("mesh").join(name)
}

fn normal(g: &BodyGeometry, q: &[usize]) -> [f64; 3] {
    let p: Vec<[f64; 3]> = q.iter().map(|&v| g.nodes[v]).collect();
    let a = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
    let b = [p[3][0] - p[0][0], p[3][1] - p[0][1], p[3][2] - p[0][2]];
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Checks face `name`: `count` quads, each normal along `sign * e_axis`, each a face of its element.
fn check_face(g: &BodyGeometry, name: &str, count: usize, axis: usize, sign: f64) {
    let (_, quads) = g.faces.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no face {name}"));
    assert_eq!(quads.len(), count, "{name}");
    for q in quads {
        let n = normal(g, q.nodes());
        assert!(n[axis] * sign > 0.0, "{name}: quad not outward");
        assert!(n[(axis + 1) % 3].abs() < 1e-12 && n[(axis + 2) % 3].abs() < 1e-12, "{name}");
        assert!(q.nodes().iter().all(|v| g.cells[q.elem].nodes().contains(v)), "{name}: quad not on its element");
    }
}

fn check_body(g: &BodyGeometry, zmin: f64) {
    assert_eq!(g.nodes.len(), 7 * 4 * 4);
    assert_eq!(g.cells.len(), 54);
    for p in &g.nodes {
        assert!((0.0..=2.0).contains(&p[0]) && (0.0..=1.0).contains(&p[1]), "{p:?}");
        assert!((zmin..=zmin + 1.0).contains(&p[2]), "{p:?}");
    }
    for h in &g.cells {
        let h: [usize; 8] = h.nodes().try_into().unwrap();
        assert!(corner_jacobians(&h.map(|v| g.nodes[v])).iter().all(|&j| j > 0.0));
    }
    let mut used = vec![false; g.nodes.len()];
    g.cells.iter().flat_map(|c| c.nodes().to_vec()).for_each(|v| used[v] = true);
    assert!(used.iter().all(|&u| u), "unused node kept");
}

#[test]
fn reads_upper_block() {
    let g = read(&mesh_file("two_blocks.msh"), Some("upper")).expect("upper");
    check_body(&g, 1.0);
    let names: Vec<&str> = g.faces.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["upper_top", "upper_bottom", "upper_left", "upper_right"]);
    check_face(&g, "upper_top", 18, 2, 1.0);
    check_face(&g, "upper_bottom", 18, 2, -1.0);
    check_face(&g, "upper_left", 9, 0, -1.0);
    check_face(&g, "upper_right", 9, 0, 1.0);
}

#[test]
fn reads_lower_block() {
    let g = read(&mesh_file("two_blocks.msh"), Some("lower")).expect("lower");
    check_body(&g, 0.0);
    let names: Vec<&str> = g.faces.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["lower_top", "lower_left"]);
    check_face(&g, "lower_top", 18, 2, 1.0);
    check_face(&g, "lower_left", 9, 0, -1.0);
}

#[test]
fn reads_binary_like_ascii() {
    let a = read(&mesh_file("two_blocks.msh"), Some("upper")).expect("ascii");
    let b = read(&mesh_file("two_blocks_binary.msh"), Some("upper")).expect("binary");
    // ASCII files carry 16 significant digits, binary ones the exact doubles.
    assert_eq!(a.nodes.len(), b.nodes.len());
    for (p, q) in a.nodes.iter().zip(&b.nodes) {
        assert!((0..3).all(|d| (p[d] - q[d]).abs() < 1e-14), "{p:?} {q:?}");
    }
    assert_eq!(a.cells, b.cells);
    assert_eq!(a.faces.len(), b.faces.len());
    for (fa, fb) in a.faces.iter().zip(&b.faces) {
        assert_eq!(fa.0, fb.0);
        assert_eq!(fa.1, fb.1);
    }
}

#[test]
fn whole_file_without_volume() {
    let g = read(&mesh_file("two_blocks.msh"), None).expect("all");
    assert_eq!(g.nodes.len(), 224);
    assert_eq!(g.cells.len(), 108);
    // The blocks do not share nodes, so both sides of the interface are boundary.
    let names: Vec<&str> = g.faces.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names.len(), 6);
    check_face(&g, "upper_bottom", 18, 2, -1.0);
    check_face(&g, "lower_top", 18, 2, 1.0);
}

#[test]
fn unknown_volume_lists_known_ones() {
    let e = read(&mesh_file("two_blocks.msh"), Some("nope")).unwrap_err().to_string();
    assert!(e.contains("\"nope\"") && e.contains("\"upper\"") && e.contains("\"lower\""), "{e}");
    assert!(!e.contains('\n'), "{e}");
}

#[test]
fn tetrahedra_only_are_read() {
    for volume in [None, Some("body")] {
        let g = read(&mesh_file("tet.msh"), volume).expect("tet.msh");
        assert_eq!(crate::mesh::cell_counts(&g.cells), [(CellKind::Tet4, 24)]);
        assert_eq!(g.faces.len(), 1);
        assert!(g.faces[0].1.iter().all(|q| q.kind == crate::mesh::FacetKind::Tri3));
    }
}

#[test]
fn truncated_file_is_an_error() {
    let bytes = std::fs::read(mesh_file("two_blocks.msh")).expect("mesh");
    let dir = std::env::temp_dir();
    for (i, cut) in [bytes.len() / 2, bytes.len() / 3, 40, 5, 0].into_iter().enumerate() {
        let p = dir.join(format!("tresca_feti_gmsh_truncated_{}_{i}.msh", std::process::id()));
        std::fs::write(&p, &bytes[..cut]).expect("temp file");
        let r = read(&p, Some("upper"));
        let _ = std::fs::remove_file(&p);
        let e = r.unwrap_err();
        assert!(matches!(e, Error::Mesh { .. }), "{e}");
        let msg = e.to_string();
        assert!(!msg.contains('\n') && msg.len() < 300, "{msg}");
    }
    let bytes = std::fs::read(mesh_file("two_blocks_binary.msh")).expect("mesh");
    let p = dir.join(format!("tresca_feti_gmsh_truncated_bin_{}.msh", std::process::id()));
    std::fs::write(&p, &bytes[..bytes.len() / 2]).expect("temp file");
    let r = read(&p, None);
    let _ = std::fs::remove_file(&p);
    let msg = r.unwrap_err().to_string();
    assert!(msg.contains(UNREADABLE) && !msg.contains('\n'), "{msg}");
}

#[test]
fn garbage_and_other_versions_are_errors() {
    for text in ["hello", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n", "$MeshFormat\n4.1 1 3\n$EndMeshFormat\n"] {
        let msg = parse(text.as_bytes(), None).unwrap_err();
        assert!(msg.starts_with(UNREADABLE) && !msg.contains('\n'), "{msg}");
    }
    let garbage = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 x\n$EndNodes\n";
    let msg = parse(garbage.as_bytes(), None).unwrap_err();
    assert!(msg.starts_with(UNREADABLE) && msg.contains("line 5"), "{msg}");
}

#[test]
fn missing_file_is_io_error() {
    let e = read(&mesh_file("does_not_exist.msh"), None).unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e}");
}

/// A single unit hex with one physical surface (its top), no `$PhysicalNames`, its nodes
/// listed in the permuted tag order `tags`, and hex connectivity `conn` (as tags).
fn one_hex(tags: [u64; 8], conn: [u64; 8], top: [u64; 4]) -> String {
    let corners = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]];
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 1 1\n");
    s += "1 0 0 1 1 1 1 1 5 0\n1 0 0 0 1 1 1 1 7 1 1\n$EndEntities\n$Nodes\n1 8 1 8\n3 1 0 8\n";
    for t in tags {
        s += &format!("{t}\n");
    }
    // Node with tag t sits at corner t-1.
    for t in tags {
        let c = corners[(t - 1) as usize];
        s += &format!("{} {} {}\n", c[0], c[1], c[2]);
    }
    s += "$EndNodes\n$Elements\n2 2 1 2\n2 1 3 1\n1";
    for t in top {
        s += &format!(" {t}");
    }
    s += "\n3 1 5 1\n2";
    for t in conn {
        s += &format!(" {t}");
    }
    s += "\n$EndElements\n";
    s
}

#[test]
fn bad_nodes_unclosed_sections_and_missing_sections_are_named() {
    let ids = [1, 2, 3, 4, 5, 6, 7, 8];
    let text = one_hex(ids, ids, [5, 6, 7, 8]);
    let err = |t: String| parse(t.as_bytes(), None).unwrap_err();
    let msg = err(text.replacen("\n0 1 1\n", "\n0 nan 1\n", 1));
    assert!(msg.contains("node 8 has a non-finite coordinate (0, NaN, 1)"), "{msg}");
    let msg = err(one_hex([1, 2, 3, 4, 5, 6, 7, 7], ids, [5, 6, 7, 8]));
    assert!(msg.contains("node 7 is defined twice"), "{msg}");
    let msg = err(one_hex(ids, ids, [5, 6, 7, 9]));
    assert!(msg.contains("quadrangle 1 refers to node 9"), "{msg}");
    let msg = err(text.replacen("$EndNodes\n", "", 1));
    assert!(msg.starts_with(UNREADABLE) && msg.contains("expected $EndNodes to close the $Nodes section"), "{msg}");
    let msg = err(text[..text.find("$Elements").unwrap()].to_string());
    assert!(msg.contains("no $Elements section"), "{msg}");
    let msg = err(text.replacen("4.1 0 8", "4.1 1 8", 1));
    assert!(msg.contains("binary") && msg.contains("line 3") && !msg.contains('\n'), "{msg}");
}

#[test]
fn permuted_dense_tags_unnamed_groups_and_inverted_hex() {
    let tags = [3, 1, 2, 8, 7, 4, 5, 6];
    let good = [1, 2, 3, 4, 5, 6, 7, 8];
    let text = one_hex(tags, good, [5, 6, 7, 8]);
    let g = parse(text.as_bytes(), Some("7")).expect("one hex");
    assert_eq!(g.nodes.len(), 8);
    // File order kept: local node i is the i-th listed node.
    for (i, &t) in tags.iter().enumerate() {
        assert_eq!(
            g.nodes[i],
            [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.], [0., 0., 1.], [1., 0., 1.], [1., 1., 1.], [0., 1., 1.]][(t - 1) as usize]
        );
    }
    assert_eq!(g.faces.len(), 1);
    check_face(&g, "5", 1, 2, 1.0);

    // Mirrored connectivity (all corner Jacobians negative) is reordered.
    let mirrored = [1, 4, 3, 2, 5, 8, 7, 6];
    let g = parse(one_hex(tags, mirrored, [5, 6, 7, 8]).as_bytes(), None).expect("mirrored");
    assert!(corner_jacobians(&<[usize; 8]>::try_from(g.cells[0].nodes()).unwrap().map(|v| g.nodes[v])).iter().all(|&j| j > 0.0));
    check_face(&g, "5", 1, 2, 1.0);

    // A twisted hex (two nodes swapped) is refused, naming the element.
    let twisted = [2, 1, 3, 4, 5, 6, 7, 8];
    let msg = parse(one_hex(tags, twisted, [5, 6, 7, 8]).as_bytes(), None).unwrap_err();
    assert!(msg.contains("hexahedron 2"), "{msg}");

    // A quad that is not on the boundary of the body is skipped: the face is omitted.
    let g = parse(one_hex(tags, good, [1, 2, 7, 8]).as_bytes(), None).expect("skip");
    assert!(g.faces.is_empty());
}

/// A file with nodes 1… at `x`, the volume blocks `cells` (Gmsh type, then per element its
/// tag and node tags) in volume entity 1 (physical volume 7 "solid"), and the surface
/// blocks `surfaces` in surface entity 1 (physical surface 5 "side").
/// One element block: the Gmsh type, then per element its tag and node tags.
type Block = (i32, Vec<(u64, Vec<u64>)>);

fn msh_text(x: &[[f64; 3]], cells: &[Block], surfaces: &[Block]) -> String {
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    s += "$PhysicalNames\n2\n2 5 \"side\"\n3 7 \"solid\"\n$EndPhysicalNames\n";
    s += "$Entities\n0 0 1 1\n1 0 0 0 1 1 1 1 5 0\n1 0 0 0 1 1 1 1 7 1 1\n$EndEntities\n";
    let n = x.len();
    s += &format!("$Nodes\n1 {n} 1 {n}\n3 1 0 {n}\n");
    for t in 1..=n {
        s += &format!("{t}\n");
    }
    for p in x {
        s += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    let blocks: Vec<(i32, &Block)> = surfaces.iter().map(|b| (2, b)).chain(cells.iter().map(|b| (3, b))).collect();
    let count: usize = blocks.iter().map(|(_, b)| b.1.len()).sum();
    let max = blocks.iter().flat_map(|(_, b)| b.1.iter().map(|e| e.0)).max().unwrap_or(0);
    s += &format!("$EndNodes\n$Elements\n{} {count} 1 {max}\n", blocks.len());
    for (dim, (ty, elems)) in blocks {
        s += &format!("{dim} 1 {ty} {}\n", elems.len());
        for (tag, nodes) in elems {
            s += &tag.to_string();
            for v in nodes {
                s += &format!(" {v}");
            }
            s += "\n";
        }
    }
    s + "$EndElements\n"
}

const TET: [[f64; 3]; 4] = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]];

/// The unit tet10 (Gmsh order): corners, then the midpoints of the edges 4:(0,1) 5:(1,2)
/// 6:(2,0) 7:(3,0) 8:(3,2) 9:(3,1).
fn tet10() -> Vec<[f64; 3]> {
    let mut x = TET.to_vec();
    for [a, b] in crate::fem::tet::TET10_EDGES {
        x.push(std::array::from_fn(|d| 0.5 * (TET[a][d] + TET[b][d])));
    }
    x
}

fn min_jacobian(g: &BodyGeometry, e: usize) -> f64 {
    crate::fem::cell::cell_min_jacobian(g.cells[e].kind, &g.cells[e].coords(&g.nodes))
}

/// Mirrored tetrahedra (4 and 10 nodes) and wedges are reordered into positive ones that
/// keep their edge nodes on their edges; a face given by the file's corners only becomes the
/// cell's own outward facet (a 6-node one on the tet10).
#[test]
fn inverted_tetrahedra_and_wedges_are_reordered() {
    // tet4 listed 0-2-1-3 (mirrored), its face y = 0 given as a triangle
    let text = msh_text(&TET, &[(4, vec![(1, vec![1, 3, 2, 4])])], &[(2, vec![(2, vec![1, 4, 2])])]);
    let g = parse(text.as_bytes(), Some("solid")).expect("tet4");
    assert_eq!(g.cells[0].nodes(), [0, 1, 2, 3]);
    assert!(min_jacobian(&g, 0) > 0.0);
    let face = &g.faces[0].1;
    assert_eq!((g.faces[0].0.as_str(), face.len(), face[0].nodes()), ("side", 1, &[0, 1, 3][..]));

    // tet10 mirrored: corners 1↔2 and the edge nodes with them (4↔6, 8↔9); its face y = 0
    // given by a 3-node triangle comes back as the tet10's 6-node facet
    let mirrored: Vec<u64> = [0, 2, 1, 3, 6, 5, 4, 7, 9, 8].iter().map(|&i| i + 1).collect();
    let text = msh_text(&tet10(), &[(11, vec![(1, mirrored)])], &[(2, vec![(2, vec![1, 2, 4])])]);
    let g = parse(text.as_bytes(), None).expect("tet10");
    assert_eq!(g.cells[0].kind, CellKind::Tet10);
    assert_eq!(g.cells[0].nodes(), (0..10).collect::<Vec<_>>());
    assert!(min_jacobian(&g, 0) > 0.0);
    let q = &g.faces[0].1[0];
    assert_eq!((q.kind, q.nodes()), (crate::mesh::FacetKind::Tri6, &[0, 1, 3, 4, 9, 7][..]));

    // a tet10 whose edge node (0,1) sits near corner 1 is inverted there: its corners are
    // fine (read), its Jacobian is not (the assembly refuses it)
    let mut x = tet10();
    x[4] = [0.95, 0.0, 0.0];
    let text = msh_text(&x, &[(11, vec![(3, (1..=10).collect())])], &[]);
    let g = parse(text.as_bytes(), None).expect("corners in order");
    assert!(min_jacobian(&g, 0) <= 0.0);

    // wedge mirrored (1↔2, 4↔5)
    let wedge = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.], [1., 0., 1.], [0., 1., 1.]];
    let text = msh_text(&wedge, &[(6, vec![(4, vec![1, 3, 2, 4, 6, 5])])], &[(3, vec![(9, vec![1, 2, 5, 4])])]);
    let g = parse(text.as_bytes(), None).expect("wedge");
    assert_eq!(g.cells[0].nodes(), [0, 1, 2, 3, 4, 5]);
    assert!(min_jacobian(&g, 0) > 0.0);
    assert_eq!(g.faces[0].1[0].nodes(), [0, 1, 4, 3]);

    // a twisted wedge (top corners 3, 4 swapped) and a flat tetrahedron name their tags
    let text = msh_text(&wedge, &[(6, vec![(4, vec![1, 2, 3, 5, 4, 6])])], &[]);
    let msg = parse(text.as_bytes(), None).unwrap_err();
    assert!(msg.contains("wedge 4 is degenerate or twisted"), "{msg}");
    let flat = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [1., 1., 0.]];
    let msg = parse(msh_text(&flat, &[(4, vec![(8, vec![1, 2, 3, 4])])], &[]).as_bytes(), None).unwrap_err();
    assert!(msg.contains("tetrahedron 8 is degenerate"), "{msg}");
    // the same tetrahedron under two tags
    let text = msh_text(&TET, &[(4, vec![(1, vec![1, 2, 3, 4]), (2, vec![4, 3, 2, 1])])], &[]);
    let msg = parse(text.as_bytes(), None).unwrap_err();
    assert!(msg.contains("tetrahedra 1 and 2 have the same 4 nodes"), "{msg}");
}

/// A hexahedron with a tetrahedron on its top: one body of two cell types, its side y = 0
/// one quadrilateral and one triangle.
#[test]
fn mixed_hexahedron_and_tetrahedron_body() {
    let x = [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.], [0., 0., 1.], [1., 0., 1.], [1., 1., 1.], [0., 1., 1.], [0., 0., 2.]];
    let cells = [(5, vec![(1, (1..=8).collect())]), (4, vec![(2, vec![5, 6, 8, 9])])];
    let side = [(3, vec![(3, vec![1, 2, 6, 5])]), (2, vec![(4, vec![5, 6, 9])])];
    let g = parse(msh_text(&x, &cells, &side).as_bytes(), Some("solid")).expect("mixed");
    assert_eq!(crate::mesh::cell_counts(&g.cells), [(CellKind::Hex8, 1), (CellKind::Tet4, 1)]);
    assert_eq!(g.nodes.len(), 9);
    assert!((0..2).all(|e| min_jacobian(&g, e) > 0.0));
    let kinds: Vec<_> = g.faces[0].1.iter().map(|q| (q.elem, q.kind)).collect();
    use crate::mesh::FacetKind;
    assert_eq!(kinds, [(0, FacetKind::Quad4), (1, FacetKind::Tri3)]);
}

/// Volume elements of another type are an error naming the type and the count, alone or
/// beside supported ones; a file without volume elements says what it holds.
#[test]
fn unsupported_volume_types_are_named() {
    // 13-node pyramids (Gmsh type 19): the nodes' positions do not matter, the type is refused
    let x: Vec<[f64; 3]> = (0..14).map(|k| [k as f64, (k * k) as f64, 1.0]).collect();
    let pyramid = (19, vec![(1, (1..14).collect::<Vec<u64>>()), (2, (2..15).collect())]);
    let tet = (4, vec![(3, vec![1, 2, 3, 5])]);
    for cells in [vec![pyramid.clone()], vec![tet.clone(), pyramid.clone()]] {
        let msg = parse(msh_text(&x, &cells, &[]).as_bytes(), Some("solid")).unwrap_err();
        assert!(msg.contains("physical volume \"solid\"") && msg.contains("Pyr13: 2") && msg.contains("not supported"), "{msg}");
        assert!(!msg.contains('\n'), "{msg}");
    }
    let msg = parse(msh_text(&x, &[], &[(2, vec![(1, vec![1, 2, 3])])]).as_bytes(), None).unwrap_err();
    assert!(msg.contains("no volume elements (found: Tri3: 1)"), "{msg}");
}

/// One parse for several bodies gives each body exactly as its own read does (nodes compared
/// bit for bit through their Debug form, cells and faces too); a volume not in the file is that
/// body's error only.
#[test]
fn one_parse_builds_every_body_as_its_own_read() {
    let p = mesh_file("sphere_on_block.msh");
    let many = read_many(&p, &[Some("ball"), Some("missing"), Some("block"), None]).expect("parses");
    assert!(many[1].is_err());
    for (got, volume) in many.iter().zip([Some("ball"), None, Some("block"), None]) {
        if let Ok(got) = got {
            let want = read(&p, volume).expect("reads");
            assert_eq!(format!("{got:?}"), format!("{want:?}"), "{volume:?}");
        }
    }
    assert!(many[0].as_ref().unwrap().cells.len() != many[2].as_ref().unwrap().cells.len());
}

/// The reader tells its progress in bytes of the file, rising, ending at its size; the bodies
/// read are the same as without it.
#[test]
fn progress_counts_the_bytes_read() {
    let path = mesh_file("two_blocks.msh");
    let calls = std::cell::RefCell::new(Vec::new());
    let with = read_many_with(&path, &[None], &|d, n| calls.borrow_mut().push((d, n))).unwrap();
    let size = std::fs::metadata(&path).unwrap().len();
    let calls = calls.into_inner();
    assert!(!calls.is_empty() && calls.windows(2).all(|w| w[0].0 <= w[1].0) && calls.iter().all(|c| c.1 == size), "{calls:?}");
    assert_eq!(calls.last(), Some(&(size, size)));
    let plain = read_many(&path, &[None]).unwrap();
    assert_eq!(format!("{:?}", with[0].as_ref().unwrap().nodes), format!("{:?}", plain[0].as_ref().unwrap().nodes));
}
