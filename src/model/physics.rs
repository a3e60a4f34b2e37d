//! Which effects a scene calls for, decided from the case alone: only those get unknowns,
//! couplings and kernels.

use crate::case::{Case, RegionKind};
use serde::Serialize;

/// Which effects the scene calls for, decided from the case before anything is assembled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Physics {
    /// Displacement unknowns exist.
    pub mechanics: bool,
    /// Temperature unknowns exist.
    pub conduction: bool,
    /// Deformation changes conduction (J C⁻¹, k(J)): whenever both fields are on.
    pub mechanics_to_heat: bool,
    /// Temperature drives deformation through thermal expansion (some α ≠ 0 and θ varies).
    pub heat_to_mechanics: bool,
    /// A third-medium region exists.
    pub medium: bool,
    /// Regularization fields p_i exist (linear medium elements).
    pub regularization: bool,
    /// Heat is stored (ρc θ̇): the case has `[time]`, conducts, and some region has `rho_c`.
    pub transient: bool,
    /// Some region has a mass density `rho` and the scene deforms: ρ ü, with the
    /// displacement and velocity per point as history.
    pub inertia: bool,
    /// Some medium region has `friction` and the scene deforms: slip history per point.
    pub friction: bool,
    /// Friction makes heat: the scene has friction, conducts, has `[time]` (slip has a rate),
    /// and some friction's `heat_fraction` is not 0.
    pub frictional_heating: bool,
}

/// Decide the active physics from the case.
pub fn decide_physics(case: &Case) -> Physics {
    let f = &case.file;
    let conduction =
        f.bc.iter()
            .any(|b| b.theta.is_some() || b.heat_flux.is_some() || b.exchanges_heat())
            || f.region
                .iter()
                .any(|r| r.heat_source.is_some_and(|q| q != 0.0));
    // θ can differ from θ0 somewhere only if some prescribed θ, ambient temperature or supplied
    // heat is non-trivial
    let theta0s: Vec<f64> = f.region.iter().map(|r| r.theta0).collect();
    let differs = |t: f64| theta0s.iter().any(|&t0| t != t0);
    let theta_varies = f.bc.iter().any(|b| {
        b.theta.is_some_and(differs)
            || b.heat_flux.is_some_and(|q| q != 0.0)
            || b.boundary_fluxes()
                .any(|q| q.anchors_temperature() && differs(q.ambient()))
    }) || f
        .region
        .iter()
        .any(|r| r.heat_source.is_some_and(|q| q != 0.0));
    let with_friction = || f.region.iter().filter_map(|r| r.friction.as_ref());
    let heating = conduction
        && f.time.is_some()
        && with_friction().any(|fr| fr.get_ref().heat_fraction() > 0.0);
    let expansion =
        f.region.iter().any(|r| r.alpha != 0.0) && conduction && (theta_varies || heating);
    let mechanical_load =
        f.bc.iter()
            .any(|b| b.ux.is_some() || b.uy.is_some() || b.uz.is_some() || b.traction.is_some())
            || f.region.iter().any(|r| {
                r.body_force
                    .as_ref()
                    .is_some_and(|b| b.get_ref().iter().any(|&v| v != 0.0))
            });
    let mechanics = mechanical_load || expansion;
    let medium = f.region.iter().any(|r| r.kind == RegionKind::Medium);
    Physics {
        mechanics,
        conduction,
        mechanics_to_heat: mechanics && conduction,
        heat_to_mechanics: expansion && mechanics,
        medium,
        // every medium element is linear so far, and p only regularizes a deforming medium
        regularization: medium && mechanics,
        transient: f.time.is_some() && conduction && f.region.iter().any(|r| r.rho_c.is_some()),
        inertia: mechanics && f.region.iter().any(|r| r.rho.is_some()),
        friction: mechanics && with_friction().next().is_some(),
        frictional_heating: mechanics && heating,
    }
}
