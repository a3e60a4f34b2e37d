//! `history.csv`: one row of numbers per converged step, rewritten atomically after each row.

use super::{OutputError, write_atomic};
use std::path::{Path, PathBuf};

/// `history.csv`, one row per converged step, flushed after each row.
pub struct History {
    path: PathBuf,
    text: String,
}

impl History {
    pub fn new(path: &Path, columns: &[String]) -> History {
        History {
            path: path.to_owned(),
            text: columns.join(",") + "\n",
        }
    }
    pub fn row(&mut self, values: &[f64]) -> Result<(), OutputError> {
        let row: Vec<String> = values
            .iter()
            .map(|&v| {
                if !v.is_finite() {
                    "NaN".to_string() // a field the scene does not simulate
                } else if v == v.trunc() && v.abs() < 1e15 {
                    format!("{}", v as i64)
                } else {
                    format!("{v:.12e}")
                }
            })
            .collect();
        self.text.push_str(&row.join(","));
        self.text.push('\n');
        write_atomic(&self.path, self.text.as_bytes())
    }
    pub fn flush_header(&self) -> Result<(), OutputError> {
        write_atomic(&self.path, self.text.as_bytes())
    }
}
