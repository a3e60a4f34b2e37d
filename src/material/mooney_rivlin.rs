//! The compressible Mooney-Rivlin law (Abaqus' form, D1 = 2/K) with the thermal expansion of
//! [`super::ThermoElastic`]: a solid law for rubbers, whose response in shear stiffens with
//! the second invariant.
#![allow(non_snake_case)]

use super::{StressResponse, Tensor4};
use nalgebra::Matrix3;

/// Ψ = C10 (Ī₁ − 3) + C01 (Ī₂ − 3) + K/2 (J − 1)² − 3 α (θ − θ0) K ln J,
///
/// Ī₁ = J^(−2/3) I₁ and Ī₂ = J^(−4/3) I₂ the invariants of the isochoric C̄ = J^(−2/3) C,
/// I₂ = ½ (I₁² − tr C²). At small strain: shear modulus μ = 2 (C10 + C01), bulk modulus K.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MooneyRivlin {
    pub C10: f64,
    pub C01: f64,
    pub K: f64,
    pub alpha: f64,
    pub theta0: f64,
}

impl MooneyRivlin {
    /// The small-strain shear modulus 2 (C10 + C01).
    pub fn shear_modulus(&self) -> f64 {
        2.0 * (self.C10 + self.C01)
    }

    /// Energy, stress and tangents; `None` when J ≤ 0 or not finite.
    pub fn stress(&self, F: &Matrix3<f64>, theta: f64) -> Option<StressResponse> {
        let J = F.determinant();
        if !(J > 0.0) || !J.is_finite() {
            return None;
        }
        let H = F.try_inverse()?.transpose(); // ∂J/∂F = J H
        let C = F.transpose() * F;
        let B = F * F.transpose();
        let FC = F * C;
        let I1 = C.trace();
        let I2 = 0.5 * (I1 * I1 - (C * C).trace());
        let (a, b) = (J.powf(-2.0 / 3.0), J.powf(-4.0 / 3.0));
        let (c10, c01, K) = (self.C10, self.C01, self.K);
        let dtheta = theta - self.theta0;
        // ∂Ī₁/∂F = a (2F − ⅔ I₁ H); ∂Ī₂/∂F = b (2 I₁ F − 2 F C − ⁴⁄₃ I₂ H)
        let dI1 = F * 2.0;
        let dI2 = F * (2.0 * I1) - FC * 2.0;
        let g1 = (dI1 - H * (2.0 / 3.0 * I1)) * a;
        let g2 = (dI2 - H * (4.0 / 3.0 * I2)) * b;
        // the volumetric and thermal part's coefficient of H
        let g = K * (J - 1.0) * J - 3.0 * self.alpha * K * dtheta;
        let P = g1 * c10 + g2 * c01 + H * g;
        let psi = c10 * (a * I1 - 3.0) + c01 * (b * I2 - 3.0) + 0.5 * K * (J - 1.0).powi(2)
            - 3.0 * self.alpha * K * dtheta * J.ln();
        let d = |p: usize, q: usize| if p == q { 1.0 } else { 0.0 };
        let dg = K * (2.0 * J - 1.0) * J;
        let mut A = Tensor4::zeros();
        for (i, Jc, k, L) in (0..81).map(|n| (n / 27, n / 9 % 3, n / 3 % 3, n % 3)) {
            let (hij, hkl, hil, hkj) = (H[(i, Jc)], H[(k, L)], H[(i, L)], H[(k, Jc)]);
            let (fij, fkl) = (F[(i, Jc)], F[(k, L)]);
            let dik_djl = d(i, k) * d(Jc, L);
            // ∂/∂F_kL of a (2F − ⅔ I₁ H)_iJ
            let t1 = -2.0 / 3.0 * hkl * g1[(i, Jc)]
                + a * (2.0 * dik_djl - 4.0 / 3.0 * fkl * hij + 2.0 / 3.0 * I1 * hil * hkj);
            // ∂/∂F_kL of b (2 I₁ F − 2 F C − ⁴⁄₃ I₂ H)_iJ
            let dFC = d(i, k) * C[(L, Jc)] + F[(i, L)] * F[(k, Jc)] + B[(i, k)] * d(Jc, L);
            let t2 = -4.0 / 3.0 * hkl * g2[(i, Jc)]
                + b * (4.0 * fkl * fij + 2.0 * I1 * dik_djl
                    - 2.0 * dFC
                    - 4.0 / 3.0 * dI2[(k, L)] * hij
                    + 4.0 / 3.0 * I2 * hil * hkj);
            let t3 = dg * hij * hkl - g * hil * hkj;
            A[(3 * i + Jc, 3 * k + L)] = c10 * t1 + c01 * t2 + t3;
        }
        Some(StressResponse {
            psi,
            P,
            dP_dF: A,
            dP_dtheta: H * (-3.0 * self.alpha * K),
            J,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAW: MooneyRivlin = MooneyRivlin {
        C10: 3.0,
        C01: 1.5,
        K: 20.0,
        alpha: 1e-2,
        theta0: 20.0,
    };

    #[test]
    fn stress_and_tangents_are_derivatives() {
        crate::material::check_stress_law(|F, theta| LAW.stress(F, theta));
    }

    #[test]
    fn small_strain_moduli_are_twice_c10_plus_c01_and_k() {
        let r = LAW.stress(&Matrix3::identity(), LAW.theta0).unwrap();
        assert!(r.P.norm() < 1e-14 && r.psi.abs() < 1e-14);
        let mu = LAW.shear_modulus();
        let lambda = LAW.K - 2.0 / 3.0 * mu;
        let d = |p: usize, q: usize| if p == q { 1.0 } else { 0.0 };
        for (i, J, k, L) in (0..81).map(|n| (n / 27, n / 9 % 3, n / 3 % 3, n % 3)) {
            let c = lambda * d(i, J) * d(k, L) + mu * (d(i, k) * d(J, L) + d(i, L) * d(k, J));
            let a = r.dP_dF[(3 * i + J, 3 * k + L)];
            assert!((a - c).abs() < 1e-12 * LAW.K, "A{i}{J}{k}{L}: {a} vs {c}");
        }
    }

    /// Without C01 and at J = 1 the law is Neo-Hooke's with μ = 2 C10 (the volumetric parts
    /// differ only away from J = 1).
    #[test]
    fn without_c01_isochoric_stress_is_neo_hookes() {
        let nh = super::super::ThermoElastic {
            K: LAW.K,
            mu: 2.0 * LAW.C10,
            alpha: 0.0,
            theta0: 0.0,
        };
        let mr = MooneyRivlin {
            C01: 0.0,
            alpha: 0.0,
            theta0: 0.0,
            ..LAW
        };
        // a simple shear, J = 1
        let F = Matrix3::new(1.0, 0.4, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        let (a, b) = (mr.stress(&F, 0.0).unwrap(), nh.stress(&F, 0.0).unwrap());
        assert!((a.P - b.P).norm() < 1e-13 * b.P.norm());
        // at J = 1 the volumetric tangents agree too: K H ⊗ H for both
        assert!((a.dP_dF - b.dP_dF).norm() < 1e-13 * b.dP_dF.norm());
        assert!((a.psi - b.psi).abs() < 1e-13);
    }

    #[test]
    fn inverted_point_is_rejected() {
        let F = Matrix3::new(-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert!(LAW.stress(&F, 0.0).is_none());
    }
}
