//! Pseudo-transient continuation: a step Newton cannot converge, solved at its load by
//! iterations that start as small, damped moves and become Newton's as the residual falls.
//!
//! Each iteration solves (K + (σ/δ) I) Δx = −r, where K is the tangent, σ the median of its
//! diagonal over the equations solved (a stiffness of the mesh's typical node) and δ a pseudo
//! time step. δ starts at 1 (the diagonal about doubled: a short move along a direction between
//! Newton's and the residual's) and follows the residual ("switched evolution relaxation":
//! δ times the last residual over this one), so it grows without bound as the residual falls
//! and shrinks where it rises. The shift changes only the path, not where it ends: the step is
//! converged by Newton's own test (residual and update), at the same load, so a state it
//! reaches is in balance as any other step's is. Where the quasi-static path folds (a leading
//! corner that sticks, then lets go, under a friction of μ = 1), Newton from the last state
//! finds no nearby balance to converge to, however short the step; continuation moves the
//! state across to the one beyond the fold. An update that turns a cell inside out however
//! halved is taken back, and the pseudo time step shortened tenfold. Kelley and Keyes,
//! "Convergence analysis of pseudo-transient continuation", SIAM J. Numer. Anal. 35 (1998).

use super::{LinearSolver, Met, Newton, Part, Residual, StepFailure, StepReport, StepState, worst};
use crate::assembly::Assembler;
use crate::model::{Model, StepContext};

/// How many times a step's Newton iterations continuation may take (16 × this at the
/// default): tried after every failed attempt of the pad in a box dragged at μ = 1 (an
/// experiment), it took 19 to 163, 30 in the median.
const ITERATIONS_PER_NEWTON: usize = 10;

/// The largest pseudo time step: beyond it the shift is round-off against the tangent.
const DELTA_MAX: f64 = 1e12;

/// An update that leaves the admissible set (J ≤ 0) however halved is taken back, and the
/// pseudo time step made this much shorter; this many times in a row at most.
const SHORTER: f64 = 0.1;
const REFUSALS: usize = 6;

impl Newton {
    /// Solve the step to `step` from `x` (the last accepted state) by pseudo-transient
    /// continuation, for the equations of `part`. One rank only (the shift is laid on each
    /// rank's part of the tangent): elsewhere it fails at once. On failure `x` is left
    /// modified, as [`Newton::step`] leaves it. A one-way scene's heat is solved by Newton:
    /// it is linear in θ, one update converges it, where the shifted solves creep down its
    /// slowest modes (the sphere dragged with friction and heat stopped where its mechanics
    /// had been taken by continuation and its heat was not, at a residual of 1.5e-3 after
    /// 160 iterations).
    pub fn continuation(
        &mut self,
        model: &Model,
        asm: &mut Assembler,
        solver: &mut LinearSolver,
        x: &mut [f64],
        step: &StepContext,
        part: Part,
    ) -> Result<StepReport, StepFailure> {
        if part == Part::Heat {
            return self.step(model, asm, solver, x, step, part);
        }
        let equations = self.equations(part);
        let diagonal: Vec<usize> = (equations.iter())
            .filter_map(|&e| asm.pattern.find(e, e))
            .collect();
        let limit = self.max_iter * ITERATIONS_PER_NEWTON;
        if asm.ranks.size > 1 || diagonal.len() < equations.len() {
            return Err(StepFailure::NotConverged {
                iterations: 0,
                last: [f64::NAN; 3],
                met: false,
                largest: None,
            });
        }
        let mut st = StepState::new(self, model, x.len(), step.t, part);
        solver.take_krylov();
        let mut delta = 1.0_f64;
        let mut last = f64::NAN;
        // the last iterate assembled, and the refusals in a row since
        let mut before = x.to_vec();
        let mut refused = 0;
        let mut met: Option<Met> = None;
        for it in 0..=limit {
            let first = it == 0;
            let (stats, pending) =
                match self.assemble_admissible(&mut st, model, asm, x, step, true, first) {
                    Ok(assembled) => assembled,
                    Err(StepFailure::Assembly(e))
                        if e.is_inadmissible() && !first && refused < REFUSALS =>
                    {
                        // halved as Newton's are and still inadmissible: back to the last
                        // iterate, moving shorter from there
                        refused += 1;
                        x.copy_from_slice(&before);
                        delta *= SHORTER;
                        continue;
                    }
                    Err(e) => return Err(e),
                };
            refused = 0;
            let rel = self.relative_residual(&mut st, model, asm, pending, first);
            st.history.push(rel);
            let converged = rel.iter().all(|&r| r <= self.tol);
            let now = worst(&rel);
            let r = Residual {
                stats,
                pending,
                rel,
                converged,
                tangent: true,
            };
            self.keep_met(&mut met, &st, model, asm, x, r, it);
            if it == limit {
                if let Some(met) = met.take() {
                    return self.end_at_met(st, model, asm, solver, x, step, met);
                }
                let largest = self.largest(model, &st.rhs, &rel);
                return Err(StepFailure::NotConverged {
                    iterations: it,
                    last: rel,
                    met: converged,
                    largest,
                });
            }
            if last.is_finite() && now > 0.0 {
                delta = (delta * last / now).min(DELTA_MAX);
            }
            last = now;
            let shift = median(diagonal.iter().map(|&s| asm.values[s].abs())) / delta;
            for &s in &diagonal {
                asm.values[s] += shift;
            }
            before.copy_from_slice(x);
            self.solve_update(&mut st, solver, asm, false)?;
            let update = self.norms(&st.rhs);
            st.apply(model, x, pending);
            if first {
                st.du_ref = st.prescribed_norms(model);
            }
            for f in 0..3 {
                st.du_ref[f] = st.du_ref[f].max(update[f]);
            }
            let (done, _) = self.converged(&st, model, x, &update, converged, first);
            if done {
                return Ok(st.report(r, it, solver));
            }
            self.spent.iterations += 1;
        }
        // the limit reached taking back updates that left the admissible set
        if let Some(met) = met {
            return self.end_at_met(st, model, asm, solver, x, step, met);
        }
        Err(StepFailure::NotConverged {
            iterations: limit,
            last: st.history.last().copied().unwrap_or([f64::NAN; 3]),
            met: false,
            largest: None,
        })
    }
}

/// The median of `values` (0 for none).
fn median(values: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.collect();
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}
