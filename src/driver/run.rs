//! One run of `tmc solve` on a built model: the solvers the strategy calls for, the step
//! controller, and what each accepted step records (history row, VTU, reactions, work).
//! [`super::solve_model`] drives it: attempt a step, then accept or reject it, until done.

use super::checkpoint::{self, Checkpoint};
use super::records::{HistoryLayout, StepRow, Summary, group_flows, peak_memory_mb};
use super::state::{Files, RunState, Totals};
use super::strategy::{Strategy, choose_linear, choose_strategy, describe, symmetric_tangent};
use super::{SolveError, SolveOptions};
use crate::assembly::{
    Assembler, AssemblyError, convection_heat, corners_through_medium, friction_cells,
    friction_work, heat_stored, kinetic_energy,
};
use crate::case::{Case, RegionKind};
use crate::dofs::Field;
use crate::mesh::point_text;
use crate::model::Model;
use crate::output::probes::Probe;
use crate::output::{History, OutputError, RunFolder, Series, write_atomic};
use crate::parallel::Ranks;
use crate::solver::engine::{self, PlanError, Planned, Request, System};
use crate::solver::linear::{LinearKind, LinearSolver};
use crate::solver::newton::{Newton, Part, StepFailure, StepReport};
use crate::solver::stepping::Controller;
use std::path::PathBuf;
use std::time::Instant;

pub(super) struct Run<'a> {
    model: &'a Model,
    probes: &'a [Probe],
    opts: &'a SolveOptions,
    /// The output folder, on the rank that writes (rank 0); `None` on the others.
    folder: Option<RunFolder>,
    out_dir: PathBuf,
    start: Instant,
    asm: Assembler,
    newton: Newton,
    /// One solver per part: the whole system, or mechanics and heat of a one-way scene.
    solvers: Vec<(Part, LinearSolver)>,
    pub(super) ctl: Controller,
    /// The last accepted state.
    x: Vec<f64>,
    /// The displacement dofs, whose forces do work.
    u_dofs: Vec<usize>,
    series: Series,
    layout: HistoryLayout,
    history: History,
    totals: Totals,
    summary: Summary,
    pb: indicatif::ProgressBar,
    /// Non-zero values held at full value from the start, as `uy = -0.2 on "top"`.
    held_in_full: Vec<String>,
    /// The case steps over physical time (`[time]`).
    transient_clock: bool,
    /// `[output] every`, and the last step written.
    every: usize,
    written: Option<usize>,
    /// What the results depend on (case, mesh), for the checkpoints.
    fingerprint: (String, String),
}

/// What a run solves with, decided and set up before the first assembly: strategy, the
/// assembler's pattern and schedule, Newton, and the symbolic analysis of every linear solver.
pub(super) struct Plan {
    pub strategy: Strategy,
    pub asm: Assembler,
    pub newton: Newton,
    /// One solver per part: the whole system, or mechanics and heat of a one-way scene.
    pub solvers: Vec<(Part, LinearSolver)>,
    /// Why the engine is not the usual one (`engine = "auto"`), if so.
    pub note: Option<String>,
}

impl Plan {
    pub(super) fn new(case: &Case, model: &Model, opts: &SolveOptions) -> Result<Plan, SolveError> {
        let kind = choose_linear(case.file.solver.linear, &model.physics);
        if kind == LinearKind::Ldlt && !symmetric_tangent(&model.physics) {
            let span = case.file.mesh.span();
            let why = if model.physics.friction {
                "this scene has friction"
            } else {
                "this scene couples mechanics and conduction"
            };
            return Err(case
                .error::<()>(
                    span,
                    format!("[solver] linear = \"ldlt\" needs a symmetric tangent, but {why}"),
                )
                .unwrap_err()
                .into());
        }
        let strategy = choose_strategy(&case.file.solver, &model.physics);
        let steps = &case.file.steps;
        let mut newton = Newton::new(model, steps.tol, steps.max_iter);
        let systems = Self::systems(model, &newton, strategy);
        let request = Request {
            solver: &case.file.solver,
            whole: kind,
            idle: opts.idle_threads,
            span: case.file.mesh.span(),
            memory_mb: opts.memory_mb,
        };
        let Planned {
            asm,
            solvers,
            idle,
            note,
        } = engine::plan(model, &request, &systems).map_err(|e| match e {
            PlanError::Case { span, message } => {
                SolveError::from(case.error::<()>(span, message).unwrap_err())
            }
            PlanError::Setup(message) => SolveError::Setup(message),
            PlanError::Linear(e) => SolveError::Linear(e),
        })?;
        newton.idle = idle;
        Ok(Plan {
            strategy,
            asm,
            newton,
            solvers,
            note,
        })
    }

    /// The systems `strategy` solves: the whole system, or mechanics and then heat.
    fn systems(model: &Model, newton: &Newton, strategy: Strategy) -> Vec<System> {
        let friction = model.physics.friction;
        let system = |part: Part, symmetric: bool| System {
            part,
            eqs: newton.equations(part),
            symmetric,
            symmetric_mechanics: !friction,
        };
        match strategy {
            Strategy::OneWay => vec![system(Part::Mechanics, !friction), system(Part::Heat, true)],
            _ => vec![system(Part::All, symmetric_tangent(&model.physics))],
        }
    }
}

impl<'a> Run<'a> {
    /// Choose strategy and solvers, and set up the records; nothing is written yet.
    pub(super) fn new(
        case: &'a Case,
        model: &'a Model,
        probes: &'a [Probe],
        mut folder: Option<RunFolder>,
        out_dir: PathBuf,
        opts: &'a SolveOptions,
        start: Instant,
    ) -> Result<Run<'a>, SolveError> {
        let Plan {
            strategy,
            asm,
            newton,
            solvers,
            note,
        } = Plan::new(case, model, opts)?;
        if !opts.quiet {
            crate::note!("{}", describe(&model.physics, strategy));
            if let Some(note) = &note {
                crate::note!("{note}");
            }
        }
        let ctl = controller(case, model);
        let layout = HistoryLayout::new(model, probes, case.file.time.is_some());
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
        let mut summary =
            Summary::start(case, model, solvers[0].1.kind, strategy, &layout, &out_dir);
        summary.ranks = asm.ranks.size;
        summary.engine = solvers[0].1.engine().into();
        summary.petsc_solver = solvers[0].1.engine_solver();
        let mut series = Series::new(&out_dir, &case.name(), model);
        if let Some(d) = asm.distribution().filter(|d| d.partition.parts > 1) {
            series = series.in_parts(model, d);
        }
        Ok(Run {
            model,
            probes,
            opts,
            folder,
            out_dir,
            start,
            asm,
            newton,
            solvers,
            ctl,
            x: model.initial_state(),
            u_dofs: (0..model.dofs.n_dofs)
                .filter(|&d| model.dofs.field[d] == Field::U)
                .collect(),
            series,
            layout,
            history,
            totals: Totals::default(),
            summary,
            pb: progress_bar(opts.quiet),
            held_in_full: case
                .file
                .bc
                .iter()
                .flat_map(|bc| bc.held_in_full())
                .collect(),
            transient_clock: case.file.time.is_some(),
            every: *case.file.output.every.get_ref() as usize,
            written: None,
            fingerprint: (
                checkpoint::case_fingerprint(case),
                checkpoint::mesh_fingerprint(&model.mesh),
            ),
        })
    }

    /// Record the initial state: step 0 of the series and of the history, and the forces the
    /// work is counted from.
    pub(super) fn record_initial(&mut self) -> Result<(), SolveError> {
        let iterations = self.settle_initial()?;
        self.write_step()?;
        let stats0 = self
            .asm
            .assemble(self.model, &self.x, 0.0, false, None)
            .map_err(|e| SolveError::Setup(format!("the initial state is invalid: {e}")))?;
        // the state at λ = 0 (settled under what is held in full) is the first accepted one:
        // the points' history starts there (inertia: displaced, at rest)
        self.asm.commit(0.0);
        self.totals.energy = stats0.energy;
        let convected = convection_heat(self.model, &self.x)
            .map_err(|e| SolveError::Setup(format!("the initial state is invalid: {e}")))?;
        let r0 = group_flows(self.model, &self.asm.r_full, &convected, 0.0);
        let row = StepRow {
            min_J_solid: stats0.min_J_solid,
            min_J_medium: stats0.min_J_medium,
            energy: stats0.energy,
            iterations,
            wall: self.start.elapsed().as_secs_f64(),
            ..StepRow::default()
        };
        if self.folder.is_some() {
            self.history
                .row(&self.layout.row(&row, &self.probe_values(), &r0))?;
        }
        self.totals.reactions = r0;
        self.totals.f_last = self.forces(0.0);
        self.save_checkpoint()
    }

    /// A steady scene with values applied in full (`ramp = false`) starts from its equilibrium
    /// at λ = 0 under them (a temperature held at 100 conducts from the start: step 0 reports
    /// that heat, not 0); a transient scene starts from its initial condition. Returns the
    /// Newton iterations spent (0 when there is nothing to settle).
    fn settle_initial(&mut self) -> Result<usize, SolveError> {
        if self.transient_clock || self.held_in_full.is_empty() {
            return Ok(0);
        }
        match self.attempt(0.0) {
            Ok((x, rep)) => {
                self.x = x;
                self.totals.iterations += rep.iterations;
                self.totals.krylov += rep.krylov;
                self.totals.tangents_skipped += rep.tangents_skipped;
                Ok(rep.iterations)
            }
            Err(failure) if !failure.recoverable() => Err(self.fail(failure)?),
            // the linear solver's failure, not the values held in full: no advice on ramps
            Err(failure @ StepFailure::Linear(_)) => Err(self.fail(failure)?),
            Err(failure) => {
                self.pb.finish_and_clear();
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
        let solvers = std::mem::take(&mut self.solvers);
        self.solvers = solvers.into_iter().map(|(p, s)| (p, wrap(s))).collect();
    }

    /// The run's ranks (their decisions to stop are taken together).
    pub(super) fn ranks(&self) -> Ranks {
        self.asm.ranks
    }

    /// The probes at the last accepted state.
    fn probe_values(&self) -> Vec<f64> {
        self.probes
            .iter()
            .map(|p| p.eval(&self.model.mesh, &self.model.dofs, &self.x))
            .collect()
    }

    /// The forces on the displacement dofs, f_int = r + f_ext, from the last assembly at `t`.
    fn forces(&self, t: f64) -> Vec<f64> {
        let mut fe = vec![0.0; self.model.dofs.n_dofs];
        self.model.f_ext(t, &mut fe);
        self.u_dofs
            .iter()
            .map(|&d| self.asm.r_full[d] + fe[d])
            .collect()
    }

    /// Solve the step to pseudo-time `target` from the last accepted state, part by part;
    /// the trial state is returned with the report.
    pub(super) fn attempt(&mut self, target: f64) -> Result<(Vec<f64>, StepReport), StepFailure> {
        let mut trial = self.x.clone();
        let mut report: Option<StepReport> = None;
        for (part, solver) in self.solvers.iter_mut() {
            let rep =
                self.newton
                    .step(self.model, &mut self.asm, solver, &mut trial, target, *part)?;
            report = Some(match report {
                None => rep,
                Some(a) => a.then(rep),
            });
        }
        Ok((trial, report.expect("at least one part")))
    }

    /// Take a converged step: the run's state moves to it, then its files and progress line.
    pub(super) fn accept(
        &mut self,
        target: f64,
        trial: Vec<f64>,
        rep: StepReport,
    ) -> Result<(), SolveError> {
        let model = self.model;
        let dlambda = model.path.lambda(target) - model.path.lambda(self.ctl.t);
        self.advance(target, trial, &rep)?;
        self.output(target, dlambda, &rep)
    }

    /// Move the run's state to the converged `trial` at `target`: the controller, the totals,
    /// the reactions and the history of the converged state, the heat and work done.
    fn advance(
        &mut self,
        target: f64,
        trial: Vec<f64>,
        rep: &StepReport,
    ) -> Result<(), SolveError> {
        let model = self.model;
        let x_last = std::mem::replace(&mut self.x, trial);
        let dt = target - self.ctl.t;
        self.ctl.accept(target, rep.iterations);
        let tot = &mut self.totals;
        tot.iterations += rep.iterations;
        tot.krylov += rep.krylov;
        tot.tangents_skipped += rep.tangents_skipped;
        tot.energy = rep.stats.energy;
        tot.lower_min_J(rep.stats.min_J_solid, rep.stats.min_J_medium);
        // reactions at the converged state (the residual of the last assembly)
        let invalid =
            |e: AssemblyError| SolveError::Setup(format!("converged state is invalid: {e}"));
        let t0 = Instant::now();
        self.asm
            .assemble(model, &self.x, target, false, None)
            .map_err(invalid)?;
        self.totals.t_reactions += t0.elapsed().as_secs_f64();
        let convected = convection_heat(model, &self.x).map_err(invalid)?;
        self.totals.reactions = group_flows(model, &self.asm.r_full, &convected, target);
        // the history of the converged state (just assembled) is what the next step starts from
        self.asm.commit(target);
        if model.physics.transient {
            self.account_heat(target, dt, convected.iter().sum())?;
        }
        self.account_points();
        let f_now = self.forces(target);
        let tot = &mut self.totals;
        tot.work += self
            .u_dofs
            .iter()
            .zip(tot.f_last.iter().zip(&f_now))
            .map(|(&d, (a, b))| 0.5 * (a + b) * (self.x[d] - x_last[d]))
            .sum::<f64>();
        tot.f_last = f_now;
        let through = corners_through_medium(model, &self.asm.reference, &self.x);
        tot.corners_through = tot.corners_through.max(through);
        self.watch_displacement(target);
        Ok(())
    }

    /// The largest nodal displacement of the accepted state, kept for the summary; the first
    /// time it exceeds [`RUNAWAY`] times the mesh's extent, a warning naming the node: in a
    /// medium, a node that barely resists (a free corner of an open medium) has run away and
    /// its cells are no solution; in a solid, its body moves far (held by its mass alone).
    fn watch_displacement(&mut self, target: f64) {
        let model = self.model;
        let dim = model.mesh.dim;
        if model.dofs.u.is_empty() {
            return;
        }
        let (node, largest) = (0..model.dofs.n_nodes)
            .map(|n| {
                let u = &model.dofs.u[n * dim..(n + 1) * dim];
                let size = u.iter().map(|&d| self.x[d as usize].powi(2)).sum::<f64>();
                (n, size.sqrt())
            })
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        let tot = &mut self.totals;
        tot.largest_displacement = tot.largest_displacement.max(largest);
        if largest <= RUNAWAY * model.d || tot.runaway_told {
            return;
        }
        tot.runaway_told = true;
        if self.opts.quiet {
            return;
        }
        let at = point_text(&model.mesh.coords[node], dim);
        let block = (model.blocks.iter()).find(|b| model.mesh.cells[b.block].conn.contains(&node));
        let (name, medium) = block.map_or(("", false), |b| {
            let (name, kind) = &model.regions[b.region];
            (name.as_str(), *kind == RegionKind::Medium)
        });
        let when = if self.show_t() {
            format!("t = {}", self.t_text(target))
        } else {
            format!("λ = {:.4}", model.path.lambda(target))
        };
        let what = if medium {
            "a node of the medium that barely resists (a free corner of an open medium, most \
             likely) runs away. The forces where the solids are held may still hold; that \
             node's cells are no solution. A [[bc]] on that boundary of the medium holds it."
        } else {
            "its body moves far, held by its mass or by little else. If it should stay in \
             place, hold it (a [[bc]]) or check its loads."
        };
        self.say(&format!(
            "warning: step {} ({when}): node {node} of region \"{name}\" (at {at} in the \
             undeformed mesh) has moved {largest:.3e}, {:.0} times the mesh's extent: {what}",
            self.ctl.accepted,
            largest / model.d
        ));
    }

    /// What an accepted step leaves: its `.vtu` (when `[output] every` asks), its history row,
    /// the checkpoint, and its progress line.
    fn output(&mut self, target: f64, dlambda: f64, rep: &StepReport) -> Result<(), SolveError> {
        let row = StepRow {
            step: self.ctl.accepted,
            lambda: self.model.path.lambda(target),
            dlambda,
            iterations: rep.iterations,
            residuals: rep.history.last().copied().unwrap_or([0.0; 3]),
            min_J_solid: rep.stats.min_J_solid,
            min_J_medium: rep.stats.min_J_medium,
            energy: rep.stats.energy,
            krylov: rep.krylov,
            halvings: rep.halvings,
            time: target,
            work: self.totals.work,
            heat: self.totals.heat_stored.zip(self.totals.heat_in),
            friction: self
                .summary
                .friction_work
                .map(|w| (w, self.summary.friction_heat.unwrap_or(0.0))),
            heat_joined: self.totals.heat_joined,
            kinetic_energy: self.summary.kinetic_energy,
            wall: self.start.elapsed().as_secs_f64(),
        };
        let values = self
            .layout
            .row(&row, &self.probe_values(), &self.totals.reactions);
        // the step's file first (when [output] every asks for it): a row never announces a
        // file that is not there yet
        if self.ctl.accepted.is_multiple_of(self.every) {
            self.write_step()?;
        }
        if self.folder.is_some() {
            self.history.row(&values)?;
        }
        self.save_checkpoint()?;
        if let Some(folder) = &mut self.folder {
            // a step taken: the previous run's files go for good
            folder.settle()?;
        }
        self.report_step(&row, rep);
        Ok(())
    }

    /// `restart.json` of the last accepted state (after its `.vtu` and history row).
    /// The run's state as a checkpoint (on several ranks every rank takes part).
    fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            version: checkpoint::VERSION,
            case: self.fingerprint.0.clone(),
            mesh: self.fingerprint.1.clone(),
            state: RunState {
                x: self.x.clone(),
                point_history: self.asm.whole_history(self.model),
                clock: self.ctl.clock(),
                newton: self.newton.tally(),
                totals: self.totals.clone(),
                files: Files {
                    series: self.series.written().len(),
                    written: self.written,
                    history: self.history.mark(),
                },
                wall: self.start.elapsed().as_secs_f64(),
            },
        }
    }

    fn save_checkpoint(&mut self) -> Result<(), SolveError> {
        if self.folder.is_none() {
            // on several ranks each holds its own cells' history per point, gathered by
            // every rank before the first rank writes it
            if !self.asm.ranks.is_serial() {
                self.asm.whole_history(self.model);
            }
            return Ok(());
        }
        let cp = self.checkpoint();
        if let Some(folder) = &mut self.folder {
            folder.record(checkpoint::FILE)?;
        }
        write_atomic(&Checkpoint::path(&self.out_dir), cp.to_json().as_bytes())?;
        Ok(())
    }

    /// End the run at its last accepted state to go on on a mesh whose reconnected layers are
    /// joined again: their cells take the slide into their references first. Returns the
    /// state as a checkpoint (the files written so far belong to it) and the output folder.
    pub(super) fn end_to_rejoin(mut self) -> (Checkpoint, Option<RunFolder>) {
        let model = self.model;
        // the heat stored as the cells were (the accepted step counted it): `rejoined` adds
        // what it is as they are joined
        if let Some(stored) = self.totals.heat_stored {
            *self.totals.heat_joined.get_or_insert(0.0) -= stored;
        }
        self.asm.absorb_slide(model, &self.x);
        let cp = self.checkpoint();
        (cp, self.folder.take())
    }

    /// A run resumed on a mesh whose reconnected layers were just joined again: their cells
    /// start from the state as it is.
    /// The next step starts from their mechanics settled at the same loads (a step of no
    /// length: no inertia), or from the state as joined where that does not converge. The
    /// points' history stays as joined: whatever the settling slipped is the next step's
    /// slip, whose work that step makes heat over its length.
    pub(super) fn rejoined(&mut self) {
        self.asm.rejoined(self.model, &self.x);
        // the settling below keeps the temperature: the heat stored changes at the join only
        if let Some(stored) = self.joined_heat() {
            *self.totals.heat_joined.get_or_insert(0.0) += stored;
        }
        let t = self.ctl.t;
        if let Ok((x, rep)) = self.attempt(t) {
            // the mechanics settled; the temperature stays (a step of no length has no
            // capacity: what it solved for θ is a steady state, not the state)
            let dofs = &self.model.dofs;
            for (d, v) in x.into_iter().enumerate() {
                if dofs.field[d] != Field::Theta {
                    self.x[d] = v;
                }
            }
            let tot = &mut self.totals;
            tot.iterations += rep.iterations;
            tot.krylov += rep.krylov;
            tot.tangents_skipped += rep.tangents_skipped;
        }
        self.asm.restore();
    }

    /// The heat stored at the last accepted state, in a transient scene (whose joins change
    /// it: its cells' temperatures are other nodes' once joined); `None` in others.
    fn joined_heat(&self) -> Option<f64> {
        let model = self.model;
        (model.physics.transient)
            .then(|| heat_stored(model, &self.asm.reference, &self.x).ok())
            .flatten()
    }

    /// The last accepted state.
    pub(super) fn state(&self) -> &[f64] {
        &self.x
    }

    /// Continue from a checkpoint instead of recording the initial state: the run goes on as
    /// if it had never stopped.
    pub(super) fn resume(&mut self, cp: Checkpoint) -> Result<(), SolveError> {
        let history: Vec<usize> = (self.asm.history.slabs.iter())
            .map(|s| s.committed.len())
            .collect();
        cp.fits(&self.out_dir, self.x.len(), &history)?;
        let state = cp.state;
        self.ctl.t = state.clock.t;
        if self.ctl.done() {
            return Err(SolveError::Setup(format!(
                "cannot restart: the run in {} has finished (it reached the end of its path, \
                 {}); there is nothing to continue, and its results stay as they are. To go \
                 further, lengthen the path and solve again without --restart",
                self.out_dir.display(),
                self.position()
            )));
        }
        self.x = state.x;
        self.asm.resume(&state.point_history, state.clock.t);
        self.ctl.set_clock(state.clock);
        self.newton.resume(state.newton);
        self.totals = state.totals;
        // the files written so far, which the first rank reads: checked before anything that
        // takes every rank, and one verdict for all
        let checkpoint = Checkpoint::path(&self.out_dir);
        let damaged = |file: &std::path::Path, what: String| {
            SolveError::Setup(format!(
                "cannot restart from {}: {} does not go with it: {what}; run without --restart \
                 to start over",
                checkpoint.display(),
                file.display()
            ))
        };
        let files = self
            .series
            .resume(state.files.series)
            .map_err(|e| damaged(self.series.pvd(), e))
            .and_then(|_| match self.folder.is_some() {
                true => (self.history.resume(state.files.history))
                    .map_err(|e| damaged(&self.out_dir.join("history.csv"), e)),
                false => Ok(()),
            });
        (self.asm.ranks).agree(files, SolveError::to_string, |text| {
            SolveError::Setup(text.into())
        })?;
        // the dissipation and the velocities so far are in the points' history, restored above
        self.account_points();
        self.written = state.files.written;
        // wall seconds go on from where the run stopped
        self.start = Instant::now()
            .checked_sub(std::time::Duration::from_secs_f64(state.wall))
            .unwrap_or(self.start);
        Ok(())
    }

    /// Heat balance of a transient scene after an accepted step of length `dt` to `t`: the heat
    /// stored, and the heat supplied over the run, Σ Δt × (rate at the step's end) as backward
    /// Euler takes it. The rate is Σ over θ dofs of the reactions and the external heat, plus
    /// the heat `convected` in (negative: out): at convergence, exactly the rate of the stored
    /// heat.
    fn account_heat(&mut self, t: f64, dt: f64, convected: f64) -> Result<(), SolveError> {
        let model = self.model;
        let invalid =
            |e: AssemblyError| SolveError::Setup(format!("converged state is invalid: {e}"));
        let mut fe = vec![0.0; model.dofs.n_dofs];
        model.f_ext(t, &mut fe);
        let mut rate = 0.0;
        for &d in &model.dofs.theta {
            let d = d as usize;
            rate += fe[d];
            if model.cons.prescribed[d].is_some() {
                rate += self.asm.r_full[d];
            }
        }
        rate += convected;
        let tot = &mut self.totals;
        tot.heat_in = Some(tot.heat_in.unwrap_or(0.0) + dt * rate);
        tot.heat_stored = Some(heat_stored(model, &self.asm.reference, &self.x).map_err(invalid)?);
        Ok(())
    }

    /// What the points' committed history holds at the step just committed: with friction,
    /// the work it dissipated and the heat it made so far; with inertia, the kinetic energy.
    fn account_points(&mut self) {
        let model = self.model;
        if model.physics.inertia {
            self.summary.kinetic_energy = Some(kinetic_energy(model, &self.asm));
        }
        if !model.physics.friction {
            return;
        }
        let works = friction_work(model, &self.asm);
        let heat = works
            .iter()
            .zip(&model.friction_blocks)
            .map(|(w, fb)| w * fb.heat_fraction)
            .sum();
        self.summary.friction_work = Some(works.iter().sum());
        self.summary.friction_heat = model.physics.frictional_heating.then_some(heat);
    }

    /// The step's line (with `--verbose`, the Newton table too) and the progress bar.
    fn report_step(&self, row: &StepRow, rep: &StepReport) {
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
                self.clock(row),
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
                self.clock(row),
                row.iterations,
                row.wall
            ));
        }
        self.pb
            .set_position((row.time / self.ctl.end * 1000.0) as u64);
        self.pb.set_message(format!(
            "step {} its {}",
            self.ctl.accepted, self.totals.iterations
        ));
    }

    /// The `.vtu` of the last accepted state, once: on several ranks each rank's part, the
    /// first rank's `.pvtu` putting them together, and one error for all if any rank's failed.
    fn write_step(&mut self) -> Result<(), SolveError> {
        let step = self.ctl.accepted;
        if self.written == Some(step) {
            return Ok(());
        }
        let mut written = Ok(());
        if let Some(folder) = &mut self.folder {
            for file in self.series.files(step) {
                written = written.and(folder.record(&file));
            }
        }
        let friction =
            (self.model.physics.friction).then(|| friction_cells(self.model, &self.asm, &self.x));
        let written = written.and_then(|_| {
            self.series.write(
                self.model,
                step,
                &self.asm.reference,
                &self.x,
                self.ctl.t,
                friction.as_deref(),
            )
        });
        let ranks = self.asm.ranks;
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

    /// Where a step ended: λ, and the physical time with `[time]`.
    fn clock(&self, row: &StepRow) -> String {
        if self.show_t() {
            format!("t {}  λ {:.4}", self.t_text(row.time), row.lambda)
        } else {
            format!("λ {:.4}", row.lambda)
        }
    }

    /// Whether where a run stands is said in t as well as λ: over physical time, or over a
    /// pseudo-time that λ does not follow (a path such as `[0, 1, 1]`, whose second segment
    /// drags at λ = 1).
    fn show_t(&self) -> bool {
        self.transient_clock || !self.model.path.lambda_is_time()
    }

    /// A time for a message: physical time to five significant digits, pseudo-time to six
    /// decimals (as λ).
    fn t_text(&self, t: f64) -> String {
        if self.transient_clock {
            format!("{t:.4e}")
        } else {
            format!("{t:.6}")
        }
    }

    /// A failed attempt: cut the step, or end the run below the minimum step (its summary
    /// written, the error returned).
    pub(super) fn reject(&mut self, target: f64, failure: StepFailure) -> Result<(), SolveError> {
        if !failure.recoverable() {
            return Err(self.fail(failure)?);
        }
        self.totals.last_failure = failure.to_string();
        // a cut step's attempt can be most of a large run's time: say so, log files too
        if !self.opts.quiet {
            let lambda = self.model.path.lambda(target);
            let to = if self.show_t() {
                format!("t {} (λ {lambda:.4})", self.t_text(target))
            } else {
                format!("λ {lambda:.4}")
            };
            self.say(&format!(
                "  step to {to} failed: {}; cutting the step",
                self.totals.last_failure
            ));
        }
        // whatever the attempts wrote into the history goes
        self.asm.restore();
        if let Err(dl) = self.ctl.reject() {
            self.pb.finish_and_clear();
            let reason = self.totals.last_failure.clone();
            let step = if self.show_t() {
                format!("Δt = {dl:.3e}")
            } else {
                format!("Δλ = {dl:.3e}")
            };
            // friction's drags stall where the full slide begins (THEORY.md, "Where drags
            // stall"): the user's guide says how far they get
            let hint = if self.model.physics.friction && !self.model.physics.inertia {
                "; with friction, drags stall where the full slide begins (docs/CASE.md, \
                 \"How far friction slides\", says how far they get and what to mesh; a \
                 small mass density `rho` on every region carries them through)"
            } else if self.model.physics.friction {
                "; with friction, drags stall where the full slide begins (docs/CASE.md, \
                 \"How far friction slides\", says how far they get and what to mesh; a \
                 larger mass density `rho` carries more of them through: finer cells need more)"
            } else {
                ""
            };
            let err = SolveError::StepTooSmall {
                at: self.position(),
                step,
                reason,
                steps: self.ctl.accepted,
                dir: self.out_dir.clone(),
                hint,
            };
            self.finish(false, err.to_string())?;
            return Err(err);
        }
        Ok(())
    }

    /// Where the run stands: "λ = 0.500000", or with `[time]` "t = 1.2000e0 (λ = 1.000000)",
    /// or on a path that λ does not follow "t = 1.077382 (λ = 1.000000)".
    fn position(&self) -> String {
        let t = self.ctl.t;
        let lambda = self.model.path.lambda(t);
        if self.show_t() {
            format!("t = {} (λ = {lambda:.6})", self.t_text(t))
        } else {
            format!("λ = {lambda:.6}")
        }
    }

    /// A failure no smaller step can mend (the engine's): the run ends at once, its summary
    /// written with the reason. Returns the error to report.
    fn fail(&mut self, failure: StepFailure) -> Result<SolveError, SolveError> {
        self.pb.finish_and_clear();
        self.asm.restore();
        let err = match failure {
            StepFailure::Linear(e) => SolveError::Linear(e),
            other => SolveError::Setup(other.to_string()),
        };
        if self.ctl.accepted == 0 && matches!(err, SolveError::Linear(_)) {
            // the engine refused before the first step (an option it did not use, a factor
            // it cannot make): a set-up failure, after which the folder is put back as it was
            return Ok(err);
        }
        self.finish(false, err.to_string())?;
        Ok(err)
    }

    /// A stop was asked for (a signal): write the summary of the steps so far and say so.
    pub(super) fn interrupt(mut self) -> Result<Summary, SolveError> {
        self.pb.finish_and_clear();
        let err = SolveError::Interrupted {
            at: self.position(),
            steps: self.ctl.accepted,
            dir: self.out_dir.clone(),
        };
        self.finish(false, format!("interrupted: {err}"))?;
        Err(err)
    }

    /// The run reached its end: write the summary and return it.
    pub(super) fn complete(mut self) -> Result<Summary, SolveError> {
        self.pb.finish_and_clear();
        let msg = if self.ctl.rejected > 0 {
            format!(
                "converged ({} rejected attempts; last: {})",
                self.ctl.rejected, self.totals.last_failure
            )
        } else {
            "converged".into()
        };
        self.finish(true, msg)?;
        Ok(self.summary)
    }

    /// Fill the summary from the run's state and write `summary.json`.
    fn finish(&mut self, converged: bool, message: String) -> Result<(), SolveError> {
        // the last state reached always has its file
        self.write_step()?;
        let (model, ctl, tot, spent) = (self.model, &self.ctl, &self.totals, self.newton.spent);
        let s = &mut self.summary;
        s.converged = converged;
        s.message = message;
        s.lambda = model.path.lambda(ctl.t);
        s.time = ctl.t;
        s.load_steps = ctl.accepted;
        s.rejected_steps = ctl.rejected;
        s.newton_iterations = tot.iterations;
        s.rejected_iterations = spent.iterations - tot.iterations;
        s.linear_solves = spent.updates;
        s.factorisations = spent.factorisations;
        s.wall_seconds = self.start.elapsed().as_secs_f64();
        s.assembly_seconds = spent.assembly + tot.t_reactions;
        s.solver_seconds = spent.solve;
        s.peak_memory_mb = peak_memory_mb();
        let ranks = self.asm.ranks;
        if !ranks.is_serial() {
            let mut each = vec![0.0; ranks.size];
            each[ranks.rank] = s.peak_memory_mb.unwrap_or(f64::NAN);
            ranks.sum_into(&mut each);
            s.peak_memory_mb_ranks = Some(each);
        }
        s.probes = self
            .probes
            .iter()
            .map(|p| (p.name.clone(), p.eval(&model.mesh, &model.dofs, &self.x)))
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
        // 0 until the first join
        s.heat_joined = (self.layout.joined).then(|| tot.heat_joined.unwrap_or(0.0));
        s.largest_displacement = tot.largest_displacement;
        if let Some(folder) = &mut self.folder {
            let json = serde_json::to_string_pretty(&*s).expect("serialisable");
            write_atomic(&self.out_dir.join("summary.json"), json.as_bytes())?;
            // results of this run's own, even if it failed: they replace the previous run's
            folder.settle()?;
        }
        Ok(())
    }

    /// A line above the progress bar, or on stderr when the bar is hidden (not a terminal).
    fn say(&self, line: &str) {
        if self.pb.is_hidden() {
            crate::note!("{line}");
        } else {
            self.pb.println(line);
        }
    }
}

/// A node that has moved this many times the mesh's extent has run away.
const RUNAWAY: f64 = 10.0;

/// The step controller: over physical time with `[time]` (steps of at most `dt`, onto every
/// listed time), else over pseudo-time as `[steps]` says.
fn controller(case: &Case, model: &Model) -> Controller {
    let steps = &case.file.steps;
    match &case.file.time {
        Some(time) => {
            let dt = time.dt_max();
            Controller::with_vertices(steps, time.vertices(), dt, dt * steps.min, dt)
        }
        None => {
            let mut ctl = Controller::new(steps, model.path.end());
            if !model.physics.mechanics {
                // conduction on the undeformed body is linear: one step (per path segment), one
                // solve
                ctl.dt = 1.0;
            }
            ctl
        }
    }
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
