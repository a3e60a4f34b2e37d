//! The case file (TOML): mesh, materials per physical group, boundary conditions, steps, probes.
//!
//! Parsing refuses unknown keys and checks every value that needs no mesh (each part of the
//! file in its own module, with its checks); `model::validate` checks the case against its
//! mesh before any work starts. Every error names the file, the key and its line.

use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::Spanned;

mod bc;
mod output;
mod region;
mod sets;
mod solver;
mod steps;

pub use bc::{Bc, RAMPED_VALUES, RadiationKey, Ramp};
pub use output::{Measure, Output, Probe, Units};
pub use region::{
    FrictionKey, Material, MediumConduction, MediumMaterial, Region, RegionKind, SlipNormal,
    SolidLawKey, SolidMaterial,
};
pub use sets::{set_path, set_path_making};
pub use solver::{CouplingChoice, EngineChoice, LinearChoice, PetscMethod, PetscOptions, Solver};
pub use steps::{Steps, Time};

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

/// A parsed case with its source, for error messages.
#[derive(Clone, Debug)]
pub struct Case {
    pub path: PathBuf,
    pub text: String,
    pub file: CaseFile,
    /// Each `[[region]]`'s material, in case order (what its checked keys give).
    pub materials: Vec<Material>,
    /// Where `--set` made this case from the file: the file's own text and the settings, so
    /// that a message cites the file's line, or the `--set` that gave the key.
    pub written: Option<(String, Vec<(String, String)>)>,
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

/// Settings as a user gave them: `key=value key=value`.
fn said(sets: &[(String, String)]) -> String {
    let said: Vec<String> = sets.iter().map(|(k, v)| format!("{k}={v}")).collect();
    said.join(" ")
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
        let said = said(sets);
        let err = |msg: String| CaseError::Set {
            path: self.path.clone(),
            sets: said.clone(),
            msg,
        };
        let mut doc: toml::Table = toml::from_str(&self.text).map_err(|e| err(e.to_string()))?;
        let mut made = Vec::new();
        for (key, raw) in sets {
            let value = toml::from_str::<toml::Table>(&format!("v = {raw}"))
                .ok()
                .and_then(|mut t| t.remove("v"))
                .unwrap_or_else(|| toml::Value::String(raw.clone()));
            if let Some(table) =
                set_path_making(&mut doc, key, value, Some(&self.text)).map_err(&err)?
            {
                made.push((key, table));
            }
        }
        let text = toml::to_string(&doc).map_err(|e| err(e.to_string()))?;
        let written = Some((self.text.clone(), sets.to_vec()));
        Case::parse_set(&self.path, text, written).map_err(|e| {
            let detail = e.detail();
            // a table made by a --set holds that key alone: what it lacks is the --set's
            match (detail.contains("missing field"), made.first()) {
                (true, Some((key, table))) => err(format!(
                    "{detail}: `{key}` makes `{table}`, which the case does not have, with that \
                     key alone; give the whole table (--set '{table}={{ ... }}')"
                )),
                _ => err(detail),
            }
        })
    }

    pub fn read(path: &Path) -> Result<Case, CaseError> {
        let text = std::fs::read_to_string(path).map_err(|source| CaseError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(path, text)
    }

    pub fn parse(path: &Path, text: String) -> Result<Case, CaseError> {
        Self::parse_set(path, text, None)
    }

    /// [`Case::parse`] of a text `--set` made from the file's (`written`).
    fn parse_set(
        path: &Path,
        text: String,
        written: Option<(String, Vec<(String, String)>)>,
    ) -> Result<Case, CaseError> {
        let file: CaseFile = toml::from_str(&text).map_err(|e| CaseError::Syntax {
            path: path.to_owned(),
            msg: e.to_string().trim_end().to_string(),
        })?;
        let mut case = Case {
            path: path.to_owned(),
            text,
            file,
            materials: Vec::new(),
            written,
        };
        case.materials = case.check_values()?;
        // what the checks of each key leave: any other number not finite or absurd
        check_numbers(&case.text).or_else(|(at, msg)| case.error(at..at, msg))?;
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

    /// The line of the case file that `span` (of [`Case::text`]) stands on: where `--set`
    /// made the text, the line in the file of the same key in the same table (0 where the
    /// file does not have it, or a `--set` gave it).
    pub fn line_of(&self, span: std::ops::Range<usize>) -> usize {
        let line = self.text[..span.start.min(self.text.len())]
            .matches('\n')
            .count()
            + 1;
        match &self.written {
            None => line,
            Some((file, sets)) => sets::line_in_file(&self.text, line, file, sets).unwrap_or(0),
        }
    }

    /// Where in the text the key `key` of the table `[table]` is written: the start of its
    /// line, or of the table's header where the table does not give it (or `key` is empty), or
    /// 0 where there is no such table.
    pub fn key_at(&self, table: &str, key: &str) -> usize {
        let header = format!("[{table}]");
        let (mut offset, mut header_at) = (0, None);
        for (line, (h, _, k)) in
            (self.text.split_inclusive('\n')).zip(sets::table_lines(&self.text))
        {
            if h == header {
                if k.is_empty() {
                    header_at.get_or_insert(offset);
                } else if k == key {
                    return offset;
                }
            }
            offset += line.len();
        }
        header_at.unwrap_or(0)
    }

    /// Where `span` stands, in words: "line N" of the case file, or the `--set` that gave it.
    pub fn place(&self, span: std::ops::Range<usize>) -> String {
        match (self.line_of(span), &self.written) {
            (0, Some((_, sets))) => format!("--set {}", said(sets)),
            (line, _) => format!("line {line}"),
        }
    }

    /// An error at `span`: at its line of the case file, or, where a `--set` gave the key or
    /// the file does not have it, naming the settings.
    pub fn error<T>(
        &self,
        span: std::ops::Range<usize>,
        msg: impl Into<String>,
    ) -> Result<T, CaseError> {
        let msg = msg.into();
        Err(match (self.line_of(span), &self.written) {
            (0, Some((_, sets))) => CaseError::Set {
                path: self.path.clone(),
                sets: said(sets),
                msg,
            },
            (line, _) => CaseError::Invalid {
                path: self.path.clone(),
                line,
                msg,
            },
        })
    }

    /// Checks that need no mesh: moduli, steps, probes. Returns the regions' materials.
    fn check_values(&self) -> Result<Vec<Material>, CaseError> {
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
        let materials = self.check_regions()?;
        let n_path = self.check_steps()?;
        self.check_bc_values(n_path)?;
        self.check_petsc_options()?;
        self.check_probes()?;
        Ok(materials)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A case of `body` (a mesh key put before it) read from memory: the case, or the error's
    /// text (`t.toml:LINE: message`).
    pub(crate) fn parsed(body: &str) -> Result<Case, String> {
        Case::parse(Path::new("t.toml"), format!("mesh = \"m.msh\"\n{body}"))
            .map_err(|e| e.to_string())
    }

    /// The error a case of `body` gives; panics if it is read.
    pub(crate) fn refused(body: &str) -> String {
        match parsed(body) {
            Ok(_) => panic!("read: {body}"),
            Err(e) => e,
        }
    }

    #[test]
    fn an_error_names_the_file_and_the_line_of_the_key() {
        let e = refused("[output]\n\nevery = 0\n");
        assert_eq!(e, "t.toml:4: [output]: `every` must be at least 1, got 0");
        // an unknown key is a syntax error that names it
        let e = refused("[steps]\ninitial = 0.1\nmaxx = 3\n");
        assert!(e.contains("maxx") && e.starts_with("t.toml"), "{e}");
        // numbers beyond any physical scale, wherever they are
        let e = refused("[mesh_options.params]\nn = 1e300\n");
        assert!(
            e.contains("`mesh_options.params.n = 1e300` is out of range"),
            "{e}"
        );
    }

    #[test]
    fn a_case_made_by_sets_cites_the_file_s_lines_or_the_set() {
        let body = "[[region]]\ngroup = \"a\"\nkind = \"solid\"\nK = 1.0\nmu = 1.0\n\n\
                    [[region]]\n# the second\ngroup = \"b\"\nkind = \"medium\"\ngamma = 1e-4\n";
        let case = parsed(body).unwrap();
        let set = |k: &str, v: &str| vec![(k.to_string(), v.to_string())];
        let changed = case.with_sets(&set("steps.max", "0.25")).unwrap();
        // region b's group stands on line 10 of the file (the mesh key first), whatever line
        // the re-written text puts it on
        let span = changed.file.region[1].group.span();
        assert_eq!(changed.line_of(span.clone()), 10);
        let e = changed.error::<()>(span, "bad").unwrap_err().to_string();
        assert_eq!(e, "t.toml:10: bad");
        // a key a --set gave is the --set's
        let changed = parsed(body)
            .unwrap()
            .with_sets(&set("region.b.gamma", "1e-3"))
            .unwrap();
        let gamma = changed.text.find("gamma").unwrap();
        let e = (changed.error::<()>(gamma..gamma, "bad").unwrap_err()).to_string();
        assert_eq!(e, "t.toml with --set region.b.gamma=1e-3: bad");
        assert_eq!(changed.place(gamma..gamma), "--set region.b.gamma=1e-3");
    }

    #[test]
    fn sets_change_a_case_and_an_error_they_cause_names_them() {
        let case = parsed("[steps]\nmax = 0.5\n").unwrap();
        let set = |k: &str, v: &str| vec![(k.to_string(), v.to_string())];
        let changed = case.clone().with_sets(&set("steps.max", "0.25")).unwrap();
        assert_eq!(changed.file.steps.max, 0.25);
        let e = case
            .with_sets(&set("steps.max", "2.0"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("with --set steps.max=2.0") && e.contains("min <= initial <= max <= 1"),
            "{e}"
        );
        // a key set in a table the case does not have: the error names the table it made
        let medium =
            parsed("[[region]]\ngroup = \"gap\"\nkind = \"medium\"\ngamma = 1e-4\n").unwrap();
        let e = medium
            .with_sets(&set("region.gap.friction.forget_slip", "true"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("missing field `mu`")
                && e.contains("makes `region.gap.friction`, which the case does not have"),
            "{e}"
        );
    }
}
