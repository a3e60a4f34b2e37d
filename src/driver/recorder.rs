//! The recorder: what each accepted step leaves behind, on the rank that writes (rank 0):
//! its `.vtu` (when `[output] every` asks), its row of `history.csv`, the checkpoint, its line
//! on the console and the progress bar; at the end, `summary.json`. It reads the stepper's
//! state and the run's accounts, and changes neither.

use super::SolveError;
use super::SolveOptions;
use super::account::Accounts;
use super::checkpoint::{self, Checkpoint};
use super::last_words::{self, Words};
use super::records::{
    Balances, FORCE_KEYS, HistoryLayout, Reactions, StepRow, Summary, contact_ratio, flow,
    peak_memory_mb,
};
use super::state::{Files, RunState, Totals};
use super::stepper::Stepper;
use super::strategy::Strategy;
use crate::case::Case;
use crate::dofs::Field;
use crate::files::Staged;
use crate::model::Model;
use crate::output::contact::ContactFaces;
use crate::output::history::Mark;
use crate::output::probes::Probe;
use crate::output::{History, OutputError, RunFolder, Series, werr, write_atomic};
use crate::post::friction_cells;
use crate::solver::newton::StepReport;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub(super) struct Recorder<'a> {
    probes: &'a [Probe],
    opts: &'a SolveOptions,
    /// The output folder, on the rank that writes (rank 0); `None` on the others.
    folder: Option<RunFolder>,
    out_dir: PathBuf,
    /// When this recorder started counting (the run's start, or its resumption from a
    /// checkpoint), and the wall seconds the run had run before that.
    start: Instant,
    before: f64,
    series: Series,
    layout: HistoryLayout,
    history: History,
    pub(super) summary: Summary,
    pb: indicatif::ProgressBar,
    /// `[output] every`, and the last step written.
    every: usize,
    written: Option<usize>,
    /// What the results depend on (case, mesh), for the checkpoints.
    fingerprint: (String, String),
    /// Wall seconds spent writing the run's files.
    writing: f64,
}

impl<'a> Recorder<'a> {
    /// The records of a run of `case` on `model` with the stepper `st` (its solvers named in
    /// the summary), into `out_dir`; nothing is written yet.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        case: &Case,
        model: &Model,
        st: &Stepper,
        strategy: Strategy,
        probes: &'a [Probe],
        mut folder: Option<RunFolder>,
        out_dir: PathBuf,
        opts: &'a SolveOptions,
        start: Instant,
    ) -> Result<Recorder<'a>, SolveError> {
        let contact = ContactFaces::of(model);
        let layout = HistoryLayout::new(model, probes, case.file.time.is_some(), contact.as_ref());
        for name in [
            "history.csv",
            "summary.json",
            &format!("{}.pvd", case.name()),
        ] {
            if let Some(folder) = &mut folder {
                folder.record(name)?;
            }
        }
        let history = History::new(&out_dir.join("history.csv"), &layout.columns);
        let solver = st.solver();
        let mut summary = Summary::start(case, model, solver.kind, strategy, &layout, &out_dir);
        summary.ranks = st.asm.ranks.size;
        summary.engine = solver.engine().into();
        summary.petsc_solver = solver.engine_solver();
        let mut series = Series::new(&out_dir, &case.name(), model, contact);
        if let Some(d) = st.asm.distribution().filter(|d| d.partition.parts > 1) {
            series = series.in_parts(model, d);
        }
        Ok(Recorder {
            probes,
            opts,
            folder,
            out_dir,
            start,
            before: 0.0,
            series,
            layout,
            history,
            summary,
            pb: progress_bar(opts.quiet),
            every: *case.file.output.every.get_ref() as usize,
            written: None,
            fingerprint: (
                checkpoint::case_fingerprint(case),
                checkpoint::mesh_fingerprint(&model.mesh),
            ),
            writing: 0.0,
        })
    }

    /// The run's output folder.
    pub(super) fn out_dir(&self) -> &Path {
        &self.out_dir
    }

    /// Wall seconds since the run started.
    pub(super) fn wall(&self) -> f64 {
        self.before + self.start.elapsed().as_secs_f64()
    }

    /// The probes at the stepper's last accepted state, whose reactions are `reactions`.
    fn probe_values(&self, st: &Stepper, reactions: &Reactions) -> Vec<f64> {
        let reaction = |g: &str, c: usize| flow(reactions, g, FORCE_KEYS[c]);
        (self.probes.iter())
            .map(|p| p.eval(&st.model.mesh, &st.model.dofs, &st.x, &reaction))
            .collect()
    }

    /// The loaded groups' columns at the stepper's last accepted state, whose reactions are
    /// `reactions`: F_t/F_n along the contact's normal of the groups that have a column for
    /// it, then their displacements.
    fn group_columns(&self, st: &Stepper, reactions: &Reactions) -> Vec<f64> {
        let mut out = Vec::new();
        let (groups, contact) = (&self.layout.contact, self.series.contact());
        if let Some(contact) = contact.filter(|_| !groups.is_empty()) {
            // an accepted state's cells all have a stress; were one not to, the ratios are
            // unknown
            let t = contact.at(st.model, &st.asm.reference, &st.x, None);
            out.extend(groups.iter().map(|(g, body)| match &t {
                Ok(t) => {
                    let r = std::array::from_fn(|c| flow(reactions, g, FORCE_KEYS[c]));
                    contact_ratio(contact, *body, t, r, st.model.mesh.dim)
                }
                Err(_) => f64::NAN,
            }));
        }
        for (_, _, dofs) in &self.layout.moved {
            out.push(dofs.iter().map(|&d| st.x[d]).sum::<f64>() / dofs.len().max(1) as f64);
        }
        out
    }

    /// What an accepted step leaves: its `.vtu` (when `[output] every` asks), its history row,
    /// the checkpoint, and its progress line; with `said` (under a launcher) also the summary
    /// that says it should the run be stopped here (`last_words.rs`).
    pub(super) fn step(
        &mut self,
        st: &Stepper,
        accounts: &Accounts,
        row: &StepRow,
        rep: &StepReport,
        said: Option<String>,
    ) -> Result<(), SolveError> {
        crate::files::placing();
        // the step's file first (when [output] every asks for it): a row never announces a
        // file that is not there yet
        if st.ctl.accepted.is_multiple_of(self.every) {
            self.timed(|rec| rec.write_vtu(st))?;
        }
        self.timed(|rec| rec.record(st, row, &accounts.totals, said))?;
        self.report_step(st, accounts, row, rep);
        Ok(())
    }

    /// The records of the stepper's state (the initial one, or an accepted step's), its `.vtu`
    /// written and taken back should the launcher end the run first (`files::placing`): its
    /// history row and the checkpoint; with `said` (under a launcher) also the summary that
    /// says it should the run be stopped here (`last_words.rs`). What takes long (the
    /// checkpoint, the summary) is made first; what replaces the previous state's records
    /// (the history row, the `.pvd`, the checkpoint, the words) is put in place under the
    /// words, so the watcher never speaks between a step's files. (The caller counts its time
    /// as the run's writing, [`Recorder::timed`].)
    pub(super) fn record(
        &mut self,
        st: &Stepper,
        row: &StepRow,
        totals: &Totals,
        said: Option<String>,
    ) -> Result<(), SolveError> {
        let reactions = &totals.reactions;
        let row = self.folder.is_some().then(|| {
            let values = self.layout.row(
                row,
                &self.probe_values(st, reactions),
                reactions,
                &self.group_columns(st, reactions),
            );
            self.history.make_row(&values)
        });
        let mark = row.as_ref().map_or(self.history.mark(), |r| r.mark);
        let checkpoint = self.stage_checkpoint(st, totals, mark)?;
        let words = said.map(|said| (self.words(st, totals, &said), said));
        if let Some(delay) = records_delay() {
            std::thread::sleep(delay);
        }
        let mut held = last_words::hold();
        if let Some(row) = row {
            self.history.write_row(row)?;
        }
        self.series.list()?;
        if let Some(c) = checkpoint {
            let path = c.path().to_owned();
            c.commit().map_err(|e| werr(&path, e))?;
        }
        if let Some(folder) = &mut self.folder {
            // a step taken: the previous run's files go for good
            if st.ctl.accepted > 0 {
                folder.settle()?;
            }
        }
        if let Some((summary, said)) = words {
            *held = Some(Words {
                summary,
                // the folder as it now stands (settled above)
                folder: self.folder.as_ref().map(RunFolder::leaving),
                said,
            });
        }
        crate::files::placed();
        Ok(())
    }

    /// `f` on the recorder, its wall time counted as the run's writing.
    pub(super) fn timed<R>(&mut self, f: impl FnOnce(&mut Self) -> R) -> R {
        let started = Instant::now();
        let r = f(self);
        self.writing += started.elapsed().as_secs_f64();
        r
    }

    /// The run's state as a checkpoint (on several ranks every rank takes part).
    pub(super) fn checkpoint(&self, st: &Stepper, totals: &Totals) -> Checkpoint {
        self.checkpoint_marked(st, totals, self.history.mark())
    }

    /// As [`Recorder::checkpoint`], with the history marked at `history`.
    fn checkpoint_marked(&self, st: &Stepper, totals: &Totals, history: Mark) -> Checkpoint {
        Checkpoint {
            version: checkpoint::VERSION,
            case: self.fingerprint.0.clone(),
            mesh: self.fingerprint.1.clone(),
            state: RunState {
                x: st.x.clone(),
                point_history: st.asm.whole_history(st.model),
                references: (st.asm.absorbs(st.model)).then(|| st.asm.reference.blocks().to_vec()),
                clock: st.ctl.clock(),
                newton: st.newton.tally(),
                totals: totals.clone(),
                files: Files {
                    series: self.series.written().len(),
                    written: self.written,
                    history,
                    seconds: self.writing,
                },
                wall: self.wall(),
            },
        }
    }

    /// `restart.json` of the stepper's state, with the history marked at `history`, written
    /// and synced under its temporary name, to be put in place with the history row it marks.
    fn stage_checkpoint(
        &mut self,
        st: &Stepper,
        totals: &Totals,
        history: Mark,
    ) -> Result<Option<Staged>, SolveError> {
        if self.folder.is_none() {
            // on several ranks each holds its own cells' history per point, gathered by
            // every rank before the first rank writes it
            if !st.asm.ranks.is_serial() {
                st.asm.whole_history(st.model);
            }
            return Ok(None);
        }
        let cp = self.checkpoint_marked(st, totals, history);
        if let Some(folder) = &mut self.folder {
            folder.record(checkpoint::FILE)?;
        }
        let path = Checkpoint::path(&self.out_dir);
        let staged =
            crate::files::stage(&path, cp.to_json().as_bytes()).map_err(|e| werr(&path, e))?;
        Ok(Some(staged))
    }

    /// Whether the folder holds a previous run's results aside, to come back unless this run
    /// takes a load step.
    pub(super) fn holds_previous(&self) -> bool {
        self.folder.as_ref().is_some_and(RunFolder::holds_previous)
    }

    /// The output folder, handed on (to the run that goes on on a mesh joined again).
    pub(super) fn take_folder(&mut self) -> Option<RunFolder> {
        self.folder.take()
    }

    /// Continue the records of a run resumed from a checkpoint: the files it had written
    /// (checked against it: one verdict for every rank), and the wall seconds it had run.
    pub(super) fn resume(
        &mut self,
        st: &Stepper,
        files: Files,
        wall: f64,
    ) -> Result<(), SolveError> {
        let checkpoint = Checkpoint::path(&self.out_dir);
        let damaged = |file: &Path, what: String| {
            SolveError::Setup(format!(
                "cannot restart from {}: {} does not go with it: {what}; run without --restart \
                 to start over",
                checkpoint.display(),
                file.display()
            ))
        };
        let resumed = self
            .series
            .resume(files.series)
            .map_err(|e| damaged(self.series.pvd(), e))
            .and_then(|_| match self.folder.is_some() {
                true => (self.history.resume(files.history))
                    .map_err(|e| damaged(&self.out_dir.join("history.csv"), e)),
                false => Ok(()),
            });
        (st.asm.ranks).agree(resumed, SolveError::to_string, |text| {
            SolveError::Setup(text.into())
        })?;
        self.written = files.written;
        self.writing = files.seconds;
        // wall seconds go on from where the run stopped, counted from now (an `Instant` moved
        // back that far would not exist on a machine started more recently than that: the
        // run's seconds then began again at 0, below its assembly's and solver's); a run that
        // goes on in this process after a remake resumes so too, from its own start
        self.before = wall;
        self.start = Instant::now();
        Ok(())
    }

    /// The step's line (with `--verbose`, the Newton table too) and the progress bar.
    fn report_step(&self, st: &Stepper, accounts: &Accounts, row: &StepRow, rep: &StepReport) {
        let fmt_j = |j: f64| {
            if j.is_finite() {
                format!("{j:.3e}")
            } else {
                "-".into()
            }
        };
        if self.opts.verbose {
            let line = format!(
                "step {:3}  {}  Δλ {:.2e}  its {:2}  {:.2} s  min J solid {} medium {}",
                row.step,
                st.clock_text(row.time),
                row.dlambda,
                row.iterations,
                row.wall,
                fmt_j(row.min_J_solid),
                fmt_j(row.min_J_medium)
            );
            // the Newton table: largest relative field residual per iteration
            let table: Vec<String> = rep
                .history
                .iter()
                .map(|h| format!("{:.0e}", h.iter().fold(0.0f64, |a, &b| a.max(b))))
                .collect();
            self.say(&format!("{line}  [{}]", table.join(" ")));
        } else if !self.opts.quiet && self.pb.is_hidden() {
            // no progress bar (not a terminal, e.g. a log file): one short line per step
            self.say(&format!(
                "step {:3}  {}  its {:2}  {:.2} s",
                row.step,
                st.clock_text(row.time),
                row.iterations,
                row.wall
            ));
        }
        self.pb
            .set_position((row.time / st.ctl.end * 1000.0) as u64);
        self.pb.set_message(format!(
            "step {} its {}",
            st.ctl.accepted, accounts.totals.iterations
        ));
    }

    /// The `.vtu` of the stepper's last accepted state, once: on several ranks each rank's
    /// part, the first rank's `.pvtu` putting them together, and one error for all if any
    /// rank's failed.
    pub(super) fn write_step(&mut self, st: &Stepper) -> Result<(), SolveError> {
        self.timed(|rec| {
            rec.write_vtu(st)?;
            Ok(rec.series.list()?)
        })
    }

    fn write_vtu(&mut self, st: &Stepper) -> Result<(), SolveError> {
        let step = st.ctl.accepted;
        if self.written == Some(step) {
            return Ok(());
        }
        let mut written = Ok(());
        if let Some(folder) = &mut self.folder {
            for file in self.series.files(step) {
                written = written.and(folder.record(&file));
            }
        }
        let model = st.model;
        let friction = (model.physics.friction).then(|| friction_cells(model, &st.asm, &st.x));
        if let Some(folder) = &self.folder {
            // the other ranks' parts too are taken back should the launcher end the run
            // before the step is recorded
            let files = self.series.files(step).into_iter();
            crate::files::placing_elsewhere(files.map(|f| folder.dir().join(f)));
        }
        let written = written.and_then(|_| {
            self.series.write(
                model,
                step,
                &st.asm.reference,
                &st.x,
                st.ctl.t,
                friction.as_deref(),
            )
        });
        let ranks = st.asm.ranks;
        let agree = |r| {
            ranks.agree(r, OutputError::to_string, |t| {
                OutputError::OtherRank(t.into())
            })
        };
        // every rank's part on disk before the first rank's .pvtu names them
        agree(written)?;
        agree(self.series.collect())?;
        self.written = Some(step);
        Ok(())
    }

    /// The progress bar cleared, before a run's last lines.
    pub(super) fn clear_bar(&self) {
        self.pb.finish_and_clear();
    }

    /// Fill the summary from the run's state and write `summary.json`.
    pub(super) fn finish(
        &mut self,
        st: &Stepper,
        totals: &Totals,
        converged: bool,
        message: String,
    ) -> Result<(), SolveError> {
        // the last state reached always has its file
        self.write_step(st)?;
        // from here the run writes its own summary: no last words in its place
        last_words::forget();
        self.summary = self.summary_at(st, totals, converged, message);
        if let (Some(open), Some(_)) = (open_balances(&self.summary.balances), &self.folder) {
            self.say(&open);
        }
        let s = &mut self.summary;
        if let Some(folder) = &mut self.folder {
            let json = serde_json::to_string_pretty(&*s).expect("serialisable");
            write_atomic(&self.out_dir.join("summary.json"), json.as_bytes())?;
            // a run that took a load step has results of its own, even if it then failed:
            // they replace the previous run's; one that did not (it failed or was stopped at
            // λ = 0) leaves the previous run's results as they were, where there are any
            if st.ctl.accepted > 0 || !folder.holds_previous() {
                folder.settle()?;
            }
        }
        Ok(())
    }

    /// Under a launcher that kills its ranks soon after a signal (`mpirun`): the summary
    /// this run would write if stopped at the stepper's state, saying `said`, for
    /// `last_words.rs` to write should the launcher kill the run before it can: where and
    /// what, on the rank that writes the run's files. Every rank takes part (the summary
    /// gathers the ranks' memory).
    fn words(&self, st: &Stepper, totals: &Totals, said: &str) -> Option<(PathBuf, String)> {
        let summary = self.summary_at(st, totals, false, format!("interrupted: {said}"));
        self.folder.as_ref().map(|_| {
            let json = serde_json::to_string_pretty(&summary).expect("serialisable");
            (self.out_dir.join("summary.json"), json)
        })
    }

    /// The summary of the stepper's state, with `converged` and `message` (on several ranks
    /// every rank takes part: it gathers their peak memory).
    fn summary_at(
        &self,
        st: &Stepper,
        totals: &Totals,
        converged: bool,
        message: String,
    ) -> Summary {
        let (model, ctl, tot, spent) = (st.model, &st.ctl, totals, st.newton.spent);
        let wall = self.wall();
        let probes = self.probe_values(st, &tot.reactions);
        let mut summary = self.summary.clone();
        let s = &mut summary;
        s.converged = converged;
        s.message = message;
        s.lambda = model.path.lambda(ctl.t);
        s.time = ctl.t;
        s.load_steps = ctl.accepted;
        s.rejected_steps = ctl.rejected;
        s.continued_steps = tot.continued;
        s.balanced_steps = tot.balanced_only;
        s.newton_iterations = tot.iterations;
        s.rejected_iterations = spent.iterations - tot.iterations;
        s.linear_solves = spent.updates;
        s.factorisations = spent.factorisations;
        s.wall_seconds = wall;
        s.assembly_seconds = spent.assembly + tot.t_reactions;
        s.solver_seconds = spent.solve;
        s.factorisation_seconds = spent.parts.map(|p| p.factorising);
        s.factor_solve_seconds = spent.parts.map(|p| p.applying);
        s.output_seconds = self.writing;
        s.peak_memory_mb = peak_memory_mb();
        let ranks = st.asm.ranks;
        if !ranks.is_serial() {
            let mut each = vec![0.0; ranks.size];
            each[ranks.rank] = s.peak_memory_mb.unwrap_or(f64::NAN);
            ranks.sum_into(&mut each);
            s.peak_memory_mb_ranks = Some(each);
        }
        s.probes = (self.probes.iter().map(|p| p.name.clone()))
            .zip(probes)
            .collect();
        s.reactions = tot.reactions.clone();
        (s.min_J_solid, s.min_J_medium) = tot.min_J;
        s.min_J = match tot.min_J {
            (Some(a), Some(b)) => a.min(b),
            (a, b) => a.or(b).unwrap_or(1.0),
        };
        s.energy = tot.energy;
        s.external_work = tot.work;
        s.krylov_iterations = tot.krylov;
        s.tangents_skipped = tot.tangents_skipped;
        s.heat_stored = tot.heat_stored;
        s.heat_in = tot.heat_in;
        s.corners_through_medium = tot.corners_through;
        s.friction_layer_joins = tot.layer_joins;
        s.medium_remade = tot.medium_remakes;
        if tot.medium_remakes > 0 {
            // measured where the mechanics are settled after each remake (`settle`)
            let measured = tot.remake_force_change.is_some();
            s.medium_remade_force_change = tot.remake_force_change;
            s.medium_remade_heat_change = tot.remake_heat_change;
            s.medium_remade_seconds = Some(tot.remake_seconds);
            s.medium_remade_unsettled = measured.then_some(tot.remake_unsettled);
            s.medium_remade_to_go_on = Some(tot.remade_to_go_on);
        }
        s.medium_edge_reached = tot.edge_reached_at.clone();
        // 0 until the first join
        s.heat_joined = (self.layout.joined).then(|| tot.heat_joined.unwrap_or(0.0));
        s.largest_displacement = tot.largest_displacement;
        // heat below what Newton leaves as round-off at every node over the run's time
        let heat_floor = model.dofs.n_nodes as f64 * st.newton.floor(Field::Theta) * ctl.t;
        s.balances = balances(s, tot, st.newton.tol, heat_floor, st.model);
        summary
    }

    /// A line above the progress bar, or on stderr when the bar is hidden (not a terminal).
    pub(super) fn say(&self, line: &str) {
        if self.pb.is_hidden() {
            crate::note!("{line}");
        } else {
            self.pb.println(line);
        }
    }
}

/// For the tests of what a launcher's kill leaves (`last_words.rs`): how long each state's
/// records wait after their new files are written, before they are put in place, as on a
/// disk that takes that long; `TMC_RECORDS_DELAY_MS`, unset in any real run.
fn records_delay() -> Option<std::time::Duration> {
    static DELAY: std::sync::OnceLock<Option<std::time::Duration>> = std::sync::OnceLock::new();
    *DELAY.get_or_init(|| {
        let ms = std::env::var("TMC_RECORDS_DELAY_MS").ok()?.parse().ok()?;
        Some(std::time::Duration::from_millis(ms))
    })
}

/// The progress bar over the run's (pseudo-)time, hidden with `--quiet`.
fn progress_bar(quiet: bool) -> indicatif::ProgressBar {
    if quiet {
        return indicatif::ProgressBar::hidden();
    }
    let pb = indicatif::ProgressBar::new(1000);
    pb.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} λ {bar:30} {percent:>3}%  {msg}  [{elapsed_precise}]",
        )
        .expect("valid template"),
    );
    pb
}

/// The run's balances at its end: the force and steady heat imbalances its accepted states
/// kept, and a transient scene's heat balance, `heat_stored` against `heat_in` +
/// `friction_heat` + `heat_joined`, over the largest of them (at least `floor`, the heat
/// that is round-off); held to Newton's `tol`.
fn balances(s: &Summary, tot: &Totals, tol: f64, floor: f64, model: &Model) -> Balances {
    let heat = match s.heat_stored.zip(s.heat_in) {
        Some((stored, supplied)) => {
            let made = s.friction_heat.unwrap_or(0.0);
            let joined = s.heat_joined.unwrap_or(0.0);
            let size = [stored, supplied, made, joined]
                .iter()
                .fold(floor, |a, v| a.max(v.abs()));
            (size > 0.0).then(|| (stored - supplied - made - joined).abs() / size)
        }
        None => Totals::relative(tot.heat_imbalance),
    };
    let force = Totals::relative(tot.force_imbalance);
    let moved = (!model.dofs.u.is_empty()).then(|| s.largest_displacement / model.d);
    let unsupported = tot.overhang.clone();
    Balances::judged(
        force,
        heat,
        moved,
        unsupported,
        Balances::tolerance_for(tol),
    )
}

/// A warning naming the balances a run left open, if any.
fn open_balances(b: &Balances) -> Option<String> {
    let open: Vec<String> = (b.open.iter())
        .filter(|name| *name == "force" || *name == "heat")
        .map(|name| {
            let value = match name.as_str() {
                "force" => b.force,
                _ => b.heat,
            };
            format!("{name} balance open by {:.1e}", value.unwrap_or(f64::NAN))
        })
        .collect();
    let balances = (!open.is_empty()).then(|| {
        format!(
            "warning: {} of the flows it balances (tolerance {:.0e}): the answers are not \
             an equilibrium; a tighter [steps] tol, or `tmc check`, may say why \
             (summary.json: balances)",
            open.join(", "),
            b.tolerance
        )
    });
    let moved = (b.open.iter().any(|name| name == "moved")).then(|| {
        format!(
            "warning: a node moved {:.1} times the mesh's extent, out of the scene the mesh \
             draws (the step's warning names it; summary.json: balances.moved)",
            b.moved.unwrap_or(f64::NAN)
        )
    });
    let unsupported = b.unsupported.as_ref().map(|at| {
        format!(
            "warning: {at} slid past the end of the face its friction layer slides on: there \
             it rests on the layer's stretched cells and on no face, and the forces are the \
             medium's, not a contact's; a longer face to slide on, or a shorter slide, keeps \
             it on its layer (summary.json: balances.unsupported)"
        )
    });
    let said: Vec<String> = [balances, moved, unsupported]
        .into_iter()
        .flatten()
        .collect();
    (!said.is_empty()).then(|| said.join("\n"))
}
