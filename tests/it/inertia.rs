//! Inertia (`rho`, a mass per reference volume): ρ ü by backward Euler. A free body under a
//! constant force moves as backward Euler's recurrence says, and loses to it exactly the
//! energy that recurrence dissipates. (In friction's drags, inertia carries the quasi-static
//! path through the slip events: friction.rs.)

use crate::common;

use common::{history, solve_text};

/// The slab of `geo/slab.geo` (2 × 1, Q1), held only in y along its bottom, pushed along x by
/// a body force `b` per reference volume from t = 0, with mass density `rho`, over `steps`
/// steps of `[time]` to t = 1.
fn pushed_slab(b: f64, rho: f64, steps: usize) -> String {
    format!(
        r#"
[[region]]
group = "solid"
kind = "solid"
K = 20.0
mu = 10.0
rho = {rho}
body_force = [{b}, 0.0]

[[bc]]
group = "bottom"
uy = 0.0

[[probe]]
name = "ux_corner"
field = "ux"
at = [2.0, 1.0]

[time]
end = 1.0
dt = {dt}
lambda = [[0.0, 1.0], [1.0, 1.0]]
"#,
        dt = 1.0 / steps as f64
    )
}

#[test]
fn a_free_body_under_a_constant_force_moves_as_backward_euler_says() {
    // Nothing holds the slab along x, so only its mass resists: every point accelerates at
    // a = b/ρ. Backward Euler from rest (v_k = v_{k-1} + Δt a, u_k = u_{k-1} + Δt v_k) gives
    // u_N = a Δt² N (N + 1)/2 and v_N = N Δt a, and loses ½ m (Δt a)² of kinetic energy in
    // every step: the work of the force is the kinetic energy plus N of those. Against the
    // motion itself, u = a t²/2, its error is a factor 1/N: first order in the step.
    let (b, rho) = (2.0, 4.0);
    let (a, mass) = (b / rho, rho * 2.0);
    let mut errors = Vec::new();
    for steps in [10, 20] {
        let (s, out) = solve_text(
            &format!("inertia-free-{steps}"),
            "slab.geo",
            "n = 4, m = 2",
            &pushed_slab(b, rho, steps),
        );
        assert!(s.converged, "{}", s.message);
        assert_eq!(s.load_steps, steps);
        let (n, dt) = (steps as f64, 1.0 / steps as f64);
        let u = s.probes["ux_corner"];
        let u_euler = a * dt * dt * n * (n + 1.0) / 2.0;
        assert!((u / u_euler - 1.0).abs() < 1e-9, "u {u} against {u_euler}");
        let v = n * dt * a;
        let kinetic = s.kinetic_energy.expect("a scene with rho reports it");
        assert!(
            (kinetic / (0.5 * mass * v * v) - 1.0).abs() < 1e-9,
            "{kinetic}"
        );
        let lost = n * 0.5 * mass * (dt * a).powi(2);
        // `external_work` takes the force of each accepted state by the trapezoidal rule; the
        // state at t = 0, at rest, carries none (its force goes into accelerating it): it
        // misses half the first step's work, ½ f u₁
        let (force, u1) = (b * 2.0, a * dt * dt);
        let work = s.external_work + 0.5 * force * u1;
        assert!(
            (work - force * u).abs() < 1e-9 * work,
            "{work} against f u = {}",
            force * u
        );
        assert!(
            (work - kinetic - lost).abs() < 1e-9 * work,
            "{work} {kinetic} {lost}"
        );
        // no deformation: a uniform force on a free body only moves it
        assert!(s.energy.abs() < 1e-12 * work, "stored {}", s.energy);
        // the history's kinetic energy column follows v_k = k Δt a
        let (cols, rows) = history(&out);
        let k = cols.iter().position(|c| c == "kinetic_energy").unwrap();
        for (step, row) in rows.iter().enumerate() {
            let v = step as f64 * dt * a;
            assert!(
                (row[k] - 0.5 * mass * v * v).abs() < 1e-9 * kinetic,
                "step {step}"
            );
        }
        errors.push(u / (a / 2.0) - 1.0);
    }
    println!("relative error of u against a t²/2: {errors:?}");
    assert!((errors[0] - 0.1).abs() < 1e-9 && (errors[1] - 0.05).abs() < 1e-9);
}

#[test]
fn a_body_that_moves_out_of_the_scene_is_told_once_and_in_the_summary() {
    // the free slab with a light mass (a = b/ρ = 500) moves u_k = a Δt² k (k + 1)/2 along x:
    // 5 after step 1 (t = 0.1), more than the mesh's extent (2), and 275 after step 10. The
    // run says so once, at step 1, naming a node of the solid, and again at its end;
    // summary.json keeps the largest displacement, which is the recurrence's u_10, and its
    // balances say it moved 137.5 times the extent (issue 70: a node that travelled 15 in a
    // mesh 6 wide was not told, as the warning waited for ten times the extent)
    let (b, rho, steps) = (2.0, 4e-3, 10);
    let case = common::case_file(
        "inertia-far",
        "slab.geo",
        "params = { n = 4, m = 2 }",
        &pushed_slab(b, rho, steps),
    );
    let out = case.with_file_name("out");
    let o = common::tmc(&["solve", case.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    let e = common::stderr(&o);
    assert!(o.status.success(), "{e}");
    let told: Vec<&str> = e
        .lines()
        .filter(|l| l.contains("times the mesh's extent") && l.starts_with("warning: step"))
        .collect();
    assert_eq!(told.len(), 1, "{e}");
    assert!(
        e.contains("warning: a node moved 137.5 times the mesh's extent, out of the scene"),
        "{e}"
    );
    assert!(
        told[0].starts_with("warning: step 1 (t = 1.0000e-1): node ")
            && told[0].contains("of region \"solid\"")
            && told[0].contains("its body moves far"),
        "{}",
        told[0]
    );
    let (a, dt) = (b / rho, 1.0 / steps as f64);
    let expected = a * dt * dt * (steps * (steps + 1)) as f64 / 2.0;
    let largest = common::summary(&out)["largest_displacement"]
        .as_f64()
        .unwrap();
    assert!(
        (largest - expected).abs() <= 1e-9 * expected,
        "largest displacement {largest} against {expected}"
    );
    let balances = &common::summary(&out)["balances"];
    let moved = balances["moved"].as_f64().unwrap();
    assert!((moved - expected / b).abs() <= 1e-9 * moved, "{balances}");
    assert_eq!(balances["open"], serde_json::json!(["moved"]), "{balances}");
    // quiet, no step says so: only the run's end, as an open balance is; the summary is the
    // same
    let quiet = case.with_file_name("quiet");
    let o = common::solve_cli(&case, &quiet, &[]);
    let e = common::stderr(&o);
    assert!(o.status.success(), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(e.starts_with("warning: a node moved 137.5 times"), "{e}");
    assert_eq!(common::summary(&quiet)["largest_displacement"], largest);
}
