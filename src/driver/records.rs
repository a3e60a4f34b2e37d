//! What a run records: `summary.json` (extend, never rename), the columns of `history.csv`,
//! reactions per Dirichlet group.

use super::strategy::Strategy;
use crate::case::{Case, CaseError};
use crate::dofs::Field;
use crate::model::{Model, Physics};
use crate::output::contact::{Contact, ContactFaces};
use crate::output::probes::{Probe, force_ratio};
use crate::output::quantity::Quantity;
use crate::solver::linear::LinearKind;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Where a solid first came up against the edge of the medium drawn around it: at the
/// accepted `step` at `time` (the clock of `history.csv`), a node of the medium's free edge
/// `distance` from the face of `solid`, the node at `at` (deformed).
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct EdgeReached {
    pub solid: String,
    pub step: usize,
    pub time: f64,
    pub at: [f64; 3],
    pub distance: f64,
}

impl EdgeReached {
    /// What happened, in words.
    pub fn came(&self) -> String {
        format!(
            "the solid \"{}\" came up against the edge of the medium drawn around it",
            self.solid
        )
    }
}

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
    /// Accepted steps that Newton could not converge however short, taken by pseudo-transient
    /// continuation at the shortest step.
    #[serde(default)]
    pub continued_steps: usize,
    /// Accepted steps that ended at the first state whose residual met the tolerance against
    /// its own reactions, where Newton's (or continuation's) updates after it did not shrink.
    #[serde(default)]
    pub balanced_steps: usize,
    /// Newton iterations of the accepted steps.
    pub newton_iterations: usize,
    /// Newton iterations of the rejected attempts (their time is in the seconds below).
    pub rejected_iterations: usize,
    /// Newton updates (linear solves) of every attempt, accepted or rejected: a mechanical
    /// step of n iterations makes n + 1. The count the assembly and solver seconds are spent on.
    pub linear_solves: usize,
    /// Numeric factorisations of every attempt: one per linear solve, less the last updates
    /// that reuse their factorisation and the updates whose engine kept an older factor.
    pub factorisations: usize,
    pub wall_seconds: f64,
    /// Assembly time of the whole run: every attempt, and the converged states' reactions.
    pub assembly_seconds: f64,
    /// Factorisation and linear-solve time of every attempt.
    pub solver_seconds: f64,
    /// Of `solver_seconds`, the numeric factorisations' (`null` on PETSc).
    pub factorisation_seconds: Option<f64>,
    /// Of `solver_seconds`, the factors' applications: a direct solve's triangular solves,
    /// GMRES's preconditioner (`null` on PETSc).
    pub factor_solve_seconds: Option<f64>,
    /// Time spent writing the run's files: each step's `.vtu`, history row and checkpoint.
    pub output_seconds: f64,
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
    /// Transient scenes: heat stored at the end, ∫ ρc (θ − θ0) dV (`null` otherwise).
    pub heat_stored: Option<f64>,
    /// Transient scenes: heat supplied over the run through every group and source, less what
    /// convected out, Σ Δt × rate by backward Euler. With `friction_heat`, equals
    /// `heat_stored` (the balance).
    pub heat_in: Option<f64>,
    /// Scenes with friction: the work dissipated by slip so far, Σ ∫ τ · Δg dV (`null`
    /// otherwise).
    pub friction_work: Option<f64>,
    /// Scenes with frictional heating: the heat friction made so far, Σ η ∫ τ · Δg dV, counted
    /// besides `heat_in` (`null` otherwise).
    pub friction_heat: Option<f64>,
    /// Scenes with a mass density (`rho`): the kinetic energy of the last accepted state,
    /// ½ ∫ ρ |v|² dV (`null` otherwise).
    pub kinetic_energy: Option<f64>,
    pub output: String,
    /// The units the case names in `[units]` (and energy and power made from them), by
    /// quantity: "length", "force", "time", "temperature", "energy", "power".
    pub units: BTreeMap<String, String>,
    /// What each column of history.csv with a physical dimension measures: column → quantity.
    pub quantities: BTreeMap<String, String>,
    /// Processes the run ran on (1 unless started by `mpirun`).
    pub ranks: usize,
    /// "faer" or "petsc".
    pub engine: String,
    /// On PETSc, its solver and preconditioner as `ksp_type/pc_type`.
    pub petsc_solver: Option<String>,
    /// On several ranks, each rank's peak resident memory (MB); `peak_memory_mb` is rank 0's.
    pub peak_memory_mb_ranks: Option<Vec<f64>>,
    /// The most medium cells an accepted step left inverted at a corner they share with a
    /// solid: a solid that passed through the medium between its quadrature points (0 if
    /// none did; linear triangles and tetrahedra cannot).
    pub corners_through_medium: usize,
    /// The largest displacement of any node in any accepted step.
    pub largest_displacement: f64,
    /// How many times a friction layer with `reconnect` was joined again (0 without one).
    pub friction_layer_joins: usize,
    /// How many times the medium was made again as the bodies moved (0 if never).
    pub medium_remade: usize,
    /// Across a remake of the medium, the largest relative change of a group's reaction
    /// |ΔR|/|R| and of its heat flow |ΔQ|/|Q|, each at the state itself settled (`null` where
    /// the medium was never made again, or not settled: `settle`).
    pub medium_remade_force_change: Option<f64>,
    pub medium_remade_heat_change: Option<f64>,
    /// The wall time the remakes took, from the state at which each was due to the state
    /// the next step starts from (`null` where the medium was never made again).
    pub medium_remade_seconds: Option<f64>,
    /// How many of those remakes left the mechanics unsettled: the settling at the same load
    /// did not converge, the next step started from the state as remade, and the changes
    /// above were read there (`null` where the medium was never made again, or not settled).
    pub medium_remade_unsettled: Option<usize>,
    /// How many times a step that would have stopped the run (Newton and continuation failing
    /// at the shortest step) asked for the medium to be made again first, made or not (`null`
    /// where the medium was never made again).
    pub medium_remade_to_go_on: Option<usize>,
    /// Where a solid first came up against the edge of the medium drawn around it (`null`
    /// where none did): the run says so as a warning at that step.
    pub medium_edge_reached: Option<EdgeReached>,
    /// Transient scenes with a friction layer with `reconnect`: what its joins changed the
    /// heat stored by, so far; with it, `heat_stored` = `heat_in` + `friction_heat` +
    /// `heat_joined` (`null` otherwise).
    pub heat_joined: Option<f64>,
    /// What the run checked of its own answers ([`Balances`]).
    pub balances: Balances,
}

/// How far a run's balances are from closing, each the largest over its accepted states
/// relative to the flows it balances (`null` where the scene has none to check), the tolerance
/// they are held to, and those left open. The force balance: the held groups' reactions and
/// the applied loads sum to zero, per component (not checked with inertia, whose forces are
/// the bodies' momentum). The heat balance: in a transient scene `heat_stored` = `heat_in` +
/// `friction_heat` + `heat_joined` (at the run's end); in a steady one the heat flows of the
/// groups, the sources and convection sum to zero.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct Balances {
    pub force: Option<f64>,
    pub heat: Option<f64>,
    pub tolerance: f64,
    /// The largest displacement of any node over the mesh's extent (`null` without
    /// displacements): beyond [`BEYOND`], a node has left the scene.
    pub moved: Option<f64>,
    /// Where a solid first stood past the end of the face its reconnected friction layer
    /// slides on, resting there on no face (`null` where none did).
    pub unsupported: Option<String>,
    /// The balances beyond the tolerance: "force", "heat"; "moved" for a node that left the
    /// scene; "unsupported" for a solid that slid past the end of its layer.
    pub open: Vec<String>,
}

/// A node that has moved farther than the mesh's extent has left the scene the mesh draws: in
/// a medium, a node that barely resists (a free corner of an open medium) has run away and
/// its cells are no solution; in a solid, its body has gone beyond everything it could touch.
pub const BEYOND: f64 = 1.0;

impl Balances {
    /// The balances of a run whose largest relative imbalances were `force` and `heat`,
    /// held to `tolerance`, and whose nodes moved at most `moved` times the mesh's extent.
    pub fn judged(
        force: Option<f64>,
        heat: Option<f64>,
        moved: Option<f64>,
        unsupported: Option<String>,
        tolerance: f64,
    ) -> Balances {
        let mut open: Vec<String> = [("force", force), ("heat", heat)]
            .into_iter()
            .filter(|(_, v)| v.is_some_and(|v| !(v <= tolerance)))
            .map(|(name, _)| name.to_string())
            .collect();
        if moved.is_some_and(|m| m > BEYOND) {
            open.push("moved".into());
        }
        if unsupported.is_some() {
            open.push("unsupported".into());
        }
        Balances {
            force,
            heat,
            tolerance,
            moved,
            unsupported,
            open,
        }
    }

    /// The tolerance of a run solved to Newton's relative `tol`: a balance sums the residual
    /// Newton leaves at every free unknown, each up to `tol` of its field's reference.
    pub fn tolerance_for(tol: f64) -> f64 {
        // to three digits: 1e3 × 1e-9 is 1.0000000000000002e-6 in binary
        let t = format!("{:.2e}", (1e3 * tol).max(1e-6));
        t.parse().unwrap_or(1e3 * tol)
    }
}

impl Summary {
    /// The summary of a run that has not stepped yet: what the case and the model are.
    pub fn start(
        case: &Case,
        model: &Model,
        linear_solver: LinearKind,
        strategy: Strategy,
        layout: &HistoryLayout,
        out_dir: &Path,
    ) -> Summary {
        let cells = model
            .mesh
            .cell_counts()
            .into_iter()
            .map(|(k, n)| (k.name().to_string(), n))
            .collect();
        let mut dofs = BTreeMap::new();
        for f in Field::ALL {
            dofs.insert(f.name().to_string(), model.dofs.count(f));
        }
        dofs.insert("total".into(), model.dofs.n_dofs);
        dofs.insert("free".into(), model.cons.n_eq);
        Summary {
            case: case.path.display().to_string(),
            mesh: model.mesh.source.display().to_string(),
            dim: model.mesh.dim,
            nodes: model.mesh.coords.len(),
            cells,
            dofs,
            physics: model.physics,
            linear_solver,
            strategy,
            converged: false,
            message: String::new(),
            lambda: 0.0,
            time: 0.0,
            load_steps: 0,
            rejected_steps: 0,
            continued_steps: 0,
            balanced_steps: 0,
            newton_iterations: 0,
            rejected_iterations: 0,
            linear_solves: 0,
            factorisations: 0,
            wall_seconds: 0.0,
            assembly_seconds: 0.0,
            solver_seconds: 0.0,
            factorisation_seconds: None,
            factor_solve_seconds: None,
            output_seconds: 0.0,
            krylov_iterations: 0,
            tangents_skipped: 0,
            peak_memory_mb: None,
            probes: BTreeMap::new(),
            reactions: BTreeMap::new(),
            min_J: 1.0,
            min_J_solid: None,
            min_J_medium: None,
            energy: 0.0,
            external_work: 0.0,
            heat_stored: None,
            heat_in: None,
            friction_work: None,
            friction_heat: None,
            kinetic_energy: None,
            ranks: 1,
            engine: "faer".into(),
            petsc_solver: None,
            peak_memory_mb_ranks: None,
            corners_through_medium: 0,
            largest_displacement: 0.0,
            friction_layer_joins: 0,
            medium_remade: 0,
            medium_remade_force_change: None,
            medium_remade_heat_change: None,
            medium_remade_seconds: None,
            medium_remade_unsettled: None,
            medium_remade_to_go_on: None,
            medium_edge_reached: None,
            heat_joined: None,
            balances: Balances::default(),
            output: out_dir.display().to_string(),
            units: Quantity::ALL
                .into_iter()
                .filter_map(|q| Some((q.name().to_string(), q.unit(&case.file.units)?)))
                .collect(),
            quantities: layout
                .columns
                .iter()
                .zip(&layout.quantities)
                .filter_map(|(c, q)| Some((c.clone(), q.as_ref()?.name().to_string())))
                .collect(),
        }
    }
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

/// Force and heat on the body through every group: the Dirichlet groups' reactions (from the
/// residual `r_full`), plus the loads of the groups with flux conditions at (pseudo-)time `t`
/// (traction, heat flux) and the heat they `convected` (per flux group, from
/// `post::convection_heat`).
pub fn group_flows(model: &Model, r_full: &[f64], convected: &[f64], t: f64) -> Reactions {
    let mut out = reactions(model, r_full);
    let lambda = model.path.lambda(t);
    for (g, group) in model.flux_groups.iter().enumerate() {
        let entry = out.entry(group.name.clone()).or_default();
        for &(_, key, value, ramped) in &group.loads {
            let amp = if ramped { lambda } else { 1.0 };
            *entry.entry(key.into()).or_default() += amp * value;
        }
        if group.convects {
            *entry.entry("heat".into()).or_default() += convected[g];
        }
    }
    out
}

/// Reactions per Dirichlet group: force components on the body and heat supplied to it.
pub fn reactions(model: &Model, r_full: &[f64]) -> Reactions {
    let mut out: BTreeMap<String, BTreeMap<String, f64>> = BTreeMap::new();
    let d = model.dofs.dim;
    for (n, _) in model.mesh.coords.iter().enumerate() {
        if model.dofs.has(Field::U) {
            for c in 0..d {
                let dof = model.dofs.u[n * d + c] as usize;
                if let Some(p) = model.cons.prescribed[dof] {
                    *out.entry(model.bc_groups[p.bc].name.clone())
                        .or_default()
                        .entry(FORCE_KEYS[c].into())
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

/// Reactions and heat flows per group: group name → component ("x", "y", "z", "heat") → value.
pub type Reactions = BTreeMap<String, BTreeMap<String, f64>>;

/// The largest relative change from `before` to `after` of a group's reaction, |ΔR|/|R| with
/// R its force vector, and of its heat flow, |ΔQ|/|Q|, over the groups of `before` with a
/// force (a heat flow) that is not zero.
pub fn flow_change(before: &Reactions, after: &Reactions) -> (f64, f64) {
    let (mut force, mut heat) = (0.0f64, 0.0f64);
    for group in before.keys() {
        let (b, a) = (
            |k: &str| flow(before, group, k),
            |k: &str| flow(after, group, k),
        );
        let (mut size, mut change) = (0.0, 0.0);
        for k in FORCE_KEYS {
            size += b(k) * b(k);
            change += (a(k) - b(k)).powi(2);
        }
        if size > 0.0 {
            force = force.max((change / size).sqrt());
        }
        let q = b("heat");
        if q != 0.0 {
            heat = heat.max((a("heat") - q).abs() / q.abs());
        }
    }
    (force, heat)
}

/// The keys of a group's force components in [`Reactions`], x, y, z in order.
pub const FORCE_KEYS: [&str; 3] = ["x", "y", "z"];

/// `group`'s flow `key` ("x", "y", "z" or "heat") in `reactions`; 0 where it has none.
pub fn flow(reactions: &Reactions, group: &str, key: &str) -> f64 {
    (reactions.get(group).and_then(|m| m.get(key)))
        .copied()
        .unwrap_or(0.0)
}

/// The name of a group's flow (component `key`: "x", "y", "z" or "heat") as a history column
/// and a study measure: `R_<group>_<key>` for a force, `Q_<group>` for heat.
pub fn flow_name(group: &str, key: &str) -> String {
    if key == "heat" {
        format!("Q_{group}")
    } else {
        format!("R_{group}_{key}")
    }
}

/// A probe named as a column tmc writes itself (`lambda`, `R_<group>_x`, `Ft_Fn_<group>`,
/// `U_<group>_x`, … for any group a `[[bc]]` names, whether or not this scene has that
/// column) is refused at its name: `history.csv` would hold two columns of one name.
pub fn refuse_column_names(case: &Case) -> Result<(), CaseError> {
    let fixed = (HISTORY_STEP_COLUMNS.iter().chain(&HISTORY_SOLVER_COLUMNS)).chain(&[
        "energy",
        "work",
        "heat_stored",
        "heat_in",
        "friction_work",
        "friction_heat",
        "heat_joined",
        "kinetic_energy",
        "wall_seconds",
    ]);
    let groups: Vec<&str> = (case.file.bc.iter())
        .map(|b| b.group.get_ref().as_str())
        .collect();
    for p in &case.file.probe {
        let name = p.name.get_ref().as_str();
        let of_group = groups.iter().find_map(|g| {
            let mut names = vec![flow_name(g, "heat"), ratio_name(g)];
            for k in FORCE_KEYS {
                names.push(flow_name(g, k));
                names.push(moved_name(g, k));
            }
            names.contains(&name.to_string()).then_some(*g)
        });
        let what = match of_group {
            Some(g) => format!("a column tmc writes for group \"{g}\""),
            None if fixed.clone().any(|f| *f == name) => "a column tmc writes".to_string(),
            None => continue,
        };
        return case.error(
            p.name.span(),
            format!("probe name \"{name}\" is {what} in history.csv; name the probe otherwise"),
        );
    }
    Ok(())
}

/// The history column of a group's F_t/F_n along the contact's normal.
pub fn ratio_name(group: &str) -> String {
    format!("Ft_Fn_{group}")
}

/// The loaded groups of `moved` (see [`moved_groups`]) whose nodes are on one body that meets
/// the medium, each with that body: the groups whose reaction [`contact_ratio`] splits.
fn contact_groups(
    model: &Model,
    contact: &ContactFaces,
    moved: &[(String, usize, Vec<usize>)],
) -> Vec<(String, usize)> {
    let mut out: Vec<(String, usize)> = Vec::new();
    for (name, _, _) in moved {
        let Some(group) = model.mesh.group(name) else {
            continue;
        };
        let mut bodies =
            (model.mesh.group_nodes(group).into_iter()).filter_map(|n| contact.body_of(n));
        let Some(body) = bodies.next() else { continue };
        if bodies.all(|b| b == body) && !out.iter().any(|(g, _)| g == name) {
            out.push((name.clone(), body));
        }
    }
    out
}

/// The history column of a loaded group's mean displacement along `key` ("x", "y", "z").
pub fn moved_name(group: &str, key: &str) -> String {
    format!("U_{group}_{key}")
}

/// Each loaded group's displacement unknowns per component it moves (not zero somewhere on
/// its path), in the order of the groups' first `[[bc]]`: the `U_<group>_<c>` columns.
fn moved_groups(model: &Model) -> Vec<(String, usize, Vec<usize>)> {
    let d = model.dofs.dim;
    let mut out: Vec<(String, usize, Vec<usize>)> = Vec::new();
    if !model.dofs.has(Field::U) {
        return out;
    }
    let mut moved = vec![[false; 3]; model.bc_groups.len()];
    for i in 0..model.mesh.coords.len() * d {
        let dof = model.dofs.u[i] as usize;
        if let Some(p) = &model.cons.prescribed[dof] {
            moved[p.bc][i % d] |= p.value != 0.0 || p.start != 0.0;
        }
    }
    for (g, group) in model.bc_groups.iter().enumerate() {
        for c in (0..d).filter(|&c| moved[g][c]) {
            if out.iter().any(|(n, k, _)| n == &group.name && *k == c) {
                continue;
            }
            // every unknown of the group along c, whichever of its entries prescribes it
            let dofs = (0..model.mesh.coords.len())
                .map(|n| model.dofs.u[n * d + c] as usize)
                .filter(|&dof| {
                    (model.cons.prescribed[dof].as_ref())
                        .is_some_and(|p| model.bc_groups[p.bc].name == group.name)
                })
                .collect();
            out.push((group.name.clone(), c, dofs));
        }
    }
    out
}

/// F_t/F_n of the reaction `R` of a group holding body `body`, split along the contact's
/// normal as that body meets it ([`ContactFaces::contact_normal`]; in 2D F_t signed as a
/// `force_ratio` probe's); NaN where nothing presses.
#[allow(non_snake_case)]
pub fn contact_ratio(
    contact: &ContactFaces,
    body: usize,
    t: &Contact,
    R: [f64; 3],
    dim: usize,
) -> f64 {
    match contact.contact_normal(body, t) {
        Some(n) => force_ratio(R, n, dim),
        None => f64::NAN,
    }
}

/// One accepted step's numbers for its history row, besides probes and reactions.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepRow {
    pub step: usize,
    pub lambda: f64,
    pub dlambda: f64,
    pub iterations: usize,
    /// Last relative residual of u, θ and p.
    pub residuals: [f64; 3],
    pub min_J_solid: f64,
    pub min_J_medium: f64,
    pub energy: f64,
    pub krylov: usize,
    pub halvings: usize,
    pub time: f64,
    pub work: f64,
    /// Transient scenes: (heat stored, heat supplied so far).
    pub heat: Option<(f64, f64)>,
    /// Scenes with friction: (work dissipated by slip, heat it made, so far).
    pub friction: Option<(f64, f64)>,
    /// Transient scenes with a reconnected friction layer: what its joins changed the heat
    /// stored by, so far.
    pub heat_joined: Option<f64>,
    /// Scenes with inertia: the kinetic energy.
    pub kinetic_energy: Option<f64>,
    /// Seconds since the run started, when the step was accepted.
    pub wall: f64,
}

/// The columns of one model's `history.csv`: the step columns, `energy`, the probes, the
/// reactions (`R_group_x`, `Q_group`), the solver columns and `work`; in transient scenes
/// then `heat_stored` and `heat_in`; with friction `friction_work`, with frictional heating
/// `friction_heat`; transient with a reconnected friction layer `heat_joined`; with inertia
/// `kinetic_energy`; last `wall_seconds`.
pub struct HistoryLayout {
    pub columns: Vec<String>,
    /// What each column measures (`None`: a count, a ratio or λ).
    pub quantities: Vec<Option<Quantity>>,
    transient: bool,
    friction: bool,
    frictional_heating: bool,
    /// Transient with a reconnected friction layer: its joins' change of the heat stored is
    /// counted (`heat_joined`).
    pub(super) joined: bool,
    inertia: bool,
    /// (group, component) of each reaction column.
    reactions: Vec<(String, String)>,
    /// The groups whose reaction is split along the contact's normal (`Ft_Fn_<group>`), each
    /// with the body it holds.
    pub contact: Vec<(String, usize)>,
    /// The loaded groups' displacements (`U_<group>_<x|y|z>`): each group, component and the
    /// displacement unknowns it prescribes along it, whose mean the column is.
    pub moved: Vec<(String, usize, Vec<usize>)>,
}

impl HistoryLayout {
    /// `physical_time`: the case has `[time]`, so the `time` column is a time; `contact`: the
    /// faces where the solids meet the medium, if any.
    pub fn new(
        model: &Model,
        probes: &[Probe],
        physical_time: bool,
        contact: Option<&ContactFaces>,
    ) -> HistoryLayout {
        let mut reactions: Vec<(String, String)> = Vec::new();
        for g in &model.bc_groups {
            for f in &g.fields {
                let (has, key) = match *f {
                    "theta" => (model.dofs.has(Field::Theta), "heat"),
                    c => (model.dofs.has(Field::U), &c[1..]),
                };
                if has {
                    reactions.push((g.name.clone(), key.to_string()));
                }
            }
        }
        // then the groups with flux conditions, in component order, unless already there
        for g in &model.flux_groups {
            let mut keys: Vec<&str> = g.loads.iter().map(|l| l.1).collect();
            if g.convects {
                keys.push("heat");
            }
            for key in ["x", "y", "z", "heat"] {
                let col = (g.name.clone(), key.to_string());
                if keys.contains(&key) && !reactions.contains(&col) {
                    reactions.push(col);
                }
            }
        }
        use Quantity::{Energy, Force, Length, Power, Time};
        let mut columns: Vec<(String, Option<Quantity>)> = HISTORY_STEP_COLUMNS
            .iter()
            .map(|c| (c.to_string(), None))
            .collect();
        columns.push(("energy".into(), Some(Energy)));
        columns.extend(probes.iter().map(|p| (p.name.clone(), p.quantity())));
        columns.extend(reactions.iter().map(|(g, k)| {
            let q = if k == "heat" { Power } else { Force };
            (flow_name(g, k), Some(q))
        }));
        let moved = moved_groups(model);
        let contact = contact.map_or_else(Vec::new, |c| contact_groups(model, c, &moved));
        columns.extend(contact.iter().map(|(g, _)| (ratio_name(g), None)));
        columns
            .extend((moved.iter()).map(|(g, c, _)| (moved_name(g, FORCE_KEYS[*c]), Some(Length))));
        for c in HISTORY_SOLVER_COLUMNS {
            let q = (c == "time" && physical_time).then_some(Time);
            columns.push((c.into(), q));
        }
        columns.push(("work".into(), Some(Energy)));
        let transient = model.physics.transient;
        if transient {
            columns.push(("heat_stored".into(), Some(Energy)));
            columns.push(("heat_in".into(), Some(Energy)));
        }
        let (friction, frictional_heating) =
            (model.physics.friction, model.physics.frictional_heating);
        if friction {
            columns.push(("friction_work".into(), Some(Energy)));
        }
        if frictional_heating {
            columns.push(("friction_heat".into(), Some(Energy)));
        }
        let joined = transient && model.reconnects();
        if joined {
            columns.push(("heat_joined".into(), Some(Energy)));
        }
        let inertia = model.physics.inertia;
        if inertia {
            columns.push(("kinetic_energy".into(), Some(Energy)));
        }
        // seconds of this machine's clock, whatever the case's units
        columns.push(("wall_seconds".into(), None));
        let (columns, quantities) = columns.into_iter().unzip();
        HistoryLayout {
            columns,
            quantities,
            transient,
            friction,
            frictional_heating,
            joined,
            inertia,
            reactions,
            contact,
            moved,
        }
    }

    /// The row of one step, in column order; `groups` are the loaded groups' columns: the
    /// `Ft_Fn_<group>` of [`HistoryLayout::contact`], then the `U_<group>_<c>` of
    /// [`HistoryLayout::moved`].
    pub fn row(
        &self,
        s: &StepRow,
        probes: &[f64],
        reactions: &Reactions,
        groups: &[f64],
    ) -> Vec<f64> {
        let mut row = vec![
            s.step as f64,
            s.lambda,
            s.dlambda,
            s.iterations as f64,
            s.residuals[0],
            s.residuals[1],
            s.residuals[2],
            s.min_J_solid,
            s.min_J_medium,
            s.energy,
        ];
        row.extend_from_slice(probes);
        row.extend(self.reactions.iter().map(|(g, k)| flow(reactions, g, k)));
        row.extend_from_slice(groups);
        row.extend([s.krylov as f64, s.halvings as f64, s.time, s.work]);
        if self.transient {
            let (stored, supplied) = s.heat.unwrap_or((0.0, 0.0));
            row.extend([stored, supplied]);
        }
        let (work, heat) = s.friction.unwrap_or((0.0, 0.0));
        if self.friction {
            row.push(work);
        }
        if self.frictional_heating {
            row.push(heat);
        }
        if self.joined {
            row.push(s.heat_joined.unwrap_or(0.0));
        }
        if self.inertia {
            row.push(s.kinetic_energy.unwrap_or(0.0));
        }
        row.push(s.wall);
        row
    }
}

#[cfg(test)]
mod tests {
    use super::{Balances, Reactions, flow_change};

    #[test]
    fn a_balance_beyond_its_tolerance_is_open_and_one_not_checked_is_not() {
        let judged = |force, heat, moved, tol| Balances::judged(force, heat, moved, None, tol);
        let b = judged(
            Some(3e-6),
            Some(1e-9),
            Some(0.5),
            Balances::tolerance_for(1e-9),
        );
        assert_eq!(
            (b.tolerance, b.open.clone()),
            (1e-6, vec!["force".to_string()])
        );
        let b = judged(None, Some(f64::NAN), None, Balances::tolerance_for(1e-6));
        assert_eq!((b.tolerance, b.open), (1e-3, vec!["heat".to_string()]));
        // a node beyond the scene; a solid past the end of its layer
        let open = |moved, past: Option<&str>| {
            let tol = Balances::tolerance_for(1e-9);
            Balances::judged(Some(1e-9), None, moved, past.map(String::from), tol).open
        };
        assert_eq!(open(Some(2.5), None), vec!["moved".to_string()]);
        assert_eq!(
            open(Some(0.5), Some("node 7")),
            vec!["unsupported".to_string()]
        );
        assert!(open(Some(1.0), None).is_empty());
    }

    fn flows(rows: &[(&str, &[(&str, f64)])]) -> Reactions {
        (rows.iter())
            .map(|(g, kv)| {
                let m = kv.iter().map(|(k, v)| (k.to_string(), *v)).collect();
                (g.to_string(), m)
            })
            .collect()
    }

    #[test]
    fn a_flow_change_is_the_largest_relative_change_of_a_group_s_force_and_heat() {
        let before = flows(&[
            ("rim", &[("x", 0.0), ("y", -2.0), ("heat", 10.0)]),
            ("bottom", &[("x", 0.0), ("y", 2.0), ("heat", -10.0)]),
            ("free", &[("x", 0.0)]),
        ]);
        let after = flows(&[
            ("rim", &[("x", 0.06), ("y", -2.08), ("heat", 10.1)]),
            ("bottom", &[("x", 0.0), ("y", 2.02), ("heat", -9.7)]),
            ("free", &[("x", 0.5)]),
        ]);
        let (force, heat) = flow_change(&before, &after);
        // rim: |(0.06, -0.08)| / 2 = 0.05; bottom's heat: 0.3 / 10; a group with no force
        // before is not measured
        assert!((force - 0.05).abs() < 1e-12, "{force}");
        assert!((heat - 0.03).abs() < 1e-12, "{heat}");
        assert_eq!(flow_change(&before, &before), (0.0, 0.0));
    }
}
