//! `history.csv`: one row of numbers per converged step, appended (with a sync) after each
//! step, so a long run's cost per step does not grow with the steps before it. Written with a
//! CSV library, so a column named with a comma or a quote (a group or probe name) is quoted,
//! and every reader sees as many fields per row as the header has. What the file holds so far
//! is marked by its length and fingerprint ([`History::mark`]), which a restart checks before
//! it goes on appending.

use super::{OutputError, werr, write_atomic};
use crate::files::Fnv;
use std::io::Write;
use std::path::{Path, PathBuf};

/// `history.csv`, one row per converged step.
pub struct History {
    path: PathBuf,
    /// The header, until the first row writes it.
    header: String,
    /// Bytes written so far, and their fingerprint.
    bytes: u64,
    hash: Fnv,
}

/// A row of `history.csv` made and not yet written.
pub struct Row {
    text: String,
    /// Whether it is the first, which writes the header too.
    first: bool,
    /// What the file holds once it is written.
    pub mark: Mark,
}

/// How far a history file had got: its length and the fingerprint of those bytes (what a
/// checkpoint keeps of it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Mark {
    pub bytes: u64,
    pub hash: u64,
}

impl History {
    pub fn new(path: &Path, columns: &[String]) -> History {
        History {
            path: path.to_owned(),
            header: csv_line(columns),
            bytes: 0,
            hash: Fnv::default(),
        }
    }

    /// What the file holds so far.
    pub fn mark(&self) -> Mark {
        Mark {
            bytes: self.bytes,
            hash: self.hash.0,
        }
    }

    /// Continue a run's history from `mark`: the file must begin with the bytes marked; rows
    /// after them (a step that was being recorded when the run stopped) are cut off, as that
    /// step is taken again. The error says what is wrong with the file.
    pub fn resume(&mut self, mark: Mark) -> Result<(), String> {
        let text = std::fs::read(&self.path).map_err(|e| format!("cannot read it ({e})"))?;
        let len = text.len() as u64;
        if len < mark.bytes {
            return Err(format!(
                "it holds {len} bytes where the checkpoint counts {}",
                mark.bytes
            ));
        }
        let mut hash = Fnv::default();
        hash.eat(&text[..mark.bytes as usize]);
        if hash.0 != mark.hash {
            return Err("its rows differ from those the checkpoint counts".into());
        }
        if len > mark.bytes {
            std::fs::OpenOptions::new()
                .write(true)
                .open(&self.path)
                .and_then(|f| f.set_len(mark.bytes).and_then(|_| f.sync_data()))
                .map_err(|e| format!("cannot cut it back to its last converged step ({e})"))?;
        }
        self.bytes = mark.bytes;
        self.hash = hash;
        Ok(())
    }

    /// Add a row: the first one with the header, replacing any older file at once; the
    /// others appended.
    pub fn row(&mut self, values: &[f64]) -> Result<(), OutputError> {
        let row = self.make_row(values);
        self.write_row(row)
    }

    /// A row of `values`, made but not yet written, and what the file will hold once it is.
    pub fn make_row(&self, values: &[f64]) -> Row {
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
        let line = csv_line(&row);
        let first = self.bytes == 0;
        let text = if first {
            format!("{}{line}", self.header)
        } else {
            line
        };
        let mut hash = self.hash;
        hash.eat(text.as_bytes());
        let mark = Mark {
            bytes: self.bytes + text.len() as u64,
            hash: hash.0,
        };
        Row { text, first, mark }
    }

    /// Write `row` (made by [`History::make_row`] since the last row was written).
    pub fn write_row(&mut self, row: Row) -> Result<(), OutputError> {
        debug_assert_eq!(row.first, self.bytes == 0, "a row made before the last one");
        if row.first {
            write_atomic(&self.path, row.text.as_bytes())?;
        } else {
            // one write of the whole row
            std::fs::OpenOptions::new()
                .append(true)
                .open(&self.path)
                .and_then(|mut f| f.write_all(row.text.as_bytes()).and_then(|_| f.sync_data()))
                .map_err(|e| werr(&self.path, e))?;
        }
        self.eaten(row.text.as_bytes());
        Ok(())
    }

    fn eaten(&mut self, bytes: &[u8]) {
        self.bytes += bytes.len() as u64;
        self.hash.eat(bytes);
    }
}

/// One CSV record (quoted where needed), with its line end.
pub fn csv_line<S: AsRef<[u8]>>(fields: &[S]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    // writing to memory cannot fail
    w.write_record(fields).expect("in memory");
    String::from_utf8(w.into_inner().expect("in memory")).expect("fields are UTF-8")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_resumed_history_cuts_the_rows_after_its_mark_and_refuses_other_rows() {
        let dir = std::env::temp_dir().join(format!("tmc-history-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("history.csv");
        let mut h = History::new(&path, &["step".into(), "x, y".into()]);
        h.row(&[0.0, 0.5]).unwrap();
        h.row(&[1.0, 0.25]).unwrap();
        let mark = h.mark();
        h.row(&[2.0, 0.125]).unwrap();
        let whole = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            whole,
            "step,\"x, y\"\n0,5.000000000000e-1\n1,2.500000000000e-1\n2,1.250000000000e-1\n"
        );
        // a restart from the mark: the third row goes, and is written again
        let mut again = History::new(&path, &["step".into(), "x, y".into()]);
        again.resume(mark).unwrap();
        again.row(&[2.0, 0.125]).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), whole);
        // a file whose marked rows changed, or that is shorter, is refused
        std::fs::write(&path, whole.replace("0,5.0", "0,6.0")).unwrap();
        let e = History::new(&path, &[]).resume(mark).unwrap_err();
        assert!(e.contains("rows differ"), "{e}");
        std::fs::write(&path, &whole[..10]).unwrap();
        let e = History::new(&path, &[]).resume(mark).unwrap_err();
        assert!(e.contains("holds 10 bytes"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
