//! The case file (TOML): mesh, materials per physical group, boundary conditions, steps, probes.
//!
//! Parsing refuses unknown keys; [`Case::validate`] checks the case against its mesh before any
//! work starts, and every error names the file, the key and its line.

use crate::material::conduction::TABLE_POINTS;
use crate::mesh::Mesh;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::Spanned;

#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    #[error("cannot read case file {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {msg}")]
    Syntax { path: PathBuf, msg: String },
    #[error("{path}:{line}: {msg}")]
    Invalid {
        path: PathBuf,
        line: usize,
        msg: String,
    },
    #[error("{path} with --set {sets}: {msg}")]
    Set {
        path: PathBuf,
        sets: String,
        msg: String,
    },
}

impl CaseError {
    /// What went wrong, without the file and line (for a message that names the settings that
    /// made the case, e.g. `--set` or a study's variant): the last line of a TOML error, which
    /// says what was found.
    pub fn detail(&self) -> String {
        match self {
            CaseError::Invalid { msg, .. } | CaseError::Set { msg, .. } => msg.clone(),
            CaseError::Syntax { msg, .. } => msg
                .lines()
                .rfind(|l| {
                    !l.trim().is_empty() && !l.contains(" | ") && !l.trim_start().starts_with('|')
                })
                .unwrap_or(msg)
                .trim()
                .to_string(),
            other => other.to_string(),
        }
    }
}

/// Region kinds.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum RegionKind {
    Solid,
    Medium,
}

/// `law` of a solid region.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SolidLawKey {
    /// Eq. (12), with `K` and `mu` (the default).
    NeoHooke,
    /// Abaqus' compressible Mooney-Rivlin, with `C10`, `C01` and `K`.
    MooneyRivlin,
}

/// `[[region]]`: the material of one physical group of cells.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [[region]] table")]
#[allow(non_snake_case)]
pub struct Region {
    pub group: Spanned<String>,
    pub kind: RegionKind,
    /// Bulk modulus (solid).
    pub K: Option<Spanned<f64>>,
    /// Shear modulus (solid, Neo-Hooke).
    pub mu: Option<Spanned<f64>>,
    /// A solid's stress law (default: Neo-Hooke).
    pub law: Option<Spanned<SolidLawKey>>,
    /// Mooney-Rivlin's coefficients of Ī₁ − 3 and Ī₂ − 3.
    pub C10: Option<Spanned<f64>>,
    pub C01: Option<Spanned<f64>>,
    /// Conductivity k (solid) or gas conductivity k_TM (medium).
    pub k: Option<Spanned<f64>>,
    /// Thermal expansion coefficient α_t.
    #[serde(default)]
    pub alpha: f64,
    /// Reference temperature θ0.
    #[serde(default)]
    pub theta0: f64,
    /// Medium stiffness γ (K = μ = γ).
    pub gamma: Option<Spanned<f64>>,
    /// Cap of the medium's conductivity (default: largest solid k).
    pub k_max: Option<Spanned<f64>>,
    /// A medium's conductivity as a table of `[J, k]` rows, linear in J between them (instead
    /// of `k` and `k_max`).
    pub k_table: Option<Spanned<Vec<Vec<f64>>>>,
    /// A medium's conductance across its closed layer h_c (heat per area, time and degree),
    /// with `thickness`, the layer's undeformed thickness t0: k ≤ h_c t0 J.
    pub h_closed: Option<Spanned<f64>>,
    pub thickness: Option<Spanned<f64>>,
    /// Regularization weights β1, β2 (eq. 20) and α_r (eq. 18).
    pub beta1: Option<Spanned<f64>>,
    pub beta2: Option<Spanned<f64>>,
    pub alpha_r: Option<Spanned<f64>>,
    /// Body force per reference volume (ramped).
    pub body_force: Option<Vec<f64>>,
    /// Heat source per reference volume (ramped).
    pub heat_source: Option<f64>,
    /// Heat capacity ρc per reference volume: with `[time]`, the region stores heat
    /// (ρc θ̇ by backward Euler); without, it is stationary.
    pub rho_c: Option<Spanned<f64>>,
    /// Coulomb friction in a slip plane of the medium (medium regions only).
    pub friction: Option<Spanned<FrictionKey>>,
}

/// `friction = { mu = 0.3, normal = [0, 1] }` (or `normal = "auto"`) of a medium region.
#[derive(Clone, Debug, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table such as { mu = 0.3, normal = [0, 1] }"
)]
pub struct FrictionKey {
    /// Coulomb coefficient μ_f ≥ 0.
    pub mu: Spanned<f64>,
    /// The slip plane's normal in the undeformed mesh: a vector of the mesh's dimension (need
    /// not be of unit length), or `"auto"`: each cell's from the solid surface nearest to it.
    pub normal: Spanned<SlipNormal>,
    /// Fraction of the dissipated work that becomes heat, in [0, 1] (default 1); heat is made
    /// only in scenes with `[time]` that conduct.
    pub heat_fraction: Option<Spanned<f64>>,
    /// Stick stiffness factor c_f > 0 of the friction modulus c_f K (1 − ln J)/J² (default 1).
    pub c_f: Option<Spanned<f64>>,
}

/// `normal` of a `friction`: given, or `"auto"` (any other word is an error at validation).
#[derive(Clone, Debug, Deserialize)]
#[serde(
    untagged,
    expecting = "`normal` must be \"auto\" or the slip plane's normal as numbers, such as [0, 1]"
)]
pub enum SlipNormal {
    Given(Vec<f64>),
    Word(String),
}

impl FrictionKey {
    /// The fraction of the dissipation that becomes heat.
    pub fn heat_fraction(&self) -> f64 {
        self.heat_fraction.as_ref().map_or(1.0, |v| *v.get_ref())
    }
}

/// `[[bc]]`: conditions on one physical group of the boundary (or of points).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [[bc]] table")]
pub struct Bc {
    pub group: Spanned<String>,
    /// A name to address this entry by (`--set bc.NAME.KEY`, a study's `set`) where its group
    /// has several `[[bc]]`.
    pub name: Option<String>,
    pub ux: Option<f64>,
    pub uy: Option<f64>,
    pub uz: Option<f64>,
    pub theta: Option<f64>,
    /// Nominal traction (force per reference area).
    pub traction: Option<Spanned<Vec<f64>>>,
    /// Heat supplied per reference area (positive = into the body).
    pub heat_flux: Option<f64>,
    /// Convection: heat transfer coefficient h ≥ 0, heat leaving per unit current area and
    /// degree, h (θ − θ∞). Acts in full from the start (not scaled by λ). Needs `theta_inf`.
    pub h: Option<Spanned<f64>>,
    /// Ambient temperature θ∞ of the convection.
    pub theta_inf: Option<Spanned<f64>>,
    /// Radiation to surroundings: heat leaving per unit current area ε σ (θ⁴ − θ∞⁴), in
    /// full from the start.
    pub radiation: Option<Spanned<RadiationKey>>,
    /// Scale by the load factor λ (true, the default) or hold at full value from the start
    /// (false): for every value of the block (`ramp = false`), or per value
    /// (`ramp = { theta = false }`: the values not named are ramped).
    pub ramp: Option<Spanned<Ramp>>,
    /// This group's own amplitude at pseudo-times 0, 1, …, T (as `[steps] path`), instead of
    /// λ: e.g. press first, then slide. Prescribed values only.
    pub path: Option<Spanned<Vec<f64>>>,
}

/// `radiation = { emissivity = 0.8, theta_inf = 293.15, sigma = 5.670374419e-8 }` of a
/// `[[bc]]`: temperatures absolute, σ in the case's units.
#[derive(Clone, Debug, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table such as { emissivity = 0.8, theta_inf = 293.15, sigma = 5.670374419e-8 }"
)]
pub struct RadiationKey {
    /// Emissivity ε in (0, 1].
    pub emissivity: Spanned<f64>,
    /// Temperature of the surroundings θ∞ > 0.
    pub theta_inf: Spanned<f64>,
    /// The Stefan–Boltzmann constant in the case's units (5.670374419e-8 in SI).
    pub sigma: Spanned<f64>,
}

/// `ramp` of a `[[bc]]`: one choice for the block, or one per value.
#[derive(Clone, Debug, Deserialize)]
#[serde(
    untagged,
    expecting = "`ramp` must be true, false, or a table such as { theta = false }"
)]
pub enum Ramp {
    All(bool),
    Per(std::collections::BTreeMap<String, bool>),
}

/// The values of a `[[bc]]` that `ramp` may name.
pub const RAMPED_VALUES: [&str; 6] = ["ux", "uy", "uz", "theta", "traction", "heat_flux"];

impl Bc {
    /// Whether `value` (one of [`RAMPED_VALUES`]) grows with λ (else it is held at full value
    /// from the start).
    pub fn ramped(&self, value: &str) -> bool {
        match self.ramp.as_ref().map(|r| r.get_ref()) {
            None => true,
            Some(Ramp::All(r)) => *r,
            Some(Ramp::Per(m)) => m.get(value).copied().unwrap_or(true),
        }
    }

    /// Whether heat leaves through the group by a law of its temperature (convection,
    /// radiation): assembled, not prescribed.
    pub fn exchanges_heat(&self) -> bool {
        self.h.is_some() || self.radiation.is_some()
    }

    /// Whether any value of the block is held at full value.
    pub fn holds_any(&self) -> bool {
        RAMPED_VALUES.iter().any(|v| self.has(v) && !self.ramped(v))
    }

    /// Whether the block gives `value`.
    pub fn has(&self, value: &str) -> bool {
        match value {
            "traction" => self.traction.is_some(),
            _ => self.scalar(value).is_some(),
        }
    }

    /// The scalar `value` of the block (`ux`, `uy`, `uz`, `theta`, `heat_flux`), if given.
    fn scalar(&self, value: &str) -> Option<f64> {
        match value {
            "ux" => self.ux,
            "uy" => self.uy,
            "uz" => self.uz,
            "theta" => self.theta,
            "heat_flux" => self.heat_flux,
            _ => None,
        }
    }

    /// The block's non-zero values that `ramp` holds at full value from the start, as
    /// `uy = -0.2 on "top"`.
    pub fn held_in_full(&self) -> Vec<String> {
        let g = self.group.get_ref();
        RAMPED_VALUES
            .iter()
            .filter(|&&v| !self.ramped(v))
            .filter_map(|&v| match (v, &self.traction) {
                ("traction", Some(t)) if t.get_ref().iter().any(|&x| x != 0.0) => {
                    Some(format!("traction = {:?} on \"{g}\"", t.get_ref()))
                }
                ("traction", _) => None,
                _ => self
                    .scalar(v)
                    .filter(|&x| x != 0.0)
                    .map(|x| format!("{v} = {x} on \"{g}\"")),
            })
            .collect()
    }
}

/// `[steps]`: load stepping and Newton controls.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default, expecting = "the [steps] table")]
pub struct Steps {
    /// First load increment Δλ.
    pub initial: f64,
    /// Smallest Δλ before the run gives up.
    pub min: f64,
    /// Largest Δλ.
    pub max: f64,
    /// Relative tolerance of the per-field residual and update norms.
    pub tol: f64,
    /// Newton iterations per step before the step is cut.
    pub max_iter: usize,
    /// Steps converging in at most this many iterations grow Δλ.
    pub easy_iter: usize,
    /// Growth factor after an easy step.
    pub grow: f64,
    /// Cut factor after a failed step.
    pub cut: f64,
    /// Load path: λ at pseudo-times t = 0, 1, …, T, linear in between (default `[0, 1]`).
    /// Every value is reached by a step: e.g. `[0, 1, 0.2]` loads, then unloads to 0.2, and
    /// `[0, 0.25, 0.5, 1]` also writes the states at λ = 0.25 and 0.5.
    pub path: Option<Vec<f64>>,
}

impl Default for Steps {
    fn default() -> Self {
        Steps {
            initial: 0.1,
            min: 1e-5,
            max: 1.0,
            tol: 1e-9,
            max_iter: 16,
            easy_iter: 7,
            grow: 1.5,
            cut: 0.25,
            path: None,
        }
    }
}

/// `[time]`: physical time t ∈ [0, end] replaces the load parameter as what the steps
/// advance; loads follow λ(t).
#[derive(Clone, Debug, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "the [time] table (end, dt, times, lambda)"
)]
pub struct Time {
    /// End time, > 0.
    pub end: Spanned<f64>,
    /// Step size Δt: steps are cut after a failure and grow back, never beyond Δt.
    pub dt: Option<Spanned<f64>>,
    /// Times that are steps of their own (and written), increasing in (0, end].
    pub times: Option<Spanned<Vec<f64>>>,
    /// The load factor over time as [[t, λ], …], piecewise linear, t increasing from 0
    /// (default `[[0, 0], [end, 1]]`).
    /// (Rows are read as lists and checked to hold two values each: a fixed-size array would
    /// drop a third silently.)
    pub lambda: Option<Spanned<Vec<Vec<f64>>>>,
}

impl Time {
    /// The times every run of this case steps onto: the `times`, the vertices of `lambda`
    /// inside (0, end), and `end`.
    pub fn vertices(&self) -> Vec<f64> {
        let end = *self.end.get_ref();
        let mut v: Vec<f64> = self
            .times
            .as_ref()
            .map_or(Vec::new(), |t| t.get_ref().clone());
        if let Some(l) = &self.lambda {
            v.extend(l.get_ref().iter().filter_map(|r| r.first().copied()));
        }
        v.push(end);
        v.retain(|&t| t > 0.0 && t <= end);
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    }

    /// The largest step: `dt`, or the longest interval between vertices.
    pub fn dt_max(&self) -> f64 {
        match &self.dt {
            Some(dt) => *dt.get_ref(),
            None => {
                let v = self.vertices();
                let mut last = 0.0;
                let mut m = 0.0f64;
                for t in v {
                    m = m.max(t - last);
                    last = t;
                }
                m
            }
        }
    }
}

/// `[solver]`: linear solver choice.
#[derive(Clone, Debug, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Solver {
    /// "auto" (LDLᵀ when the tangent is symmetric, else block-preconditioned GMRES), "gmres",
    /// "lu", "ldlt".
    pub linear: LinearChoice,
    /// "auto" (one-way coupled scenes solve mechanics, then heat, per step) or "monolithic".
    pub coupling: CouplingChoice,
    /// "faer" (one process, the default) or "petsc" (the distributed engine; what `mpirun`
    /// runs on whatever this says).
    pub engine: EngineChoice,
    /// `[solver.petsc]`: the PETSc engine's options.
    pub petsc: PetscOptions,
}

#[derive(Clone, Copy, Debug, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum EngineChoice {
    #[default]
    Faer,
    Petsc,
}

/// `[solver.petsc]`.
#[derive(Clone, Debug, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct PetscOptions {
    /// PETSc's own options, as on its command line (`"-ksp_type cg -pc_type gamg"`); added to
    /// those of the `PETSC_OPTIONS` environment variable, and taking precedence over them.
    pub options: Option<Spanned<String>>,
    /// tmc's defaults under the options: "direct" (MUMPS) or "multigrid" (GMRES with a field
    /// split: smoothed-aggregation multigrid on the mechanics, BoomerAMG on heat).
    pub method: PetscMethod,
}

#[derive(Clone, Copy, Debug, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum PetscMethod {
    #[default]
    Direct,
    Multigrid,
}

#[derive(Clone, Copy, Debug, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum CouplingChoice {
    #[default]
    Auto,
    Monolithic,
}

#[derive(Clone, Copy, Debug, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum LinearChoice {
    #[default]
    Auto,
    Lu,
    Ldlt,
    Gmres,
}

/// `[[probe]]`: a named scalar output evaluated after every converged step.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [[probe]] table")]
pub struct Probe {
    pub name: Spanned<String>,
    /// "ux", "uy", "uz", "theta" (value at `at`) or "distance" (between `from` and `to`).
    pub field: Spanned<String>,
    pub at: Option<Vec<f64>>,
    pub from: Option<Vec<f64>>,
    pub to: Option<Vec<f64>>,
    /// Axis of the distance: "x", "y" or "z".
    pub axis: Option<String>,
}

/// `[mesh_options]`: how to mesh when `mesh` names a `.geo`.
#[derive(Clone, Debug, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct MeshOpts {
    pub order: Option<u8>,
    pub incomplete: bool,
    /// `.geo` parameters (DefineConstant names) and their values.
    pub params: std::collections::BTreeMap<String, f64>,
}

/// A whole case file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseFile {
    pub mesh: Spanned<String>,
    #[serde(default)]
    pub mesh_options: MeshOpts,
    #[serde(default)]
    pub region: Vec<Region>,
    #[serde(default)]
    pub bc: Vec<Bc>,
    #[serde(default)]
    pub steps: Steps,
    pub time: Option<Time>,
    #[serde(default)]
    pub solver: Solver,
    #[serde(default)]
    pub probe: Vec<Probe>,
    #[serde(default)]
    pub output: Output,
    #[serde(default)]
    pub units: Units,
}

/// `[units]`: the names of the case's units, for plot axes and `summary.json` only. tmc
/// converts nothing: the numbers are read and written in whatever consistent set the case uses.
#[derive(Clone, Debug, Deserialize, Default, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct Units {
    pub length: Option<String>,
    pub force: Option<String>,
    pub time: Option<String>,
    pub temperature: Option<String>,
    /// Default: force·length.
    pub energy: Option<String>,
    /// Of heat flows; default: energy/time.
    pub power: Option<String>,
}

/// `[output]`: which steps get a `.vtu` (history.csv has every step).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, expecting = "the [output] table")]
pub struct Output {
    /// A `.vtu` every this many accepted steps (default 1: every step); step 0 and the last
    /// step reached are always written.
    pub every: Spanned<i64>,
}

impl Default for Output {
    fn default() -> Self {
        Output {
            every: Spanned::new(0..0, 1),
        }
    }
}

/// A parsed case with its source, for error messages.
#[derive(Clone, Debug)]
pub struct Case {
    pub path: PathBuf,
    pub text: String,
    pub file: CaseFile,
}

/// Set `path` (dotted) in the case `doc` to `value`. In an array of tables (`[[bc]]`,
/// `[[region]]`, `[[probe]]`) the segment after its name picks an entry by its `group` or
/// `name`: `bc.top.uy`; where several match, `bc.bottom#2.theta` picks the second of them in
/// file order, and without `#N` the error lists them, with their lines when `text` (the case
/// file's source) is given.
pub fn set_path(
    doc: &mut toml::Table,
    path: &str,
    value: toml::Value,
    text: Option<&str>,
) -> Result<(), String> {
    let segs: Vec<&str> = path.split('.').collect();
    let mut cur: &mut toml::Table = doc;
    for (i, seg) in segs.iter().enumerate() {
        if i + 1 == segs.len() {
            cur.insert(seg.to_string(), value);
            return Ok(());
        }
        let entry = cur
            .entry(seg.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = match entry {
            toml::Value::Table(t) => t,
            toml::Value::Array(items) => {
                // the entry segment: GROUP or NAME, then #N (from 1) among those that match
                let next = segs[i + 1];
                let (key, nth) = match next.split_once('#') {
                    Some((k, n)) => match n.parse::<usize>() {
                        Ok(n) if n >= 1 => (k, Some(n)),
                        _ => {
                            return Err(format!(
                                "\"{path}\": \"#{n}\" is no entry number (they count from 1 in \
                                 file order)"
                            ));
                        }
                    },
                    None => (next, None),
                };
                let matches = |t: &toml::Table| {
                    ["group", "name"]
                        .iter()
                        .any(|k| t.get(*k).and_then(|g| g.as_str()) == Some(key))
                };
                let found: Vec<usize> = (0..items.len())
                    .filter(|&k| items[k].as_table().is_some_and(matches))
                    .collect();
                let pick = match (nth, found.len()) {
                    (_, 0) => {
                        return Err(format!(
                            "\"{path}\": no [[{seg}]] with group or name \"{key}\""
                        ));
                    }
                    (None, 1) => found[0],
                    (Some(n), m) if n <= m => found[n - 1],
                    (nth, m) => {
                        let lines = entry_lines(text, seg);
                        let list: Vec<String> = found
                            .iter()
                            .enumerate()
                            .map(|(r, &k)| match lines.get(k) {
                                Some(l) => format!("{seg}.{key}#{} (line {l})", r + 1),
                                None => format!("{seg}.{key}#{}", r + 1),
                            })
                            .collect();
                        let why = match nth {
                            Some(n) => format!("there is no #{n}"),
                            None => "say which".to_string(),
                        };
                        return Err(format!(
                            "\"{path}\": {m} [[{seg}]] have group or name \"{key}\", {why}: {} \
                             (or give the entry a name = \"...\" and use that)",
                            list.join(", ")
                        ));
                    }
                };
                let Some(t) = items[pick].as_table_mut() else {
                    unreachable!("picked among tables")
                };
                // the array segment consumed the next one too
                let rest = &segs[i + 2..];
                if rest.is_empty() {
                    return Err(format!("\"{path}\": names an entry, not a key in it"));
                }
                return set_path(t, &rest.join("."), value, None);
            }
            _ => return Err(format!("\"{path}\": \"{seg}\" is not a table")),
        };
    }
    Err(format!("\"{path}\": empty key"))
}

/// The lines (from 1) of the `[[seg]]` headers of a case's source, in file order: entry k of
/// the array is at the k-th (none where the source is unknown).
fn entry_lines(text: Option<&str>, seg: &str) -> Vec<usize> {
    let header = format!("[[{seg}]]");
    text.map_or(Vec::new(), |t| {
        t.lines()
            .enumerate()
            .filter(|(_, l)| l.trim_start().starts_with(&header))
            .map(|(n, _)| n + 1)
            .collect()
    })
}

/// Most load or time steps a case may ask for (a `path` value or a `dt` is at least one).
pub const MAX_STEPS: usize = 100_000;
/// Smallest `[steps] min`, as a fraction of the path.
pub const MIN_STEP: f64 = 1e-12;

/// Largest magnitude of any number in a case file: beyond it, products of moduli, strains and
/// lengths overflow (no physical quantity in consistent units comes near).
pub const MAX_MAGNITUDE: f64 = 1e30;

/// Every number of a case file finite and at most [`MAX_MAGNITUDE`] in magnitude; the error
/// gives the offending value's byte offset and its dotted key.
fn check_numbers(text: &str) -> Result<(), (usize, String)> {
    use toml::de::{DeTable, DeValue};
    fn walk(v: &toml::Spanned<DeValue<'_>>, key: &str) -> Result<(), (usize, String)> {
        match v.get_ref() {
            DeValue::Float(f) => {
                let x: f64 = f.as_str().replace('_', "").parse().unwrap_or(f64::NAN);
                if !x.is_finite() {
                    return Err((
                        v.span().start,
                        format!("`{key} = {f}` is not a finite number"),
                    ));
                }
                if x.abs() > MAX_MAGNITUDE {
                    return Err((
                        v.span().start,
                        format!("`{key} = {f}` is out of range (|value| ≤ {MAX_MAGNITUDE:e})"),
                    ));
                }
            }
            DeValue::Array(a) => {
                for (i, e) in a.iter().enumerate() {
                    walk(e, &format!("{key}[{i}]"))?;
                }
            }
            DeValue::Table(t) => {
                for (k, e) in t.iter() {
                    let sub = if key.is_empty() {
                        k.get_ref().to_string()
                    } else {
                        format!("{key}.{}", k.get_ref())
                    };
                    walk(e, &sub)?;
                }
            }
            _ => {}
        }
        Ok(())
    }
    let Ok(table) = DeTable::parse(text) else {
        return Ok(()); // syntax errors are reported by the parse proper
    };
    let span = table.span();
    walk(
        &toml::Spanned::new(span, DeValue::Table(table.into_inner())),
        "",
    )
}

impl Case {
    /// The case with `sets` applied: dotted paths as in a study's `set`
    /// (`mesh_options.params.n`, `region.medium.gamma`, `steps.max`), values in TOML syntax
    /// (a bare word is a string). The case as written was checked already; an error the
    /// settings cause names them.
    pub fn with_sets(self, sets: &[(String, String)]) -> Result<Case, CaseError> {
        if sets.is_empty() {
            return Ok(self);
        }
        let said = sets
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(" ");
        let err = |msg: String| CaseError::Set {
            path: self.path.clone(),
            sets: said.clone(),
            msg,
        };
        let mut doc: toml::Table = toml::from_str(&self.text).map_err(|e| err(e.to_string()))?;
        for (key, raw) in sets {
            let value = toml::from_str::<toml::Table>(&format!("v = {raw}"))
                .ok()
                .and_then(|mut t| t.remove("v"))
                .unwrap_or_else(|| toml::Value::String(raw.clone()));
            set_path(&mut doc, key, value, Some(&self.text)).map_err(&err)?;
        }
        let text = toml::to_string(&doc).map_err(|e| err(e.to_string()))?;
        Case::parse(&self.path, text).map_err(|e| err(e.detail()))
    }

    pub fn read(path: &Path) -> Result<Case, CaseError> {
        let text = std::fs::read_to_string(path).map_err(|source| CaseError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(path, text)
    }

    pub fn parse(path: &Path, text: String) -> Result<Case, CaseError> {
        let file: CaseFile = toml::from_str(&text).map_err(|e| CaseError::Syntax {
            path: path.to_owned(),
            msg: e.to_string().trim_end().to_string(),
        })?;
        let case = Case {
            path: path.to_owned(),
            text,
            file,
        };
        case.check_values()?;
        // what the checks of each key leave: any other number not finite or absurd
        check_numbers(&case.text).map_err(|(at, msg)| CaseError::Invalid {
            path: case.path.clone(),
            line: case.line_of(at..at),
            msg,
        })?;
        Ok(case)
    }

    /// The mesh path, relative to the case file's folder.
    pub fn mesh_path(&self) -> PathBuf {
        let dir = self.path.parent().unwrap_or(Path::new("."));
        dir.join(self.file.mesh.get_ref())
    }

    /// Case name: the file stem.
    pub fn name(&self) -> String {
        self.path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "case".into())
    }

    pub fn line_of(&self, span: std::ops::Range<usize>) -> usize {
        self.text[..span.start.min(self.text.len())]
            .matches('\n')
            .count()
            + 1
    }

    pub fn error<T>(
        &self,
        span: std::ops::Range<usize>,
        msg: impl Into<String>,
    ) -> Result<T, CaseError> {
        Err(CaseError::Invalid {
            path: self.path.clone(),
            line: self.line_of(span),
            msg: msg.into(),
        })
    }

    /// Checks that need no mesh: moduli, steps, probes.
    fn check_values(&self) -> Result<(), CaseError> {
        let every = &self.file.output.every;
        if *every.get_ref() < 1 {
            return self.error(
                every.span(),
                format!(
                    "[output]: `every` must be at least 1, got {}",
                    every.get_ref()
                ),
            );
        }
        self.check_regions()?;
        let n_path = self.check_steps()?;
        self.check_bc_values(n_path)?;
        self.check_petsc_options()?;
        self.check_probes()
    }

    /// `[solver.petsc] options` in PETSc's command-line syntax: every word an option (`-name`)
    /// or the value right after one. PETSc skips a word that is neither without a word.
    fn check_petsc_options(&self) -> Result<(), CaseError> {
        let Some(o) = &self.file.solver.petsc.options else {
            return Ok(());
        };
        let is_option = |w: &str| w.starts_with('-') && w.parse::<f64>().is_err();
        let mut after_option = false;
        for w in o.get_ref().split_whitespace() {
            if is_option(w) {
                after_option = true;
            } else if after_option {
                after_option = false;
            } else {
                return self.error(
                    o.span(),
                    format!(
                        "[solver.petsc] options: \"{w}\" is neither an option nor an option's \
                         value (options start with a dash: \"-{w}\"?)"
                    ),
                );
            }
        }
        Ok(())
    }

    /// Every region: its kind's required moduli positive, no key of the other kind, a
    /// positive finite `rho_c`.
    fn check_regions(&self) -> Result<(), CaseError> {
        let f = &self.file;
        for (i, r) in f.region.iter().enumerate() {
            let at = r.group.span();
            let name = r.group.get_ref();
            let positive_if_given =
                |key: &str, v: &Option<Spanned<f64>>| -> Result<(), CaseError> {
                    match v {
                        Some(v) if !(*v.get_ref() > 0.0) => self.error(
                            v.span(),
                            format!(
                                "region[{i}] (\"{name}\"): `{key}` must be positive, got {}",
                                v.get_ref()
                            ),
                        ),
                        _ => Ok(()),
                    }
                };
            let need = |key: &str, v: &Option<Spanned<f64>>| -> Result<(), CaseError> {
                if v.is_none() {
                    return self.error(
                        at.clone(),
                        format!("region[{i}] (\"{name}\"): `{key}` is required"),
                    );
                }
                positive_if_given(key, v)
            };
            if let Some(v) = &r.rho_c
                && !(*v.get_ref() > 0.0 && v.get_ref().is_finite())
            {
                return self.error(
                    v.span(),
                    format!(
                        "region[{i}] (\"{name}\"): `rho_c` must be positive and finite, got {}",
                        v.get_ref()
                    ),
                );
            }
            if let Some(fr) = &r.friction {
                if r.kind == RegionKind::Solid {
                    return self.error(
                        fr.span(),
                        format!(
                            "region[{i}] (\"{name}\"): `friction` acts in a medium's slip plane; \
                             this region is a solid (give it to the medium region between the bodies)"
                        ),
                    );
                }
                self.check_friction(i, name, fr.get_ref())?;
            }
            match r.kind {
                RegionKind::Solid => {
                    need("K", &r.K)?;
                    self.check_solid_law(i, name, r)?;
                    positive_if_given("k", &r.k)?;
                    for (key, v) in [
                        ("gamma", &r.gamma),
                        ("k_max", &r.k_max),
                        ("h_closed", &r.h_closed),
                        ("thickness", &r.thickness),
                        ("beta1", &r.beta1),
                        ("beta2", &r.beta2),
                        ("alpha_r", &r.alpha_r),
                    ] {
                        if let Some(v) = v {
                            return self.error(v.span(), format!("region[{i}] (\"{name}\"): `{key}` is a medium key; this region is a solid"));
                        }
                    }
                }
                RegionKind::Medium => {
                    need("gamma", &r.gamma)?;
                    positive_if_given("k", &r.k)?;
                    positive_if_given("k_max", &r.k_max)?;
                    positive_if_given("beta1", &r.beta1)?;
                    positive_if_given("beta2", &r.beta2)?;
                    positive_if_given("alpha_r", &r.alpha_r)?;
                    self.check_medium_conductivity(i, name, r)?;
                    for (key, v) in [("K", &r.K), ("mu", &r.mu), ("C10", &r.C10), ("C01", &r.C01)] {
                        if let Some(v) = v {
                            return self.error(v.span(), format!("region[{i}] (\"{name}\"): `{key}` is a solid key; the medium's moduli are `gamma`"));
                        }
                    }
                    if let Some(law) = &r.law {
                        return self.error(
                            law.span(),
                            format!(
                                "region[{i}] (\"{name}\"): `law` chooses a solid's law; the medium's \
                                 is eq. (13), Neo-Hooke with K = μ = `gamma`"
                            ),
                        );
                    }
                }
            }
        }
        Ok(())
    }

    /// A medium's conductivity law: the paper's (`k`, `k_max`), capped by a closed layer's
    /// conductance (`h_closed` with `thickness`), or a table (`k_table`, alone).
    fn check_medium_conductivity(&self, i: usize, name: &str, r: &Region) -> Result<(), CaseError> {
        let at = |msg: String, span: std::ops::Range<usize>| {
            self.error::<()>(span, format!("region[{i}] (\"{name}\"): {msg}"))
        };
        for (key, v) in [("h_closed", &r.h_closed), ("thickness", &r.thickness)] {
            if let Some(v) = v
                && !(*v.get_ref() > 0.0 && v.get_ref().is_finite())
            {
                return at(
                    format!("`{key}` must be positive, got {}", v.get_ref()),
                    v.span(),
                );
            }
        }
        match (&r.h_closed, &r.thickness) {
            (Some(h), None) => {
                return at(
                    "`h_closed` needs `thickness`, the layer's undeformed thickness".into(),
                    h.span(),
                );
            }
            (None, Some(t)) => {
                return at(
                    "`thickness` is that of a closed layer whose conductance is `h_closed`; give `h_closed` too".into(),
                    t.span(),
                );
            }
            _ => {}
        }
        let Some(table) = &r.k_table else {
            return Ok(());
        };
        for (key, v) in [("k", &r.k), ("k_max", &r.k_max), ("h_closed", &r.h_closed)] {
            if let Some(v) = v {
                return at(
                    format!("`{key}` and `k_table` are two conductivity laws; give one"),
                    v.span(),
                );
            }
        }
        let rows = table.get_ref();
        let bad = |why: &str| {
            at(
                format!(
                    "`k_table` {why} (rows [J, k]: 2 to {TABLE_POINTS}, J > 0 all different, k > 0)"
                ),
                table.span(),
            )
        };
        if !(2..=TABLE_POINTS).contains(&rows.len()) {
            return bad(&format!("has {} rows", rows.len()));
        }
        if let Some((n, row)) = rows
            .iter()
            .enumerate()
            .find(|(_, row)| row.len() != 2 || !row.iter().all(|v| *v > 0.0 && v.is_finite()))
        {
            return bad(&format!("row {n} is {row:?}"));
        }
        let mut js: Vec<f64> = rows.iter().map(|row| row[0]).collect();
        js.sort_by(f64::total_cmp);
        if let Some(w) = js.windows(2).find(|w| w[0] == w[1]) {
            return bad(&format!("gives J = {} twice", w[0]));
        }
        Ok(())
    }

    /// A solid region's law and its moduli: Neo-Hooke's `mu` > 0, or Mooney-Rivlin's `C10` > 0
    /// and `C01` ≥ 0; no key of the other law.
    fn check_solid_law(&self, i: usize, name: &str, r: &Region) -> Result<(), CaseError> {
        let law = r
            .law
            .as_ref()
            .map_or(SolidLawKey::NeoHooke, |l| *l.get_ref());
        let at = || r.law.as_ref().map_or(r.group.span(), |l| l.span());
        type Keys<'a, T> = &'a [(&'a str, &'a Option<Spanned<f64>>, T)];
        let (needed, other): (Keys<bool>, Keys<()>) = match law {
            SolidLawKey::NeoHooke => (
                &[("mu", &r.mu, true)],
                &[("C10", &r.C10, ()), ("C01", &r.C01, ())],
            ),
            SolidLawKey::MooneyRivlin => (
                &[("C10", &r.C10, true), ("C01", &r.C01, false)],
                &[("mu", &r.mu, ())],
            ),
        };
        let law_name = match law {
            SolidLawKey::NeoHooke => "neo-hooke",
            SolidLawKey::MooneyRivlin => "mooney-rivlin",
        };
        for &(key, v, ()) in other {
            if let Some(v) = v {
                return self.error(
                    v.span(),
                    format!(
                        "region[{i}] (\"{name}\"): `{key}` is not a key of law \"{law_name}\" \
                         (neo-hooke takes `K` and `mu`; mooney-rivlin `K`, `C10` and `C01`)"
                    ),
                );
            }
        }
        for &(key, v, positive) in needed {
            let Some(v) = v else {
                return self.error(
                    at(),
                    format!("region[{i}] (\"{name}\"): law \"{law_name}\" needs `{key}`"),
                );
            };
            let x = *v.get_ref();
            let ok = x.is_finite() && if positive { x > 0.0 } else { x >= 0.0 };
            if !ok {
                let must = if positive { "positive" } else { "≥ 0" };
                return self.error(
                    v.span(),
                    format!("region[{i}] (\"{name}\"): `{key}` must be {must}, got {x}"),
                );
            }
        }
        Ok(())
    }

    /// A medium region's `friction`: μ ≥ 0, a normal of 2 or 3 finite components not all
    /// zero or "auto", `heat_fraction` in [0, 1], `c_f` positive (the normal's dimension is checked
    /// against the mesh's in [`Case::validate`]).
    fn check_friction(&self, i: usize, name: &str, fr: &FrictionKey) -> Result<(), CaseError> {
        let key = |k: &str| format!("region[{i}] (\"{name}\"): `friction.{k}`");
        let mu = *fr.mu.get_ref();
        if !(mu >= 0.0 && mu.is_finite()) {
            return self.error(
                fr.mu.span(),
                format!("{} must be finite and ≥ 0, got {mu}", key("mu")),
            );
        }
        let bad_normal = |got: String| {
            self.error(
                fr.normal.span(),
                format!(
                    "{} must be \"auto\" or a vector of 2 (2D) or 3 (3D) finite components, not all zero; got {got}",
                    key("normal")
                ),
            )
        };
        match fr.normal.get_ref() {
            SlipNormal::Given(n) => {
                let length = n.iter().map(|v| v * v).sum::<f64>().sqrt();
                if !(2..=3).contains(&n.len())
                    || !n.iter().all(|v| v.is_finite())
                    || !(length > 0.0)
                {
                    return bad_normal(format!("{n:?}"));
                }
            }
            SlipNormal::Word(w) if w != "auto" => return bad_normal(format!("\"{w}\"")),
            SlipNormal::Word(_) => {}
        }
        if let Some(v) = &fr.heat_fraction
            && !(0.0..=1.0).contains(v.get_ref())
        {
            return self.error(
                v.span(),
                format!(
                    "{} must be in [0, 1], got {}",
                    key("heat_fraction"),
                    v.get_ref()
                ),
            );
        }
        if let Some(v) = &fr.c_f
            && !(*v.get_ref() > 0.0 && v.get_ref().is_finite())
        {
            return self.error(
                v.span(),
                format!(
                    "{} must be positive and finite, got {}",
                    key("c_f"),
                    v.get_ref()
                ),
            );
        }
        Ok(())
    }

    /// `[steps]` and `[time]`; returns how many values a group's own `path` needs.
    fn check_steps(&self) -> Result<usize, CaseError> {
        let f = &self.file;
        let s = &f.steps;
        let steps_at = self.text.find("[steps]").unwrap_or(0);
        let bad = |msg: &str| self.error::<()>(steps_at..steps_at, format!("[steps]: {msg}"));
        if !(s.min > 0.0 && s.min <= s.initial && s.initial <= s.max && s.max <= 1.0) {
            bad("need 0 < min <= initial <= max <= 1")?;
        }
        if s.min < MIN_STEP {
            bad(&format!(
                "min = {:e} is below {MIN_STEP:e}: a step that small changes nothing a double \
                 can hold, and cutting down to it takes thousands of failed attempts",
                s.min
            ))?;
        }
        if let Some(p) = &s.path
            && p.len() > MAX_STEPS
        {
            bad(&format!(
                "path has {} values; at most {MAX_STEPS} (each is at least one load step)",
                p.len()
            ))?;
        }
        if !(s.tol > 0.0 && s.tol < 1.0) {
            bad("tol must be in (0, 1)")?;
        }
        if s.max_iter < 2 {
            bad("max_iter must be at least 2")?;
        }
        if !(s.grow >= 1.0 && s.cut > 0.0 && s.cut < 1.0) {
            bad("need grow >= 1 and 0 < cut < 1")?;
        }
        let n_path = match (&s.path, &f.time) {
            (Some(_), Some(_)) => {
                bad(
                    "`path` is over pseudo-time; with [time], give the load factor as [time] lambda = [[t, λ], …]",
                )?;
                0
            }
            (Some(p), None) if p.len() < 2 || p[0] != 0.0 || p.iter().any(|v| !v.is_finite()) => {
                bad("path needs at least two finite values, the first 0 (the unloaded state)")?;
                0
            }
            (Some(p), None) => p.len(),
            (None, Some(t)) => {
                self.check_time(t)?;
                t.lambda.as_ref().map_or(2, |l| l.get_ref().len())
            }
            (None, None) => 2,
        };
        Ok(n_path)
    }

    /// Each `[[bc]]`'s own `path` (`n_path` values), `ramp` and convection.
    fn check_bc_values(&self, n_path: usize) -> Result<(), CaseError> {
        let f = &self.file;
        for (i, bc) in f.bc.iter().enumerate() {
            let Some(r) = &bc.ramp else { continue };
            if let Ramp::Per(m) = r.get_ref() {
                let given: Vec<&str> = RAMPED_VALUES
                    .iter()
                    .copied()
                    .filter(|v| bc.has(v))
                    .collect();
                if let Some(k) = m.keys().find(|k| !given.contains(&k.as_str())) {
                    return self.error(
                        r.span(),
                        format!(
                            "bc[{i}] (\"{}\"): `ramp` names \"{k}\", which this block does not give (it gives {})",
                            bc.group.get_ref(),
                            given.join(", ")
                        ),
                    );
                }
            }
        }
        for bc in &f.bc {
            let Some(own) = &bc.path else { continue };
            let g = bc.group.get_ref();
            let v = own.get_ref();
            if v.len() != n_path || v[0] != 0.0 || v.iter().any(|v| !v.is_finite()) {
                return self.error(
                    own.span(),
                    format!("bc on \"{g}\": `path` needs {n_path} finite values (one per value of [steps] path, or per row of [time] lambda), the first 0"),
                );
            }
            if bc.traction.is_some()
                || bc.heat_flux.is_some()
                || bc.exchanges_heat()
                || bc.holds_any()
            {
                return self.error(
                    own.span(),
                    format!("bc on \"{g}\": `path` applies to prescribed values (ux, uy, uz, theta) only, not to `traction`, `heat_flux`, `h`, `radiation` or `ramp = false`"),
                );
            }
        }
        for bc in &f.bc {
            self.check_convection(bc)?;
            self.check_radiation(bc)?;
        }
        // a group that convects in one [[bc]] and holds θ in another: the held θ wins, and
        // the convected heat would be in no balance
        for bc in f.bc.iter().filter(|b| b.theta.is_some()) {
            let g = bc.group.get_ref();
            let exchanging = f.bc.iter().filter(|b| b.group.get_ref() == g);
            let law = exchanging
                .flat_map(|b| {
                    let h = b.h.as_ref().map(|h| ("convects (`h`)", h.span()));
                    let r = b
                        .radiation
                        .as_ref()
                        .map(|r| ("radiates (`radiation`)", r.span()));
                    h.into_iter().chain(r)
                })
                .next();
            if let Some((what, at)) = law {
                let theta_line = self.line_of(bc.group.span());
                return self.error(
                    at,
                    format!(
                        "bc on \"{g}\": the group {what} here and has a prescribed \
                         `theta` in the [[bc]] at line {theta_line}; a boundary is either held \
                         at a temperature or lets heat out by a law"
                    ),
                );
            }
        }
        Ok(())
    }

    /// Probes: a known field with the points it needs, names used once.
    fn check_probes(&self) -> Result<(), CaseError> {
        let f = &self.file;
        for p in &f.probe {
            let field = p.field.get_ref().as_str();
            match field {
                "ux" | "uy" | "uz" | "theta" => {
                    if p.at.is_none() {
                        return self.error(
                            p.field.span(),
                            format!(
                                "probe \"{}\": field \"{field}\" needs `at`",
                                p.name.get_ref()
                            ),
                        );
                    }
                }
                "distance" => {
                    if p.from.is_none() || p.to.is_none() || p.axis.is_none() {
                        return self.error(
                            p.field.span(),
                            format!(
                                "probe \"{}\": a distance needs `from`, `to` and `axis`",
                                p.name.get_ref()
                            ),
                        );
                    }
                    if !matches!(p.axis.as_deref(), Some("x" | "y" | "z")) {
                        return self.error(
                            p.field.span(),
                            format!(
                                "probe \"{}\": axis must be \"x\", \"y\" or \"z\"",
                                p.name.get_ref()
                            ),
                        );
                    }
                }
                other => {
                    return self.error(
                        p.field.span(),
                        format!(
                            "probe \"{}\": unknown field \"{other}\" (ux, uy, uz, theta, distance)",
                            p.name.get_ref()
                        ),
                    );
                }
            }
        }
        let mut names: Vec<&str> = f.probe.iter().map(|p| p.name.get_ref().as_str()).collect();
        names.sort_unstable();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            let p = f
                .probe
                .iter()
                .find(|p| p.name.get_ref() == w[0])
                .expect("found");
            return self.error(
                p.name.span(),
                format!("probe name \"{}\" is used twice", w[0]),
            );
        }
        Ok(())
    }

    /// `[time]`: a positive end, steps (`dt` or `times`) inside it, and a load table that
    /// starts at t = 0 and increases.
    fn check_time(&self, t: &Time) -> Result<(), CaseError> {
        let end = *t.end.get_ref();
        if !(end > 0.0 && end.is_finite()) {
            return self.error(
                t.end.span(),
                format!("[time]: `end` must be positive and finite, got {end}"),
            );
        }
        if t.dt.is_none() && t.times.is_none() {
            return self.error(
                t.end.span(),
                "[time]: no steps; give the step size `dt` or the step times `times`",
            );
        }
        if let Some(dt) = &t.dt {
            let v = *dt.get_ref();
            if !(v > 0.0 && v <= end) {
                return self.error(
                    dt.span(),
                    format!("[time]: `dt` must be positive and at most `end` ({end}), got {v}"),
                );
            }
            if end / v > MAX_STEPS as f64 {
                return self.error(
                    dt.span(),
                    format!(
                        "[time]: end / dt = {:.3e} steps; at most {MAX_STEPS}",
                        end / v
                    ),
                );
            }
        }
        if let Some(times) = &t.times {
            let v = times.get_ref();
            if v.len() > MAX_STEPS {
                return self.error(
                    times.span(),
                    format!("[time]: {} `times`; at most {MAX_STEPS}", v.len()),
                );
            }
            let increasing = v.windows(2).all(|w| w[0] < w[1]);
            if v.is_empty() || !increasing || !(v[0] > 0.0) || !(v[v.len() - 1] <= end) {
                return self.error(
                    times.span(),
                    format!("[time]: `times` must increase within (0, end = {end}]"),
                );
            }
        }
        if let Some(l) = &t.lambda {
            let v = l.get_ref();
            if let Some((i, r)) = v.iter().enumerate().find(|(_, r)| r.len() != 2) {
                return self.error(
                    l.span(),
                    format!(
                        "[time]: `lambda` row {} has {} value{}; each row is [t, λ]",
                        i + 1,
                        r.len(),
                        if r.len() == 1 { "" } else { "s" }
                    ),
                );
            }
            let ok = v.len() >= 2
                && v[0][0] == 0.0
                && v.windows(2).all(|w| w[0][0] < w[1][0])
                && v.iter().flatten().all(|x| x.is_finite());
            if !ok {
                return self.error(
                    l.span(),
                    "[time]: `lambda` needs at least two finite [t, λ] rows, t increasing from 0",
                );
            }
        }
        Ok(())
    }

    /// A radiation condition: emissivity in (0, 1], θ∞ and σ positive and finite.
    fn check_radiation(&self, bc: &Bc) -> Result<(), CaseError> {
        let Some(rad) = &bc.radiation else {
            return Ok(());
        };
        let g = bc.group.get_ref();
        let rad = rad.get_ref();
        let e = *rad.emissivity.get_ref();
        if !(e > 0.0 && e <= 1.0) {
            return self.error(
                rad.emissivity.span(),
                format!("bc on \"{g}\": `radiation.emissivity` must be in (0, 1], got {e}"),
            );
        }
        for (key, v) in [("theta_inf", &rad.theta_inf), ("sigma", &rad.sigma)] {
            let x = *v.get_ref();
            if !(x > 0.0 && x.is_finite()) {
                let why = if key == "theta_inf" {
                    " (an absolute temperature, e.g. in kelvin)"
                } else {
                    " (5.670374419e-8 in SI units)"
                };
                return self.error(
                    v.span(),
                    format!(
                        "bc on \"{g}\": `radiation.{key}` must be positive and finite{why}, got {x}"
                    ),
                );
            }
        }
        Ok(())
    }

    /// A convection condition has both `h` (finite, ≥ 0) and `theta_inf` (finite), and no
    /// prescribed θ on the same group.
    fn check_convection(&self, bc: &Bc) -> Result<(), CaseError> {
        let g = bc.group.get_ref();
        match (&bc.h, &bc.theta_inf) {
            (None, None) => Ok(()),
            (Some(h), None) => self.error(
                h.span(),
                format!("bc on \"{g}\": convection `h` needs `theta_inf`, the ambient temperature"),
            ),
            (None, Some(t)) => self.error(
                t.span(),
                format!("bc on \"{g}\": `theta_inf` is the ambient temperature of a convection; give `h` too"),
            ),
            (Some(h), Some(t)) => {
                let hv = *h.get_ref();
                if !(hv >= 0.0) || !hv.is_finite() {
                    return self.error(
                        h.span(),
                        format!("bc on \"{g}\": `h` must be finite and ≥ 0, got {hv}"),
                    );
                }
                if !t.get_ref().is_finite() {
                    return self.error(
                        t.span(),
                        format!("bc on \"{g}\": `theta_inf` must be finite, got {}", t.get_ref()),
                    );
                }
                if bc.theta.is_some() {
                    return self.error(
                        h.span(),
                        format!("bc on \"{g}\": a group with a prescribed `theta` cannot also convect (`h`)"),
                    );
                }
                Ok(())
            }
        }
    }

    /// Checks against the mesh: groups exist and have the right dimension, every cell has a
    /// material, prescribed components exist in this dimension.
    pub fn validate(&self, mesh: &Mesh) -> Result<(), CaseError> {
        let region_groups = self.validate_regions(mesh)?;
        self.validate_cells(mesh, &region_groups)?;
        self.validate_bcs(mesh)?;
        self.validate_probes(mesh)?;
        self.validate_sizes(mesh)
    }

    /// No probe of a z quantity in a 2D mesh; points with the mesh's number of coordinates.
    fn validate_probes(&self, mesh: &Mesh) -> Result<(), CaseError> {
        for p in &self.file.probe {
            let z = p.field.get_ref() == "uz" || p.axis.as_deref() == Some("z");
            if mesh.dim == 2 && z {
                return self.error(
                    p.field.span(),
                    format!(
                        "probe \"{}\": a z quantity in a 2D mesh (x and y only)",
                        p.name.get_ref()
                    ),
                );
            }
        }
        Ok(())
    }

    /// The groups of `mesh` of a dimension `dim_ok` accepts, quoted, for error messages.
    fn groups_of(mesh: &Mesh, dim_ok: &dyn Fn(usize) -> bool) -> String {
        let names: Vec<String> = mesh
            .groups
            .iter()
            .filter(|g| dim_ok(g.dim))
            .map(|g| format!("\"{}\"", g.name))
            .collect();
        if names.is_empty() {
            "none".into()
        } else {
            names.join(", ")
        }
    }

    /// Every region names a group of cells of the mesh, once; returns those groups.
    fn validate_regions(&self, mesh: &Mesh) -> Result<Vec<usize>, CaseError> {
        let available = |dim_ok: &dyn Fn(usize) -> bool| Self::groups_of(mesh, dim_ok);
        let mut region_groups = Vec::new();
        for (i, r) in self.file.region.iter().enumerate() {
            let name = r.group.get_ref();
            let Some(g) = mesh.group(name) else {
                return self.error(
                    r.group.span(),
                    format!(
                        "region[{i}]: physical group \"{name}\" is not in the mesh {} (its {}D groups: {})",
                        mesh.source.display(),
                        mesh.dim,
                        available(&|d| d == mesh.dim)
                    ),
                );
            };
            if mesh.groups[g].dim != mesh.dim {
                return self.error(
                    r.group.span(),
                    format!(
                        "region[{i}]: group \"{name}\" has dimension {}, a region needs a {}D group of cells",
                        mesh.groups[g].dim, mesh.dim
                    ),
                );
            }
            if region_groups.contains(&g) {
                return self.error(
                    r.group.span(),
                    format!("region[{i}]: group \"{name}\" is given twice"),
                );
            }
            if let Some(fr) = &r.friction
                && let SlipNormal::Given(n) = fr.get_ref().normal.get_ref()
                && n.len() != mesh.dim
            {
                return self.error(
                    fr.get_ref().normal.span(),
                    format!(
                        "region[{i}] (\"{name}\"): `friction.normal` has {} components; the mesh is {}D",
                        n.len(),
                        mesh.dim
                    ),
                );
            }
            region_groups.push(g);
        }
        Ok(region_groups)
    }

    /// Every block of cells belongs to exactly one region.
    fn validate_cells(&self, mesh: &Mesh, region_groups: &[usize]) -> Result<(), CaseError> {
        for b in &mesh.cells {
            let n = b
                .groups
                .iter()
                .filter(|g| region_groups.contains(g))
                .count();
            if n != 1 {
                let names: Vec<&str> = b
                    .groups
                    .iter()
                    .map(|&g| mesh.groups[g].name.as_str())
                    .collect();
                let at = self.text.find("[[region]]").unwrap_or(0);
                return self.error(
                    at..at,
                    if n == 0 {
                        format!(
                            "{} cells of groups [{}] have no [[region]]; every cell needs exactly one material",
                            b.n_cells(),
                            names.join(", ")
                        )
                    } else {
                        format!("cells belong to several regions [{}]", names.join(", "))
                    },
                );
            }
        }
        Ok(())
    }

    /// Every `[[bc]]` names a boundary group of a dimension its conditions can act on.
    fn validate_bcs(&self, mesh: &Mesh) -> Result<(), CaseError> {
        let available = |dim_ok: &dyn Fn(usize) -> bool| Self::groups_of(mesh, dim_ok);
        for (i, bc) in self.file.bc.iter().enumerate() {
            let name = bc.group.get_ref();
            let Some(g) = mesh.group(name) else {
                return self.error(
                    bc.group.span(),
                    format!(
                        "bc[{i}]: physical group \"{name}\" is not in the mesh {} (boundary groups: {})",
                        mesh.source.display(),
                        available(&|d| d < mesh.dim)
                    ),
                );
            };
            let gdim = mesh.groups[g].dim;
            if gdim >= mesh.dim {
                return self.error(
                    bc.group.span(),
                    format!("bc[{i}]: group \"{name}\" is a {gdim}D group of cells; boundary conditions go on curves/surfaces/points"),
                );
            }
            if mesh.group_nodes(g).is_empty() {
                return self.error(
                    bc.group.span(),
                    format!("bc[{i}]: group \"{name}\" has no elements in the mesh {} (its entities carry no mesh, or none of its nodes belongs to a cell)", mesh.source.display()),
                );
            }
            if mesh.dim == 2 && bc.uz.is_some() {
                return self.error(
                    bc.group.span(),
                    format!("bc[{i}] (\"{name}\"): `uz` in a 2D mesh"),
                );
            }
            let natural = bc.traction.is_some() || bc.heat_flux.is_some();
            if natural && gdim + 1 != mesh.dim {
                return self.error(
                    bc.group.span(),
                    format!("bc[{i}] (\"{name}\"): traction and heat_flux need a {}D boundary group, this one is {gdim}D", mesh.dim - 1),
                );
            }
            if let Some(h) = &bc.h
                && gdim + 1 != mesh.dim
            {
                return self.error(
                    h.span(),
                    format!("bc[{i}] (\"{name}\"): convection `h` needs a {}D boundary group, this one is {gdim}D", mesh.dim - 1),
                );
            }
            if let Some(r) = &bc.radiation
                && gdim + 1 != mesh.dim
            {
                return self.error(
                    r.span(),
                    format!("bc[{i}] (\"{name}\"): `radiation` needs a {}D boundary group, this one is {gdim}D", mesh.dim - 1),
                );
            }
            if let Some(t) = &bc.traction
                && t.get_ref().len() != mesh.dim
            {
                return self.error(
                    t.span(),
                    format!("bc[{i}]: traction needs {} components", mesh.dim),
                );
            }
            let any = bc.ux.is_some()
                || bc.uy.is_some()
                || bc.uz.is_some()
                || bc.theta.is_some()
                || bc.exchanges_heat()
                || natural;
            if !any {
                return self.error(
                    bc.group.span(),
                    format!("bc[{i}] (\"{name}\"): prescribes nothing"),
                );
            }
        }
        Ok(())
    }

    /// Vectors and points have the mesh's dimension.
    fn validate_sizes(&self, mesh: &Mesh) -> Result<(), CaseError> {
        for r in &self.file.region {
            if let Some(b) = &r.body_force
                && b.len() != mesh.dim
            {
                return self.error(
                    r.group.span(),
                    format!("body_force needs {} components", mesh.dim),
                );
            }
        }
        for p in &self.file.probe {
            for pt in [&p.at, &p.from, &p.to].into_iter().flatten() {
                if pt.len() != mesh.dim {
                    return self.error(
                        p.name.span(),
                        format!(
                            "probe \"{}\": points need {} coordinates",
                            p.name.get_ref(),
                            mesh.dim
                        ),
                    );
                }
            }
        }
        Ok(())
    }
}
