//! A run's output folder: held by one run at a time (a lock file naming its process), with a
//! manifest of the files the run writes there, so that the next run replaces exactly those
//! and nothing else a user keeps in the folder.

use super::{OutputError, werr, write_atomic};
use std::path::{Path, PathBuf};

/// The lock file: the pid of the run that holds the folder.
pub const LOCK: &str = ".tmc.lock";
/// The manifest: one file name per line, every file the last run in this folder wrote.
pub const MANIFEST: &str = ".tmc-manifest";

/// An output folder held by this run; the lock goes when it is dropped.
#[derive(Debug)]
pub struct RunFolder {
    dir: PathBuf,
    /// Files of the previous run, still in place until [`RunFolder::replace_previous`].
    previous: Vec<String>,
    /// Files of this run (after `replace_previous`).
    written: Vec<String>,
    replaced: bool,
    /// The folder did not exist before this run.
    created: bool,
}

impl RunFolder {
    /// Create `dir` if needed and take it; refused while another live process holds it.
    pub fn open(dir: &Path) -> Result<RunFolder, OutputError> {
        let created = !dir.exists();
        std::fs::create_dir_all(dir).map_err(|e| werr(dir, e))?;
        let lock = dir.join(LOCK);
        let me = std::process::id();
        loop {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&lock)
            {
                Ok(mut f) => {
                    use std::io::Write;
                    f.write_all(format!("{me}\n").as_bytes())
                        .and_then(|_| f.sync_all())
                        .map_err(|e| werr(&lock, e))?;
                    break;
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let holder = std::fs::read_to_string(&lock)
                        .ok()
                        .and_then(|t| t.trim().parse::<i32>().ok());
                    match holder {
                        Some(pid) if alive(pid) => {
                            return Err(OutputError::Busy {
                                dir: dir.to_owned(),
                                pid,
                            });
                        }
                        // a lock left by a run that was killed: take it over
                        _ => std::fs::remove_file(&lock).map_err(|e| werr(&lock, e))?,
                    }
                }
                Err(e) => return Err(werr(&lock, e)),
            }
        }
        let previous = std::fs::read_to_string(dir.join(MANIFEST))
            .map(|t| {
                t.lines()
                    .filter(|l| own_name(l))
                    .map(String::from)
                    .collect()
            })
            .unwrap_or_default();
        Ok(RunFolder {
            dir: dir.to_owned(),
            previous,
            written: Vec::new(),
            replaced: false,
            created,
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Remove the previous run's files (those its manifest lists), once this run is known to
    /// start: everything before (case, mesh, model) has been checked.
    pub fn replace_previous(&mut self) -> Result<(), OutputError> {
        for name in std::mem::take(&mut self.previous) {
            let p = self.dir.join(&name);
            match std::fs::remove_file(&p) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(werr(&p, e)),
            }
        }
        self.replaced = true;
        self.save()
    }

    /// Keep the previous run's files: this run continues it (a restart), and its manifest
    /// goes on from the previous one.
    pub fn keep_previous(&mut self) -> Result<(), OutputError> {
        self.written = std::mem::take(&mut self.previous);
        self.replaced = true;
        self.save()
    }

    /// Note that this run writes `name` in the folder (before writing it).
    pub fn record(&mut self, name: &str) -> Result<(), OutputError> {
        debug_assert!(self.replaced, "record after replace_previous");
        if self.written.iter().any(|w| w == name) {
            return Ok(());
        }
        self.written.push(name.to_string());
        self.save()
    }

    fn save(&self) -> Result<(), OutputError> {
        let mut text = self.written.join("\n");
        text.push('\n');
        write_atomic(&self.dir.join(MANIFEST), text.as_bytes())
    }
}

impl Drop for RunFolder {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(self.dir.join(LOCK));
        if self.created && !self.replaced {
            // a run that failed on its input leaves no empty folder behind (only removed if
            // empty)
            let _ = std::fs::remove_dir(&self.dir);
        }
    }
}

/// A plain file name in the folder (a manifest is never trusted with paths).
fn own_name(name: &str) -> bool {
    !name.is_empty()
        && !name.contains('/')
        && !name.contains('\\')
        && name != "."
        && name != ".."
        && name != LOCK
        && name != MANIFEST
}

/// Whether process `pid` exists (a signal-0 probe: EPERM means it exists under another user).
fn alive(pid: i32) -> bool {
    if pid <= 0 {
        return false;
    }
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}
