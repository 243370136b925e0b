//! Unit tests of the HDF5 result file: round trips, layouts, rejected data, distributed rows.

use ::hdf5::File;

use super::dataspace::{block, block_owner, gather_block};
use super::layout::{CELL_DATASETS, CENTER_ATTR, MESH, MIXED, TETRAHEDRA, TIME_ATTR};
use super::read::{link_names, read_str_attr};
use crate::mesh::{Cell, CellKind};
use crate::output::{Field, Step};

use super::*;

fn tmp(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("tresca_feti_h5_{}_{name}", std::process::id()))
}

/// Two hexahedra side by side along x: 12 nodes.
fn sample() -> OutputData {
    // two hexahedra side by side along x: 12 nodes
    let mut g = crate::mesh::boxgen::generate([0.0; 3], [0.2, 1.0, 1.0], [3, 2, 2]);
    for p in &mut g.nodes {
        // values that must round-trip bit for bit
        p[1] += 1e-300;
        p[2] /= -3.0;
    }
    let big: String = (0..50 * 1024).map(|i| char::from(b'a' + (i % 26) as u8)).collect();
    OutputData {
        coordinates: g.nodes,
        cells: g.cells,
        mesh_rows: None,
        fields: vec![
            Field { name: "displacement".into(), center: Center::Node, ncomp: 3, values: Values::F64((0..36).map(|i| i as f64 * 1.25e-7 - 3.0).collect()) },
            Field { name: "von_mises".into(), center: Center::Cell, ncomp: 1, values: Values::F64(vec![std::f64::consts::PI, f64::MIN_POSITIVE]) },
            Field { name: "subdomain".into(), center: Center::Cell, ncomp: 1, values: Values::I32(vec![-7, i32::MAX]) },
            Field { name: "a field with spaces, ünïcode".into(), center: Center::Node, ncomp: 2, values: Values::I32((0..24).collect()) },
        ],
        // Deliberately not in name order: creation order must survive.
        attributes: vec![("version".into(), "tresca-feti 0.1.0 — ✓".into()), ("report".into(), big)],
        rows: Default::default(),
        steps: Vec::new(),
    }
}

fn assert_same_fields(a: &[Field], b: &[Field]) {
    assert_eq!(a.len(), b.len());
    for (fa, fb) in a.iter().zip(b) {
        assert_eq!(fa.name, fb.name);
        assert_eq!(fa.center, fb.center);
        assert_eq!(fa.ncomp, fb.ncomp);
        assert_eq!(fa.values, fb.values);
    }
}

fn assert_same(a: &OutputData, b: &OutputData) {
    assert_eq!(a.coordinates, b.coordinates);
    assert_eq!(a.cells, b.cells);
    assert_same_fields(&a.fields, &b.fields);
    assert_eq!(a.steps.len(), b.steps.len());
    for (sa, sb) in a.steps.iter().zip(&b.steps) {
        assert_eq!(sa.time.to_bits(), sb.time.to_bits());
        assert_same_fields(&sa.fields, &sb.fields);
    }
    // Compared piecewise: a failing assert_eq! on a 50 KB string floods the output.
    let names = |d: &OutputData| d.attributes.iter().map(|(n, v)| (n.clone(), v.len())).collect::<Vec<_>>();
    assert_eq!(names(a), names(b));
    for ((name, va), (_, vb)) in a.attributes.iter().zip(&b.attributes) {
        assert!(va == vb, "attribute {name:?} differs");
    }
}

/// A mesh given as rows (each rank its own, here one rank holding all of them in reverse
/// order) is written whole, as the same file as the whole mesh; read back and verified row
/// by row. A row beyond the mesh is refused before anything is written.
#[test]
fn a_mesh_given_as_rows_is_written_whole() {
    let whole = sample();
    let (nn, nc) = (whole.coordinates.len(), whole.cells.len());
    let mut dist = whole.clone();
    let node_rows: Vec<usize> = (0..nn).rev().collect();
    let cell_rows: Vec<usize> = (0..nc).rev().collect();
    dist.coordinates = node_rows.iter().map(|&r| whole.coordinates[r]).collect();
    dist.cells = cell_rows.iter().map(|&r| whole.cells[r].clone()).collect();
    dist.mesh_rows = Some(crate::output::MeshRows { nodes: nn, cells: nc, node_rows, cell_rows });
    let (a, b) = (tmp("mesh_whole.h5"), tmp("mesh_rows.h5"));
    write(&a, &whole).unwrap();
    write(&b, &dist).unwrap();
    assert_same(&read(&a).unwrap(), &read(&b).unwrap());
    assert_eq!(verify(&b, &dist).unwrap(), verify(&a, &whole).unwrap());
    dist.mesh_rows.as_mut().unwrap().node_rows[0] = nn;
    let c = tmp("mesh_bad_row.h5");
    let e = write(&c, &dist).unwrap_err().to_string();
    assert!(e.contains(&format!("node row {nn} beyond the {nn} nodes")), "{e}");
    assert!(!c.exists());
}

#[test]
fn round_trip_is_exact() {
    let data = sample();
    let path = tmp("round_trip.h5");
    write(&path, &data).unwrap();
    let back = read(&path).unwrap();
    assert_same(&data, &back);
    assert_eq!(back.attributes[1].1.len(), 50 * 1024);

    // Overwriting an existing file works and replaces it.
    let mut smaller = data.clone();
    smaller.fields.truncate(1);
    smaller.attributes.pop();
    write(&path, &smaller).unwrap();
    assert_same(&smaller, &read(&path).unwrap());
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn many_attributes_keep_their_order() {
    // More than the 8 compact attributes: the root group switches to dense storage.
    let mut data = sample();
    data.attributes = (0..20).rev().map(|i| (format!("k{i:02}"), format!("v{i}"))).collect();
    data.fields = (0..12).rev().map(|i| Field { name: format!("f{i:02}"), center: Center::Cell, ncomp: 1, values: Values::I32(vec![i, -i]) }).collect();
    let path = tmp("many.h5");
    write(&path, &data).unwrap();
    assert_same(&data, &read(&path).unwrap());
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn empty_mesh_round_trips() {
    let data = OutputData::default();
    let path = tmp("empty.h5");
    write(&path, &data).unwrap();
    assert_same(&data, &read(&path).unwrap());
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn inconsistent_data_is_rejected_before_writing() {
    let path = tmp("bad.h5");
    let mut data = sample();
    data.fields[1].values = Values::F64(vec![1.0; 3]);
    let err = write(&path, &data).unwrap_err().to_string();
    assert!(err.contains("bad.h5") && err.contains("von_mises"), "{err}");
    assert!(!path.exists());

    let mut data = sample();
    data.cells[1].nodes_mut()[7] = 12;
    assert!(write(&path, &data).unwrap_err().to_string().contains("cell 1 references node"));
    let mut data = sample();
    data.fields[0].name = "a/b".into();
    assert!(write(&path, &data).is_err());
    let mut data = sample();
    data.attributes.push(("nul".into(), "a\0b".into()));
    assert!(write(&path, &data).is_err());
    assert!(!path.exists());
}

#[test]
fn errors_name_the_file() {
    let missing = tmp("does_not_exist.h5");
    let err = read(&missing).unwrap_err().to_string();
    assert!(err.starts_with("output ") && err.contains("does_not_exist.h5"), "{err}");
    assert!(!err.contains('\n'), "{err}");

    let dir = tmp("no_such_dir").join("x.h5");
    let err = write(&dir, &sample()).unwrap_err().to_string();
    assert!(err.contains("x.h5") && !err.contains('\n'), "{err}");

    // Not an HDF5 file.
    let junk = tmp("junk.h5");
    std::fs::write(&junk, b"not hdf5").unwrap();
    let err = read(&junk).unwrap_err().to_string();
    assert!(err.contains("junk.h5") && !err.contains('\n'), "{err}");
    std::fs::remove_file(&junk).unwrap();
}

/// `sample()` on a load path of 3 steps: per step a node vector, a cell scalar and an
/// integer cell field, with values that differ from step to step; the last step is the
/// final state.
fn with_steps() -> OutputData {
    let mut data = sample();
    data.steps = [0.25, 0.5, 1.0]
        .iter()
        .enumerate()
        .map(|(k, &time)| {
            let k = k as f64;
            Step {
                time,
                fields: vec![
                    Field {
                        name: "displacement".into(),
                        center: Center::Node,
                        ncomp: 3,
                        values: Values::F64((0..36).map(|i| time * (i as f64 * 1.25e-7 - 3.0)).collect()),
                    },
                    Field { name: "von_mises".into(), center: Center::Cell, ncomp: 1, values: Values::F64(vec![k / 3.0, -k * f64::MIN_POSITIVE]) },
                    Field { name: "contact status".into(), center: Center::Cell, ncomp: 1, values: Values::I32(vec![k as i32, -1]) },
                ],
                rows: Default::default(),
            }
        })
        .collect();
    data
}

#[test]
fn steps_round_trip_and_verify() {
    let data = with_steps();
    let path = tmp("steps.h5");
    write(&path, &data).unwrap();
    let back = read(&path).unwrap();
    assert_same(&data, &back);
    assert_eq!(back.steps.iter().map(|s| s.time).collect::<Vec<_>>(), [0.25, 0.5, 1.0]);
    let values: usize = (data.fields.iter().chain(data.steps.iter().flat_map(|s| &s.fields))).map(|f| values_len(&f.values)).sum();
    let mesh = 3 * 12 + 8 * 2;
    assert_eq!(verify(&path, &data).unwrap(), mesh + values + 3);

    // The layout itself: /steps/0002 with its time, datasets carrying `center`.
    let file = File::open(&path).unwrap();
    assert_eq!(link_names(&file.group("steps").unwrap()).unwrap(), ["0001", "0002", "0003"]);
    let step = file.group("steps/0002").unwrap();
    assert_eq!(step.attr(TIME_ATTR).unwrap().read_scalar::<f64>().unwrap(), 0.5);
    let ds = step.dataset("displacement").unwrap();
    assert_eq!(ds.shape(), [12, 3]);
    assert_eq!(read_str_attr(&ds.attr(CENTER_ATTR).unwrap()).unwrap(), "node");
    drop((ds, step, file));

    // verify notices a step that differs from the one in memory.
    let mut other = data.clone();
    other.steps[2].fields[1].values = Values::F64(vec![2.0 / 3.0, 0.5]);
    let err = verify(&path, &other).unwrap_err().to_string();
    assert!(err.contains("step 0003") && err.contains("von_mises") && err.contains("row 1"), "{err}");
    other.steps[2] = data.steps[2].clone();
    other.steps[1].time = 0.75;
    assert!(verify(&path, &other).unwrap_err().to_string().contains("step 0002: time"));
    other.steps.pop();
    assert!(verify(&path, &other).unwrap_err().to_string().contains("3 steps, expected 2"));
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn distributed_step_fields_are_written_at_their_rows() {
    // This process holds the two cells in reverse order, and nodes 11, 0 only of a step
    // field: the file has every row, at its place (node rows it does not hold stay 0).
    let mut data = with_steps();
    let step = &mut data.steps[1];
    step.fields[1].values = Values::F64(vec![20.0, 10.0]);
    step.rows.insert("von_mises".into(), vec![1, 0]);
    step.fields[0].values = Values::F64(vec![11.0, 11.5, 12.0, 0.0, 0.5, 1.0]);
    step.rows.insert("displacement".into(), vec![11, 0]);
    let path = tmp("steps_rows.h5");
    write(&path, &data).unwrap();
    let back = read(&path).unwrap();
    assert_eq!(back.steps[1].fields[1].values, Values::F64(vec![10.0, 20.0]));
    let Values::F64(u) = &back.steps[1].fields[0].values else { panic!("not f64") };
    assert_eq!((u.len(), &u[..3], &u[33..]), (36, &[0.0, 0.5, 1.0][..], &[11.0, 11.5, 12.0][..]));
    assert_same_fields(&back.steps[2].fields, &data.steps[2].fields);
    assert!(verify(&path, &data).is_ok());
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn blocks_tile_the_rows_and_owners_find_them() {
    for len in 1..40 {
        for size in 1..9 {
            for rank in 0..size {
                let (lo, hi) = block(len, rank, size);
                assert!((lo..hi).all(|r| block_owner(r, len, size) == rank), "len {len} size {size}");
            }
            assert_eq!(block(len, size - 1, size).1, len);
        }
    }
    // one rank: every row, unheld rows 0, a row held twice by its last holder
    let v = [1.5, -2.0, 3.0, 4.0, 5.0, 6.0];
    let got = gather_block(&crate::comm::SerialComm, 4, 2, &[3, 0, 3], &v);
    assert_eq!(got, [3.0, 4.0, 0.0, 0.0, 0.0, 0.0, 5.0, 6.0]);
    assert_eq!(gather_block(&crate::comm::SerialComm, 3, 1, &[2, 0], &[-7i32, i32::MIN]), [i32::MIN, 0, -7]);
}

#[test]
fn bad_steps_are_rejected_before_writing() {
    let path = tmp("bad_steps.h5");
    let reject = |data: &OutputData, what: &[&str]| {
        let err = write(&path, data).unwrap_err().to_string();
        assert!(what.iter().all(|w| err.contains(w)), "{err}");
        assert!(!path.exists());
    };
    let mut data = with_steps();
    data.steps[1].fields[1].values = Values::F64(vec![1.0; 3]);
    reject(&data, &["bad_steps.h5", "step 0002", "von_mises", "3 values"]);
    // Through write_all too: neither a result file nor a temporary one stays behind.
    let err = crate::output::write_all(&crate::comm::SerialComm, &path, &data, true, None);
    assert!(err.is_err());
    let leftovers = ["h5", "xdmf", "h5.tmp", "xdmf.tmp"].map(|e| path.with_extension(e));
    assert!(leftovers.iter().all(|p| !p.exists()), "{leftovers:?}");

    let mut data = with_steps();
    data.steps[2].fields[2].name = "von_mises".into();
    reject(&data, &["step 0003", "appears twice"]);
    let mut data = with_steps();
    data.steps[0].fields[0].name = "a/b".into();
    reject(&data, &["step 0001"]);
    let mut data = with_steps();
    data.steps[0].rows.insert("von_mises".into(), vec![0, 2]);
    reject(&data, &["step 0001", "row 2"]);
    let mut data = with_steps();
    data.steps[1].time = f64::NAN;
    reject(&data, &["step 0002", "not finite"]);
    let mut data = with_steps();
    data.steps[2].time = 0.5;
    reject(&data, &["step 0003", "not after step 0002"]);
}

/// `sample()` on the 12 nodes with `cells` instead of its two hexahedra, the cell fields
/// resized to them.
fn with_cells(cells: Vec<Cell>) -> OutputData {
    let mut data = sample();
    let n = cells.len();
    data.cells = cells;
    data.fields[1].values = Values::F64((0..n).map(|i| i as f64 / 7.0).collect());
    data.fields[2].values = Values::I32((0..n as i32).map(|i| -i).collect());
    data
}

fn cell(kind: CellKind, from: usize) -> Cell {
    Cell::new(kind, &(from..from + kind.len()).collect::<Vec<_>>())
}

/// Each layout: the dataset it names, its raw values (tet10 in XDMF order: its last two edge
/// nodes swapped; mixed: type id then nodes), and a round trip that gives the same cells;
/// the same file from the mesh given as rows (reversed), verified row by row.
#[test]
fn every_cell_layout_round_trips() {
    // cells, their dataset, its shape, its values
    type Case = (Vec<Cell>, &'static str, Vec<usize>, Vec<i64>);
    let cases: Vec<Case> = vec![
        (vec![cell(CellKind::Tet4, 0), cell(CellKind::Tet4, 4), cell(CellKind::Tet4, 8)], "tetrahedra", vec![3, 4], (0..12).collect()),
        (
            vec![cell(CellKind::Tet10, 0), cell(CellKind::Tet10, 2)],
            "tetrahedra10",
            vec![2, 10],
            vec![0, 1, 2, 3, 4, 5, 6, 7, 9, 8, 2, 3, 4, 5, 6, 7, 8, 9, 11, 10],
        ),
        (vec![cell(CellKind::Wedge6, 6), cell(CellKind::Wedge6, 0)], "wedges", vec![2, 6], vec![6, 7, 8, 9, 10, 11, 0, 1, 2, 3, 4, 5]),
        (vec![cell(CellKind::Pyr5, 3), cell(CellKind::Pyr5, 0)], "pyramids", vec![2, 5], vec![3, 4, 5, 6, 7, 0, 1, 2, 3, 4]),
        (
            vec![cell(CellKind::Hex8, 0), cell(CellKind::Tet10, 2), cell(CellKind::Tet4, 8), cell(CellKind::Wedge6, 1)],
            "mixed",
            vec![1 + 8 + 1 + 10 + 1 + 4 + 1 + 6],
            [vec![9], (0..8).collect(), vec![38, 2, 3, 4, 5, 6, 7, 8, 9, 11, 10, 6, 8, 9, 10, 11, 8], (1..7).collect()].concat(),
        ),
    ];
    for (cells, name, shape, raw) in cases {
        let whole = with_cells(cells);
        let path = tmp(&format!("layout_{name}.h5"));
        write(&path, &whole).unwrap();
        let file = File::open(&path).unwrap();
        let mesh = file.group(MESH).unwrap();
        assert_eq!(CELL_DATASETS.iter().filter(|d| mesh.link_exists(d)).collect::<Vec<_>>(), [&name], "{name}");
        let ds = mesh.dataset(name).unwrap();
        assert_eq!(ds.shape(), shape, "{name}");
        assert_eq!(ds.read_raw::<i64>().unwrap(), raw, "{name}");
        drop((ds, mesh, file));
        let back = read(&path).unwrap();
        assert_same(&whole, &back);
        assert!(verify(&path, &whole).is_ok(), "{name}");

        let (nn, nc) = (whole.coordinates.len(), whole.cells.len());
        let mut dist = whole.clone();
        let cell_rows: Vec<usize> = (0..nc).rev().collect();
        dist.cells = cell_rows.iter().map(|&r| whole.cells[r].clone()).collect();
        dist.mesh_rows = Some(crate::output::MeshRows { nodes: nn, cells: nc, node_rows: (0..nn).collect(), cell_rows });
        let path2 = tmp(&format!("layout_{name}_rows.h5"));
        write(&path2, &dist).unwrap();
        assert_same(&read(&path2).unwrap(), &back);
        assert_eq!(verify(&path2, &dist).unwrap(), verify(&path, &whole).unwrap(), "{name}");
        let layout = cell_layout(&crate::comm::SerialComm, &dist).unwrap();
        assert_eq!(layout, CellLayout::of_cells(&whole.cells));
        assert_eq!(layout.dataset(), name);

        // a distributed mesh with a cell row nobody holds is refused, no file left
        dist.cells.pop();
        dist.mesh_rows.as_mut().unwrap().cell_rows.pop();
        let path3 = tmp(&format!("layout_{name}_hole.h5"));
        let e = write(&path3, &dist).unwrap_err().to_string();
        assert!(e.contains("1 of the") && e.contains("held by no rank"), "{e}");
        assert!(!path3.exists());
        for p in [path, path2] {
            std::fs::remove_file(p).unwrap();
        }
    }
}

/// A file with a cell dataset that does not parse is an error naming it.
#[test]
fn bad_cell_datasets_are_named() {
    let path = tmp("bad_cells.h5");
    write(&path, &with_cells(vec![cell(CellKind::Hex8, 0), cell(CellKind::Tet4, 0)])).unwrap();
    let file = ::hdf5::File::open_rw(&path).unwrap();
    let mesh = file.group(MESH).unwrap();
    mesh.unlink(MIXED).unwrap();
    mesh.new_dataset::<i64>().shape([6]).create(MIXED).unwrap().write_raw(&[6i64, 0, 1, 2, 3, 5]).unwrap();
    drop((mesh, file));
    let e = read(&path).unwrap_err().to_string();
    assert!(e.contains("/mesh/mixed") && e.contains("unknown XDMF cell type 5"), "{e}");
    let file = ::hdf5::File::open_rw(&path).unwrap();
    file.group(MESH).unwrap().new_dataset::<i64>().shape([1, 4]).create(TETRAHEDRA).unwrap().write_raw(&[0i64, 1, 2, 3]).unwrap();
    drop(file);
    let e = read(&path).unwrap_err().to_string();
    assert!(e.contains("several cell datasets"), "{e}");
    std::fs::remove_file(&path).unwrap();
}
