//! `history.csv`: one row of numbers per converged step, rewritten atomically after each row.
//! Written with a CSV library, so a column named with a comma or a quote (a group or probe
//! name) is quoted, and every reader sees as many fields per row as the header has.

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
            text: csv_line(columns),
        }
    }
    /// Continue a run's history: `text` is the file as it stood (header and rows).
    pub fn resume(&mut self, text: String) {
        self.text = text;
    }

    /// The file's text so far.
    pub fn text(&self) -> &str {
        &self.text
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
        self.text.push_str(&csv_line(&row));
        write_atomic(&self.path, self.text.as_bytes())
    }
    pub fn flush_header(&self) -> Result<(), OutputError> {
        write_atomic(&self.path, self.text.as_bytes())
    }
}

/// One CSV record (quoted where needed), with its line end.
pub fn csv_line<S: AsRef<[u8]>>(fields: &[S]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    // writing to memory cannot fail
    w.write_record(fields).expect("in memory");
    String::from_utf8(w.into_inner().expect("in memory")).expect("fields are UTF-8")
}
