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
    /// K + μ at small strain: the scale of the stresses a strain makes.
    fn stiffness_scale(&self) -> f64;
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
    fn stiffness_scale(&self) -> f64 {
        self.K + self.mu
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
    fn stiffness_scale(&self) -> f64 {
        self.K + self.shear_modulus()
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

/// `$body` with `$l` bound to the law a `&SolidLaw` holds, as its own type (a [`Stress`]):
/// the one place that lists the solid laws, so that a generic body is compiled per law.
#[macro_export]
macro_rules! with_solid_law {
    ($law:expr, |$l:ident| $body:expr) => {
        match $law {
            $crate::material::SolidLaw::NeoHooke($l) => $body,
            $crate::material::SolidLaw::MooneyRivlin($l) => $body,
        }
    };
}

impl SolidLaw {
    /// Energy, stress and tangents; `None` when J ≤ 0 or not finite.
    #[inline(always)]
    pub fn stress(&self, F: &Matrix3<f64>, theta: f64) -> Option<StressResponse> {
        crate::with_solid_law!(self, |l| Stress::stress(l, F, theta))
    }

    /// The temperature at which the law is free of thermal stress.
    pub fn theta0(&self) -> f64 {
        crate::with_solid_law!(self, |l| Stress::theta0(l))
    }

    /// K + μ at small strain: the scale of the stresses a strain makes.
    pub fn stiffness_scale(&self) -> f64 {
        crate::with_solid_law!(self, |l| Stress::stiffness_scale(l))
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
