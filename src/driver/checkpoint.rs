//! `restart.json`: what a run needs to continue from its last converged step exactly as if
//! it had never stopped (`tmc solve CASE --restart`). Written after every accepted step, with
//! the step's `.vtu` and `history.csv` row already on disk. Numbers are written so that they
//! read back to the same bits. Its first key, `seal`, is a fingerprint of the rest of the
//! text: a file cut short or changed after it was written is refused, whatever it changed.

use super::SolveError;
use super::state::RunState;
use crate::case::Case;
use crate::files::Fnv;
use crate::mesh::Mesh;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub const FILE: &str = "restart.json";

/// This format's version: a checkpoint of another version is refused. 2: friction keeps the
/// step's slip per point (7 history values, 4 before). 3: the mesh's fingerprint covers its
/// physical groups (a boundary group moved to other nodes changes the run). 4: `history.csv`
/// and the `.pvd` are counted, not copied (their cost per step no longer grows with the run);
/// sealed; the point history whole on several ranks too. 5: the run state as one value
/// (Newton's tally, the totals and the files each an object of their own). 6: friction keeps
/// the normal traction per point too (8 history values). 7: friction's work per point is the
/// work itself, not per reference volume (a reconnected cell's reference changes as it is
/// joined again).
pub const VERSION: u32 = 7;

/// How a sealed checkpoint begins: `{"seal":"` and 16 hex digits, then `",` and the rest.
const SEAL: &str = "{\"seal\":\"";

/// The JSON object `body` (`{…}`, without a seal) sealed: `seal` first, the FNV-1a of the
/// object's text without it, then the object's keys as they were.
pub fn seal(body: &str) -> String {
    let mut h = Fnv::default();
    h.eat(body.as_bytes());
    let rest = body.strip_prefix('{').unwrap_or(body);
    let sep = if rest.starts_with('}') { "" } else { "," };
    format!("{SEAL}{:016x}\"{sep}{rest}", h.0)
}

/// The object a sealed text holds, without its seal; the error says what is wrong.
fn unseal(text: &str) -> Result<String, String> {
    let sealed = text
        .strip_prefix(SEAL)
        .and_then(|t| Some((t.get(..16)?, t.get(16..)?.strip_prefix('"')?)))
        .and_then(|(hex, rest)| Some((u64::from_str_radix(hex, 16).ok()?, rest)));
    let Some((seal, rest)) = sealed else {
        return Err("it does not begin with its seal (it is no tmc checkpoint, or was cut)".into());
    };
    let body = match rest.strip_prefix(',') {
        Some(keys) => format!("{{{keys}"),
        None => format!("{{{rest}"),
    };
    let mut h = Fnv::default();
    h.eat(body.as_bytes());
    if h.0 != seal {
        return Err(
            "its text does not match its seal: it was cut short or changed after it \
                    was written"
                .into(),
        );
    }
    Ok(body)
}

/// A run's state with what it was computed from.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Checkpoint {
    pub version: u32,
    /// What the results depend on: the case without `[steps]` controls and `[output]`, and
    /// the mesh. A restart under another case or mesh is refused.
    pub case: String,
    pub mesh: String,
    /// Everything the run carries from one step to the next.
    #[serde(flatten)]
    pub state: RunState,
}

/// What the results of `case` depend on: its text with the `[steps]` controls (all but
/// `path`) and `[output]` left out, which a restart may change (a smaller `min` to get past a
/// hard step, another output frequency).
pub fn case_fingerprint(case: &Case) -> String {
    let mut doc: toml::Table = toml::from_str(&case.text).unwrap_or_default();
    doc.remove("output");
    if let Some(toml::Value::Table(steps)) = doc.get_mut("steps") {
        steps.retain(|k, _| k == "path");
        if steps.is_empty() {
            doc.remove("steps");
        }
    }
    toml::to_string(&doc).unwrap_or_default()
}

/// What differs between two case fingerprints, key by key ("region[0].k: 10 then, 11 now"),
/// at most a few.
fn case_changes(then: &str, now: &str) -> String {
    let parse = |t: &str| {
        toml::from_str::<toml::Table>(t)
            .map(toml::Value::Table)
            .ok()
    };
    let (Some(a), Some(b)) = (parse(then), parse(now)) else {
        return "its keys differ".into();
    };
    let mut out = Vec::new();
    differences(&a, &b, String::new(), &mut out);
    let shown: Vec<String> = out.iter().take(4).cloned().collect();
    let more = out.len().saturating_sub(shown.len());
    let mut text = shown.join("; ");
    if more > 0 {
        text.push_str(&format!("; and {more} more"));
    }
    if text.is_empty() {
        "its keys differ".into()
    } else {
        text
    }
}

/// Dotted paths where `a` (then) and `b` (now) differ, with both values.
fn differences(a: &toml::Value, b: &toml::Value, at: String, out: &mut Vec<String>) {
    use toml::Value;
    let join = |k: &str| {
        if at.is_empty() {
            k.to_string()
        } else {
            format!("{at}.{k}")
        }
    };
    match (a, b) {
        (Value::Table(x), Value::Table(y)) => {
            for (k, v) in x {
                match y.get(k) {
                    Some(w) => differences(v, w, join(k), out),
                    None => out.push(format!("{} removed (was {v})", join(k))),
                }
            }
            for (k, w) in y {
                if !x.contains_key(k) {
                    out.push(format!("{} added ({w})", join(k)));
                }
            }
        }
        (Value::Array(x), Value::Array(y))
            if x.len() == y.len() && x.iter().all(Value::is_table) =>
        {
            for (i, (v, w)) in x.iter().zip(y).enumerate() {
                differences(v, w, format!("{at}[{i}]"), out);
            }
        }
        _ if a != b => out.push(format!("{at}: {a} then, {b} now")),
        _ => {}
    }
}

/// The mesh's size and a hash (FNV-1a) of its coordinates' bits and its cells.
pub fn mesh_fingerprint(mesh: &Mesh) -> String {
    let mut h = Fnv::default();
    for x in mesh.coords.iter().flatten() {
        h.eat_u64(x.to_bits());
    }
    for b in &mesh.cells {
        for c in 0..b.n_cells() {
            for &n in b.cell(c) {
                h.eat_u64(n as u64);
            }
        }
    }
    // the physical groups: their names, dimensions and nodes (the boundary conditions act there)
    for (g, group) in mesh.groups.iter().enumerate() {
        for b in group.name.bytes() {
            h.eat_u64(b as u64);
        }
        h.eat_u64(group.dim as u64);
        for n in mesh.group_nodes(g) {
            h.eat_u64(n as u64);
        }
    }
    let h = h.0;
    format!(
        "{} nodes, {} cells, {h:016x}",
        mesh.coords.len(),
        mesh.n_cells()
    )
}

impl Checkpoint {
    pub fn path(dir: &Path) -> PathBuf {
        dir.join(FILE)
    }

    /// The sealed text of the checkpoint.
    pub fn to_json(&self) -> String {
        seal(&serde_json::to_string(self).expect("a checkpoint is serialisable"))
    }

    /// A checkpoint from the text of [`Checkpoint::to_json`] (as another rank sends it).
    pub fn from_json(text: &[u8]) -> Result<Checkpoint, SolveError> {
        let not_one =
            |e: String| SolveError::Setup(format!("the checkpoint rank 0 sent is not one: {e}"));
        let body = unseal(&String::from_utf8_lossy(text)).map_err(not_one)?;
        serde_json::from_str(&body).map_err(|e| not_one(e.to_string()))
    }

    /// Whether `dir` holds a checkpoint; the error says what to do when it does not.
    pub fn exists(dir: &Path) -> Result<(), SolveError> {
        let path = Checkpoint::path(dir);
        if path.is_file() {
            return Ok(());
        }
        Err(SolveError::Setup(format!(
            "cannot restart: {} has no {FILE} (a run leaves it from its first step on); run \
             without --restart to start over",
            dir.display()
        )))
    }

    /// The checkpoint (of the run in `dir`, read by [`Checkpoint::of_case`]), checked against
    /// the mesh it continues.
    pub fn on_mesh(self, dir: &Path, mesh: &Mesh) -> Result<Checkpoint, SolveError> {
        let now = mesh_fingerprint(mesh);
        if self.mesh != now {
            return Err(refusal(
                &Checkpoint::path(dir),
                &format!("the mesh has changed since ({} then, {now} now)", self.mesh),
            ));
        }
        Ok(self)
    }

    /// The checkpoint of the run in `dir`, checked against the case it continues (not yet
    /// its mesh): what a restart refuses first, before what the case itself cannot restart.
    pub fn of_case(dir: &Path, case: &Case) -> Result<Checkpoint, SolveError> {
        let path = Checkpoint::path(dir);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            SolveError::Setup(format!(
                "cannot restart: {} ({e}); a run leaves it after its first converged step — \
                 run without --restart to start over",
                path.display()
            ))
        })?;
        let body = unseal(&text).map_err(|e| refusal(&path, &e))?;
        let cp: Checkpoint = serde_json::from_str(&body).map_err(|e| {
            SolveError::Setup(format!(
                "cannot restart: {} is not a tmc checkpoint: {e}",
                path.display()
            ))
        })?;
        let refuse = |what: &str| Err(refusal(&path, what));
        if cp.version != VERSION {
            return refuse(&format!(
                "it was written by another version of tmc (format {})",
                cp.version
            ));
        }
        let now = case_fingerprint(case);
        if cp.case != now {
            return refuse(&format!(
                "{} has changed since: {} (only [steps] controls and [output] may change)",
                case.path.display(),
                case_changes(&cp.case, &now)
            ));
        }
        Ok(cp)
    }

    /// Whether the checkpoint in `dir` fits a run of `unknowns` unknowns whose point history
    /// blocks hold `history` values each, and its run time is a duration: the file may say the
    /// right version, case and mesh and still be damaged. `carried`: the checkpoint is the
    /// one the run made itself to go on on a changed mesh (a layer joined, the medium made
    /// again), not a restart's; one that does not fit is tmc's fault, and said so.
    pub fn fits(
        &self,
        dir: &Path,
        unknowns: usize,
        history: &[usize],
        carried: bool,
    ) -> Result<(), SolveError> {
        let state = &self.state;
        let read: Vec<usize> = state.point_history.iter().map(Vec::len).collect();
        let what = if state.x.len() != unknowns {
            format!(
                "its state has {} values where this run has {unknowns} unknowns",
                state.x.len()
            )
        } else if read != history {
            format!(
                "it holds {read:?} history values per block of points where this run keeps \
                 {history:?}"
            )
        } else if std::time::Duration::try_from_secs_f64(state.wall).is_err() {
            format!("its run time, {} s, is no duration", state.wall)
        } else {
            return Ok(());
        };
        Err(match carried {
            true => SolveError::Setup(format!(
                "the run could not go on on its changed mesh at t = {}: the state it carried \
                 does not fit it ({what}); this is a fault of tmc, not of the case: please \
                 report it with the case file",
                state.clock.t
            )),
            false => refusal(&Checkpoint::path(dir), &what),
        })
    }
}

/// The mesh a run whose medium is made again ran on after its `remakes`-th remake, with the
/// new medium cells' references and the regularization's extent: what a restart from a
/// checkpoint on that mesh builds its model from. Two are kept, [`MEDIUM_FILES`]: the newest,
/// and the one the folder's checkpoint continues, so that a run stopped after remakes and
/// before its next step restarts from the state before them.
#[derive(Debug, Serialize, Deserialize)]
pub struct RemadeMedium {
    pub remakes: usize,
    pub d: f64,
    pub mesh: Mesh,
    pub reference: Vec<Option<Vec<[f64; 3]>>>,
}

/// The files of the last two remakes' meshes: the newest first.
pub const MEDIUM_FILES: [&str; 2] = ["medium.json", "medium-previous.json"];

impl RemadeMedium {
    /// Write it into `dir` as the newest. The one it replaces is kept as the previous, unless
    /// the previous holds remake `saved` (the one the folder's checkpoint continues) and the
    /// newest does not: a remake that no step followed is replaced.
    pub fn write(&self, dir: &Path, saved: Option<usize>) -> Result<(), SolveError> {
        let [newest, previous] = MEDIUM_FILES.map(|f| dir.join(f));
        let keep_previous = saved.is_some_and(|k| {
            Self::remakes_in(&previous) == Some(k) && Self::remakes_in(&newest) != Some(k)
        });
        if !keep_previous {
            match std::fs::rename(&newest, &previous) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    return Err(SolveError::Output(crate::output::werr(&previous, e)));
                }
                _ => {}
            }
        }
        let text = serde_json::to_string(self).expect("a mesh is serialisable");
        crate::output::write_atomic(&newest, text.as_bytes()).map_err(SolveError::Output)
    }

    /// The remake a medium file at `path` holds, read from its start (the file begins with
    /// it: `{"remakes":N,`); `None` where there is none or it cannot be read.
    fn remakes_in(path: &Path) -> Option<usize> {
        use std::io::Read;
        let mut start = [0u8; 32];
        let n = std::fs::File::open(path).ok()?.read(&mut start).ok()?;
        let text = std::str::from_utf8(&start[..n]).ok()?;
        let rest = text.strip_prefix("{\"remakes\":")?;
        let digits = rest.split(|c: char| !c.is_ascii_digit()).next()?;
        digits.parse().ok()
    }

    /// The medium of the `remakes`-th remake from `dir`'s files; the error says what is
    /// missing or wrong.
    pub fn read(dir: &Path, remakes: usize) -> Result<RemadeMedium, SolveError> {
        let mut found = Vec::new();
        for name in MEDIUM_FILES {
            let path = dir.join(name);
            let Ok(text) = std::fs::read_to_string(&path) else {
                continue;
            };
            let m: RemadeMedium = serde_json::from_str(&text).map_err(|e| {
                refusal(
                    &path,
                    &format!("it is not the mesh of a medium made again: {e}"),
                )
            })?;
            if m.remakes == remakes {
                return Ok(m);
            }
            found.push(format!("{name} holds remake {}", m.remakes));
        }
        let found = if found.is_empty() {
            format!(
                "neither {} nor {} is there",
                MEDIUM_FILES[0], MEDIUM_FILES[1]
            )
        } else {
            found.join(", ")
        };
        Err(refusal(
            &Checkpoint::path(dir),
            &format!("it continues the mesh of the medium's remake {remakes}, and {found}"),
        ))
    }
}

/// A checkpoint at `path` that cannot be continued from, and why.
fn refusal(path: &Path, what: &str) -> SolveError {
    SolveError::Setup(format!(
        "cannot restart from {}: {what}; run without --restart to start over",
        path.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sealed_text_reads_back_and_any_change_breaks_its_seal() {
        for body in [r#"{"a":1,"b":[2.5,null]}"#, "{}"] {
            let sealed = seal(body);
            assert!(sealed.starts_with(SEAL));
            serde_json::from_str::<serde_json::Value>(&sealed).expect("still JSON");
            assert_eq!(unseal(&sealed).unwrap(), body);
            // every byte changed, and every length cut short, is found
            for i in 0..sealed.len() {
                let mut bytes = sealed.clone().into_bytes();
                bytes[i] = if bytes[i] == b'7' { b'8' } else { b'7' };
                let changed = String::from_utf8(bytes).unwrap();
                assert!(unseal(&changed).is_err(), "byte {i}: {changed}");
                assert!(unseal(&sealed[..i]).is_err(), "cut at {i}");
            }
        }
    }
}
