//! Results on disk: one HDF5 file with an XDMF sidecar for ParaView, and a JSON report.
//!
//! Owns the [`OutputData`] description (mesh + named node/cell fields + string attributes, and
//! the [`Step`]s of a load path) that the pipeline fills, and the writers. Files are written
//! under a temporary name and renamed only when everything succeeded, so a failed run leaves
//! no result file behind.

pub mod guard;
pub mod hdf5;
pub mod xdmf;

/// Where a field lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Center {
    Node,
    Cell,
}

/// Values of a field, row-major `len × ncomp`.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    F64(Vec<f64>),
    I32(Vec<i32>),
}

/// A named field on the mesh: `/fields/<name>` in the HDF5 file.
#[derive(Clone, Debug)]
pub struct Field {
    pub name: String,
    pub center: Center,
    /// Components per node/cell (1 = scalar, 3 = vector).
    pub ncomp: usize,
    pub values: Values,
}

/// Everything one result file holds.
#[derive(Clone, Debug, Default)]
pub struct OutputData {
    /// `/mesh/coordinates`, nnodes × 3 (this rank's rows only where `mesh_rows` is set).
    pub coordinates: Vec<[f64; 3]>,
    /// `/mesh/hexahedra`, nelems × 8, VTK/XDMF node order, global node numbers (this rank's
    /// rows only where `mesh_rows` is set).
    pub hexahedra: Vec<[usize; 8]>,
    /// A distributed mesh: the sizes of the whole mesh and the rows this rank holds of it.
    /// None: `coordinates` and `hexahedra` are the whole mesh (on every rank).
    pub mesh_rows: Option<MeshRows>,
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
    pub nodes: usize,
    pub cells: usize,
    /// The nodes whose coordinates this rank holds, in the order of `coordinates`.
    pub node_rows: Vec<usize>,
    /// The cells whose hexahedra this rank holds, in the order of `hexahedra`.
    pub cell_rows: Vec<usize>,
}

impl OutputData {
    /// Nodes of the whole mesh.
    pub fn nnodes(&self) -> usize {
        self.mesh_rows.as_ref().map_or(self.coordinates.len(), |m| m.nodes)
    }

    /// Cells of the whole mesh.
    pub fn ncells(&self) -> usize {
        self.mesh_rows.as_ref().map_or(self.hexahedra.len(), |m| m.cells)
    }
}

/// One state of a load path: `/steps/<index as 4 digits, from 1>/<field name>` in the HDF5 file,
/// attribute `time` (f64) on that group.
#[derive(Clone, Debug, Default)]
pub struct Step {
    /// Pseudo-time of this state (the same on every rank); finite, and strictly increasing
    /// along [`OutputData::steps`].
    pub time: f64,
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
            return Err(format!(
                "step {}: time {} is not after step {}'s {}",
                step_name(i),
                step.time,
                step_name(i - 1),
                steps[i - 1].time
            ));
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
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let written = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written.map_err(io)
}

/// `<path with extension ext>` beside `h5`.
pub fn sibling(h5: &Path, ext: &str) -> PathBuf {
    h5.with_extension(ext)
}

fn tmp(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".tmp");
    PathBuf::from(s)
}

/// Writes the HDF5 file (all ranks together, [`hdf5::write_collective`]), the XDMF sidecar (if
/// `xdmf`) and the JSON report (if given; both by rank 0), each first under `<name>.tmp`; only
/// when all succeeded on every rank are they renamed to their final names. On failure the
/// temporary files are removed and every rank returns the error. Returns the final paths.
pub fn write_all<C: Comm>(comm: &C, h5: &Path, data: &OutputData, xdmf: bool, report: Option<&serde_json::Value>) -> Result<Vec<PathBuf>> {
    let dir = comm.agree(match h5.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) if comm.is_root() => std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display().to_string(), e)),
        _ => Ok(()),
    });
    dir?;
    let mut targets = vec![h5.to_path_buf()];
    if xdmf {
        targets.push(sibling(h5, "xdmf"));
    }
    if report.is_some() {
        targets.push(sibling(h5, "json"));
    }
    let temps: Vec<PathBuf> = targets.iter().map(|p| tmp(p)).collect();
    let written = comm.agree(hdf5::write_collective(comm, &temps[0], data));
    let result = written.and_then(|()| {
        comm.agree(if comm.is_root() { finish(h5, data, xdmf, report, &targets, &temps) } else { Ok(()) })
    });
    if result.is_err() && comm.is_root() {
        for t in &temps {
            let _ = std::fs::remove_file(t);
        }
    }
    result.map(|_| targets)
}

/// Replaces the JSON report beside `h5` (rank 0; written to a temporary file, then renamed):
/// the report once the `output` phase it times is over.
pub fn rewrite_report<C: Comm>(comm: &C, h5: &Path, report: &serde_json::Value) -> Result<()> {
    comm.agree(if comm.is_root() {
        let (path, temp) = (sibling(h5, "json"), tmp(&sibling(h5, "json")));
        serde_json::to_string_pretty(report)
            .map_err(|e| Error::output(path.display().to_string(), e.to_string()))
            .and_then(|text| std::fs::write(&temp, text + "\n").map_err(|e| Error::io(temp.display().to_string(), e)))
            .and_then(|()| std::fs::rename(&temp, &path).map_err(|e| Error::io(path.display().to_string(), e)))
    } else {
        Ok(())
    })
}

/// Rank 0's part of [`write_all`]: the sidecars and the renames.
fn finish(h5: &Path, data: &OutputData, xdmf: bool, report: Option<&serde_json::Value>, targets: &[PathBuf], temps: &[PathBuf]) -> Result<()> {
    let mut i = 1;
    if xdmf {
        let name = h5.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        xdmf::write(&temps[i], &name, data)?;
        i += 1;
    }
    if let Some(r) = report {
        let text = serde_json::to_string_pretty(r).map_err(|e| Error::output(targets[i].display().to_string(), e.to_string()))?;
        std::fs::write(&temps[i], text + "\n").map_err(|e| Error::io(temps[i].display().to_string(), e))?;
    }
    for (t, p) in temps.iter().zip(targets) {
        std::fs::rename(t, p).map_err(|e| Error::io(p.display().to_string(), e))?;
    }
    Ok(())
}
