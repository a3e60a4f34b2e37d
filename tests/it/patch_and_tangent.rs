//! Patch tests (a homogeneous deformation with a linear temperature field is reproduced exactly
//! on distorted and mixed meshes) and the assembled tangent checked against finite differences
//! of the assembled residual in random directions, for every element type in 2D and 3D.

#![allow(non_snake_case, clippy::needless_range_loop)]

use crate::common;
use common::*;
use tmc::assembly::Assembler;
use tmc::dofs::NONE;
use tmc::kernel::friction::HISTORY_PER_POINT;
use tmc::model::Model;
use tmc::solver::linear::{LinearKind, LinearSolver};
use tmc::solver::newton::{Newton, Part};

fn case_text(dim: usize, alpha: f64) -> String {
    let comps = if dim == 2 {
        "ux = 0.0\nuy = 0.0"
    } else {
        "ux = 0.0\nuy = 0.0\nuz = 0.0"
    };
    format!(
        r#"
[[region]]
group = "solid"
kind = "solid"
K = 20.0
mu = 10.0
k = 3.0
alpha = {alpha}
[[bc]]
group = "boundary"
{comps}
theta = 0.0
"#
    )
}

/// Deterministic pseudo-random numbers in [−1, 1].
fn noise(i: usize) -> f64 {
    let x = ((i as f64 + 1.0) * 12.9898).sin() * 43758.5453;
    2.0 * (x - x.floor()) - 1.0
}

/// Prescribe u = (F − I) X and θ = 10 + g · X on the boundary and solve.
fn patch(model: &mut Model) {
    let d = model.mesh.dim;
    let F = [[1.3, 0.2, 0.1], [-0.15, 0.8, 0.05], [0.1, -0.1, 1.1]];
    let g = [4.0, -2.0, 1.5];
    let exact_u = |x: &[f64; 3], c: usize| {
        (0..d)
            .map(|j| (F[c][j] - if c == j { 1.0 } else { 0.0 }) * x[j])
            .sum::<f64>()
    };
    let exact_t = |x: &[f64; 3]| 10.0 + (0..d).map(|j| g[j] * x[j]).sum::<f64>();
    for n in 0..model.mesh.coords.len() {
        let x = model.mesh.coords[n];
        for c in 0..d {
            if let Some(p) = model.cons.prescribed[model.dofs.u[n * d + c] as usize].as_mut() {
                p.value = exact_u(&x, c);
            }
        }
        if let Some(p) = model.cons.prescribed[model.dofs.theta[n] as usize].as_mut() {
            p.value = exact_t(&x);
        }
    }
    let mut asm = Assembler::new(model);
    let mut solver = LinearSolver::new(
        LinearKind::Lu,
        &asm.pattern,
        &tmc::dofs::equation_structure(&model.dofs, &model.cons),
    )
    .unwrap();
    let mut newton = Newton::new(model, 1e-12, 30);
    let mut x = model.initial_state();
    for lambda in [0.25, 0.5, 0.75, 1.0] {
        newton
            .step(
                model,
                &mut asm,
                &mut solver,
                &mut x,
                &model.path.step(0.0, lambda),
                Part::All,
            )
            .unwrap();
    }
    let mut interior = 0;
    for n in 0..model.mesh.coords.len() {
        let X = model.mesh.coords[n];
        if model.cons.eq[model.dofs.theta[n] as usize] != NONE {
            interior += 1;
        }
        for c in 0..d {
            let u = x[model.dofs.u[n * d + c] as usize];
            assert!(
                (u - exact_u(&X, c)).abs() < 1e-10,
                "node {n} u{c}: {u} vs {}",
                exact_u(&X, c)
            );
        }
        let t = x[model.dofs.theta[n] as usize];
        assert!(
            (t - exact_t(&X)).abs() < 1e-9,
            "node {n} θ: {t} vs {}",
            exact_t(&X)
        );
    }
    assert!(interior > 3, "the patch needs interior nodes");
}

#[test]
fn patch_test_mixed_t1_q1_mesh() {
    let (_, mut model) = model_from(&case_text(2, 0.0), "mixed2d.geo", "patch-mixed2d");
    let kinds = model.mesh.cell_kinds();
    assert!(
        kinds.len() == 2,
        "mesh must mix triangles and quads: {kinds:?}"
    );
    patch(&mut model);
}

#[test]
fn patch_test_tet4_mesh() {
    let (_, mut model) = model_from(&case_text(3, 0.0), "box-tet.geo", "patch-tet");
    patch(&mut model);
}

#[test]
fn patch_test_hex8_mesh() {
    let text = case_text(3, 0.0).replace("\"boundary\"", "\"x0\"");
    let mut text = text;
    for g in ["x1", "y0", "y1", "z0", "z1"] {
        text.push_str(&format!(
            "[[bc]]\ngroup = \"{g}\"\nux = 0.0\nuy = 0.0\nuz = 0.0\ntheta = 0.0\n"
        ));
    }
    let (_, mut model) = model_from(&text, "bar3d.geo", "patch-hex");
    patch(&mut model);
}

/// K v against (r(x + h v) − r(x − h v)) / 2h on the free equations, coupled and unsymmetric.
/// Returns the assembler of the state checked (its trial history is that state's).
fn tangent_check(model: &Model) -> Assembler {
    if model.physics.regularization {
        assert!(model.dofs.count(tmc::dofs::Field::P) > 0);
    }
    let mut asm = Assembler::new(model);
    let n = model.dofs.n_dofs;
    let mut x = model.initial_state();
    let span = model.mesh.extent();
    for (i, v) in x.iter_mut().enumerate() {
        *v += match model.dofs.field[i] {
            tmc::dofs::Field::Theta => 20.0 * noise(i),
            // u and p are lengths
            _ => 0.01 * span * noise(i),
        };
    }
    asm.assemble(model, &x, &model.path.step(0.0, 1.0), true, None)
        .unwrap();
    let p = asm.pattern.clone();
    let k = asm.values.clone();
    for trial in 0..3 {
        let v: Vec<f64> = (0..n).map(|i| noise(1000 * (trial + 1) + i)).collect();
        let vf: Vec<f64> = {
            let mut vf = vec![0.0; p.n];
            for (d, &e) in model.cons.eq.iter().enumerate() {
                if e != NONE {
                    vf[e as usize] = v[d];
                }
            }
            vf
        };
        let mut kv = vec![0.0; p.n];
        for j in 0..p.n {
            for q in p.col_ptr[j]..p.col_ptr[j + 1] {
                kv[p.row_idx[q]] += k[q] * vf[j];
            }
        }
        let h = 1e-6;
        let shifted = |s: f64| {
            let y: Vec<f64> = x
                .iter()
                .enumerate()
                .map(|(d, xv)| {
                    if model.cons.eq[d] != NONE {
                        xv + s * v[d]
                    } else {
                        *xv
                    }
                })
                .collect();
            let mut a = Assembler::new(model);
            a.assemble(model, &y, &model.path.step(0.0, 1.0), false, None)
                .unwrap();
            a.r_full
        };
        let (rp, rm) = (shifted(h), shifted(-h));
        let scale = kv.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        for (d, &e) in model.cons.eq.iter().enumerate() {
            if e != NONE {
                let fd = (rp[d] - rm[d]) / (2.0 * h);
                assert!(
                    (fd - kv[e as usize]).abs() < 1e-6 * scale,
                    "dof {d}: K v = {} vs FD {fd}",
                    kv[e as usize]
                );
            }
        }
    }
    // the coupled tangent is genuinely unsymmetric
    let mut asym = 0.0f64;
    for j in 0..p.n {
        for q in p.col_ptr[j]..p.col_ptr[j + 1] {
            let i = p.row_idx[q];
            asym = asym.max((k[q] - k[p.slot(j, i)]).abs());
        }
    }
    assert!(asym > 1e-8, "two-way coupled tangent should be unsymmetric");
    asm
}

#[test]
fn assembled_tangent_t1_q1() {
    let (_, model) = model_from(&case_text(2, 1e-3), "mixed2d.geo", "tangent-mixed2d");
    tangent_check(&model);
}

#[test]
fn assembled_tangent_tet4() {
    let (_, model) = model_from(&case_text(3, 1e-3), "box-tet.geo", "tangent-tet");
    tangent_check(&model);
}

#[test]
fn assembled_tangent_hex8() {
    let text = case_text(3, 1e-3).replace("\"boundary\"", "\"x0\"");
    let (_, model) = model_from(&text, "bar3d.geo", "tangent-hex");
    tangent_check(&model);
}

#[test]
fn assembled_tangent_hex8_with_convecting_faces() {
    // convection on deformed faces through the same scatter as the cells: ∂r_θ/∂θ and the
    // area's ∂(da)/∂u in the assembled tangent
    let mut text = case_text(3, 1e-3).replace("\"boundary\"", "\"x0\"");
    for g in ["x1", "y1", "z1"] {
        text.push_str(&format!(
            "[[bc]]\ngroup = \"{g}\"\nh = 3.0\ntheta_inf = -5.0\n"
        ));
    }
    let (_, model) = model_from(&text, "bar3d.geo", "tangent-hex-convection");
    assert_eq!(model.facet_blocks.len(), 3);
    tangent_check(&model);
}

/// A medium region with its regularization next to a solid, two-way coupled, for the
/// assembled check: `groups` are (solid, medium, clamped boundary).
fn medium_case(dim: usize) -> String {
    let comps = if dim == 2 {
        "ux = 0.0\nuy = 0.0"
    } else {
        "ux = 0.0\nuy = 0.0\nuz = 0.0"
    };
    let solid = if dim == 2 { "solid" } else { "block" };
    let extra = if dim == 2 {
        ""
    } else {
        "[[region]]\ngroup = \"plate\"\nkind = \"solid\"\nK = 20.0\nmu = 10.0\nk = 3.0\nalpha = 1e-3\n"
    };
    format!(
        r#"
[[region]]
group = "{solid}"
kind = "solid"
K = 20.0
mu = 10.0
k = 3.0
alpha = 1e-3
{extra}
[[region]]
group = "medium"
kind = "medium"
gamma = 1e-2
k = 0.5
alpha = 2e-3
beta2 = 0.1
[[bc]]
group = "bottom"
{comps}
theta = 0.0
"#
    )
}

#[test]
fn assembled_tangent_with_regularized_medium_q1_t1() {
    for tri in [0.0, 1.0] {
        let (_, model) = model_with(
            &medium_case(2),
            "block.geo",
            &[("n", 4.0), ("m", 2.0), ("l", 2.0), ("tri", tri)],
            "tangent-medium-2d",
        );
        assert!(model.physics.regularization);
        tangent_check(&model);
    }
}

#[test]
fn assembled_tangent_with_regularized_medium_h1() {
    let (_, model) = model_with(
        &medium_case(3),
        "block-plate-3d.geo",
        &[("n", 2.0), ("nb", 1.0), ("nm", 1.0), ("nq", 1.0)],
        "tangent-medium-3d",
    );
    tangent_check(&model);
}

#[test]
fn assembled_tangent_with_friction_and_its_heat_q1_t1_h1() {
    // friction in a tilted plane, heat made in one unit of time: the slip term, its heat
    // source and their derivatives in u and θ, some points slipping and some sticking
    for (dim, geo, params, normal) in [
        (
            2,
            "block.geo",
            vec![("n", 4.0), ("m", 2.0), ("l", 2.0)],
            "[0.3, 1]",
        ),
        (
            2,
            "block.geo",
            vec![("n", 4.0), ("m", 2.0), ("l", 2.0), ("tri", 1.0)],
            "[0.3, 1]",
        ),
        (
            3,
            "block-plate-3d.geo",
            vec![("n", 2.0), ("nb", 1.0), ("nm", 1.0), ("nq", 1.0)],
            "[0.3, 0.2, 1]",
        ),
    ] {
        let text = medium_case(dim).replace(
            "beta2 = 0.1\n",
            &format!("beta2 = 0.1\nfriction = {{ mu = 2.0, normal = {normal} }}\n"),
        ) + "[time]\nend = 1.0\ndt = 1.0\n";
        let (_, model) = model_with(&text, geo, &params, "tangent-friction");
        assert!(model.physics.frictional_heating && !model.friction_blocks.is_empty());
        let asm = tangent_check(&model);
        let nc = model.capacity_blocks.len();
        let points = || {
            asm.history.slabs[nc..]
                .iter()
                .flat_map(|s| s.trial.chunks(HISTORY_PER_POINT))
        };
        let slipped = points()
            .filter(|h| h[0] != 0.0 || h[1] != 0.0 || h[2] != 0.0)
            .count();
        let points = points().count();
        assert!(
            slipped > 0 && slipped < points,
            "{dim}D: {slipped} of {points} points slip"
        );
    }
}

#[test]
fn assembled_tangent_with_inertia_q1_t1_h1() {
    // a mass density on every region (ρ/Δt² comparable to the solids' stiffness at Δt = 1):
    // the inertia term's residual and tangent, and its history (u, then v = (u − uₙ)/Δt per
    // point, from rest at uₙ = 0)
    for (dim, geo, params) in [
        (2, "block.geo", vec![("n", 4.0), ("m", 2.0), ("l", 2.0)]),
        (
            2,
            "block.geo",
            vec![("n", 4.0), ("m", 2.0), ("l", 2.0), ("tri", 1.0)],
        ),
        (
            3,
            "block-plate-3d.geo",
            vec![("n", 2.0), ("nb", 1.0), ("nm", 1.0), ("nq", 1.0)],
        ),
    ] {
        let text = medium_case(dim)
            .replace("mu = 10.0\n", "mu = 10.0\nrho = 30.0\n")
            .replace("gamma = 1e-2\n", "gamma = 1e-2\nrho = 3.0\n");
        let (_, model) = model_with(&text, geo, &params, "tangent-inertia");
        assert!(model.physics.inertia);
        assert_eq!(model.inertia_blocks.len(), model.blocks.len());
        let asm = tangent_check(&model);
        let per_point = 2 * dim;
        let slabs = &asm.history.slabs[model.capacity_blocks.len()..];
        assert_eq!(slabs.len(), model.inertia_blocks.len());
        for s in slabs {
            for h in s.trial.chunks(per_point) {
                let (u, v) = h.split_at(dim);
                assert_eq!(u, v, "{dim}D: v = u/Δt from rest with Δt = 1");
            }
            assert!(s.trial.iter().any(|&x| x != 0.0));
        }
    }
}

/// Move every node that carries no Dirichlet condition by up to `a` × (smallest cell size) in
/// pseudo-random directions: quadratic cells get curved edges, which isoparametric elements
/// must still handle exactly for a linear field.
fn distort(model: &mut Model, a: f64) {
    let d = model.mesh.dim;
    let h = model.mesh.extent() / 20.0;
    for n in 0..model.mesh.coords.len() {
        let free = model.cons.eq[model.dofs.theta[n] as usize] != NONE;
        if free {
            for c in 0..d {
                model.mesh.coords[n][c] += a * h * noise(7 * n + c);
            }
        }
    }
}

fn patch_quadratic(
    geo: &str,
    boundary_groups: &[&str],
    order: (u8, bool),
    kinds: &[&str],
    amplitude: f64,
) {
    let dim = if geo.contains("2d") { 2 } else { 3 };
    let mut text =
        case_text(dim, 0.0).replace("\"boundary\"", &format!("\"{}\"", boundary_groups[0]));
    for g in &boundary_groups[1..] {
        let comps = if dim == 2 {
            "ux = 0.0\nuy = 0.0"
        } else {
            "ux = 0.0\nuy = 0.0\nuz = 0.0"
        };
        text.push_str(&format!("[[bc]]\ngroup = \"{g}\"\n{comps}\ntheta = 0.0\n"));
    }
    let (_, mut model) = model_order(
        &text,
        geo,
        &[],
        order,
        &format!("patch-{geo}-{}{}", order.0, order.1),
    );
    let names: Vec<&str> = model.mesh.cells.iter().map(|b| b.kind.name()).collect();
    for k in kinds {
        assert!(
            names.contains(k),
            "{geo}: expected {k} cells, got {names:?}"
        );
    }
    distort(&mut model, amplitude);
    patch(&mut model);
}

const HEX_FACES: [&str; 6] = ["x0", "x1", "y0", "y1", "z0", "z1"];

#[test]
fn patch_test_distorted_tri6_quad9() {
    patch_quadratic(
        "mixed2d.geo",
        &["boundary"],
        (2, false),
        &["T2 (tri6)", "Q2 (quad9)"],
        0.15,
    );
}

#[test]
fn patch_test_distorted_quad8() {
    patch_quadratic(
        "mixed2d.geo",
        &["boundary"],
        (2, true),
        &["Q2S (quad8)"],
        0.15,
    );
}

#[test]
fn patch_test_distorted_tet10() {
    // unstructured tets include slivers: a smaller push keeps every Jacobian positive
    patch_quadratic("box-tet.geo", &["boundary"], (2, false), &["tet10"], 0.05);
}

#[test]
fn patch_test_distorted_hex27() {
    patch_quadratic("bar3d.geo", &HEX_FACES, (2, false), &["H2 (hex27)"], 0.15);
}

#[test]
fn patch_test_distorted_hex20() {
    patch_quadratic("bar3d.geo", &HEX_FACES, (2, true), &["H2S (hex20)"], 0.15);
}

/// Assembled with 8 threads (cells cut three times into halves that run at once) and with
/// one, the residual, tangent, lifting and energy agree to round-off: no entry is lost or
/// added twice by cells running at once.
#[test]
fn parallel_assembly_matches_one_thread() {
    let (_, model) = model_with(
        &medium_case(3),
        "block-plate-3d.geo",
        &[("n", 16.0), ("nb", 4.0), ("nm", 1.0), ("nq", 3.0)],
        "parallel-assembly",
    );
    let mut x = model.initial_state();
    for (d, v) in x.iter_mut().enumerate() {
        *v += 1e-3 * (((d * 7919) % 101) as f64 / 101.0 - 0.5);
    }
    let dx: Vec<f64> = (0..x.len()).map(|d| 1e-4 * (d % 3) as f64).collect();
    let assemble = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut asm = Assembler::new(&model);
            let stats = asm
                .assemble(&model, &x, &model.path.step(0.0, 0.5), true, Some(&dx))
                .unwrap();
            (asm.values, asm.r_full, asm.lift, stats.energy)
        })
    };
    let cells: usize = model.mesh.cells.iter().map(|b| b.n_cells()).sum();
    assert!(
        cells >= 2048,
        "{cells} cells: too few to be cut three times"
    );
    let one = assemble(1);
    let eight = assemble(8);
    let close = |a: &[f64], b: &[f64]| {
        let (worst, scale) = common::largest_difference(a, b);
        assert!(scale > 0.0);
        assert!(worst <= 1e-13 * scale, "{worst:e} of {scale:e}");
    };
    close(&one.0, &eight.0);
    close(&one.1, &eight.1);
    close(&one.2, &eight.2);
    assert!((one.3 - eight.3).abs() <= 1e-13 * one.3.abs());
}

/// A medium cell flipped inside out is reported as inverted, in the medium: by the look
/// before a tangent assembly, and by the kernels of a residual-only assembly (which skips it).
#[test]
fn an_inverted_medium_cell_is_reported_with_and_without_the_tangent() {
    let (_, model) = model_with(
        &medium_case(3),
        "block-plate-3d.geo",
        &[("n", 4.0), ("nb", 2.0), ("nm", 1.0), ("nq", 2.0)],
        "inverted-medium",
    );
    let bi = model
        .blocks
        .iter()
        .position(|b| b.mat.medium)
        .expect("a medium block");
    let cell = model.mesh.cells[model.blocks[bi].block].cell(0).to_vec();
    let zc = cell.iter().map(|&n| model.mesh.coords[n][2]).sum::<f64>() / cell.len() as f64;
    // mirror the cell's nodes in its mid-plane: J < 0 at every quadrature point
    let mut x = model.initial_state();
    for &n in &cell {
        x[model.dofs.u[3 * n + 2] as usize] = -2.0 * (model.mesh.coords[n][2] - zc);
    }
    let look = tmc::assembly::check_inversion(&model, &tmc::assembly::References::new(&model), &x);
    assert!(
        matches!(&look, Err(tmc::assembly::AssemblyError::Inverted { region, J, .. }) if region == "medium" && *J <= 0.0),
        "{look:?}"
    );
    assert!(
        tmc::assembly::check_inversion(
            &model,
            &tmc::assembly::References::new(&model),
            &model.initial_state()
        )
        .is_ok()
    );
    let mut asm = Assembler::new(&model);
    for tangent in [true, false] {
        match asm.assemble(&model, &x, &model.path.step(0.0, 0.5), tangent, None) {
            Err(tmc::assembly::AssemblyError::Inverted { region, J, .. }) => {
                assert_eq!(region, "medium", "tangent {tangent}");
                assert!(J <= 0.0, "tangent {tangent}: J = {J}");
            }
            other => panic!("tangent {tangent}: {other:?}"),
        }
    }
    assert!(
        asm.assemble(
            &model,
            &model.initial_state(),
            &model.path.step(0.0, 0.5),
            true,
            None
        )
        .is_ok()
    );
}

/// The cells that write an entry first store instead of adding, so the tangent is never
/// zeroed: assembled at one state and then at another, it equals a fresh assembly at the
/// second, on a medium whose interface nodes carry p rows the solid cells do not write.
#[test]
fn reassembly_leaves_nothing_of_the_previous_tangent() {
    let (_, model) = model_with(
        &medium_case(3),
        "block-plate-3d.geo",
        &[("n", 8.0), ("nb", 2.0), ("nm", 1.0), ("nq", 2.0)],
        "reassembly",
    );
    let state = |scale: f64| {
        let mut x = model.initial_state();
        for (d, v) in x.iter_mut().enumerate() {
            *v += scale * (((d * 7919) % 101) as f64 / 101.0 - 0.5);
        }
        x
    };
    let (x1, x2) = (state(2e-3), state(-1e-3));
    let mut reused = Assembler::new(&model);
    reused
        .assemble(&model, &x1, &model.path.step(0.0, 0.5), true, None)
        .unwrap();
    reused
        .assemble(&model, &x2, &model.path.step(0.0, 0.5), true, None)
        .unwrap();
    let mut fresh = Assembler::new(&model);
    fresh
        .assemble(&model, &x2, &model.path.step(0.0, 0.5), true, None)
        .unwrap();
    assert!(fresh.values.iter().any(|&v| v != 0.0));
    assert_eq!(reused.values, fresh.values);
    // and an assembly cut short by an inverted solid cell (found by the kernels, after
    // other cells were written) leaves nothing either
    let mut x3 = x2.clone();
    let bi = model.blocks.iter().position(|b| !b.mat.medium).unwrap();
    let blk = &model.mesh.cells[model.blocks[bi].block];
    let cell = blk.cell(blk.n_cells() / 2);
    let zc = cell.iter().map(|&n| model.mesh.coords[n][2]).sum::<f64>() / cell.len() as f64;
    for &n in cell {
        x3[model.dofs.u[3 * n + 2] as usize] = -2.0 * (model.mesh.coords[n][2] - zc);
    }
    assert!(matches!(
        reused.assemble(&model, &x3, &model.path.step(0.0, 0.5), true, None),
        Err(tmc::assembly::AssemblyError::Inverted { .. })
    ));
    reused
        .assemble(&model, &x2, &model.path.step(0.0, 0.5), true, None)
        .unwrap();
    assert_eq!(reused.values, fresh.values);
}

/// The rigid motions of `model::rigid` (with the regularization fields a rotation implies) are
/// the tangent's kernel at the undeformed state: K m = 0 on every equation whose cells hold
/// no prescribed value, to round-off of K's size; and they are not all zero there.
fn rigid_motions_are_the_kernel(model: &Model) {
    let mut asm = Assembler::new(model);
    let x = model.initial_state();
    asm.assemble(model, &x, &model.path.step(0.0, 0.0), true, None)
        .unwrap();
    let (p, k) = (&asm.pattern, &asm.values);
    let node_of_dof = model.dofs.node_of_dof();
    let mut held = vec![false; model.mesh.coords.len()];
    for (d, c) in model.cons.prescribed.iter().enumerate() {
        if c.is_some() {
            held[node_of_dof[d] as usize] = true;
        }
    }
    let mut near = vec![false; held.len()];
    for b in &model.mesh.cells {
        for c in 0..b.n_cells() {
            if b.cell(c).iter().any(|&n| held[n]) {
                b.cell(c).iter().for_each(|&n| near[n] = true);
            }
        }
    }
    let mut node_of_eq = vec![0usize; p.n];
    for (d, &e) in model.cons.eq.iter().enumerate() {
        if e != NONE {
            node_of_eq[e as usize] = node_of_dof[d] as usize;
        }
    }
    let scale = k.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let modes = tmc::model::rigid::rigid_motions(model);
    assert_eq!(modes.len(), if model.mesh.dim == 2 { 3 } else { 6 });
    for (i, m) in modes.iter().enumerate() {
        let size = m.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        assert!(size > 0.1, "mode {i} vanishes");
        let mut km = vec![0.0; p.n];
        for j in 0..p.n {
            for q in p.col_ptr[j]..p.col_ptr[j + 1] {
                km[p.row_idx[q]] += k[q] * m[j];
            }
        }
        let (mut worst, mut rows) = (0.0f64, 0);
        for (e, v) in km.iter().enumerate() {
            if !near[node_of_eq[e]] {
                worst = worst.max(v.abs());
                rows += 1;
            }
        }
        assert!(rows > 0);
        assert!(
            worst < 1e-10 * scale * size,
            "mode {i}: |K m| = {worst:.3e} on {rows} free rows (|K| {scale:.3e})"
        );
    }
}

#[test]
fn rigid_motions_are_the_tangent_s_kernel_2d_and_3d() {
    let (_, model) = model_with(
        &medium_case(2),
        "block.geo",
        &[("n", 4.0), ("m", 2.0), ("l", 2.0)],
        "rigid-medium-2d",
    );
    assert!(model.physics.regularization);
    rigid_motions_are_the_kernel(&model);
    let (_, model) = model_with(
        &medium_case(3),
        "block-plate-3d.geo",
        &[("n", 2.0), ("nb", 2.0), ("nm", 1.0), ("nq", 1.0)],
        "rigid-medium-3d",
    );
    assert!(model.physics.regularization);
    rigid_motions_are_the_kernel(&model);
}

/// On several ranks each rank's pattern holds the entries of its own cells (every position
/// the assembler writes there is in it), together the ranks' patterns are the whole one, and
/// the whole rows of a rank's equations (for the parallel matrix's preallocation) are the
/// whole pattern's columns of the equations of its nodes, other columns empty.
#[test]
fn each_rank_s_pattern_is_its_cells_part_of_the_whole() {
    use tmc::mesh::partition;
    use tmc::parallel::{Distribution, Ranks};
    let (_, model) = model_from(&case_body("block"), "block.geo", "pattern-ranks");
    let whole = Assembler::new(&model).pattern;
    let column =
        |p: &tmc::dofs::Pattern, e: usize| p.row_idx[p.col_ptr[e]..p.col_ptr[e + 1]].to_vec();
    let node = tmc::dofs::equation_structure(&model.dofs, &model.cons).node;
    for size in [2, 3] {
        let partition = partition::cut(&model.mesh, size).unwrap();
        let mut union = vec![std::collections::BTreeSet::new(); whole.n];
        for rank in 0..size {
            let distribution = Distribution {
                ranks: Ranks { rank, size },
                partition: partition.clone(),
            };
            let asm = Assembler::distributed(&model, distribution);
            let (local, rows) = (&asm.pattern, asm.rows_owned(&model).unwrap());
            assert_eq!((local.n, rows.n), (whole.n, whole.n));
            assert!(
                local.nnz() < whole.nnz(),
                "{size} ranks: rank {rank} holds every entry"
            );
            for e in 0..whole.n {
                union[e].extend(column(local, e));
                let owned = partition.node_rank[node[e] as usize] as usize == rank;
                let want = if owned { column(&whole, e) } else { vec![] };
                assert_eq!(
                    column(&rows, e),
                    want,
                    "{size} ranks: rank {rank}'s row {e}"
                );
            }
        }
        for e in 0..whole.n {
            let got: Vec<usize> = union[e].iter().copied().collect();
            assert_eq!(got, column(&whole, e), "{size} ranks: column {e}");
        }
    }
}
