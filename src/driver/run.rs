//! One run of `tmc solve` on a built model, made of three parts: the stepper (`stepper.rs`:
//! what a step is solved with, the controller, the last accepted state), the accounts
//! (`account.rs`: reactions, work, heat, the watches) and the recorder (`recorder.rs`: the
//! files and lines each accepted step leaves). [`super::solve_model`] drives it: attempt a
//! step, then accept or reject it, until done.

use super::account::{Accounts, joined_heat, point_totals};
use super::checkpoint::Checkpoint;
use super::recorder::Recorder;
use super::records::{Reactions, StepRow, Summary, flow_change};
use super::stepper::{Plan, Stepper, assemble_initial};
use super::strategy::describe;
use super::{Left, SolveError, SolveOptions};
use crate::case::Case;
use crate::model::Model;
use crate::output::RunFolder;
use crate::output::probes::Probe;
use crate::parallel::Ranks;
use crate::solver::newton::{StepFailure, StepReport};
use std::path::PathBuf;
use std::time::Instant;

#[cfg(test)]
use crate::solver::linear::LinearSolver;

pub(super) struct Run<'a> {
    opts: &'a SolveOptions,
    pub(super) st: Stepper<'a>,
    accounts: Accounts,
    rec: Recorder<'a>,
    /// Non-zero values held at full value from the start, as `uy = -0.2 on "top"`.
    held_in_full: Vec<String>,
    /// What the run solves and how, and the plan's note, for [`Run::announce`].
    plan_said: Vec<String>,
    /// The medium was made again and its mechanics not settled, and no step has been taken
    /// from it yet ([`Settle::Deferred`]).
    unsettled: bool,
    /// Where a step would stop the run, the medium may be made again at its last accepted
    /// state instead, except at this time (where it was made so last): see
    /// [`Run::remake_before_stopping`].
    remake_before_stopping: Option<f64>,
    /// A step that would have stopped the run asked for the medium to be made again.
    wants_remake: bool,
}

/// How the mechanics are brought to balance after the mesh changed under the state
/// ([`Run::rejoined`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Settle {
    /// A reconnected layer joined again: settled to the steps' own tolerance.
    Join,
    /// The medium made again, settled (`settle`; to [`crate::model::remake::SETTLED`]), what
    /// the remake changed measured there.
    Remade,
    /// The medium made again, not settled: the next step starts from the state as carried,
    /// and where it fails, the mechanics are settled (to [`crate::model::remake::SETTLED`])
    /// and the step tried again.
    Deferred,
}

impl<'a> Run<'a> {
    /// Choose strategy and solvers, and set up the records; nothing is written or said yet.
    pub(super) fn new(
        case: &'a Case,
        model: &'a Model,
        probes: &'a [Probe],
        folder: Option<RunFolder>,
        out_dir: PathBuf,
        opts: &'a SolveOptions,
        start: Instant,
    ) -> Result<Run<'a>, SolveError> {
        let plan = Plan::new(case, model, opts, crate::mesh::gmsh::opened())?;
        let plan_said = std::iter::once(describe(&model.physics, plan.strategy))
            .chain(plan.note.clone())
            .collect();
        let strategy = plan.strategy;
        let st = Stepper::new(case, model, plan);
        let rec = Recorder::new(
            case, model, &st, strategy, probes, folder, out_dir, opts, start,
        )?;
        Ok(Run {
            opts,
            st,
            accounts: Accounts::new(model),
            rec,
            held_in_full: case
                .file
                .bc
                .iter()
                .flat_map(|bc| bc.held_in_full())
                .collect(),
            plan_said,
            unsettled: false,
            remake_before_stopping: None,
            wants_remake: false,
        })
    }

    /// Say (unless quiet) what the run solves and how: once a run, not again on each mesh
    /// it goes on with after a layer is joined or the medium made again.
    pub(super) fn announce(&self) {
        if !self.opts.quiet {
            for line in &self.plan_said {
                crate::note!("{line}");
            }
        }
    }

    /// Record the initial state: step 0 of the series and of the history, and the forces the
    /// work is counted from.
    pub(super) fn record_initial(&mut self) -> Result<(), SolveError> {
        let iterations = self.settle_initial()?;
        // the initial state's files are taken back should the launcher end the run before
        // they are all written (`files::placing`)
        crate::files::placing();
        self.rec.write_step(&self.st)?;
        let st = &mut self.st;
        let model = st.model;
        let stats0 = assemble_initial(&mut st.asm, model, &st.x)?;
        // the state at λ = 0 (settled under what is held in full) is the first accepted one:
        // the points' history starts there (inertia: displaced, at rest)
        st.asm.commit();
        self.accounts.totals.energy = stats0.energy;
        let (r0, _) = (st.flows_assembled(0.0))
            .map_err(|e| SolveError::Setup(format!("the initial state is invalid: {e}")))?;
        let row = StepRow {
            min_J_solid: stats0.min_J_solid,
            min_J_medium: stats0.min_J_medium,
            energy: stats0.energy,
            iterations,
            wall: self.rec.wall(),
            ..StepRow::default()
        };
        self.accounts.totals.reactions = r0;
        let mut fe = vec![0.0; model.dofs.n_dofs];
        model.f_ext(model.path.lambda(0.0), &mut fe);
        self.accounts.totals.f_last = self.accounts.forces(&self.st, &fe);
        let said = super::last_words::wanted().then(|| self.stopped_here().to_string());
        let totals = &self.accounts.totals;
        (self.rec).timed(|rec| rec.record(&self.st, &row, totals, said))
    }

    /// A steady scene with values applied in full (`ramp = false`) starts from its equilibrium
    /// at λ = 0 under them (a temperature held at 100 conducts from the start: step 0 reports
    /// that heat, not 0); a transient scene starts from its initial condition. Returns the
    /// Newton iterations spent (0 when there is nothing to settle).
    fn settle_initial(&mut self) -> Result<usize, SolveError> {
        if self.st.transient_clock || self.held_in_full.is_empty() {
            return Ok(0);
        }
        match self.st.attempt(0.0) {
            Ok((x, rep)) => {
                self.st.x = x;
                self.accounts.count(&rep);
                Ok(rep.iterations)
            }
            Err(failure) if !failure.recoverable() => Err(self.fail(failure)?),
            // the linear solver's failure, not the values held in full: no advice on ramps
            Err(failure @ StepFailure::Linear(_)) => Err(self.fail(failure)?),
            Err(failure) => {
                self.rec.clear_bar();
                let err = SolveError::Setup(format!(
                    "the state at λ = 0 does not converge ({failure}) under the values applied \
                     in full from the first step (ramp = false): {}; let them grow with λ \
                     (ramp = true, or ramp = {{ NAME = true }} for one value)",
                    self.held_in_full.join(", ")
                ));
                self.finish(false, err.to_string())?;
                Err(err)
            }
        }
    }

    /// Every solver replaced by what `wrap` makes of it (a test's scripted engine).
    #[cfg(test)]
    pub(super) fn wrap_solvers(&mut self, wrap: impl Fn(LinearSolver) -> LinearSolver) {
        self.st.wrap_solvers(wrap);
    }

    /// The run's ranks (their decisions to stop are taken together).
    pub(super) fn ranks(&self) -> Ranks {
        self.st.ranks()
    }

    /// The pseudo-time of the last accepted state and of the next step's end.
    pub(super) fn next_step(&self) -> (f64, f64) {
        (self.st.ctl.t, self.st.ctl.target())
    }

    /// Whether the run stands at a vertex of its load path, before its end.
    pub(super) fn at_vertex(&self) -> bool {
        self.st.ctl.at_vertex()
    }

    /// Let the next step end at `until` at the latest.
    pub(super) fn cap_step(&mut self, until: f64) {
        self.st.ctl.cap(until);
    }

    /// The steps accepted so far, those before a restart or a change of mesh included.
    pub(super) fn accepted(&self) -> usize {
        self.st.ctl.accepted
    }

    /// Where a step would stop the run (Newton and continuation fail at the shortest step),
    /// end it instead to make its medium again at the last accepted state and try that step
    /// again on the new one ([`Run::wants_remake`]), unless the medium was made so at time
    /// `except` (once per state). A stall on the medium as it is may not be one on a new one.
    pub(super) fn remake_before_stopping(&mut self, except: f64) {
        self.remake_before_stopping = Some(except);
    }

    /// Whether a step that would have stopped the run asked for the medium to be made again
    /// (asked once: the question clears it).
    pub(super) fn wants_remake(&mut self) -> bool {
        std::mem::take(&mut self.wants_remake)
    }

    /// The attempts rejected so far.
    pub(super) fn rejected(&self) -> usize {
        self.st.ctl.rejected
    }

    /// Whether the run reached the end of its path.
    pub(super) fn done(&self) -> bool {
        self.st.ctl.done()
    }

    /// Attempt the controller's next step, then accept or reject it.
    pub(super) fn step(&mut self) -> Result<(), SolveError> {
        let target = self.st.ctl.target();
        match self.st.attempt(target) {
            Ok((trial, rep)) => self.accept(target, trial, rep),
            Err(failure) => self.reject(target, failure),
        }
    }

    /// Take a converged step: the stepper moves to it, the accounts add what it did, then the
    /// recorder writes its files and progress line.
    fn accept(&mut self, target: f64, trial: Vec<f64>, rep: StepReport) -> Result<(), SolveError> {
        let model = self.st.model;
        let dlambda = model.path.lambda(target) - model.path.lambda(self.st.ctl.t);
        self.unsettled = false;
        if rep.balanced_only {
            self.balanced_only(target, rep.iterations);
        }
        let (step, x_last) = self.st.advance(target, trial, rep.iterations);
        let warning = self.accounts.step(&mut self.st, &step, &x_last, &rep)?;
        // what the next step starts from, written to the checkpoint below
        (self.st.asm).absorb_closed_layers(self.st.model, &self.st.x);
        self.take_point_totals();
        if let Some(warning) = warning.filter(|_| !self.opts.quiet) {
            self.rec.say(&warning);
        }
        let summary = &self.rec.summary;
        let totals = &self.accounts.totals;
        let row = StepRow {
            step: self.st.ctl.accepted,
            lambda: step.lambda,
            dlambda,
            iterations: rep.iterations,
            residuals: rep.history.last().copied().unwrap_or([0.0; 3]),
            min_J_solid: rep.stats.min_J_solid,
            min_J_medium: rep.stats.min_J_medium,
            energy: rep.stats.energy,
            krylov: rep.krylov,
            halvings: rep.halvings,
            time: target,
            work: totals.work,
            heat: totals.heat_stored.zip(totals.heat_in),
            friction: summary
                .friction_work
                .map(|w| (w, summary.friction_heat.unwrap_or(0.0))),
            heat_joined: totals.heat_joined,
            kinetic_energy: summary.kinetic_energy,
            wall: self.rec.wall(),
        };
        let said = super::last_words::wanted().then(|| self.stopped_here().to_string());
        self.rec.step(&self.st, &self.accounts, &row, &rep, said)
    }

    /// A solid's node `node` stands past the end of the face its reconnected layer slides
    /// on, at the last accepted step: kept for the summary's balances, and said once.
    pub(super) fn overhangs(&mut self, node: usize) {
        let tot = &mut self.accounts.totals;
        if tot.overhang.is_some() {
            return;
        }
        let model = self.st.model;
        let at = crate::mesh::point_text(&model.mesh.coords[node], model.mesh.dim);
        let text = format!(
            "from step {} on, node {node} of the solid (at {at} in the undeformed mesh)",
            self.st.ctl.accepted
        );
        if !self.opts.quiet {
            self.rec.say(&format!(
                "warning: {text} stands past the end of the face its friction layer slides \
                 on: the layer is no longer joined, and the solid rests there on no face"
            ));
        }
        tot.overhang = Some(text);
    }

    /// What the points' committed history holds, into the summary.
    fn take_point_totals(&mut self) {
        let points = point_totals(&self.st);
        let s = &mut self.rec.summary;
        s.kinetic_energy = points.kinetic_energy;
        s.friction_work = points.friction_work;
        s.friction_heat = points.friction_heat;
    }

    /// End the run at its last accepted state to go on on a mesh whose reconnected layers are
    /// joined again: their cells take the slide into their references first. Returns the
    /// state as a checkpoint (the files written so far belong to it) and the output folder.
    pub(super) fn end_to_rejoin(mut self) -> (Checkpoint, Option<RunFolder>) {
        let totals = &mut self.accounts.totals;
        // the heat stored as the cells were (the accepted step counted it): `rejoined` adds
        // what it is as they are joined
        if let Some(stored) = totals.heat_stored {
            *totals.heat_joined.get_or_insert(0.0) -= stored;
        }
        let st = &mut self.st;
        st.asm.absorb_slide(st.model, &st.x);
        let cp = self.rec.checkpoint(&self.st, &self.accounts.totals);
        (cp, self.rec.take_folder())
    }

    /// A run resumed on a mesh changed under its state: a reconnected layer's cells joined
    /// again, or the medium made again, each starting from the state as it is.
    ///
    /// As `settle` says, the next step starts from the mechanics settled at the same loads
    /// (see [`Run::settle`]), or (a remake not settled) from the state as carried, whose
    /// imbalance the next step takes up with its own; where that step fails, the mechanics
    /// are settled then and the step tried again (see [`Run::reject`]).
    pub(super) fn rejoined(&mut self, settle: Settle) {
        let st = &mut self.st;
        st.asm.rejoined(st.model, &st.x);
        // the settling below keeps the temperature: the heat stored changes at the join only
        if let Some(stored) = joined_heat(&self.st) {
            *self.accounts.totals.heat_joined.get_or_insert(0.0) += stored;
        }
        self.unsettled = settle == Settle::Deferred;
        if !self.unsettled {
            self.settle(settle);
        }
    }

    /// The mechanics settled at the same loads (a step of no length: no inertia), or left as
    /// they are where that does not converge. The points' history stays as joined: whatever
    /// the settling slipped is the next step's slip, whose work that step makes heat over its
    /// length. A remake's settling where the medium asks for one (`settle`) that does not
    /// converge is counted, and said: the first time (unless quiet), or each time with `-v`;
    /// any other, with `-v` only.
    fn settle(&mut self, settle: Settle) {
        let to = match settle {
            Settle::Join => None,
            Settle::Remade | Settle::Deferred => Some(crate::model::remake::SETTLED),
        };
        let why = match self.st.settle_mechanics(to) {
            Ok((rep, continued)) => {
                self.accounts.totals.continued += usize::from(continued);
                self.accounts.totals.balanced_only += usize::from(rep.balanced_only);
                return self.accounts.count(&rep);
            }
            Err(why) => why,
        };
        let t = self.st.t_text(self.st.ctl.t);
        if self.opts.verbose {
            crate::note!(
                "  not settled at t = {t} on the new mesh ({why}); the next step starts from it \
                 as it is"
            );
        }
        if settle != Settle::Remade {
            return;
        }
        let tot = &mut self.accounts.totals;
        tot.remake_unsettled += 1;
        if tot.remake_unsettled == 1 && !self.opts.verbose && !self.opts.quiet {
            self.rec.say(&format!(
                "warning: the mechanics did not settle on the medium made again at t = {t} \
                 ({why}); the next step starts from it as it is (`-v` says each such remake; \
                 summary.json counts them, `medium_remade_unsettled`)"
            ));
        }
    }

    /// Each group's reaction and heat flow at the last accepted state over a step of no
    /// length (what the state itself transmits, nothing stored over a step), the history
    /// left as it was.
    pub(super) fn flows_at_rest(&mut self) -> Result<Reactions, SolveError> {
        let st = &mut self.st;
        let t = st.ctl.t;
        let step = st.model.path.step(t, t);
        let invalid = |e| SolveError::Setup(format!("the state at t = {t} is invalid: {e}"));
        st.asm
            .assemble(st.model, &st.x, &step, false, None)
            .map_err(invalid)?;
        let flows = st.flows_assembled(t).map_err(invalid);
        st.asm.restore();
        Ok(flows?.0)
    }

    /// After the medium was made again (and [`Run::rejoined`]), `since` it was due: the time
    /// the remake took, kept in the totals; where the mechanics were settled, with the flows
    /// `before` it, how much each group's reaction and heat flow changed, the largest kept
    /// too (see [`flow_change`]), and `-v` says this remake's.
    pub(super) fn remade_from(
        &mut self,
        before: Option<&Reactions>,
        since: std::time::Instant,
    ) -> Result<(), SolveError> {
        // measured where settled, the flows at rest counted in the remake's time
        let change = match before {
            Some(before) => Some(flow_change(before, &self.flows_at_rest()?)),
            None => None,
        };
        let tot = &mut self.accounts.totals;
        tot.remake_seconds += since.elapsed().as_secs_f64();
        let Some((force, heat)) = change else {
            return Ok(());
        };
        tot.remake_force_change = Some(tot.remake_force_change.unwrap_or(0.0).max(force));
        tot.remake_heat_change = Some(tot.remake_heat_change.unwrap_or(0.0).max(heat));
        if self.opts.verbose {
            crate::note!(
                "  the groups' reactions changed by {:.2} % at most, their heat flows by {:.2} %",
                100.0 * force,
                100.0 * heat
            );
        }
        Ok(())
    }

    /// Keep the remade medium's watch `m` as it is after the last accepted state: the next
    /// step's checkpoint holds it.
    pub(super) fn keep_medium(&mut self, m: &crate::model::remake::Medium) {
        self.accounts.totals.medium = Some(m.clone());
    }

    /// The last accepted state.
    pub(super) fn state(&self) -> &[f64] {
        &self.st.x
    }

    /// The cells' own references as the run has them (a medium's closed layers take their
    /// slide into them at each accepted step).
    pub(super) fn references(&self) -> &crate::model::remake::CellReferences {
        self.st.asm.reference.blocks()
    }

    /// Continue from a checkpoint instead of recording the initial state: the run goes on as
    /// if it had never stopped. `carried`: the state the run itself carried onto a changed
    /// mesh, not a restart's ([`Checkpoint::fits`]).
    pub(super) fn resume(&mut self, cp: Checkpoint, carried: bool) -> Result<(), SolveError> {
        let st = &mut self.st;
        let history: Vec<usize> = (st.asm.history.slabs.iter())
            .map(|s| s.committed.len())
            .collect();
        cp.fits(self.rec.out_dir(), st.x.len(), &history, carried)?;
        let state = cp.state;
        st.ctl.t = state.clock.t;
        if st.ctl.done() {
            return Err(SolveError::Setup(format!(
                "cannot restart: the run in {} has finished (it reached the end of its path, \
                 {}); there is nothing to continue, and its results stay as they are. To go \
                 further, lengthen the path and solve again without --restart",
                self.rec.out_dir().display(),
                st.position()
            )));
        }
        st.x = state.x;
        st.asm.resume(&state.point_history);
        if let Some(blocks) = state.references {
            st.asm.reference.set_blocks(blocks);
        }
        st.ctl.set_clock(state.clock);
        st.newton.resume(state.newton);
        self.accounts.totals = state.totals;
        // the files written so far, which the first rank reads: checked before anything that
        // takes every rank, and one verdict for all
        self.rec.resume(&self.st, state.files, state.wall)?;
        // the dissipation and the velocities so far are in the points' history, restored above
        self.take_point_totals();
        Ok(())
    }

    /// A failed attempt: cut the step, or end the run below the minimum step (its summary
    /// written, the error returned).
    fn reject(&mut self, target: f64, failure: StepFailure) -> Result<(), SolveError> {
        if !failure.recoverable() {
            return Err(self.fail(failure)?);
        }
        self.accounts.totals.last_failure = failure.to_string();
        if std::mem::take(&mut self.unsettled) {
            // the first step from a medium made again as carried: tried again settled
            if !self.opts.quiet {
                self.rec.say(&format!(
                    "  step to {} failed: {}; settling the medium made again and trying it again",
                    self.target_text(target),
                    self.accounts.totals.last_failure
                ));
            }
            self.st.asm.restore();
            self.st.ctl.retry();
            // the remake's own work, done late
            let since = std::time::Instant::now();
            self.settle(Settle::Deferred);
            self.accounts.totals.remake_seconds += since.elapsed().as_secs_f64();
            return Ok(());
        }
        // a cut step's attempt can be most of a large run's time: say so, log files too
        if !self.opts.quiet {
            self.rec.say(&format!(
                "  step to {} failed: {}; cutting the step",
                self.target_text(target),
                self.accounts.totals.last_failure
            ));
        }
        // whatever the attempts wrote into the history goes
        if let Err(dl) = self.st.cut() {
            if self.continued(target)? {
                return Ok(());
            }
            if self.remake_instead(target, dl) {
                return Ok(());
            }
            self.rec.clear_bar();
            let st = &self.st;
            let reason = self.accounts.totals.last_failure.clone();
            let step = if st.show_t() {
                format!("Δt = {dl:.3e}")
            } else {
                format!("Δλ = {dl:.3e}")
            };
            let remade = self.accounts.totals.medium.is_some();
            let drag = !pressing(st.model, st.ctl.t, target);
            // where a body came up against the medium's edge, that first: past it nothing
            // is in contact, whatever else the physics suggests
            let edge = (self.accounts.totals.edge_reached_at.as_ref()).map(|reached| {
                format!(
                    "; {} at step {} ({}), where the medium ends and is pushed ahead of it (the \
                     warning then): draw the medium past where the solid goes",
                    reached.came(),
                    reached.step,
                    super::account::when(st, reached.time)
                )
            });
            // the medium was made again at this state to go on (or kept, where gmsh failed)
            let again = if self.remake_before_stopping == Some(st.ctl.t) {
                "; it failed so on the medium made again at this state too"
            } else {
                ""
            };
            let hint =
                (edge.unwrap_or_default() + again + stall_hint(&st.model.physics, remade, drag))
                    .into_boxed_str();
            let err = SolveError::StepTooSmall {
                at: st.position(),
                step,
                reason,
                steps: st.ctl.accepted,
                left: Left::new(
                    st.ctl.accepted,
                    &st.position(),
                    self.rec.out_dir(),
                    st.ctl.accepted == 0 && self.rec.holds_previous(),
                    false,
                ),
                hint,
            };
            self.finish(false, err.to_string())?;
            return Err(err);
        }
        Ok(())
    }

    /// The step to `target`, of length `dl`, would stop the run: whether it asks for the
    /// medium to be made again instead (see [`Run::remake_before_stopping`]); the step is
    /// then tried again on the new medium at that length, or shorter where the new medium's
    /// first step must be.
    fn remake_instead(&mut self, target: f64, dl: f64) -> bool {
        let t = self.st.ctl.t;
        if self.remake_before_stopping.is_none_or(|except| except == t) {
            return false;
        }
        self.remake_before_stopping = None;
        self.wants_remake = true;
        self.st.ctl.dt = dl;
        let tot = &mut self.accounts.totals;
        tot.remade_to_go_on += 1;
        if first_or_verbose(&mut tot.remade_to_go_on_told, self.opts) {
            self.rec.say(&format!(
                "  step to {} failed at the shortest step ({}); the medium made again at {} to \
                 go on (docs/THEORY.md, \"Steps Newton cannot take\"; summary.json counts them, \
                 `medium_remade_to_go_on`)",
                self.target_text(target),
                self.accounts.totals.last_failure,
                self.st.position()
            ));
        }
        true
    }

    /// Where a step to `target` ends, for a line: "t 1.02 (λ 1.0000)" or "λ 0.5000".
    fn target_text(&self, target: f64) -> String {
        let st = &self.st;
        let lambda = st.model.path.lambda(target);
        if st.show_t() {
            format!("t {} (λ {lambda:.4})", st.t_text(target))
        } else {
            format!("λ {lambda:.4}")
        }
    }

    /// Newton failed at the shortest step: the step to `target` by pseudo-transient
    /// continuation, accepted where it converges (said the first time unless quiet, each
    /// time with `-v`; counted in the summary). Returns whether it was; where not, the
    /// failure says why continuation did not take it either.
    fn continued(&mut self, target: f64) -> Result<bool, SolveError> {
        if !self.st.continues() {
            return Ok(false);
        }
        let (trial, rep) = match self.st.attempt_continued(target) {
            Ok(taken) => taken,
            Err(failure) => {
                self.st.asm.restore();
                let tot = &mut self.accounts.totals;
                tot.last_failure = format!(
                    "{}; by continuation at the same load: {failure}",
                    tot.last_failure
                );
                return Ok(false);
            }
        };
        let tot = &mut self.accounts.totals;
        tot.continued += 1;
        if first_or_verbose(&mut tot.continued_told, self.opts) {
            self.rec.say(&format!(
                "  step to {} taken by continuation in {} iterations: Newton did not converge \
                 however short the step (docs/THEORY.md, \"Steps Newton cannot take\"; \
                 summary.json counts them, `continued_steps`)",
                self.target_text(target),
                rep.iterations
            ));
        }
        self.accept(target, trial, rep)?;
        Ok(true)
    }

    /// Count a step that ended in balance where Newton's updates did not shrink, and say it:
    /// the first time (unless quiet), or each time with `-v`.
    fn balanced_only(&mut self, target: f64, iterations: usize) {
        let tot = &mut self.accounts.totals;
        tot.balanced_only += 1;
        if first_or_verbose(&mut tot.balanced_only_told, self.opts) {
            self.rec.say(&format!(
                "  step to {} ended at its iteration {iterations}, in balance (its residual below \
                 tolerance against its own reactions), where the updates after it did not shrink \
                 (docs/THEORY.md, \"Steps Newton cannot take\"; summary.json counts them, \
                 `balanced_steps`)",
                self.target_text(target),
            ));
        }
    }

    /// A failure no smaller step can mend (the engine's): the run ends at once, its summary
    /// written with the reason. Returns the error to report.
    fn fail(&mut self, failure: StepFailure) -> Result<SolveError, SolveError> {
        self.rec.clear_bar();
        self.st.asm.restore();
        let err = match failure {
            StepFailure::Linear(e) => SolveError::Linear(e),
            other => SolveError::Setup(other.to_string()),
        };
        if self.st.ctl.accepted == 0 && matches!(err, SolveError::Linear(_)) {
            // the engine refused before the first step (an option it did not use, a factor
            // it cannot make): a set-up failure, after which the folder is put back as it was
            return Ok(err);
        }
        self.finish(false, err.to_string())?;
        Ok(err)
    }

    /// The mesh could not be changed as the run asked after its last accepted step (`what`
    /// could not be done, `why`): the run ends there, its summary written, as at a step that
    /// fails.
    pub(super) fn cannot_change(mut self, what: &str, why: &str) -> SolveError {
        self.rec.clear_bar();
        let st = &self.st;
        let why = format!("{what} at {}: {why}", st.position());
        let left = Left::new(
            st.ctl.accepted,
            &st.position(),
            self.rec.out_dir(),
            st.ctl.accepted == 0 && self.rec.holds_previous(),
            false,
        );
        let err = SolveError::Setup(format!("{why}; {left}"));
        match self.finish(false, err.to_string()) {
            Ok(()) => err,
            Err(e) => e,
        }
    }

    /// A stop was asked for (a signal): write the summary of the steps so far and say so.
    pub(super) fn interrupt(mut self) -> Result<Summary, SolveError> {
        self.rec.clear_bar();
        let err = self.stopped_here();
        self.finish(false, format!("interrupted: {err}"))?;
        Err(err)
    }

    /// What a run stopped at its last accepted state says.
    fn stopped_here(&self) -> SolveError {
        SolveError::Interrupted {
            at: self.st.position(),
            steps: self.st.ctl.accepted,
            left: Left::new(
                self.st.ctl.accepted,
                &self.st.position(),
                self.rec.out_dir(),
                self.st.ctl.accepted == 0 && self.rec.holds_previous(),
                true,
            ),
        }
    }

    /// The run reached its end: write the summary and return it.
    pub(super) fn complete(mut self) -> Result<Summary, SolveError> {
        self.rec.clear_bar();
        let ctl = &self.st.ctl;
        let msg = if ctl.rejected > 0 {
            format!(
                "converged ({} rejected attempts; last: {})",
                ctl.rejected, self.accounts.totals.last_failure
            )
        } else {
            "converged".into()
        };
        self.finish(true, msg)?;
        Ok(self.rec.summary)
    }

    /// The summary written with the run's state.
    fn finish(&mut self, converged: bool, message: String) -> Result<(), SolveError> {
        (self.rec).finish(&self.st, &self.accounts.totals, converged, message)
    }
}

/// What a run that cannot step says of friction: drags stall where the full slide begins
/// (docs/notes/2026-11-29-friction-measurements.md, "Where drags stall"), or over a medium
/// made again where a leading corner digs into the face it slides on; the user's guide says
/// how far they get, and a mass density carries them through, or many of them: on every
/// region, or where the medium is made again (which takes none) on the solids
/// (docs/notes/2026-12-04-a-sigterm-in-metis-and-a-hint-taken.md). Nothing where the step
/// that fails is a press (`drag` false, [`pressing`]): the drag's words would send the user
/// after the wrong cause.
fn stall_hint(physics: &crate::model::Physics, remade: bool, drag: bool) -> &'static str {
    match (physics.friction && drag, physics.inertia, remade) {
        (false, _, _) => "",
        (true, false, false) => {
            "; with friction, drags stall where the full slide begins (docs/CASE.md, \
             \"How far friction slides\", says how far they get and what to mesh; a \
             small mass density `rho` on every region carries them through)"
        }
        (true, true, false) => {
            "; with friction, drags stall where the full slide begins (docs/CASE.md, \
             \"How far friction slides\", says how far they get and what to mesh; a \
             larger mass density `rho` carries more of them through: finer cells need more)"
        }
        (true, false, true) => {
            "; with friction, a drag can stall where a body's leading corner digs into the \
             face it slides on (docs/CASE.md, \"How far friction slides\"); a small mass \
             density `rho` on every solid can carry it through (a medium made again takes \
             none)"
        }
        (true, true, true) => {
            "; with friction, a drag can stall where a body's leading corner digs into the \
             face it slides on (docs/CASE.md, \"How far friction slides\"); a larger mass \
             density `rho` on the solids can carry more of them through (a medium made again \
             takes none)"
        }
    }
}

/// Whether the step from `from` to `to` moves the prescribed displacements as the run's first
/// segment of time does (a press, where a drag follows it): along the same axes, the
/// increments' sizes summed per axis as vectors less than 60° apart. A step that moves none,
/// or a first segment that moves none (a press by a load), is taken for a drag.
fn pressing(model: &Model, from: f64, to: f64) -> bool {
    let moved = |from: f64, to: f64| {
        let (a, b) = (model.path.amplitudes(from), model.path.amplitudes(to));
        let dim = model.dofs.dim;
        let mut along = [0.0f64; 3];
        for (k, &d) in model.dofs.u.iter().enumerate() {
            if let Some(p) = model
                .cons
                .prescribed
                .get(d as usize)
                .and_then(|p| p.as_ref())
            {
                along[k % dim] += (p.at(&b) - p.at(&a)).abs();
            }
        }
        nalgebra::Vector3::from(along)
    };
    let first = model.path.times.get(1).copied().unwrap_or(0.0);
    let (step, press) = (moved(from, to), moved(0.0, first));
    let norms = step.norm() * press.norm();
    norms > 0.0 && step.dot(&press) >= 0.5 * norms
}

/// Whether to say something said once unless quiet, or every time with `-v` (`told`: whether
/// it has been said; set when it is).
fn first_or_verbose(told: &mut bool, opts: &SolveOptions) -> bool {
    let say = opts.verbose || !(*told || opts.quiet);
    *told |= say;
    say
}
