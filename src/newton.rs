//! Newton–Raphson on the monolithic system for one load step.
//!
//! Convergence is checked per field (u, θ, p). A field's residual is measured against the
//! largest of: its norm at the step's first iteration, the norm of its reactions (internal
//! forces on prescribed dofs), and the largest such reference seen earlier in the run. A step is
//! converged only when every field's residual is below `tol` times its reference *and* the
//! update that residual implies (solved with the last factorisation, no new one) is below
//! `sqrt(tol)` times the step's largest update of that field.

use crate::assembly::{Assembler, AssemblyError, AssemblyStats};
use crate::dofs::{Field, NONE};
use crate::linsolve::{LinearError, LinearSolver};
use crate::model::Model;

/// Norms per field, indexed by `Field as usize`.
pub type FieldNorms = [f64; 3];

fn idx(f: Field) -> usize {
    match f {
        Field::U => 0,
        Field::Theta => 1,
        Field::P => 2,
    }
}

#[derive(Clone, Debug)]
pub struct StepReport {
    pub iterations: usize,
    /// Relative residual per field at each iteration.
    pub history: Vec<FieldNorms>,
    pub stats: AssemblyStats,
    /// Seconds in assembly, factorisation and solves.
    pub t_assembly: f64,
    pub t_solve: f64,
}

#[derive(Debug)]
pub enum StepFailure {
    NotConverged { iterations: usize, last: FieldNorms },
    Assembly(AssemblyError),
    Linear(LinearError),
}

impl std::fmt::Display for StepFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StepFailure::NotConverged { iterations, last } => write!(
                f,
                "no convergence in {iterations} iterations (relative residuals u {:.1e}, theta {:.1e}, p {:.1e})",
                last[0], last[1], last[2]
            ),
            StepFailure::Assembly(e) => write!(f, "{e}"),
            StepFailure::Linear(e) => write!(f, "{e}"),
        }
    }
}

/// Newton state carried across steps: references for the per-field residual scale.
pub struct Newton {
    pub tol: f64,
    pub max_iter: usize,
    run_ref: FieldNorms,
    /// Field of each free equation.
    eq_field: Vec<Field>,
}

impl Newton {
    pub fn new(model: &Model, tol: f64, max_iter: usize) -> Newton {
        let mut eq_field = vec![Field::U; model.cons.n_eq];
        for (d, &e) in model.cons.eq.iter().enumerate() {
            if e != NONE {
                eq_field[e as usize] = model.dofs.field[d];
            }
        }
        Newton {
            tol,
            max_iter,
            run_ref: [0.0; 3],
            eq_field,
        }
    }

    fn norms(&self, v: &[f64]) -> FieldNorms {
        let mut n = [0.0; 3];
        for (x, &f) in v.iter().zip(&self.eq_field) {
            n[idx(f)] += x * x;
        }
        n.map(f64::sqrt)
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

    /// Solve the step λ_old → λ_new, updating `x` in place. On failure `x` is left modified:
    /// the caller restores its copy of the last converged state.
    pub fn step(
        &mut self,
        model: &Model,
        asm: &mut Assembler,
        solver: &mut LinearSolver,
        x: &mut [f64],
        lambda: f64,
    ) -> Result<StepReport, StepFailure> {
        let n_eq = model.cons.n_eq;
        let eq = &model.cons.eq;
        let mut t_asm = 0.0;
        let mut t_sol = 0.0;
        // increment of the prescribed values, moved to the right-hand side
        let mut dx_p = vec![0.0; x.len()];
        for (d, p) in model.cons.prescribed.iter().enumerate() {
            if let Some(p) = p {
                dx_p[d] = p.at(lambda) - x[d];
            }
        }
        let mut rhs = vec![0.0; n_eq];
        let mut history = Vec::new();
        let mut step_ref = [0.0; 3];
        let mut du_ref = [0.0; 3];
        let mut last_update: FieldNorms;
        let mut it = 0;
        loop {
            let t0 = std::time::Instant::now();
            let first = it == 0;
            let stats = asm
                .assemble(
                    model,
                    x,
                    lambda,
                    true,
                    if first { Some(&dx_p) } else { None },
                )
                .map_err(StepFailure::Assembly)?;
            t_asm += t0.elapsed().as_secs_f64();
            for (d, &e) in eq.iter().enumerate() {
                if e != NONE {
                    rhs[e as usize] = -asm.r_full[d];
                }
            }
            if first {
                for (r, l) in rhs.iter_mut().zip(&asm.lift) {
                    *r -= l;
                }
            }
            let res = self.norms(&rhs);
            let reac = Self::reaction_norms(model, &asm.r_full);
            for f in 0..3 {
                if first {
                    step_ref[f] = res[f];
                }
                step_ref[f] = step_ref[f].max(reac[f]);
                self.run_ref[f] = self.run_ref[f].max(step_ref[f]);
            }
            let rel: FieldNorms = std::array::from_fn(|f| {
                let r = step_ref[f].max(self.run_ref[f]);
                if r > 0.0 { res[f] / r } else { 0.0 }
            });
            history.push(rel);
            let residual_ok = rel.iter().all(|&r| r <= self.tol);
            if it >= self.max_iter {
                return Err(StepFailure::NotConverged {
                    iterations: it,
                    last: rel,
                });
            }
            let t1 = std::time::Instant::now();
            if !residual_ok || first {
                solver.factor(&asm.values).map_err(StepFailure::Linear)?;
            }
            solver.solve(&mut rhs);
            t_sol += t1.elapsed().as_secs_f64();
            if !rhs.iter().all(|v| v.is_finite()) {
                return Err(StepFailure::Assembly(AssemblyError::NotFinite));
            }
            last_update = self.norms(&rhs);
            for (d, &e) in eq.iter().enumerate() {
                if e != NONE {
                    x[d] += rhs[e as usize];
                } else if first {
                    x[d] += dx_p[d];
                }
            }
            if first {
                let pres = {
                    let mut n = [0.0; 3];
                    for (d, v) in dx_p.iter().enumerate() {
                        n[idx(model.dofs.field[d])] += v * v;
                    }
                    n.map(f64::sqrt)
                };
                du_ref = pres;
            }
            for f in 0..3 {
                du_ref[f] = du_ref[f].max(last_update[f]);
            }
            if residual_ok && !first {
                // an update is small against the step's largest one, or negligible against the
                // field itself (a field the step hardly changes has round-off updates only)
                let size = self.norms_of_state(model, x);
                let update_ok = (0..3).all(|f| {
                    last_update[f] <= self.tol.sqrt() * du_ref[f]
                        || last_update[f] <= 1e-10 * size[f]
                });
                if update_ok {
                    return Ok(StepReport {
                        iterations: it,
                        history,
                        stats,
                        t_assembly: t_asm,
                        t_solve: t_sol,
                    });
                }
            }
            it += 1;
        }
    }
}
