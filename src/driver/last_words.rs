//! A run's last words under a launcher. Open MPI's `mpirun`, on Ctrl-C, sends its ranks
//! SIGTERM a second later and kills them a second after that (`odls_base_sigkill_timeout`):
//! a step longer than that never finishes, and an interrupted run would end without its
//! summary and with its lock. So, under a launcher, the initial state and each accepted step
//! leave ready the summary the run would write were it stopped there; on SIGTERM a watcher
//! thread gives the run [`GRACE`] to stop by itself, and if it has not, writes that summary,
//! lets go of the folder (its lock removed; before the first step, a previous run's results
//! put back), says so and ends the process: the run ends as an interrupted run does, at its
//! last accepted state. A step's new files are written first, and what replaces the previous
//! state's records (history row, `.pvd`, checkpoint, words) is put in place under the words'
//! lock; a watcher that speaks while a step is written halts the process's writing and takes
//! that step's new files back (`files::halt`), so the folder is always that of a recorded
//! state, however long a step's files take to write.

use crate::output::RunFolder;
use crate::output::folder::Leaving;
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
    /// the first step, a previous run's results put back); none on the ranks that do not
    /// write the run's files, which only stop writing theirs.
    pub folder: Option<Leaving>,
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
    let dir = folder.dir().display();
    let said = match folder.holds_previous() {
        true => {
            format!("interrupted before its first step; {dir} keeps the previous run's results")
        }
        false => format!("interrupted before its first step; it wrote no results in {dir}"),
    };
    leave_setup_words(folder, said);
}

/// As [`while_setting_up`], for a restart: the folder keeps the run it continues, as it was.
pub(super) fn while_restarting(folder: &RunFolder) {
    let dir = folder.dir().display();
    let said = format!(
        "interrupted before its first step; {dir} keeps the run's results as they were, to \
         continue with --restart"
    );
    leave_setup_words(folder, said);
}

fn leave_setup_words(folder: &RunFolder, said: String) {
    if !wanted() {
        return;
    }
    *hold() = Some(Words {
        summary: None,
        folder: Some(folder.leaving()),
        said,
    });
}

/// Under a launcher, on a rank that does not write the run's files: should the launcher stop
/// the run, this rank stops writing (its temporary files removed); the rank that writes the
/// run's files takes back what the step under way had written, and speaks.
pub(super) fn on_another_rank() {
    if wanted() {
        *hold() = Some(Words {
            summary: None,
            folder: None,
            said: String::new(),
        });
    }
}

/// The run writes its own summary from here: nothing to speak for it.
pub(super) fn forget() {
    hold().take();
}

/// What a SIGTERM does to a solve.
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
/// and end the process as an interrupted run ends. Nothing of this process is written after
/// (`files::halt`): what the records of a step under way had written goes, and the folder is
/// as the last recorded state left it. A rank that does not write the run's files stops
/// writing its own and leaves the end to the first rank and the launcher.
fn speak() {
    let mut words = hold();
    let Some(w) = words.take() else {
        return;
    };
    // a rank that does not write the run's files stops writing its own, and leaves them (a
    // `.pvtu` the first rank wrote names them); the first rank takes the step's back, theirs
    // included
    let halted = crate::files::halt(w.folder.is_some());
    let Some(folder) = w.folder else {
        return;
    };
    if let Some((path, json)) = &w.summary
        && halted.write_atomic(path, json.as_bytes()).is_err()
    {
        return;
    }
    folder.end_here(&halted);
    eprintln!("error: {}", w.said);
    // SAFETY: ends the process at once, as the launcher is about to; no destructor runs
    // (MPI's would wait for ranks that are being killed)
    unsafe { libc::_exit(1) }
}
