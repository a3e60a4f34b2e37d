//! Output: one `.vtu` per converged step and a `.pvd` collection ([`vtu`]), `history.csv`
//! ([`history`]), the cell fields written with each step ([`fields`]), the probes
//! ([`probes`]) and what their numbers measure ([`quantity`]). Every file is written to a
//! temporary name and renamed, so a failure never leaves a half-written file.

pub mod contact;
pub mod fields;
pub mod folder;
pub mod history;
pub mod nodal;
pub mod probes;
pub mod quantity;
pub mod series;
pub mod vtu;

pub use folder::RunFolder;
pub use history::History;
pub use series::Series;
pub use vtu::{StepFields, write_pvd, write_vtu};

use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {path}: {msg}")]
    Write { path: PathBuf, msg: String },
    #[error("post-processing failed at step {step}: {msg}")]
    Fields { step: usize, msg: String },
    #[error(
        "{dir} is in use by another tmc run (process {pid}); wait for it, stop it, or write \
         elsewhere with -o"
    )]
    Busy { dir: PathBuf, pid: i32 },
    /// Another rank's error, as that rank said it (a distributed run stops on all ranks).
    #[error("{0}")]
    OtherRank(String),
}

pub(crate) fn werr(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Write {
        path: path.to_owned(),
        msg: e.to_string(),
    }
}

/// Write `bytes` to `path` atomically: to a temporary name beside it, synced to the disk
/// (a full disk fails here, naming the file), then renamed; on failure the temporary file is
/// removed and `path` keeps its old content.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    crate::files::write_atomic(path, bytes).map_err(|e| werr(path, e))
}

/// Write a small text file (e.g. a log) atomically.
pub fn write_text(path: &Path, text: &str) -> Result<(), OutputError> {
    let mut buf = Vec::new();
    buf.write_all(text.as_bytes()).map_err(|e| werr(path, e))?;
    write_atomic(path, &buf)
}
