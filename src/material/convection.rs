//! Convection (a Robin condition): heat leaving a boundary per unit current area,
//! q_n = h (θ − θ∞), with h ≥ 0 the heat transfer coefficient and θ∞ the ambient temperature.

/// The convection law of one boundary group.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Convection {
    /// Heat transfer coefficient h ≥ 0 (heat per unit current area, time and temperature).
    pub h: f64,
    /// Ambient temperature θ∞.
    pub theta_inf: f64,
}

impl Convection {
    /// Outward heat flux per unit current area and its derivative in θ: (h (θ − θ∞), h).
    #[inline]
    pub fn flux(&self, theta: f64) -> (f64, f64) {
        (self.h * (theta - self.theta_inf), self.h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flux_and_its_derivative() {
        let law = Convection {
            h: 7.5,
            theta_inf: 20.0,
        };
        assert_eq!(law.flux(20.0).0, 0.0);
        let (q, dq) = law.flux(30.0);
        assert_eq!(q, 75.0);
        let e = 1e-3;
        let fd = (law.flux(30.0 + e).0 - law.flux(30.0 - e).0) / (2.0 * e);
        assert!((fd - dq).abs() < 1e-9);
    }
}
