//! How a scene's fields are solved: one field, one-way (mechanics, then heat), or monolithic,
//! and with which linear solver.

use crate::case::{CouplingChoice, LinearChoice};
use crate::model::Physics;
use crate::solver::linear::LinearKind;
use serde::Serialize;

/// How the fields of a scene are solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Strategy {
    /// One field only (mechanics or conduction): one system, symmetric unless with friction.
    SingleField,
    /// Mechanics drives conduction, not back: per step, Newton on (u, p), then the (linear)
    /// conduction on the deformed state.
    OneWay,
    /// Newton on the whole coupled system.
    Monolithic,
}

/// The strategy the physics allows, unless the case forces the monolithic one (or a
/// whole-system linear solver). Friction's heat is a one-way coupling like the medium's
/// deformation heat: its mechanics (unsymmetric) is solved first, by LU, then the heat.
pub fn choose_strategy(solver: &crate::case::Solver, physics: &Physics) -> Strategy {
    if !(physics.mechanics && physics.conduction) {
        Strategy::SingleField
    } else if physics.heat_to_mechanics
        || solver.coupling == CouplingChoice::Monolithic
        || matches!(
            solver.linear.get_ref(),
            LinearChoice::Lu | LinearChoice::Gmres
        )
    {
        Strategy::Monolithic
    } else {
        Strategy::OneWay
    }
}

/// A line naming the active physics and the strategy.
pub fn describe(physics: &Physics, strategy: Strategy) -> String {
    let mut on = Vec::new();
    if physics.mechanics {
        on.push("mechanics");
    }
    if physics.conduction {
        on.push(if physics.transient {
            "transient conduction"
        } else {
            "conduction"
        });
    }
    if physics.medium {
        on.push("third medium");
    }
    if physics.regularization {
        on.push("regularization p");
    }
    if physics.friction {
        on.push(if physics.frictional_heating {
            "friction with frictional heating"
        } else {
            "friction"
        });
    }
    if physics.inertia {
        on.push("inertia");
    }
    let coupling = match (physics.mechanics_to_heat, physics.heat_to_mechanics) {
        (true, true) => "two-way coupled",
        (true, false) => "one-way coupled (deformation → heat)",
        _ => "uncoupled",
    };
    let how = match strategy {
        Strategy::SingleField if physics.friction => "one unsymmetric system",
        Strategy::SingleField => "one symmetric system",
        Strategy::OneWay if physics.friction => "mechanics (LU), then heat (LDLᵀ) per step",
        Strategy::OneWay => "mechanics, then heat per step, symmetric factorisations",
        Strategy::Monolithic => "monolithic Newton",
    };
    format!("physics: {}; {coupling}; {how}", on.join(" + "))
}

/// Whether the whole tangent is symmetric: one field, and no friction (Coulomb's limit moves
/// with the normal traction).
pub fn symmetric_tangent(physics: &Physics) -> bool {
    !(physics.friction || physics.mechanics && physics.conduction)
}

/// Choose the whole-system linear solver: LDLᵀ where the tangent is symmetric, LU for
/// friction's mechanics alone (unsymmetric), GMRES with the block-triangular preconditioner
/// for coupled fields (its mechanics block factorised by LU with friction, by LDLᵀ without);
/// LU or LDLᵀ when the case asks.
pub fn choose_linear(choice: LinearChoice, physics: &Physics) -> LinearKind {
    match choice {
        LinearChoice::Lu => LinearKind::Lu,
        LinearChoice::Ldlt => LinearKind::Ldlt,
        LinearChoice::Gmres => LinearKind::BlockGmres,
        LinearChoice::Auto => {
            if symmetric_tangent(physics) {
                LinearKind::Ldlt
            } else if physics.friction && !physics.conduction {
                LinearKind::Lu
            } else {
                LinearKind::BlockGmres
            }
        }
    }
}
