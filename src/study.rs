//! `tmc study`: one scene solved over a list of variants (mesh parameters, element order, γ,
//! medium layers, β2, strategy: any case key), each a normal `tmc solve` in its own process
//! (so that time and peak memory are its own), then the trade of accuracy against time:
//! `study.csv`, `study.md` and PNG plots.
//!
//! ```toml
//! case = "../../cases/block.toml"     # the base case (relative to the study file)
//! measure = ["gap", "Q_top"]          # probes, Q_<group> or R_<group>_<x|y|z>
//! show = ["min_J_medium"]             # shown, not compared (also any summary.json number)
//! reference = "last"                  # "last" (the finest variant), a variant's name, or
//!                                     # a table of values: reference = { gap = 3.0e-4 };
//!                                     # without measure and reference the study tabulates
//! history = ["gap", "Q_top"]          # history.csv columns drawn against λ, per variant
//!
//! [[variant]]
//! name = "Q1 16"
//! group = "Q1"                        # one curve per group in error_vs_time.png
//! set = { "mesh_options.params" = { n = 16, m = 16, l = 4 }, "region.medium.gamma" = 1e-5 }
//! paper = { steps = 29, its = 189 }   # published figures, printed beside ours
//! ```
//!
//! `set` keys are dotted paths into the case; a segment that meets an array of tables
//! (`region`, `bc`, `probe`) picks the entry whose `group` (or `name`) it names.

use crate::case::set_path;
use crate::plot::{Chart, History, Labels, PlotError, Series, line_chart};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {msg}")]
    Invalid { path: PathBuf, msg: String },
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// The reference the errors are measured against.
#[derive(Clone, Debug, Deserialize)]
#[serde(
    untagged,
    expecting = "`reference` must be \"last\", a variant's name, or known values such as { gap = 3.0e-4 }"
)]
pub enum Reference {
    /// "last" (the last variant, by convention the finest) or a variant's name.
    Variant(String),
    /// Known values (analytical or published) per measured quantity.
    Values(BTreeMap<String, f64>),
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [[variant]] table")]
pub struct Variant {
    pub name: String,
    /// The curve this variant belongs to in the error-vs-time plot (default "all").
    pub group: Option<String>,
    /// Case keys to change, as dotted paths.
    #[serde(default)]
    pub set: toml::Table,
    /// Published figures for this variant, printed beside tmc's in the table.
    #[serde(default)]
    pub paper: BTreeMap<String, toml::Value>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// Default: the study file's stem.
    pub name: Option<String>,
    pub description: Option<String>,
    pub case: String,
    /// Compared against `reference` (none: the study only tabulates).
    #[serde(default)]
    pub measure: Vec<String>,
    /// Quantities shown beside the measured ones but not compared (e.g. a gap whose reference
    /// is 0).
    #[serde(default)]
    pub show: Vec<String>,
    /// What the measures are compared with (none: no errors, no error-vs-time plot).
    pub reference: Option<Reference>,
    #[serde(default)]
    pub history: Vec<String>,
    pub variant: Vec<Variant>,
}

impl StudyFile {
    /// The variant the errors are measured against, by name ("last" resolved), if the
    /// reference is a variant.
    fn reference_variant(&self) -> Option<&str> {
        match &self.reference {
            Some(Reference::Variant(r)) if r == "last" => {
                self.variant.last().map(|v| v.name.as_str())
            }
            Some(Reference::Variant(r)) => Some(r),
            _ => None,
        }
    }
}

/// One solved variant.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub variant: Variant,
    pub dir: PathBuf,
    pub converged: bool,
    pub message: String,
    pub dofs: f64,
    pub free_dofs: f64,
    pub cells: f64,
    pub load_steps: f64,
    pub newton_iterations: f64,
    pub assembly_s: f64,
    pub solver_s: f64,
    pub total_s: f64,
    pub peak_memory_mb: f64,
    /// Measured quantities, in `measure` order (NaN where the run gave none).
    pub values: Vec<f64>,
    /// Relative errors against the reference, in `measure` order.
    pub errors: Vec<f64>,
    /// The `show` quantities.
    pub shown: Vec<f64>,
}

impl Outcome {
    /// The largest relative error over the measured quantities.
    pub fn error(&self) -> f64 {
        self.errors.iter().copied().fold(f64::NAN, f64::max)
    }
}

/// What `run_study` produced.
pub struct StudyReport {
    pub name: String,
    pub out: PathBuf,
    pub outcomes: Vec<Outcome>,
    pub files: Vec<PathBuf>,
}

fn invalid(path: &Path, msg: impl Into<String>) -> StudyError {
    StudyError::Invalid {
        path: path.to_owned(),
        msg: msg.into(),
    }
}

/// Flatten a `set` table into (dotted path, leaf value) pairs.
fn flatten(prefix: &str, t: &toml::Table, out: &mut Vec<(String, toml::Value)>) {
    for (k, v) in t {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            // a table under a plain key sets its keys one by one (params = { n = 8 } keeps m)
            toml::Value::Table(sub) => flatten(&key, sub, out),
            _ => out.push((key, v.clone())),
        }
    }
}

/// The case text of one variant: the base case with the variant's keys set, and `mesh` made
/// absolute (the variant's case file lives elsewhere).
/// `source`, the base case's text, lets an error name the lines of the entries a key could mean.
pub fn variant_case(
    base: &toml::Table,
    source: Option<&str>,
    case_dir: &Path,
    v: &Variant,
) -> Result<String, String> {
    let mut doc = base.clone();
    if let Some(toml::Value::String(m)) = doc.get("mesh").cloned() {
        let abs = case_dir.join(&m);
        doc.insert(
            "mesh".into(),
            toml::Value::String(abs.display().to_string()),
        );
    }
    let mut sets = Vec::new();
    flatten("", &v.set, &mut sets);
    for (k, val) in sets {
        set_path(&mut doc, &k, val, source)?;
    }
    toml::to_string(&doc).map_err(|e| e.to_string())
}

/// A file-system name for a variant.
fn slug(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// A measured quantity from a summary: a probe, `Q_<group>` or `R_<group>_<axis>`, or a
/// number of the summary; `NaN` if the summary has no such quantity (see [`known_quantity`]).
fn measured(summary: &serde_json::Value, q: &str) -> f64 {
    known_quantity(summary, q).unwrap_or(f64::NAN)
}

/// The names a measure may take in `summary`, for an error message.
fn quantity_names(summary: &serde_json::Value) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    if let Some(p) = summary["probes"].as_object() {
        names.extend(p.keys().cloned());
    }
    if let Some(r) = summary["reactions"].as_object() {
        for (g, v) in r {
            for (k, _) in v.as_object().into_iter().flatten() {
                names.push(crate::driver::records::flow_name(g, k));
            }
        }
    }
    if let Some(o) = summary.as_object() {
        names.extend(
            o.iter()
                .filter(|(_, v)| v.is_number())
                .map(|(k, _)| k.clone()),
        );
    }
    names
}

fn known_quantity(summary: &serde_json::Value, q: &str) -> Option<f64> {
    if let Some(v) = summary["probes"][q].as_f64() {
        return Some(v);
    }
    let r = &summary["reactions"];
    let heat = q.strip_prefix("Q_").and_then(|g| r[g]["heat"].as_f64());
    let force = q
        .strip_prefix("R_")
        .and_then(|rest| rest.rsplit_once('_'))
        .and_then(|(g, c)| r[g][c].as_f64());
    heat.or(force).or_else(|| summary[q].as_f64())
}

/// Options of `tmc study`.
pub struct StudyOptions {
    /// Output folder (default `results/NAME`).
    pub out_dir: Option<PathBuf>,
    /// The `tmc` executable that solves each variant.
    pub exe: PathBuf,
    pub quiet: bool,
}

/// Run a study file end to end.
pub fn run_study(path: &Path, opts: &StudyOptions) -> Result<StudyReport, StudyError> {
    let (study, name) = read_study(path)?;
    // every variant's case is built (and refused) before anything runs
    let cases = variant_cases(path, &study)?;
    let out = opts
        .out_dir
        .clone()
        .unwrap_or_else(|| PathBuf::from("results").join(&name));
    let runs = out.join("runs");
    std::fs::create_dir_all(&runs).map_err(|source| StudyError::Io {
        path: runs.clone(),
        source,
    })?;
    let mut outcomes = Vec::new();
    for (i, (v, case)) in study.variant.iter().zip(&cases).enumerate() {
        if !opts.quiet {
            crate::note!("[{}/{}] {} ...", i + 1, study.variant.len(), v.name);
        }
        let o =
            run_variant(&study, v, case, &runs.join(slug(&v.name)), opts).map_err(|m| match m {
                VariantError::Study(e) => e,
                VariantError::Unknown(msg) => invalid(path, msg),
            })?;
        if !opts.quiet {
            crate::note!(
                "      {}: {:.0} dofs, {:.0} steps, {:.0} its, {:.2} s",
                o.message,
                o.dofs,
                o.load_steps,
                o.newton_iterations,
                o.total_s
            );
        }
        outcomes.push(o);
    }
    let reference_text = set_errors(&study, &mut outcomes);
    let mut files = Vec::new();
    files.push(write_csv(&out, &study, &outcomes)?);
    files.push(write_markdown(
        &out,
        &name,
        path,
        &study,
        &outcomes,
        &reference_text,
    )?);
    files.extend(write_plots(&out, &name, &study, &outcomes)?);
    Ok(StudyReport {
        name,
        out,
        outcomes,
        files,
    })
}

/// The study file, checked (variants, measures, unique names, a known reference), and its
/// name.
fn read_study(path: &Path) -> Result<(StudyFile, String), StudyError> {
    let text = std::fs::read_to_string(path).map_err(|source| StudyError::Io {
        path: path.to_owned(),
        source,
    })?;
    let study: StudyFile = toml::from_str(&text).map_err(|e| invalid(path, e.to_string()))?;
    let name = study.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_else(|| "study".into())
    });
    if study.variant.is_empty() {
        return Err(invalid(path, "a study needs at least one [[variant]]"));
    }
    if study.reference.is_some() && study.measure.is_empty() {
        return Err(invalid(
            path,
            "a `reference` needs the quantities to compare with it: `measure = [...]`",
        ));
    }
    let mut names: Vec<&str> = study.variant.iter().map(|v| v.name.as_str()).collect();
    names.sort_unstable();
    if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
        return Err(invalid(
            path,
            format!("variant name \"{}\" is used twice", w[0]),
        ));
    }
    let mut slugs: Vec<(String, &str)> = study
        .variant
        .iter()
        .map(|v| (slug(&v.name), v.name.as_str()))
        .collect();
    slugs.sort_unstable();
    if let Some(w) = slugs.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(invalid(
            path,
            format!(
                "variants \"{}\" and \"{}\" would share the folder runs/{}; rename one",
                w[0].1, w[1].1, w[0].0
            ),
        ));
    }
    if let Some(Reference::Variant(r)) = &study.reference
        && r != "last"
        && !study.variant.iter().any(|v| &v.name == r)
    {
        return Err(invalid(
            path,
            format!("reference \"{r}\" is neither \"last\" nor a variant's name"),
        ));
    }
    Ok((study, name))
}

/// The case text of every variant: the study's case with the variant's settings.
fn variant_cases(path: &Path, study: &StudyFile) -> Result<Vec<String>, StudyError> {
    let study_dir = path.parent().unwrap_or(Path::new("."));
    let case_path = study_dir.join(&study.case);
    let case_text = std::fs::read_to_string(&case_path).map_err(|source| StudyError::Io {
        path: case_path.clone(),
        source,
    })?;
    let base: toml::Table =
        toml::from_str(&case_text).map_err(|e| invalid(&case_path, e.to_string()))?;
    // absolute: the variants' case files live elsewhere
    let case_dir = std::fs::canonicalize(&case_path)
        .map_err(|source| StudyError::Io {
            path: case_path.clone(),
            source,
        })?
        .parent()
        .unwrap_or(Path::new("/"))
        .to_owned();
    study
        .variant
        .iter()
        .map(|v| {
            let text = variant_case(&base, Some(&case_text), &case_dir, v)
                .map_err(|m| invalid(path, format!("variant \"{}\": {m}", v.name)))?;
            // the whole case check (unknown keys, values) now, naming the variant and what it
            // sets, not a line of a generated file later
            crate::case::Case::parse(&case_path, text.clone()).map_err(|e| {
                invalid(
                    path,
                    format!(
                        "variant \"{}\" (set = {}) makes an invalid case: {}",
                        v.name,
                        toml::Value::Table(v.set.clone()),
                        e.detail()
                    ),
                )
            })?;
            Ok(text)
        })
        .collect()
}

/// Why a variant stops the study.
enum VariantError {
    Study(StudyError),
    /// A measure, shown quantity or history column its results do not have.
    Unknown(String),
}

impl From<StudyError> for VariantError {
    fn from(e: StudyError) -> Self {
        VariantError::Study(e)
    }
}

/// Every `measure`, `show` and `history` name the study asks for is in a converged variant's
/// results.
fn check_names(
    study: &StudyFile,
    summary: &serde_json::Value,
    res: &Path,
) -> Result<(), VariantError> {
    for q in study.measure.iter().chain(&study.show) {
        if known_quantity(summary, q).is_none() {
            return Err(VariantError::Unknown(format!(
                "the results have no quantity \"{q}\" to measure (they have: {})",
                quantity_names(summary).join(", ")
            )));
        }
    }
    if !study.history.is_empty() {
        let h = History::read(&res.join("history.csv"))
            .map_err(|e| VariantError::Unknown(e.to_string()))?;
        for c in &study.history {
            if h.column(c).is_none() {
                return Err(VariantError::Unknown(format!(
                    "history.csv has no column \"{c}\" to draw (columns: {})",
                    h.columns.join(", ")
                )));
            }
        }
    }
    Ok(())
}

/// Solve one variant's `case` with `tmc solve` in `dir`, and read what it measured.
fn run_variant(
    study: &StudyFile,
    v: &Variant,
    case: &str,
    dir: &Path,
    opts: &StudyOptions,
) -> Result<Outcome, VariantError> {
    let io = |path: &Path| {
        let path = path.to_owned();
        move |source| StudyError::Io { path, source }
    };
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let case_file = dir.join("case.toml");
    std::fs::write(&case_file, case).map_err(io(&case_file))?;
    let res = dir.join("out");
    let t0 = Instant::now();
    let proc = std::process::Command::new(&opts.exe)
        .arg("solve")
        .arg(&case_file)
        .arg("-o")
        .arg(&res)
        .arg("-q")
        .output()
        .map_err(io(&opts.exe))?;
    let wall = t0.elapsed().as_secs_f64();
    let summary: serde_json::Value = std::fs::read_to_string(res.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or(serde_json::Value::Null);
    let num = |k: &str| summary[k].as_f64().unwrap_or(f64::NAN);
    let converged = proc.status.success() && summary["converged"].as_bool() == Some(true);
    if converged {
        check_names(study, &summary, &res)?;
    }
    let quantities = |qs: &[String]| -> Vec<f64> {
        qs.iter()
            .map(|q| {
                if converged {
                    measured(&summary, q)
                } else {
                    f64::NAN
                }
            })
            .collect()
    };
    let message = if converged {
        "converged".to_string()
    } else {
        let err = String::from_utf8_lossy(&proc.stderr);
        err.lines()
            .find(|l| l.starts_with("error"))
            .unwrap_or(err.trim())
            .to_string()
    };
    Ok(Outcome {
        variant: v.clone(),
        dir: res,
        converged,
        message,
        dofs: summary["dofs"]["total"].as_f64().unwrap_or(f64::NAN),
        free_dofs: summary["dofs"]["free"].as_f64().unwrap_or(f64::NAN),
        cells: summary["cells"]
            .as_object()
            .map(|m| m.values().filter_map(|v| v.as_f64()).sum())
            .unwrap_or(f64::NAN),
        load_steps: num("load_steps"),
        newton_iterations: num("newton_iterations"),
        assembly_s: num("assembly_seconds"),
        solver_s: num("solver_seconds"),
        total_s: if summary.is_null() {
            wall
        } else {
            num("wall_seconds")
        },
        peak_memory_mb: num("peak_memory_mb"),
        values: quantities(&study.measure),
        errors: Vec::new(),
        shown: quantities(&study.show),
    })
}

/// The relative errors of every outcome against the study's reference; returns the
/// reference, in words.
fn set_errors(study: &StudyFile, outcomes: &mut [Outcome]) -> String {
    let Some(reference) = &study.reference else {
        for o in outcomes.iter_mut() {
            o.errors = vec![f64::NAN; study.measure.len()];
        }
        return "nothing (the study has no `reference`: it tabulates)".into();
    };
    let reference_values: Vec<f64> = match reference {
        Reference::Values(m) => study
            .measure
            .iter()
            .map(|q| m.get(q).copied().unwrap_or(f64::NAN))
            .collect(),
        Reference::Variant(_) => {
            let name = study.reference_variant();
            outcomes
                .iter()
                .find(|o| Some(o.variant.name.as_str()) == name)
                .map(|o| o.values.clone())
                .unwrap_or_default()
        }
    };
    for o in outcomes.iter_mut() {
        o.errors = o
            .values
            .iter()
            .zip(&reference_values)
            .map(|(v, r)| (v - r).abs() / r.abs())
            .collect();
    }
    match reference {
        Reference::Values(m) => format!(
            "known values: {}",
            m.iter()
                .map(|(k, v)| format!("{k} = {v:e}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        Reference::Variant(r) if r == "last" => format!(
            "the last (finest) variant, \"{}\"",
            study.reference_variant().unwrap_or("")
        ),
        Reference::Variant(r) => format!("the variant \"{r}\""),
    }
}

const COLUMNS: [&str; 11] = [
    "variant",
    "group",
    "dofs",
    "free_dofs",
    "cells",
    "load_steps",
    "newton_iterations",
    "assembly_s",
    "solver_s",
    "total_s",
    "peak_memory_mb",
];

fn group(v: &Variant) -> &str {
    v.group.as_deref().unwrap_or("all")
}

fn write_file(path: PathBuf, text: &str) -> Result<PathBuf, StudyError> {
    crate::output::write_atomic(&path, text.as_bytes())
        .map_err(|e| invalid(&path, e.to_string()))?;
    Ok(path)
}

fn write_csv(out: &Path, study: &StudyFile, os: &[Outcome]) -> Result<PathBuf, StudyError> {
    let mut cols: Vec<String> = COLUMNS.iter().map(|s| s.to_string()).collect();
    cols.extend(study.measure.iter().cloned());
    cols.extend(study.show.iter().cloned());
    cols.extend(study.measure.iter().map(|q| format!("err_{q}")));
    cols.extend(["error", "converged"].map(String::from));
    let mut text = crate::output::history::csv_line(&cols);
    for o in os {
        let mut row = vec![o.variant.name.clone(), group(&o.variant).to_string()];
        row.extend(
            [
                o.dofs,
                o.free_dofs,
                o.cells,
                o.load_steps,
                o.newton_iterations,
                o.assembly_s,
                o.solver_s,
                o.total_s,
                o.peak_memory_mb,
            ]
            .map(|v| format!("{v}")),
        );
        row.extend(o.values.iter().map(|v| format!("{v:e}")));
        row.extend(o.shown.iter().map(|v| format!("{v:e}")));
        row.extend(o.errors.iter().map(|v| format!("{v:e}")));
        row.push(format!("{:e}", o.error()));
        row.push(o.converged.to_string());
        text += &crate::output::history::csv_line(&row);
    }
    write_file(out.join("study.csv"), &text)
}

fn fmt_num(v: f64) -> String {
    if !v.is_finite() {
        "—".into()
    } else if v == v.round() && v.abs() < 1e7 {
        format!("{v:.0}")
    } else if v.abs() >= 0.01 && v.abs() < 1e4 {
        format!("{v:.3}")
    } else {
        format!("{v:.3e}")
    }
}

fn secs(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2}")
    } else {
        "—".into()
    }
}

fn write_markdown(
    out: &Path,
    name: &str,
    path: &Path,
    study: &StudyFile,
    os: &[Outcome],
    reference: &str,
) -> Result<PathBuf, StudyError> {
    let mut t = format!("# Study: {name}\n\n");
    if let Some(d) = &study.description {
        t += &format!("{}\n\n", d.trim());
    }
    t += &format!(
        "Case `{}`; errors are relative, against {reference}; `error` is the largest over {}.\n\
         Regenerate with `tmc study {}`.\n\n",
        study.case,
        study.measure.join(", "),
        path.display()
    );
    let paper = os.iter().any(|o| !o.variant.paper.is_empty());
    let mut head = vec![
        "variant",
        "dofs (free)",
        "steps",
        "its",
        "assembly s",
        "solver s",
        "total s",
        "peak MB",
    ]
    .into_iter()
    .map(String::from)
    .collect::<Vec<_>>();
    head.extend(study.measure.iter().cloned());
    head.extend(study.show.iter().cloned());
    head.push("error".into());
    if paper {
        head.push("paper".into());
    }
    t += &format!("| {} |\n", head.join(" | "));
    t += &format!("|{}\n", "---|".repeat(head.len()));
    for o in os {
        let mut row = vec![
            o.variant.name.clone(),
            format!("{} ({})", fmt_num(o.dofs), fmt_num(o.free_dofs)),
            fmt_num(o.load_steps),
            fmt_num(o.newton_iterations),
            secs(o.assembly_s),
            secs(o.solver_s),
            secs(o.total_s),
            if o.peak_memory_mb.is_finite() {
                format!("{:.0}", o.peak_memory_mb)
            } else {
                "—".into()
            },
        ];
        row.extend(o.values.iter().map(|v| fmt_num(*v)));
        row.extend(o.shown.iter().map(|v| fmt_num(*v)));
        row.push(if o.converged {
            format!("{:.2e}", o.error())
        } else {
            format!("failed: {}", o.message.replace('|', "/"))
        });
        if paper {
            row.push(
                o.variant
                    .paper
                    .iter()
                    .map(|(k, v)| format!("{k} {v}"))
                    .collect::<Vec<_>>()
                    .join(", "),
            );
        }
        t += &format!("| {} |\n", row.join(" | "));
    }
    t += "\n![error vs time](error_vs_time.png)\n";
    for c in &study.history {
        t += &format!("![{c} vs λ](history_{c}.png)\n");
    }
    write_file(out.join("study.md"), &t)
}

fn write_plots(
    out: &Path,
    name: &str,
    study: &StudyFile,
    os: &[Outcome],
) -> Result<Vec<PathBuf>, StudyError> {
    let mut files = Vec::new();
    if study.reference.is_some() {
        files.push(error_plot(out, name, study, os)?);
    }
    files.extend(history_plots(out, name, study, os)?);
    Ok(files)
}

/// Error against total time, one curve per group, in time order.
fn error_plot(
    out: &Path,
    name: &str,
    study: &StudyFile,
    os: &[Outcome],
) -> Result<PathBuf, StudyError> {
    let mut groups: Vec<String> = Vec::new();
    for o in os {
        if !groups.iter().any(|g| g == group(&o.variant)) {
            groups.push(group(&o.variant).to_string());
        }
    }
    let series: Vec<Series> = groups
        .iter()
        .map(|g| {
            let mut pts: Vec<(f64, f64)> = os
                .iter()
                .filter(|o| group(&o.variant) == g && o.converged)
                .map(|o| (o.total_s, o.error()))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series {
                name: g.clone(),
                points: pts,
            }
        })
        .collect();
    let f = out.join("error_vs_time.png");
    line_chart(
        &f,
        &Chart {
            title: &format!("{name}: error vs time{}", reference_note(study)),
            x_label: "total time, s",
            y_label: &format!("relative error ({})", study.measure.join(", ")),
            series: &series,
            log_x: true,
            log_y: true,
        },
    )?;
    Ok(f)
}

/// A reference variant's own error is 0, which a log axis cannot show: say so in the title.
fn reference_note(study: &StudyFile) -> String {
    study
        .reference_variant()
        .map(|name| format!(" (reference \"{name}\": error 0, not drawn)"))
        .unwrap_or_default()
}

/// The chosen history columns of every variant against λ, one plot per column.
fn history_plots(
    out: &Path,
    name: &str,
    study: &StudyFile,
    os: &[Outcome],
) -> Result<Vec<PathBuf>, StudyError> {
    let mut files = Vec::new();
    // the variants share their case's units and columns
    let labels = os.first().map(|o| Labels::read(&o.dir)).unwrap_or_default();
    for c in &study.history {
        let mut series = Vec::new();
        for o in os {
            let Ok(h) = History::read(&o.dir.join("history.csv")) else {
                continue;
            };
            if let (Some(l), Some(y)) = (h.column("lambda"), h.column(c)) {
                series.push(Series {
                    name: o.variant.name.clone(),
                    points: l.into_iter().zip(y).collect(),
                });
            }
        }
        let f = out.join(format!("history_{c}.png"));
        line_chart(
            &f,
            &Chart {
                title: &format!("{name}: {c}"),
                x_label: &labels.axis("lambda"),
                y_label: &labels.axis(c),
                series: &series,
                log_x: false,
                log_y: false,
            },
        )?;
        files.push(f);
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dotted_paths_reach_tables_and_entries_of_arrays() {
        let mut doc: toml::Table = toml::from_str(
            "mesh = \"a.geo\"\n[[region]]\ngroup = \"solid\"\nK = 1.0\n[[region]]\ngroup = \"medium\"\ngamma = 1e-4\n",
        )
        .unwrap();
        set_path(
            &mut doc,
            "region.medium.gamma",
            toml::Value::Float(1e-5),
            None,
        )
        .unwrap();
        set_path(&mut doc, "steps.max", toml::Value::Float(0.5), None).unwrap();
        set_path(
            &mut doc,
            "mesh_options.params.n",
            toml::Value::Integer(8),
            None,
        )
        .unwrap();
        assert_eq!(doc["region"][1]["gamma"].as_float(), Some(1e-5));
        assert_eq!(doc["region"][0]["K"].as_float(), Some(1.0));
        assert_eq!(doc["steps"]["max"].as_float(), Some(0.5));
        assert_eq!(doc["mesh_options"]["params"]["n"].as_integer(), Some(8));
        let e = set_path(&mut doc, "region.gas.gamma", toml::Value::Float(1.0), None).unwrap_err();
        assert!(
            e.contains("no [[region]] with group or name \"gas\""),
            "{e}"
        );
    }

    #[test]
    fn a_variant_reaches_the_second_of_two_entries_on_one_group() {
        // as cases/block.toml's "bottom": ux/uy, then θ; by number (from 1), or by name
        let source = "mesh = \"a.geo\"\n[[bc]]\ngroup = \"bottom\"\nux = 0.0\n[[bc]]\ngroup = \"bottom\"\ntheta = 20.0\nname = \"cold\"\n";
        let base: toml::Table = toml::from_str(source).unwrap();
        let variant = |set: &str| Variant {
            name: "v".into(),
            group: None,
            set: toml::from_str(set).unwrap(),
            paper: BTreeMap::new(),
        };
        for set in [
            "bc = { \"bottom#2\" = { theta = 30.0 } }",
            "\"bc.bottom#2.theta\" = 30.0",
            "bc = { cold = { theta = 30.0 } }",
        ] {
            let text = variant_case(&base, None, Path::new("/c"), &variant(set)).unwrap();
            let doc: toml::Table = toml::from_str(&text).unwrap();
            assert_eq!(doc["bc"][1]["theta"].as_float(), Some(30.0), "{set}");
            assert!(doc["bc"][0].get("theta").is_none(), "{set}");
        }
        // the group alone names two entries: refused, listing both
        let e = variant_case(
            &base,
            None,
            Path::new("/c"),
            &variant("bc = { bottom = { theta = 30.0 } }"),
        )
        .unwrap_err();
        assert!(e.contains("bc.bottom#1, bc.bottom#2"), "{e}");
        // with the case's source at hand, with their lines
        let e = variant_case(
            &base,
            Some(source),
            Path::new("/c"),
            &variant("bc = { bottom = { theta = 30.0 } }"),
        )
        .unwrap_err();
        assert!(
            e.contains("bc.bottom#1 (line 2), bc.bottom#2 (line 5)"),
            "{e}"
        );
    }

    #[test]
    fn nested_set_tables_change_only_their_keys() {
        let base: toml::Table =
            toml::from_str("mesh = \"g.geo\"\n[mesh_options]\nparams = { n = 4, m = 2 }\n")
                .unwrap();
        let v: Variant = toml::from_str(
            "name = \"a\"\nset = { mesh_options = { params = { n = 8 } }, \"steps.max\" = 0.5 }\n",
        )
        .unwrap();
        let text = variant_case(&base, None, Path::new("/x/cases"), &v).unwrap();
        let doc: toml::Table = toml::from_str(&text).unwrap();
        assert_eq!(doc["mesh"].as_str(), Some("/x/cases/g.geo"));
        assert_eq!(doc["mesh_options"]["params"]["n"].as_integer(), Some(8));
        assert_eq!(doc["mesh_options"]["params"]["m"].as_integer(), Some(2));
        assert_eq!(doc["steps"]["max"].as_float(), Some(0.5));
    }
}
