//! Reading a file back ([`super::read`](fn@super::read)) and checking that it holds what was written
//! ([`verify`]).

use std::path::Path;

use ::hdf5::plist::file_create::{AttrCreationOrder, LinkCreationOrder};
use ::hdf5::types::{IntSize, TypeDescriptor, VarLenAscii, VarLenUnicode};
use ::hdf5::{Attribute, Dataset, File, Group, H5Type, IndexType, IterationOrder};

use super::layout::{file_order, kind_of_id, CellLayout, CELL_DATASETS, CENTER_ATTR, COORDINATES, FIELDS, MESH, MIXED, STEPS, TIME_ATTR};
use super::{h5e, read, values_len, Rows, R};
use crate::error::{Error, Result};
use crate::mesh::cell::MAX_CELL_NODES;
use crate::mesh::{Cell, CellKind};
use crate::output::{step_name, Center, Field, OutputData, Step, Values};

/// Reads `path` back and checks that it holds `data` bit for bit: the mesh, this rank's rows
/// of the distributed fields (`data.rows`) and the other fields whole, and likewise every
/// step's time and fields. Returns the number of values compared (each step's time counts
/// one); a difference is an error naming the step, the field and the row.
pub fn verify(path: &Path, data: &OutputData) -> Result<usize> {
    let shown = path.display().to_string();
    let back = read(path)?;
    let fail = |m: String| Error::output(&shown, format!("read back: {m}"));
    let same_mesh = match &data.mesh_rows {
        None => back.coordinates == data.coordinates && back.cells == data.cells,
        Some(m) => {
            back.coordinates.len() == m.nodes
                && back.cells.len() == m.cells
                && m.node_rows.iter().zip(&data.coordinates).all(|(&r, x)| back.coordinates[r].map(f64::to_bits) == x.map(f64::to_bits))
                && m.cell_rows.iter().zip(&data.cells).all(|(&r, h)| back.cells[r] == *h)
        }
    };
    if !same_mesh {
        return Err(fail("the mesh differs from the one in memory".into()));
    }
    let mut checked = 3 * data.coordinates.len() + data.cells.iter().map(|c| c.kind.len()).sum::<usize>();
    checked += verify_fields(&data.fields, &data.rows, &back.fields).map_err(fail)?;
    if back.steps.len() != data.steps.len() {
        return Err(fail(format!("{} steps, expected {}", back.steps.len(), data.steps.len())));
    }
    for (i, (step, got)) in data.steps.iter().zip(&back.steps).enumerate() {
        let name = step_name(i);
        if got.time.to_bits() != step.time.to_bits() {
            return Err(fail(format!("step {name}: time {} instead of {}", got.time, step.time)));
        }
        let n = verify_fields(&step.fields, &step.rows, &got.fields).map_err(|m| fail(format!("step {name}: {m}")))?;
        checked += 1 + n;
    }
    Ok(checked)
}

/// Checks that `back` holds `fields` bit for bit (this rank's rows of the distributed ones, the
/// others whole); returns the number of values compared.
fn verify_fields(fields: &[Field], rows: &Rows, back: &[Field]) -> R<usize> {
    let mut checked = 0;
    for f in fields {
        let g = back.iter().find(|g| g.name == f.name).ok_or_else(|| format!("field {:?} missing", f.name))?;
        let n = f.ncomp;
        let same = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
        let rows: Vec<usize> = match rows.get(&f.name) {
            Some(r) => r.clone(),
            None => (0..values_len(&f.values) / n).collect(),
        };
        for (k, &row) in rows.iter().enumerate() {
            let ok = match (&f.values, &g.values) {
                (Values::F64(a), Values::F64(b)) => b.len() >= (row + 1) * n && same(&a[k * n..(k + 1) * n], &b[row * n..(row + 1) * n]),
                (Values::I32(a), Values::I32(b)) => b.len() >= (row + 1) * n && a[k * n..(k + 1) * n] == b[row * n..(row + 1) * n],
                _ => false,
            };
            if !ok {
                return Err(format!("field {:?} differs at row {row}", f.name));
            }
        }
        checked += rows.len() * n;
    }
    Ok(checked)
}

pub(super) fn read_file(path: &Path) -> R<OutputData> {
    let file = File::open(path).map_err(h5e("cannot open"))?;
    let mesh = file.group(MESH).map_err(h5e("opening /mesh"))?;

    let (shape, coords) = read_f64(&mesh.dataset(COORDINATES).map_err(h5e("opening /mesh/coordinates"))?).map_err(|m| format!("/mesh/coordinates: {m}"))?;
    if shape.len() != 2 || shape[1] != 3 {
        return Err(format!("/mesh/coordinates: shape {shape:?}, expected n × 3"));
    }
    let coordinates = coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();

    let cells = read_cells(&mesh)?;

    let fields = read_fields(&file.group(FIELDS).map_err(h5e("opening /fields"))?)?;
    let steps = match file.link_exists(STEPS) {
        true => read_steps(&file.group(STEPS).map_err(h5e("opening /steps"))?)?,
        false => Vec::new(),
    };

    let root = file.group("/").map_err(h5e("opening /"))?;
    let mut attributes = Vec::new();
    for name in attr_names(&root).map_err(h5e("listing root attributes"))? {
        let attr = root.attr(&name).map_err(h5e(format!("opening attribute {name:?}")))?;
        let value = read_str_attr(&attr).map_err(|m| format!("attribute {name:?}: {m}"))?;
        attributes.push((name, value));
    }
    Ok(OutputData { coordinates, cells, mesh_rows: None, fields, attributes, rows: Default::default(), steps })
}

/// Every field dataset in `group`, in creation order (by name where the group does not track
/// it).
fn read_fields(group: &Group) -> R<Vec<Field>> {
    let path = group.name();
    let names = link_names(group).map_err(h5e(format!("listing {path}")))?;
    let mut fields = Vec::with_capacity(names.len());
    for name in names {
        fields.push(read_field(group, &name).map_err(|m| format!("{path}/{name}: {m}"))?);
    }
    Ok(fields)
}

/// The steps under `/steps`, which must be named `0001`, `0002`, … without a gap.
fn read_steps(group: &Group) -> R<Vec<Step>> {
    let mut names = link_names(group).map_err(h5e("listing /steps"))?;
    // Numeric order whether or not the file tracks creation order (`10000` after `9999`).
    names.sort_by(|a, b| a.len().cmp(&b.len()).then_with(|| a.cmp(b)));
    let mut steps = Vec::with_capacity(names.len());
    for (i, name) in names.iter().enumerate() {
        if *name != step_name(i) {
            return Err(format!("/steps/{name}: expected step {} here", step_name(i)));
        }
        let step = group.group(name).map_err(h5e(format!("opening /steps/{name}")))?;
        let time = read_time_attr(&step).map_err(|m| format!("/steps/{name}: attribute \"time\": {m}"))?;
        steps.push(Step { time, fields: read_fields(&step)?, rows: Default::default() });
    }
    Ok(steps)
}

/// Reads a step's scalar float `time` attribute as f64.
fn read_time_attr(group: &Group) -> R<f64> {
    let attr = group.attr(TIME_ATTR).map_err(h5e("opening"))?;
    if !attr.is_scalar() {
        return Err(format!("shape {:?}, expected a scalar", attr.shape()));
    }
    match attr.dtype().and_then(|t| t.to_descriptor()).map_err(h5e("datatype"))? {
        TypeDescriptor::Float(_) => attr.read_scalar::<f64>().map_err(h5e("reading")),
        other => Err(format!("datatype {other:?}, expected a float")),
    }
}

/// Link names in creation order, or by name where the group does not track creation order.
pub(super) fn link_names(g: &Group) -> ::hdf5::Result<Vec<String>> {
    let tracked = g.gcpl().map(|p| p.get_link_creation_order().ok()).ok().flatten();
    let ordered = matches!(tracked, Some(LinkCreationOrder::Indexed | LinkCreationOrder::Tracked));
    let index = if ordered { IndexType::CreationOrder } else { IndexType::Name };
    g.member_names_by(index, IterationOrder::Increasing)
}

/// Attribute names in creation order, or by name where the group does not track it.
///
/// Asks the group's own creation property list: the one `H5Fget_create_plist` gives for the
/// file reports attribute creation order as untracked even when the root group tracks it.
fn attr_names(g: &Group) -> ::hdf5::Result<Vec<String>> {
    let tracked = g.gcpl().map(|p| p.get_attr_creation_order().ok()).ok().flatten();
    let ordered = matches!(tracked, Some(AttrCreationOrder::Indexed | AttrCreationOrder::Tracked));
    let index = if ordered { IndexType::CreationOrder } else { IndexType::Name };
    g.attr_names_by(index, IterationOrder::Increasing)
}

fn read_raw<T: H5Type>(ds: &Dataset) -> ::hdf5::Result<Vec<T>> {
    // Avoid handing HDF5 a dangling pointer for an empty dataset.
    if ds.size() == 0 {
        Ok(Vec::new())
    } else {
        ds.read_raw()
    }
}

fn read_f64(ds: &Dataset) -> R<(Vec<usize>, Vec<f64>)> {
    match ds.dtype().and_then(|t| t.to_descriptor()).map_err(h5e("datatype"))? {
        TypeDescriptor::Float(_) => {}
        other => return Err(format!("datatype {other:?}, expected a float")),
    }
    Ok((ds.shape(), read_raw(ds).map_err(h5e("reading"))?))
}

fn read_field(group: &Group, name: &str) -> R<Field> {
    let ds = group.dataset(name).map_err(h5e("opening"))?;
    let shape = ds.shape();
    let ncomp = match shape.as_slice() {
        [_] => 1,
        [_, n] if *n > 0 => *n,
        _ => return Err(format!("shape {shape:?}, expected len or len × ncomp")),
    };
    let values = match ds.dtype().and_then(|t| t.to_descriptor()).map_err(h5e("datatype"))? {
        TypeDescriptor::Float(_) => Values::F64(read_raw(&ds).map_err(h5e("reading"))?),
        TypeDescriptor::Integer(IntSize::U1 | IntSize::U2 | IntSize::U4) | TypeDescriptor::Unsigned(IntSize::U1 | IntSize::U2) => {
            Values::I32(read_raw(&ds).map_err(h5e("reading"))?)
        }
        other => return Err(format!("unsupported datatype {other:?}")),
    };
    let attr = ds.attr(CENTER_ATTR).map_err(h5e("no \"center\" attribute"))?;
    let center = match read_str_attr(&attr).map_err(|m| format!("attribute \"center\": {m}"))?.as_str() {
        "node" => Center::Node,
        "cell" => Center::Cell,
        other => return Err(format!("attribute \"center\" is {other:?}, expected \"node\" or \"cell\"")),
    };
    Ok(Field { name: name.to_owned(), center, ncomp, values })
}

/// Reads a scalar variable-length string attribute (UTF-8 or ASCII).
pub(super) fn read_str_attr(attr: &Attribute) -> R<String> {
    if !attr.is_scalar() {
        return Err(format!("shape {:?}, expected a scalar string", attr.shape()));
    }
    match attr.dtype().and_then(|t| t.to_descriptor()).map_err(h5e("datatype"))? {
        TypeDescriptor::VarLenUnicode => Ok(attr.read_scalar::<VarLenUnicode>().map_err(h5e("reading"))?.as_str().to_owned()),
        TypeDescriptor::VarLenAscii => Ok(attr.read_scalar::<VarLenAscii>().map_err(h5e("reading"))?.as_str().to_owned()),
        other => Err(format!("datatype {other:?}, expected a variable-length string")),
    }
}

/// The cells of `/mesh` in our node order, from whichever of [`CELL_DATASETS`] the file holds.
fn read_cells(mesh: &Group) -> R<Vec<Cell>> {
    let present: Vec<&str> = CELL_DATASETS.iter().copied().filter(|n| mesh.link_exists(n)).collect();
    let name = match present.as_slice() {
        [one] => *one,
        [] => return Err(format!("/mesh holds no cells (none of {})", CELL_DATASETS.join(", "))),
        several => return Err(format!("/mesh holds several cell datasets ({}), expected one", several.join(", "))),
    };
    let path = format!("/mesh/{name}");
    let ds = mesh.dataset(name).map_err(h5e(format!("opening {path}")))?;
    let shape = ds.shape();
    let raw: Vec<i64> = read_raw(&ds).map_err(h5e(format!("reading {path}")))?;
    let node = |v: i64| usize::try_from(v).map_err(|_| format!("{path}: negative node index {v}"));
    let cell = |kind: CellKind, file: &[i64]| -> R<Cell> {
        let mut n = [0usize; MAX_CELL_NODES];
        for (k, &i) in file_order(kind).iter().enumerate() {
            n[i] = node(file[k])?;
        }
        Ok(Cell::new(kind, &n[..kind.len()]))
    };
    if name == MIXED {
        if shape.len() != 1 {
            return Err(format!("{path}: shape {shape:?}, expected a flat list"));
        }
        let mut cells = Vec::new();
        let mut at = 0;
        while at < raw.len() {
            let kind = kind_of_id(raw[at]).ok_or_else(|| format!("{path}: unknown XDMF cell type {} at value {at}", raw[at]))?;
            let nodes = raw.get(at + 1..at + 1 + kind.len()).ok_or_else(|| format!("{path}: the last cell ({}) lacks nodes", kind.xdmf_name()))?;
            cells.push(cell(kind, nodes)?);
            at += 1 + kind.len();
        }
        return Ok(cells);
    }
    let kind = CellKind::ALL.into_iter().find(|&k| CellLayout::Uniform(k).dataset() == name).unwrap_or(CellKind::Hex8);
    if shape.len() != 2 || shape[1] != kind.len() {
        return Err(format!("{path}: shape {shape:?}, expected n × {}", kind.len()));
    }
    raw.chunks_exact(kind.len()).map(|c| cell(kind, c)).collect()
}
