//! `make bench`: bodies slid along a plate, the medium made again as they move (issue 68).
//!
//! The first table: `cases/cylinder-slide.toml` (the rim pressed 0.15 over t ∈ [0, 1], then
//! moved along the plate over t ∈ [1, 2]) on the case's mesh (h = 0.1) and one twice as fine,
//! slid 0.3 (as shipped) and 0.5, its medium Lagrangian (`remake = false`) and made again as
//! the cylinder moves: how far each slides, the normal force over the slide against the
//! press's end, the force ratio F_t/F_n over the slide (time-weighted mean and largest size;
//! exact contact: 0), the remakes and the share of the run's wall time they take
//! (`medium_remade_seconds`). Issue 68's item 3 and item 7. After each pair, the same slide in
//! exact contact on the same mesh without a medium (`validation/cylinder-exact/`, FEniCSx: the
//! rim a rigid polygon, penalty contact; its mean over its steps), where a faceted cylinder
//! swings too.
//!
//! The second: friction (item 4), each scene as a user draws it, with no special key, the
//! medium made again as the body moves: the pad in a box of `cases/pad-box-slide.toml`
//! (triangles and quadrilaterals, h = 0.1 and 0.05) dragged five pad widths in steps of 0.01, and
//! last at μ = 0.1 on h = 0.1 in steps of 0.002 (a step's slide adds to F_t/F_n) and at μ = 0.3 on
//! triangles in steps of 0.002 (the drawn medium stalls its first steps), and after them
//! dragged one width at μ = 0.3 and 1 on a plate 1000 times stiffer (its face stays flat); the
//! square pad in 3D of `cases/pad-box-slide-3d.toml` (a half pad 1 × 0.5 × 0.5 over a plate,
//! the medium a box of tetrahedra around it, h = 0.2, the pad at 0.2 and at 0.15) dragged its
//! width; the hemisphere of `cases/sphere-drag.toml` dragged three radii; the block as wide as
//! its base (`geo/block.geo`, n = 16 and 32) pressed 0.35 into its 0.25 layer and dragged 0.5.
//! Each row: how far it was dragged of the drag asked, where full slip begins (the first step at
//! 97 % of μ), F_t/F_n from there to the end (mean, range, the steps outside 3 % of μ), the
//! steps, remakes and their share of the wall time.
//!
//! `TMC_BENCH_PART=cylinder` or `friction` runs one table; `TMC_BENCH_ROW=K` with it runs that
//! table's row K alone (from 0, no header), so that rows can run side by side;
//! `TMC_BENCH_REPORT=1` prints the rows of runs already solved, without solving again. The
//! friction table takes about an hour and a half of one core: on the 16-core machine, one
//! thread a row, its rows took 54 minutes in all while the quadrilaterals at h = 0.05 still
//! stopped in their press, and each pad at h = 0.05 took 9–10 minutes
//! (docs/notes/2026-12-04-the-friction-table-on-16-cores.md).

mod common;
use common::{case_text, root, solve};

fn main() {
    let part = std::env::var("TMC_BENCH_PART").ok();
    let only: Option<usize> = std::env::var("TMC_BENCH_ROW")
        .ok()
        .map(|k| k.parse().expect("TMC_BENCH_ROW: a row's number"));
    let runs = |name: &str| part.as_deref().is_none_or(|p| p == name);
    let wanted = |k: usize| only.is_none_or(|o| o == k);
    if runs("cylinder") {
        if only.is_none() {
            println!(
                "\n| h | slide asked | medium | slid | F_n over the slide / pressed | F_t/F_n mean | largest |F_t/F_n| | steps | remakes | wall s | remakes' share |"
            );
            println!("|---|---|---|---|---|---|---|---|---|---|---|");
        }
        let rows = [0.1, 0.05]
            .into_iter()
            .flat_map(|h| [0.3, 0.5].map(|slide| (h, slide)))
            .flat_map(|(h, slide)| [0, 1, 2].map(|medium| (h, slide, medium)));
        for (k, (h, slide, medium)) in rows.enumerate() {
            match (wanted(k), medium) {
                (false, _) => {}
                (true, 2) => exact_row(h, slide),
                (true, _) => row(h, slide, medium == 1),
            }
        }
    }
    if runs("friction") {
        if only.is_none() {
            println!(
                "\n| scene | mesh | μ | dragged / asked | full slip from | F_t/F_n mean | range | outside 3 % of μ | steps | remakes | wall s | remakes' share |"
            );
            println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
        }
        for (k, scene) in friction_scenes().into_iter().enumerate() {
            if wanted(k) {
                scene.run();
            }
        }
    }
}

/// The friction table's scenes, in its order.
fn friction_scenes() -> Vec<Scene> {
    let mut all = Vec::new();
    for quads in [false, true] {
        for h in [0.1, 0.05] {
            for mu in [0.1, 0.3, 0.5, 1.0] {
                all.push(Scene::Pad {
                    quads,
                    h,
                    mu,
                    step: 0.01,
                });
            }
        }
    }
    for (hp, mu) in [
        (0.2, 0.3),
        (0.15, 0.1),
        (0.15, 0.3),
        (0.15, 0.5),
        (0.15, 1.0),
    ] {
        all.push(Scene::Pad3d { hp, mu });
    }
    for (h, mu) in [(0.25, 0.3), (0.15, 0.3)] {
        all.push(Scene::Sphere { h, mu });
    }
    for n in [16, 32] {
        for mu in [0.3, 0.5] {
            all.push(Scene::Block { n, mu });
        }
    }
    // last, so that the rows above keep their numbers: at μ = 0.1 the excess over μ grows with
    // the slide per step (docs/notes/2026-12-07-a-face-that-runs-onto-the-medium-and-the-2d-pad-s-drag.md)
    for quads in [false, true] {
        all.push(Scene::Pad {
            quads,
            h: 0.1,
            mu: 0.1,
            step: 0.002,
        });
    }
    // the drawn medium's closed layer, several cells across, stalls the drag's first steps: the
    // medium made again where the run would stop carries it on
    // (docs/notes/2026-12-07-a-medium-made-again-before-a-run-stops.md)
    all.push(Scene::Pad {
        quads: false,
        h: 0.1,
        mu: 0.3,
        step: 0.002,
    });
    // a plate whose face stays flat, where a contact that slides everywhere meets μ exactly: at
    // μ = 1 the pad's leading part sticks and its face rolls onto it
    // (docs/notes/2026-12-07-a-remake-s-fixed-costs-and-the-pad-at-mu-1-on-a-stiff-plate.md)
    for mu in [0.3, 1.0] {
        all.push(Scene::StiffPlate { mu });
    }
    all
}

/// One row of the friction table.
enum Scene {
    /// `cases/pad-box-slide.toml` dragged five pad widths in steps of `step`.
    Pad {
        quads: bool,
        h: f64,
        mu: f64,
        step: f64,
    },
    /// The square pad in 3D, meshed at `hp`, dragged its width.
    Pad3d { hp: f64, mu: f64 },
    /// `cases/sphere-drag.toml` on a plate reaching x = 2.2, dragged three radii.
    Sphere { h: f64, mu: f64 },
    /// The block as wide as its base, n cells along it.
    Block { n: usize, mu: f64 },
    /// `cases/pad-box-slide.toml` on a plate 1000 times stiffer than the pad, dragged one
    /// width in steps of 0.005.
    StiffPlate { mu: f64 },
}

impl Scene {
    fn run(&self) {
        match *self {
            Scene::Pad { quads, h, mu, step } => {
                let text = edit(
                    &case_text("pad-box-slide"),
                    &[
                        (
                            "params = { h = 0.1 }",
                            &format!("params = {{ h = {h}, quads = {} }}", quads as u8),
                        ),
                        ("mu = 0.3, normal", &format!("mu = {mu}, normal")),
                        ("ux = 1.0\n", "ux = 5.0\n"),
                        (
                            "initial = 0.05\nmax = 0.05",
                            &format!("initial = {step}\nmax = {step}"),
                        ),
                    ],
                ) + ENDS;
                let cells = if quads { "quadrilaterals" } else { "triangles" };
                let (dir, mesh) = if step == 0.01 {
                    (format!("pad-{cells}-{h}-{mu}"), format!("{cells}, h = {h}"))
                } else {
                    (
                        format!("pad-{cells}-{h}-{mu}-{step}"),
                        format!("{cells}, h = {h}, steps of {step}"),
                    )
                };
                friction_row("pad in a box", &mesh, mu, 5.0, &dir, &text, ("top", "y"));
            }
            Scene::Pad3d { hp, mu } => {
                let text = edit(
                    &case_text("pad-box-slide-3d"),
                    &[
                        ("hp = 0.15 }", &format!("hp = {hp} }}")),
                        (
                            "remake = true\n",
                            &format!(
                                "remake = true\nfriction = {{ mu = {mu}, normal = \"auto\" }}\n"
                            ),
                        ),
                    ],
                ) + ENDS;
                let dir = format!("pad-3d-{hp}-{mu}");
                friction_row(
                    "square pad, 3D",
                    &format!("the pad at {hp}"),
                    mu,
                    1.0,
                    &dir,
                    &text,
                    ("top", "z"),
                );
            }
            Scene::Sphere { h, mu } => {
                let text = edit(
                    &case_text("sphere-drag"),
                    &[
                        (
                            "params = { h = 0.15 }",
                            &format!("params = {{ h = {h}, x1 = 2.2 }}"),
                        ),
                        (
                            "friction = { mu = 0.3,",
                            &format!("remake = true\nfriction = {{ mu = {mu},"),
                        ),
                        ("ux = 0.4\n", "ux = 1.2\n"),
                    ],
                ) + ENDS;
                let dir = format!("sphere-{h}-{mu}");
                friction_row(
                    "hemisphere, 3D",
                    &format!("h = {h}"),
                    mu,
                    1.2,
                    &dir,
                    &text,
                    ("slider_top", "z"),
                );
            }
            Scene::StiffPlate { mu } => {
                let text = edit(
                    &case_text("pad-box-slide"),
                    &[
                        (
                            "group = \"plate\"\nkind = \"solid\"\nK = 20.0\nmu = 10.0",
                            "group = \"plate\"\nkind = \"solid\"\nK = 20000.0\nmu = 10000.0",
                        ),
                        ("mu = 0.3, normal", &format!("mu = {mu}, normal")),
                        ("initial = 0.05\nmax = 0.05", "initial = 0.005\nmax = 0.005"),
                    ],
                ) + ENDS;
                let dir = format!("pad-stiff-plate-{mu}");
                let mesh = "triangles, h = 0.1, steps of 0.005, the plate 1000 times stiffer";
                friction_row("pad in a box", mesh, mu, 1.0, &dir, &text, ("top", "y"));
            }
            Scene::Block { n, mu } => {
                let geo = root().join("geo/block.geo");
                let text = format!(
                    "mesh = \"{}\"\n\n[mesh_options]\nparams = {{ n = {n}, m = {}, l = {} }}\n{}",
                    geo.display(),
                    n / 2,
                    n / 4,
                    BLOCK.replace("MU", &mu.to_string())
                );
                let dir = format!("block-{n}-{mu}");
                friction_row(
                    "block as wide as its base",
                    &format!("n = {n}"),
                    mu,
                    0.5,
                    &dir,
                    &text,
                    ("top", "y"),
                );
            }
        }
    }
}

/// `text` with each `(from, to)` replaced, each `from` found once.
fn edit(text: &str, changes: &[(&str, &str)]) -> String {
    let mut text = text.to_string();
    for (from, to) in changes {
        assert_eq!(text.matches(from).count(), 1, "{from}");
        text = text.replace(from, to);
    }
    text
}

/// The ends only in `[output]`: no step between is read.
const ENDS: &str = "\n[output]\nevery = 1000000\n";

/// The block of the friction table, as `tests/it/friction.rs` drags it, its medium made again.
const BLOCK: &str = r#"
[[region]]
group = "solid"
kind = "solid"
K = 20.0
mu = 10.0

[[region]]
group = "medium"
kind = "medium"
gamma = 1e-4
beta1 = 1.0
beta2 = 1e-2
remake = true
friction = { mu = MU, normal = "auto" }

[[bc]]
group = "bottom"
ux = 0.0
uy = 0.0

[[bc]]
group = "top"
uy = -0.35
path = [0.0, 1.0, 1.0]

[[bc]]
group = "top"
ux = 0.5
path = [0.0, 0.0, 1.0]

[steps]
path = [0.0, 1.0, 1.0]
initial = 0.025
max = 0.025

[output]
every = 1000000
"#;

/// Solve `text` in `target/bench-sliding/dir` and print its row: the driven `group`'s force
/// along x against its force along the plate's normal (`axis`), from the first step of the drag
/// (t > 1) at 97 % of `mu` to the end; `asked` the drag asked.
fn friction_row(
    scene: &str,
    mesh: &str,
    mu: f64,
    asked: f64,
    dir: &str,
    text: &str,
    (group, axis): (&str, &str),
) {
    let dir = root().join("target/bench-sliding").join(dir);
    let s = solved(&dir, text);
    let (at, rows) = history(&dir);
    let (t, fx, fnormal, ux) = (
        at("time"),
        at(&format!("R_{group}_x")),
        at(&format!("R_{group}_{axis}")),
        at(&format!("U_{group}_x")),
    );
    let drag: Vec<(f64, f64)> = (rows.iter())
        .filter(|r| r[t] > 1.0)
        .map(|r| (r[ux], r[fx] / -r[fnormal]))
        .collect();
    let dragged = drag.last().map_or(0.0, |d| d.0);
    let slip: Vec<(f64, f64)> = (drag.iter().copied())
        .skip_while(|d| d.1 < 0.97 * mu)
        .collect();
    let from = slip
        .first()
        .map_or("—".to_string(), |d| format!("{:.3}", d.0));
    let ratios: Vec<f64> = slip.iter().map(|d| d.1).collect();
    let n = ratios.len().max(1) as f64;
    let mean = ratios.iter().sum::<f64>() / n;
    let (lo, hi) = (ratios.iter()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &r| {
        (a.min(r), b.max(r))
    });
    let outside = (ratios.iter())
        .filter(|r| (*r - mu).abs() > 0.03 * mu)
        .count();
    let wall = s["wall_seconds"].as_f64().unwrap();
    let remade = s["medium_remade_seconds"].as_f64().unwrap_or(0.0);
    println!(
        "| {scene} | {mesh} | {mu} | {dragged:.3} / {asked} | {from} | {mean:.4} | {lo:.4}–{hi:.4} | {outside} of {} | {} | {} | {wall:.1} | {:.2} |",
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
    let s = solved(&dir, &text);
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

/// The same slide in exact contact (`validation/cylinder-exact/cylinder.py`, FEniCSx, no
/// medium) on the mesh of the row before, in steps of 0.0025 (200 steps over 0.3 on h = 0.1
/// met a snap Newton could not take at 0.019): its F_t/F_n in tmc's sign (the rim's
/// reaction), its mean over the steps.
fn exact_row(h: f64, slide: f64) {
    let msh = root().join(format!(
        "target/bench-sliding/{h}-{slide}-made again/out/mesh.msh"
    ));
    let head = format!("| {h} | {slide} | none: exact contact |");
    if !msh.exists() {
        println!("{head} (needs the row before, solved: {}) |", msh.display());
        return;
    }
    let since = std::time::Instant::now();
    let o = std::process::Command::new("/usr/bin/python3")
        .arg(root().join("validation/cylinder-exact/cylinder.py"))
        .arg(&msh)
        .args(["--slide", &slide.to_string()])
        .args(["--steps", &((slide / 0.0025).round() as usize).to_string()])
        .output();
    let text = match &o {
        Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout).into_owned(),
        _ => {
            println!("{head} (not run: /usr/bin/python3 with python3-dolfinx, `make deps`) |");
            return;
        }
    };
    let wall = since.elapsed().as_secs_f64();
    let pressed: f64 = (text.lines())
        .find_map(|l| l.strip_prefix("# pressed 0.15: F_n "))
        .and_then(|v| v.parse().ok())
        .unwrap_or(f64::NAN);
    let rows: Vec<Vec<f64>> = (text.lines())
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            l.split_whitespace()
                .filter_map(|v| v.parse().ok())
                .collect()
        })
        .filter(|r: &Vec<f64>| r.len() == 4)
        .collect();
    let (mut lo, mut hi, mut most, mut mean) = (f64::INFINITY, 0f64, 0f64, 0.0);
    for r in &rows {
        (lo, hi) = (lo.min(r[2] / pressed), hi.max(r[2] / pressed));
        most = most.max(r[3].abs());
        mean -= r[3] / rows.len() as f64;
    }
    let slid = rows.last().map_or(0.0, |r| r[0]);
    println!(
        "{head} {slid:.3} | {lo:.3}–{hi:.3} of {pressed:.3} | {mean:+.3} | {most:.3} | {} | — | {wall:.2} | — |",
        rows.len()
    );
}

/// `text` solved afresh into `dir/out`, its `summary.json`; with `TMC_BENCH_REPORT` set, the
/// run already there read again (one stopped part-way, by `timeout`, is reported as far as it
/// went).
fn solved(dir: &std::path::Path, text: &str) -> serde_json::Value {
    if std::env::var_os("TMC_BENCH_REPORT").is_some() {
        let summary = std::fs::read_to_string(dir.join("out/summary.json")).unwrap();
        return serde_json::from_str(&summary).unwrap();
    }
    let _ = std::fs::remove_dir_all(dir);
    solve(dir, text).1
}

/// The history of the run solved into `dir/out`: a column's index by its name, and the rows.
fn history(dir: &std::path::Path) -> (impl Fn(&str) -> usize, Vec<Vec<f64>>) {
    let h = tmc::plot::History::read(&dir.join("out/history.csv")).unwrap();
    let columns = h.columns;
    let at = move |name: &str| columns.iter().position(|c| c == name).unwrap();
    (at, h.rows)
}
