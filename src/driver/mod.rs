//! `tmc solve`: case → mesh → model → load stepping with Newton → VTU series, history, summary.

pub mod records;
mod run;
pub mod strategy;

pub use records::{HISTORY_SOLVER_COLUMNS, HISTORY_STEP_COLUMNS, Summary, group_flows, reactions};
pub use strategy::{Strategy, choose_linear, choose_strategy, describe};

use crate::case::{Case, CaseError};
use crate::mesh::gmsh::{GmshError, MeshOptions, mesh_geo};
use crate::mesh::msh::{MshError, read_msh};
use crate::model::{Model, build};
use crate::output::probes::{self, Probe};
use crate::output::{self, OutputError};
use crate::solver::idle::IdleThreads;
use crate::solver::linear::LinearError;
use run::Run;
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
    #[error("linear solver: {0}")]
    Linear(#[from] LinearError),
    #[error("{0}")]
    Setup(String),
    #[error(
        "load step from λ = {lambda:.6} failed with Δλ = {dlambda:.3e}, below the minimum step ({reason}); \
         the {steps} converged steps up to λ = {lambda:.6} are in {dir}"
    )]
    StepTooSmall {
        lambda: f64,
        dlambda: f64,
        reason: String,
        steps: usize,
        dir: PathBuf,
    },
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
}

/// Mesh the case's `.geo` into `out_dir/mesh.msh`, or return its `.msh` path.
pub fn mesh_for(case: &Case, out_dir: &Path) -> Result<PathBuf, SolveError> {
    let path = case.mesh_path();
    match path.extension().and_then(|e| e.to_str()) {
        Some("geo") => {
            let out = out_dir.join("mesh.msh");
            let m = &case.file.mesh_options;
            let opts = MeshOptions {
                order: m.order.unwrap_or(1),
                incomplete: m.incomplete,
                set_numbers: m.params.iter().map(|(k, v)| (k.clone(), *v)).collect(),
                verbose: false,
            };
            mesh_geo(&path, &out, &opts)?;
            Ok(out)
        }
        Some("msh") => Ok(path),
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

/// Solve a case file end to end.
pub fn run(case_path: &Path, opts: &SolveOptions) -> Result<Summary, SolveError> {
    let start = Instant::now();
    let case = Case::read(case_path)?;
    let out_dir = opts
        .out_dir
        .clone()
        .unwrap_or_else(|| PathBuf::from("results").join(case.name()));
    output::clean_dir(&out_dir)?;
    let msh = mesh_for(&case, &out_dir)?;
    let mesh = read_msh(&msh)?;
    case.validate(&mesh)?;
    let model = build(&case, mesh)?;
    let probes = probes::build(&case, &model.mesh)?;
    solve_model(&case, model, &probes, &out_dir, opts, start)
}

/// Step the model from its initial state to the end of its load path.
fn solve_model(
    case: &Case,
    model: Model,
    probes: &[Probe],
    out_dir: &Path,
    opts: &SolveOptions,
    start: Instant,
) -> Result<Summary, SolveError> {
    let mut run = Run::new(case, &model, probes, out_dir, opts, start)?;
    run.record_initial()?;
    while !run.ctl.done() {
        let target = run.ctl.target();
        match run.attempt(target) {
            Ok((trial, rep)) => run.accept(target, trial, rep)?,
            Err(failure) => run.reject(target, failure)?,
        }
    }
    run.complete()
}
