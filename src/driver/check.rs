//! `tmc check`: everything `tmc solve` does before its first step (case, mesh, groups,
//! physics, what a run on several ranks refuses, strategy, unknowns, the symbolic analysis of
//! the linear solvers, the initial state assembled), then a report; nothing is written where
//! results go.

use super::stepper::{Plan, assemble_initial};
use super::strategy::describe;
use super::{SolveError, SolveOptions, checked_model};
use crate::case::Case;
use crate::dofs::Field;
use crate::mesh::Mesh;
use crate::output::werr;
use crate::parallel::Ranks;
use crate::solver::engine::run_memory_mb;
use crate::solver::linear::Speedup;
use std::path::Path;

/// What `tmc check` found.
pub struct CheckReport {
    pub mesh: Mesh,
    /// The physics and the strategy, in words.
    pub physics: String,
    /// Unknowns per field, in field order, and the free ones.
    pub unknowns: Vec<(&'static str, usize)>,
    pub free: usize,
    /// Stored entries of the tangent.
    pub tangent_entries: usize,
    /// The linear solver of each system a solve factorises (its part, then the engine and
    /// method), in words.
    pub linear: Vec<String>,
    /// Entries of the direct factors (known before factorising for LDLᵀ), if known.
    pub factor_entries: Option<usize>,
    /// Bytes of their values, each factor in its precision.
    pub factor_bytes: Option<usize>,
    /// The largest factor's speed-ups at 2, 4, 16 and 64 threads as its elimination tree
    /// predicts them; empty where no factor is worked over its tree.
    pub predicted_speedup: Vec<(usize, Speedup)>,
    /// Why the engine is not the usual one (`engine = "auto"` over the memory), if so.
    pub engine_note: Option<String>,
    /// The probes' names.
    pub probes: Vec<String>,
    /// Regions with thermal expansion, with the temperature their strain is counted from.
    pub expansion: Vec<String>,
    /// The model's warnings and notes (a body the medium alone holds in some direction).
    pub warnings: Vec<String>,
    /// On several ranks, each rank's tangent entries and estimated peak memory in MB (its
    /// own part), in rank order; empty on one process.
    pub per_rank: Vec<(usize, f64)>,
    /// Whether a solve after this check opens gmsh: its mesh a `.geo` that the cache of
    /// meshes does not keep (`mesh/cache.rs`; one it keeps, this check has just kept).
    pub gmsh: bool,
}

impl CheckReport {
    /// The run's peak memory in MB: what its tangent brings with it and the factors in their
    /// precision (without the factor where it is PETSc's, sized only when it factorises).
    pub fn estimated_mb(&self) -> f64 {
        run_memory_mb(self.tangent_entries, self.factor_bytes, self.gmsh)
    }
}

/// Each region with α ≠ 0 and the θ0 its thermal strain α (θ − θ0) is counted from: a case in
/// °C whose θ0 is left at 0 strains its bodies from 0 °C to the first temperature.
fn expansion(case: &Case) -> Vec<String> {
    let doc: toml::Table = toml::from_str(&case.text).unwrap_or_default();
    let given = |i: usize| {
        doc.get("region")
            .and_then(|r| r.as_array())
            .and_then(|r| r.get(i))
            .and_then(|r| r.get("theta0"))
            .is_some()
    };
    case.file
        .region
        .iter()
        .enumerate()
        .filter(|(_, r)| r.alpha != 0.0)
        .map(|(i, r)| {
            let from = if given(i) {
                format!("θ0 = {}", r.theta0)
            } else {
                "θ0 = 0 (not given: temperatures are taken relative to the stress-free one; a \
                 case in absolute units sets theta0, e.g. 20 for °C)"
                    .to_string()
            };
            format!("\"{}\": α = {} from {from}", r.group.get_ref(), r.alpha)
        })
        .collect()
}

/// Check the case at `case_path` (with `opts.sets`) as a solve would, up to its first
/// assembly. A `.geo` is meshed in a temporary folder that is removed afterwards.
pub fn check(case_path: &Path, opts: &SolveOptions) -> Result<CheckReport, SolveError> {
    let case = Case::read(case_path)?.with_sets(&opts.sets)?;
    let scratch = crate::files::scratch_dir("check");
    std::fs::create_dir_all(&scratch).map_err(|e| SolveError::Output(werr(&scratch, e)))?;
    // the mesh's warnings go to the report
    let checked = checked_model(&case, &scratch, true);
    let _ = std::fs::remove_dir_all(&scratch);
    let (mut model, probes, _staged) = checked?;
    // a reconnected friction layer that cannot be joined again fails here as in a solve
    if let Some(layer) = crate::model::rejoin::Layer::find(&model)? {
        model.warnings.push(layer.describe());
    }
    // so does a medium asked to be made again that cannot be
    if let Some(medium) = crate::model::remake::Medium::find(&model, case.remade_medium())? {
        let next = if super::settling(&case) {
            "the mechanics settled at the same load after each, what it changed measured"
        } else {
            "the next step from the state as carried (`settle` settles it first)"
        };
        model
            .warnings
            .push(format!("{}; {next}", medium.describe(&model)));
    }
    super::refuse_on_ranks(&case, &model, Ranks::world())?;
    let gmsh = super::meshes_again(&case);
    let mut plan = Plan::new(&case, &model, opts, gmsh)?;
    // the state a solve starts from, assembled as its first step records it
    assemble_initial(&mut plan.asm, &model, &model.initial_state())?;
    let factor_entries = plan
        .solvers
        .iter()
        .map(|(_, s)| s.factor_entries())
        .sum::<Option<usize>>();
    let factor_bytes = plan
        .solvers
        .iter()
        .map(|(_, s)| s.factor_bytes())
        .sum::<Option<usize>>();
    let largest = (plan.solvers.iter()).max_by_key(|(_, s)| s.factor_entries().unwrap_or(0));
    let predicted_speedup = [2, 4, 16, 64]
        .into_iter()
        .filter_map(|p| Some((p, largest?.1.predicted_speedup(p as f64)?)))
        .collect();
    let tangent_entries = plan.asm.pattern.row_idx.len();
    let ranks = plan.asm.ranks;
    let per_rank = if ranks.is_serial() {
        Vec::new()
    } else {
        // each rank its own slot, summed: every rank holds every rank's figures
        let mut mine = vec![0.0; 2 * ranks.size];
        mine[2 * ranks.rank] = tangent_entries as f64;
        mine[2 * ranks.rank + 1] = run_memory_mb(tangent_entries, factor_bytes, gmsh);
        ranks.sum_into(&mut mine);
        mine.chunks(2).map(|r| (r[0] as usize, r[1])).collect()
    };
    Ok(CheckReport {
        physics: describe(&model.physics, plan.strategy),
        unknowns: Field::ALL
            .iter()
            .map(|&f| (f.name(), model.dofs.count(f)))
            .filter(|&(_, n)| n > 0)
            .collect(),
        free: model.cons.n_eq,
        tangent_entries,
        factor_entries,
        factor_bytes,
        predicted_speedup,
        engine_note: plan.note,
        linear: (plan.solvers.iter())
            .map(|(part, s)| format!("{}: {}", part.name(), s.method()))
            .collect(),
        probes: probes.iter().map(|p| p.name.clone()).collect(),
        expansion: expansion(&case),
        warnings: model.warnings,
        per_rank,
        gmsh,
        mesh: model.mesh,
    })
}
