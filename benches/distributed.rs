//! `make bench` (distributed table, with the `petsc` build): the paper's Table 2 H1 rows
//! (block-plate-3d-tm1; 32×32 only with TMC_BENCH_LARGE=1) on faer, on PETSc with MUMPS and
//! on PETSc with tmc's multigrid (`method = "multigrid"`: GMRES around a field split, MUMPS on
//! the rows of the medium's nodes, GAMG with the rigid motions on the solids' u, BoomerAMG on
//! their θ), on 1 and 2 ranks: load steps, Newton iterations, Krylov iterations per Newton
//! update, solver and assembly seconds, peak memory per rank, and the λ reached. Then
//! multigrid's Krylov iterations against the medium's γ (1e-4, 1e-5, 1e-6) on block-plate-3d
//! 8×8 (and 16×16 with TMC_BENCH_LARGE=1: about 20 minutes a run). The engines of a row run
//! one after another (interleaved), once.

mod common;
use common::{case_text, root, solve_on};
use std::path::Path;

/// Solve `text` on `ranks` (0: faer, serial) with PETSc's `method`: (succeeded, summary).
fn solve(dir: &Path, text: &str, ranks: usize, method: &str) -> (bool, serde_json::Value) {
    let mut text = text.to_string();
    if ranks > 0 {
        text.push_str(&format!(
            "\n[solver]\nengine = \"petsc\"\n[solver.petsc]\nmethod = \"{method}\"\n"
        ));
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
        "{label} | {} | {:.3} | {} | {} | {:.1} | {:.1} | {:.1} | {mem} | {:.4e} |",
        if ok { "yes" } else { "no" },
        f("lambda"),
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
    let engines: [(&str, usize, &str); 5] = [
        ("faer", 0, ""),
        ("PETSc MUMPS, 1 rank", 1, "direct"),
        ("PETSc MUMPS, 2 ranks", 2, "direct"),
        ("PETSc multigrid, 1 rank", 1, "multigrid"),
        ("PETSc multigrid, 2 ranks", 2, "multigrid"),
    ];
    // TMC_BENCH_PART=gamma: the γ table alone
    let tables = std::env::var("TMC_BENCH_PART").unwrap_or_default() != "gamma";
    let base = case_text("block-plate-3d-tm1");
    if tables {
        table2(&plans, &engines, &base);
    }
    gamma_table(&plans[..if large { 2 } else { 1 }]);
}

/// The Table 2 rows of `plans`, each on every engine.
fn table2(plans: &[(&str, &str)], engines: &[(&str, usize, &str)], base: &str) {
    println!("Table 2, H1 (block-plate-3d-tm1)\n");
    println!(
        "| plan | engine | converged | λ reached | load steps | Newton its | Krylov its per update | solver s | assembly s | peak MB per rank | gap |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for (plan, options) in plans {
        let text = base.replace("params = { nm = 1 }", options);
        for (i, (label, ranks, opts)) in engines.iter().enumerate() {
            let dir = root().join(format!("target/bench/distributed/{plan}-{i}"));
            let (ok, s) = solve(&dir, &text, *ranks, opts);
            println!("| {plan} | {}", row(label, ok, &s));
        }
    }
}

/// Multigrid on block-plate-3d against the medium's γ, on `plans` (at most the first two).
fn gamma_table(plans: &[(&str, &str)]) {
    println!("\nMultigrid (tmc's, 1 rank) against the medium's γ, block-plate-3d\n");
    println!(
        "| plan | γ | converged | λ reached | load steps | Newton its | Krylov its per update | solver s | assembly s | peak MB | gap |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let base = case_text("block-plate-3d");
    for (plan, options) in &plans[..plans.len().min(2)] {
        for gamma in ["1e-4", "1e-5", "1e-6"] {
            let text = format!(
                "{}\n[mesh_options]\n{options}\n",
                base.replace("gamma = 1e-4", &format!("gamma = {gamma}"))
            );
            let dir = root().join(format!("target/bench/distributed/gamma-{plan}-{gamma}"));
            let (ok, s) = solve(&dir, &text, 1, "multigrid");
            println!("| {plan} | {}", row(gamma, ok, &s));
        }
    }
}
