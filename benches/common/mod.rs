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
    solve_on(dir, text, 1)
}

/// As [`solve`], on `ranks` processes: `mpirun -n ranks` when more than one (allowed to run as
/// root, as CI does).
#[allow(dead_code)]
pub fn solve_on(dir: &Path, text: &str, ranks: usize) -> (bool, serde_json::Value) {
    std::fs::create_dir_all(dir).unwrap();
    let case = dir.join("case.toml");
    std::fs::write(&case, text).unwrap();
    let out = dir.join("out");
    let tmc = env!("CARGO_BIN_EXE_tmc");
    let mut cmd = if ranks > 1 {
        let mut c = Command::new("mpirun");
        c.args(["-n", &ranks.to_string(), tmc]);
        c.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
            .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
        c
    } else {
        Command::new(tmc)
    };
    let ok = cmd
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
