//! `make bench`: what friction costs, and how far it slides.
//!
//! First table: each friction scene of `cases/` solved as shipped, with the slip planes found
//! by tmc (`normal = "auto"`) where it gives them by hand, and without friction; the variants
//! interleaved over three rounds (this machine's speed drifts), as a markdown table of medians
//! with the wall time relative to the frictionless run.
//!
//! Second table: a block (`geo/block.geo`) and a pad on a long plate (`geo/pad.geo`), pressed
//! 0.3 and dragged 1.0 (four times the medium's thickness), at several μ and numbers l of cells
//! across the medium: how far each drag gets, the force ratio on the way, and how far the
//! solid's leading bottom corner has slid by then, in cells of the layer (a drag that stops
//! before that corner has slid a cell stops before any change of the medium's connectivity
//! that follows the slide could act), each friction drag without and with a slip viscosity
//! η_s = 1e-3. `TMC_BENCH_PART=cost` or `reach` runs one table.

mod common;
use common::{case_text, root, solve};

const ROUNDS: usize = 3;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let part = std::env::var("TMC_BENCH_PART");
    if part.as_deref() != Ok("reach") {
        cost();
    }
    if part.as_deref() != Ok("cost") {
        reach();
    }
}

/// Cells across the solid's bottom in the second table's meshes (`n`), 2 wide.
const CELLS: usize = 16;

/// Where the solid's bottom face ends ahead (in x; at y = 0.25, the medium's thickness) in
/// `geo`: the block spans 0 to 2, the pad 1 to 3.
fn leading_corner(geo: &str) -> f64 {
    if geo == "pad.geo" { 3.0 } else { 2.0 }
}

/// The drag of the second table: press the top 0.3 down (pseudo-time 0 to 1), then drag it
/// 1.0 along x (1 to 2), Δt at most 0.025; friction `mu` (none for 0) with slip viscosity
/// `eta`. The probe `corner_x` is the x displacement of the solid's leading bottom corner.
fn drag_text(geo: &str, l: usize, mu: f64, eta: f64) -> String {
    let friction = if mu > 0.0 {
        format!("friction = {{ mu = {mu}, normal = [0, 1], viscosity = {eta:e} }}")
    } else {
        String::new()
    };
    format!(
        r#"mesh = "{}"
[mesh_options]
params = {{ n = {CELLS}, m = {m}, l = {l} }}
[[region]]
group = "solid"
kind = "solid"
K = 20.0
mu = 10.0
[[region]]
group = "medium"
kind = "medium"
gamma = 1e-4
{friction}
[[bc]]
group = "bottom"
ux = 0.0
uy = 0.0
[[bc]]
group = "top"
uy = -0.3
path = [0.0, 1.0, 1.0]
[[bc]]
group = "top"
ux = 1.0
path = [0.0, 0.0, 1.0]
[[probe]]
name = "corner_x"
field = "ux"
at = [{corner}, 0.25]
[steps]
initial = 0.025
max = 0.025
path = [0.0, 1.0, 1.0]
"#,
        root().join("geo").join(geo).display(),
        m = CELLS / 2,
        corner = leading_corner(geo),
    )
}

/// How far each drag gets: the drag reached (1.0 if it completes), F_t / F_n of the top,
/// largest and last, over the drag, and the solid's leading corner's slide then in cells.
fn reach() {
    println!();
    println!(
        "| scene | cells across the medium | μ | η_s | completes | drag reached | leading corner slid (cells) | load steps | Newton its | largest F_t/F_n | last F_t/F_n | wall s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    let runs = [("block.geo", [1, 2, 4, 8].as_slice()), ("pad.geo", &[1, 4])];
    for (geo, layers) in runs {
        for &l in layers {
            let drags = [0.0, 0.1, 0.3, 0.5, 1.0].into_iter().flat_map(|mu| {
                let etas: &[f64] = if mu > 0.0 { &[0.0, 1e-3] } else { &[0.0] };
                etas.iter().map(move |&eta| (mu, eta))
            });
            for (mu, eta) in drags {
                let dir = root().join(format!("target/bench-friction/reach-{geo}-{l}-{mu}-{eta}"));
                let (ok, s) = solve(&dir, &drag_text(geo, l, mu, eta));
                let text = std::fs::read_to_string(dir.join("out/history.csv")).unwrap();
                let mut lines = text.lines();
                let head: Vec<&str> = lines.next().unwrap().split(',').collect();
                let col = |name: &str| head.iter().position(|c| *c == name).unwrap();
                let (t, fx, fy) = (col("time"), col("R_top_x"), col("R_top_y"));
                let ratios: Vec<(f64, f64)> = lines
                    .map(|row| {
                        let v: Vec<f64> = row.split(',').map(|x| x.parse().unwrap()).collect();
                        (v[t] - 1.0, -v[fx] / v[fy])
                    })
                    .filter(|(d, _)| *d > 0.0)
                    .collect();
                let largest = ratios.iter().map(|r| r.1).fold(f64::NAN, f64::max);
                let (reached, last) = ratios.last().copied().unwrap_or((0.0, f64::NAN));
                let cell = 2.0 / CELLS as f64;
                let slid = s["probes"]["corner_x"].as_f64().unwrap_or(f64::NAN) / cell;
                println!(
                    "| {} | {l} | {mu} | {eta} | {} | {reached:.3} | {slid:.2} | {} | {} | {largest:.4} | {last:.4} | {:.1} |",
                    geo.trim_end_matches(".geo"),
                    if ok { "yes" } else { "no" },
                    s["load_steps"],
                    s["newton_iterations"],
                    s["wall_seconds"].as_f64().unwrap_or(f64::NAN),
                );
            }
        }
    }
}

/// The first table: the shipped friction scenes with and without friction.
fn cost() {
    let given = "friction = { mu = 0.3, normal = [0, 1] }";
    let auto = "friction = { mu = 0.3, normal = \"auto\" }";
    // (scene, [(label, case text)]); the first is the frictionless reference
    let mut scenes: Vec<(&str, Vec<(&str, String)>)> =
        ["friction-heating", "discs-ellipse-friction", "sphere-drag"]
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
                // with fixed time steps, the frictionless twin's: none shortened for its Newton
                // iterations
                if shipped.contains("[time]") {
                    let same = shipped.replace("[time]", "[steps]\nmax_iter = 60\n[time]");
                    v.push(("μ = 0.3, the twin's steps", same));
                }
                (name, v)
            })
            .collect();
    // load steps of 1/16 on both, none shortened for its Newton iterations (a step is still
    // cut where Newton fails): the discs' cost at (nearly) the same steps
    let fixed = "\n[steps]\ninitial = 0.0625\nmax = 0.0625\nmax_iter = 60\n";
    let discs = case_text("discs-ellipse-friction");
    scenes.push((
        "discs-ellipse-friction, steps of 1/16",
        vec![
            (
                "no friction",
                discs.replace(&format!("{auto}\n"), "") + fixed,
            ),
            ("μ = 0.3", discs.clone() + fixed),
        ],
    ));
    // runs[scene][variant] = summaries of the rounds
    let mut runs: Vec<Vec<Vec<serde_json::Value>>> = scenes
        .iter()
        .map(|(_, v)| vec![Vec::new(); v.len()])
        .collect();
    for round in 0..ROUNDS {
        for (si, (name, variants)) in scenes.iter().enumerate() {
            for (vi, (_, text)) in variants.iter().enumerate() {
                let folder = format!("{name}-{vi}-{round}").replace([',', ' ', '/'], "_");
                let dir = root().join("target/bench-friction").join(folder);
                let (ok, s) = solve(&dir, text);
                assert!(ok, "{name} variant {vi} failed: {}", s["message"]);
                runs[si][vi].push(s);
            }
        }
    }
    println!(
        "| scene | variant | dofs | strategy | linear solver | load steps | Newton its | friction work | wall s (median of {ROUNDS}) | linear solve s | wall / no friction |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for ((name, variants), rounds) in scenes.iter().zip(&runs) {
        let wall = |r: &[serde_json::Value], key: &str| {
            median(r.iter().map(|s| s[key].as_f64().unwrap()).collect())
        };
        let reference = wall(&rounds[0], "wall_seconds");
        for ((label, _), r) in variants.iter().zip(rounds) {
            let s = &r[0];
            let w = wall(r, "wall_seconds");
            println!(
                "| {name} | {label} | {} | {} | {} | {} | {} | {} | {w:.2} | {:.2} | {:.2} |",
                s["dofs"]["total"],
                s["strategy"].as_str().unwrap_or("-"),
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
