//! The solid laws a region may choose (`law` on a `[[region]]`): one list, each law a file of
//! its own. The medium is always Neo-Hooke with K = μ = γ (eq. 13).
#![allow(non_snake_case)]

use super::{Coefficients, MooneyRivlin, Real, StressResponse, ThermoElastic};
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
    /// The bulk modulus K at small strain (friction's modulus in the medium scales with it).
    fn bulk_modulus(&self) -> f64;
    /// The energy and the stress and tangent in [`Coefficients`]' form (P = c_H F⁻ᵀ + m F, …)
    /// at J, I1 = tr C and θ, in any scalar type: the lane kernel evaluates them for four
    /// cells at once and contracts them with the shape gradients in O(N²) per point. A law
    /// of this form overrides it for speed; the default, `None`, makes the lane kernel
    /// contract the law's full ∂P/∂F from [`Stress::stress`], lane by lane, which is right
    /// for any law.
    #[inline(always)]
    fn isotropic_form<S: Real>(&self, _J: S, _I1: S, _theta: S) -> Option<(S, Coefficients<S>)> {
        None
    }
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
    fn bulk_modulus(&self) -> f64 {
        self.K
    }
    #[inline(always)]
    fn isotropic_form<S: Real>(&self, J: S, I1: S, theta: S) -> Option<(S, Coefficients<S>)> {
        let sc = self.scalars(J, I1, theta);
        Some((sc.psi, self.coefficients(&sc, I1)))
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
    fn bulk_modulus(&self) -> f64 {
        self.K
    }
}

/// A solid's stress law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SolidLaw {
    /// Eq. (12): the paper's law.
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

    /// The bulk modulus K at small strain.
    pub fn bulk_modulus(&self) -> f64 {
        crate::with_solid_law!(self, |l| Stress::bulk_modulus(l))
    }
}
