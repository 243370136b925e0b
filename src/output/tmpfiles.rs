//! The run's temporary result files (`<name>.tmp`), and what happens to them on SIGINT or
//! SIGTERM. Owns the process-wide list of the temporary files that exist (writers [`track`]
//! one before creating it and [`untrack`] it once renamed or removed) and the signal thread
//! ([`remove_on_signal`]): signal-hook's handler only wakes that thread (async-signal-safe);
//! the thread, an ordinary one, removes every tracked file, says so in one line (rank 0, where
//! there was one) and ends the process with 128 + the signal's number. Renames into place run
//! under [`hold`], so a signal never interleaves with them.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

static TRACKED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The list, even if a thread panicked while holding it (a list of paths stays valid).
fn list() -> MutexGuard<'static, Vec<PathBuf>> {
    TRACKED.lock().unwrap_or_else(|e| e.into_inner())
}

/// Records `path` as a temporary file to remove if a signal ends the run.
pub fn track(path: &Path) {
    list().push(path.to_path_buf());
}

/// Forgets `path` (renamed into place, or removed).
pub fn untrack(path: &Path) {
    let mut l = list();
    if let Some(i) = l.iter().position(|p| p == path) {
        l.swap_remove(i);
    }
}

/// Holds the list for the caller's renames: the signal thread waits until they are done.
pub fn hold() -> MutexGuard<'static, Vec<PathBuf>> {
    list()
}

/// Starts the thread that, on SIGINT or SIGTERM, removes the tracked files and ends the
/// process (exit status 128 + signal number); `loud`: print the one line (rank 0 only).
pub fn remove_on_signal(loud: bool) -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
    std::thread::Builder::new().name("signals".into()).spawn(move || {
        if let Some(sig) = signals.forever().next() {
            let files = list();
            for f in files.iter() {
                let _ = std::fs::remove_file(f);
            }
            // nothing removed: a rank that mpirun ends after another failed (its error is said)
            if loud && !files.is_empty() {
                let name = if sig == SIGINT { "SIGINT" } else { "SIGTERM" };
                eprintln!("error: interrupted by {name}; removed {} temporary file(s)", files.len());
            }
            // SAFETY: _exit ends the process at once, holding the list so no rename follows;
            // neither MPI nor HDF5 (mid-write on the main thread) is finalized or flushed.
            unsafe { libc::_exit(128 + sig) }
        }
    })?;
    Ok(())
}
