//! Analytical checks, each asserting a number: finite stretch, free thermal expansion, steady
//! conduction, conduction in a compressed slab; Newton's quadratic convergence.

#![allow(non_snake_case, clippy::needless_range_loop)]

use crate::common;
use common::*;
use nalgebra::Matrix3;
use tmc::assembly::Assembler;
use tmc::material::ThermoElastic;
use tmc::solver::linear::{LinearKind, LinearSolver};
use tmc::solver::newton::{Newton, Part};

const LAW: ThermoElastic = ThermoElastic {
    K: 20.0,
    mu: 10.0,
    alpha: 0.0,
    theta0: 0.0,
};

/// Lateral stretch t that makes the lateral stress vanish under axial stretch `l`:
/// F = diag(l, t, t) in 3D, diag(l, t, 1) in plane strain. Returns (t, P11).
fn uniaxial(l: f64, plane: bool) -> (f64, f64) {
    let f = |t: f64| {
        let F = Matrix3::from_diagonal(&nalgebra::Vector3::new(l, t, if plane { 1.0 } else { t }));
        LAW.stress(&F, 0.0).unwrap().P
    };
    let (mut a, mut b) = (0.3, 1.5);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if f(m)[(1, 1)] > 0.0 { b = m } else { a = m }
    }
    let t = 0.5 * (a + b);
    (t, f(t)[(0, 0)])
}

/// Mooney-Rivlin (C10, C01, K) under F = diag(l, t, t), written in the stretches alone:
/// J = l t², I₁ = l² + 2 t², I₂ = 2 l² t² + t⁴ and Ψ(l, t) of the law. Returns the lateral
/// stretch t where ∂Ψ/∂t = 0 (free lateral faces) and P11 = ∂Ψ/∂l there.
fn mooney_rivlin_uniaxial(l: f64, c10: f64, c01: f64, k: f64) -> (f64, f64) {
    // ∂Ψ/∂x from ∂J/∂x, ∂I₁/∂x, ∂I₂/∂x
    let dpsi = |t: f64, dj: f64, di1: f64, di2: f64| {
        let (j, i1, i2) = (
            l * t * t,
            l * l + 2.0 * t * t,
            2.0 * l * l * t * t + t.powi(4),
        );
        c10 * (-2.0 / 3.0 * j.powf(-5.0 / 3.0) * dj * i1 + j.powf(-2.0 / 3.0) * di1)
            + c01 * (-4.0 / 3.0 * j.powf(-7.0 / 3.0) * dj * i2 + j.powf(-4.0 / 3.0) * di2)
            + k * (j - 1.0) * dj
    };
    let lateral = |t: f64| dpsi(t, 2.0 * l * t, 4.0 * t, 4.0 * l * l * t + 4.0 * t.powi(3));
    let (mut a, mut b) = (0.3, 1.5);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if lateral(m) > 0.0 { b = m } else { a = m }
    }
    let t = 0.5 * (a + b);
    (t, dpsi(t, t * t, 2.0 * l, 4.0 * l * t * t))
}

/// The bar3d-stretch run `s` against lateral stretch `t` and nominal stress `p11`: at the
/// corner (2, 0.5, 0.5) u_y = 0.5 (t − 1), on x1 the force P11 × B². Returns that force.
fn bar3d_matches(s: &tmc::driver::Summary, t: f64, p11: f64) -> f64 {
    assert!(s.converged);
    let uy = s.probes["uy_corner"];
    assert!(
        (uy - 0.5 * (t - 1.0)).abs() < 1e-9,
        "uy {uy} vs {}",
        0.5 * (t - 1.0)
    );
    let fx = s.reactions["x1"]["x"];
    assert!(
        (fx - p11 * 0.25).abs() < 1e-9 * p11,
        "force {fx} vs {}",
        p11 * 0.25
    );
    fx
}

#[test]
fn bar3d_uniaxial_stretch_matches_mooney_rivlin_closed_form() {
    let body = case_body("bar3d-stretch")
        .replace("mu = 10.0", "law = \"mooney-rivlin\"\nC10 = 3.0\nC01 = 2.0");
    let (s, _) = solve_text_opts("bar3d-mooney-rivlin", "bar3d.geo", "", &body);
    assert!(s.converged);
    let (t, p11) = mooney_rivlin_uniaxial(1.5, 3.0, 2.0, 20.0);
    let fx = bar3d_matches(&s, t, p11);
    assert!((s.reactions["x0"]["x"] + fx).abs() < 1e-9);
    // not Neo-Hooke's answer with the same small-strain moduli (μ = 2 (C10 + C01) = 10)
    let (t_nh, p11_nh) = uniaxial(1.5, false);
    assert!((p11 - p11_nh).abs() > 1e-3 * p11 && (t - t_nh).abs() > 1e-4);
}

#[test]
fn bar3d_uniaxial_stretch_matches_neo_hooke_closed_form() {
    let (s, dir) = solve_case("bar3d-stretch");
    assert!(s.converged);
    let (t, p11) = uniaxial(1.5, false);
    let fx = bar3d_matches(&s, t, p11);
    assert!((s.reactions["x0"]["x"] + fx).abs() < 1e-9);

    // the .vtu read by meshio (an independent reader): integer connectivity, the region by
    // name, and at every node the uniaxial Cauchy stress σ11 = P11 / t² as von Mises and as
    // the first principal stress, the other two zero
    let vtu = dir.join(format!("step_{:04}.vtu", s.load_steps));
    let script = "import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
vm, pr = m.point_data['von_mises'], m.point_data['sigma_principal']
print(m.cells[0].data.dtype.name, sorted(m.field_data), len(vm), vm.min(), vm.max(), pr[:, 0].min(), pr[:, 0].max(), abs(pr[:, 1:]).max())";
    let o = std::process::Command::new("/usr/bin/python3")
        .args(["-c", script])
        .arg(&vtu)
        .output()
        .expect("python3-meshio is installed by make test");
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let w: Vec<&str> = out.split_whitespace().collect();
    assert_eq!(&w[..2], ["int64", "['solid']"], "{out}");
    let v: Vec<f64> = w[2..].iter().map(|x| x.parse().unwrap()).collect();
    let sigma11 = p11 / (t * t);
    assert!(v[0] > 0.0, "{out}");
    for (what, x) in [
        ("von Mises min", v[1]),
        ("max", v[2]),
        ("σ1 min", v[3]),
        ("σ1 max", v[4]),
    ] {
        assert!(
            (x - sigma11).abs() < 1e-9 * sigma11,
            "{what} {x} vs σ11 = {sigma11}"
        );
    }
    assert!(v[5] < 1e-9 * sigma11, "σ2, σ3 up to {}", v[5]);
}

#[test]
fn plane_strain_slab_stretch_matches_closed_form() {
    let (s, _) = solve_case("slab-stretch");
    let (t, p11) = uniaxial(1.5, true);
    assert!((s.probes["uy_top_right"] - (t - 1.0)).abs() < 1e-9);
    assert!((s.reactions["right"]["x"] - p11 * 1.0).abs() < 1e-9 * p11);
}

#[test]
fn free_thermal_expansion_is_stress_free_with_j_exp_3_alpha_dtheta() {
    let (s, dir) = solve_case("box-expansion");
    assert!(s.converged);
    // J = exp(3 α Δθ) ⇒ every edge grows by exp(α Δθ)
    let stretch = (1e-3f64 * 100.0).exp();
    assert!((s.probes["ux_far"] - (stretch - 1.0)).abs() < 1e-10);
    let (cols, rows) = history(&dir);
    let last = rows.last().unwrap();
    let j = (3.0 * 1e-3f64 * 100.0).exp();
    let jc = cols.iter().position(|c| c == "min_J_solid").unwrap();
    assert!((last[jc] - j).abs() < 1e-10, "J {} vs {j}", last[jc]);
    for r in s.reactions.values() {
        for v in r.values() {
            assert!(v.abs() < 1e-10, "a stress-free body has no reactions: {v}");
        }
    }
    let sigma = cell_array(&dir.join(format!("step_{:04}.vtu", s.load_steps)), "sigma");
    let max = sigma.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(
        !sigma.is_empty() && max < 1e-10,
        "Cauchy stress must vanish, max |σ| = {max}"
    );
}

#[test]
fn steady_conduction_through_a_slab() {
    let (s, dir) = solve_case("slab-conduction");
    assert!(!s.physics.mechanics && s.physics.conduction);
    assert_eq!(s.newton_iterations, 1, "linear conduction takes one solve");
    assert!((s.probes["theta_mid"] - 60.0).abs() < 1e-10);
    // k Δθ H / L = 5 × 80 × 1 / 2
    assert!((s.reactions["left"]["heat"] - 200.0).abs() < 1e-9);
    assert!((s.reactions["right"]["heat"] + 200.0).abs() < 1e-9);
    // the heat flux at every node: q = −k ∇θ = (200, 0, 0)
    let q = point_array(&dir.join(format!("step_{:04}.vtu", s.load_steps)), "q");
    assert_eq!(q.len(), 3 * s.nodes);
    for x in q.chunks(3) {
        assert!(
            (x[0] - 200.0).abs() < 1e-9 && x[1].abs() < 1e-9 && x[2] == 0.0,
            "{x:?}"
        );
    }
}

#[test]
fn radiation_slab_matches_the_closed_form_end_temperature() {
    let (s, _) = solve_case("slab-radiation");
    assert!(!s.physics.mechanics && s.physics.conduction);
    // k (θ_L − θ_R) / L = ε σ (θ_R⁴ − θ∞⁴), by bisection
    let (k, l, es, inf) = (5.0, 2.0, 0.8 * 5.670374419e-8, 300.0f64);
    let out = |t: f64| k * (600.0 - t) / l - es * (t.powi(4) - inf.powi(4));
    let (mut a, mut b) = (inf, 600.0);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if out(m) > 0.0 { a = m } else { b = m }
    }
    let right = 0.5 * (a + b);
    assert!((right - 377.70).abs() < 0.01, "{right}");
    let theta_r = s.probes["theta_right"];
    assert!(
        (theta_r - right).abs() < 1e-9 * right,
        "θ_R {theta_r} vs {right}"
    );
    assert!((s.probes["theta_mid"] - 0.5 * (600.0 + right)).abs() < 1e-9 * right);
    // the heat conducted, k (θ_L − θ_R) H / L, in through the left and radiated out the right
    let flow = k * (600.0 - right) / l;
    assert!((s.reactions["left"]["heat"] - flow).abs() < 1e-9 * flow);
    assert!((s.reactions["right"]["heat"] + flow).abs() < 1e-9 * flow);
}

/// A medium slab (L = 2, H = 1) squeezed in uniaxial strain to J (its faces x = 0 and
/// x = L held apart by (1 − J) L, its top and bottom held in y) with θ = 100 and 0 held on
/// its ends: the heat flow across it is k(J) Δθ H / (J L), its layer J L thick.
fn squeezed_medium(tag: &str, j: f64, conductivity: &str) -> f64 {
    let body = format!(
        "[[region]]\ngroup = \"solid\"\nkind = \"medium\"\ngamma = 1e-2\n{conductivity}\n\
         [[bc]]\ngroup = \"left\"\nux = 0.0\ntheta = 100.0\n\
         [[bc]]\ngroup = \"right\"\nux = {}\ntheta = 0.0\n\
         [[bc]]\ngroup = \"top\"\nuy = 0.0\n[[bc]]\ngroup = \"bottom\"\nuy = 0.0\n\
         [[probe]]\nname = \"theta_mid\"\nfield = \"theta\"\nat = [1.0, 0.5]\n\
         [steps]\ntol = 1e-12\n",
        -(1.0 - j) * 2.0,
    );
    let (s, _) = solve_text(tag, "slab.geo", "n = 4, m = 2", &body);
    assert!(s.converged, "{tag}");
    // linear across the layer (probes are at undeformed positions)
    assert!(
        (s.probes["theta_mid"] - 50.0).abs() < 1e-8,
        "{tag}: {:?}",
        s.probes
    );
    let (q_in, q_out) = (s.reactions["left"]["heat"], s.reactions["right"]["heat"]);
    assert!(
        (q_in + q_out).abs() < 1e-9 * q_in,
        "{tag}: heat in {q_in}, out {q_out}"
    );
    q_in
}

#[test]
fn a_closed_layer_conducts_h_c_and_a_table_gives_its_k() {
    // k = min(k_TM (1 + ln² J), k_max, h_c t0 J) = h_c t0 J at J = 0.01: h_c Δθ H
    let closed = "k = 0.1\nk_max = 1000.0\nh_closed = 50.0\nthickness = 2.0";
    let q = squeezed_medium("medium-closed", 0.01, closed);
    assert!((q - 50.0 * 100.0).abs() < 1e-8 * q, "closed layer: {q}");
    // the paper's law alone: k_TM (1 + ln² J) Δθ H / (J L)
    let paper = squeezed_medium("medium-paper", 0.01, "k = 0.1\nk_max = 1000.0");
    let k = 0.1 * (1.0 + 0.01f64.ln().powi(2));
    assert!(
        (paper - k * 100.0 / 0.02).abs() < 1e-8 * paper,
        "paper: {paper}"
    );
    // a table, between its points (0.1, 0.5) and (0.01, 2) at J = 0.05
    let table = "k_table = [[1.0, 0.1], [0.01, 2.0], [0.1, 0.5]]";
    let q = squeezed_medium("medium-table", 0.05, table);
    let k = 0.5 + 1.5 * 0.05 / 0.09;
    assert!((q - k * 100.0 / 0.1).abs() < 1e-8 * q, "table: {q}");
}

#[test]
fn convection_bar_matches_the_closed_form_end_temperature() {
    let (s, dir) = solve_case("slab-convection");
    assert!(!s.physics.mechanics && s.physics.conduction);
    // θ_R = (k θ_L / L + h θ∞) / (k / L + h) = 60, linear in between
    assert!((s.probes["theta_right"] - 60.0).abs() < 1e-10);
    assert!((s.probes["theta_mid"] - 80.0).abs() < 1e-10);
    // h (θ_R − θ∞) H = 100 in through the left and out through the convecting right
    assert!((s.reactions["left"]["heat"] - 100.0).abs() < 1e-9);
    assert!((s.reactions["right"]["heat"] + 100.0).abs() < 1e-9);
    let (cols, rows) = history(&dir);
    let q = cols
        .iter()
        .position(|c| c == "Q_right")
        .expect("Q_right column");
    assert!((rows.last().unwrap()[q] + 100.0).abs() < 1e-9);
}

#[test]
fn convection_leaves_through_the_current_area_of_a_stretched_slab() {
    let (s, _) = solve_case("slab-convection-stretched");
    assert!(s.physics.mechanics_to_heat && !s.physics.heat_to_mechanics);
    // θ_R = (k θ_L / (l L) + h θ∞) / (k / (l L) + h) with l = 1.5
    let theta_r = s.probes["theta_right"];
    assert!((theta_r - 52.0).abs() < 1e-9, "θ_R {theta_r}");
    // heat flow h (θ_R − θ∞) t H through the current right face, t H its current length
    let t = 1.0 + s.probes["uy_top_right"];
    assert!(t < 0.95, "the stretch contracts the slab laterally: {t}");
    let q = 2.5 * (52.0 - 20.0) * t;
    assert!((s.reactions["left"]["heat"] - q).abs() < 1e-9 * q);
    assert!((s.reactions["right"]["heat"] + q).abs() < 1e-9 * q);
}

#[test]
fn compressed_slab_conducts_through_its_current_geometry() {
    let (s, _) = solve_case("slab-compressed-conduction");
    assert!(s.physics.mechanics_to_heat && !s.physics.heat_to_mechanics);
    let h = s.probes["height"];
    assert!(h > 1.0, "compression bulges the slab laterally: {h}");
    // pulled-back Fourier law: heat flow = k Δθ H' / L'
    let expect = 5.0 * 80.0 * h / 1.6;
    let q = s.reactions["left"]["heat"];
    assert!((q - expect).abs() < 1e-9 * expect, "{q} vs {expect}");
    // and not the reference-geometry value
    assert!((q - 200.0).abs() > 50.0);
}

#[test]
fn newton_converges_quadratically_on_a_stiff_step() {
    // the whole 50 % stretch of the bar in one load step
    let text = r#"
[[region]]
group = "solid"
kind = "solid"
K = 20.0
mu = 10.0
[[bc]]
group = "x0"
ux = 0.0
[[bc]]
group = "y0"
uy = 0.0
[[bc]]
group = "z0"
uz = 0.0
[[bc]]
group = "x1"
ux = 1.0
"#;
    let (_, model) = model_from(text, "bar3d.geo", "newton-quadratic");
    let mut asm = Assembler::new(&model);
    let mut solver = LinearSolver::new(
        LinearKind::Ldlt,
        &asm.pattern,
        &tmc::dofs::equation_structure(&model.dofs, &model.cons),
    )
    .unwrap();
    let mut newton = Newton::new(&model, 1e-12, 20);
    let mut x = model.initial_state();
    let rep = newton
        .step(
            &model,
            &mut asm,
            &mut solver,
            &mut x,
            &model.path.step(0.0, 1.0),
            Part::All,
        )
        .unwrap();
    assert!(rep.iterations <= 6, "took {} iterations", rep.iterations);
    let r: Vec<f64> = rep.history.iter().map(|h| h[0]).collect();
    // in the asymptotic range each residual is about the square of the previous one
    let k = r
        .iter()
        .position(|&v| v < 1e-2)
        .expect("reaches the asymptotic range");
    assert!(k + 1 < r.len());
    for w in r[k..].windows(2) {
        if w[1] > 1e-13 {
            assert!(w[1] < 10.0 * w[0] * w[0], "not quadratic: {r:?}");
        }
    }
}

#[test]
fn a_rigid_cylinder_presses_hertz_s_pressure_into_a_half_space() {
    // cases/hertz.toml: the contact pressure the step file holds on the block's top against
    // Hertz's for the load the run measured, P: a = √(4PR/(πE*)), p = p0 √(1 − x²/a²), p0 =
    // 2P/(πa), E* = E/(1 − ν²) (plane strain, the cylinder rigid)
    let (s, out) = solve_case("hertz");
    assert!(s.converged);
    let (cols, rows) = history(&out);
    let P = -rows.last().unwrap()[cols.iter().position(|c| c == "R_rim_y").unwrap()];
    let (K, mu) = (20.0, 10.0);
    let (E, nu) = (
        9.0 * K * mu / (3.0 * K + mu),
        (3.0 * K - 2.0 * mu) / (2.0 * (3.0 * K + mu)),
    );
    let Es = E / (1.0 - nu * nu);
    let a = (4.0 * P / (std::f64::consts::PI * Es)).sqrt();
    let p0 = 2.0 * P / (std::f64::consts::PI * a);
    // measured: P = 0.2686, a = 0.1105 (a/R = 0.11)
    assert!(a > 0.08 && a < 0.15, "a = {a}");
    let vtu = out.join(format!("step_{:04}.vtu", rows.len() - 1));
    let (p, shear) = (
        point_array(&vtu, "contact_pressure"),
        point_array(&vtu, "contact_shear"),
    );
    let (u, x) = (point_array(&vtu, "u"), point_array(&vtu, "position"));
    // the block's top: y = 0 in the mesh
    let mut top: Vec<usize> = (0..p.len())
        .filter(|&n| p[n] != 0.0 && (x[3 * n + 1] - u[3 * n + 1]).abs() < 1e-9)
        .collect();
    top.sort_by(|&i, &j| x[3 * i].total_cmp(&x[3 * j]));
    // it sums to the load (measured: within 0.1 %, the trapezoid rule over nodal values)
    let sum: f64 = (top.windows(2))
        .map(|w| 0.5 * (p[w[0]] + p[w[1]]) * (x[3 * w[1]] - x[3 * w[0]]))
        .sum();
    assert!((sum / P - 1.0).abs() < 0.01, "∫ p = {sum} against P = {P}");
    // its peak is p0 (measured: 1.5 % above), it follows Hertz over |x| < 0.8 a (measured:
    // 1.4 % of p0, RMS), it is all but gone beyond 1.2 a (measured: 0.8 % of p0 at most; the
    // medium spreads the edges), and there is no shear (frictionless; measured 0.05 % of p0)
    let peak = top.iter().map(|&n| p[n]).fold(0.0, f64::max);
    assert!((peak / p0 - 1.0).abs() < 0.03, "peak {peak}, p0 {p0}");
    let inside: Vec<f64> = (top.iter())
        .filter(|&&n| x[3 * n].abs() < 0.8 * a)
        .map(|&n| p[n] - p0 * (1.0 - (x[3 * n] / a).powi(2)).sqrt())
        .collect();
    assert!(inside.len() > 20, "{} nodes inside 0.8 a", inside.len());
    let rms = (inside.iter().map(|e| e * e).sum::<f64>() / inside.len() as f64).sqrt();
    assert!(rms < 0.025 * p0, "RMS {rms} against p0 {p0}");
    for &n in top.iter().filter(|&&n| x[3 * n].abs() > 1.2 * a) {
        assert!(p[n] < 0.02 * p0, "p = {} at x = {}", p[n], x[3 * n]);
    }
    let most_shear = top.iter().map(|&n| shear[3 * n].abs()).fold(0.0, f64::max);
    assert!(most_shear < 0.01 * p0, "shear {most_shear}");
}
