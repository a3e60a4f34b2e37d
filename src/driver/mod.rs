//! `tmc solve`: case → mesh → model → load stepping with Newton → VTU series, history, summary.

pub mod records;
pub mod strategy;

pub use records::{HISTORY_SOLVER_COLUMNS, HISTORY_STEP_COLUMNS, Summary, reactions};
pub use strategy::{Strategy, choose_linear, choose_strategy, describe};

use crate::assembly::Assembler;
use crate::case::{Case, CaseError, RegionKind};
use crate::dofs::{Field, NONE, equation_structure};
use crate::mesh::gmsh::{GmshError, MeshOptions, mesh_geo};
use crate::mesh::msh::{MshError, read_msh};
use crate::model::{Model, build};
use crate::output::probes::{self, Probe};
use crate::output::{self, History, OutputError, StepFields};
use crate::solver::idle::IdleThreads;
use crate::solver::linear::{LinearError, LinearKind, LinearSolver};
use crate::solver::newton::{Newton, Part, Spent, StepFailure, StepReport};
use crate::solver::stepping::Controller;
use records::peak_memory_mb;
use std::collections::BTreeMap;
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

/// A line above the progress bar, or on stderr when the bar is hidden (not a terminal).
fn say(pb: &indicatif::ProgressBar, line: &str) {
    if pb.is_hidden() {
        eprintln!("{line}");
    } else {
        pb.println(line);
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

fn solve_model(
    case: &Case,
    model: Model,
    probes: &[Probe],
    out_dir: &Path,
    opts: &SolveOptions,
    start: Instant,
) -> Result<Summary, SolveError> {
    let kind = choose_linear(case.file.solver.linear, &model.physics);
    if kind == LinearKind::Ldlt && model.physics.mechanics && model.physics.conduction {
        let span = case.file.mesh.span();
        return Err(case
            .error::<()>(span, "[solver] linear = \"ldlt\" needs a symmetric tangent, but this scene couples mechanics and conduction")
            .unwrap_err()
            .into());
    }
    let strategy = choose_strategy(&case.file.solver, &model.physics);
    let mut asm = Assembler::new(&model);
    let steps = &case.file.steps;
    let mut newton = Newton::new(&model, steps.tol, steps.max_iter);
    newton.idle = opts.idle_threads;
    let structure = equation_structure(&model.dofs, &model.cons);
    // one solver per part: the whole system, or mechanics and heat of a one-way scene
    let mut solvers: Vec<(Part, LinearSolver)> = match strategy {
        Strategy::OneWay => vec![
            (
                Part::Mechanics,
                LinearSolver::block_ldlt(
                    &asm.pattern,
                    &structure,
                    &newton.equations(Part::Mechanics),
                )?,
            ),
            (
                Part::Heat,
                LinearSolver::block_ldlt(&asm.pattern, &structure, &newton.equations(Part::Heat))?,
            ),
        ],
        _ => vec![(
            Part::All,
            LinearSolver::new(kind, &asm.pattern, &structure)?,
        )],
    };
    let kind = solvers[0].1.kind;
    if !opts.quiet {
        eprintln!("{}", describe(&model.physics, strategy));
    }
    let mut ctl = Controller::new(steps, model.path.end());
    if !model.physics.mechanics {
        // conduction on the undeformed body is linear: one step (per path segment), one solve
        ctl.dt = 1.0;
    }
    let mut x = model.initial_state();

    // bookkeeping for output
    let d = model.mesh.dim;
    let region_of_cell: Vec<i32> = model
        .blocks
        .iter()
        .flat_map(|b| std::iter::repeat_n(b.region as i32, model.mesh.cells[b.block].n_cells()))
        .collect();
    let kind_of_cell: Vec<i32> = region_of_cell
        .iter()
        .map(|&r| (model.regions[r as usize].1 == RegionKind::Medium) as i32)
        .collect();
    let mut reaction_cols: Vec<(String, String)> = Vec::new();
    for g in &model.bc_groups {
        for f in &g.fields {
            let (has, key) = match *f {
                "theta" => (model.dofs.has(Field::Theta), "heat"),
                c => (model.dofs.has(Field::U), &c[1..]),
            };
            if has {
                reaction_cols.push((g.name.clone(), key.to_string()));
            }
        }
    }
    let mut columns: Vec<String> = HISTORY_STEP_COLUMNS.map(String::from).to_vec();
    columns.push("energy".into());
    columns.extend(probes.iter().map(|p| p.name.clone()));
    columns.extend(reaction_cols.iter().map(|(g, k)| {
        if k == "heat" {
            format!("Q_{g}")
        } else {
            format!("R_{g}_{k}")
        }
    }));
    columns.extend(HISTORY_SOLVER_COLUMNS.map(String::from));
    columns.push("work".into());
    let mut history = History::new(&out_dir.join("history.csv"), &columns);
    let name = case.name();
    let mut pvd: Vec<(f64, String)> = Vec::new();

    let write_step = |step: usize,
                      x: &[f64],
                      pvd: &mut Vec<(f64, String)>,
                      lambda: f64|
     -> Result<(), SolveError> {
        let cells = output::fields::all_cell_fields(&model, x)
            .map_err(|e| SolveError::Setup(format!("post-processing failed: {e:?}")))?;
        let u: Vec<[f64; 3]> = (0..model.mesh.coords.len())
            .map(|n| {
                let mut v = [0.0; 3];
                if model.dofs.has(Field::U) {
                    for c in 0..d {
                        v[c] = x[model.dofs.u[n * d + c] as usize];
                    }
                }
                v
            })
            .collect();
        let theta: Option<Vec<f64>> = model
            .dofs
            .has(Field::Theta)
            .then(|| model.dofs.theta.iter().map(|&t| x[t as usize]).collect());
        let np = model.dofs.np;
        let p: Option<Vec<f64>> = model.dofs.has(Field::P).then(|| {
            model
                .dofs
                .p
                .iter()
                .map(|&d| if d == NONE { 0.0 } else { x[d as usize] })
                .collect()
        });
        let file = format!("step_{step:04}.vtu");
        output::write_vtu(
            &out_dir.join(&file),
            &model.mesh,
            &StepFields {
                u: &u,
                theta: theta.as_deref(),
                p: p.as_deref().map(|p| (p, np)),
                cells: &cells,
                region: &region_of_cell,
                kind: &kind_of_cell,
            },
        )?;
        pvd.push((lambda, file));
        output::write_pvd(&out_dir.join(format!("{name}.pvd")), pvd)?;
        Ok(())
    };

    // initial state
    write_step(0, &x, &mut pvd, 0.0)?;
    let stats0 = asm
        .assemble(&model, &x, 0.0, false, None)
        .map_err(|e| SolveError::Setup(format!("the initial state is invalid: {e}")))?;
    let mut row0 = vec![
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        stats0.min_J_solid,
        stats0.min_J_medium,
        stats0.energy,
    ];
    row0.extend(probes.iter().map(|p| p.eval(&model.mesh, &model.dofs, &x)));
    let r0 = reactions(&model, &asm.r_full);
    row0.extend(
        reaction_cols
            .iter()
            .map(|(g, k)| r0.get(g).and_then(|m| m.get(k)).copied().unwrap_or(0.0)),
    );
    row0.extend([0.0, 0.0, 0.0, 0.0]);
    history.row(&row0)?;
    // the forces on the displacement dofs, f_int = r + f_ext, for the work done by them
    let u_dofs: Vec<usize> = (0..model.dofs.n_dofs)
        .filter(|&d| model.dofs.field[d] == Field::U)
        .collect();
    let forces = |r: &[f64], t: f64| -> Vec<f64> {
        let mut fe = vec![0.0; model.dofs.n_dofs];
        model.f_ext(t, &mut fe);
        u_dofs.iter().map(|&d| r[d] + fe[d]).collect()
    };
    let mut f_last = forces(&asm.r_full, 0.0);
    let mut work = 0.0;

    let pb = if opts.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        let pb = indicatif::ProgressBar::new(1000);
        pb.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} λ {bar:30} {percent:>3}%  {msg}  [{elapsed_precise}]",
            )
            .expect("valid template"),
        );
        pb
    };
    let mut total_iterations = 0;
    let mut total_krylov = 0;
    // assembly of the converged states' reactions (Newton keeps the rest of the time)
    let mut t_reactions = 0.0;
    let mut min_j = (f64::INFINITY, f64::INFINITY);
    let mut last_reactions = r0;
    let mut last_failure = String::new();
    let mut summary = Summary {
        case: case.path.display().to_string(),
        mesh: model.mesh.source.display().to_string(),
        dim: d,
        nodes: model.mesh.coords.len(),
        cells: {
            let mut m = BTreeMap::new();
            for b in &model.mesh.cells {
                *m.entry(b.kind.name().to_string()).or_default() += b.n_cells();
            }
            m
        },
        dofs: {
            let mut m = BTreeMap::new();
            for f in Field::ALL {
                m.insert(f.name().to_string(), model.dofs.count(f));
            }
            m.insert("total".into(), model.dofs.n_dofs);
            m.insert("free".into(), model.cons.n_eq);
            m
        },
        physics: model.physics,
        linear_solver: kind,
        strategy,
        converged: false,
        message: String::new(),
        lambda: 0.0,
        time: 0.0,
        load_steps: 0,
        rejected_steps: 0,
        newton_iterations: 0,
        rejected_iterations: 0,
        linear_solves: 0,
        wall_seconds: 0.0,
        assembly_seconds: 0.0,
        solver_seconds: 0.0,
        krylov_iterations: 0,
        tangents_skipped: 0,
        peak_memory_mb: None,
        probes: BTreeMap::new(),
        reactions: BTreeMap::new(),
        min_J: 1.0,
        min_J_solid: None,
        min_J_medium: None,
        energy: stats0.energy,
        external_work: 0.0,
        output: out_dir.display().to_string(),
    };
    let finish = |s: &mut Summary,
                  converged: bool,
                  message: String,
                  x: &[f64],
                  r: &BTreeMap<String, BTreeMap<String, f64>>,
                  ctl: &Controller,
                  its: usize,
                  mj: (f64, f64),
                  spent: Spent,
                  t_reactions: f64|
     -> Result<(), SolveError> {
        s.converged = converged;
        s.message = message;
        s.lambda = model.path.lambda(ctl.t);
        s.time = ctl.t;
        s.load_steps = ctl.accepted;
        s.rejected_steps = ctl.rejected;
        s.newton_iterations = its;
        s.rejected_iterations = spent.iterations - its;
        s.linear_solves = spent.updates;
        s.wall_seconds = start.elapsed().as_secs_f64();
        s.assembly_seconds = spent.assembly + t_reactions;
        s.solver_seconds = spent.solve;
        s.peak_memory_mb = peak_memory_mb();
        s.probes = probes
            .iter()
            .map(|p| (p.name.clone(), p.eval(&model.mesh, &model.dofs, x)))
            .collect();
        s.reactions = r.clone();
        let finite = |v: f64| v.is_finite().then_some(v);
        s.min_J_solid = finite(mj.0);
        s.min_J_medium = finite(mj.1);
        s.min_J = finite(mj.0.min(mj.1)).unwrap_or(1.0);
        let json = serde_json::to_string_pretty(&*s).expect("serialisable");
        output::write_atomic(&out_dir.join("summary.json"), json.as_bytes())?;
        Ok(())
    };

    while !ctl.done() {
        let target = ctl.target();
        let lambda = model.path.lambda(target);
        let dl = lambda - model.path.lambda(ctl.t);
        let mut trial = x.clone();
        let mut result: Result<Option<StepReport>, StepFailure> = Ok(None);
        for (part, solver) in solvers.iter_mut() {
            result = result.and_then(|acc| {
                let rep = newton.step(&model, &mut asm, solver, &mut trial, target, *part)?;
                Ok(Some(match acc {
                    None => rep,
                    Some(a) => a.then(rep),
                }))
            });
        }
        match result.map(|r| r.expect("at least one part")) {
            Ok(rep) => {
                let x_last = std::mem::replace(&mut x, trial);
                ctl.accept(target, rep.iterations);
                total_iterations += rep.iterations;
                min_j = (
                    min_j.0.min(rep.stats.min_J_solid),
                    min_j.1.min(rep.stats.min_J_medium),
                );
                // reactions at the converged state (the residual of the last assembly)
                let t0 = Instant::now();
                asm.assemble(&model, &x, target, false, None)
                    .map_err(|e| SolveError::Setup(format!("converged state is invalid: {e}")))?;
                t_reactions += t0.elapsed().as_secs_f64();
                last_reactions = reactions(&model, &asm.r_full);
                let f_now = forces(&asm.r_full, target);
                work += u_dofs
                    .iter()
                    .zip(f_last.iter().zip(&f_now))
                    .map(|(&d, (a, b))| 0.5 * (a + b) * (x[d] - x_last[d]))
                    .sum::<f64>();
                f_last = f_now;
                summary.energy = rep.stats.energy;
                summary.external_work = work;
                let last = rep.history.last().copied().unwrap_or([0.0; 3]);
                let mut row = vec![
                    ctl.accepted as f64,
                    lambda,
                    dl,
                    rep.iterations as f64,
                    last[0],
                    last[1],
                    last[2],
                    rep.stats.min_J_solid,
                    rep.stats.min_J_medium,
                    rep.stats.energy,
                ];
                row.extend(probes.iter().map(|p| p.eval(&model.mesh, &model.dofs, &x)));
                row.extend(reaction_cols.iter().map(|(g, k)| {
                    last_reactions
                        .get(g)
                        .and_then(|m| m.get(k))
                        .copied()
                        .unwrap_or(0.0)
                }));
                row.extend([rep.krylov as f64, rep.halvings as f64, target, work]);
                total_krylov += rep.krylov;
                summary.krylov_iterations = total_krylov;
                summary.tangents_skipped += rep.tangents_skipped;
                history.row(&row)?;
                write_step(ctl.accepted, &x, &mut pvd, target)?;
                let fmt_j = |j: f64| {
                    if j.is_finite() {
                        format!("{j:.3e}")
                    } else {
                        "-".into()
                    }
                };
                let line = format!(
                    "step {:3}  λ {:.4}  Δλ {:.2e}  its {:2}  min J solid {} medium {}",
                    ctl.accepted,
                    lambda,
                    dl,
                    rep.iterations,
                    fmt_j(rep.stats.min_J_solid),
                    fmt_j(rep.stats.min_J_medium)
                );
                if opts.verbose {
                    // the Newton table: largest relative field residual per iteration
                    let table: Vec<String> = rep
                        .history
                        .iter()
                        .map(|h| format!("{:.0e}", h.iter().fold(0.0f64, |a, &b| a.max(b))))
                        .collect();
                    say(&pb, &format!("{line}  [{}]", table.join(" ")));
                }
                pb.set_position((target / ctl.end * 1000.0) as u64);
                pb.set_message(format!("step {} its {}", ctl.accepted, total_iterations));
            }
            Err(f) => {
                last_failure = f.to_string();
                if opts.verbose {
                    say(
                        &pb,
                        &format!(
                            "  step to λ {lambda:.4} failed: {last_failure}; cutting the step"
                        ),
                    );
                }
                if let Err(dl) = ctl.reject() {
                    pb.finish_and_clear();
                    let err = SolveError::StepTooSmall {
                        lambda: model.path.lambda(ctl.t),
                        dlambda: dl,
                        reason: last_failure.clone(),
                        steps: ctl.accepted,
                        dir: out_dir.to_owned(),
                    };
                    finish(
                        &mut summary,
                        false,
                        err.to_string(),
                        &x,
                        &last_reactions,
                        &ctl,
                        total_iterations,
                        min_j,
                        newton.spent,
                        t_reactions,
                    )?;
                    return Err(err);
                }
            }
        }
    }
    pb.finish_and_clear();
    let msg = if ctl.rejected > 0 {
        format!(
            "converged ({} rejected attempts; last: {last_failure})",
            ctl.rejected
        )
    } else {
        "converged".into()
    };
    finish(
        &mut summary,
        true,
        msg,
        &x,
        &last_reactions,
        &ctl,
        total_iterations,
        min_j,
        newton.spent,
        t_reactions,
    )?;
    Ok(summary)
}
