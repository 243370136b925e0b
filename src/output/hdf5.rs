//! The HDF5 result file, written by all ranks together: MPI-IO file access and collective
//! writes ([`write_collective`]), each rank writing one contiguous block of every dataset's rows
//! (a hyperslab; the rows of a distributed field first sent to the rank whose block holds them,
//! one all-to-all exchange); one process without MPI writes it alone ([`write`]).
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
//! | `/mesh/mixed` | i64 | Σ (1 + nodes of the cell) (cells of several types) |
//! | `/fields/<name>` | f64 or i32 | `len` (ncomp = 1) or `len × ncomp` |
//! | `/steps/<NNNN>/<name>` | f64 or i32 | as `/fields/<name>` |
//!
//! `/mesh` holds exactly one of the cell datasets ([`CellLayout`]; a mesh of hexahedra writes
//! `/mesh/hexahedra` as it always has). Cells are rows in the global cell order, nodes as global
//! node numbers in XDMF's (= VTK's) node order, which is ours but for a 10-node tetrahedron: its
//! edge nodes (0,1), (1,2), (0,2), (0,3), (1,3), (2,3) — Gmsh's last two swapped. `/mesh/mixed` is
//! XDMF's `Mixed` topology: per cell, in the global cell order, its XDMF type id
//! ([`CellKind::xdmf_id`]: Hexahedron 9, Tetrahedron 6, Tetrahedron_10 38, Wedge 8) and its
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
//! group it creates track creation order, so [`read`] gives steps, fields and attributes back
//! in the order they were written (files from elsewhere that do not track it come back sorted
//! by name).
//!
//! [`write`] writes the file in place; [`super::write_all`] gives it a temporary name and
//! renames it only when every output file succeeded.

use std::path::{Path, PathBuf};

use ::hdf5::plist::file_create::{AttrCreationOrder, LinkCreationOrder};
use ::hdf5::types::{IntSize, TypeDescriptor, VarLenAscii, VarLenUnicode};
use ::hdf5::{Attribute, Dataset, File, Group, H5Type, IndexType, IterationOrder, Location};

use super::{check_step_times, step_name, Center, Field, OutputData, Step, Values};
use crate::comm::Comm;
use crate::error::{Error, Result};
use crate::mesh::cell::MAX_CELL_NODES;
use crate::mesh::{Cell, CellKind};

const MESH: &str = "mesh";
const FIELDS: &str = "fields";
const STEPS: &str = "steps";
const TIME_ATTR: &str = "time";
const COORDINATES: &str = "coordinates";
const HEXAHEDRA: &str = "hexahedra";
const TETRAHEDRA: &str = "tetrahedra";
const TETRAHEDRA10: &str = "tetrahedra10";
const WEDGES: &str = "wedges";
const MIXED: &str = "mixed";
const CENTER_ATTR: &str = "center";

/// Distributed fields: field name → the rows this rank holds ([`OutputData::rows`]).
type Rows = std::collections::BTreeMap<String, Vec<usize>>;

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

/// Refuses, before the file is created, to write `data` where the file system lacks room for
/// it: a disk that fills up in the middle of a collective write can leave the ranks' HDF5
/// metadata apart, and closing the file then waits forever (see [`write_file`]).
/// `TRESCA_FETI_SPACE_CHECK=off` skips the check (to test the failure in the middle).
fn check_room(path: &Path, data: &OutputData) -> Result<()> {
    if std::env::var("TRESCA_FETI_SPACE_CHECK").is_ok_and(|v| v == "off") {
        return Ok(());
    }
    let need = estimated_bytes(data);
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    match free_bytes(dir) {
        Some(free) if free < need => Err(Error::output(
            path.display().to_string(),
            format!("needs about {need} bytes, its file system has {free} free ({})", std::io::Error::from_raw_os_error(libc::ENOSPC)),
        )),
        _ => Ok(()),
    }
}

/// An upper bound of the file's size: every dataset's values (whole) and its metadata
/// ([`metadata_bytes`]).
fn estimated_bytes(data: &OutputData) -> u64 {
    let fields = |fs: &[Field]| -> u64 { fs.iter().map(|f| (mesh_len(data, f.center) * f.ncomp * 8) as u64).sum() };
    // the cells' values: exact for a whole mesh; for a distributed one, the widest of this
    // rank's cells for every cell
    let cell_values = match (&data.mesh_rows, CellLayout::of_cells(&data.cells)) {
        (None, CellLayout::Uniform(k)) => data.ncells() * k.len(),
        (None, CellLayout::Mixed { len }) => len,
        (Some(_), layout) => {
            let mixed = usize::from(matches!(layout, CellLayout::Mixed { .. }));
            data.ncells() * data.cells.iter().map(|c| c.kind.len() + mixed).max().unwrap_or(8)
        }
    };
    let mesh = (data.nnodes() * 3 * 8 + cell_values * 8) as u64;
    mesh + fields(&data.fields) + data.steps.iter().map(|s| fields(&s.fields)).sum::<u64>() + metadata_bytes(data)
}

/// An upper bound of what HDF5 writes besides the datasets' values: the attributes and room
/// for its own structures (object headers, heaps, B-trees).
fn metadata_bytes(data: &OutputData) -> u64 {
    let attrs: u64 = data.attributes.iter().map(|(k, v)| (k.len() + v.len()) as u64).sum();
    let objects = 4 + data.fields.len() + data.attributes.len() + data.steps.iter().map(|s| 1 + s.fields.len()).sum::<usize>();
    attrs + 4096 * objects as u64 + 65536
}

/// Room held on the file's file system for HDF5's metadata until the file closes (rank 0's
/// `<file>.reserve`, allocated before the file is created): HDF5 writes most of its metadata
/// while closing, and a disk full by then fails that write on some ranks only, which leaves
/// the ranks apart inside H5Fclose (a hang). Given back just before the close.
struct Reserve(Option<PathBuf>);

impl Reserve {
    /// Allocates `bytes` beside `path` (rank 0); fails with the OS's ENOSPC text when there
    /// is no room even for that.
    fn hold(path: &Path, bytes: u64) -> Result<Reserve> {
        let mut name = path.as_os_str().to_owned();
        name.push(".reserve");
        let r = PathBuf::from(name);
        super::tmpfiles::track(&r);
        let reserve = Reserve(Some(r.clone()));
        let io = |e: std::io::Error| Error::output(path.display().to_string(), format!("cannot hold {bytes} bytes for its metadata: {e}"));
        let f = std::fs::File::create(&r).map_err(io)?;
        use std::os::unix::io::AsRawFd;
        // SAFETY: a valid open descriptor; posix_fallocate returns an error number, sets no errno
        match unsafe { libc::posix_fallocate(f.as_raw_fd(), 0, bytes as libc::off_t) } {
            0 => Ok(reserve),
            e => Err(io(std::io::Error::from_raw_os_error(e))),
        }
    }

    /// Gives the room back (removes the file); idempotent.
    fn release(&mut self) {
        if let Some(r) = self.0.take() {
            let _ = std::fs::remove_file(&r);
            super::tmpfiles::untrack(&r);
        }
    }
}

impl Drop for Reserve {
    fn drop(&mut self) {
        self.release();
    }
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

/// Reads a file written by [`write`] back.
///
/// Fields and attributes come back in creation order when the file tracks it (files written
/// by [`write`] do), otherwise sorted by name. Float fields of any width are read as f64,
/// signed integer fields up to 32 bits (and unsigned up to 16) as i32; the `center` attribute
/// is required on every field. Root attributes must be variable-length strings.
pub fn read(path: &Path) -> Result<OutputData> {
    let shown = path.display().to_string();
    read_file(path).map_err(|msg| Error::output(shown, msg))
}

// ---------------------------------------------------------------------------------------------
// writing

/// Checks everything that would otherwise fail half-way through writing.
fn validate(data: &OutputData) -> std::result::Result<(), String> {
    let nnodes = data.nnodes();
    if let Some(m) = &data.mesh_rows {
        if m.node_rows.len() != data.coordinates.len() || m.cell_rows.len() != data.cells.len() {
            return Err(format!(
                "distributed mesh: {} node rows for {} coordinates, {} cell rows for {} cells",
                m.node_rows.len(),
                data.coordinates.len(),
                m.cell_rows.len(),
                data.cells.len()
            ));
        }
        if let Some(r) = m.node_rows.iter().find(|&&r| r >= m.nodes) {
            return Err(format!("distributed mesh: node row {r} beyond the {} nodes", m.nodes));
        }
        if let Some(r) = m.cell_rows.iter().find(|&&r| r >= m.cells) {
            return Err(format!("distributed mesh: cell row {r} beyond the {} cells", m.cells));
        }
    }
    if let Some((e, cell)) = data.cells.iter().enumerate().find(|(_, h)| h.nodes().iter().any(|&n| n >= nnodes)) {
        return Err(format!("cell {e} references node {:?} beyond the {nnodes} nodes", cell.nodes()));
    }
    validate_fields(data, &data.fields, &data.rows)?;
    check_step_times(&data.steps)?;
    for (i, step) in data.steps.iter().enumerate() {
        validate_fields(data, &step.fields, &step.rows).map_err(|m| format!("step {}: {m}", step_name(i)))?;
    }
    let mut names = std::collections::HashSet::new();
    for (name, value) in &data.attributes {
        if name.is_empty() {
            return Err("empty attribute name".into());
        }
        if name.contains('\0') || value.contains('\0') {
            return Err(format!("attribute {name:?}: name or value contains a NUL character"));
        }
        if !names.insert(name.as_str()) {
            return Err(format!("attribute {name:?} appears twice"));
        }
    }
    Ok(())
}

/// Checks one group's fields against the mesh of `data`: usable unique names, ncomp > 0, rows
/// on the mesh, and as many values as rows × ncomp.
fn validate_fields(data: &OutputData, fields: &[Field], rows: &Rows) -> std::result::Result<(), String> {
    let mut names = std::collections::HashSet::new();
    for f in fields {
        check_link_name(&f.name).map_err(|m| format!("field {:?}: {m}", f.name))?;
        if !names.insert(f.name.as_str()) {
            return Err(format!("field {:?} appears twice", f.name));
        }
        if f.ncomp == 0 {
            return Err(format!("field {:?}: ncomp is 0", f.name));
        }
        let len = mesh_len(data, f.center);
        let expected = match rows.get(&f.name) {
            Some(rows) => {
                if let Some(r) = rows.iter().find(|&&r| r >= len) {
                    return Err(format!("field {:?}: row {r} beyond the {len} {}s", f.name, center_str(f.center)));
                }
                rows.len()
            }
            None => len,
        };
        let got = values_len(&f.values);
        if got != expected * f.ncomp {
            return Err(format!("field {:?}: {got} values, expected {expected} {}s × {} components", f.name, center_str(f.center), f.ncomp));
        }
    }
    Ok(())
}

/// The number of nodes or cells of the mesh of `data`: the rows of a field centered at `c`.
fn mesh_len(data: &OutputData, c: Center) -> usize {
    match c {
        Center::Node => data.nnodes(),
        Center::Cell => data.ncells(),
    }
}

/// A dataset name must be one link: non-empty, no `/`, not `.`, no NUL.
fn check_link_name(name: &str) -> std::result::Result<(), &'static str> {
    if name.is_empty() || name == "." || name.contains('/') || name.contains('\0') {
        Err("a field name must be non-empty, not \".\", and contain no '/' or NUL")
    } else {
        Ok(())
    }
}

fn values_len(v: &Values) -> usize {
    match v {
        Values::F64(x) => x.len(),
        Values::I32(x) => x.len(),
    }
}

fn center_str(c: Center) -> &'static str {
    match c {
        Center::Node => "node",
        Center::Cell => "cell",
    }
}

/// Turns an hdf5 error into a one-line message prefixed by what was being done.
fn ctx(what: impl std::fmt::Display) -> impl FnOnce(::hdf5::Error) -> Error {
    move |e| Error::output(String::new(), format!("{what}: {}", h5_text(&e)))
}

/// One line for an HDF5 error: the top of its stack and, where it differs, the innermost
/// frame — the cause the operating system or MPI-IO gave (e.g. "No space left on device"),
/// which the top ("can't write data") does not say.
fn h5_text(e: &::hdf5::Error) -> String {
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

/// What each collective step of writing one file needs: the ranks, and the file, to name it
/// in a message before the message travels to the other ranks.
struct Writer<'a, C: Comm> {
    comm: &'a C,
    path: &'a Path,
}

impl<C: Comm> Writer<'_, C> {
    /// Agrees on one collective step's result over the ranks ([`Comm::agree`]): when any rank
    /// failed, every rank returns the error (naming the file) of the lowest failing rank.
    fn all<T>(&self, r: Result<T>) -> Result<T> {
        self.comm.agree(r.map_err(|e| match e {
            Error::Output { path, msg } if path.is_empty() => Error::output(self.path.display().to_string(), msg),
            other => other,
        }))
    }

    /// The cause of a failed write that HDF5's stack does not give (MPI-IO reports a short
    /// write as "file write failed"): when the file's file system has less room left than the
    /// `need`ed bytes, `" (<the OS's text for ENOSPC>)"`, else nothing.
    fn no_space(&self, need: u64) -> String {
        let dir = self.path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        match free_bytes(dir) {
            Some(free) if free < need.max(1) => format!(" ({})", std::io::Error::from_raw_os_error(libc::ENOSPC)),
            _ => String::new(),
        }
    }
}

/// Bytes an unprivileged writer may still use on the file system holding `dir` (statvfs).
fn free_bytes(dir: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    let mut st = std::mem::MaybeUninit::<libc::statvfs>::uninit();
    // SAFETY: `c` is a NUL-terminated path and `st` a buffer statvfs fills on success only.
    let st = unsafe {
        if libc::statvfs(c.as_ptr(), st.as_mut_ptr()) != 0 {
            return None;
        }
        st.assume_init()
    };
    Some((st.f_bavail as u64).saturating_mul(st.f_frsize as u64))
}

/// Creates, fills and closes the file. Every rank runs the same sequence of collective HDF5
/// calls: each fallible step is agreed ([`Comm::agree`]) before the next one, so an error on
/// one rank (MPI-IO's "No space left on device" in a collective write) stops every rank at
/// the same point, and the file is closed (collectively) by all of them.
fn write_file<C: Comm>(comm: &C, tmp: &Path, data: &OutputData, reserve: &mut Reserve) -> Result<()> {
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

/// After a write that reported success: the file must hold at least its datasets' bytes. Open
/// MPI's MPI-IO (ompio) prints "No space left on device" for a short collective write and
/// still returns success, leaving holes; a file allocated short of its values on a file system
/// with less room left than the shortfall is that (a compressing file system with room is not).
fn whole_on_disk(path: &Path, data: &OutputData) -> Result<()> {
    use std::os::unix::fs::MetadataExt;
    let values = estimated_bytes(data) - metadata_bytes(data);
    let allocated = std::fs::metadata(path).map(|m| m.blocks() * 512).unwrap_or(u64::MAX);
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    match free_bytes(dir) {
        Some(free) if allocated < values && free < values - allocated => Err(Error::output(
            path.display().to_string(),
            format!("the file holds {allocated} of its {values} bytes of values ({})", std::io::Error::from_raw_os_error(libc::ENOSPC)),
        )),
        _ => Ok(()),
    }
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

// ---------------------------------------------------------------------------------------------
// cells

/// How the cells of a result file are stored under `/mesh` (see the module's table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellLayout {
    /// Every cell of one type (an empty mesh: hexahedra): `/mesh/hexahedra`, `/mesh/tetrahedra`,
    /// `/mesh/tetrahedra10` or `/mesh/wedges`, ncells × nodes per cell.
    Uniform(CellKind),
    /// Cells of several types: `/mesh/mixed`, `len` values, per cell its XDMF type id
    /// ([`CellKind::xdmf_id`]) and its nodes.
    Mixed { len: usize },
}

impl CellLayout {
    /// From the number of cells of each type ([`CellKind::ALL`] order).
    fn from_counts(n: [usize; 4]) -> Self {
        let kinds: Vec<CellKind> = CellKind::ALL.iter().zip(n).filter(|(_, c)| *c > 0).map(|(&k, _)| k).collect();
        match kinds.as_slice() {
            [] => CellLayout::Uniform(CellKind::Hex8),
            [k] => CellLayout::Uniform(*k),
            _ => CellLayout::Mixed { len: CellKind::ALL.iter().zip(n).map(|(k, c)| c * (1 + k.len())).sum() },
        }
    }

    /// The layout of the whole mesh `cells`.
    pub fn of_cells(cells: &[Cell]) -> Self {
        let mut n = [0usize; 4];
        for c in cells {
            n[c.kind.code()] += 1;
        }
        Self::from_counts(n)
    }

    /// The dataset under `/mesh` that holds the cells.
    pub fn dataset(self) -> &'static str {
        match self {
            CellLayout::Uniform(CellKind::Hex8) => HEXAHEDRA,
            CellLayout::Uniform(CellKind::Tet4) => TETRAHEDRA,
            CellLayout::Uniform(CellKind::Tet10) => TETRAHEDRA10,
            CellLayout::Uniform(CellKind::Wedge6) => WEDGES,
            CellLayout::Mixed { .. } => MIXED,
        }
    }
}

/// The cell datasets [`read`] knows, one of which a file holds.
const CELL_DATASETS: [&str; 5] = [HEXAHEDRA, TETRAHEDRA, TETRAHEDRA10, WEDGES, MIXED];

/// The layout of the cells of `data` over all ranks: that of `data.cells` where they are the
/// whole mesh; where the mesh is distributed, that of the rows the ranks hold (their cell types
/// sent to the ranks whose [`block`]s hold the rows, one all-to-all exchange, then one sum).
/// Collective; the same result on every rank. A distributed mesh with a cell row that no rank
/// holds is an error.
pub fn cell_layout<C: Comm>(comm: &C, data: &OutputData) -> Result<CellLayout> {
    let Some(m) = &data.mesh_rows else { return Ok(CellLayout::of_cells(&data.cells)) };
    let ids: Vec<i64> = data.cells.iter().map(|c| c.kind.xdmf_id() as i64).collect();
    let mine = gather_block(comm, m.cells, 1, &m.cell_rows, &ids);
    // cells of each type in this rank's block, then the rows of it no rank holds (id 0)
    let mut n = [0u64; 5];
    for &id in &mine {
        match kind_of_id(id) {
            Some(k) => n[k.code()] += 1,
            None => n[4] += 1,
        }
    }
    comm.sum_u64(&mut n);
    if n[4] > 0 {
        return Err(Error::output(String::new(), format!("distributed mesh: {} of the {} cell rows are held by no rank", n[4], m.cells)));
    }
    Ok(CellLayout::from_counts(std::array::from_fn(|k| n[k] as usize)))
}

/// The cell type of an XDMF type id, if it is one of ours.
fn kind_of_id(id: i64) -> Option<CellKind> {
    CellKind::ALL.into_iter().find(|k| k.xdmf_id() as i64 == id)
}

/// The position in our node order of each node in the file's (XDMF's = VTK's) order: the same
/// but for a 10-node tetrahedron, whose edge nodes (3,2) and (3,1) come the other way round
/// there ((1,3) before (2,3)). An involution: it maps back as well.
fn file_order(kind: CellKind) -> &'static [usize] {
    const TET10: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];
    const IDENTITY: [usize; MAX_CELL_NODES] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9];
    match kind {
        CellKind::Tet10 => &TET10,
        k => &IDENTITY[..k.len()],
    }
}

/// The cells as i64 values in the file's node order: per cell its nodes (`mixed` false); its
/// XDMF type id and its nodes (`mixed`); and with `pad` each such record filled up with 0 to
/// 1 + [`MAX_CELL_NODES`] values (to be sent in fixed-size rows).
fn cell_values(cells: &[Cell], mixed: bool, pad: bool) -> Result<Vec<i64>> {
    let mut out = Vec::with_capacity(cells.len() * (1 + MAX_CELL_NODES));
    let big = || Error::output(String::new(), "node index does not fit in i64");
    for c in cells {
        if mixed {
            out.push(c.kind.xdmf_id() as i64);
        }
        for &i in file_order(c.kind) {
            out.push(i64::try_from(c.nodes()[i]).map_err(|_| big())?);
        }
        if pad {
            out.extend(std::iter::repeat_n(0, MAX_CELL_NODES - c.kind.len()));
        }
    }
    Ok(out)
}

/// Writes `/mesh/mixed` (`len` values): whole from every rank where the cells are the whole
/// mesh; where they are distributed, each rank's cells first sent to the rank whose [`block`]
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

/// Creates the group `name` in `parent`, tracking the creation order of its links and
/// attributes (so [`read`] gives them back in that order).
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

/// The rows `[lo, hi)` of `len` that rank `rank` of `size` writes: contiguous blocks in rank
/// order, the ranks' shares as even as can be.
fn block(len: usize, rank: usize, size: usize) -> (usize, usize) {
    (len * rank / size, len * (rank + 1) / size)
}

/// The rank whose [`block`] holds row `row` (< `len`).
fn block_owner(row: usize, len: usize, size: usize) -> usize {
    ((row + 1) * size - 1) / len
}

/// Element types of the datasets, carried bit for bit through [`Comm::all_to_all_u64`].
trait Bits: H5Type + Copy + Default {
    fn to_u64(self) -> u64;
    fn from_u64(b: u64) -> Self;
}

impl Bits for f64 {
    fn to_u64(self) -> u64 {
        self.to_bits()
    }
    fn from_u64(b: u64) -> Self {
        f64::from_bits(b)
    }
}

impl Bits for i32 {
    fn to_u64(self) -> u64 {
        u64::from(self as u32)
    }
    fn from_u64(b: u64) -> Self {
        b as u32 as i32
    }
}

impl Bits for i64 {
    fn to_u64(self) -> u64 {
        self as u64
    }
    fn from_u64(b: u64) -> Self {
        b as i64
    }
}

/// This rank's [`block`] of a distributed field of `len` rows × `ncomp`, from the rows each rank
/// holds (`rows`, values `v` in their order): one all-to-all exchange, each row sent to the rank
/// whose block has it. Rows no rank holds are 0 (HDF5's fill value); a row held twice gets the
/// values of its last holder (by rank, then by position).
fn gather_block<T: Bits, C: Comm>(comm: &C, len: usize, ncomp: usize, rows: &[usize], v: &[T]) -> Vec<T> {
    let size = comm.size();
    let mut counts = vec![0usize; size];
    for &r in rows {
        counts[block_owner(r, len, size)] += 1 + ncomp;
    }
    let mut send: Vec<Vec<u64>> = counts.iter().map(|&n| Vec::with_capacity(n)).collect();
    for (&r, x) in rows.iter().zip(v.chunks_exact(ncomp)) {
        let m = &mut send[block_owner(r, len, size)];
        m.push(r as u64);
        m.extend(x.iter().map(|&y| y.to_u64()));
    }
    let (lo, hi) = block(len, comm.rank(), size);
    let mut out = vec![T::default(); (hi - lo) * ncomp];
    for m in comm.all_to_all_u64(&send) {
        for rec in m.chunks_exact(1 + ncomp) {
            let at = (rec[0] as usize - lo) * ncomp;
            for (o, &b) in out[at..at + ncomp].iter_mut().zip(&rec[1..]) {
                *o = T::from_u64(b);
            }
        }
    }
    out
}

/// Creates the dataset `name` of the global `shape` (len or len × ncomp) and writes this
/// rank's [`block`] of its rows as one hyperslab: taken from `v` where it is replicated (rows
/// None), gathered by [`gather_block`] from every rank's rows `rows` (values `v` in their order)
/// where it is distributed. Collective (a rank with nothing to write still takes part with an
/// empty selection), and through collective MPI-IO transfers under MPI.
fn write_dataset<T: Bits, C: Comm>(w: &Writer<'_, C>, group: &Group, name: &str, shape: &[usize], rows: Option<&[usize]>, v: &[T]) -> Result<Dataset> {
    let ncomp = shape.get(1).copied().unwrap_or(1);
    let (lo, hi) = block(shape[0], w.comm.rank(), w.comm.size());
    let gathered;
    let vals = match rows {
        Some(r) => {
            gathered = gather_block(w.comm, shape[0], ncomp, r, v);
            &gathered[..]
        }
        None => &v[lo * ncomp..hi * ncomp],
    };
    write_rows(w, group, name, shape, lo, hi, vals)
}

/// Creates the dataset `name` of the global `shape` and writes the rows `[lo, hi)` of it from
/// `vals` (`(hi − lo) × ncomp` values) as one hyperslab. Collective, like [`write_dataset`]:
/// every rank calls it, each with its own rows (possibly none); the ranks' rows must not
/// overlap.
fn write_rows<T: Bits, C: Comm>(w: &Writer<'_, C>, group: &Group, name: &str, shape: &[usize], lo: usize, hi: usize, vals: &[T]) -> Result<Dataset> {
    use hdf5_sys::h5::hsize_t;
    use hdf5_sys::h5d::{H5Dget_space, H5Dwrite};
    use hdf5_sys::h5p::{H5FD_mpio_xfer_t, H5Pclose, H5Pcreate, H5Pset_dxpl_mpio, H5P_CLS_DATASET_XFER, H5P_DEFAULT};
    use hdf5_sys::h5s::{H5S_seloper_t, H5Sclose, H5Screate_simple, H5Sselect_hyperslab, H5Sselect_none};
    let what = || format!("dataset {}/{name}", group.name());
    let ncomp = shape.get(1).copied().unwrap_or(1);
    let ds = w.all(group.new_dataset::<T>().shape(shape.to_vec()).create(name).map_err(|e| ctx(format!("creating {}", what()))(e)))?;
    let mem_type = w.all(::hdf5::Datatype::from_type::<T>().map_err(|e| ctx(format!("datatype of {}", what()))(e)))?;
    let collective = w.comm.mpi_comm().is_some();
    // SAFETY: plain HDF5 C calls on ids this function owns (closed below) or that `ds` keeps
    // alive; the buffer holds `vals.len()` elements of `T`, matching the memory space. They run
    // under hdf5-metno's global lock, like its own calls (HDF5 is not thread-safe).
    let status = ::hdf5::sync::sync(|| unsafe {
        let fspace = H5Dget_space(ds.id());
        if hi > lo {
            let start = [lo as hsize_t, 0];
            let count = [(hi - lo) as hsize_t, ncomp as hsize_t];
            H5Sselect_hyperslab(fspace, H5S_seloper_t::H5S_SELECT_SET, start.as_ptr(), std::ptr::null(), count.as_ptr(), std::ptr::null());
        } else {
            H5Sselect_none(fspace);
        }
        let mdims = [vals.len().max(1) as hsize_t];
        let mspace = H5Screate_simple(1, mdims.as_ptr(), std::ptr::null());
        if vals.is_empty() {
            H5Sselect_none(mspace);
        }
        let dxpl = if collective {
            let d = H5Pcreate(*H5P_CLS_DATASET_XFER);
            H5Pset_dxpl_mpio(d, H5FD_mpio_xfer_t::H5FD_MPIO_COLLECTIVE);
            d
        } else {
            H5P_DEFAULT
        };
        // HDF5 wants a non-null buffer even when nothing is selected
        let one = std::mem::MaybeUninit::<T>::uninit();
        let buf = if vals.is_empty() { one.as_ptr() } else { vals.as_ptr() };
        let st = H5Dwrite(ds.id(), mem_type.id(), mspace, fspace, dxpl, buf.cast());
        // the reason, read off HDF5's error stack before another call clears it
        let why = (st < 0).then(|| ::hdf5::Error::query().map_or_else(|e| e.to_string(), |e| h5_text(&e)));
        if collective {
            H5Pclose(dxpl);
        }
        H5Sclose(mspace);
        H5Sclose(fspace);
        why
    });
    // one rank's failed share of a collective write stops every rank here
    w.all(match status {
        Some(why) => Err(Error::output(String::new(), format!("writing {}: {why}{}", what(), w.no_space(std::mem::size_of_val(vals) as u64)))),
        None => Ok(()),
    })?;
    Ok(ds)
}

/// Writes a scalar variable-length UTF-8 string attribute on `loc`.
fn write_str_attr(loc: &Location, name: &str, value: &str) -> std::result::Result<(), String> {
    let v: VarLenUnicode = value.parse().map_err(|e| format!("attribute {name:?}: {e}"))?;
    let attr = loc.new_attr::<VarLenUnicode>().shape(()).create(name).map_err(|e| format!("creating attribute {name:?}: {}", h5_text(&e)))?;
    attr.write_scalar(&v).map_err(|e| format!("writing attribute {name:?}: {}", h5_text(&e)))
}

// ---------------------------------------------------------------------------------------------
// reading

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

type R<T> = std::result::Result<T, String>;

fn h5e(what: impl std::fmt::Display) -> impl FnOnce(::hdf5::Error) -> String {
    move |e| format!("{what}: {}", one_line(&e.to_string()))
}

fn read_file(path: &Path) -> R<OutputData> {
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
fn link_names(g: &Group) -> ::hdf5::Result<Vec<String>> {
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
fn read_str_attr(attr: &Attribute) -> R<String> {
    if !attr.is_scalar() {
        return Err(format!("shape {:?}, expected a scalar string", attr.shape()));
    }
    match attr.dtype().and_then(|t| t.to_descriptor()).map_err(h5e("datatype"))? {
        TypeDescriptor::VarLenUnicode => Ok(attr.read_scalar::<VarLenUnicode>().map_err(h5e("reading"))?.as_str().to_owned()),
        TypeDescriptor::VarLenAscii => Ok(attr.read_scalar::<VarLenAscii>().map_err(h5e("reading"))?.as_str().to_owned()),
        other => Err(format!("datatype {other:?}, expected a variable-length string")),
    }
}

#[cfg(test)]
mod tests {
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
        dist.cells = cell_rows.iter().map(|&r| whole.cells[r]).collect();
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
            dist.cells = cell_rows.iter().map(|&r| whole.cells[r]).collect();
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
        mesh.new_dataset::<i64>().shape([6]).create(MIXED).unwrap().write_raw(&[6i64, 0, 1, 2, 3, 7]).unwrap();
        drop((mesh, file));
        let e = read(&path).unwrap_err().to_string();
        assert!(e.contains("/mesh/mixed") && e.contains("unknown XDMF cell type 7"), "{e}");
        let file = ::hdf5::File::open_rw(&path).unwrap();
        file.group(MESH).unwrap().new_dataset::<i64>().shape([1, 4]).create(TETRAHEDRA).unwrap().write_raw(&[0i64, 1, 2, 3]).unwrap();
        drop(file);
        let e = read(&path).unwrap_err().to_string();
        assert!(e.contains("several cell datasets"), "{e}");
        std::fs::remove_file(&path).unwrap();
    }
}
