//! `make bench`: the README's cylinder slid along its plate, frictionless (issue 68's item 3
//! and what the remakes cost, item 7).
//!
//! `cases/cylinder-slide.toml` (the rim pressed 0.15 over t ∈ [0, 1], then moved along the
//! plate over t ∈ [1, 2]) on the case's mesh (h = 0.1) and one twice as fine, slid 0.3 (as
//! shipped) and 0.5, its medium Lagrangian (`remake = false`) and made again as the cylinder
//! moves: how far each slides, the normal force over the slide against the press's end, the
//! force ratio F_t/F_n over the slide (time-weighted mean and largest size; exact contact: 0),
//! the remakes and the share of the run's wall time they take (`medium_remade_seconds`).

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
    let history = std::fs::read_to_string(dir.join("out/history.csv")).unwrap();
    let mut lines = history.lines();
    let cols: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = |name: &str| cols.iter().position(|c| *c == name).unwrap();
    let (t, fy, ratio, ux) = (at("time"), at("R_rim_y"), at("Ft_Fn_rim"), at("U_rim_x"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
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
