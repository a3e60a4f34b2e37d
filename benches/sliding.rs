//! `make bench`: the README's cylinder slid along its plate, frictionless (issue 68's item 3
//! and what the remakes cost, item 7).
//!
//! `cases/cylinder-slide.toml` (the rim pressed 0.15 over t ∈ [0, 1], then moved along the
//! plate over t ∈ [1, 2]) on the case's mesh (h = 0.1) and one twice as fine, slid 0.3 (as
//! shipped) and 0.5, its medium Lagrangian (`remake = false`) and made again as the cylinder
//! moves: how far each slides, the normal force over the slide against the press's end, the
//! force ratio F_t/F_n over the slide (time-weighted mean and largest size; exact contact: 0),
//! the remakes and the share of the run's wall time they take (`medium_remade_seconds`).
//!
//! Then the square pad in 3D (`geo/pad-box-3d.geo`: a half pad 1 × 0.5 × 0.5 over a plate, the
//! medium a box of tetrahedra around it, h = 0.2, the pad at 0.2 and at 0.15) pressed 0.12
//! and dragged its width with friction, the medium made again as it moves (issue 68's item 4):
//! how far it slides, F_t/F_n from a drag of 0.05 on (mean, range, the steps outside 3 % of
//! μ), the steps, remakes and their share.

mod common;
use common::{case_text, root, solve};

fn main() {
    println!(
        "\n| h | slide asked | medium | slid | F_n over the slide / pressed | F_t/F_n mean | largest |F_t/F_n| | steps | remakes | wall s | remakes' share |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for h in [0.1, 0.05] {
        for slide in [0.3, 0.5] {
            for remake in [false, true] {
                row(h, slide, remake);
            }
        }
    }
    println!(
        "\n| 3D pad, h = 0.2 | μ | dragged | F_t/F_n mean | range | outside 3 % of μ | steps | remakes | wall s | remakes' share |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for (hp, mu) in [(0.2, 0.3), (0.15, 0.1), (0.15, 0.3), (0.15, 1.0)] {
        pad_row(hp, mu);
    }
}

/// The 3D pad of the second table: a half pad on the plane of symmetry y = 0, pressed over
/// t ∈ [0, 1] and dragged its width over t ∈ [1, 2].
const PAD_3D: &str = r#"
[[region]]
group = "plate"
kind = "solid"
K = 20.0
mu = 10.0

[[region]]
group = "pad"
kind = "solid"
K = 20.0
mu = 10.0

[[region]]
group = "medium"
kind = "medium"
gamma = 1e-4
remake = true
friction = { mu = MU, normal = "auto" }

[[bc]]
group = "bottom"
ux = 0.0
uy = 0.0
uz = 0.0

[[bc]]
group = "y0"
uy = 0.0

[[bc]]
group = "top"
uz = -0.12
path = [0.0, 1.0, 1.0]

[[bc]]
group = "top"
ux = 1.0
path = [0.0, 0.0, 1.0]

[steps]
path = [0.0, 1.0, 1.0]
initial = 0.05
max = 0.05

[output]
every = 1000000
"#;

/// One run of the 3D pad's table: the pad meshed at `hp`, friction coefficient `mu`.
fn pad_row(hp: f64, mu: f64) {
    let geo = root().join("geo/pad-box-3d.geo");
    let text = format!(
        "mesh = \"{}\"\n\n[mesh_options]\nparams = {{ h = 0.2, hp = {hp} }}\n{}",
        geo.display(),
        PAD_3D.replace("MU", &mu.to_string())
    );
    let dir = root().join(format!("target/bench-sliding/pad-3d-{hp}-{mu}"));
    let _ = std::fs::remove_dir_all(&dir);
    let (_, s) = solve(&dir, &text);
    let (at, rows) = history(&dir);
    let (t, fx, fz, ux) = (at("time"), at("R_top_x"), at("R_top_z"), at("U_top_x"));
    let dragged = rows
        .last()
        .map_or(0.0, |r| if r[t] > 1.0 { r[ux] } else { 0.0 });
    let ratios: Vec<f64> = (rows.iter())
        .filter(|r| r[t] > 1.0 && r[ux] >= 0.05)
        .map(|r| r[fx] / -r[fz])
        .collect();
    let n = ratios.len().max(1) as f64;
    let mean = ratios.iter().sum::<f64>() / n;
    let (lo, hi) = (ratios.iter()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &r| {
        (a.min(r), b.max(r))
    });
    let outside = ratios
        .iter()
        .filter(|r| (*r - mu).abs() > 0.03 * mu)
        .count();
    let wall = s["wall_seconds"].as_f64().unwrap();
    let remade = s["medium_remade_seconds"].as_f64().unwrap_or(0.0);
    println!(
        "| pad at {hp} | {mu} | {dragged:.3} | {mean:.4} | {lo:.4}–{hi:.4} | {outside} of {} | {} | {} | {wall:.1} | {:.2} |",
        ratios.len(),
        s["load_steps"],
        s["medium_remade"],
        remade / wall,
    );
}

/// One run of the table.
fn row(h: f64, slide: f64, remake: bool) {
    let text = case_text("cylinder-slide");
    assert!(
        text.contains("ux = 0.3\n")
            && text.contains("h = 0.1 }")
            && text.contains("remake = true\n")
    );
    let text = text
        .replace("ux = 0.3\n", &format!("ux = {slide}\n"))
        .replace("h = 0.1 }", &format!("h = {h} }}"))
        .replace("remake = true\n", &format!("remake = {remake}\n"));
    let medium = if remake { "made again" } else { "Lagrangian" };
    let dir = root().join(format!("target/bench-sliding/{h}-{slide}-{medium}"));
    let _ = std::fs::remove_dir_all(&dir);
    let (_, s) = solve(&dir, &text);
    let (at, rows) = history(&dir);
    let (t, fy, ratio, ux) = (at("time"), at("R_rim_y"), at("Ft_Fn_rim"), at("U_rim_x"));
    let pressed = rows.iter().rfind(|r| r[t] <= 1.0 + 1e-12).unwrap()[fy].abs();
    let sliding: Vec<&Vec<f64>> = rows.iter().filter(|r| r[t] > 1.0 + 1e-12).collect();
    let slid = sliding.last().map_or(0.0, |r| r[ux]);
    let (mut lo, mut hi, mut most, mut mean) = (f64::INFINITY, 0f64, 0f64, 0.0);
    let mut before = 1.0;
    for r in &sliding {
        let f = r[fy].abs() / pressed;
        (lo, hi) = (lo.min(f), hi.max(f));
        most = most.max(r[ratio].abs());
        mean += r[ratio] * (r[t] - before);
        before = r[t];
    }
    let mean = mean / (before - 1.0).max(f64::MIN_POSITIVE);
    let wall = s["wall_seconds"].as_f64().unwrap();
    let remade = s["medium_remade_seconds"].as_f64();
    println!(
        "| {h} | {slide} | {medium} | {slid:.3} | {lo:.3}–{hi:.3} of {pressed:.3} | {mean:+.3} | {most:.3} | {} | {} | {wall:.2} | {} |",
        s["load_steps"],
        s["medium_remade"],
        remade.map_or("—".into(), |r| format!("{:.2}", r / wall)),
    );
}

/// The history of the run solved into `dir/out`: a column's index by its name, and the rows.
fn history(dir: &std::path::Path) -> (impl Fn(&str) -> usize, Vec<Vec<f64>>) {
    let h = tmc::plot::History::read(&dir.join("out/history.csv")).unwrap();
    let columns = h.columns;
    let at = move |name: &str| columns.iter().position(|c| c == name).unwrap();
    (at, h.rows)
}
