//! A run's last words under a launcher. Open MPI's `mpirun`, on Ctrl-C, sends its ranks
//! SIGTERM a second later and kills them a second after that (`odls_base_sigkill_timeout`):
//! a step longer than that never finishes, and an interrupted run would end without its
//! summary and with its lock. So, under a launcher, the initial state and each accepted step
//! leave ready the summary the run would write were it stopped there; on SIGTERM a watcher
//! thread gives the run [`GRACE`] to stop by itself, and if it has not, writes that summary,
//! lets go of the folder (its lock removed; before the first step, a previous run's results
//! put back), says so and ends the process: the run ends as an interrupted run does, at its
//! last accepted state. The step's records and the words are kept under one lock, so the
//! watcher never speaks between a step's files.

use crate::output::RunFolder;
use crate::output::folder::Leaving;
use crate::output::write_atomic;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard};
use std::time::Duration;

/// The summary of the last accepted step (or of the initial state, before the first) as an
/// interrupted run writes it, and where.
pub(super) struct Words {
    /// Where, and what; none while the run sets up (meshing, the model), before it has one.
    pub summary: Option<(PathBuf, String)>,
    /// The run's folder, to let go of as an interrupted run does (its lock removed; before
    /// the first step, a previous run's results put back).
    pub folder: Leaving,
    /// What the run says when it is interrupted.
    pub said: String,
}

static WORDS: Mutex<Option<Words>> = Mutex::new(None);

/// Set by SIGTERM.
static TERMINATED: AtomicBool = AtomicBool::new(false);

/// How long the watcher leaves the run to stop by itself after SIGTERM: under the second
/// before `mpirun` kills it.
pub const GRACE: Duration = Duration::from_millis(500);

/// Whether this process was started by a launcher that kills its ranks soon after a
/// signal (Open MPI's or MPICH's environment).
pub fn wanted() -> bool {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
        .iter()
        .any(|v| std::env::var_os(v).is_some())
}

/// The words, held while a step is recorded (the watcher waits for it).
pub(super) fn hold() -> MutexGuard<'static, Option<Words>> {
    WORDS.lock().unwrap_or_else(|e| e.into_inner())
}

/// Under a launcher, while the run sets up in `folder` (meshing, the model, before its initial
/// state is recorded): the folder as dropping it would leave it (its lock removed, a previous
/// run's results put back, a folder this run created and left empty removed), and the words.
pub(super) fn while_setting_up(folder: &RunFolder) {
    if !wanted() {
        return;
    }
    let dir = folder.dir().display();
    let said = match folder.holds_previous() {
        true => {
            format!("interrupted before its first step; {dir} keeps the previous run's results")
        }
        false => format!("interrupted before its first step; it wrote no results in {dir}"),
    };
    *hold() = Some(Words {
        summary: None,
        folder: folder.leaving(),
        said,
    });
}

/// The run writes its own summary from here: nothing to speak for it.
pub(super) fn forget() {
    hold().take();
}

/// What the SIGTERM handler does (a store, safe in a handler).
pub(super) fn on_terminate() {
    TERMINATED.store(true, Ordering::Relaxed);
}

/// Start the watcher, under a launcher (by the `tmc` binary, once).
pub(super) fn watch() {
    if !wanted() {
        return;
    }
    std::thread::spawn(|| {
        while !TERMINATED.load(Ordering::Relaxed) {
            std::thread::sleep(Duration::from_millis(20));
        }
        std::thread::sleep(GRACE);
        speak();
    });
}

/// Write the last words, if the run has left some and not written its own summary since,
/// and end the process as an interrupted run ends.
fn speak() {
    let mut words = hold();
    let Some(w) = words.take() else {
        return;
    };
    if let Some((path, json)) = &w.summary
        && write_atomic(path, json.as_bytes()).is_err()
    {
        return;
    }
    w.folder.end_here();
    eprintln!("error: {}", w.said);
    // SAFETY: ends the process at once, as the launcher is about to; no destructor runs
    // (MPI's would wait for ranks that are being killed)
    unsafe { libc::_exit(1) }
}
