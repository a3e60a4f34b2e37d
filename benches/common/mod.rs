//! What the benchmarks share: a shipped case's text, and a `tmc solve` of case text in its own
//! process (so peak memory is the run's own).

use std::path::{Path, PathBuf};
use std::process::Command;

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `cases/NAME.toml` with its `.geo` path made absolute, so it can be written anywhere.
pub fn case_text(name: &str) -> String {
    let cases = root().join("cases");
    std::fs::read_to_string(cases.join(format!("{name}.toml")))
        .unwrap()
        .replace("\"../geo/", &format!("\"{}/../geo/", cases.display()))
}

/// Write `text` as `dir/case.toml`, solve it into `dir/out`: (succeeded, summary.json).
#[allow(dead_code)] // not every benchmark solves a whole case
pub fn solve(dir: &Path, text: &str) -> (bool, serde_json::Value) {
    std::fs::create_dir_all(dir).unwrap();
    let case = dir.join("case.toml");
    std::fs::write(&case, text).unwrap();
    let out = dir.join("out");
    let ok = Command::new(env!("CARGO_BIN_EXE_tmc"))
        .args([
            "solve",
            case.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ])
        .status()
        .unwrap()
        .success();
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    (ok, serde_json::from_str(&summary).unwrap())
}
