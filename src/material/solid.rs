//! The solid laws a region may choose (`law` on a `[[region]]`): one list, each law a file of
//! its own. The medium is always Neo-Hooke with K = μ = γ (eq. 13).
#![allow(non_snake_case)]

use super::{MooneyRivlin, StressResponse, ThermoElastic};
use nalgebra::Matrix3;

/// A solid law as the kernels call it: each law its own type, so that a kernel is compiled
/// for each and the list's choice is made once per cell, not per point.
pub trait Stress {
    /// The temperature at which the law is free of thermal stress.
    fn theta0(&self) -> f64;
    /// Energy, stress and tangents; `None` when J ≤ 0 or not finite.
    fn stress(&self, F: &Matrix3<f64>, theta: f64) -> Option<StressResponse>;
}

impl Stress for ThermoElastic {
    #[inline(always)]
    fn theta0(&self) -> f64 {
        self.theta0
    }
    #[inline(always)]
    fn stress(&self, F: &Matrix3<f64>, theta: f64) -> Option<StressResponse> {
        ThermoElastic::stress(self, F, theta)
    }
}

impl Stress for MooneyRivlin {
    #[inline(always)]
    fn theta0(&self) -> f64 {
        self.theta0
    }
    #[inline(always)]
    fn stress(&self, F: &Matrix3<f64>, theta: f64) -> Option<StressResponse> {
        MooneyRivlin::stress(self, F, theta)
    }
}

/// A solid's stress law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SolidLaw {
    /// Eq. (12): the paper's law, and the one the vectorised kernel is written for.
    NeoHooke(ThermoElastic),
    /// Abaqus' compressible Mooney-Rivlin.
    MooneyRivlin(MooneyRivlin),
}

impl SolidLaw {
    /// Energy, stress and tangents; `None` when J ≤ 0 or not finite.
    #[inline(always)]
    pub fn stress(&self, F: &Matrix3<f64>, theta: f64) -> Option<StressResponse> {
        match self {
            SolidLaw::NeoHooke(l) => l.stress(F, theta),
            SolidLaw::MooneyRivlin(l) => l.stress(F, theta),
        }
    }

    /// The temperature at which the law is free of thermal stress.
    pub fn theta0(&self) -> f64 {
        match self {
            SolidLaw::NeoHooke(l) => l.theta0,
            SolidLaw::MooneyRivlin(l) => l.theta0,
        }
    }

    /// K + μ at small strain: the scale of the stresses a strain makes.
    pub fn stiffness_scale(&self) -> f64 {
        match self {
            SolidLaw::NeoHooke(l) => l.K + l.mu,
            SolidLaw::MooneyRivlin(l) => l.K + l.shear_modulus(),
        }
    }

    /// The law as the vectorised kernel's Neo-Hooke, if it is one (others take the one-cell
    /// kernel, which needs only [`SolidLaw::stress`]).
    pub fn neo_hooke(&self) -> Option<&ThermoElastic> {
        match self {
            SolidLaw::NeoHooke(l) => Some(l),
            _ => None,
        }
    }
}
