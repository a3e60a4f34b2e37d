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

    /// The temperature at which no heat flows: θ∞.
    pub fn ambient(&self) -> f64 {
        match self {
            BoundaryFlux::Convection(l) => l.theta_inf,
            BoundaryFlux::Radiation(l) => l.theta_inf,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// At its ambient temperature no law moves heat, and an anchoring law moves it towards it.
    #[test]
    fn no_heat_flows_at_the_ambient_temperature() {
        for q in [
            BoundaryFlux::Convection(Convection {
                h: 3.0,
                theta_inf: 20.0,
            }),
            BoundaryFlux::Radiation(Radiation {
                emissivity: 0.8,
                theta_inf: 293.15,
                sigma: 5.670374419e-8,
            }),
        ] {
            let t = q.ambient();
            assert!(q.anchors_temperature());
            assert_eq!(q.flux(t).unwrap().0, 0.0, "{q:?}");
            assert!(q.flux(t + 1.0).unwrap().0 > 0.0 && q.flux(t - 1.0).unwrap().0 < 0.0);
        }
    }
}
