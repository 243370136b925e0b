//! The HDF5 result file, written by all ranks together: MPI-IO file access and collective
//! writes ([`write_collective`]), each rank writing one contiguous block of every dataset's rows
//! (a hyperslab; the rows of a distributed field first sent to the rank whose block holds them,
//! one all-to-all exchange); one process without MPI writes it alone ([`write`](fn@write)).
//!
//! Layout:
//!
//! | path | type | shape |
//! |---|---|---|
//! | `/mesh/coordinates` | f64 | nnodes × 3 |
//! | `/mesh/hexahedra` | i64 | ncells × 8 (hex8 cells only, or no cells) |
//! | `/mesh/tetrahedra` | i64 | ncells × 4 (tet4 cells only) |
//! | `/mesh/tetrahedra10` | i64 | ncells × 10 (tet10 cells only) |
//! | `/mesh/wedges` | i64 | ncells × 6 (wedge6 cells only) |
//! | `/mesh/hexahedra20` | i64 | ncells × 20 (hex20 cells only, VTK's node order) |
//! | `/mesh/hexahedra27` | i64 | ncells × 27 (hex27 cells only, VTK's node order) |
//! | `/mesh/wedges15` | i64 | ncells × 15 (wedge15 cells only, VTK's node order) |
//! | `/mesh/pyramids` | i64 | ncells × 5 (pyr5 cells only) |
//! | `/mesh/mixed` | i64 | Σ (1 + nodes of the cell) (cells of several types) |
//! | `/fields/<name>` | f64 or i32 | `len` (ncomp = 1) or `len × ncomp` |
//! | `/steps/<NNNN>/<name>` | f64 or i32 | as `/fields/<name>` |
//!
//! `/mesh` holds exactly one of the cell datasets ([`CellLayout`]; a mesh of hexahedra writes
//! `/mesh/hexahedra` as it always has). Cells are rows in the global cell order, nodes as global
//! node numbers in XDMF's (= VTK's) node order, which is ours but for a 10-node tetrahedron: its
//! edge nodes (0,1), (1,2), (0,2), (0,3), (1,3), (2,3) — Gmsh's last two swapped. `/mesh/mixed` is
//! XDMF's `Mixed` topology: per cell, in the global cell order, its XDMF type id
//! ([`CellKind::xdmf_id`](crate::mesh::CellKind::xdmf_id): Hexahedron 9, Tetrahedron 6, Tetrahedron_10 38, Wedge 8, Pyramid 7, …) and its
//! nodes. Cell-centred fields are indexed by the global cell order whatever the layout. Under
//! MPI with a distributed mesh, the layout is agreed over the ranks ([`cell_layout`]), and each
//! rank writes the mixed values of its block of cell rows at their offset in the global list.
//!
//! Each field dataset carries a string attribute `center` (`"node"` or `"cell"`). Every entry of
//! [`OutputData::attributes`] is a variable-length UTF-8 string attribute on the root group.
//! `/steps` exists only for a load path ([`OutputData::steps`] non-empty): one group per
//! [`super::Step`], named by its index from 1 in 4 digits (`0001`, `0002`, …), with a scalar
//! f64 attribute `time` and the step's fields written like those of `/fields`; `/fields` holds
//! the final state either way. Datasets are contiguous and uncompressed. The file and every
//! group it creates track creation order, so [`read`](fn@read) gives steps, fields and attributes back
//! in the order they were written (files from elsewhere that do not track it come back sorted
//! by name).
//!
//! [`write`](fn@write) writes the file in place; [`super::write_all`] gives it a temporary name and
//! renames it only when every output file succeeded.
//!
//! The files here: this one the public calls and the error text every part shares;
//! `layout.rs` what goes where in the file (the names, [`CellLayout`], cells as values);
//! `validate.rs` the checks of the data before anything is created; `room.rs` the file
//! system's room (refusing a write that cannot fit, holding room for the metadata);
//! `write.rs` the collective steps that create and fill the file; `dataspace.rs` the rows each
//! rank writes (blocks, the all-to-all exchange, hyperslab selections); `read.rs` reading a
//! file back and checking it; `tests.rs` the unit tests.

mod dataspace;
mod layout;
mod read;
mod room;
#[cfg(test)]
mod tests;
mod validate;
mod write;

use std::path::Path;

use read::read_file;
use room::{check_room, metadata_bytes, Reserve};
use validate::validate;
use write::write_file;

use super::{Center, OutputData, Values};
use crate::comm::Comm;
use crate::error::{Error, Result};

pub use layout::{cell_layout, CellLayout};
pub use read::verify;

/// Distributed fields: field name → the rows this rank holds ([`OutputData::rows`]).
pub(super) type Rows = std::collections::BTreeMap<String, Vec<usize>>;

/// Writes `data` to the HDF5 file `path` (replacing it) from this one process; a partly
/// written file is removed.
///
/// Fails on inconsistent data (a field, in `/fields` or in a step, whose length does not match
/// the node/cell count, a cell referencing a missing node, an unusable field name, a string with
/// an interior NUL, step times not finite and increasing) before anything is created.
pub fn write(path: &Path, data: &OutputData) -> Result<()> {
    write_collective(&crate::comm::SerialComm, path, data)
}

/// Writes `data` to `path` with every rank of `comm` (each passing its own rows of the
/// distributed fields, `data.rows`, and the same everything else): one file through MPI-IO,
/// collective transfers. A partly written file is removed by rank 0.
pub fn write_collective<C: Comm>(comm: &C, path: &Path, data: &OutputData) -> Result<()> {
    let shown = path.display().to_string();
    comm.agree(validate(data).map_err(|msg| Error::output(&shown, msg)))?;
    comm.agree(if comm.is_root() { check_room(path, data) } else { Ok(()) })?;
    let mut reserve = comm.agree(if comm.is_root() { Reserve::hold(path, metadata_bytes(data)) } else { Ok(Reserve(None)) })?;
    let result = write_file(comm, path, data, &mut reserve);
    if result.is_err() && comm.is_root() {
        let _ = std::fs::remove_file(path);
    }
    result.map_err(|e| match e {
        Error::Output { msg, .. } => Error::output(&shown, msg),
        other => other,
    })
}

/// Writes named f64 arrays (each with its shape) to a new serial HDF5 file, under
/// a temporary name of its own renamed when complete: a failure leaves no file.
pub fn write_arrays(path: &Path, arrays: &[(&str, Vec<usize>, &[f64])]) -> Result<()> {
    let shown = path.display().to_string();
    let tmp = super::staging(path, &super::tmpfiles::token());
    super::tmpfiles::track(&tmp);
    let result = (|| -> std::result::Result<(), ::hdf5::Error> {
        let file = ::hdf5::File::create(&tmp)?;
        for (name, shape, v) in arrays {
            file.new_dataset::<f64>().shape(shape.clone()).create(*name)?.write_raw(v)?;
        }
        file.close()
    })()
    .map_err(|e| Error::output(&shown, h5_text(&e)))
    .and_then(|()| {
        let _held = super::tmpfiles::hold();
        std::fs::rename(&tmp, path).map_err(|e| Error::io(&shown, e))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    super::tmpfiles::untrack(&tmp);
    result
}

/// Reads a file written by [`write`](fn@write) back.
///
/// Fields and attributes come back in creation order when the file tracks it (files written
/// by [`write`](fn@write) do), otherwise sorted by name. Float fields of any width are read as f64,
/// signed integer fields up to 32 bits (and unsigned up to 16) as i32; the `center` attribute
/// is required on every field. Root attributes must be variable-length strings.
pub fn read(path: &Path) -> Result<OutputData> {
    let shown = path.display().to_string();
    read_file(path).map_err(|msg| Error::output(shown, msg))
}

/// The number of nodes or cells of the mesh of `data`: the rows of a field centered at `c`.
pub(super) fn mesh_len(data: &OutputData, c: Center) -> usize {
    match c {
        Center::Node => data.nnodes(),
        Center::Cell => data.ncells(),
    }
}

pub(super) fn values_len(v: &Values) -> usize {
    match v {
        Values::F64(x) => x.len(),
        Values::I32(x) => x.len(),
    }
}

/// Turns an hdf5 error into a one-line message prefixed by what was being done.
pub(super) fn ctx(what: impl std::fmt::Display) -> impl FnOnce(::hdf5::Error) -> Error {
    move |e| Error::output(String::new(), format!("{what}: {}", h5_text(&e)))
}

/// One line for an HDF5 error: the top of its stack and, where it differs, the innermost
/// frame — the cause the operating system or MPI-IO gave (e.g. "No space left on device"),
/// which the top ("can't write data") does not say.
pub(super) fn h5_text(e: &::hdf5::Error) -> String {
    let Some(stack) = e.stack() else { return one_line(&e.to_string()) };
    let descs: Vec<String> = stack.iter().map(|f| one_line(f.desc())).filter(|d| !d.is_empty()).collect();
    match (descs.first(), descs.last()) {
        (Some(top), Some(cause)) if top != cause => format!("{top}: {cause}"),
        (Some(top), _) => top.clone(),
        _ => one_line(&e.to_string()),
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

pub(super) type R<T> = std::result::Result<T, String>;

pub(super) fn h5e(what: impl std::fmt::Display) -> impl FnOnce(::hdf5::Error) -> String {
    move |e| format!("{what}: {}", one_line(&e.to_string()))
}
