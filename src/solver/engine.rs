//! The linear engines behind one trait. A run's plan says which systems its strategy solves
//! ([`System`]: the equations of a part and the symmetry of its tangent); the engine sets up a
//! solver for each: [`Faer`] on this process (LDLᵀ, LU with static pivots, GMRES with the
//! block-triangular preconditioner), or `Petsc` over the ranks of an MPI run. [`plan`] chooses
//! the engine from `[solver]` and the ranks the run has, and sets it up with the assembler
//! that goes with it (on several ranks, each rank's part of the mesh): the driver asks for a
//! plan and never names an engine.

use super::idle::IdleThreads;
use super::linear::{LinearError, LinearKind, LinearSolver};
use super::newton::Part;
use crate::assembly::Assembler;
use crate::case::{EngineChoice, PetscMethod, Solver};
use crate::dofs::{Ordering, Pattern, Structure, build_pattern, equation_structure};
use crate::model::Model;
use crate::parallel::Ranks;
use std::ops::Range;
use std::sync::Arc;

/// One system a strategy solves.
#[derive(Clone, Debug)]
pub struct System {
    pub part: Part,
    /// Its equations (increasing).
    pub eqs: Vec<usize>,
    /// Whether its tangent is symmetric.
    pub symmetric: bool,
    /// Whether its mechanics rows are (not with friction, whose limit moves with the normal
    /// traction).
    pub symmetric_mechanics: bool,
}

/// What solves a run's linear systems.
pub trait Engine {
    /// A solver for `system`, its symbolic analysis done, on the pattern of the whole system.
    fn solver(
        &self,
        system: &System,
        pattern: &Pattern,
        structure: &Structure,
    ) -> Result<LinearSolver, LinearError>;

    /// One solver per system, in order.
    fn solvers(
        &self,
        systems: &[System],
        pattern: &Pattern,
        structure: &Structure,
    ) -> Result<Vec<(Part, LinearSolver)>, LinearError> {
        systems
            .iter()
            .map(|s| Ok((s.part, self.solver(s, pattern, structure)?)))
            .collect()
    }
}

/// faer's sparse solvers on this process. `whole`: the method for a monolithic system (the
/// parts of a one-way split take LDLᵀ, or LU where their tangent is unsymmetric).
pub struct Faer {
    pub whole: LinearKind,
}

impl Engine for Faer {
    fn solver(
        &self,
        system: &System,
        pattern: &Pattern,
        structure: &Structure,
    ) -> Result<LinearSolver, LinearError> {
        match system.part {
            Part::All if self.whole == LinearKind::BlockGmres => {
                LinearSolver::block_gmres(pattern, structure, !system.symmetric_mechanics)
            }
            Part::All => LinearSolver::new(self.whole, pattern, structure),
            _ if system.symmetric => LinearSolver::block_ldlt(pattern, structure, &system.eqs),
            _ => LinearSolver::block_lu(pattern, structure, &system.eqs),
        }
    }
}

/// PETSc's KSP over the ranks, each holding the rows of the nodes it owns.
#[cfg(feature = "petsc")]
pub struct Petsc<'a> {
    pub own: super::petsc::Ownership<'a>,
    pub hints: super::petsc::Hints<'a>,
    pub method: crate::case::PetscMethod,
}

#[cfg(feature = "petsc")]
impl Engine for Petsc<'_> {
    fn solver(
        &self,
        system: &System,
        pattern: &Pattern,
        structure: &Structure,
    ) -> Result<LinearSolver, LinearError> {
        let on_ranks = super::petsc::PetscSystem::new(
            pattern,
            structure,
            &system.eqs,
            &self.own,
            system.symmetric,
            &self.hints,
            self.method,
        )?;
        Ok(LinearSolver::with(LinearKind::Petsc, Box::new(on_ranks)))
    }
}

/// What a run asks of its linear algebra: `[solver]` (engine, method and the PETSc engine's
/// options), the method chosen for faer's monolithic system, and what the other threads do
/// during faer's solves.
pub struct Request<'a> {
    pub solver: &'a Solver,
    pub whole: LinearKind,
    pub idle: IdleThreads,
    /// The memory (MB) the linear algebra may take (`None`: what the machine has available),
    /// for `engine = "auto"`.
    pub memory_mb: Option<f64>,
    /// Whether the run opens gmsh (meshes a `.geo`), whose libraries its memory then holds.
    pub gmsh: bool,
    /// How faer's direct solvers order their equations.
    pub ordering: Ordering,
}

/// The assembler and the solvers a run uses, their symbolic analyses done, and what Newton's
/// other threads may do during the solves.
pub struct Planned {
    pub asm: Assembler,
    /// One solver per system, in the order asked for.
    pub solvers: Vec<(Part, LinearSolver)>,
    pub idle: IdleThreads,
    /// Why `engine = "auto"` chose what it did, where it did not choose faer as usual.
    pub note: Option<String>,
}

/// Bytes a run holds per entry of its tangent, besides the direct factors: the tangent's
/// values and pattern, the blocks' copies of them, the assembler's maps, the Krylov vectors,
/// the mesh and the state. Measured on block-plate-3d-tm1 (H1, faer, block-triangular GMRES),
/// as (peak resident − factor bytes) / tangent entries: 57.5 at 147k unknowns (1 483 MB,
/// 15.9 M entries), 51.8 at 1.1 M (15 876 MB, 120 M entries).
const BYTES_PER_TANGENT_ENTRY: f64 = 60.0;

/// What a run that meshes its `.geo` holds whatever its size (the program and its libraries,
/// gmsh's among them, the runtime), MB: the peak resident of block-plate-3d-tm1 at 8×8 less
/// its tangent's and factor's share (23 MB): 50 MB without PETSc built in, 73 with it.
const BASE_MB: f64 = 80.0;

/// What gmsh's libraries (OpenCASCADE's among them) add to a run's resident memory, MB, where
/// it opens them: block-plate-3d-tm1's peak with its mesh made in the run against taken from
/// the cache of meshes, 75.6 against 35.5 MB at 8×8, 220.2 against 179.0 at 16×16.
pub const GMSH_MB: f64 = 40.0;

/// The peak memory of a run in MB, from its tangent's entries ([`BYTES_PER_TANGENT_ENTRY`]
/// each) and its factors' values in the precision each is held in (`factor_bytes`, as the
/// symbolic analysis laid them out), gmsh's libraries counted where the run opens them
/// (`gmsh`). Measured against it on block-plate-3d-tm1 (faer, the build without PETSc,
/// meshing): 73 / 210 / 1 483 / 15 876 MB at 3k / 20.5k / 147k / 1.1M unknowns for an
/// estimate of 103 / 248 / 1 603 / 16 944.
pub fn run_memory_mb(tangent_entries: usize, factor_bytes: Option<usize>, gmsh: bool) -> f64 {
    let base = if gmsh { BASE_MB } else { BASE_MB - GMSH_MB };
    base + (tangent_entries as f64 * BYTES_PER_TANGENT_ENTRY + factor_bytes.unwrap_or(0) as f64)
        / 1e6
}

/// The memory this machine has available now (`MemAvailable` of /proc/meminfo), MB.
fn available_mb() -> Option<f64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0 / 1e6)
}

/// With `engine = "auto"`: the memory faer's `solvers` would take on `pattern`, and the
/// budget, where it does not fit (`None` where it does, or where nothing is known).
fn over_budget(
    request: &Request,
    pattern: &Pattern,
    solvers: &[(Part, LinearSolver)],
) -> Option<(f64, f64)> {
    let factors = solvers.iter().map(|(_, s)| s.factor_bytes()).sum();
    let need = run_memory_mb(pattern.nnz(), factors, request.gmsh);
    let budget = request.memory_mb.or_else(available_mb)?;
    (need > budget).then_some((need, budget))
}

/// Why a run's linear algebra could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// Something the case says, at `span` (a byte range of its text).
    #[error("{message}")]
    Case { span: Range<usize>, message: String },
    /// The processes could not be set up (MPI, the mesh's partition).
    #[error("{0}")]
    Setup(String),
    #[error(transparent)]
    Linear(#[from] LinearError),
}

/// Set up the engine `request` asks for (PETSc when the case says so or the run has several
/// ranks; with `engine = "auto"` and `linear = "auto"` also where faer's factors would not fit
/// in the memory the run has, then with its multigrid; faer otherwise): its assembler (on
/// several ranks, each rank's part of the mesh) and one solver for each of `systems`.
pub fn plan(model: &Model, request: &Request, systems: &[System]) -> Result<Planned, PlanError> {
    if *request.solver.engine.get_ref() == EngineChoice::Petsc || !Ranks::world().is_serial() {
        return on_ranks(model, request, systems, request.solver.petsc.method);
    }
    // the assembler's maps and schedule beside the solvers' ordering and symbolic analysis:
    // a medium made again plans its run anew each time
    let pattern = Arc::new(build_pattern(&model.mesh, &model.dofs, &model.cons));
    let structure = Structure {
        ordering: request.ordering,
        ..equation_structure(&model.dofs, &model.cons)
    };
    let faer = Faer {
        whole: request.whole,
    };
    let (asm, solvers) = rayon::join(
        || Assembler::on(model, Arc::clone(&pattern)),
        || faer.solvers(systems, &pattern, &structure),
    );
    let solvers = solvers?;
    let auto = *request.solver.engine.get_ref() == EngineChoice::Auto
        && *request.solver.linear.get_ref() == crate::case::LinearChoice::Auto;
    let mut note = None;
    if auto && let Some((need, budget)) = over_budget(request, &asm.pattern, &solvers) {
        let why = format!(
            "a run on faer would take about {need:.0} MB at its peak, more than the {budget:.0} \
             MB it has"
        );
        if cfg!(feature = "petsc") {
            drop((solvers, asm));
            let mut planned = on_ranks(model, request, systems, PetscMethod::Multigrid)?;
            planned.note = Some(format!(
                "engine \"auto\": PETSc's multigrid, since {why} (--memory or TMC_MEMORY_MB \
                 sets the budget)"
            ));
            return Ok(planned);
        }
        note = Some(format!(
            "warning: engine \"auto\": {why}, and this tmc has no PETSc engine to solve without \
             them ({})",
            crate::parallel::NOT_BUILT
        ));
    }
    if !auto && let Some((need, budget)) = over_budget(request, &asm.pattern, &solvers) {
        let asked = match request.solver.engine.get_ref() {
            EngineChoice::Faer => "engine \"faer\"",
            _ => "a `linear` solver given",
        };
        note = Some(format!(
            "warning: {asked}: a run on faer would take about {need:.0} MB at its peak, more \
             than the {budget:.0} MB it has (--memory or TMC_MEMORY_MB sets the budget); it \
             runs as asked"
        ));
    }
    let petsc = &request.solver.petsc;
    if *request.solver.engine.get_ref() == EngineChoice::Faer
        && (petsc.options.is_some() || petsc.method != PetscMethod::Direct)
    {
        let ignored = "warning: engine \"faer\": [solver.petsc] is for the PETSc engine, and \
                       this run on one process ignores it (under mpirun, which runs on PETSc, \
                       it applies)";
        note = Some(match note {
            Some(n) => format!("{n}\n{ignored}"),
            None => ignored.to_string(),
        });
    }
    Ok(Planned {
        asm,
        solvers,
        idle: request.idle,
        note,
    })
}

/// The PETSc engine: the mesh cut into one part per rank, each rank's assembler running its
/// part, PETSc systems for the strategy's parts (symmetric ones marked so, for Cholesky or CG),
/// with tmc's defaults of `method` under the case's options.
#[cfg(feature = "petsc")]
fn on_ranks(
    model: &Model,
    request: &Request,
    systems: &[System],
    method: PetscMethod,
) -> Result<Planned, PlanError> {
    use super::petsc::{Hints, Ownership};
    use crate::case::LinearChoice;
    use crate::mesh::partition;
    use crate::parallel::Distribution;
    use crate::parallel::petsc;
    let solver = request.solver;
    if *solver.linear.get_ref() != LinearChoice::Auto {
        return Err(PlanError::Case {
            span: solver.linear.span(),
            message: "[solver] linear chooses faer's solvers; on the PETSc engine choose with \
                      [solver.petsc] options (e.g. \"-ksp_type gmres -pc_type gamg\")"
                .into(),
        });
    }
    let ranks = petsc::start().map_err(|e| PlanError::Setup(e.to_string()))?;
    if let Some(o) = &solver.petsc.options {
        petsc::insert_options(o.get_ref()).map_err(|e| PlanError::Case {
            span: o.span(),
            message: format!("[solver.petsc] options: {e}"),
        })?;
    }
    let asm = if ranks.is_serial() {
        Assembler::new(model)
    } else {
        let partition = partition::cut(&model.mesh, ranks.size)
            .map_err(|e| PlanError::Setup(format!("mpirun -n {}: {e}", ranks.size)))?;
        Assembler::distributed(model, Distribution { ranks, partition })
    };
    let structure = equation_structure(&model.dofs, &model.cons);
    let rows = asm.rows_owned(model);
    let rigid = crate::model::rigid::rigid_motions(model);
    let medium = model.nodes_of(crate::model::RegionKind::Medium);
    let on_ranks = Petsc {
        own: Ownership {
            ranks,
            node_rank: asm.distribution().map(|d| &d.partition.node_rank[..]),
            rows: rows.as_ref(),
        },
        hints: Hints {
            rigid: &rigid,
            medium: &medium,
        },
        method,
    };
    let solvers = on_ranks.solvers(systems, &asm.pattern, &structure)?;
    Ok(Planned {
        asm,
        solvers,
        // PETSc's calls stay on this thread: no pool around the solves
        idle: IdleThreads::CallingThread,
        note: None,
    })
}

/// Without the PETSc engine built in: what to do to have it.
#[cfg(not(feature = "petsc"))]
fn on_ranks(
    _model: &Model,
    request: &Request,
    _systems: &[System],
    _method: PetscMethod,
) -> Result<Planned, PlanError> {
    use crate::parallel::{NOT_BUILT, launched_size};
    if !Ranks::world().is_serial() || launched_size().unwrap_or(1) > 1 {
        return Err(PlanError::Setup(NOT_BUILT.into()));
    }
    Err(PlanError::Case {
        span: request.solver.engine.span(),
        message: format!("[solver] engine = \"petsc\": {NOT_BUILT}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two nodes, each with one mechanics and one temperature unknown, all coupled.
    fn two_nodes() -> (Pattern, Structure) {
        let n = 4;
        let pattern = Pattern {
            n,
            col_ptr: (0..=n).map(|j| j * n).collect(),
            row_idx: (0..n * n).map(|k| k % n).collect(),
        };
        let structure = Structure::new(vec![0, 0, 1, 1], vec![false, true, false, true]);
        (pattern, structure)
    }

    #[test]
    fn faer_sets_up_the_solver_each_system_asks_for() {
        let (p, s) = two_nodes();
        let system = |part, eqs: &[usize], symmetric, symmetric_mechanics| System {
            part,
            eqs: eqs.to_vec(),
            symmetric,
            symmetric_mechanics,
        };
        let one_way = |friction: bool| {
            vec![
                system(Part::Mechanics, &[0, 2], !friction, !friction),
                system(Part::Heat, &[1, 3], true, !friction),
            ]
        };
        let kinds = |engine: &Faer, systems: &[System]| -> Vec<LinearKind> {
            let solvers = engine.solvers(systems, &p, &s).unwrap();
            solvers.iter().map(|(_, l)| l.kind).collect()
        };
        let ldlt = Faer {
            whole: LinearKind::Ldlt,
        };
        // a one-way split: LDLᵀ for its symmetric parts, LU for friction's mechanics
        assert_eq!(kinds(&ldlt, &one_way(false)), [LinearKind::Ldlt; 2]);
        assert_eq!(
            kinds(&ldlt, &one_way(true)),
            [LinearKind::Lu, LinearKind::Ldlt]
        );
        // the whole system: the method asked for
        let all = [system(Part::All, &[0, 1, 2, 3], false, false)];
        for whole in [LinearKind::Lu, LinearKind::BlockGmres, LinearKind::Ldlt] {
            assert_eq!(kinds(&Faer { whole }, &all), [whole]);
        }
    }
}
