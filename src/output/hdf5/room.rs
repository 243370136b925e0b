//! The file system's room for the file: the estimate of its size, the refusal to start a write
//! that cannot fit ([`check_room`]), the room held for HDF5's metadata until the close
//! ([`Reserve`]), and the check after a write that reported success ([`whole_on_disk`]).

use std::path::{Path, PathBuf};

use super::layout::CellLayout;
use super::mesh_len;
#[cfg(doc)]
use super::write::write_file;
use crate::error::{Error, Result};
use crate::output::{Field, OutputData};

/// Refuses, before the file is created, to write `data` where the file system lacks room for
/// it: a disk that fills up in the middle of a collective write can leave the ranks' HDF5
/// metadata apart, and closing the file then waits forever (see [`write_file`]).
/// `TRESCA_FETI_SPACE_CHECK=off` skips the check (to test the failure in the middle).
pub(super) fn check_room(path: &Path, data: &OutputData) -> Result<()> {
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
pub(super) fn metadata_bytes(data: &OutputData) -> u64 {
    let attrs: u64 = data.attributes.iter().map(|(k, v)| (k.len() + v.len()) as u64).sum();
    let objects = 4 + data.fields.len() + data.attributes.len() + data.steps.iter().map(|s| 1 + s.fields.len()).sum::<usize>();
    attrs + 4096 * objects as u64 + 65536
}

/// Room held on the file's file system for HDF5's metadata until the file closes (rank 0's
/// `<file>.reserve`, allocated before the file is created): HDF5 writes most of its metadata
/// while closing, and a disk full by then fails that write on some ranks only, which leaves
/// the ranks apart inside H5Fclose (a hang). Given back just before the close.
pub(super) struct Reserve(pub(super) Option<PathBuf>);

impl Reserve {
    /// Allocates `bytes` beside `path` (rank 0); fails with the OS's ENOSPC text when there
    /// is no room even for that.
    pub(super) fn hold(path: &Path, bytes: u64) -> Result<Reserve> {
        let mut name = path.as_os_str().to_owned();
        name.push(".reserve");
        let r = PathBuf::from(name);
        crate::output::tmpfiles::track(&r);
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
    pub(super) fn release(&mut self) {
        if let Some(r) = self.0.take() {
            let _ = std::fs::remove_file(&r);
            crate::output::tmpfiles::untrack(&r);
        }
    }
}

impl Drop for Reserve {
    fn drop(&mut self) {
        self.release();
    }
}

/// Bytes an unprivileged writer may still use on the file system holding `dir` (statvfs).
pub(super) fn free_bytes(dir: &Path) -> Option<u64> {
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

/// After a write that reported success: the file must hold at least its datasets' bytes. Open
/// MPI's MPI-IO (ompio) prints "No space left on device" for a short collective write and
/// still returns success, leaving holes; a file allocated short of its values on a file system
/// with less room left than the shortfall is that (a compressing file system with room is not).
pub(super) fn whole_on_disk(path: &Path, data: &OutputData) -> Result<()> {
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
