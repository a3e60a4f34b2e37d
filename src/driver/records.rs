//! What a run records: `summary.json` (extend, never rename), the columns of `history.csv`,
//! reactions per Dirichlet group.

use super::strategy::Strategy;
use crate::dofs::Field;
use crate::model::{Model, Physics};
use crate::solver::linear::LinearKind;
use serde::Serialize;
use std::collections::BTreeMap;

/// What `summary.json` holds (extend, never rename: users' scripts rely on it).
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub case: String,
    pub mesh: String,
    pub dim: usize,
    /// Mesh nodes (of cells).
    pub nodes: usize,
    pub cells: BTreeMap<String, usize>,
    pub dofs: BTreeMap<String, usize>,
    pub physics: Physics,
    pub linear_solver: LinearKind,
    /// How the coupled fields are solved: "single_field", "one_way" (mechanics, then heat on
    /// the deformed state, each with a symmetric factorisation) or "monolithic".
    pub strategy: Strategy,
    pub converged: bool,
    pub message: String,
    pub lambda: f64,
    /// Pseudo-time reached (equal to λ without a `[steps] path`).
    pub time: f64,
    pub load_steps: usize,
    pub rejected_steps: usize,
    /// Newton iterations of the accepted steps.
    pub newton_iterations: usize,
    /// Newton iterations of the rejected attempts (their time is in the seconds below).
    pub rejected_iterations: usize,
    /// Newton updates (linear solves) of every attempt, accepted or rejected: a mechanical
    /// step of n iterations makes n + 1. The count the assembly and solver seconds are spent on.
    pub linear_solves: usize,
    pub wall_seconds: f64,
    /// Assembly time of the whole run: every attempt, and the converged states' reactions.
    pub assembly_seconds: f64,
    /// Factorisation and linear-solve time of every attempt.
    pub solver_seconds: f64,
    /// GMRES iterations over all accepted steps (0 with a direct solver).
    pub krylov_iterations: usize,
    /// Accepted steps whose converging residual was assembled without the tangent (its
    /// factorisation was reused for the last update).
    pub tangents_skipped: usize,
    /// Peak resident memory of the process so far, MB (Linux; null elsewhere).
    pub peak_memory_mb: Option<f64>,
    pub probes: BTreeMap<String, f64>,
    pub reactions: BTreeMap<String, BTreeMap<String, f64>>,
    /// Smallest J at any quadrature point of any accepted step (solids and medium).
    pub min_J: f64,
    pub min_J_solid: Option<f64>,
    /// `null` without a medium.
    pub min_J_medium: Option<f64>,
    /// Stored energy of the last accepted state (elastic, medium and regularization).
    pub energy: f64,
    /// Work of the forces on the displacements, ∫ f·du summed by the trapezoidal rule over the
    /// accepted steps. Equals `energy` for hyperelastic scenes without thermal strain.
    pub external_work: f64,
    pub output: String,
}

/// The leading columns of history.csv: the step's bookkeeping. Then come `energy`, the probes
/// and the reactions, then [`HISTORY_SOLVER_COLUMNS`] and `work`.
pub const HISTORY_STEP_COLUMNS: [&str; 9] = [
    "step",
    "lambda",
    "dlambda",
    "newton_iterations",
    "res_u",
    "res_theta",
    "res_p",
    "min_J_solid",
    "min_J_medium",
];

/// The solver's counters and the pseudo-time, near the end of history.csv.
pub const HISTORY_SOLVER_COLUMNS: [&str; 3] = ["krylov_iterations", "halvings", "time"];

/// Reactions per Dirichlet group: force components on the body and heat supplied to it.
pub fn reactions(model: &Model, r_full: &[f64]) -> BTreeMap<String, BTreeMap<String, f64>> {
    let mut out: BTreeMap<String, BTreeMap<String, f64>> = BTreeMap::new();
    let d = model.dofs.dim;
    let comp = ["x", "y", "z"];
    for (n, _) in model.mesh.coords.iter().enumerate() {
        if model.dofs.has(Field::U) {
            for c in 0..d {
                let dof = model.dofs.u[n * d + c] as usize;
                if let Some(p) = model.cons.prescribed[dof] {
                    *out.entry(model.bc_groups[p.bc].name.clone())
                        .or_default()
                        .entry(comp[c].into())
                        .or_default() += r_full[dof];
                }
            }
        }
        if model.dofs.has(Field::Theta) {
            let dof = model.dofs.theta[n] as usize;
            if let Some(p) = model.cons.prescribed[dof] {
                *out.entry(model.bc_groups[p.bc].name.clone())
                    .or_default()
                    .entry("heat".into())
                    .or_default() += r_full[dof];
            }
        }
    }
    out
}

/// The process's peak resident set (VmHWM) in MB, where /proc tells it.
pub(super) fn peak_memory_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}
