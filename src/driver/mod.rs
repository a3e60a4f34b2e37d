//! `tmc solve`: case → mesh → model → load stepping with Newton → VTU series, history, summary.

mod account;
pub mod check;
pub mod checkpoint;
mod last_words;
mod recorder;
pub mod records;
mod run;
pub mod state;
mod stepper;
pub mod strategy;

pub use check::{CheckReport, check};
pub use records::{HISTORY_SOLVER_COLUMNS, HISTORY_STEP_COLUMNS, Summary, group_flows, reactions};
pub use strategy::{Strategy, choose_linear, choose_strategy, describe};

use crate::case::{Case, CaseError};
use crate::dofs::NONE;
use crate::files::TempFile;
use crate::mesh::Mesh;
use crate::mesh::gmsh::{GmshError, MeshOptions, mesh_geo};
use crate::mesh::msh::{MshError, read_msh};
use crate::model::rejoin::{Layer, LayerError};
use crate::model::{Model, Term, remake};
use crate::output::probes::{self, Probe};
use crate::output::{OutputError, RunFolder, werr};
use crate::parallel::Ranks;
use crate::solver::idle::IdleThreads;
use crate::solver::linear::LinearError;
use run::{Run, Settle};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error(transparent)]
    Case(#[from] CaseError),
    #[error(transparent)]
    Msh(#[from] MshError),
    #[error(transparent)]
    Gmsh(#[from] GmshError),
    #[error(transparent)]
    Output(#[from] OutputError),
    /// (Its text is the linear solver's, not repeated as a cause.)
    #[error("linear solver: {0}")]
    Linear(LinearError),
    #[error("{0}")]
    Setup(String),
    /// `at`: where the run stands ("λ = 0.5", or "t = 1.2 (λ = 1)" with `[time]`); `step`:
    /// the step that failed ("Δλ = 2e-5", or "Δt = 2e-5"); `left`: what the run left in its
    /// folder ([`Left`]); `hint`: what the scene's physics suggests to read ("" or a sentence
    /// starting with "; ").
    #[error(
        "load step from {at} failed with {step}, below the minimum step ({reason}); {left}{hint}"
    )]
    StepTooSmall {
        at: String,
        step: String,
        reason: String,
        steps: usize,
        left: Left,
        hint: Box<str>,
    },
    #[error("interrupted at {at} after {steps} converged steps; {left}")]
    Interrupted {
        at: String,
        steps: usize,
        left: Left,
    },
}

/// What a run that stopped early left in its output folder: its converged steps (`steps`, up
/// to `at`), or, where it took none and the folder held a previous run's, those results as
/// they were.
#[derive(Debug)]
pub struct Left(String);

impl Left {
    /// For a run that stopped at `at` after `steps` converged steps in `dir`; `interrupted`:
    /// by the user (its summary.json says so).
    pub fn new(steps: usize, at: &str, dir: &Path, kept_previous: bool, interrupted: bool) -> Left {
        let dir = dir.display();
        Left(match (kept_previous, interrupted) {
            (true, _) => {
                format!("no load step was taken, so {dir} keeps the previous run's results")
            }
            (false, false) => format!("the {steps} converged steps up to {at} are in {dir}"),
            (false, true) => format!("they are in {dir} (summary.json says \"interrupted\")"),
        })
    }
}

impl std::fmt::Display for Left {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl From<remake::RemakeError> for SolveError {
    fn from(e: remake::RemakeError) -> SolveError {
        SolveError::Setup(e.to_string())
    }
}

impl From<LayerError> for SolveError {
    fn from(e: LayerError) -> SolveError {
        SolveError::Setup(e.to_string())
    }
}

impl From<LinearError> for SolveError {
    fn from(e: LinearError) -> SolveError {
        SolveError::Linear(e)
    }
}

/// Set by SIGINT/SIGTERM (see [`take_signals`]): runs stop after their current step.
static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether a stop was asked for.
pub fn interrupted() -> bool {
    INTERRUPTED.load(std::sync::atomic::Ordering::Relaxed)
}

/// Ask running solves to stop after their current step (what the signal handler does).
pub fn request_stop() {
    INTERRUPTED.store(true, std::sync::atomic::Ordering::Relaxed);
}

/// End the process as `signal`'s default action does (from the thread that takes signals).
fn end_as(signal: libc::c_int) {
    // SAFETY: the default disposition, the signal let through on this thread, and raised at it
    unsafe {
        libc::signal(signal, libc::SIG_DFL);
        let one = crate::signals::set(&[signal]);
        libc::pthread_sigmask(libc::SIG_UNBLOCK, &one, std::ptr::null_mut());
        libc::raise(signal);
    }
}

/// Take SIGINT (Ctrl-C) and SIGTERM on a thread of their own, for the `tmc` binary: called
/// first in `main`, before any other thread starts, so that every thread the process starts
/// (rayon's, MPI's, the last words' watcher) keeps them blocked and no handler ever runs in
/// the middle of other code. METIS, for one, puts a handler on SIGTERM while it works that
/// jumps out of wherever the signal lands: out of `malloc`, whose lock then stays taken, and
/// the process hangs at its next allocation. With `graceful` (a solve), a signal stops the run
/// after its current step, with its summary written, and the same signal again ends the
/// process at once; under a launcher that kills its ranks soon after SIGTERM, a run whose step
/// does not end in time ends at its last accepted step instead (`last_words.rs`). Otherwise a
/// signal ends the process as it would have.
pub fn take_signals(graceful: bool) {
    let both = crate::signals::set(&[libc::SIGINT, libc::SIGTERM]);
    // SAFETY: blocking two signals on this thread; threads started after inherit it
    unsafe { libc::pthread_sigmask(libc::SIG_BLOCK, &both, std::ptr::null_mut()) };
    let taker = move || {
        let mut seen = [false; 2];
        loop {
            let mut signal = 0;
            // SAFETY: waiting for one of the two signals blocked on every thread
            if unsafe { libc::sigwait(&both, &mut signal) } != 0 {
                continue;
            }
            let once = &mut seen[usize::from(signal == libc::SIGTERM)];
            if !graceful || *once {
                end_as(signal);
            }
            *once = true;
            request_stop();
            if signal == libc::SIGTERM {
                last_words::on_terminate();
            }
        }
    };
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(taker)
        .expect("a thread to take signals starts");
    if graceful {
        last_words::watch();
    }
}

/// Options of `tmc solve`.
#[derive(Clone, Debug, Default)]
pub struct SolveOptions {
    /// Output folder (default `results/NAME`).
    pub out_dir: Option<PathBuf>,
    pub quiet: bool,
    /// Print one line per step.
    pub verbose: bool,
    /// What the other threads do during linear solves (`TMC_IDLE_THREADS` for `tmc solve`).
    pub idle_threads: IdleThreads,
    /// Case keys set on the command line: (dotted path, value in TOML syntax).
    pub sets: Vec<(String, String)>,
    /// Continue the run in the output folder from its last converged step.
    pub restart: bool,
    /// The memory (MB) the run's linear algebra may take, for `[solver] engine = "auto"`
    /// (`None`: what the machine has available).
    pub memory_mb: Option<f64>,
}

/// A mesh written for this run under a temporary name: moved to its final name once the run
/// starts, removed if the run fails before.
pub type StagedMesh = TempFile;

/// The options a case meshes its `.geo` with.
fn mesh_options(case: &Case) -> MeshOptions {
    let m = &case.file.mesh_options;
    MeshOptions {
        order: m.order.unwrap_or(1),
        incomplete: m.incomplete,
        set_numbers: m.params.iter().map(|(k, v)| (k.clone(), *v)).collect(),
        verbose: false,
    }
}

/// Whether a run of `case` would mesh with gmsh: its mesh a `.geo` that the cache of meshes
/// does not keep (or has not kept yet).
pub(crate) fn meshes_again(case: &Case) -> bool {
    let path = case.mesh_path();
    path.extension().is_some_and(|e| e == "geo")
        && crate::mesh::gmsh::kept(&path, &mesh_options(case)).is_none_or(|k| !k.held())
}

/// The case's mesh: its `.msh` read, or its `.geo` meshed into a staged file in `out_dir`.
pub fn mesh_for(case: &Case, out_dir: &Path) -> Result<(Mesh, Option<StagedMesh>), SolveError> {
    let path = case.mesh_path();
    match path.extension().and_then(|e| e.to_str()) {
        Some("geo") => {
            let out = out_dir.join(".mesh.new.msh");
            let report = mesh_geo(&path, &out, &mesh_options(case))?;
            let staged = TempFile::new(out);
            let mut mesh = report.mesh;
            mesh.warnings = report.warnings;
            mesh.source = path;
            Ok((mesh, Some(staged)))
        }
        Some("msh") => Ok((read_msh(&path)?, None)),
        _ => {
            let span = case.file.mesh.span();
            Err(case
                .error::<()>(
                    span,
                    format!("mesh \"{}\" must be a .msh or .geo file", path.display()),
                )
                .unwrap_err()
                .into())
        }
    }
}

/// The case's model and probes, everything checked: its mesh (a `.geo` meshed into a staged
/// file in `mesh_dir`; the mesh's warnings printed unless `quiet`), the case against the mesh,
/// the model (every body held).
pub(crate) fn checked_model(
    case: &Case,
    mesh_dir: &Path,
    quiet: bool,
) -> Result<(Model, Vec<Probe>, Option<StagedMesh>), SolveError> {
    let (mesh, staged) = mesh_for(case, mesh_dir)?;
    let (model, probes) = model_on(case, mesh, quiet)?;
    Ok((model, probes, staged))
}

/// The case's model and probes on `mesh`, everything checked.
fn model_on(case: &Case, mesh: Mesh, quiet: bool) -> Result<(Model, Vec<Probe>), SolveError> {
    let d = mesh.extent();
    model_on_extent(case, mesh, d, quiet)
}

/// [`model_on`] with the extent d of eq. 21 given.
fn model_on_extent(
    case: &Case,
    mesh: Mesh,
    d: f64,
    quiet: bool,
) -> Result<(Model, Vec<Probe>), SolveError> {
    if !quiet {
        for w in &mesh.warnings {
            crate::note!("warning: {}: {w}", mesh.source.display());
        }
    }
    records::refuse_column_names(case)?;
    crate::model::validate::validate(case, &mesh)?;
    let model = crate::model::build::build_with_extent(case, mesh, d)?;
    if !quiet {
        for w in &model.warnings {
            crate::note!("{}: {w}", case.path.display());
        }
    }
    let probes = probes::build(case, &model.mesh)?;
    Ok((model, probes))
}

/// Solve a case file end to end.
///
/// Nothing in the output folder changes until the case, the mesh and the model have been
/// checked: a run that fails on its input leaves the previous run's results as they were.
/// Then the previous run's files (and only those, as its manifest lists them) are replaced.
pub fn run(case_path: &Path, opts: &SolveOptions) -> Result<Summary, SolveError> {
    let start = Instant::now();
    let case = Case::read(case_path)?.with_sets(&opts.sets)?;
    let ranks = Ranks::world();
    if !ranks.is_serial() {
        return run_ranks(&case, opts, ranks, start);
    }
    let out_dir = opts
        .out_dir
        .clone()
        .unwrap_or_else(|| PathBuf::from("results").join(case.name()));
    let mut folder = RunFolder::open(&out_dir)?;
    if opts.restart {
        // a case changed since the run is refused for what changed, before what it asks that
        // cannot restart (a layer reconnected, a medium remade: the run had them too)
        if checkpoint::Checkpoint::path(&out_dir).exists() {
            checkpoint::Checkpoint::of_case(&out_dir, &case)?;
        }
        let reconnected = (case.file.region.iter())
            .any(|r| r.friction.as_ref().is_some_and(|f| f.get_ref().reconnect()));
        if reconnected {
            return Err(SolveError::Setup(
                "cannot restart a run whose friction layer is reconnected \
                 (`friction.reconnect`): its mesh changed as it ran; run it again without \
                 --restart"
                    .into(),
            ));
        }
        return restart(&case, folder, opts, start);
    }
    last_words::while_setting_up(&folder);
    let (mut model, probes, staged) = checked_model(&case, &out_dir, opts.quiet)?;
    take_folder(&mut folder, &mut model, staged)?;
    solve_model(&case, model, &probes, folder, opts, start, None)
}

/// Whether the medium made again is settled after each remake, what it changed measured there
/// (`settle`).
pub(crate) fn settling(case: &Case) -> bool {
    case.file.region.iter().any(|r| r.settles())
}

/// What a run on several ranks refuses before it starts (`tmc check` refuses it too): a
/// friction layer that is reconnected, and a medium made again, run on one process.
pub(crate) fn refuse_on_ranks(case: &Case, model: &Model, ranks: Ranks) -> Result<(), SolveError> {
    if ranks.is_serial() {
        return Ok(());
    }
    let what = match (model.reconnects(), case.remade_medium()) {
        (true, _) => "a friction layer that is reconnected (`friction.reconnect`)",
        (false, Some(_)) => "a medium made again as the bodies move (`remake`)",
        (false, None) => return Ok(()),
    };
    Err(SolveError::Setup(format!(
        "mpirun -n {}: {what} runs on one process; run it without mpirun",
        ranks.size
    )))
}

/// The checked run takes its folder: the previous run's files set aside, the mesh meshed for
/// this run, if any, moved to `mesh.msh` there (errors so far named the .geo; from now on the
/// mesh is the file written), and under a launcher the words for a stop before the first step.
fn take_folder(
    folder: &mut RunFolder,
    model: &mut Model,
    staged: Option<StagedMesh>,
) -> Result<(), SolveError> {
    folder.replace_previous()?;
    if let Some(staged) = staged {
        folder.record("mesh.msh")?;
        model.mesh.source = folder.dir().join("mesh.msh");
        staged
            .commit(&model.mesh.source)
            .map_err(|e| SolveError::Output(werr(&model.mesh.source, e)))?;
    }
    last_words::while_setting_up(folder);
    Ok(())
}

/// A run on several ranks. Rank 0 does what a serial run does before it steps (takes the
/// output folder, meshes, checks the case and the model) and then tells the others the mesh
/// to read (the one it wrote for a `.geo`), or that it failed; every rank then builds the same
/// model, and they step together, rank 0 writing the files.
fn run_ranks(
    case: &Case,
    opts: &SolveOptions,
    ranks: Ranks,
    start: Instant,
) -> Result<Summary, SolveError> {
    let out_dir = opts
        .out_dir
        .clone()
        .unwrap_or_else(|| PathBuf::from("results").join(case.name()));
    let root = if ranks.is_root() {
        let setup = (|| -> Result<_, SolveError> {
            let mut folder = RunFolder::open(&out_dir)?;
            // before anything of the folder's is replaced
            let serial_only = |model: &Model| refuse_on_ranks(case, model, ranks);
            if opts.restart {
                let (model, probes, cp) = restart_setup(case, &mut folder, opts)?;
                serial_only(&model)?;
                return Ok((model, probes, folder, Some(cp)));
            }
            last_words::while_setting_up(&folder);
            let (mut model, probes, staged) = checked_model(case, &out_dir, opts.quiet)?;
            serial_only(&model)?;
            take_folder(&mut folder, &mut model, staged)?;
            Ok((model, probes, folder, None))
        })();
        Some(setup)
    } else {
        // a stop under the launcher takes back what this rank writes of a step under way
        last_words::on_another_rank();
        None
    };
    // rank 0's verdict: the mesh file to read, or empty when it failed
    let mut mesh_file = match &root {
        Some(Ok((model, ..))) => model
            .mesh
            .source
            .to_string_lossy()
            .into_owned()
            .into_bytes(),
        _ => Vec::new(),
    };
    ranks.broadcast(0, &mut mesh_file);
    // and the checkpoint a restart continues from, as rank 0 read and checked it
    let mut resumed = match &root {
        Some(Ok((.., Some(cp)))) => cp.to_json().into_bytes(),
        _ => Vec::new(),
    };
    if opts.restart {
        ranks.broadcast(0, &mut resumed);
    }
    let (model, probes, folder, from) = match root {
        Some(setup) => {
            let (model, probes, folder, from) = setup?;
            (model, probes, Some(folder), from)
        }
        None if mesh_file.is_empty() => {
            return Err(SolveError::Setup("rank 0 failed to set the run up".into()));
        }
        None => {
            // read_msh names the mesh by the path it read
            let mesh = read_msh(Path::new(&*String::from_utf8_lossy(&mesh_file)))?;
            let (model, probes) = model_on(case, mesh, true)?;
            let from = match opts.restart {
                true => Some(checkpoint::Checkpoint::from_json(&resumed)?),
                false => None,
            };
            (model, probes, None, from)
        }
    };
    let mut run = Run::new(case, &model, &probes, folder, out_dir, opts, start)?;
    run.announce();
    match from {
        Some(cp) => run.resume(cp, false)?,
        None => run.record_initial()?,
    }
    step_to_end(run)
}

/// Continue the run in `folder` from its checkpoint, on the mesh it ran on (the folder's
/// `mesh.msh` when the case meshes a `.geo`).
fn restart(
    case: &Case,
    mut folder: RunFolder,
    opts: &SolveOptions,
    start: Instant,
) -> Result<Summary, SolveError> {
    let (model, probes, cp) = restart_setup(case, &mut folder, opts)?;
    solve_model(case, model, &probes, folder, opts, start, Some(cp))
}

/// The model a restart continues on (on the mesh the run ran on) and its checkpoint, checked
/// against the case and the mesh; the folder's files are kept.
fn restart_setup(
    case: &Case,
    folder: &mut RunFolder,
    opts: &SolveOptions,
) -> Result<(Model, Vec<Probe>, checkpoint::Checkpoint), SolveError> {
    last_words::while_restarting(folder);
    let dir = folder.dir().to_owned();
    checkpoint::Checkpoint::exists(&dir)?;
    let mesh = if case.mesh_path().extension().is_some_and(|e| e == "geo") {
        read_msh(&dir.join("mesh.msh"))?
    } else {
        mesh_for(case, &dir)?.0
    };
    // a medium made again: the mesh of the remake the checkpoint continues
    let cp = checkpoint::Checkpoint::of_case(&dir, case)?;
    let (model, probes) = match cp.state.totals.medium_remakes {
        n if n > 0 && case.remade_medium().is_some() => {
            let remade = checkpoint::RemadeMedium::read(&dir, n)?;
            let mut mesh = remade.mesh;
            mesh.source = dir.join(checkpoint::MEDIUM_FILES[0]);
            let (mut model, probes) = model_on_extent(case, mesh, remade.d, true)?;
            model.made_again(remade.reference);
            (model, probes)
        }
        _ => model_on(case, mesh, opts.quiet)?,
    };
    let cp = cp.on_mesh(&dir, &model.mesh)?;
    folder.keep_previous()?;
    // the folder as it now stands: a stop before the first step leaves its manifest as it was
    last_words::while_restarting(folder);
    Ok((model, probes, cp))
}

/// Step the model from its initial state to the end of its load path. Where a friction
/// region's layer is reconnected, the run goes on on a mesh whose layer is joined again each
/// time its faces have slid a cell past each other; elsewhere, on a mesh whose medium is made
/// again each time its cells' faces have slid past each other by [`remake::SLID`] of a cell.
fn solve_model(
    case: &Case,
    model: Model,
    probes: &[Probe],
    folder: RunFolder,
    opts: &SolveOptions,
    start: Instant,
    from: Option<checkpoint::Checkpoint>,
) -> Result<Summary, SolveError> {
    let out_dir = folder.dir().to_owned();
    let mut layer = Layer::find(&model)?;
    let mut medium = remake::Medium::find(&model, case.remade_medium())?;
    if medium.is_some() {
        // each remake drops the run's structures and builds them again: the pages it frees
        // are kept for the next
        crate::memory::keep_freed_for_reuse();
    }
    let settles = settling(case);
    let mut check_first = medium
        .as_mut()
        .is_some_and(|m| watch_from(m, &model, from.as_ref()));
    let (mut model, mut folder, mut from) = (model, Some(folder), from);
    // the remake whose mesh the folder's checkpoint continues (none before a first step)
    let mut saved = from.as_ref().map(|cp| cp.state.totals.medium_remakes);
    let mut probes = probes.to_vec();
    let mut changed = false;
    // when a remake was due, and the groups' flows before it where it is measured
    let mut before_remake: Option<(Option<records::Reactions>, Instant)> = None;
    let mut stuck = Stuck::default();
    // when the medium was last made again where a step would have stopped the run
    let mut remade_to_go_on = f64::NAN;
    // the remakes in a row the mesher failed
    let mut mesher_failed = 0;
    loop {
        let mut run = Run::new(
            case,
            &model,
            &probes,
            folder.take(),
            out_dir.clone(),
            opts,
            start,
        )?;
        if !changed {
            run.announce();
        }
        let here = from.as_ref().map_or(0, |cp| cp.state.totals.medium_remakes);
        match from.take() {
            // after a change the checkpoint is the one the run carried itself
            Some(cp) => run.resume(cp, changed)?,
            None => run.record_initial()?,
        }
        let accepted = run.accepted();
        if layer.is_none() && medium.is_none() {
            return step_to_end(run);
        }
        if let Some(m) = &medium {
            run.keep_medium(m);
            run.remake_before_stopping(remade_to_go_on);
        }
        if changed {
            run.rejoined(match &medium {
                None => Settle::Join,
                Some(_) if settles => Settle::Remade,
                Some(_) => Settle::Deferred,
            });
        }
        if let Some((before, since)) = before_remake.take() {
            run.remade_from(before.as_ref(), since)?;
        }
        if changed && medium.is_some() {
            // a medium made at a vertex: the watch is not asked before the first step
            segment_starts(&mut run, &model, case);
        }
        stuck.rejected = run.rejected();
        let due = |run: &mut Run| match (&layer, medium.as_mut()) {
            (Some(layer), _) => {
                if let Some(node) = layer.overhang(&model, run.state()) {
                    run.overhangs(node);
                }
                layer.due(&model, run.state()).map(Change::Join)
            }
            (None, Some(medium)) => {
                let (t, target) = run.next_step();
                let watch = medium.due(&model, run.references(), run.state(), t, target);
                // the watch after this state, for the next step's checkpoint
                run.keep_medium(medium);
                if let remake::Watch::Until(passes) = watch {
                    run.cap_step(passes + PAST * largest_step(case));
                }
                segment_starts(run, &model, case);
                let due = watch == remake::Watch::Remake;
                if run.wants_remake() {
                    remade_to_go_on = t;
                    return Some(Change::Remake);
                }
                let stuck_here = stuck.after(run.rejected(), t);
                if stuck_here && medium.stuck(&model) && opts.verbose {
                    crate::note!(
                        "  stuck at t = {t} on the medium as made: made again by {} first",
                        medium.mesher().name()
                    );
                }
                (due || stuck_here).then_some(Change::Remake)
            }
            (None, None) => None,
        };
        let first = std::mem::take(&mut check_first);
        let (mut run, change) = match step_until(run, first, due)? {
            Stepped::Ended(summary) => return Ok(summary),
            Stepped::Changed(run, change) => (run, change),
        };
        if run.accepted() > accepted {
            saved = Some(here);
        }
        // the new medium is made while the run can still end with its summary if it cannot be
        let mut made = None;
        if let (Change::Remake, Some(m)) = (&change, &medium) {
            let since = Instant::now();
            (run, made) = remade_or_kept(run, m, &model, &mut mesher_failed)?;
            if made.is_some() {
                let before = settles.then(|| run.flows_at_rest()).transpose()?;
                before_remake = Some((before, since));
            }
        }
        let (mut cp, mut kept) = run.end_to_rejoin();
        // a medium the mesher could not make again goes on as it is, watched as it was
        if made.is_some() || !matches!(change, Change::Remake) {
            let (new, placed) =
                changed_model(case, &model, change, &mut layer, made, &mut cp, opts)?;
            model = new;
            if let Some(placed) = placed {
                probes = placed;
            }
            medium_again(case, &model, &mut medium, &mut cp, kept.as_mut(), saved)?;
        }
        folder = kept;
        // the run's clock goes on through the change: the time it took (gmsh, the new model)
        // is the run's too
        cp.state.wall = start.elapsed().as_secs_f64();
        from = Some(cp);
        changed = true;
    }
}

/// Start following the medium `m` of `model` as a run begins: from the watch the checkpoint
/// `from` kept, after the step it ended with (as the run did before it was stopped; returns
/// true: whether to make it again is asked before the first step), or from the state the run
/// starts at.
fn watch_from(
    m: &mut remake::Medium,
    model: &Model,
    from: Option<&checkpoint::Checkpoint>,
) -> bool {
    match from {
        Some(cp) => match &cp.state.totals.medium {
            Some(kept) => {
                *m = kept.clone();
                return true;
            }
            None => {
                m.start(model, &cp.state.x, cp.state.clock.t, 0.0);
            }
        },
        None => {
            m.start(model, &model.initial_state(), 0.0, 0.0);
        }
    }
    false
}

/// The remade medium's mesh in `folder`, for a restart from the next step's checkpoint on;
/// the mesh of remake `saved`, which the folder's checkpoint continues, is kept beside it.
fn write_remade(
    folder: &mut RunFolder,
    model: &Model,
    cp: &checkpoint::Checkpoint,
    saved: Option<usize>,
) -> Result<(), SolveError> {
    for name in checkpoint::MEDIUM_FILES {
        folder.record(name)?;
    }
    let remade = checkpoint::RemadeMedium {
        remakes: cp.state.totals.medium_remakes,
        d: model.d,
        mesh: model.mesh.clone(),
        reference: model.cell_reference.clone(),
    };
    remade.write(folder.dir(), saved)?;
    Ok(())
}

/// After a change at the checkpoint `cp`, the medium of `model` (the new one) watched from
/// its state, and its mesh in the run's folder for a restart (beside remake `saved`'s, which
/// the folder's checkpoint continues).
fn medium_again(
    case: &Case,
    model: &Model,
    medium: &mut Option<remake::Medium>,
    cp: &mut checkpoint::Checkpoint,
    folder: Option<&mut RunFolder>,
    saved: Option<usize>,
) -> Result<(), SolveError> {
    let Some((rate, made_for_pass)) = medium.as_ref().map(|m| (m.rate, m.made_for_pass)) else {
        return Ok(());
    };
    *medium = remake::Medium::find(model, case.remade_medium())?;
    if let Some(m) = medium.as_mut() {
        m.made_for_pass = made_for_pass;
        restart_medium(case, model, m, cp, rate);
    }
    if let Some(folder) = folder {
        write_remade(folder, model, cp, saved)?;
    }
    Ok(())
}

/// The medium `m` of `model` made again at the run's state; `None` where the mesher failed
/// (told, and counted in `failed`, the failures in a row) and the run may go on a step with
/// the medium it has; an error, with the run's summary written, where it may not.
fn remade_or_kept<'a>(
    run: Run<'a>,
    m: &remake::Medium,
    model: &Model,
    failed: &mut usize,
) -> Result<(Run<'a>, Option<remake::Remade>), SolveError> {
    match m.remake(model, run.references(), run.state()) {
        Ok(new) => {
            *failed = 0;
            Ok((run, Some(new)))
        }
        Err(e) if e.mesher && *failed < MESHER_TRIES => {
            *failed += 1;
            crate::note!(
                "  the medium could not be made again at t = {}: {e}; going on with it as it \
                 is, to make it again after the next step",
                run.next_step().0
            );
            Ok((run, None))
        }
        Err(e) => Err(run.cannot_change("the medium could not be made again", &e.to_string())),
    }
}

/// How many remakes in a row the mesher may fail before the run ends (each time the run goes
/// on a step with the medium it has).
const MESHER_TRIES: usize = 3;

/// The attempts that failed from the last accepted state: when a step fails there twice (the
/// cut step too), the medium is made again at that state, once (its cells may be what stops
/// the step; a failure a cut mends, as a contact closing, leaves it).
#[derive(Default)]
struct Stuck {
    /// The run's rejected attempts when last asked.
    rejected: usize,
    /// The accepted state's t, and how many attempts from it failed.
    at: f64,
    failures: usize,
}

impl Stuck {
    /// After an attempt, given the run's rejected attempts so far and the last accepted
    /// state's t: whether the attempt was the second to fail from that state.
    fn after(&mut self, rejected: usize, t: f64) -> bool {
        let failed = rejected > self.rejected;
        self.rejected = rejected;
        if failed {
            self.failures = if self.at == t { self.failures + 1 } else { 1 };
            self.at = t;
        }
        failed && self.failures == 2
    }
}

/// The model on which a run goes on after `change` at the checkpoint `cp`'s state (laid out
/// again for it), and, for a remade medium, the probes re-placed on it.
#[allow(clippy::too_many_arguments)]
fn changed_model(
    case: &Case,
    model: &Model,
    change: Change,
    layer: &mut Option<Layer>,
    made: Option<remake::Remade>,
    cp: &mut checkpoint::Checkpoint,
    opts: &SolveOptions,
) -> Result<(Model, Option<Vec<Probe>>), SolveError> {
    let t = cp.state.clock.t;
    match (change, layer.as_mut(), made) {
        (Change::Join(shift), Some(layer), _) => {
            cp.state.totals.layer_joins += 1;
            let mut mesh = model.mesh.clone();
            layer.join(model, &mut mesh, &mut cp.state.x, shift);
            if opts.verbose {
                crate::note!("friction layer joined again, shifted {shift} cells, at t = {t}");
            }
            Ok((model_on(case, mesh, true)?.0, None))
        }
        (Change::Remake, _, Some(made)) => {
            cp.state.totals.medium_remakes += 1;
            let (new, probes) = remade(case, model, made, cp)?;
            if opts.verbose {
                crate::note!(
                    "medium made again at t = {t}: {} nodes",
                    new.mesh.coords.len()
                );
            }
            Ok((new, Some(probes)))
        }
        _ => unreachable!("a change comes from the layer or the medium there is"),
    }
}

/// Start the new medium `m` at the checkpoint's state, and cut the next step so that it takes
/// none of its slivers, as made, past the end of its edge at the speed of the last (`rate`;
/// but not to less than [`FIRST`] of the largest step without friction, [`PAST`] with).
fn restart_medium(
    case: &Case,
    model: &Model,
    m: &mut remake::Medium,
    cp: &mut checkpoint::Checkpoint,
    rate: f64,
) {
    let room = m.start(model, &cp.state.x, cp.state.clock.t, rate);
    let largest = largest_step(case);
    let clock = &mut cp.state.clock;
    // with friction a thin tetrahedron's pass asks at once, and a shorter first step doubled
    // the remakes of a 3D drag
    let first = if model.rubs() { PAST } else { FIRST };
    clock.dt = clock.dt.min(room.max(first * largest));
}

/// A share of the largest step: how long after a sliver's node gets to the end of the edge
/// across it the step that takes it there ends (the step after which the medium is made
/// again), and the first step of a new segment of the path.
const PAST: f64 = 0.1;

/// A share of the largest step: the shortest first step after a remake without friction. A
/// new medium resists the slide from the state it was made at, and a first step of a tenth
/// took the square pad's leading face over a row of the plate's nodes in one go: F_t/F_n
/// 0.0259 at most (0.0034 on average) in 3D; at a twentieth 0.0106 (0.0020), in 15 % more
/// Newton iterations and the same wall
/// (docs/notes/2026-12-07-friction-in-3d-and-a-drag-at-each-row-of-nodes.md).
const FIRST: f64 = 0.05;

/// Cut the next step of a medium made again to [`PAST`] of the largest step where it starts a
/// new segment of the path and there is no friction: the watch has no speed of the bodies to
/// foresee the first step's passes by, and without friction a closed layer's shear since its
/// medium was made is all drag (the sphere's first step of its slide, taken at the step of its
/// press, met F_t/F_n 0.079 where the steps after it met at most 0.03); a friction layer takes
/// its slide into its cells at every step.
fn segment_starts(run: &mut Run, model: &Model, case: &Case) {
    if run.at_vertex() && !model.rubs() {
        let (t, _) = run.next_step();
        run.cap_step(t + PAST * largest_step(case));
    }
}

/// The case's largest step.
fn largest_step(case: &Case) -> f64 {
    match &case.file.time {
        Some(time) => time.dt_max(),
        None => case.file.steps.max,
    }
}

/// The model on which a run goes on once its medium is made again (`made`) at the checkpoint
/// `cp`'s state (which is laid out again for it): the new medium's cells measured from their
/// own references, the regularization's extent d kept.
fn remade(
    case: &Case,
    model: &Model,
    made: remake::Remade,
    cp: &mut checkpoint::Checkpoint,
) -> Result<(Model, Vec<Probe>), SolveError> {
    let mut mesh = made.mesh.clone();
    mesh.warnings.clear();
    let (mut new, probes) = model_on_extent(case, mesh, model.d, true)?;
    new.made_again(made.reference.clone());
    let from = made.old_dofs(model, &new);
    let old_state = std::mem::take(&mut cp.state.x);
    // the old cells as the run left them; the new ones start from the remake's references
    let old_reference = cp.state.references.take();
    cp.state.x = made.state(model, &old_state, &new);
    // the forces the work is counted from, per displacement dof in dof order: a new node's
    // are nil (no load acts inside the medium)
    let old_u: Vec<usize> = (0..model.dofs.n_dofs)
        .filter(|&d| model.dofs.field[d] == crate::dofs::Field::U)
        .collect();
    let f_of: std::collections::HashMap<usize, f64> = old_u
        .iter()
        .copied()
        .zip(cp.state.totals.f_last.iter().copied())
        .collect();
    cp.state.totals.f_last = (0..new.dofs.n_dofs)
        .filter(|&d| new.dofs.field[d] == crate::dofs::Field::U)
        .map(|d| match from[d] {
            NONE => 0.0,
            o => f_of.get(&(o as usize)).copied().unwrap_or(0.0),
        })
        .collect();
    // the point history: the solids' blocks keep theirs (a medium with stored heat or a mass
    // is not made again); the medium's friction carries on what it transmitted
    let terms = crate::assembly::history_terms(model);
    let of = |t: Term| terms.iter().position(|&o| o == t);
    let mut old_history = std::mem::take(&mut cp.state.point_history);
    let old_friction: Vec<&[f64]> = (0..model.friction_blocks.len())
        .map(|f| &old_history[of(Term::Friction(f)).expect("a friction slab")][..])
        .collect();
    let mut friction = match new.rubs() {
        false => Vec::new(),
        true => remake::carried_friction(
            model,
            old_reference.as_deref().unwrap_or(&model.cell_reference),
            &old_state,
            &old_friction,
            &new,
            &cp.state.x,
        )
        .map_err(|e| SolveError::Setup(format!("the medium could not be made again: {e}")))?,
    }
    .into_iter();
    cp.state.point_history = (crate::assembly::history_terms(&new).into_iter())
        .map(|t| match t {
            Term::Friction(_) => friction.next().expect("a carried friction slab"),
            t => std::mem::take(&mut old_history[of(t).expect("a solid's slab kept")]),
        })
        .collect();
    Ok((new, probes))
}

/// What changes the mesh a run goes on with.
enum Change {
    /// The friction layer joined again with this shift.
    Join(i64),
    /// The medium made again.
    Remake,
}

/// How stepping ended: at the end of the load path or at a stop (the run's summary), or where
/// the mesh is to change (the run, and how).
#[allow(clippy::large_enum_variant)] // made once per run or change, moved at once
enum Stepped<'a> {
    Ended(Summary),
    Changed(Run<'a>, Change),
}

/// Step until the end of the load path, a stop, or an accepted step after which `change`
/// asks for the mesh to change; with `first`, `change` is asked of the state the run starts
/// from too (a restart, whose run was stopped before it could ask).
fn step_until<'a>(
    mut run: Run<'a>,
    first: bool,
    mut change: impl FnMut(&mut Run) -> Option<Change>,
) -> Result<Stepped<'a>, SolveError> {
    if let Some(c) = (first && !run.done()).then(|| change(&mut run)).flatten() {
        return Ok(Stepped::Changed(run, c));
    }
    while !run.done() {
        if run.ranks().max(f64::from(u8::from(interrupted()))) > 0.0 {
            return run.interrupt().map(Stepped::Ended);
        }
        run.step()?;
        if let Some(c) = (!run.done()).then(|| change(&mut run)).flatten() {
            return Ok(Stepped::Changed(run, c));
        }
    }
    run.complete().map(Stepped::Ended)
}

/// Step until the end of the load path, or a stop.
fn step_to_end(run: Run) -> Result<Summary, SolveError> {
    match step_until(run, false, |_| None)? {
        Stepped::Ended(summary) => Ok(summary),
        Stepped::Changed(..) => unreachable!("nothing asked for the mesh to change"),
    }
}

#[cfg(test)]
mod tests {
    //! The accept/reject logic of a run, against an engine whose failures are scripted: a
    //! failure a smaller step may mend cuts the step, one it cannot ends the run with its
    //! summary written, and a run that keeps failing stops below the minimum step. Each run
    //! keeps what it accepted, and a restart from its checkpoint ends where an unbroken run
    //! ends.

    use super::*;
    use crate::dofs::Field;
    use crate::solver::linear::{Factorization, LinearSolver};
    use crate::solver::newton::StepReport;
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// Which factorisation (counted from 0 over the run) fails, and how.
    type Script = fn(usize) -> Option<LinearError>;

    /// A real solver whose factorisations fail as the script says.
    struct Scripted {
        inner: LinearSolver,
        script: Script,
        calls: Arc<AtomicUsize>,
    }

    impl Factorization for Scripted {
        fn factor(&mut self, values: &[f64]) -> Result<(), LinearError> {
            let call = self.calls.fetch_add(1, Ordering::Relaxed);
            match (self.script)(call) {
                Some(failure) => Err(failure),
                None => self.inner.factor(values),
            }
        }

        fn solve(&mut self, b: &mut [f64]) -> Result<usize, LinearError> {
            self.inner.solve(b)?;
            Ok(self.inner.krylov_last)
        }
    }

    /// The block scene's coarse mesh, as `--set` says it.
    fn coarse() -> Vec<(String, String)> {
        let params = ("mesh_options.params", "{ n = 4, m = 4, l = 1 }");
        vec![(params.0.to_string(), params.1.to_string())]
    }

    /// The block scene on a coarse mesh, solved into `target/unit-scratch/NAME` with the
    /// engine's failures scripted; the run's result and its folder.
    fn solve_scripted(name: &str, script: Script) -> (Result<Summary, SolveError>, PathBuf) {
        solve_scripted_from(name, script, None)
    }

    /// [`solve_scripted`], the mesh taken as changed under the initial state as `settle` says.
    fn solve_scripted_from(
        name: &str,
        script: Script,
        settle: Option<Settle>,
    ) -> (Result<Summary, SolveError>, PathBuf) {
        with_scripted_run(name, script, |mut run| {
            run.record_initial().and_then(|_| {
                if let Some(settle) = settle {
                    run.rejoined(settle);
                }
                step_to_end(run)
            })
        })
    }

    /// What `go` makes of a run of the block scene on a coarse mesh, into
    /// `target/unit-scratch/NAME`, with the engine's failures scripted; and the run's folder.
    fn with_scripted_run<R>(name: &str, script: Script, go: impl FnOnce(Run) -> R) -> (R, PathBuf) {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let out = root.join("target/unit-scratch/driver").join(name);
        let _ = std::fs::remove_dir_all(&out);
        let case = Case::read(&root.join("cases/block.toml"))
            .and_then(|c| c.with_sets(&coarse()))
            .unwrap();
        let opts = SolveOptions {
            out_dir: Some(out.clone()),
            quiet: true,
            ..Default::default()
        };
        let mut folder = RunFolder::open(&out).unwrap();
        let (mut model, probes, staged) = checked_model(&case, &out, true).unwrap();
        take_folder(&mut folder, &mut model, staged).unwrap();
        let start = Instant::now();
        let mut run = Run::new(
            &case,
            &model,
            &probes,
            Some(folder),
            out.clone(),
            &opts,
            start,
        )
        .unwrap();
        let calls = Arc::new(AtomicUsize::new(0));
        run.wrap_solvers(|inner| {
            let kind = inner.kind;
            let scripted = Scripted {
                inner,
                script,
                calls: calls.clone(),
            };
            LinearSolver::with(kind, Box::new(scripted))
        });
        (go(run), out)
    }

    fn summary_in(dir: &Path) -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
    }

    fn history_rows(dir: &Path) -> usize {
        std::fs::read_to_string(dir.join("history.csv"))
            .unwrap()
            .lines()
            .count()
            - 1
    }

    fn gap(s: &Summary) -> f64 {
        s.probes["gap"]
    }

    #[test]
    fn a_failure_a_smaller_step_may_mend_cuts_the_step_and_the_run_goes_on() {
        let (clean, _) = solve_scripted("clean", |_| None);
        let clean = clean.unwrap();
        assert!(clean.converged && clean.rejected_steps == 0);
        // the 4th and 9th factorisations fail as a singular tangent would
        let (cut, dir) = solve_scripted("cut", |k| {
            (k == 3 || k == 8).then(|| LinearError::Factor("scripted".into()))
        });
        let cut = cut.unwrap();
        assert!(cut.converged, "{}", cut.message);
        assert_eq!(cut.rejected_steps, 2);
        assert!(cut.message.contains("2 rejected attempts") && cut.message.contains("scripted"));
        assert_eq!(cut.lambda, 1.0);
        // each rejected attempt left nothing behind: one history row per accepted step
        assert_eq!(history_rows(&dir), cut.load_steps + 1);
        // the same end state, by another path (hyperelastic: the path does not matter)
        let rel = (gap(&cut) - gap(&clean)).abs() / gap(&clean);
        assert!(rel < 1e-6, "gap {} against {}", gap(&cut), gap(&clean));
    }

    /// The first step from a mesh changed under the state and not settled (a medium made
    /// again, `Settle::Deferred`) that fails is tried again at its length once the mechanics
    /// are settled; failing from a settled state, it is cut.
    #[test]
    fn a_step_failing_from_an_unsettled_remake_is_tried_again_settled_not_cut() {
        let (clean, _) = solve_scripted("settled-clean", |_| None);
        let clean = clean.unwrap();
        // the first step's first factorisation (the first two are the initial state's)
        let fail_first = |k| (k == 2).then(|| LinearError::Factor("scripted".into()));
        for (settle, cut) in [(Settle::Deferred, false), (Settle::Remade, true)] {
            let (run, _) = solve_scripted_from("settled-retry", fail_first, Some(settle));
            let run = run.unwrap();
            assert!(run.converged, "{}", run.message);
            assert_eq!(run.rejected_steps, 1, "{settle:?}");
            // a cut step takes more steps to the end
            assert_eq!(
                run.load_steps > clean.load_steps,
                cut,
                "{settle:?}: {} steps",
                run.load_steps
            );
            let rel = (gap(&run) - gap(&clean)).abs() / gap(&clean);
            assert!(rel < 1e-6, "gap {} against {}", gap(&run), gap(&clean));
        }
    }

    #[test]
    fn an_engine_failure_ends_the_run_keeping_what_it_accepted_and_a_restart_finishes_it() {
        let (clean, _) = solve_scripted("unbroken", |_| None);
        let clean = clean.unwrap();
        let (broken, dir) = solve_scripted("broken", |k| {
            (k == 12).then(|| LinearError::Engine("scripted engine failure".into()))
        });
        let Err(SolveError::Linear(LinearError::Engine(m))) = broken else {
            panic!("an engine failure ends the run: {broken:?}");
        };
        assert_eq!(m, "scripted engine failure");
        // no step was cut for it, and the summary says why the run ended
        let s = summary_in(&dir);
        assert_eq!(s["converged"], false);
        assert_eq!(s["rejected_steps"], 0);
        assert!(
            s["message"]
                .as_str()
                .unwrap()
                .contains("scripted engine failure")
        );
        let steps = s["load_steps"].as_u64().unwrap() as usize;
        assert!(steps > 0 && s["lambda"].as_f64().unwrap() < 1.0);
        assert_eq!(history_rows(&dir), steps + 1);
        // a restart (with a sound engine) goes on from the last accepted step to the end
        let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/block.toml");
        let opts = SolveOptions {
            out_dir: Some(dir.clone()),
            quiet: true,
            restart: true,
            sets: coarse(),
            ..Default::default()
        };
        let resumed = run(&case, &opts).unwrap();
        assert!(resumed.converged);
        assert_eq!(resumed.load_steps, clean.load_steps);
        assert_eq!(history_rows(&dir), clean.load_steps + 1);
        assert_eq!(gap(&resumed).to_bits(), gap(&clean).to_bits());
    }

    #[test]
    fn a_run_that_keeps_failing_stops_below_the_minimum_step_with_its_steps_kept() {
        let (failed, dir) = solve_scripted("stuck", |k| {
            (k >= 10).then_some(LinearError::Krylov {
                iterations: 300,
                residual: 0.5,
            })
        });
        let Err(SolveError::StepTooSmall { steps, reason, .. }) = failed else {
            panic!("a run that cannot step stops: {failed:?}");
        };
        assert!(reason.contains("GMRES did not converge"), "{reason}");
        let s = summary_in(&dir);
        assert_eq!(s["converged"], false);
        assert_eq!(s["load_steps"].as_u64().unwrap() as usize, steps);
        assert!(s["rejected_steps"].as_u64().unwrap() > 3);
        assert_eq!(history_rows(&dir), steps + 1);
    }

    /// Where a step would stop the run and its medium may be made again there, the run asks
    /// for that instead, at the state it stands at, and will try the failed step again at its
    /// length; asked not to at that state, it stops.
    #[test]
    fn a_step_that_would_stop_the_run_asks_for_its_medium_made_again_once() {
        let (stopped, _) = with_scripted_run(
            "remake-to-go-on",
            |k| {
                (k >= 10).then_some(LinearError::Krylov {
                    iterations: 300,
                    residual: 0.5,
                })
            },
            |mut run| {
                run.record_initial().unwrap();
                run.remake_before_stopping(f64::NAN);
                // the last attempt's start and length, as the controller measures it
                let (mut t, mut length) = (0.0, 0.0);
                while !run.wants_remake() {
                    assert!(!run.done(), "the run asked for no remake");
                    let (start, target) = run.next_step();
                    (t, length) = (start, run.st.ctl.dt.min(target - start));
                    run.step().unwrap();
                }
                assert!(run.accepted() > 0 && run.next_step().0 == t);
                assert_eq!(run.st.ctl.dt, length);
                // asked once: the question cleared it
                assert!(!run.wants_remake());
                run.remake_before_stopping(t);
                loop {
                    if let Err(e) = run.step() {
                        break e;
                    }
                    assert!(!run.wants_remake());
                }
            },
        );
        let SolveError::StepTooSmall { hint, .. } = &stopped else {
            panic!("a run that cannot step stops: {stopped}");
        };
        assert!(
            hint.contains("on the medium made again at this state too"),
            "{hint}"
        );
    }

    /// A step taken by continuation solves a one-way scene's mechanics by continuation and
    /// its heat, linear in θ, by Newton: one update, where continuation's shifted solves
    /// would creep (the block's first step: the same state as Newton's to round-off).
    #[test]
    fn a_step_by_continuation_solves_the_heat_of_a_one_way_scene_by_newton() {
        let (rows, _) = with_scripted_run(
            "continued-heat",
            |_| None,
            |mut run| {
                run.record_initial().unwrap();
                let (_, target) = run.next_step();
                let (newton, by_newton) = run.st.attempt(target).unwrap();
                run.st.asm.restore();
                let (continued, by_continuation) = run.st.attempt_continued(target).unwrap();
                let theta = |x: &[f64]| -> Vec<f64> {
                    let dofs = &run.st.model.dofs;
                    (0..x.len())
                        .filter(|&d| dofs.field[d] == Field::Theta)
                        .map(|d| x[d])
                        .collect()
                };
                let (a, b) = (theta(&newton), theta(&continued));
                let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let differ = a
                    .iter()
                    .zip(&b)
                    .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                assert!(
                    scale > 0.0 && differ <= 1e-8 * scale,
                    "θ differs by {differ}"
                );
                // the heat's rows: those where the mechanics' residual is not assembled
                let heat = |r: &StepReport| r.history.iter().filter(|h| h[0] == 0.0).count();
                (heat(&by_newton), heat(&by_continuation))
            },
        );
        assert!(rows.0 > 0 && rows.1 == rows.0, "heat rows {rows:?}");
    }
}
