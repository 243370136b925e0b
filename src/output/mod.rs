//! Results on disk: one HDF5 file with an XDMF sidecar for ParaView, and a JSON report.
//!
//! Owns the [`OutputData`] description (mesh + named node/cell fields + string attributes, and
//! the [`Step`]s of a load path) that the pipeline fills, and the writers. A result set is
//! written under temporary names of its own ([`stage`]: `<name>.<pid>-<clock>.tmp`, tracked by
//! [`tmpfiles`] for signals), read back and completed there, and renamed into place only when
//! all of it succeeded ([`Staged::commit`]), under an exclusive lock on the results' folder,
//! so that of two runs writing the same set the later commit replaces the whole earlier set; a
//! rename that fails takes back the ones before it, so a failed run leaves neither a result
//! file nor a temporary one behind.

pub(crate) mod guard;
pub mod hdf5;
pub mod tmpfiles;
pub(crate) mod xdmf;

/// Where a field lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Center {
    /// One row per node.
    Node,
    /// One row per cell.
    Cell,
}

/// Values of a field, row-major `len × ncomp`.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// Floating-point values.
    F64(Vec<f64>),
    /// Integer values (e.g. the contact status).
    I32(Vec<i32>),
}

/// A named field on the mesh: `/fields/<name>` in the HDF5 file.
#[derive(Clone, Debug)]
pub struct Field {
    /// Name of the field: `/fields/<name>` in the HDF5 file.
    pub name: String,
    /// Where it lives: on nodes or cells.
    pub center: Center,
    /// Components per node/cell (1 = scalar, 3 = vector).
    pub ncomp: usize,
    /// The values, row-major `len × ncomp`.
    pub values: Values,
}

/// Everything one result file holds.
#[derive(Clone, Debug, Default)]
pub struct OutputData {
    /// `/mesh/coordinates`, nnodes × 3 (this rank's rows only where `mesh_rows` is set).
    pub coordinates: Vec<[f64; 3]>,
    /// The cells (any mix of [`crate::mesh::CellKind`]s), our (Gmsh's) node order, global node
    /// numbers (this rank's rows only where `mesh_rows` is set); the HDF5 file stores them in
    /// XDMF's node order ([`hdf5`]'s table).
    pub cells: Vec<crate::mesh::Cell>,
    /// A distributed mesh: the sizes of the whole mesh and the rows this rank holds of it.
    /// None: `coordinates` and `cells` are the whole mesh (on every rank).
    pub mesh_rows: Option<MeshRows>,
    /// The fields of the final state.
    pub fields: Vec<Field>,
    /// String attributes on the root group (resolved scene, versions, timings, report).
    pub attributes: Vec<(String, String)>,
    /// Distributed fields: field name → the rows (nodes or cells) this rank holds, whose
    /// values the field's `values` are (in this order). A field not listed holds every row
    /// (replicated). Either way, under MPI each rank writes one contiguous block of the rows.
    pub rows: std::collections::BTreeMap<String, Vec<usize>>,
    /// The states of a quasi-static load path, in order: `/steps/0001`, `/steps/0002`, … in
    /// the HDF5 file, a temporal collection in the XDMF sidecar. Empty = one load state: the
    /// files are exactly as without load paths. `fields` stays the final state either way.
    pub steps: Vec<Step>,
}

/// The rows of the mesh one rank holds ([`OutputData::mesh_rows`]): every node and cell held
/// by some rank, as for a distributed field.
#[derive(Clone, Debug, Default)]
pub struct MeshRows {
    /// Nodes of the whole mesh.
    pub nodes: usize,
    /// Cells of the whole mesh.
    pub cells: usize,
    /// The nodes whose coordinates this rank holds, in the order of `coordinates`.
    pub node_rows: Vec<usize>,
    /// The cells this rank holds, in the order of `cells`.
    pub cell_rows: Vec<usize>,
}

impl OutputData {
    /// Nodes of the whole mesh.
    pub fn nnodes(&self) -> usize {
        self.mesh_rows.as_ref().map_or(self.coordinates.len(), |m| m.nodes)
    }

    /// Cells of the whole mesh.
    pub fn ncells(&self) -> usize {
        self.mesh_rows.as_ref().map_or(self.cells.len(), |m| m.cells)
    }
}

/// One state of a load path: `/steps/<index as 4 digits, from 1>/<field name>` in the HDF5 file,
/// attribute `time` (f64) on that group.
#[derive(Clone, Debug, Default)]
pub struct Step {
    /// Pseudo-time of this state (the same on every rank); finite, and strictly increasing
    /// along [`OutputData::steps`].
    pub time: f64,
    /// The fields of this state.
    pub fields: Vec<Field>,
    /// Same meaning as OutputData::rows, for this step's fields.
    pub rows: std::collections::BTreeMap<String, Vec<usize>>,
}

use std::path::{Path, PathBuf};

use crate::comm::Comm;
use crate::error::{Error, Result};

/// The name of step `index` (from 0) under `/steps`: `0001`, `0002`, … (wider past 9999).
fn step_name(index: usize) -> String {
    format!("{:04}", index + 1)
}

/// Step times must be finite (XDMF writes them as text) and strictly increasing (ParaView
/// plays the steps in time order and merges equal times).
fn check_step_times(steps: &[Step]) -> std::result::Result<(), String> {
    for (i, step) in steps.iter().enumerate() {
        if !step.time.is_finite() {
            return Err(format!("step {}: time {} is not finite", step_name(i), step.time));
        }
        if i > 0 && step.time <= steps[i - 1].time {
            return Err(format!("step {}: time {} is not after step {}'s {}", step_name(i), step.time, step_name(i - 1), steps[i - 1].time));
        }
    }
    Ok(())
}

/// Writes `bytes` to `path` through a temporary sibling and a rename, creating the folder: a
/// failure leaves no half-written file behind.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let io = |e| crate::error::Error::io(path.display().to_string(), e);
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    let tmp = staging(path, &tmpfiles::token());
    tmpfiles::track(&tmp);
    let written = std::fs::write(&tmp, bytes).and_then(|()| {
        let mut held = tmpfiles::hold();
        let _lock = FolderLock::take(path)?;
        std::fs::rename(&tmp, path)?;
        held.untrack(&tmp);
        Ok(())
    });
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    tmpfiles::untrack(&tmp);
    written.map_err(io)
}

/// `<path with extension ext>` beside `h5`.
pub fn sibling(h5: &Path, ext: &str) -> PathBuf {
    h5.with_extension(ext)
}

/// `<path>.<token>.tmp`: where `path` is written before its rename.
pub(crate) fn staging(path: &Path, token: &str) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(format!(".{token}.tmp"));
    PathBuf::from(s)
}

/// The token of one run's temporary names, the same on every rank (rank 0's [`tmpfiles::token`]).
fn run_token<C: Comm>(comm: &C) -> String {
    let mut buf = if comm.is_root() { tmpfiles::token().into_bytes() } else { Vec::new() };
    comm.broadcast_bytes(0, &mut buf);
    String::from_utf8_lossy(&buf).into_owned()
}

/// An exclusive `flock` on the folder of a result, held while a set is renamed into place:
/// runs writing into one folder commit one after the other. Released when dropped (closed).
struct FolderLock {
    /// The open folder; closing it releases the lock.
    _folder: std::fs::File,
}

impl FolderLock {
    fn take(target: &Path) -> std::io::Result<FolderLock> {
        use std::os::fd::AsRawFd;
        let dir = target.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let f = std::fs::File::open(dir)?;
        loop {
            // SAFETY: flock on a descriptor this function owns
            if unsafe { libc::flock(f.as_raw_fd(), libc::LOCK_EX) } == 0 {
                return Ok(FolderLock { _folder: f });
            }
            let e = std::io::Error::last_os_error();
            if e.kind() != std::io::ErrorKind::Interrupted {
                return Err(e);
            }
        }
    }
}

/// A result set under its temporary names, until [`Staged::commit`] renames it into place;
/// dropped uncommitted, its temporary files are removed (rank 0).
pub struct Staged {
    /// Final names: the HDF5 file, then the XDMF and JSON sidecars where written.
    targets: Vec<PathBuf>,
    /// `<target>.tmp`, in the same order.
    temps: Vec<PathBuf>,
    /// Where the JSON report is in `targets`, if written.
    json: Option<usize>,
    root: bool,
    committed: bool,
}

impl Staged {
    /// The HDF5 file under its temporary name (to read back before the commit).
    pub fn h5_temp(&self) -> &Path {
        &self.temps[0]
    }

    /// Replaces the staged JSON report (rank 0): the report once the phases it times are
    /// over. Nothing to do when the set has none.
    pub fn rewrite_report<C: Comm>(&self, comm: &C, report: &serde_json::Value) -> Result<()> {
        comm.agree(match self.json {
            Some(i) if self.root => write_json(&self.temps[i], &self.targets[i], report),
            _ => Ok(()),
        })
    }

    /// Renames every file of the set into place (rank 0, agreed); if one rename fails, the
    /// files of the set already renamed are removed too: no part of the set remains. Returns
    /// the final paths.
    pub fn commit<C: Comm>(mut self, comm: &C) -> Result<Vec<PathBuf>> {
        let renamed = comm.agree(if self.root { rename_all(&self.temps, &self.targets) } else { Ok(()) });
        self.committed = renamed.is_ok();
        if self.committed {
            // every rank's list: a signal now removes nothing of the set
            for t in &self.temps {
                tmpfiles::untrack(t);
            }
        }
        renamed.map(|()| self.targets.clone())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if self.committed {
            return;
        }
        for t in &self.temps {
            if self.root {
                let _ = std::fs::remove_file(t);
            }
            tmpfiles::untrack(t);
        }
    }
}

/// Renames each of `temps` to its `targets`, under [`tmpfiles::hold`] and the [`FolderLock`] of
/// the first target; on a failure removes the targets renamed so far and the temporary files
/// left. Once all are renamed, the targets are the signal thread's written set.
fn rename_all(temps: &[PathBuf], targets: &[PathBuf]) -> Result<()> {
    let mut held = tmpfiles::hold();
    let _lock = match targets.first().map(|p| FolderLock::take(p).map_err(|e| Error::io(p.display().to_string(), e))) {
        Some(Err(e)) => {
            for left in temps {
                let _ = std::fs::remove_file(left);
            }
            return Err(e);
        }
        lock => lock,
    };
    for (i, (t, p)) in temps.iter().zip(targets).enumerate() {
        if let Err(e) = std::fs::rename(t, p) {
            for done in &targets[..i] {
                let _ = std::fs::remove_file(done);
            }
            for left in &temps[i..] {
                let _ = std::fs::remove_file(left);
            }
            return Err(Error::io(p.display().to_string(), e));
        }
    }
    for t in temps {
        held.untrack(t);
    }
    held.written.extend(targets.iter().cloned());
    Ok(())
}

/// Writes the HDF5 file (all ranks together, [`hdf5::write_collective`]), the XDMF sidecar (if
/// `xdmf`) and the JSON report (if given; both by rank 0), each under `<name>.tmp`, and
/// renames them to their final names when all succeeded on every rank ([`stage`], then
/// [`Staged::commit`]). On failure no file of the set remains and every rank returns the
/// error. Returns the final paths.
pub fn write_all<C: Comm>(comm: &C, h5: &Path, data: &OutputData, xdmf: bool, report: Option<&serde_json::Value>) -> Result<Vec<PathBuf>> {
    stage(comm, h5, data, xdmf, report)?.commit(comm)
}

/// The writing half of [`write_all`]: the set under its temporary names, nothing renamed.
pub fn stage<C: Comm>(comm: &C, h5: &Path, data: &OutputData, xdmf: bool, report: Option<&serde_json::Value>) -> Result<Staged> {
    let dir = comm.agree(match h5.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) if comm.is_root() => std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display().to_string(), e)),
        _ => Ok(()),
    });
    dir?;
    let mut targets = vec![h5.to_path_buf()];
    if xdmf {
        targets.push(sibling(h5, "xdmf"));
    }
    let json = report.map(|_| {
        targets.push(sibling(h5, "json"));
        targets.len() - 1
    });
    let token = run_token(comm);
    let temps: Vec<PathBuf> = targets.iter().map(|p| staging(p, &token)).collect();
    for t in &temps {
        tmpfiles::track(t);
    }
    let staged = Staged { targets, temps, json, root: comm.is_root(), committed: false };
    comm.agree(hdf5::write_collective(comm, staged.h5_temp(), data))?;
    // the layout of the cells over all ranks (collective), for rank 0's XDMF topology
    let cells = comm.agree(hdf5::cell_layout(comm, data))?;
    comm.agree(if comm.is_root() { write_sidecars(&staged, h5, data, cells, xdmf, report) } else { Ok(()) })?;
    Ok(staged)
}

/// The JSON text of `report` into `temp` (`shown` names the result in messages).
fn write_json(temp: &Path, shown: &Path, report: &serde_json::Value) -> Result<()> {
    let text = serde_json::to_string_pretty(report).map_err(|e| Error::output(shown.display().to_string(), e.to_string()))?;
    std::fs::write(temp, text + "\n").map_err(|e| Error::io(temp.display().to_string(), e))
}

/// Rank 0's part of [`stage`]: the sidecars under their temporary names.
fn write_sidecars(staged: &Staged, h5: &Path, data: &OutputData, cells: hdf5::CellLayout, xdmf: bool, report: Option<&serde_json::Value>) -> Result<()> {
    if xdmf {
        let name = h5.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        xdmf::write(&staged.temps[1], &name, data, cells)?;
    }
    if let (Some(r), Some(i)) = (report, staged.json) {
        write_json(&staged.temps[i], &staged.targets[i], r)?;
    }
    Ok(())
}
