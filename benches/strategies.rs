//! `make bench`: each scene under each solve strategy it admits, as a markdown table of dofs,
//! load steps, Newton iterations, wall time, linear-solve time and peak memory, with the wall
//! time of the reduced path relative to the monolithic one. Every run is a separate `tmc
//! solve` process, so peak memory is its own.

mod common;
use common::{case_text, root, solve};

/// Solve `cases/NAME.toml` with a `[solver]` table appended; the parsed summary.
fn run(name: &str, solver: &str, tag: &str) -> serde_json::Value {
    let dir = root().join("target/bench").join(format!("{name}-{tag}"));
    let (ok, summary) = solve(&dir, &format!("{}\n[solver]\n{solver}\n", case_text(name)));
    assert!(ok, "{name} ({tag}) failed");
    summary
}

fn main() {
    // (scene, [(label, [solver] keys)]); the first entry is the monolithic reference
    let scenes: &[(&str, &[(&str, &str)])] = &[
        (
            "block",
            &[
                (
                    "monolithic, GMRES + block LDLᵀ",
                    "coupling = \"monolithic\"",
                ),
                ("monolithic, LU", "linear = \"lu\""),
                ("one-way, LDLᵀ + LDLᵀ", ""),
            ],
        ),
        (
            "two-blocks",
            &[
                (
                    "monolithic, GMRES + block LDLᵀ",
                    "coupling = \"monolithic\"",
                ),
                ("monolithic, LU", "linear = \"lu\""),
                ("one-way, LDLᵀ + LDLᵀ", ""),
            ],
        ),
        (
            "slab-compressed-conduction",
            &[
                (
                    "monolithic, GMRES + block LDLᵀ",
                    "coupling = \"monolithic\"",
                ),
                ("one-way, LDLᵀ + LDLᵀ", ""),
            ],
        ),
        (
            "block-plate-3d",
            &[
                ("monolithic, GMRES + block LDLᵀ", ""),
                ("monolithic, LU", "linear = \"lu\""),
            ],
        ),
    ];
    println!(
        "| scene | strategy | dofs | load steps | Newton its | Krylov its | wall s | linear solve s | peak MB | wall / first row |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for (name, variants) in scenes {
        let mut reference = None;
        for (label, solver) in *variants {
            let tag: String = label
                .chars()
                .filter(|c| c.is_ascii_alphanumeric())
                .collect();
            let s = run(name, solver, &tag);
            let wall = s["wall_seconds"].as_f64().unwrap();
            let r = *reference.get_or_insert(wall);
            println!(
                "| {name} | {label} | {} | {} | {} | {} | {wall:.2} | {:.2} | {:.0} | {:.2} |",
                s["dofs"]["total"],
                s["load_steps"],
                s["newton_iterations"],
                s["krylov_iterations"],
                s["solver_seconds"].as_f64().unwrap(),
                s["peak_memory_mb"].as_f64().unwrap_or(f64::NAN),
                wall / r
            );
        }
    }
}
