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
//! η_s = 1e-3, and with a mass density ρ = 1e-4 on every region (inertia).
//!
//! Third table: issue 36's drags with inertia, on n = 16 and 32, Q1 and T1, at μ = 0.1 to 1:
//! how far each gets and its force ratio along the way.
//!
//! Fourth table: the pad with one cell across on a plate running 3 beyond it, its layer
//! joined again as it slides (`friction.reconnect`), dragged 2.0 with ρ = 1e-4 at μ = 0 to 1 on
//! n = 16 and 32 (and 64 with `TMC_BENCH_FINE=1`), quadrilaterals (Q1) and triangles (T1, the
//! layer zipped node by node): how far each gets, and its force ratio from a drag of 0.25 to
//! the end (range and mean).
//!
//! Fifth table: issue 36's block with one cell across the medium (docs/THEORY.md, "The block
//! with one cell across"), ρ = 1e-4, pressed 0.35 and dragged 0.5, at μ = 0.1 to 1: T1 (each
//! cell's diagonal the same way, and alternating) and Q1 on n = 16, 32 and 64, and the 3D block
//! (`geo/block3d.geo`, nb = n/4) on n = 8 and 16 in hexahedra (H1) and tetrahedra (T4,
//! `tet = 1`). Whether each completes, F_t/F_n from a drag of 0.3 to the end (least and
//! greatest, against μ), at the end, and how far the middle of the block's bottom slid (x = 1;
//! in 3D at mid-depth).
//!
//! Sixth table: the same one-cell block pressed lightly
//! (docs/notes/2026-11-29-friction-measurements.md, "The press decides"):
//! 0.27 (the medium's 0.25 closed and the block squeezed 2 %, where 0.35 squeezes it 10 % and
//! pitches its leading end onto the base's corner) and 0.25 (the block hardly squeezed), with
//! the medium's γ = 1e-4 and, at 0.25, 1e-5, the last also with `friction.forget_slip` (the
//! medium's law at F (I − gₙ⊗N): no drag of its own); T1 and Q1 on n = 16, 32, 64, H1 and T4
//! on n = 8, 16, at μ = 0 to 1: F_t/F_n from a drag of 0.3 (least and greatest, against μ),
//! and the same net of the medium's own drag, (F_t − F_t at μ = 0)/F_n, the frictionless
//! run's F_t taken at the same drag; the normal force at the end, and how far the middle of
//! the block's bottom slid.
//!
//! `TMC_BENCH_PART=cost`, `reach`, `slide`, `rejoined`, `one-cell` or `one-cell-light` runs one
//! table.

mod common;
use common::{case_text, root, solve};

const ROUNDS: usize = 3;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let part = std::env::var("TMC_BENCH_PART");
    if part.is_err() || part.as_deref() == Ok("cost") {
        cost();
    }
    if part.is_err() || part.as_deref() == Ok("reach") {
        reach();
    }
    if part.is_err() || part.as_deref() == Ok("slide") {
        slide();
    }
    if part.is_err() || part.as_deref() == Ok("rejoined") {
        rejoined();
    }
    if part.is_err() || part.as_deref() == Ok("one-cell") {
        one_cell();
    }
    if part.is_err() || part.as_deref() == Ok("one-cell-light") {
        one_cell_light();
    }
}

/// The fifth table: the block with one cell across (see the module's words).
fn one_cell() {
    println!();
    println!(
        "| cells | n | μ | completes | F_t/F_n from 0.3: least…greatest | against μ | at the end | bottom's middle slid | load steps | Newton its | wall s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let mut runs = Vec::new();
    for cells in ["T1", "T1 alternate", "Q1"] {
        for n in [16, 32, 64] {
            for mu in [0.1, 0.3, 0.5, 1.0] {
                runs.push((cells, n, mu));
            }
        }
    }
    for cells in ["H1", "T4"] {
        for n in [8, 16] {
            for mu in [0.1, 0.3, 0.5, 1.0] {
                runs.push((cells, n, mu));
            }
        }
    }
    for (cells, n, mu) in runs {
        let dir = root()
            .join("target/bench-friction")
            .join(format!("one-cell-{cells}-{n}-{mu}"));
        let (ok, s) = solve(&dir, &one_cell_text(cells, n, mu, 0.35, 1e-4, false));
        let ratios = drag_ratios(&dir, 0.5, vertical(cells));
        let late: Vec<f64> = (ratios.iter())
            .filter(|r| r.0 >= 0.3 - 1e-9)
            .map(|r| r.1)
            .collect();
        let (least, greatest) = least_greatest(late);
        let end = ratios.last().map_or(f64::NAN, |r| r.1);
        println!(
            "| {cells} | {n} | {mu} | {} | {least:.4}…{greatest:.4} | {:+.1}…{:+.1} % | {end:.4} | {:.5} | {} | {} | {:.1} |",
            completes(ok, ratios.last().map_or(0.0, |r| r.0)),
            (least / mu - 1.0) * 100.0,
            (greatest / mu - 1.0) * 100.0,
            s["probes"]["middle_x"].as_f64().unwrap_or(f64::NAN),
            s["load_steps"],
            s["newton_iterations"],
            s["wall_seconds"].as_f64().unwrap_or(f64::NAN),
        );
    }
}

/// The least and the greatest of `values` (NaN for none).
fn least_greatest(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    (values.into_iter()).fold((f64::NAN, f64::NAN), |(a, b), r| (a.min(r), b.max(r)))
}

/// A table's "completes" cell: yes, or how far the drag got.
fn completes(ok: bool, reached: f64) -> String {
    if ok {
        "yes".to_string()
    } else {
        format!("no: {reached:.3}")
    }
}

/// Whether [`one_cell`]'s `cells` are those of the 3D block.
fn in_3d(cells: &str) -> bool {
    matches!(cells, "H1" | "T4")
}

/// The history column of the top's normal reaction on the block of `cells`.
fn vertical(cells: &str) -> &'static str {
    if in_3d(cells) { "R_top_z" } else { "R_top_y" }
}

/// The case of [`one_cell`]: `cells` "T1", "T1 alternate" (diagonals alternating, `tri = 2`),
/// "Q1" (`geo/block.geo`), "H1" or "T4" (`geo/block3d.geo`, nb = n/4, tetrahedra for T4), n
/// cells along the block, friction μ, every region ρ = 1e-4,
/// the medium's stiffness `gamma`, pressed `press` (pseudo-time 0 to 1) and dragged 0.5 (1 to
/// 2), Δt at most 0.025; the probe `middle_x` at the middle of the block's bottom.
fn one_cell_text(cells: &str, n: usize, mu: f64, press: f64, gamma: f64, forget: bool) -> String {
    let three = in_3d(cells);
    let geo = root()
        .join("geo")
        .join(if three { "block3d.geo" } else { "block.geo" });
    let (params, normal, held, down, middle) = if three {
        (
            format!(
                "n = {n}, nb = {}, m = {}, l = 1, tet = {}",
                n / 4,
                n / 2,
                u8::from(cells == "T4")
            ),
            "[0, 0, 1]",
            "ux = 0.0\nuy = 0.0\nuz = 0.0",
            "uy = 0.0\nuz",
            "[1.0, 0.5, 0.25]",
        )
    } else {
        (
            format!(
                "n = {n}, m = {}, l = 1, tri = {}",
                n / 2,
                match cells {
                    "T1" => 1,
                    "T1 alternate" => 2,
                    _ => 0,
                }
            ),
            "[0, 1]",
            "ux = 0.0\nuy = 0.0",
            "uy",
            "[1.0, 0.25]",
        )
    };
    format!(
        r#"mesh = "{}"
[mesh_options]
params = {{ {params} }}
[[region]]
group = "solid"
kind = "solid"
K = 20.0
mu = 10.0
rho = 1e-4
[[region]]
group = "medium"
kind = "medium"
gamma = {gamma:e}
friction = {{ mu = {mu}, normal = {normal}{forget} }}
rho = 1e-4
[[bc]]
group = "bottom"
{held}
{loads}"#,
        geo.display(),
        loads = press_then_drag(down, press, 0.5, "middle_x", middle),
        forget = if forget { ", forget_slip = true" } else { "" },
    )
}

/// The loads of a drag case: the group "top" pressed `press` along `down` (its last line's key;
/// earlier lines hold other components), pseudo-time 0 to 1, then dragged `amount` along x,
/// 1 to 2, with Δt at most 0.025; and the probe `probe` of ux at `at`.
fn press_then_drag(down: &str, press: f64, amount: f64, probe: &str, at: &str) -> String {
    format!(
        r#"[[bc]]
group = "top"
{down} = -{press}
path = [0.0, 1.0, 1.0]
[[bc]]
group = "top"
ux = {amount}
path = [0.0, 0.0, 1.0]
[[probe]]
name = "{probe}"
field = "ux"
at = {at}
[steps]
initial = 0.025
max = 0.025
path = [0.0, 1.0, 1.0]
"#
    )
}

/// The forces on the top at each accepted step of a drag of `amount` (pseudo-time 1 to 2)
/// solved in `dir`: (drag, F_t, F_n), F_n its reaction `vertical`, both signed so that
/// F_t/F_n is the force ratio.
fn drag_forces(dir: &std::path::Path, amount: f64, vertical: &str) -> Vec<(f64, f64, f64)> {
    let h = tmc::plot::History::read(&dir.join("out/history.csv")).unwrap();
    let col = |name: &str| h.columns.iter().position(|c| c == name).unwrap();
    let (t, fx, fy) = (col("time"), col("R_top_x"), col(vertical));
    (h.rows.iter())
        .map(|v| (amount * (v[t] - 1.0), -v[fx], v[fy]))
        .filter(|(d, _, _)| *d > 0.0)
        .collect()
}

/// The force ratio F_t/F_n of the top at each accepted step of a drag (see [`drag_forces`]):
/// (drag, ratio).
fn drag_ratios(dir: &std::path::Path, amount: f64, vertical: &str) -> Vec<(f64, f64)> {
    (drag_forces(dir, amount, vertical).into_iter())
        .map(|(d, t, n)| (d, t / n))
        .collect()
}

/// The sixth table: the one-cell block pressed lightly, its ratio also net of the medium's own
/// drag (see the module's words).
fn one_cell_light() {
    println!();
    println!(
        "| press | γ | cells | n | μ | completes | F_t/F_n from 0.3 against μ | net of the medium's drag | F_t/F_n at μ = 0, end | F_n at the end | bottom's middle slid | load steps | Newton its |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut runs: Vec<(&str, usize)> = Vec::new();
    for cells in ["T1", "Q1"] {
        runs.extend([16, 32, 64].map(|n| (cells, n)));
    }
    for cells in ["H1", "T4"] {
        runs.extend([8, 16].map(|n| (cells, n)));
    }
    let settings = [
        (0.27, 1e-4, false),
        (0.25, 1e-4, false),
        (0.25, 1e-5, false),
        (0.25, 1e-5, true),
    ];
    for (press, gamma, forget) in settings {
        for &(cells, n) in &runs {
            one_cell_light_rows(press, gamma, forget, cells, n);
        }
    }
}

/// The sixth table's rows of one mesh: μ = 0.1 to 1, each net of the μ = 0 run's F_t.
fn one_cell_light_rows(press: f64, gamma: f64, forget: bool, cells: &str, n: usize) {
    let stiffness = match gamma == 1e-4 {
        true => String::new(),
        false => format!("-gamma{gamma:e}"),
    };
    let (stiffness, medium) = match forget {
        true => (
            format!("{stiffness}-forget"),
            format!("{gamma:e}, slip forgotten"),
        ),
        false => (stiffness, format!("{gamma:e}")),
    };
    let run = |mu: f64| {
        let dir = root()
            .join("target/bench-friction")
            .join(format!("one-cell-{press}{stiffness}-{cells}-{n}-{mu}"));
        let (ok, s) = solve(&dir, &one_cell_text(cells, n, mu, press, gamma, forget));
        (ok, s, drag_forces(&dir, 0.5, vertical(cells)))
    };
    let (_, _, free) = run(0.0);
    // the frictionless run's F_t at drag d, linear between its steps
    let free_t = |d: f64| {
        let i = free.partition_point(|f| f.0 < d).clamp(1, free.len() - 1);
        let (a, b) = (free[i - 1], free[i]);
        a.1 + (b.1 - a.1) * ((d - a.0) / (b.0 - a.0)).clamp(0.0, 1.0)
    };
    let drag_share = free.last().map_or(f64::NAN, |f| f.1 / f.2);
    for mu in [0.1, 0.3, 0.5, 1.0] {
        let (ok, s, forces) = run(mu);
        let late = forces.iter().filter(|f| f.0 >= 0.3 - 1e-9);
        let spread = |v: Vec<f64>| {
            let (a, b) = least_greatest(v);
            format!(
                "{:+.1}…{:+.1} %",
                (a / mu - 1.0) * 100.0,
                (b / mu - 1.0) * 100.0
            )
        };
        let raw = spread(late.clone().map(|f| f.1 / f.2).collect());
        let net = spread(late.map(|f| (f.1 - free_t(f.0)) / f.2).collect());
        println!(
            "| {press} | {medium} | {cells} | {n} | {mu} | {} | {raw} | {net} | {drag_share:.4} | {:.3} | {:.5} | {} | {} |",
            completes(ok, forces.last().map_or(0.0, |f| f.0)),
            forces.last().map_or(f64::NAN, |f| f.2.abs()),
            s["probes"]["middle_x"].as_f64().unwrap_or(f64::NAN),
            s["load_steps"],
            s["newton_iterations"],
        );
    }
}

/// The fourth table: the reconnected pad (see the module's words).
fn rejoined() {
    println!();
    println!(
        "| cells | μ | completes | drag reached | load steps | Newton its | F_t/F_n from 0.25 to the end | its mean | at the end | wall s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut sizes = vec![16, 32];
    if std::env::var("TMC_BENCH_FINE").is_ok() {
        sizes.push(64);
    }
    for (n, tri) in sizes.into_iter().flat_map(|n| [(n, false), (n, true)]) {
        for mu in [0.0, 0.1, 0.3, 0.5, 1.0] {
            let d = Drag {
                geo: "pad.geo",
                n,
                l: 1,
                tri,
                mu,
                eta: 0.0,
                rho: 1e-4,
                press: 0.3,
                amount: 2.0,
                reconnect: true,
            };
            let (ok, reached, ratios, s) = d.run(&format!("rejoined-{n}-{tri}-{mu}"));
            let slid: Vec<f64> = (ratios.iter().filter(|r| r.0 >= 0.25))
                .map(|r| r.1)
                .collect();
            let range = match slid.is_empty() {
                true => "–".to_string(),
                false => format!(
                    "{:.4} … {:.4}",
                    slid.iter().copied().fold(f64::INFINITY, f64::min),
                    slid.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                ),
            };
            let mean = slid.iter().sum::<f64>() / slid.len() as f64;
            println!(
                "| {} n = {n} | {mu} | {} | {reached:.3} | {} | {} | {range} | {mean:.4} | {:.4} | {:.1} |",
                if tri { "T1" } else { "Q1" },
                if ok { "yes" } else { "no" },
                s["load_steps"],
                s["newton_iterations"],
                ratios.last().map_or(f64::NAN, |r| r.1),
                s["wall_seconds"].as_f64().unwrap_or(f64::NAN),
            );
        }
    }
}

/// Cells across the solid's bottom in the second table's meshes (`n`), 2 wide.
const CELLS: usize = 16;

/// Where the solid's bottom face ends ahead (in x; at y = 0.25, the medium's thickness) in
/// `geo`: the block spans 0 to 2, the pad 1 to 3.
fn leading_corner(geo: &str) -> f64 {
    if geo == "pad.geo" { 3.0 } else { 2.0 }
}

/// A drag: the top of `geo` (n cells along, `l` across the medium, triangles if `tri`)
/// pressed `press` down (pseudo-time 0 to 1), then dragged `amount` along x (1 to 2), Δt at
/// most 0.025; friction `mu` (none for 0) with slip viscosity `eta`, every region with mass
/// density `rho` (none for 0). The probe `corner_x` is the x displacement of the solid's
/// leading bottom corner.
#[derive(Clone, Copy)]
struct Drag {
    geo: &'static str,
    n: usize,
    l: usize,
    tri: bool,
    mu: f64,
    eta: f64,
    rho: f64,
    press: f64,
    amount: f64,
    /// The layer joined again as it slides (`friction.reconnect`), on a plate running 3
    /// beyond the pad (`a = 3`).
    reconnect: bool,
}

impl Drag {
    fn text(&self) -> String {
        let friction = match (self.reconnect, self.mu > 0.0) {
            (true, _) => format!(
                "friction = {{ mu = {}, normal = [0, 1], reconnect = true }}",
                self.mu
            ),
            (false, true) => format!(
                "friction = {{ mu = {}, normal = [0, 1], viscosity = {:e} }}",
                self.mu, self.eta
            ),
            (false, false) => String::new(),
        };
        let plate = if self.reconnect { ", a = 3" } else { "" };
        let rho = if self.rho > 0.0 {
            format!("rho = {:e}", self.rho)
        } else {
            String::new()
        };
        let geo = root().join("geo").join(self.geo);
        let tri = if self.tri { ", tri = 1" } else { "" };
        format!(
            r#"mesh = "{}"
[mesh_options]
params = {{ n = {n}, m = {m}, l = {l}{tri}{plate} }}
[[region]]
group = "solid"
kind = "solid"
K = 20.0
mu = 10.0
{rho}
[[region]]
group = "medium"
kind = "medium"
gamma = 1e-4
{friction}
{rho}
[[bc]]
group = "bottom"
ux = 0.0
uy = 0.0
{loads}"#,
            geo.display(),
            n = self.n,
            m = self.n / 2,
            l = self.l,
            loads = press_then_drag(
                "uy",
                self.press,
                self.amount,
                "corner_x",
                &format!("[{}, 0.25]", leading_corner(self.geo)),
            ),
        )
    }

    /// `geo/pad.geo` meshed in triangles (its `Recombine` line left out), written beside the
    /// bench's runs.
    /// Solve it in `target/bench-friction/TAG`: whether it completed, the drag reached, the
    /// force ratio F_t/F_n of the top at each accepted step of the drag (drag, ratio), and the
    /// summary.
    fn run(&self, tag: &str) -> (bool, f64, Vec<(f64, f64)>, serde_json::Value) {
        let dir = root().join("target/bench-friction").join(tag);
        let (ok, s) = solve(&dir, &self.text());
        let ratios = drag_ratios(&dir, self.amount, "R_top_y");
        let reached = ratios.last().map_or(0.0, |r| r.0);
        (ok, reached, ratios, s)
    }

    /// How far the solid's leading bottom corner slid, in cells of the layer.
    fn corner_cells(&self, s: &serde_json::Value) -> f64 {
        let cell = 2.0 / self.n as f64;
        s["probes"]["corner_x"].as_f64().unwrap_or(f64::NAN) / cell
    }
}

/// How far each drag gets: the drag reached (1.0 if it completes), F_t / F_n of the top,
/// largest and last, over the drag, and the solid's leading corner's slide then in cells;
/// each friction drag quasi-static, with a slip viscosity and with inertia.
fn reach() {
    println!();
    println!(
        "| scene | cells across the medium | μ | η_s | ρ | completes | drag reached | leading corner slid (cells) | load steps | Newton its | largest F_t/F_n | last F_t/F_n | wall s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let runs = [("block.geo", [1, 2, 4, 8].as_slice()), ("pad.geo", &[1, 4])];
    for (geo, layers) in runs {
        for &l in layers {
            let drags = [0.0, 0.1, 0.3, 0.5, 1.0].into_iter().flat_map(|mu| {
                let extra: &[(f64, f64)] = if mu > 0.0 {
                    &[(0.0, 0.0), (1e-3, 0.0), (0.0, 1e-4)]
                } else {
                    &[(0.0, 0.0)]
                };
                extra.iter().map(move |&(eta, rho)| (mu, eta, rho))
            });
            for (mu, eta, rho) in drags {
                let d = Drag {
                    geo,
                    n: CELLS,
                    l,
                    tri: false,
                    mu,
                    eta,
                    rho,
                    press: 0.3,
                    amount: 1.0,
                    reconnect: false,
                };
                let (ok, reached, ratios, s) = d.run(&format!("reach-{geo}-{l}-{mu}-{eta}-{rho}"));
                let largest = ratios.iter().map(|r| r.1).fold(f64::NAN, f64::max);
                let last = ratios.last().map_or(f64::NAN, |r| r.1);
                println!(
                    "| {} | {l} | {mu} | {eta} | {rho} | {} | {reached:.3} | {:.2} | {} | {} | {largest:.4} | {last:.4} | {:.1} |",
                    geo.trim_end_matches(".geo"),
                    if ok { "yes" } else { "no" },
                    d.corner_cells(&s),
                    s["load_steps"],
                    s["newton_iterations"],
                    s["wall_seconds"].as_f64().unwrap_or(f64::NAN),
                );
            }
        }
    }
}

/// Issue 36's drags with inertia (every region ρ = 1e-4): the block (`l = n/4` cells across
/// the medium, pressed 0.35, dragged 0.5, twice the medium's thickness) and the pad (pressed
/// 0.3, dragged 2.0, its own width), Q1 and T1, on n = 16 and 32 (and the block on Q1 n = 64
/// with `TMC_BENCH_FINE=1`, about an hour): whether each completes, and F_t/F_n at a quarter,
/// a half and the whole of the drag.
fn slide() {
    println!();
    println!(
        "| scene | cells | l | μ | completes | drag reached | load steps | Newton its | largest F_t/F_n | at ¼ / ½ / all of the drag | leading corner slid (cells) | wall s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut drags = Vec::new();
    let block = |n, tri, mu| Drag {
        geo: "block.geo",
        n,
        l: n / 4,
        tri,
        mu,
        eta: 0.0,
        rho: 1e-4,
        press: 0.35,
        amount: 0.5,
        reconnect: false,
    };
    for n in [16, 32] {
        for tri in [false, true] {
            for mu in [0.1, 0.3, 0.5, 1.0] {
                drags.push(block(n, tri, mu));
            }
        }
    }
    for n in [16, 32] {
        for l in [1, 4] {
            for tri in [false, true] {
                for mu in [0.3, 0.5, 1.0] {
                    drags.push(Drag {
                        geo: "pad.geo",
                        l,
                        press: 0.3,
                        amount: 2.0,
                        ..block(n, tri, mu)
                    });
                }
            }
        }
    }
    if std::env::var("TMC_BENCH_FINE").is_ok() {
        drags.extend([0.1, 0.3, 0.5, 1.0].map(|mu| block(64, false, mu)));
    }
    for d in drags {
        let cells = format!("{} n = {}", if d.tri { "T1" } else { "Q1" }, d.n);
        let (ok, reached, r, s) = d.run(&format!(
            "slide-{}-{}-{}-{}-{}",
            d.geo, d.n, d.l, d.tri, d.mu
        ));
        let at = |f: f64| {
            let x = f * d.amount;
            r.iter()
                .rev()
                .find(|p| p.0 <= x + 1e-9)
                .filter(|_| reached >= x - 1e-9)
                .map_or("–".to_string(), |p| format!("{:.3}", p.1))
        };
        let largest = r.iter().map(|r| r.1).fold(f64::NAN, f64::max);
        println!(
            "| {} | {cells} | {} | {} | {} | {reached:.3} | {} | {} | {largest:.4} | {} / {} / {} | {:.2} | {:.1} |",
            d.geo.trim_end_matches(".geo"),
            d.l,
            d.mu,
            if ok { "yes" } else { "no" },
            s["load_steps"],
            s["newton_iterations"],
            at(0.25),
            at(0.5),
            at(1.0),
            d.corner_cells(&s),
            s["wall_seconds"].as_f64().unwrap_or(f64::NAN),
        );
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
