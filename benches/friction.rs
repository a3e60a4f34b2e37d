//! `make bench`: what friction costs. Each friction scene of `cases/` solved as shipped, with
//! the slip planes found by tmc (`normal = "auto"`) where it gives them by hand, and without
//! friction; the variants interleaved over three rounds (this machine's speed drifts), as a
//! markdown table of medians with the wall time relative to the frictionless run.

mod common;
use common::{case_text, root, solve};

const ROUNDS: usize = 3;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let given = "friction = { mu = 0.3, normal = [0, 1] }";
    let auto = "friction = { mu = 0.3, normal = \"auto\" }";
    // (scene, [(label, case text)]); the first is the frictionless reference
    let scenes: Vec<(&str, Vec<(&str, String)>)> = ["friction-heating", "discs-ellipse-friction"]
        .iter()
        .map(|&name| {
            let shipped = case_text(name);
            let line = if shipped.contains(given) { given } else { auto };
            let mut v = vec![
                ("no friction", shipped.replace(&format!("{line}\n"), "")),
                ("μ = 0.3, as shipped", shipped.clone()),
            ];
            if line == given {
                v.push(("μ = 0.3, normal = \"auto\"", shipped.replace(given, auto)));
            }
            (name, v)
        })
        .collect();
    // runs[scene][variant] = summaries of the rounds
    let mut runs: Vec<Vec<Vec<serde_json::Value>>> = scenes
        .iter()
        .map(|(_, v)| vec![Vec::new(); v.len()])
        .collect();
    for round in 0..ROUNDS {
        for (si, (name, variants)) in scenes.iter().enumerate() {
            for (vi, (_, text)) in variants.iter().enumerate() {
                let dir = root().join(format!("target/bench-friction/{name}-{vi}-{round}"));
                let (ok, s) = solve(&dir, text);
                assert!(ok, "{name} variant {vi} failed: {}", s["message"]);
                runs[si][vi].push(s);
            }
        }
    }
    println!(
        "| scene | variant | dofs | linear solver | load steps | Newton its | friction work | wall s (median of {ROUNDS}) | linear solve s | wall / no friction |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for ((name, variants), rounds) in scenes.iter().zip(&runs) {
        let wall = |r: &[serde_json::Value], key: &str| {
            median(r.iter().map(|s| s[key].as_f64().unwrap()).collect())
        };
        let reference = wall(&rounds[0], "wall_seconds");
        for ((label, _), r) in variants.iter().zip(rounds) {
            let s = &r[0];
            let w = wall(r, "wall_seconds");
            println!(
                "| {name} | {label} | {} | {} | {} | {} | {} | {w:.2} | {:.2} | {:.2} |",
                s["dofs"]["total"],
                s["linear_solver"].as_str().unwrap_or("-"),
                s["load_steps"],
                s["newton_iterations"],
                s["friction_work"]
                    .as_f64()
                    .map_or("-".to_string(), |v| format!("{v:.4e}")),
                wall(r, "solver_seconds"),
                w / reference
            );
        }
    }
}
