//! Physical time and transient heat: backward Euler against the erfc solution with its
//! convergence slopes in Δt and h, the stationary limit, the heat balance, and the history
//! per quadrature point across accepted and rejected steps.

use crate::common;
use common::*;
use tmc::assembly::Assembler;

/// A semi-infinite body (a long strip, L = 1, insulated far end) at θ = 0 whose surface x = 0
/// is held at θ = 1 from t = 0 on: θ = erfc(x / (2 √(κ t))), κ = k/ρc = 1, at t = T.
const T: f64 = 0.02;

fn erfc_case(steps: usize) -> String {
    format!(
        r#"
[[region]]
group = "solid"
kind = "solid"
K = 1.0
mu = 1.0
k = 1.0
rho_c = 1.0

[[bc]]
group = "left"
theta = 1.0
ramp = false

[time]
end = {T}
dt = {dt}

[[probe]]
name = "a"
field = "theta"
at = [0.05, 0.025]

[[probe]]
name = "b"
field = "theta"
at = [0.1, 0.025]

[[probe]]
name = "c"
field = "theta"
at = [0.2, 0.025]
"#,
        dt = T / steps as f64
    )
}

/// θ at the probes (nodes of every mesh below) after `steps` steps on `n` cells along x.
fn erfc_probes(n: usize, steps: usize) -> [f64; 3] {
    let (s, _) = solve_text(
        &format!("erfc-{n}-{steps}"),
        "slab.geo",
        &format!("L = 1.0, H = 0.05, n = {n}, m = 1"),
        &erfc_case(steps),
    );
    assert!(s.physics.transient && !s.physics.mechanics);
    assert_eq!(s.load_steps, steps, "fixed steps of dt");
    assert!((s.time - T).abs() < 1e-15);
    ["a", "b", "c"].map(|k| s.probes[k])
}

/// erfc to about 1e-16 (W. J. Cody's rational approximation is not in std; Abramowitz &
/// Stegun 7.1.26 is only 1.5e-7, too coarse here): the series of erf for small x, the
/// continued fraction of erfc for large x.
fn erfc(x: f64) -> f64 {
    if x < 2.0 {
        // erf x = 2/√π Σ (−1)^n x^(2n+1) / (n! (2n+1))
        let (mut term, mut sum) = (x, x);
        for n in 1..60 {
            term *= -x * x / n as f64;
            sum += term / (2 * n + 1) as f64;
        }
        1.0 - 2.0 / std::f64::consts::PI.sqrt() * sum
    } else {
        // erfc x = e^(−x²)/√π · 1/(x + 1/2/(x + 1/(x + 3/2/(x + …))))
        let mut f = x;
        for k in (1..80).rev() {
            f = x + (k as f64 / 2.0) / f;
        }
        (-x * x).exp() / std::f64::consts::PI.sqrt() / f
    }
}

fn exact() -> [f64; 3] {
    [0.05, 0.1, 0.2].map(|x: f64| erfc(x / (2.0 * T.sqrt())))
}

fn max_error(p: [f64; 3], reference: [f64; 3]) -> f64 {
    (0..3).fold(0.0, |m, i| f64::max(m, (p[i] - reference[i]).abs()))
}

/// Least-squares slope of log e against log s.
fn slope(s: &[f64], e: &[f64]) -> f64 {
    let (x, y): (Vec<f64>, Vec<f64>) = s.iter().zip(e).map(|(a, b)| (a.ln(), b.ln())).unzip();
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

#[test]
fn erfc_helper_is_accurate() {
    // tabulated values
    for (x, v) in [
        (0.5, 0.479_500_122_186_953_5),
        (1.0, 0.157_299_207_050_285_1),
        (2.5, 4.069_520_174_449_59e-4),
        (3.0, 2.209_049_699_858_544e-5),
    ] {
        assert!((erfc(x) - v).abs() < 1e-15 + 1e-13 * v, "{x}: {}", erfc(x));
    }
}

#[test]
fn backward_euler_converges_at_first_order_in_dt() {
    // a fine mesh (h = 1/400), so the error is the time discretisation's
    let steps = [10, 20, 40, 80];
    let errors: Vec<f64> = steps
        .iter()
        .map(|&k| max_error(erfc_probes(400, k), exact()))
        .collect();
    let dts: Vec<f64> = steps.iter().map(|&k| T / k as f64).collect();
    let p = slope(&dts, &errors);
    assert!((0.9..1.1).contains(&p), "slope in Δt {p}: {errors:?}");
    assert!(errors[3] < 2e-3, "{errors:?}");
}

#[test]
fn linear_elements_converge_at_second_order_in_h() {
    // the time error removed by Richardson extrapolation (θ(Δt/2) twice minus θ(Δt), O(Δt²))
    let ns = [20, 40, 80];
    let errors: Vec<f64> = ns
        .iter()
        .map(|&n| {
            let (p1, p2) = (erfc_probes(n, 100), erfc_probes(n, 200));
            max_error(std::array::from_fn(|i| 2.0 * p2[i] - p1[i]), exact())
        })
        .collect();
    let hs: Vec<f64> = ns.iter().map(|&n| 1.0 / n as f64).collect();
    let p = slope(&hs, &errors);
    assert!((1.85..2.15).contains(&p), "slope in h {p}: {errors:?}");
}

#[test]
fn long_times_reach_the_stationary_solution_and_the_heat_balances() {
    // slab-convection (stationary: θ_R = 60) with a heat capacity: the left face heated to
    // 100 within 1 s, then held for 25 time constants (L² ρc / k = 0.8)
    let body =
        case_body("slab-convection").replace("k = 5.0", "k = 5.0\nrho_c = 1.0\ntheta0 = 20.0");
    let text = format!(
        "{body}\n[time]\nend = 20.0\ndt = 0.5\nlambda = [[0.0, 0.0], [1.0, 1.0], [20.0, 1.0]]\n"
    );
    let (s, dir) = solve_text("transient-slab-convection", "slab.geo", "", &text);
    assert!(s.physics.transient && s.converged);
    assert!(
        (s.probes["theta_right"] - 60.0).abs() < 1e-8,
        "{}",
        s.probes["theta_right"]
    );
    assert!((s.probes["theta_mid"] - 80.0).abs() < 1e-8);
    // at the stationary state, what enters on the left leaves on the right
    assert!((s.reactions["left"]["heat"] - 100.0).abs() < 1e-7);
    assert!((s.reactions["right"]["heat"] + 100.0).abs() < 1e-7);
    // stored = supplied, step by step (the columns) and over the run (the summary)
    let (stored, supplied) = (s.heat_stored.unwrap(), s.heat_in.unwrap());
    // ∫ ρc (θ − 20) dA of the linear profile from 100 to 60 over 2 × 1
    assert!((stored - 2.0 * 60.0).abs() < 1e-6, "{stored}");
    assert!((stored - supplied).abs() < 1e-8 * supplied.abs());
    let (cols, rows) = history(&dir);
    let (a, b) = (
        cols.iter().position(|c| c == "heat_stored").unwrap(),
        cols.iter().position(|c| c == "heat_in").unwrap(),
    );
    assert_eq!(rows.len(), 41);
    for row in &rows {
        assert!(
            (row[a] - row[b]).abs() <= 1e-8 * row[b].abs().max(1.0),
            "{row:?}"
        );
    }
    // the temperature rises monotonically to the stationary state, not in one step
    assert!(rows[1][a] < 0.5 * stored);
}

#[test]
fn a_case_without_time_or_without_rho_c_stays_stationary() {
    let (s, _) = solve_case("slab-convection");
    assert!(!s.physics.transient && s.heat_stored.is_none());
    let body = case_body("slab-convection");
    let (s, _) = solve_text(
        "time-without-capacity",
        "slab.geo",
        "",
        &format!("{body}\n[time]\nend = 1.0\ndt = 0.25\n"),
    );
    // quasi-static steps over physical time: the stationary answer at each
    assert!(!s.physics.transient && s.load_steps == 4);
    assert!((s.probes["theta_right"] - 60.0).abs() < 1e-10);
}

#[test]
fn the_history_is_committed_at_accepted_steps_and_restored_at_rejected_ones() {
    let body = case_body("slab-convection").replace("k = 5.0", "k = 5.0\nrho_c = 2.0");
    let text = format!("{body}\n[time]\nend = 1.0\ndt = 0.5\n");
    let (_, model) = model_from(&text, "slab.geo", "history-commit");
    let mut asm = Assembler::new(&model);
    let committed = |asm: &Assembler| asm.history.slabs[0].committed.clone();
    let trial = |asm: &Assembler| asm.history.slabs[0].trial.clone();
    let x0 = model.initial_state();
    let start = committed(&asm);
    assert!(start.iter().all(|&v| v == 0.0), "θ0 everywhere at first");
    // an attempt at some other state writes the trial history only
    let mut x1 = x0.clone();
    for &d in &model.dofs.theta {
        x1[d as usize] = 7.0;
    }
    asm.assemble(&model, &x1, &model.path.step(0.0, 0.5), true, None)
        .unwrap();
    assert!(trial(&asm).iter().all(|&v| (v - 7.0).abs() < 1e-12));
    assert_eq!(committed(&asm), start);
    let r1 = asm.r_full.clone();
    // rejected: the trial history goes back; the same attempt gives the same residual
    asm.restore();
    assert_eq!(trial(&asm), start);
    asm.assemble(&model, &x1, &model.path.step(0.0, 0.5), false, None)
        .unwrap();
    assert_eq!(asm.r_full, r1);
    // accepted: θ of that state becomes θₙ of the next step, whose capacity term then
    // vanishes at the same state
    asm.commit();
    assert!(committed(&asm).iter().all(|&v| (v - 7.0).abs() < 1e-12));
    let mut x2 = x1.clone();
    for &d in &model.dofs.theta {
        x2[d as usize] = 9.0;
    }
    asm.assemble(&model, &x2, &model.path.step(0.5, 1.0), false, None)
        .unwrap();
    let heat: f64 = model
        .dofs
        .theta
        .iter()
        .map(|&d| asm.r_full[d as usize])
        .sum();
    // Σ r_θ = ρc (9 − 7) A / Δt + convection h (9 − 20) H on the right = 2·2·2/0.5 − 27.5
    assert!((heat - (16.0 - 27.5)).abs() < 1e-10, "{heat}");
}

#[test]
fn block_transient_scene_balances_its_heat() {
    let (s, dir) = solve_case("block-transient");
    assert!(s.converged && s.physics.transient && s.physics.mechanics_to_heat);
    let (stored, supplied) = (s.heat_stored.unwrap(), s.heat_in.unwrap());
    assert!(
        (stored - supplied).abs() < 1e-8 * supplied,
        "stored {stored} vs supplied {supplied}"
    );
    // the gap closes as in block.toml (the same load, now over t ≤ 1)
    assert!(
        (s.probes["gap"] - 2.94e-4).abs() < 0.02e-4,
        "{}",
        s.probes["gap"]
    );
    // the block warms from 20 towards the base's 100, not all the way in 3 s
    let theta = s.probes["theta_block"];
    assert!(theta > 50.0 && theta < 99.0, "{theta}");
    // heat enters through the base and leaves through the sides
    assert!(s.reactions["bottom"]["heat"] > 0.0);
    assert!(s.reactions["solid_left"]["heat"] < 0.0);
    let (l, r) = (
        s.reactions["solid_left"]["heat"],
        s.reactions["solid_right"]["heat"],
    );
    assert!(
        (l - r).abs() < 1e-9 * l.abs(),
        "symmetric sides: {l} vs {r}"
    );
    // the conductance rises as the medium closes: the base's heat at t = 1 (closed) is many
    // times that at t = 0.1 (open)
    let (cols, rows) = history(&dir);
    let (q, t) = (
        cols.iter().position(|c| c == "Q_bottom").unwrap(),
        cols.iter().position(|c| c == "time").unwrap(),
    );
    let at = |time: f64| rows.iter().find(|r| (r[t] - time).abs() < 1e-9).unwrap()[q];
    assert!(at(1.0) > 5.0 * at(0.1), "{} vs {}", at(1.0), at(0.1));
}
