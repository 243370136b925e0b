//! Creating and filling the file: the collective steps every rank runs in the same order, each
//! agreed over the ranks ([`Writer`]), the groups, the mesh, the fields, the steps and the
//! attributes.

use std::path::Path;

use ::hdf5::plist::file_create::{AttrCreationOrder, LinkCreationOrder};
use ::hdf5::types::VarLenUnicode;
use ::hdf5::{File, Group, Location};

use super::dataspace::{gather_block, write_dataset, write_rows};
use super::layout::{cell_layout, cell_values, center_str, kind_of_id, CellLayout, CENTER_ATTR, COORDINATES, FIELDS, MESH, MIXED, STEPS, TIME_ATTR};
use super::room::{free_bytes, whole_on_disk, Reserve};
use super::{ctx, h5_text, mesh_len, Rows};
use crate::comm::Comm;
use crate::error::{Error, Result};
use crate::mesh::cell::MAX_CELL_NODES;
use crate::mesh::CellKind;
use crate::output::{step_name, Field, OutputData, Values};

/// What each collective step of writing one file needs: the ranks, and the file, to name it
/// in a message before the message travels to the other ranks.
pub(super) struct Writer<'a, C: Comm> {
    pub(super) comm: &'a C,
    pub(super) path: &'a Path,
}

impl<C: Comm> Writer<'_, C> {
    /// Agrees on one collective step's result over the ranks ([`Comm::agree`]): when any rank
    /// failed, every rank returns the error (naming the file) of the lowest failing rank.
    pub(super) fn all<T>(&self, r: Result<T>) -> Result<T> {
        self.comm.agree(r.map_err(|e| match e {
            Error::Output { path, msg } if path.is_empty() => Error::output(self.path.display().to_string(), msg),
            other => other,
        }))
    }

    /// The cause of a failed write that HDF5's stack does not give (MPI-IO reports a short
    /// write as "file write failed"): when the file's file system has less room left than the
    /// `need`ed bytes, `" (<the OS's text for ENOSPC>)"`, else nothing.
    pub(super) fn no_space(&self, need: u64) -> String {
        let dir = self.path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        match free_bytes(dir) {
            Some(free) if free < need.max(1) => format!(" ({})", std::io::Error::from_raw_os_error(libc::ENOSPC)),
            _ => String::new(),
        }
    }
}

/// Creates, fills and closes the file. Every rank runs the same sequence of collective HDF5
/// calls: each fallible step is agreed ([`Comm::agree`]) before the next one, so an error on
/// one rank (MPI-IO's "No space left on device" in a collective write) stops every rank at
/// the same point, and the file is closed (collectively) by all of them.
pub(super) fn write_file<C: Comm>(comm: &C, tmp: &Path, data: &OutputData, reserve: &mut Reserve) -> Result<()> {
    let w = Writer { comm, path: tmp };
    let file = w.all(
        File::with_options()
            .with_fapl(|p| match comm.mpi_comm() {
                Some(raw) => p.mpio(raw, None),
                None => p,
            })
            .with_fcpl(|p| p.attr_creation_order(AttrCreationOrder::Indexed).link_creation_order(LinkCreationOrder::Indexed))
            .create(tmp)
            .map_err(ctx("cannot create file")),
    )?;
    let written = write_contents(&w, &file, data);
    if written.is_err() && comm.is_root() {
        // HDF5 flushes its metadata when the file closes, rank 0 writing it: on a full disk
        // that fails on rank 0 alone and the ranks part ways inside H5Fclose (a hang). The
        // file is going anyway: emptied, it leaves room for that last small write.
        let _ = std::fs::OpenOptions::new().write(true).open(tmp).and_then(|f| f.set_len(0));
    }
    // the room held for the metadata is given back before any rank's close writes it
    reserve.release();
    let _ = w.all(Ok(()));
    // Every child handle is dropped by now, so this really closes (and flushes) the file; after
    // an error it is closed all the same, by every rank.
    let closed = w.all(file.close().map_err(|e| ctx(format!("closing file{}", w.no_space(1)))(e)));
    let whole = if written.is_ok() && closed.is_ok() { w.all(if comm.is_root() { whole_on_disk(tmp, data) } else { Ok(()) }) } else { Ok(()) };
    written.and(closed).and(whole)
}

fn write_contents<C: Comm>(w: &Writer<'_, C>, file: &File, data: &OutputData) -> Result<()> {
    let mesh = create_group(w, file, MESH)?;
    let rows = data.mesh_rows.as_ref().map(|m| (m.node_rows.as_slice(), m.cell_rows.as_slice()));
    let coords: Vec<f64> = data.coordinates.iter().flatten().copied().collect();
    write_dataset(w, &mesh, COORDINATES, &[data.nnodes(), 3], rows.map(|r| r.0), &coords)?;
    let layout = w.all(cell_layout(w.comm, data))?;
    match layout {
        CellLayout::Uniform(kind) => {
            let conn = w.all(cell_values(&data.cells, false, false))?;
            write_dataset(w, &mesh, layout.dataset(), &[data.ncells(), kind.len()], rows.map(|r| r.1), &conn)?;
        }
        CellLayout::Mixed { len } => write_mixed(w, &mesh, data, len)?,
    }
    drop(mesh);

    let fields = create_group(w, file, FIELDS)?;
    write_fields(w, &fields, data, &data.fields, &data.rows)?;
    drop(fields);
    if !data.steps.is_empty() {
        write_steps(w, file, data)?;
    }

    for (name, value) in &data.attributes {
        w.all(write_str_attr(file, name, value).map_err(|m| Error::output(String::new(), m)))?;
    }
    Ok(())
}

/// Writes `/mesh/mixed` (`len` values): whole from every rank where the cells are the whole
/// mesh; where they are distributed, each rank's cells first sent to the rank whose [`block`](super::dataspace::block)
/// of cell rows holds them, and each rank writes its block's values at their offset in the
/// global order (the sum of the lower ranks' lengths, one sum over the ranks).
fn write_mixed<C: Comm>(w: &Writer<'_, C>, group: &Group, data: &OutputData, len: usize) -> Result<()> {
    let Some(m) = &data.mesh_rows else {
        let flat = w.all(cell_values(&data.cells, true, false))?;
        write_dataset(w, group, MIXED, &[len], None, &flat)?;
        return Ok(());
    };
    const WIDTH: usize = 1 + MAX_CELL_NODES;
    let records = w.all(cell_values(&data.cells, true, true))?;
    let mine = gather_block(w.comm, m.cells, WIDTH, &m.cell_rows, &records);
    let mut chunk = Vec::with_capacity(mine.len());
    for r in mine.chunks_exact(WIDTH) {
        // every row is held ([`cell_layout`] refused the mesh otherwise)
        let n = kind_of_id(r[0]).map_or(0, CellKind::len);
        chunk.extend_from_slice(&r[..1 + n]);
    }
    let (rank, size) = (w.comm.rank(), w.comm.size());
    let mut lens = vec![0u64; size];
    lens[rank] = chunk.len() as u64;
    w.comm.sum_u64(&mut lens);
    let lo = lens[..rank].iter().sum::<u64>() as usize;
    let total = lens.iter().sum::<u64>() as usize;
    w.all(match total == len {
        true => Ok(()),
        false => Err(Error::output(String::new(), format!("/mesh/{MIXED}: the ranks' cells make {total} values, expected {len}"))),
    })?;
    write_rows(w, group, MIXED, &[len], lo, lo + chunk.len(), &chunk)?;
    Ok(())
}

/// Creates the group `name` in `parent`, tracking the creation order of its links and
/// attributes (so [`read`](fn@super::read) gives them back in that order).
/// Collective: agreed over the ranks.
fn create_group<C: Comm>(w: &Writer<'_, C>, parent: &Group, name: &str) -> Result<Group> {
    w.all(
        parent
            .create_group_builder()
            .with_gcpl(|p| p.link_creation_order(LinkCreationOrder::Indexed).attr_creation_order(AttrCreationOrder::Indexed))
            .create(name)
            .map_err(ctx(format!("creating {}/{name}", parent.name().trim_end_matches('/')))),
    )
}

/// Writes `fields` into `group`, one dataset each with its `center` attribute: the rows `rows`
/// of the distributed ones, the replicated ones whole (see [`write_dataset`]).
fn write_fields<C: Comm>(w: &Writer<'_, C>, group: &Group, data: &OutputData, fields: &[Field], rows: &Rows) -> Result<()> {
    for f in fields {
        let len = mesh_len(data, f.center);
        let rows = rows.get(&f.name).map(Vec::as_slice);
        let shape = if f.ncomp == 1 { vec![len] } else { vec![len, f.ncomp] };
        let ds = match &f.values {
            Values::F64(v) => write_dataset(w, group, &f.name, &shape, rows, v)?,
            Values::I32(v) => write_dataset(w, group, &f.name, &shape, rows, v)?,
        };
        w.all(write_str_attr(&ds, CENTER_ATTR, center_str(f.center)).map_err(|m| Error::output(String::new(), format!("{}/{}: {m}", group.name(), f.name))))?;
    }
    Ok(())
}

/// Writes `/steps`: one group per step with its `time` attribute and its fields.
fn write_steps<C: Comm>(w: &Writer<'_, C>, file: &File, data: &OutputData) -> Result<()> {
    let steps = create_group(w, file, STEPS)?;
    for (i, step) in data.steps.iter().enumerate() {
        let group = create_group(w, &steps, &step_name(i))?;
        w.all(write_time_attr(&group, step.time))?;
        write_fields(w, &group, data, &step.fields, &step.rows)?;
    }
    Ok(())
}

/// Writes the scalar f64 attribute `time` on a step's group.
fn write_time_attr(group: &Group, time: f64) -> Result<()> {
    let what = || format!("attribute {TIME_ATTR:?} of {}", group.name());
    group
        .new_attr::<f64>()
        .shape(())
        .create(TIME_ATTR)
        .map_err(|e| ctx(format!("creating {}", what()))(e))?
        .write_scalar(&time)
        .map_err(|e| ctx(format!("writing {}", what()))(e))
}

/// Writes a scalar variable-length UTF-8 string attribute on `loc`.
fn write_str_attr(loc: &Location, name: &str, value: &str) -> std::result::Result<(), String> {
    let v: VarLenUnicode = value.parse().map_err(|e| format!("attribute {name:?}: {e}"))?;
    let attr = loc.new_attr::<VarLenUnicode>().shape(()).create(name).map_err(|e| format!("creating attribute {name:?}: {}", h5_text(&e)))?;
    attr.write_scalar(&v).map_err(|e| format!("writing attribute {name:?}: {}", h5_text(&e)))
}
