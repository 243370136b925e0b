//! The run's temporary result files (`<name>.<token>.tmp`), and what happens to them on SIGINT or
//! SIGTERM. Owns the process-wide list of the temporary files that exist (writers [`track`]
//! one before creating it and [`untrack`] it once renamed or removed) and the signal thread
//! ([`remove_on_signal`]): signal-hook's handler only wakes that thread (async-signal-safe);
//! the thread, an ordinary one, removes every tracked file, says so in one line (rank 0, where
//! there was one, or that the set was already complete) and ends the process with 128 + the
//! signal's number. Renames into place run under [`hold`], so a signal never interleaves with
//! them. Temporary names carry a per-run [`token`].

use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// The run's files as a signal finds them.
pub struct Files {
    /// Temporary files that exist (or are being written).
    pub temps: Vec<PathBuf>,
    /// Result files renamed into place: the set is complete.
    pub written: Vec<PathBuf>,
    /// The last checkpoint written: (its step, the path's steps, the scene, the file).
    pub checkpoint: Option<(usize, usize, PathBuf, PathBuf)>,
    /// The command that repeats this run up to `--resume` (its scene, `--set`s, `--out`),
    /// as [`note_resume_command`] gave it; empty: `tresca-feti solve SCENE`.
    pub resume: Vec<String>,
}

static TRACKED: Mutex<Files> = Mutex::new(Files { temps: Vec::new(), written: Vec::new(), checkpoint: None, resume: Vec::new() });

/// The list, even if a thread panicked while holding it (a list of paths stays valid).
fn list() -> MutexGuard<'static, Files> {
    TRACKED.lock().unwrap_or_else(|e| e.into_inner())
}

/// Records `path` as a temporary file to remove if a signal ends the run.
pub fn track(path: &Path) {
    list().temps.push(path.to_path_buf());
}

/// Forgets `path` (renamed into place, or removed).
pub fn untrack(path: &Path) {
    list().untrack(path);
}

impl Files {
    /// Forgets temporary file `path` (for a caller holding the list, [`hold`]).
    pub fn untrack(&mut self, path: &Path) {
        if let Some(i) = self.temps.iter().position(|p| p == path) {
            self.temps.swap_remove(i);
        }
    }
}

/// Records that the checkpoint `file` of `scene` now holds step `step` of `steps`.
pub fn note_checkpoint(step: usize, steps: usize, scene: &Path, file: &Path) {
    list().checkpoint = Some((step, steps, scene.to_path_buf(), file.to_path_buf()));
}

/// Records the words of the command that resumes this run (`tresca-feti solve SCENE --set …
/// --out … --checkpoint`, without `--resume`): a resumed run must repeat the `--set`s (the
/// checkpoint holds the scene's digest after them) and `--out` (or it writes elsewhere).
pub fn note_resume_command(words: Vec<String>) {
    list().resume = words;
}

/// The one line that says how to resume from checkpoint `file` (shell-quoted).
fn resume_line(words: &[String], scene: &Path, file: &Path) -> String {
    let mut w: Vec<String> = if words.is_empty() { vec!["tresca-feti".into(), "solve".into(), scene.display().to_string()] } else { words.to_vec() };
    w.extend(["--resume".into(), file.display().to_string()]);
    shell_words::join(w)
}

/// Holds the list for the caller's renames: the signal thread waits until they are done.
pub fn hold() -> MutexGuard<'static, Files> {
    list()
}

/// A unique suffix for one run's temporary files: this process's id and the clock, so that
/// runs writing the same results at once never share a temporary name.
pub fn token() -> String {
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    format!("{}-{:x}", std::process::id(), nanos as u64)
}

/// Starts the thread that, on SIGINT, SIGTERM or SIGUSR1 (Slurm's `--signal`), removes the tracked files and ends the
/// process (exit status 128 + signal number); `loud`: print the one line (rank 0 only): the
/// temporary files removed (no result written), or, once the set was renamed into place, that
/// it is complete.
pub fn remove_on_signal(loud: bool) -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM, SIGUSR1};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGUSR1])?;
    std::thread::Builder::new().name("signals".into()).spawn(move || {
        if let Some(sig) = signals.forever().next() {
            let files = list();
            // every rank removes the set's files (another rank may have been first)
            for f in &files.temps {
                let _ = std::fs::remove_file(f);
            }
            let name = match sig {
                SIGINT => "SIGINT",
                SIGUSR1 => "SIGUSR1",
                _ => "SIGTERM",
            };
            // nothing staged nor written: a rank that mpirun ends after another failed (its
            // error is said)
            if let (true, true, Some((k, n, scene, file))) = (loud, files.written.is_empty(), &files.checkpoint) {
                // the checkpoint's renames run under the list: the last one is whole
                eprintln!("stopped by {name} after step {k} of {n}; resume with: {}", resume_line(&files.resume, scene, file));
            } else if loud && !files.temps.is_empty() {
                eprintln!("error: interrupted by {name}; removed {} temporary file(s), no result written", files.temps.len());
            } else if loud && !files.written.is_empty() {
                let names: Vec<String> = files.written.iter().map(|p| p.display().to_string()).collect();
                eprintln!("error: interrupted by {name} after the results were written (complete): {}", names.join(", "));
            }
            // SAFETY: _exit ends the process at once, holding the list so no rename follows;
            // neither MPI nor HDF5 (mid-write on the main thread) is finalized or flushed.
            unsafe { libc::_exit(128 + sig) }
        }
    })?;
    Ok(())
}
