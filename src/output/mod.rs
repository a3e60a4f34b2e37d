//! Output: one `.vtu` per converged step and a `.pvd` collection ([`vtu`]), `history.csv`
//! ([`history`]), the cell fields written with each step ([`fields`]) and the probes
//! ([`probes`]). Every file is written to a temporary name and renamed, so a failure never
//! leaves a half-written file.

pub mod fields;
pub mod history;
pub mod probes;
pub mod series;
pub mod vtu;

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
}

pub(crate) fn werr(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Write {
        path: path.to_owned(),
        msg: e.to_string(),
    }
}

/// Write `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let tmp = path.with_extension(format!(
        "{}.part",
        path.extension()
            .map(|e| e.to_string_lossy().into_owned())
            .unwrap_or_default()
    ));
    std::fs::write(&tmp, bytes).map_err(|e| werr(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| werr(path, e))
}

/// Remove stale step files of an earlier run in `dir`.
pub fn clean_dir(dir: &Path) -> Result<(), OutputError> {
    std::fs::create_dir_all(dir).map_err(|e| werr(dir, e))?;
    for entry in std::fs::read_dir(dir).map_err(|e| werr(dir, e))?.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if (name.starts_with("step_") && name.ends_with(".vtu"))
            || name == "history.csv"
            || name == "summary.json"
            || name.ends_with(".pvd")
        {
            std::fs::remove_file(entry.path()).map_err(|e| werr(&entry.path(), e))?;
        }
    }
    Ok(())
}

/// Write a small text file (e.g. a log) atomically.
pub fn write_text(path: &Path, text: &str) -> Result<(), OutputError> {
    let mut buf = Vec::new();
    buf.write_all(text.as_bytes()).map_err(|e| werr(path, e))?;
    write_atomic(path, &buf)
}
