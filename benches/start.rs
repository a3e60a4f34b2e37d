//! `make bench` (start): what a start of `tmc` costs and which libraries it loads. gmsh and
//! PETSc are opened when a run first needs them (src/dynamic.rs): `tmc --version`, the shipped
//! block checked and solved from a `.msh` on faer load neither; meshing its `.geo` loads gmsh;
//! the PETSc engine (in a `--features petsc` build) loads PETSc. The commands run interleaved,
//! seven rounds: the median wall time of each, and the shared libraries the loader opened
//! (`LD_DEBUG=files`).

mod common;
use common::{case_text, root};
use std::process::Command;
use std::time::Instant;

/// Rounds of every command, one after another.
const ROUNDS: usize = 7;

fn main() {
    let dir = root().join("target/bench/start");
    std::fs::create_dir_all(&dir).unwrap();
    let tmc = env!("CARGO_BIN_EXE_tmc");
    let geo_case = dir.join("block-geo.toml");
    std::fs::write(&geo_case, case_text("block")).unwrap();
    let msh = dir.join("block.msh");
    let geo = root().join("geo/block.geo");
    let meshed = Command::new(tmc)
        .args(["mesh", geo.to_str().unwrap(), "-o", msh.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(meshed.status.success(), "{meshed:?}");
    let text = case_text("block");
    let line = text
        .lines()
        .find(|l| l.starts_with("mesh = "))
        .expect("the block's mesh key")
        .to_string();
    let msh_case = dir.join("block-msh.toml");
    std::fs::write(
        &msh_case,
        text.replace(&line, &format!("mesh = {:?}", msh.to_str().unwrap())),
    )
    .unwrap();
    let (g, m) = (geo_case.to_str().unwrap(), msh_case.to_str().unwrap());
    let out = dir.join("out");
    let o = out.to_str().unwrap();
    let mut commands: Vec<(&str, Vec<&str>)> = vec![
        ("tmc --version", vec!["--version"]),
        ("tmc check, mesh from a .msh", vec!["check", m]),
        ("tmc solve, .msh, faer", vec!["solve", m, "-q", "-o", o]),
        ("tmc check, mesh from the .geo", vec!["check", g]),
        ("tmc solve, .geo, faer", vec!["solve", g, "-q", "-o", o]),
    ];
    if cfg!(feature = "petsc") {
        commands.push((
            "tmc solve, .msh, PETSc engine",
            vec![
                "solve",
                m,
                "-q",
                "-o",
                o,
                "--set",
                "solver.engine=\"petsc\"",
            ],
        ));
    }
    let mut times = vec![Vec::new(); commands.len()];
    for _ in 0..ROUNDS {
        for ((_, args), t) in commands.iter().zip(&mut times) {
            let start = Instant::now();
            let run = Command::new(tmc).args(args).output().unwrap();
            t.push(start.elapsed().as_secs_f64());
            assert!(run.status.success(), "{args:?}: {run:?}");
        }
    }
    println!("What a start costs (the block, {ROUNDS} rounds interleaved)\n");
    println!("| command | median wall ms | libraries loaded | gmsh | PETSc |");
    println!("|---|---|---|---|---|");
    for ((label, args), t) in commands.iter().zip(&mut times) {
        t.sort_by(f64::total_cmp);
        let run = Command::new(tmc)
            .args(args)
            .env("LD_DEBUG", "files")
            .output()
            .unwrap();
        let log = String::from_utf8_lossy(&run.stderr);
        let opened: std::collections::BTreeSet<&str> = log
            .lines()
            .filter_map(|l| l.split("file=").nth(1))
            .filter_map(|rest| rest.split_whitespace().next())
            .collect();
        let has = |lib: &str| {
            if opened.iter().any(|f| f.contains(lib)) {
                "yes"
            } else {
                "no"
            }
        };
        println!(
            "| {label} | {:.1} | {} | {} | {} |",
            1e3 * t[t.len() / 2],
            opened.len(),
            has("libgmsh"),
            has("libpetsc"),
        );
    }
}
