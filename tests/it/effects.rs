//! Only the effects a scene calls for: which unknowns exist, and how the coupled fields are
//! solved (one field, one-way staggered, or monolithic) without changing the answer.

use crate::common;
use common::*;
use tmc::dofs::Field;
use tmc::driver::Strategy;

fn counts(model: &tmc::model::Model) -> [usize; 3] {
    [Field::U, Field::Theta, Field::P].map(|f| model.dofs.count(f))
}

#[test]
fn unknowns_exist_only_for_active_fields() {
    let nodes = |m: &tmc::model::Model| m.mesh.coords.len();
    // mechanics only: a stretched slab has no temperature
    let (_, m) = model_from(&case_body("slab-stretch"), "slab.geo", "effects-mech");
    assert_eq!(counts(&m), [2 * nodes(&m), 0, 0]);
    assert!(m.physics.mechanics && !m.physics.conduction);
    // conduction only: no displacement
    let (_, m) = model_from(&case_body("slab-conduction"), "slab.geo", "effects-heat");
    assert_eq!(counts(&m), [0, nodes(&m), 0]);
    assert!(!m.physics.mechanics && m.physics.conduction);
    // one-way (α = 0): u, θ, and p on the medium
    let (_, m) = model_with(
        &case_body("block"),
        "block.geo",
        &[("n", 4.0), ("m", 4.0), ("l", 2.0)],
        "effects-one-way",
    );
    assert_eq!(counts(&m), [2 * nodes(&m), nodes(&m), 5 * 3]);
    assert!(m.physics.mechanics_to_heat && !m.physics.heat_to_mechanics);
    // two-way (α ≠ 0 and θ varies)
    let (_, m) = model_from(
        &case_body("plate-hole"),
        "plate-hole.geo",
        "effects-two-way",
    );
    assert_eq!(counts(&m), [2 * nodes(&m), nodes(&m), 0]);
    assert!(m.physics.mechanics_to_heat && m.physics.heat_to_mechanics);
}

#[test]
fn a_scene_assembles_only_the_terms_it_calls_for() {
    use tmc::model::Term;
    let kinds = |m: &tmc::model::Model| -> Vec<&'static str> {
        let mut k: Vec<&str> = (m.terms().iter())
            .map(|t| match t {
                Term::Bulk(_) => "bulk",
                Term::Flux(_) => "flux",
                Term::Capacity(_) => "capacity",
                Term::Friction(_) => "friction",
                Term::Inertia(_) => "inertia",
            })
            .collect();
        k.dedup();
        k
    };
    let small = [("n", 4.0), ("m", 4.0), ("l", 2.0)];
    // pressed and heated, stationary: the regions' cells alone
    let (_, m) = model_with(&case_body("block"), "block.geo", &small, "terms-block");
    assert_eq!(kinds(&m), ["bulk"]);
    // in time, convecting sides: heat storage (with θₙ per point) and the convecting faces
    let (_, m) = model_with(
        &case_body("block-transient"),
        "block.geo",
        &small,
        "terms-time",
    );
    assert_eq!(kinds(&m), ["bulk", "flux", "capacity"]);
    // dragged with friction in time: the slip per point too
    let (_, m) = model_with(
        &case_body("friction-heating"),
        "block.geo",
        &small,
        "terms-fric",
    );
    assert_eq!(kinds(&m), ["bulk", "capacity", "friction"]);
    // every term with history has its slab, in term order, and no other term has one
    let asm = tmc::assembly::Assembler::new(&m);
    let with_history = (m.terms().into_iter())
        .filter(|&t| tmc::assembly::integrand(&m, t).history_per_point(&m) > 0)
        .count();
    assert_eq!(asm.history.slabs.len(), with_history);
    assert!(with_history >= 2);
    // a mass density: the displacement and velocity per point, after every other term
    let text = case_body("friction-heating").replacen(
        "kind = \"solid\"\n",
        "kind = \"solid\"\nrho = 1e-3\n",
        1,
    );
    let (_, m) = model_with(&text, "block.geo", &small, "terms-inertia");
    assert!(m.physics.inertia);
    assert_eq!(kinds(&m), ["bulk", "capacity", "friction", "inertia"]);
    let asm = tmc::assembly::Assembler::new(&m);
    assert_eq!(asm.history.slabs.len(), 3);
    // its slab: u and v per quadrature point of the solid's cells (Q1: 4 points)
    let solid = m.inertia_blocks[0].block;
    assert_eq!(asm.history.slabs[2].width, 4 * 2 * 2);
    assert_eq!(
        asm.history.slabs[2].committed.len(),
        m.mesh.cells[solid].n_cells() * 16
    );
}

#[test]
fn strategies_follow_the_coupling() {
    for (case, strategy) in [
        ("slab-stretch", Strategy::SingleField),
        ("slab-conduction", Strategy::SingleField),
        ("slab-compressed-conduction", Strategy::OneWay),
        ("plate-hole", Strategy::Monolithic),
    ] {
        let (s, _) = solve_case(case);
        assert_eq!(s.strategy, strategy, "{case}");
        if case == "slab-conduction" {
            assert_eq!(
                (s.load_steps, s.newton_iterations),
                (1, 1),
                "one linear solve"
            );
        }
    }
}

/// The one-way path (mechanics with LDLᵀ, then heat with LDLᵀ, per step) and the monolithic
/// Newton reach the same state on the block scene.
#[test]
fn one_way_path_matches_the_monolithic_one() {
    let body = case_body("block");
    let params = "n = 16, m = 16, l = 4";
    let probes = "[[probe]]\nname = \"t_mid\"\nfield = \"theta\"\nat = [1.0, 0.75]\n\
                  [[probe]]\nname = \"ux_side\"\nfield = \"ux\"\nat = [2.0, 0.75]\n";
    let (one, d1) = solve_text("one-way", "block.geo", params, &format!("{body}{probes}"));
    let (mono, d2) = solve_text(
        "monolithic",
        "block.geo",
        params,
        &format!("{body}{probes}[solver]\ncoupling = \"monolithic\"\n"),
    );
    assert_eq!(one.strategy, Strategy::OneWay);
    assert_eq!(mono.strategy, Strategy::Monolithic);
    assert_eq!(one.linear_solver, tmc::solver::linear::LinearKind::Ldlt);
    for (k, v) in &mono.probes {
        let w = one.probes[k];
        assert!((v - w).abs() <= 1e-8 * v.abs().max(1e-3), "{k}: {w} vs {v}");
    }
    // the stored energy of the final step (each part assembles only its own equations)
    let energy = |d: &std::path::Path| {
        let (cols, rows) = history(d);
        let i = cols.iter().position(|c| c == "energy").unwrap();
        rows.last().unwrap()[i]
    };
    let (e1, e2) = (energy(&d1), energy(&d2));
    assert!(
        e2 > 0.0 && (e1 - e2).abs() <= 1e-8 * e2,
        "energy {e1} vs {e2}"
    );
    // every nodal value of the final step
    let last = |d: &std::path::Path, n: usize| d.join(format!("step_{n:04}.vtu"));
    for field in ["u", "theta"] {
        let a = point_array(&last(&d1, one.load_steps), field);
        let b = point_array(&last(&d2, mono.load_steps), field);
        let (diff, scale) = common::largest_difference(&b, &a);
        assert!(
            diff <= 1e-8 * scale,
            "{field}: max difference {diff} of {scale}"
        );
    }
}
