//! The heat-flux laws a boundary group may carry (`[[bc]]` keys `h` and `radiation`): one
//! list, each law a file of its own.

use super::{Convection, Radiation};

/// Heat leaving a boundary per unit current area, as a function of the temperature there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoundaryFlux {
    /// h (θ − θ∞).
    Convection(Convection),
    /// ε σ (θ⁴ − θ∞⁴).
    Radiation(Radiation),
}

impl BoundaryFlux {
    /// The flux and its derivative in θ; `None` where the law has no value at θ (radiation
    /// at θ ≤ 0).
    #[inline]
    pub fn flux(&self, theta: f64) -> Option<(f64, f64)> {
        match self {
            BoundaryFlux::Convection(l) => Some(l.flux(theta)),
            BoundaryFlux::Radiation(l) => l.flux(theta),
        }
    }

    /// Whether the flux grows with θ everywhere it is defined, so that a body losing heat
    /// through it has a unique stationary temperature.
    pub fn anchors_temperature(&self) -> bool {
        match self {
            BoundaryFlux::Convection(l) => l.h > 0.0,
            BoundaryFlux::Radiation(l) => l.emissivity * l.sigma > 0.0,
        }
    }
}
