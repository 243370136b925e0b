//! The crate's typed error. Every failure a user can cause or meet ends up here, with a
//! one-line message naming the offending key, file or phase.

/// Everything that can go wrong, from reading a scene to writing the result.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene or mesh file that does not parse (`file: line:col: message`).
    #[error("{file}: {msg}")]
    Parse {
        /// The scene or mesh file.
        file: String,
        /// What does not parse, with the line and column where known.
        msg: String,
    },
    /// A scene value that parses but is not allowed; `key` is the dotted path.
    #[error("{key}: {msg}")]
    Scene {
        /// The dotted path of the key.
        key: String,
        /// What is wrong with its value.
        msg: String,
    },
    /// A mesh file that is readable but unusable.
    #[error("{file}: {msg}")]
    Mesh {
        /// The mesh file.
        file: String,
        /// What makes it unusable.
        msg: String,
    },
    /// A file that could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// Numerical failure (factorization breakdown, NaN, no convergence), with the reason.
    #[error("{what}: {reason}")]
    Numerical {
        /// What failed.
        what: String,
        /// Why.
        reason: String,
    },
    /// A dual solver that failed; its typed error (`qp::QpError`, with the counters of an
    /// unconverged run) is the source.
    #[error("{what}: {source}")]
    Solver {
        /// The solve that failed, as messages name it.
        what: String,
        /// The solver's typed error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A result file that could not be written or verified.
    #[error("output {path}: {msg}")]
    Output {
        /// The file.
        path: String,
        /// What went wrong.
        msg: String,
    },
    /// A run refused before it allocates because it would not fit in memory (`what`: the scene
    /// key that sets its size), or an allocation that failed (`what`: the array).
    #[error("{what}: {msg}")]
    Memory {
        /// The scene key or the array.
        what: String,
        /// What does not fit.
        msg: String,
    },
    /// A launcher (`mpirun`, `srun`, a container's exec) that did not run a study's case, with
    /// its cause.
    #[error("{what}: {msg}")]
    Launch {
        /// The case.
        what: String,
        /// The launcher's failure.
        msg: String,
    },
    /// An error raised on another MPI rank, forwarded so that every rank stops with it.
    #[error("{0}")]
    Remote(String),
}

/// The crate's result, with [`Error`] by default.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An [`Error::Scene`] on `key`.
    pub fn scene(key: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Scene { key: key.into(), msg: msg.into() }
    }
    /// An [`Error::Mesh`] in `file`.
    pub fn mesh(file: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Mesh { file: file.into(), msg: msg.into() }
    }
    /// An [`Error::Io`] on `path`.
    pub fn io(path: impl Into<String>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }
    /// An [`Error::Numerical`] of `what`.
    pub fn numerical(what: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::Numerical { what: what.into(), reason: reason.into() }
    }
    /// An [`Error::Solver`] of `what`, `source` its cause.
    pub fn solver(what: impl Into<String>, source: impl std::error::Error + Send + Sync + 'static) -> Self {
        Error::Solver { what: what.into(), source: Box::new(source) }
    }
    /// An [`Error::Memory`] for `what`.
    pub fn memory(what: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Memory { what: what.into(), msg: msg.into() }
    }
    /// An allocation of `bytes` for `what` that failed.
    pub fn alloc(what: impl Into<String>, bytes: usize) -> Self {
        Error::Memory { what: what.into(), msg: format!("could not allocate {} (out of memory)", human_bytes(bytes as f64)) }
    }
    /// An [`Error::Launch`] of `what`.
    pub fn launch(what: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Launch { what: what.into(), msg: msg.into() }
    }
    /// An [`Error::Output`] on `path`.
    pub fn output(path: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Output { path: path.into(), msg: msg.into() }
    }

    /// The section of `docs/troubleshooting.md` that says what to do (none for an error
    /// forwarded from another rank: only its text travels).
    pub fn docs_section(&self) -> Option<&'static str> {
        Some(match self {
            Error::Parse { .. } | Error::Scene { .. } => "scene-errors",
            Error::Mesh { .. } => "mesh-errors",
            Error::Io { .. } => "files-that-cannot-be-read",
            Error::Numerical { .. } | Error::Solver { .. } => "solver-failures",
            Error::Output { .. } => "writing-results",
            Error::Memory { .. } => "too-large-for-the-machine",
            Error::Launch { .. } => "running-under-mpi",
            Error::Remote(_) => return None,
        })
    }

    /// The one line the command prints: `error: <message> (see docs/troubleshooting.md#…)`.
    pub fn line(&self) -> String {
        match self.docs_section() {
            Some(s) => format!("error: {self} (see docs/troubleshooting.md#{s})"),
            None => format!("error: {self}"),
        }
    }
}

/// A byte count for messages: `61.2 GB`, `512 MB`, `3.4 kB`, `12 B` (decimal units).
pub fn human_bytes(b: f64) -> String {
    let (v, unit) = [(1e12, "TB"), (1e9, "GB"), (1e6, "MB"), (1e3, "kB")].into_iter().find(|&(u, _)| b >= u).map_or((b, "B"), |(u, n)| (b / u, n));
    if unit == "B" || v >= 100.0 {
        format!("{v:.0} {unit}")
    } else {
        format!("{v:.1} {unit}")
    }
}
