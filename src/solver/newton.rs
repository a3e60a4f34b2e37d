//! Newton–Raphson on the monolithic system for one load step.
//!
//! Convergence is checked per field (u, θ, p). A field's residual is measured against the
//! largest of: its norm at the step's first iteration, the norm of its reactions (internal
//! forces on prescribed dofs), and the largest such reference seen earlier in the run. A step is
//! converged only when every field's residual is below `tol` times its reference *and* the
//! update that residual implies (solved with the last factorisation, no new one) is below
//! `sqrt(tol)` times the step's largest update of that field. Where the iterations run out with
//! updates that do not shrink (the tangent singular along them), the step ends at the first
//! state after its start whose residual met the tolerance against its own reactions, if one
//! did ([`Newton::end_at_met`]).
//!
//! The regularization fields p_i are lengths (p_i ≈ d f_i), so their residuals are forces like
//! those of u: p is measured against the larger of the u and p references. Without that, a
//! field that the load hardly excites (p in a uniaxial squeeze) would be judged against its
//! own round-off.

mod continuation;

use super::idle::IdleThreads;
use super::linear::{LinearError, LinearSolver, SolveParts};
use crate::assembly::{Assembler, AssemblyError, AssemblyStats};
use crate::dofs::{Field, NONE, equation_structure};
use crate::model::{Model, StepContext};

/// Norms per field, indexed by `Field as usize`.
pub type FieldNorms = [f64; 3];

fn idx(f: Field) -> usize {
    match f {
        Field::U => 0,
        Field::Theta => 1,
        Field::P => 2,
    }
}

/// Halvings of one update before the step is given up.
const MAX_HALVINGS: usize = 8;

/// The reference of field `f`: its own, or for p the larger of the u and p ones.
fn same_units(f: usize, r: impl Fn(usize) -> f64) -> f64 {
    if f == idx(Field::P) {
        r(f).max(r(idx(Field::U)))
    } else {
        r(f)
    }
}

#[derive(Clone, Debug)]
pub struct StepReport {
    pub iterations: usize,
    /// Times an update was halved because it left the admissible set.
    pub halvings: usize,
    /// Relative residual per field at each iteration.
    pub history: Vec<FieldNorms>,
    pub stats: AssemblyStats,
    /// Krylov iterations over the step (0 with a direct solver).
    pub krylov: usize,
    /// Tangents not assembled: a step about to converge reuses its factorisation for the
    /// last update, so its last assembly is the residual only (1, or 0 if mispredicted).
    pub tangents_skipped: usize,
    /// Whether the step ended at the first state whose residual met the tolerance in balance
    /// with its own reactions, the updates after it not shrinking (`Newton::end_at_met`).
    pub balanced_only: bool,
}

#[derive(Debug)]
pub enum StepFailure {
    /// `met`: the last residual was below tolerance, but the updates did not shrink.
    /// `largest`: where the last residual's worst field is largest (not for `met`).
    NotConverged {
        iterations: usize,
        last: FieldNorms,
        met: bool,
        largest: Option<Largest>,
    },
    Assembly(AssemblyError),
    Linear(LinearError),
}

impl std::fmt::Display for StepFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StepFailure::NotConverged {
                iterations,
                last,
                met,
                largest,
            } => {
                let fields = format!(
                    "u {:.1e}, theta {:.1e}, p {:.1e}",
                    last[0], last[1], last[2]
                );
                if *met {
                    write!(
                        f,
                        "no convergence in {iterations} iterations: the residual is below \
                         tolerance (relative {fields}) but Newton's updates do not shrink (the \
                         tangent is singular along them: the load path turns or branches here)"
                    )
                } else {
                    write!(
                        f,
                        "no convergence in {iterations} iterations (relative residuals {fields})"
                    )?;
                    match largest {
                        Some(l) => write!(f, "; {l}"),
                        None => Ok(()),
                    }
                }
            }
            StepFailure::Assembly(e) => write!(f, "{e}"),
            StepFailure::Linear(e) => write!(f, "{e}"),
        }
    }
}

/// Where a residual is largest: the field, and the mesh node (reference coordinates) of the
/// equation. A step that fails at one corner of a large mesh says which.
#[derive(Debug)]
pub struct Largest {
    pub field: Field,
    pub at: Vec<f64>,
}

impl std::fmt::Display for Largest {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let at: Vec<String> = self.at.iter().map(|x| format!("{x:.4}")).collect();
        write!(
            f,
            "its {} residual is largest at the node at ({})",
            self.field.name(),
            at.join(", ")
        )
    }
}

impl StepFailure {
    /// Whether a smaller load step may succeed where this attempt failed (see
    /// [`LinearError::recoverable`]); a failure that is not ends the run.
    pub fn recoverable(&self) -> bool {
        match self {
            StepFailure::Linear(e) => e.recoverable(),
            _ => true,
        }
    }
}

impl StepReport {
    /// The report of this part of a step followed by `next` (the next part, same step).
    pub fn then(self, next: StepReport) -> StepReport {
        let last = |r: &StepReport| r.history.last().copied().unwrap_or([0.0; 3]);
        let (a, b) = (last(&self), last(&next));
        let mut history = self.history;
        history.extend(next.history);
        // the step's final residuals: each field as its own part left it
        history.push(std::array::from_fn(|f| a[f].max(b[f])));
        StepReport {
            iterations: self.iterations + next.iterations,
            halvings: self.halvings + next.halvings,
            history,
            // a part assembles only its own equations: J from either, energy from mechanics
            stats: AssemblyStats {
                min_J_solid: self.stats.min_J_solid.min(next.stats.min_J_solid),
                min_J_medium: self.stats.min_J_medium.min(next.stats.min_J_medium),
                energy: self.stats.energy + next.stats.energy,
            },
            krylov: self.krylov + next.krylov,
            tangents_skipped: self.tangents_skipped + next.tangents_skipped,
            balanced_only: self.balanced_only || next.balanced_only,
        }
    }
}

/// Which equations a Newton solve iterates on: all of them (monolithic), or one side of a
/// one-way coupled system (mechanics u with p, then heat on the deformed state).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    All,
    Mechanics,
    /// Conduction on the converged deformed state: linear in θ, so one solve.
    Heat,
}

impl Part {
    /// What the part solves, in words.
    pub fn name(self) -> &'static str {
        match self {
            Part::All => "the whole system",
            Part::Mechanics => "mechanics",
            Part::Heat => "heat",
        }
    }

    /// The equations a kernel call must fill for this part.
    pub fn active(self) -> crate::kernel::Active {
        crate::kernel::Active {
            mechanics: self.has(Field::U),
            heat: self.has(Field::Theta),
        }
    }

    pub fn has(self, f: Field) -> bool {
        match self {
            Part::All => true,
            Part::Mechanics => f != Field::Theta,
            Part::Heat => f == Field::Theta,
        }
    }
}

/// Work done by all attempts of a run, rejected ones included.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Spent {
    /// Seconds in assembly (residual and tangent).
    pub assembly: f64,
    /// Seconds in factorisations and linear solves.
    pub solve: f64,
    /// Newton iterations, counted as in [`StepReport::iterations`].
    pub iterations: usize,
    /// Newton updates, each one linear solve: one more than the iterations per attempt (the
    /// first update applies the step's prescribed increments).
    pub updates: usize,
    /// Numeric factorisations (fewer than the updates where a factor was kept).
    #[serde(default)]
    pub factorisations: usize,
    /// Of [`Spent::solve`], the seconds in factorisations and in applying the factors, where
    /// the engine times them apart.
    #[serde(default)]
    pub parts: Option<SolveParts>,
}

/// What Newton carries from one step to the next, and over a restart: the run's residual
/// references and the work of every attempt so far.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct Tally {
    pub run_ref: FieldNorms,
    pub spent: Spent,
}

/// Newton state carried across steps: references for the per-field residual scale.
pub struct Newton {
    pub tol: f64,
    /// A settling (a step of no length from a state a remake left a little out of balance):
    /// it ends at the first residual below `tol` (with no update if that is the first),
    /// whatever its updates.
    pub settling: bool,
    pub max_iter: usize,
    /// Totals over every step attempt so far, converged or not.
    pub spent: Spent,
    run_ref: FieldNorms,
    /// Residual per field below which it has converged whatever its reference: round-off for
    /// the stiffest body (u and p), for the most conductive one (θ). A step that loads a field
    /// with nothing (the equilibrium at λ = 0 under temperatures held in full; the heat of a
    /// first, tiny slip in a scene that is nowhere warm yet) leaves it only round-off
    /// residuals, which no reference built from that step's own loads can judge.
    floor: FieldNorms,
    /// Update per field below which it is negligible whatever the step's updates (u and p; 0
    /// for θ): a displacement of 1e-12 of the body's extent.
    update_floor: FieldNorms,
    /// Field of each free equation.
    eq_field: Vec<Field>,
    /// What the other threads do during linear solves.
    pub idle: IdleThreads,
}

/// The largest of the fields' relative residuals.
fn worst(h: &FieldNorms) -> f64 {
    h.iter().fold(0.0f64, |a, &v| a.max(v))
}

/// The heat flow that a temperature difference of 1e-12 of the scene's temperatures (its
/// largest initial or prescribed |θ|, at least one degree) drives through the most
/// conductive body across its extent: a θ residual below it is round-off.
fn heat_floor(model: &Model) -> f64 {
    let k = model
        .blocks
        .iter()
        .map(|b| b.mat.cond.k_max())
        .fold(0.0, f64::max);
    let prescribed = (model.cons.prescribed.iter().zip(&model.dofs.field))
        .filter(|(_, f)| **f == Field::Theta)
        .filter_map(|(p, _)| p.as_ref())
        .flat_map(|p| [p.value, p.start]);
    let theta = (model.theta_init.iter().copied())
        .chain(prescribed)
        .fold(1.0, |a: f64, t| a.max(t.abs()));
    1e-12 * k * theta * model.d.powi(model.mesh.dim as i32 - 2)
}

/// A relative residual at or below which Newton is in its last, quadratic iterations: the
/// tangent moves little from one to the next, so an engine may keep its last factor.
/// Measured on Table 2 H1 16×16: a factor one iteration old preconditioned the new tangent
/// within 12 GMRES iterations at every residual up to 7.3e-4, at none from 1.6e-3 up.
const NEAR_RESIDUAL: f64 = 1e-3;

/// Halvings of an update whose residual grew.
const MAX_DAMPING: usize = 3;

/// The share of `max_iter` a step may take beyond it while Newton is in its quadratic tail:
/// its largest relative residual at most [`NEAR_RESIDUAL`] and at most a tenth of the
/// iteration's before. From there two or three iterations converge, where cutting the step
/// throws away every iteration it took (at 1.1M unknowns a rejected attempt of 16 iterations
/// cost half an hour). A quarter: 4 more at the default 16, none below 4.
const TAIL_SHARE: usize = 4;

impl Newton {
    pub fn new(model: &Model, tol: f64, max_iter: usize) -> Newton {
        let mut eq_field = vec![Field::U; model.cons.n_eq];
        for (d, &e) in model.cons.eq.iter().enumerate() {
            if e != NONE {
                eq_field[e as usize] = model.dofs.field[d];
            }
        }
        // a residual below the force that strains the stiffest body by 1e-12 (modulus × area
        // of its extent × 1e-12) is converged whatever the step's loads
        let modulus = model
            .blocks
            .iter()
            .map(|b| b.mat.law.stiffness_scale())
            .fold(0.0, f64::max);
        let force = 1e-12 * modulus * model.d.powi(model.mesh.dim as i32 - 1);
        let mut floor = [0.0; 3];
        floor[idx(Field::U)] = force;
        floor[idx(Field::P)] = force;
        floor[idx(Field::Theta)] = heat_floor(model);
        let mut update_floor = [0.0; 3];
        update_floor[idx(Field::U)] = 1e-12 * model.d;
        update_floor[idx(Field::P)] = 1e-12 * model.d;
        Newton {
            tol,
            settling: false,
            max_iter,
            spent: Spent::default(),
            run_ref: [0.0; 3],
            floor,
            update_floor,
            eq_field,
            idle: IdleThreads::default(),
        }
    }

    /// The residual references and the work so far (what a restart carries over).
    /// The residual of field `f` below which it is round-off (see `floor`).
    pub fn floor(&self, f: Field) -> f64 {
        self.floor[idx(f)]
    }

    pub fn tally(&self) -> Tally {
        Tally {
            run_ref: self.run_ref,
            spent: self.spent,
        }
    }

    /// Continue a run: its references and the work of its attempts so far.
    pub fn resume(&mut self, tally: Tally) {
        self.run_ref = tally.run_ref;
        self.spent = tally.spent;
    }

    /// The free equations of `part`, increasing.
    pub fn equations(&self, part: Part) -> Vec<usize> {
        (0..self.eq_field.len())
            .filter(|&e| part.has(self.eq_field[e]))
            .collect()
    }

    fn norms(&self, v: &[f64]) -> FieldNorms {
        let mut n = [0.0; 3];
        for (x, &f) in v.iter().zip(&self.eq_field) {
            n[idx(f)] += x * x;
        }
        n.map(f64::sqrt)
    }

    /// −r on the free equations of `part`, 0 on the others.
    fn free_residual(&self, model: &Model, part: Part, r_full: &[f64], out: &mut [f64]) {
        for (d, &e) in model.cons.eq.iter().enumerate() {
            if e != NONE {
                out[e as usize] = if part.has(model.dofs.field[d]) {
                    -r_full[d]
                } else {
                    0.0
                };
            }
        }
    }

    /// Where the residual `r` (free equations) of the field worst in `rel` is largest.
    fn largest(&self, model: &Model, r: &[f64], rel: &FieldNorms) -> Option<Largest> {
        let worst = (0..3).max_by(|&a, &b| rel[a].total_cmp(&rel[b]))?;
        let e = (0..r.len())
            .filter(|&e| idx(self.eq_field[e]) == worst)
            .max_by(|&a, &b| r[a].abs().total_cmp(&r[b].abs()))?;
        let node = equation_structure(&model.dofs, &model.cons).node[e] as usize;
        Some(Largest {
            field: self.eq_field[e],
            at: model.mesh.coords[node][..model.mesh.dim].to_vec(),
        })
    }

    /// Norms of the free part of the state per field.
    fn norms_of_state(&self, model: &Model, x: &[f64]) -> FieldNorms {
        let mut n = [0.0; 3];
        for (d, &e) in model.cons.eq.iter().enumerate() {
            if e != NONE {
                n[idx(self.eq_field[e as usize])] += x[d] * x[d];
            }
        }
        n.map(f64::sqrt)
    }

    fn reaction_norms(model: &Model, r_full: &[f64]) -> FieldNorms {
        let mut n = [0.0; 3];
        for (d, p) in model.cons.prescribed.iter().enumerate() {
            if p.is_some() {
                n[idx(model.dofs.field[d])] += r_full[d] * r_full[d];
            }
        }
        n.map(f64::sqrt)
    }

    /// Solve the step λ_old → λ_new for the equations of `part`, updating `x` in place (the
    /// other fields stay as they are). `solver` must be built for exactly those equations
    /// ([`Newton::equations`]). On failure `x` is left modified: the caller restores its copy
    /// of the last converged state.
    pub fn step(
        &mut self,
        model: &Model,
        asm: &mut Assembler,
        solver: &mut LinearSolver,
        x: &mut [f64],
        step: &StepContext,
        part: Part,
    ) -> Result<StepReport, StepFailure> {
        let mut st = StepState::new(self, model, x.len(), step.t, part);
        solver.take_krylov();
        let mut it = 0;
        // the last update was small: the step most likely ends at the next residual
        let mut expect_converged = false;
        let mut prev_rel = f64::INFINITY;
        let mut met: Option<Met> = None;
        loop {
            let first = it == 0;
            let r = self.damped_residual(&mut st, model, asm, x, step, first, expect_converged)?;
            st.history.push(r.rel);
            self.keep_met(&mut met, &st, model, asm, x, r, it);
            if r.converged && self.settling {
                return Ok(st.report(r, it, solver));
            }
            let rel = worst(&r.rel);
            let limit = if rel <= NEAR_RESIDUAL && rel <= 0.1 * prev_rel {
                self.max_iter + self.max_iter / TAIL_SHARE
            } else {
                self.max_iter
            };
            if it >= limit && !r.converged {
                if let Some(met) = met.take() {
                    return self.end_at_met(st, model, asm, solver, x, step, met);
                }
                return Err(StepFailure::NotConverged {
                    iterations: it,
                    last: r.rel,
                    met: false,
                    largest: self.largest(model, &st.rhs, &r.rel),
                });
            }
            // near: the tangent moved little since the last iteration's (a factor of a state
            // converged, or both residuals in the quadratic tail)
            solver.set_near(first || rel.max(prev_rel) <= NEAR_RESIDUAL);
            prev_rel = rel;
            self.solve_update(&mut st, solver, asm, r.converged && !first)?;
            let last_update = self.norms(&st.rhs);
            st.apply(model, x, r.pending);
            if first {
                // the prescribed increments are the step's first update
                st.du_ref = st.prescribed_norms(model);
            }
            for f in 0..3 {
                st.du_ref[f] = st.du_ref[f].max(last_update[f]);
            }
            let converged_after = if part == Part::Heat {
                Some(self.heat_converged(&mut st, model, asm, x, step)?)
            } else {
                let (done, expect) =
                    self.converged(&st, model, x, &last_update, r.converged, first);
                expect_converged = expect;
                done.then_some(it)
            };
            if let Some(iterations) = converged_after {
                return Ok(st.report(r, iterations, solver));
            }
            if it >= limit {
                if let Some(met) = met.take() {
                    return self.end_at_met(st, model, asm, solver, x, step, met);
                }
                return Err(StepFailure::NotConverged {
                    iterations: it,
                    last: r.rel,
                    met: r.converged,
                    largest: None,
                });
            }
            it += 1;
            self.spent.iterations += 1;
        }
    }

    /// Keep in `met` the state `x` at iteration `it` with its residual `r` if it is the first
    /// after the step's start whose residual met the tolerance, every load applied, in balance
    /// with its own reactions ([`Newton::balanced`]).
    #[allow(clippy::too_many_arguments)]
    fn keep_met(
        &self,
        met: &mut Option<Met>,
        st: &StepState,
        model: &Model,
        asm: &Assembler,
        x: &[f64],
        r: Residual,
        it: usize,
    ) {
        let candidate = met.is_none() && r.converged && !r.pending && it > 0;
        if candidate && st.part != Part::Heat && self.balanced(st, model, asm) {
            *met = Some((x.to_vec(), r, it));
        }
    }

    /// Whether the residual in `st.rhs` (no increment pending) is below tolerance against the
    /// reactions of the state assembled last alone, or round-off: a state in balance whatever
    /// the step's and the run's largest references, which may be many times its own loads
    /// (a pad on one crushed cell met 5e-10 of them with its forces open by 2e-3).
    fn balanced(&self, st: &StepState, model: &Model, asm: &Assembler) -> bool {
        let res = self.norms(&st.rhs);
        let reac = Self::reaction_norms(model, &asm.r_full);
        (0..3)
            .filter(|&f| st.active[f])
            .all(|f| res[f] <= self.tol * same_units(f, |g| reac[g]) || res[f] <= self.floor[f])
    }

    /// The step's end at `met` (a state, its residual and the iterations to it: the first after
    /// the step's start whose residual met the tolerance), where the iterations after it did not
    /// converge: `x` put back there and assembled there again, so that what the assembler holds
    /// (the reactions, friction's trial slip) is that state's, and its residual the step's last.
    #[allow(clippy::too_many_arguments)]
    fn end_at_met(
        &mut self,
        mut st: StepState,
        model: &Model,
        asm: &mut Assembler,
        solver: &mut LinearSolver,
        x: &mut [f64],
        step: &StepContext,
        met: Met,
    ) -> Result<StepReport, StepFailure> {
        let (at, r, iterations) = met;
        x.copy_from_slice(&at);
        let (stats, _) = self.assemble_admissible(&mut st, model, asm, x, step, false, false)?;
        st.history.push(r.rel);
        let r = Residual {
            stats,
            tangent: false,
            ..r
        };
        Ok(StepReport {
            balanced_only: true,
            ..st.report(r, iterations, solver)
        })
    }

    /// An iteration's residual at `x`, and its tangent unless the step is `expect_converged`
    /// (a step about to converge reuses its factorisation for the last update, so its last
    /// tangent would be thrown away: then the residual is assembled alone, and the tangent only
    /// if the residual turns out not converged after all). A full update can overshoot: where
    /// the medium closes (its stiffness grows without bound) and at friction's stick–slip
    /// switches. While the residual grows, the update is halved (a few times, then kept
    /// regardless). Undamped, Newton wandered at residuals of 0.1–10 until the iteration
    /// limit, 25 % of block-plate-3d's iterations, on a path that round-off alone could change.
    #[allow(clippy::too_many_arguments)]
    fn damped_residual(
        &mut self,
        st: &mut StepState,
        model: &Model,
        asm: &mut Assembler,
        x: &mut [f64],
        step: &StepContext,
        first: bool,
        expect_converged: bool,
    ) -> Result<Residual, StepFailure> {
        let t0 = std::time::Instant::now();
        let mut tangent = first || !expect_converged;
        let mut damped = 0;
        let out = loop {
            let (stats, pending) =
                match self.assemble_admissible(st, model, asm, x, step, tangent, first) {
                    Ok(a) => a,
                    Err(e) => break Err(e),
                };
            let rel = self.relative_residual(st, model, asm, pending, first);
            let converged = rel.iter().all(|&r| r <= self.tol);
            let grew = st
                .history
                .last()
                .is_some_and(|last| worst(&rel) > worst(last));
            if !first && !converged && grew && damped < MAX_DAMPING {
                damped += 1;
                st.cuts += 1;
                st.halve_update(x);
                tangent = true;
                continue;
            }
            if !tangent && (!converged || pending) {
                tangent = true;
                continue;
            }
            break Ok(Residual {
                stats,
                pending,
                rel,
                converged,
                tangent,
            });
        };
        self.spent.assembly += t0.elapsed().as_secs_f64();
        out
    }

    /// Assemble at `x`, the prescribed increments still to apply lifted to the right-hand
    /// side. Safeguard: an update that leaves the admissible set (J ≤ 0, an unbounded
    /// regularization, NaN) is halved until the state is admissible again. Returns the
    /// statistics and whether prescribed increments are pending.
    #[allow(clippy::too_many_arguments)]
    fn assemble_admissible(
        &mut self,
        st: &mut StepState,
        model: &Model,
        asm: &mut Assembler,
        x: &mut [f64],
        step: &StepContext,
        tangent: bool,
        first: bool,
    ) -> Result<(AssemblyStats, bool), StepFailure> {
        let part = st.part;
        let mut halvings = 0;
        loop {
            let mut pending = false;
            for (d, p) in model.cons.prescribed.iter().enumerate() {
                if let Some(p) = p.filter(|_| part.has(model.dofs.field[d])) {
                    st.dx_p[d] = p.at(&st.amps) - x[d];
                    pending |= st.dx_p[d] != 0.0;
                }
            }
            match asm.assemble_part(
                model,
                x,
                step,
                tangent,
                pending.then_some(&st.dx_p[..]),
                part.active(),
            ) {
                Ok(stats) => {
                    st.cuts += halvings;
                    return Ok((stats, pending));
                }
                Err(e) if first || halvings == MAX_HALVINGS || !e.is_inadmissible() => {
                    return Err(StepFailure::Assembly(e));
                }
                Err(_) => {
                    halvings += 1;
                    st.halve_update(x);
                }
            }
        }
    }

    /// −r on the free equations into `st.rhs` (less the lifting where increments are
    /// pending), the references updated, and the residual of each active field relative to
    /// its reference.
    fn relative_residual(
        &mut self,
        st: &mut StepState,
        model: &Model,
        asm: &Assembler,
        pending: bool,
        first: bool,
    ) -> FieldNorms {
        let part = st.part;
        self.free_residual(model, part, &asm.r_full, &mut st.rhs);
        if pending {
            for ((r, l), f) in st.rhs.iter_mut().zip(&asm.lift).zip(&self.eq_field) {
                if part.has(*f) {
                    *r -= l;
                }
            }
        }
        let res = self.norms(&st.rhs);
        let reac = Self::reaction_norms(model, &asm.r_full);
        for f in (0..3).filter(|&f| st.active[f]) {
            if first {
                st.step_ref[f] = res[f];
            }
            st.step_ref[f] = st.step_ref[f].max(reac[f]);
            self.run_ref[f] = self.run_ref[f].max(st.step_ref[f]);
        }
        std::array::from_fn(|f| {
            let r = same_units(f, |g| st.step_ref[g].max(self.run_ref[g]));
            let rel = if r > 0.0 && st.active[f] {
                res[f] / r
            } else {
                0.0
            };
            self.floored(f, res[f], rel)
        })
    }

    /// The relative residual `rel` of field `f`, or less where its residual `res` is below
    /// the field's floor (round-off: converged whatever its reference).
    fn floored(&self, f: usize, res: f64, rel: f64) -> f64 {
        if res <= self.floor[f] {
            rel.min(self.tol * res / self.floor[f])
        } else {
            rel
        }
    }

    /// Solve for the update into `st.rhs`, with a new factorisation unless `reuse` allows the
    /// last one (a converged residual after the first iteration).
    fn solve_update(
        &mut self,
        st: &mut StepState,
        solver: &mut LinearSolver,
        asm: &Assembler,
        reuse: bool,
    ) -> Result<(), StepFailure> {
        let t1 = std::time::Instant::now();
        let (rhs, b_sub, sub) = (&mut st.rhs, &mut st.b_sub, &st.sub);
        let solved = self.idle.run(|| {
            if !reuse {
                solver.factor(&asm.values)?;
            }
            if let Some(sub) = sub {
                for (b, &e) in b_sub.iter_mut().zip(sub) {
                    *b = rhs[e];
                }
                solver.solve(b_sub)?;
                for (b, &e) in b_sub.iter().zip(sub) {
                    rhs[e] = *b;
                }
                Ok(())
            } else {
                solver.solve(rhs)
            }
        });
        self.spent.solve += t1.elapsed().as_secs_f64();
        self.spent.factorisations += solver.take_factorisations();
        if let Some(p) = solver.take_parts() {
            *self.spent.parts.get_or_insert_with(SolveParts::default) += p;
        }
        solved.map_err(StepFailure::Linear)?;
        self.spent.updates += 1;
        if !st.rhs.iter().all(|v| v.is_finite()) {
            return Err(StepFailure::Assembly(AssemblyError::NotFinite));
        }
        Ok(())
    }

    /// Conduction on a fixed deformed state is linear in θ (k depends on J only): the direct
    /// solve is the solution, and a residual-only assembly reports it. One iteration.
    fn heat_converged(
        &mut self,
        st: &mut StepState,
        model: &Model,
        asm: &mut Assembler,
        x: &[f64],
        step: &StepContext,
    ) -> Result<usize, StepFailure> {
        let t2 = std::time::Instant::now();
        asm.assemble_part(model, x, step, false, None, st.part.active())
            .map_err(StepFailure::Assembly)?;
        self.spent.assembly += t2.elapsed().as_secs_f64();
        let mut r = vec![0.0; model.cons.n_eq];
        self.free_residual(model, st.part, &asm.r_full, &mut r);
        let th = idx(Field::Theta);
        let res = self.norms(&r)[th];
        let rel = res / st.step_ref[th].max(self.run_ref[th]).max(f64::MIN_POSITIVE);
        let rel = self.floored(th, res, rel);
        if !(rel <= self.tol) {
            return Err(StepFailure::NotConverged {
                iterations: 1,
                last: [0.0, rel, 0.0],
                met: false,
                largest: self.largest(model, &r, &[0.0, rel, 0.0]),
            });
        }
        st.history.push([0.0, rel, 0.0]);
        self.spent.iterations += 1;
        Ok(1)
    }

    /// Whether the step has converged after the update `last_update` (residual below
    /// tolerance before it, not the first iteration, and the update small), and whether the
    /// next residual is expected to converge (the update small and the residual falling
    /// quadratically).
    fn converged(
        &self,
        st: &StepState,
        model: &Model,
        x: &[f64],
        last_update: &FieldNorms,
        residual_ok: bool,
        first: bool,
    ) -> (bool, bool) {
        // an update is small against the step's largest one, or negligible against the field
        // itself (a field the step hardly changes has round-off updates only)
        let size = self.norms_of_state(model, x);
        let update_ok = (0..3).filter(|&f| st.active[f]).all(|f| {
            last_update[f] <= self.tol.sqrt() * same_units(f, |g| st.du_ref[g])
                || last_update[f] <= 1e-10 * same_units(f, |g| size[g])
                || last_update[f] <= self.update_floor[f]
        });
        // and the residual, falling at its last rate, would be below tolerance
        let falling = match st.history.as_slice() {
            [.., a, b] => worst(b) * worst(b) <= self.tol * worst(a),
            _ => false,
        };
        (residual_ok && !first && update_ok, update_ok && falling)
    }
}

/// What one step's Newton iterations carry from one to the next.
struct StepState {
    part: Part,
    /// The amplitudes of the prescribed values at the step's time.
    amps: Vec<f64>,
    /// Fields the part iterates on.
    active: [bool; 3],
    /// The free equations of the part, when it is not the whole system, and their values.
    sub: Option<Vec<usize>>,
    b_sub: Vec<f64>,
    /// Increment of the prescribed values still to apply, moved to the right-hand side.
    dx_p: Vec<f64>,
    /// −r on the free equations, then the update.
    rhs: Vec<f64>,
    /// The update applied last (all dofs), halved on overshoot.
    applied: Vec<f64>,
    /// Relative residual per field at each iteration.
    history: Vec<FieldNorms>,
    /// The step's residual references and largest updates per field.
    step_ref: FieldNorms,
    du_ref: FieldNorms,
    /// Halvings over the step.
    cuts: usize,
}

/// The first state after a step's start whose residual met the tolerance in balance with its
/// own reactions, that residual, and the iterations to it: where the step ends if its
/// iterations run out with updates that do not shrink ([`Newton::end_at_met`]).
type Met = (Vec<f64>, Residual, usize);

/// An iteration's residual: the assembly's statistics, whether prescribed increments are
/// still to apply, the relative residual per field and whether it is converged, and whether
/// the tangent was assembled with it.
#[derive(Clone, Copy)]
struct Residual {
    stats: AssemblyStats,
    pending: bool,
    rel: FieldNorms,
    converged: bool,
    tangent: bool,
}

impl StepState {
    /// The report of the step converged at the residual `r` in `iterations`.
    fn report(self, r: Residual, iterations: usize, solver: &mut LinearSolver) -> StepReport {
        StepReport {
            iterations,
            halvings: self.cuts,
            history: self.history,
            stats: r.stats,
            krylov: solver.take_krylov(),
            tangents_skipped: usize::from(!r.tangent),
            balanced_only: false,
        }
    }

    /// The norms per field of the step's prescribed increments (its first update).
    fn prescribed_norms(&self, model: &Model) -> FieldNorms {
        let mut n = [0.0; 3];
        for (d, v) in self.dx_p.iter().enumerate() {
            n[idx(model.dofs.field[d])] += v * v;
        }
        n.map(f64::sqrt)
    }

    fn new(newton: &Newton, model: &Model, n_dofs: usize, t: f64, part: Part) -> StepState {
        let sub = (part != Part::All).then(|| newton.equations(part));
        StepState {
            part,
            amps: model.path.amplitudes(t),
            active: Field::ALL.map(|f| part.has(f)),
            b_sub: vec![0.0; sub.as_ref().map_or(0, Vec::len)],
            sub,
            dx_p: vec![0.0; n_dofs],
            rhs: vec![0.0; model.cons.n_eq],
            applied: vec![0.0; n_dofs],
            history: Vec::new(),
            step_ref: [0.0; 3],
            du_ref: [0.0; 3],
            cuts: 0,
        }
    }

    /// Take back half of the update applied last.
    fn halve_update(&mut self, x: &mut [f64]) {
        for (xi, a) in x.iter_mut().zip(self.applied.iter_mut()) {
            *a *= 0.5;
            *xi -= *a;
        }
    }

    /// Apply the update in `rhs` (free equations) and the pending prescribed increments to
    /// `x`, and keep it as the update applied last.
    fn apply(&mut self, model: &Model, x: &mut [f64], pending: bool) {
        for (d, &e) in model.cons.eq.iter().enumerate() {
            self.applied[d] = if e != NONE {
                self.rhs[e as usize]
            } else if pending {
                self.dx_p[d]
            } else {
                0.0
            };
            x[d] += self.applied[d];
        }
    }
}

#[cfg(test)]
mod tests {
    //! Newton on a small system of its own: the block scene on a coarse mesh (8 × 4 solid
    //! cells over 2 of medium, mechanics, heat and p), one step from the undeformed state.

    use super::*;
    use crate::case::Case;
    use crate::dofs::equation_structure;
    use crate::mesh::gmsh::{MeshOptions, mesh_geo};
    use crate::solver::linear::LinearKind;
    use std::path::Path;

    /// The coarse block's model, its `.geo` meshed into `target/unit-scratch/newton/NAME.msh`
    /// (a file per test: they run at once).
    fn block(name: &str) -> Model {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let case = Case::read(&root.join("cases/block.toml")).unwrap();
        let out = root.join(format!("target/unit-scratch/newton/{name}.msh"));
        std::fs::create_dir_all(out.parent().unwrap()).unwrap();
        let opts = MeshOptions {
            order: 1,
            incomplete: false,
            set_numbers: vec![("n".into(), 8.0), ("m".into(), 4.0), ("l".into(), 2.0)],
            verbose: false,
        };
        let mesh = mesh_geo(&case.mesh_path(), &out, &opts).unwrap().mesh;
        crate::model::validate::validate(&case, &mesh).unwrap();
        crate::model::build(&case, mesh).unwrap()
    }

    /// The assembler, an LU solver and a Newton to 1e-10 in `max_iter` iterations for `model`.
    fn solving(model: &Model, max_iter: usize) -> (Assembler, LinearSolver, Newton) {
        let asm = Assembler::new(model);
        let structure = equation_structure(&model.dofs, &model.cons);
        let solver = LinearSolver::new(LinearKind::Lu, &asm.pattern, &structure).unwrap();
        (asm, solver, Newton::new(model, 1e-10, max_iter))
    }

    /// One step from the initial state to pseudo-time `t` with `max_iter` iterations.
    fn step(model: &Model, t: f64, max_iter: usize) -> Result<StepReport, StepFailure> {
        let (mut asm, mut solver, mut newton) = solving(model, max_iter);
        let mut x = model.initial_state();
        let context = model.path.step(0.0, t);
        newton.step(model, &mut asm, &mut solver, &mut x, &context, Part::All)
    }

    /// The coarse block's model (a mesh file `name` as in [`block`]), its assembler, solver
    /// and Newton, and the state one step converged to t = 0.05 from the initial one.
    struct Converged {
        model: Model,
        asm: Assembler,
        solver: LinearSolver,
        newton: Newton,
        x: Vec<f64>,
        to: StepContext,
    }

    fn converged(name: &str) -> Converged {
        let model = block(name);
        let (mut asm, mut solver, mut newton) = solving(&model, 30);
        let mut x = model.initial_state();
        let to = model.path.step(0.0, 0.05);
        newton
            .step(&model, &mut asm, &mut solver, &mut x, &to, Part::All)
            .unwrap();
        Converged {
            model,
            asm,
            solver,
            newton,
            x,
            to,
        }
    }

    /// The worst field's relative residual at each iteration.
    fn worst_history(rep: &StepReport) -> Vec<f64> {
        rep.history.iter().map(worst).collect()
    }

    #[test]
    fn newton_converges_quadratically_on_a_small_step() {
        let model = block("quadratic");
        let rep = step(&model, 0.05, 30).unwrap();
        let r = worst_history(&rep);
        assert!(r.last().unwrap() <= &1e-10, "{r:?}");
        // in the asymptotic range each residual is about the square of the one before
        let tail: Vec<(f64, f64)> = (r.windows(2))
            .map(|w| (w[0], w[1]))
            .filter(|&(a, b)| a < 1e-2 && b > 1e-15)
            .collect();
        assert!(
            !tail.is_empty(),
            "no iteration in the quadratic range: {r:?}"
        );
        for (a, b) in tail {
            assert!(b <= 10.0 * a * a, "{b:.2e} after {a:.2e}: {r:?}");
        }
    }

    #[test]
    fn continuation_ends_where_newton_does_and_takes_its_first_moves_short() {
        let model = block("continuation");
        let to = model.path.step(0.0, 0.05);
        let solve = |continued: bool| {
            let (mut asm, mut solver, mut newton) = solving(&model, 30);
            let mut x = model.initial_state();
            let (asm, solver) = (&mut asm, &mut solver);
            let rep = match continued {
                false => newton.step(&model, asm, solver, &mut x, &to, Part::All),
                true => newton.continuation(&model, asm, solver, &mut x, &to, Part::All),
            };
            (x, rep.unwrap())
        };
        let (newton, by_newton) = solve(false);
        let (continued, by_continuation) = solve(true);
        // the same balance at the same load, to about the tolerance (1e-10)
        let gap = (newton.iter().zip(&continued)).fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
        let size = newton.iter().fold(0.0f64, |a, p| a.max(p.abs()));
        assert!(gap <= 1e-8 * size, "{gap:e} of {size:e}");
        let r = worst_history(&by_continuation);
        assert!(*r.last().unwrap() <= 1e-10, "{r:?}");
        // the shifted updates are shorter than Newton's: more iterations to the same state
        assert!(
            by_continuation.iterations > by_newton.iterations,
            "{} against Newton's {}",
            by_continuation.iterations,
            by_newton.iterations
        );
    }

    #[test]
    fn a_step_that_cannot_converge_in_its_iterations_says_where_its_residual_is_largest() {
        let model = block("failure");
        let Err(failure) = step(&model, 1.0, 1) else {
            panic!("one iteration cannot close the medium");
        };
        let StepFailure::NotConverged {
            iterations,
            met,
            largest,
            ..
        } = &failure
        else {
            panic!("{failure}");
        };
        assert_eq!((*iterations, *met), (1, false));
        let largest = largest
            .as_ref()
            .expect("the node where the residual is largest");
        assert_eq!(largest.at.len(), 2);
        let text = failure.to_string();
        assert!(text.starts_with("no convergence in 1 iterations"), "{text}");
        // a failure a smaller step may mend
        assert!(failure.recoverable());
    }

    #[test]
    fn a_settling_ends_at_its_own_tolerance_and_updates_nothing_where_the_state_is_in_balance() {
        let Converged {
            model,
            mut asm,
            mut solver,
            mut newton,
            x,
            ..
        } = converged("settling");
        asm.commit();
        let at_rest = model.path.step(0.05, 0.05);
        let mut settle = |x: &mut Vec<f64>, to: Option<f64>| {
            newton.settling = to.is_some();
            newton.tol = to.unwrap_or(1e-10);
            let rep = newton.step(&model, &mut asm, &mut solver, x, &at_rest, Part::All);
            asm.restore();
            rep.unwrap()
        };
        // in balance to 1e-10: the first residual ends it
        let mut y = x.clone();
        let rep = settle(&mut y, Some(1e-6));
        assert_eq!((rep.iterations, rep.history.len()), (0, 1));
        assert!(worst_history(&rep)[0] <= 1e-6);
        assert_eq!(y, x);
        // the free displacements short by a share: out of balance
        let short = |share: f64| {
            let mut y = x.clone();
            for (d, &e) in model.cons.eq.iter().enumerate() {
                if e != NONE {
                    y[d] *= 1.0 - share;
                }
            }
            y
        };
        // by 1 %: it ends at the first residual below 1e-6, a step at one below 1e-10
        let (mut y, mut z) = (short(1e-2), short(1e-2));
        let settled = worst_history(&settle(&mut y, Some(1e-6)));
        let (last, before) = settled.split_last().unwrap();
        assert!(*last <= 1e-6 && !before.is_empty(), "{settled:?}");
        assert!(before.iter().all(|&r| r > 1e-6), "{settled:?}");
        let full = worst_history(&settle(&mut z, None));
        assert!(*full.last().unwrap() <= 1e-10, "{full:?}");
        assert!(full.len() >= settled.len(), "{full:?} against {settled:?}");
        // the settled state is the balanced one to about the residual's size
        let gap = (y.iter().zip(&z)).fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
        let size = z.iter().fold(0.0f64, |a, p| a.max(p.abs()));
        assert!(gap <= 1e-4 * size, "{gap:e} of {size:e}");
        // by 1e-7: settled already, where a step still updates
        let (mut y, mut z) = (short(1e-7), short(1e-7));
        let first = worst_history(&settle(&mut y, Some(1e-6)));
        assert!(first.len() == 1 && first[0] > 1e-10, "{first:?}");
        assert_eq!(y, short(1e-7));
        let full = worst_history(&settle(&mut z, None));
        assert!(full.len() > 1, "{full:?}");
    }

    #[test]
    fn a_step_out_of_iterations_ends_at_a_state_in_balance_with_its_own_reactions() {
        let Converged {
            model,
            mut asm,
            mut solver,
            mut newton,
            mut x,
            to,
        } = converged("balanced");
        // the residual at `y`, measured as a step measures it, and whether it is in balance
        let at = |newton: &mut Newton, asm: &mut Assembler, y: &mut Vec<f64>| {
            let mut st = StepState::new(newton, &model, y.len(), to.t, Part::All);
            let (stats, pending) =
                (newton.assemble_admissible(&mut st, &model, asm, y, &to, false, false)).unwrap();
            let rel = newton.relative_residual(&mut st, &model, asm, pending, false);
            let balanced = newton.balanced(&st, &model, asm);
            (
                st,
                stats,
                rel,
                !pending && rel.iter().all(|&r| r <= newton.tol),
                balanced,
            )
        };
        let (_, at_x, _, met, balanced) = at(&mut newton, &mut asm, &mut x);
        assert!(met && balanced);
        // the free displacements 1e-4 short: out of balance with its own reactions, though its
        // residual meets the tolerance against a run's reference a billion times larger
        let mut y = x.clone();
        for (d, &e) in model.cons.eq.iter().enumerate() {
            if e != NONE {
                y[d] *= 1.0 - 1e-4;
            }
        }
        let (_, _, _, met, balanced) = at(&mut newton, &mut asm, &mut y);
        assert!(!met && !balanced);
        let large = newton.run_ref;
        newton.run_ref = large.map(|r| 1e9 * r);
        let (st, _, rel, met, balanced) = at(&mut newton, &mut asm, &mut y);
        assert!(met && !balanced, "{rel:?}");
        newton.run_ref = large;
        // a step ending at x from y: x again, its own statistics, and the assembler holding
        // x's residual (in balance)
        let r = Residual {
            stats: at_x,
            pending: false,
            rel,
            converged: true,
            tangent: true,
        };
        let met = (x.clone(), r, 3);
        let rep = (newton.end_at_met(st, &model, &mut asm, &mut solver, &mut y, &to, met)).unwrap();
        assert_eq!(y, x);
        assert!(rep.balanced_only && rep.iterations == 3);
        assert_eq!(rep.stats.energy, at_x.energy);
        let mut st = StepState::new(&newton, &model, x.len(), to.t, Part::All);
        newton.relative_residual(&mut st, &model, &asm, false, false);
        assert!(newton.balanced(&st, &model, &asm));
    }

    #[test]
    fn an_update_that_would_invert_the_medium_is_damped_and_the_step_still_converges() {
        let model = block("damped");
        // the whole press at once: full updates overshoot where the medium closes
        match step(&model, 1.0, 60) {
            Ok(rep) => {
                assert!(
                    rep.halvings > 0,
                    "no update was cut: {:?}",
                    worst_history(&rep)
                );
                assert!(worst_history(&rep).last().unwrap() <= &1e-10);
            }
            Err(failure) => panic!("{failure}"),
        }
    }
}
