//! `make bench` (distributed table, with the `petsc` build): the paper's Table 2 H1 rows
//! (block-plate-3d-tm1; 32×32 only with TMC_BENCH_LARGE=1) on faer, on PETSc with MUMPS and
//! on PETSc with algebraic multigrid (GMRES + GAMG), on 1 and 2 ranks: load steps, Newton
//! iterations, Krylov iterations per Newton update, solver and assembly seconds, peak memory
//! per rank. Then multigrid's Krylov iterations against the medium's γ (1e-4, 1e-5, 1e-6) and
//! the mesh on block-plate-3d. The engines of a row run one after another (interleaved), once.

mod common;
use common::{case_text, root, solve_on};
use std::path::Path;

/// The multigrid options measured: GMRES with PETSc's smoothed-aggregation AMG.
const MULTIGRID: &str = "-ksp_type gmres -pc_type gamg -ksp_rtol 1e-10 -ksp_gmres_restart 200";

/// Solve `text` on `ranks` (0: faer, serial) with PETSc `options`: (succeeded, summary).
fn solve(dir: &Path, text: &str, ranks: usize, options: Option<&str>) -> (bool, serde_json::Value) {
    let mut text = text.to_string();
    if ranks > 0 {
        text.push_str("\n[solver]\nengine = \"petsc\"\n");
        if let Some(o) = options {
            text.push_str(&format!("[solver.petsc]\noptions = \"{o}\"\n"));
        }
    }
    solve_on(dir, &text, ranks.max(1))
}

fn row(label: &str, ok: bool, s: &serde_json::Value) -> String {
    let f = |k: &str| s[k].as_f64().unwrap_or(f64::NAN);
    let updates = f("linear_solves").max(1.0);
    let mem = match s["peak_memory_mb_ranks"].as_array() {
        Some(each) => each
            .iter()
            .map(|m| format!("{:.0}", m.as_f64().unwrap_or(f64::NAN)))
            .collect::<Vec<_>>()
            .join(" + "),
        None => format!("{:.0}", f("peak_memory_mb")),
    };
    format!(
        "{label} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {mem} | {:.4e} |",
        if ok { "yes" } else { "no" },
        s["load_steps"],
        s["newton_iterations"],
        f("krylov_iterations") / updates,
        f("solver_seconds"),
        f("assembly_seconds"),
        s["probes"]["gap"].as_f64().unwrap_or(f64::NAN),
    )
}

fn main() {
    let large = std::env::var_os("TMC_BENCH_LARGE").is_some();
    let mut plans = vec![
        ("8×8", "params = { n = 8, nb = 5, nm = 1, nq = 3 }"),
        ("16×16", "params = { n = 16, nb = 10, nm = 1, nq = 6 }"),
    ];
    if large {
        plans.push(("32×32", "params = { n = 32, nb = 20, nm = 1, nq = 12 }"));
    }
    let engines: [(&str, usize, Option<&str>); 5] = [
        ("faer", 0, None),
        ("PETSc MUMPS, 1 rank", 1, None),
        ("PETSc MUMPS, 2 ranks", 2, None),
        ("PETSc GMRES+GAMG, 1 rank", 1, Some(MULTIGRID)),
        ("PETSc GMRES+GAMG, 2 ranks", 2, Some(MULTIGRID)),
    ];
    let base = case_text("block-plate-3d-tm1");
    println!("Table 2, H1 (block-plate-3d-tm1)\n");
    println!(
        "| plan | engine | converged | load steps | Newton its | Krylov its per update | solver s | assembly s | peak MB per rank | gap |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for (plan, options) in &plans {
        let text = base.replace("params = { nm = 1 }", options);
        for (i, (label, ranks, opts)) in engines.iter().enumerate() {
            let dir = root().join(format!("target/bench/distributed/{plan}-{i}"));
            let (ok, s) = solve(&dir, &text, *ranks, *opts);
            println!("| {plan} | {}", row(label, ok, &s));
        }
    }
    println!("\nMultigrid (GMRES + GAMG, 1 rank) against the medium's γ, block-plate-3d\n");
    println!(
        "| plan | γ | converged | load steps | Newton its | Krylov its per update | solver s | assembly s | peak MB | gap |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let base = case_text("block-plate-3d");
    for (plan, options) in &plans[..plans.len().min(2)] {
        for gamma in ["1e-4", "1e-5", "1e-6"] {
            let text = format!(
                "{}\n[mesh_options]\n{options}\n",
                base.replace("gamma = 1e-4", &format!("gamma = {gamma}"))
            );
            let dir = root().join(format!("target/bench/distributed/gamma-{plan}-{gamma}"));
            let (ok, s) = solve(&dir, &text, 1, Some(MULTIGRID));
            println!("| {plan} | {}", row(gamma, ok, &s));
        }
    }
}
