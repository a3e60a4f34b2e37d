//! The stepper: from the last accepted state to the next, one attempt at a time. It holds
//! what a step is solved with (the plan: strategy, assembler, Newton and the linear solvers,
//! set up before the first assembly), the step controller and the last accepted state; what an
//! accepted step leaves behind is the recorder's (`recorder.rs`), what it did the accounts'
//! (`account.rs`).

use super::records::{Reactions, group_flows};
use super::strategy::{Strategy, choose_linear, choose_strategy, symmetric_tangent};
use super::{SolveError, SolveOptions};
use crate::assembly::{Assembler, AssemblyError, AssemblyStats};
use crate::case::Case;
use crate::dofs::{Field, Ordering};
use crate::model::{Model, StepContext};
use crate::parallel::Ranks;
use crate::post::convection_heat;
use crate::solver::engine::{self, PlanError, Planned, Request, System};
use crate::solver::linear::{LinearKind, LinearSolver};
use crate::solver::newton::{Newton, Part, StepFailure, StepReport};
use crate::solver::stepping::Controller;

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
    /// The plan of a run of `case` on `model`, `gmsh` whether the run opens gmsh (for the
    /// memory it will hold).
    pub(super) fn new(
        case: &Case,
        model: &Model,
        opts: &SolveOptions,
        gmsh: bool,
    ) -> Result<Plan, SolveError> {
        let kind = choose_linear(*case.file.solver.linear.get_ref(), &model.physics);
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
            memory_mb: opts.memory_mb,
            gmsh,
            ordering: ordering(case, model),
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

/// How a step is solved for one part: [`Newton::step`] or [`Newton::continuation`].
type Solve = fn(
    &mut Newton,
    &Model,
    &mut Assembler,
    &mut LinearSolver,
    &mut [f64],
    &StepContext,
    Part,
) -> Result<StepReport, StepFailure>;

/// The run's solving state: the plan's assembler, Newton and solvers, the step controller, and
/// the last accepted state.
pub(super) struct Stepper<'a> {
    pub(super) model: &'a Model,
    pub(super) asm: Assembler,
    pub(super) newton: Newton,
    /// One solver per part: the whole system, or mechanics and heat of a one-way scene.
    solvers: Vec<(Part, LinearSolver)>,
    pub(super) ctl: Controller,
    /// The last accepted state.
    pub(super) x: Vec<f64>,
    /// The case steps over physical time (`[time]`).
    pub(super) transient_clock: bool,
    /// Whether a step Newton cannot take is tried by continuation (`[steps] continuation`).
    continuation: bool,
}

impl<'a> Stepper<'a> {
    /// A stepper at the model's initial state, with the plan's solvers and the case's step
    /// controller.
    pub(super) fn new(case: &Case, model: &'a Model, plan: Plan) -> Stepper<'a> {
        Stepper {
            model,
            asm: plan.asm,
            newton: plan.newton,
            solvers: plan.solvers,
            ctl: controller(case, model),
            x: model.initial_state(),
            transient_clock: case.file.time.is_some(),
            continuation: case.file.steps.continuation,
        }
    }

    /// Whether a step Newton cannot take is tried by continuation: where the case has it
    /// (`[steps] continuation`) and the run is on one rank (`Newton::continuation`).
    pub(super) fn continues(&self) -> bool {
        self.continuation && self.asm.ranks.size == 1
    }

    /// The run's ranks (their decisions to stop are taken together).
    pub(super) fn ranks(&self) -> Ranks {
        self.asm.ranks
    }

    /// The first part's linear solver (the one the summary names).
    pub(super) fn solver(&self) -> &LinearSolver {
        &self.solvers[0].1
    }

    /// Every solver replaced by what `wrap` makes of it (a test's scripted engine).
    #[cfg(test)]
    pub(super) fn wrap_solvers(&mut self, wrap: impl Fn(LinearSolver) -> LinearSolver) {
        let solvers = std::mem::take(&mut self.solvers);
        self.solvers = solvers.into_iter().map(|(p, s)| (p, wrap(s))).collect();
    }

    /// Solve the step to pseudo-time `target` from the last accepted state, part by part;
    /// the trial state is returned with the report.
    pub(super) fn attempt(&mut self, target: f64) -> Result<(Vec<f64>, StepReport), StepFailure> {
        self.attempt_by(target, Newton::step, false)
    }

    /// The step to `target` that [`Stepper::attempt`] could not converge however short,
    /// solved by pseudo-transient continuation (`Newton::continuation`). Only where the case
    /// has it ([`Stepper::continues`]).
    pub(super) fn attempt_continued(
        &mut self,
        target: f64,
    ) -> Result<(Vec<f64>, StepReport), StepFailure> {
        self.attempt_by(target, Newton::continuation, false)
    }

    /// The step to `target` solved by `solve` for each part in turn; with `no_heat`, each but
    /// the heat of a one-way coupling.
    fn attempt_by(
        &mut self,
        target: f64,
        solve: Solve,
        no_heat: bool,
    ) -> Result<(Vec<f64>, StepReport), StepFailure> {
        let step = self.model.path.step(self.ctl.t, target);
        let mut trial = self.x.clone();
        let mut report: Option<StepReport> = None;
        let parts = (self.solvers.iter_mut()).filter(|(part, _)| !no_heat || *part != Part::Heat);
        for (part, solver) in parts {
            let (model, asm) = (self.model, &mut self.asm);
            let rep = solve(
                &mut self.newton,
                model,
                asm,
                solver,
                &mut trial,
                &step,
                *part,
            )?;
            report = Some(match report {
                None => rep,
                Some(a) => a.then(rep),
            });
        }
        Ok((trial, report.expect("at least one part")))
    }

    /// Move to the converged `trial` at `target` in `iterations`: the controller accepts the
    /// step. Returns the step taken and the state it started from.
    pub(super) fn advance(
        &mut self,
        target: f64,
        trial: Vec<f64>,
        iterations: usize,
    ) -> (StepContext, Vec<f64>) {
        let x_last = std::mem::replace(&mut self.x, trial);
        let step = self.model.path.step(self.ctl.t, target);
        self.ctl.accept(target, iterations);
        (step, x_last)
    }

    /// A failed attempt: whatever it wrote into the history goes, and the controller cuts the
    /// step (`Err`: the step it would take, below the minimum).
    pub(super) fn cut(&mut self) -> Result<(), f64> {
        self.asm.restore();
        self.ctl.reject()
    }

    /// Each group's reaction and heat flow at time `t` from the residual of the last assembly,
    /// which must have been at the state, and the heat all boundaries convect away.
    pub(super) fn flows_assembled(&self, t: f64) -> Result<(Reactions, f64), AssemblyError> {
        let convected = convection_heat(self.model, &self.x)?;
        let flows = group_flows(self.model, &self.asm.r_full, &convected, t);
        Ok((flows, convected.iter().sum()))
    }

    /// The mechanics settled at the time reached, over a step of no length; in a transient
    /// scene the temperature kept (a step of no length has no capacity: what it would solve
    /// for θ is a steady state, not the state; a one-way coupling does not solve it, a
    /// monolithic one solves it with the mechanics and leaves it), in a steady one settled
    /// too; the history stays as it was. To the relative residual `to` where given and
    /// looser than the steps' (see [`Newton::settling`]); where Newton does not converge, by
    /// continuation if the case has it. Returns the report and whether continuation took it,
    /// or why not (the state unchanged) where neither converges.
    ///
    /// `pad-flash` (settled after each of its 66 remakes) gives the same `history.csv` but
    /// for θ's relative residuals at round-off, whose scale the discarded solve had raised;
    /// its remakes took 0.214–0.218 of its wall with the solve, 0.205–0.207 without.
    pub(super) fn settle_mechanics(
        &mut self,
        to: Option<f64>,
    ) -> Result<(StepReport, bool), StepFailure> {
        let transient = self.model.physics.transient;
        let tol = self.newton.tol;
        if let Some(to) = to {
            (self.newton.tol, self.newton.settling) = (tol.max(to), true);
        }
        let t = self.ctl.t;
        let mut attempt = (self.attempt_by(t, Newton::step, transient)).map(|a| (a, false));
        if let (Err(StepFailure::NotConverged { .. }), true) = (&attempt, self.continues()) {
            attempt = (self.attempt_by(t, Newton::continuation, transient)).map(|a| (a, true));
        }
        (self.newton.tol, self.newton.settling) = (tol, false);
        let settled = attempt.map(|((x, rep), continued)| {
            let dofs = &self.model.dofs;
            for (d, v) in x.into_iter().enumerate() {
                if !transient || dofs.field[d] != Field::Theta {
                    self.x[d] = v;
                }
            }
            (rep, continued)
        });
        self.asm.restore();
        settled
    }

    /// Where the run stands: "λ = 0.500000", or with `[time]` "t = 1.2000e0 (λ = 1.000000)",
    /// or on a path that λ does not follow "t = 1.077382 (λ = 1.000000)".
    pub(super) fn position(&self) -> String {
        let t = self.ctl.t;
        let lambda = self.model.path.lambda(t);
        if self.show_t() {
            format!("t = {} (λ = {lambda:.6})", self.t_text(t))
        } else {
            format!("λ = {lambda:.6}")
        }
    }

    /// Where a step to `t` ends, for a line: λ, and the physical time with `[time]`.
    pub(super) fn clock_text(&self, t: f64) -> String {
        let lambda = self.model.path.lambda(t);
        if self.show_t() {
            format!("t {}  λ {lambda:.4}", self.t_text(t))
        } else {
            format!("λ {lambda:.4}")
        }
    }

    /// Whether where a run stands is said in t as well as λ: over physical time, or over a
    /// pseudo-time that λ does not follow (a path such as `[0, 1, 1]`, whose second segment
    /// drags at λ = 1).
    pub(super) fn show_t(&self) -> bool {
        self.transient_clock || !self.model.path.lambda_is_time()
    }

    /// A time for a message: physical time to five significant digits, pseudo-time to six
    /// decimals (as λ).
    pub(super) fn t_text(&self, t: f64) -> String {
        if self.transient_clock {
            format!("{t:.4e}")
        } else {
            format!("{t:.6}")
        }
    }
}

/// The residual at the state `x` at λ = 0, as a run's first step records it (and `tmc check`
/// assembles it): what makes it invalid (a radiating face at θ ≤ 0) ends the run before it
/// starts.
pub(super) fn assemble_initial(
    asm: &mut Assembler,
    model: &Model,
    x: &[f64],
) -> Result<AssemblyStats, SolveError> {
    (asm.assemble(model, x, &model.path.step(0.0, 0.0), false, None))
        .map_err(|e| SolveError::Setup(format!("the initial state is invalid: {e}")))
}

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

/// How a run's direct solvers order their equations. A medium made again in 2D plans the
/// run anew every few steps: there faer's minimum degree, found in a fraction of METIS's time
/// with about as little fill, took 18 % off the frictionless pad in a box's remakes (7 % off
/// its run) and 10 % off those of the README cylinder slid on h = 0.05 (4 %;
/// docs/notes/2026-12-05-a-remake-s-plan-made-cheaper.md). In 3D, where gmsh's meshing is
/// most of a remake and minimum degree fills more, and in any other run, METIS's nested
/// dissection.
fn ordering(case: &Case, model: &Model) -> Ordering {
    if case.remade_medium().is_some() && model.mesh.dim == 2 {
        Ordering::MinimumDegree
    } else {
        Ordering::NestedDissection
    }
}
