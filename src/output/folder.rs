//! A run's output folder: held by one run at a time (a lock file naming its process), with a
//! manifest of the files the run writes there, so that the next run replaces exactly those
//! and nothing else a user keeps in the folder.
//!
//! Replacing is a transaction: the previous run's files are moved aside (into [`HELD`]), not
//! deleted, until the new run has taken its first step ([`RunFolder::settle`]). A run that
//! fails before (its engine refuses an option, a write fails, it is killed) puts them back:
//! when it drops the folder, or, if it was killed, when the next run opens it.

use super::{OutputError, werr, write_atomic};
use std::path::{Path, PathBuf};

/// The lock file: the pid of the run that holds the folder.
pub const LOCK: &str = ".tmc.lock";
/// The manifest: one file name per line, every file the last run in this folder wrote.
pub const MANIFEST: &str = ".tmc-manifest";
/// Where the previous run's files wait (with its manifest) until the new run settles.
pub const HELD: &str = ".tmc-previous";
/// A settled run's [`HELD`] folder on its way out (renamed first, so a kill while it is being
/// removed never leaves a half-removed previous run that looks like one to put back).
const DISCARDED: &str = ".tmc-discarded";

/// An output folder held by this run; the lock goes when it is dropped.
#[derive(Debug)]
pub struct RunFolder {
    dir: PathBuf,
    /// Files of the previous run, still in place until [`RunFolder::replace_previous`].
    previous: Vec<String>,
    /// Files of this run (after `replace_previous`).
    written: Vec<String>,
    replaced: bool,
    /// The previous run's files are in [`HELD`], to go when this run settles or to come back
    /// if it fails first.
    held: bool,
    /// The folder did not exist before this run.
    created: bool,
    /// [`HELD`] holds files of a previous run (not only its manifest).
    held_results: bool,
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
        // a run killed before it settled: its previous run comes back
        if dir.join(HELD).is_dir() {
            put_back(dir, &read_manifest(dir))?;
        }
        remove_discarded(dir)?;
        Ok(RunFolder {
            dir: dir.to_owned(),
            previous: read_manifest(dir),
            written: Vec::new(),
            replaced: false,
            held: false,
            created,
            held_results: false,
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Move the previous run's files (those its manifest lists) aside, once this run is known
    /// to start: everything before (case, mesh, model) has been checked. They go for good when
    /// this run settles, and come back if it fails before.
    pub fn replace_previous(&mut self) -> Result<(), OutputError> {
        let held = self.dir.join(HELD);
        std::fs::create_dir(&held).map_err(|e| werr(&held, e))?;
        self.held = true;
        self.replaced = true;
        for name in std::mem::take(&mut self.previous)
            .iter()
            .map(String::as_str)
            .chain([MANIFEST])
        {
            let p = self.dir.join(name);
            match std::fs::rename(&p, held.join(name)) {
                Ok(()) => self.held_results |= name != MANIFEST,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(werr(&p, e)),
            }
        }
        self.save()
    }

    /// This run has taken its first step (or ended with results of its own): the previous
    /// run's files go for good.
    pub fn settle(&mut self) -> Result<(), OutputError> {
        if !self.held {
            return Ok(());
        }
        set_aside_held(&self.dir)?;
        self.held = false;
        remove_discarded(&self.dir)
    }

    /// Whether a previous run's results wait aside, to come back unless this run settles.
    pub fn holds_previous(&self) -> bool {
        self.held && self.held_results
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
        self.leaving().leave();
    }
}

impl RunFolder {
    /// What letting go of the folder takes, apart from the folder itself: for a process that
    /// must end at once, without unwinding (`driver/last_words.rs`).
    pub fn leaving(&self) -> Leaving {
        Leaving {
            dir: self.dir.clone(),
            written: self.written.clone(),
            held: self.held,
            held_results: self.held_results,
            created: self.created,
            replaced: self.replaced,
        }
    }
}

/// A [`RunFolder`] as it stood when [`RunFolder::leaving`] was taken.
#[derive(Clone, Debug)]
pub struct Leaving {
    dir: PathBuf,
    written: Vec<String>,
    held: bool,
    held_results: bool,
    created: bool,
    replaced: bool,
}

impl Leaving {
    /// What dropping the folder does: an unsettled replacement is undone (the previous run
    /// comes back), the lock goes, and a folder this run created and left empty goes too.
    fn leave(&self) {
        let put_back = self.held && put_back(&self.dir, &self.written).is_ok();
        let _ = std::fs::remove_file(self.dir.join(LOCK));
        if self.created && (!self.replaced || put_back) {
            // a run that failed on its input leaves no empty folder behind (only removed if
            // empty)
            let _ = std::fs::remove_dir(&self.dir);
        }
    }

    /// Let go of the folder as a run stopped here ends (its summary written), by the process
    /// that `halted` its writing: a previous run's results held aside come back; with none
    /// held, this run's files stay as the folder's results, its manifest as it stood when
    /// this was taken (a step recorded after it was taken back).
    pub fn end_here(mut self, halted: &crate::files::Halted) {
        if self.held && !self.held_results && set_aside_held(&self.dir).is_ok() {
            self.held = false;
            let _ = remove_discarded(&self.dir);
        }
        if !self.held && self.replaced {
            let mut text = self.written.join("\n");
            text.push('\n');
            let _ = halted.write_atomic(&self.dir.join(MANIFEST), text.as_bytes());
        }
        self.leave();
    }
}

/// The file names the manifest in `dir` lists.
fn read_manifest(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join(MANIFEST))
        .map(|t| {
            t.lines()
                .filter(|l| own_name(l))
                .map(String::from)
                .collect()
        })
        .unwrap_or_default()
}

/// Undo an unsettled replacement in `dir`: remove `written` (the failed run's files; a folder
/// of the user's by one of their names, which the run could not write, stays), move the held
/// files and manifest back, remove the empty [`HELD`] folder.
fn put_back(dir: &Path, written: &[String]) -> Result<(), OutputError> {
    let held = dir.join(HELD);
    // nothing held (the run settled since): this run's files are the folder's results
    if !held.is_dir() {
        return Err(werr(&held, "no previous run is held aside"));
    }
    for name in written {
        let p = dir.join(name);
        match std::fs::remove_file(&p) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound || p.is_dir() => {}
            Err(e) => return Err(werr(&p, e)),
        }
    }
    let _ = std::fs::remove_file(dir.join(MANIFEST));
    for entry in std::fs::read_dir(&held).map_err(|e| werr(&held, e))? {
        let entry = entry.map_err(|e| werr(&held, e))?;
        let to = dir.join(entry.file_name());
        std::fs::rename(entry.path(), &to).map_err(|e| werr(&to, e))?;
    }
    std::fs::remove_dir(&held).map_err(|e| werr(&held, e))
}

/// A settled run's [`HELD`] folder renamed to [`DISCARDED`], to be removed.
fn set_aside_held(dir: &Path) -> Result<(), OutputError> {
    let (held, gone) = (dir.join(HELD), dir.join(DISCARDED));
    std::fs::rename(&held, &gone).map_err(|e| werr(&held, e))
}

/// Remove a settled run's discarded files, if any are left.
fn remove_discarded(dir: &Path) -> Result<(), OutputError> {
    let gone = dir.join(DISCARDED);
    match std::fs::remove_dir_all(&gone) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(werr(&gone, e)),
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
        && name != HELD
        && name != DISCARDED
}

/// Whether process `pid` is running (a signal-0 probe: EPERM means it exists under another
/// user). A zombie is not: a rank of a job that mpirun left behind when another rank was
/// killed ends as one where nothing reaps it, and would hold the folder for ever.
fn alive(pid: i32) -> bool {
    if pid <= 0 {
        return false;
    }
    let r = unsafe { libc::kill(pid, 0) };
    let exists = r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM);
    exists && !zombie(pid)
}

/// Whether process `pid` has exited and waits to be reaped (its state in /proc/PID/stat is Z
/// or X; false where /proc cannot tell).
fn zombie(pid: i32) -> bool {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    // pid (comm) state …: the comm may hold spaces and parentheses, so read after the last ')'
    let state = stat
        .rsplit_once(')')
        .and_then(|(_, rest)| rest.split_whitespace().next());
    matches!(state, Some("Z") | Some("X"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// A folder left by a run that wrote `a.vtu` and `history.csv`, beside a user's note.
    fn previous_run(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("tmc-folder-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for (f, text) in [
            ("a.vtu", "old a"),
            ("history.csv", "old history"),
            ("notes.txt", "the user's"),
            (MANIFEST, "a.vtu\nhistory.csv\n"),
        ] {
            std::fs::write(dir.join(f), text).unwrap();
        }
        dir
    }

    fn files(dir: &Path) -> BTreeMap<String, String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                let text = std::fs::read_to_string(e.path()).unwrap_or("(folder)".into());
                (e.file_name().to_string_lossy().into_owned(), text)
            })
            .collect()
    }

    /// Open `dir`, replace the previous run, write `b.vtu` and a new `history.csv`.
    fn new_run(dir: &Path) -> RunFolder {
        let mut f = RunFolder::open(dir).unwrap();
        f.replace_previous().unwrap();
        for (name, text) in [("b.vtu", "new b"), ("history.csv", "new history")] {
            f.record(name).unwrap();
            std::fs::write(dir.join(name), text).unwrap();
        }
        f
    }

    #[test]
    fn an_exited_process_waiting_to_be_reaped_holds_no_folder() {
        let me = std::process::id() as i32;
        assert!(alive(me) && !zombie(me));
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let pid = child.id() as i32;
        let t0 = std::time::Instant::now();
        while !zombie(pid) {
            assert!(t0.elapsed().as_secs() < 30, "`true` did not exit");
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        // it exists for a signal-0 probe, but it is not running
        assert_eq!(unsafe { libc::kill(pid, 0) }, 0);
        assert!(!alive(pid));
        child.wait().unwrap();
        assert!(!alive(pid));
    }

    #[test]
    fn a_run_that_fails_before_settling_puts_the_previous_run_back() {
        let dir = previous_run("dropped");
        let before = files(&dir);
        drop(new_run(&dir));
        assert_eq!(files(&dir), before);
    }

    #[test]
    fn a_folder_of_the_user_s_named_as_a_file_of_the_run_stays_and_the_previous_run_comes_back() {
        // a run on two ranks whose second rank could not write its part of a step, a folder
        // being in the way: the run fails, and before, putting back stopped at that folder
        // and left the previous run aside
        let dir = previous_run("in-the-way");
        std::fs::create_dir(dir.join("step_0001_1.vtu")).unwrap();
        let before = files(&dir);
        let mut f = new_run(&dir);
        f.record("step_0001_1.vtu").unwrap();
        drop(f);
        assert_eq!(files(&dir), before);
    }

    #[test]
    fn a_run_killed_before_settling_is_undone_by_the_next_open() {
        let dir = previous_run("killed");
        let before = files(&dir);
        // killed: no drop, its lock and the held files stay
        std::mem::forget(new_run(&dir));
        assert!(dir.join(HELD).is_dir());
        // (its lock names a process that is gone)
        std::fs::write(dir.join(LOCK), "0\n").unwrap();
        let f = RunFolder::open(&dir).unwrap();
        assert_eq!(f.previous, vec!["a.vtu", "history.csv"]);
        drop(f);
        assert_eq!(files(&dir), before);
    }

    #[test]
    fn a_settled_run_replaces_the_previous_one_and_keeps_the_user_s_files() {
        let dir = previous_run("settled");
        let mut f = new_run(&dir);
        f.settle().unwrap();
        drop(f);
        let now = files(&dir);
        let names: Vec<&str> = now.keys().map(String::as_str).collect();
        assert_eq!(names, [MANIFEST, "b.vtu", "history.csv", "notes.txt"]);
        assert_eq!(now["history.csv"], "new history");
        assert_eq!(now[MANIFEST], "b.vtu\nhistory.csv\n");
    }
}
