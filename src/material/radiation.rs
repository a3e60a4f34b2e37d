//! Surface radiation to surroundings at θ∞: heat leaving a boundary per unit current area,
//! q_n = ε σ (θ⁴ − θ∞⁴), temperatures absolute.

/// The radiation law of one boundary group.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Radiation {
    /// Emissivity ε in (0, 1].
    pub emissivity: f64,
    /// Temperature of the surroundings θ∞ > 0 (absolute).
    pub theta_inf: f64,
    /// Stefan–Boltzmann constant σ in the case's units (5.670374419e-8 W/(m² K⁴) in SI).
    pub sigma: f64,
}

impl Radiation {
    /// Outward heat flux per unit current area and its derivative in θ:
    /// (ε σ (θ⁴ − θ∞⁴), 4 ε σ θ³); `None` at θ ≤ 0 (or not finite), where an absolute
    /// temperature cannot be.
    #[inline]
    pub fn flux(&self, theta: f64) -> Option<(f64, f64)> {
        if !(theta > 0.0) || !theta.is_finite() {
            return None;
        }
        let es = self.emissivity * self.sigma;
        let t2 = theta * theta;
        let i2 = self.theta_inf * self.theta_inf;
        Some((es * (t2 * t2 - i2 * i2), 4.0 * es * t2 * theta))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAW: Radiation = Radiation {
        emissivity: 0.8,
        theta_inf: 300.0,
        sigma: 5.670374419e-8,
    };

    #[test]
    fn flux_and_its_derivative() {
        assert_eq!(LAW.flux(300.0).unwrap().0, 0.0);
        let (q, dq) = LAW.flux(400.0).unwrap();
        let exact = 0.8 * 5.670374419e-8 * (400f64.powi(4) - 300f64.powi(4));
        assert!((q - exact).abs() < 1e-12 * exact);
        let e = 1e-3;
        let fd = (LAW.flux(400.0 + e).unwrap().0 - LAW.flux(400.0 - e).unwrap().0) / (2.0 * e);
        assert!((fd - dq).abs() < 1e-8 * dq);
        // colder than the surroundings: heat comes in
        assert!(LAW.flux(250.0).unwrap().0 < 0.0);
    }

    #[test]
    fn no_absolute_temperature_at_or_below_zero() {
        assert!(LAW.flux(0.0).is_none());
        assert!(LAW.flux(-5.0).is_none());
        assert!(LAW.flux(f64::NAN).is_none());
    }
}
