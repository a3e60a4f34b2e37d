//! The thermo-elastic compressible Neo-Hooke law of eq. (12), shared by the solids and the
//! third medium (eq. 13, K = μ = γ).
#![allow(non_snake_case)]

use super::{Real, Tensor4};
use nalgebra::Matrix3;

/// Thermo-elastic compressible Neo-Hooke law of eq. (12), mechanical part:
///
/// Ψ = K/2 (ln J)² + μ/2 (J^(−2/3) tr C − 3) − 3 α (θ − θ0) K ln J.
///
/// The third medium uses the same law with K = μ = γ (eq. 13).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThermoElastic {
    pub K: f64,
    pub mu: f64,
    pub alpha: f64,
    pub theta0: f64,
}

/// Stress response at one point.
#[derive(Clone, Debug)]
pub struct StressResponse {
    /// Ψ (the expansion term evaluated with θ held fixed)
    pub psi: f64,
    /// First Piola–Kirchhoff stress P = ∂Ψ/∂F.
    pub P: Matrix3<f64>,
    /// ∂P/∂F.
    pub dP_dF: Tensor4,
    /// ∂P/∂θ (thermal expansion coupling).
    pub dP_dtheta: Matrix3<f64>,
    pub J: f64,
}

/// The law's scalar functions of J, tr C and θ, from which its stress and tangent are built
/// (see [`Coefficients`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scalars<S = f64> {
    pub psi: S,
    /// Coefficient of F⁻ᵀ from the volumetric and thermal parts: K ln J − 3 α (θ − θ0) K.
    pub a: S,
    /// μ J^(−2/3).
    pub m: S,
}

/// The stress and its derivatives as combinations of H = F⁻ᵀ and F, I1 = tr C:
///
/// P = c_H H + m F,
/// ∂P_iJ/∂F_kL = c1 H_iJ H_kL + c2 H_iL H_kJ + t (F_iJ H_kL + H_iJ F_kL) + m δ_ik δ_JL,
/// ∂P/∂θ = e H.
///
/// The lane kernel contracts them with the shape gradients directly; the one-cell kernel's
/// 9 × 9 ∂P/∂F ([`ThermoElastic::stress`]) is the same tensor from the same scalars, grouped
/// around the deviator (tested equal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficients<S = f64> {
    /// a − ⅓ m I1.
    pub c_H: S,
    /// μ J^(−2/3).
    pub m: S,
    /// K + 2⁄9 m I1.
    pub c1: S,
    /// ⅓ m I1 − a.
    pub c2: S,
    /// −⅔ m.
    pub t: S,
    /// −3 α K.
    pub e: S,
}

impl ThermoElastic {
    /// Ψ, a and m at J > 0, I1 = tr C and θ.
    #[inline(always)]
    pub fn scalars<S: Real>(&self, J: S, I1: S, theta: S) -> Scalars<S> {
        let lnJ = J.ln();
        let Jm23 = J.powf(-2.0 / 3.0);
        let c = S::splat(3.0 * self.alpha) * (theta - S::splat(self.theta0)) * S::splat(self.K);
        let (K, mu) = (S::splat(self.K), S::splat(self.mu));
        Scalars {
            psi: S::splat(0.5 * self.K) * lnJ * lnJ
                + S::splat(0.5 * self.mu) * (Jm23 * I1 - S::splat(3.0))
                - c * lnJ,
            a: K * lnJ - c,
            m: mu * Jm23,
        }
    }

    /// The coefficients of the stress and its derivatives from the scalars at I1 = tr C.
    #[inline(always)]
    pub fn coefficients<S: Real>(&self, sc: &Scalars<S>, I1: S) -> Coefficients<S> {
        let third = I1 * S::splat(1.0 / 3.0);
        Coefficients {
            c_H: sc.a - sc.m * third,
            m: sc.m,
            c1: S::splat(self.K) + S::splat(2.0 / 3.0) * sc.m * third,
            c2: sc.m * third - sc.a,
            t: S::splat(-2.0 / 3.0) * sc.m,
            e: S::splat(-3.0 * self.alpha * self.K),
        }
    }

    /// Energy, stress and tangents; `None` when J ≤ 0 or not finite.
    #[inline(always)]
    pub fn stress(&self, F: &Matrix3<f64>, theta: f64) -> Option<StressResponse> {
        let J = F.determinant();
        if !(J > 0.0) || !J.is_finite() {
            return None;
        }
        let Finv = F.try_inverse()?;
        let H = Finv.transpose(); // F⁻ᵀ = ∂J/∂F / J
        let I1 = F.norm_squared(); // tr C
        let sc = self.scalars(J, I1, theta);
        let (a, m) = (sc.a, sc.m);
        // the same tensors as `coefficients` (tested below), grouped around the deviator
        // dev = F − ⅓ I1 H: 10 % faster in the one-cell kernel than c_H H + m F, c1 H + t F
        // (benches/kernel.rs, H1 and Q1 rows)
        let P = H * a + (F - H * (I1 / 3.0)) * m;
        let alpha = (H * self.K) - (F - H * (I1 / 3.0)) * (2.0 / 3.0 * m);
        let beta = H * (-2.0 / 3.0 * m);
        let gamma = m * I1 / 3.0 - a;
        let e = -3.0 * self.alpha * self.K;
        let mut A = Tensor4::zeros();
        for L in 0..3 {
            for k in 0..3 {
                let (hkl, fkl) = (H[(k, L)], F[(k, L)]);
                let s = 3 * k + L;
                for Jc in 0..3 {
                    let ghkj = gamma * H[(k, Jc)];
                    for i in 0..3 {
                        A[(3 * i + Jc, s)] =
                            hkl * alpha[(i, Jc)] + fkl * beta[(i, Jc)] + ghkj * H[(i, L)];
                    }
                }
            }
        }
        for r in 0..9 {
            A[(r, r)] += m;
        }
        let dP_dtheta = H * e;
        let psi = sc.psi;
        Some(StressResponse {
            psi,
            P,
            dP_dF: A,
            dP_dtheta,
            J,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::sample_F;

    const LAW: ThermoElastic = ThermoElastic {
        K: 20.0,
        mu: 10.0,
        alpha: 1e-2,
        theta0: 20.0,
    };

    #[test]
    fn stress_and_tangents_are_derivatives() {
        crate::material::check_stress_law(|F, theta| LAW.stress(F, theta));
    }

    #[test]
    fn stress_free_reference_and_free_expansion() {
        let r = LAW.stress(&Matrix3::identity(), LAW.theta0).unwrap();
        assert!(r.P.norm() < 1e-14);
        // free thermal expansion: F = J^(1/3) I with J = exp(3 α Δθ) has P = 0
        let dtheta = 15.0;
        let J: f64 = (3.0 * LAW.alpha * dtheta).exp();
        let r = LAW
            .stress(&(Matrix3::identity() * J.cbrt()), LAW.theta0 + dtheta)
            .unwrap();
        assert!(r.P.norm() < 1e-12, "{}", r.P);
    }

    #[test]
    fn coefficients_give_the_stress_and_tangent_of_stress() {
        for plane in [false, true] {
            let F = sample_F(plane);
            let theta = 55.0;
            let r = LAW.stress(&F, theta).unwrap();
            let H = F.try_inverse().unwrap().transpose();
            let I1 = F.norm_squared();
            let co = LAW.coefficients(&LAW.scalars(r.J, I1, theta), I1);
            let P = H * co.c_H + F * co.m;
            assert!((P - r.P).norm() < 1e-13 * r.P.norm());
            assert!((H * co.e - r.dP_dtheta).norm() < 1e-15);
            let d = |a: usize, b: usize| if a == b { 1.0 } else { 0.0 };
            for (i, J, k, L) in (0..81).map(|n| (n / 27, n / 9 % 3, n / 3 % 3, n % 3)) {
                let A = co.c1 * H[(i, J)] * H[(k, L)]
                    + co.c2 * H[(i, L)] * H[(k, J)]
                    + co.t * (F[(i, J)] * H[(k, L)] + H[(i, J)] * F[(k, L)])
                    + co.m * d(i, k) * d(J, L);
                let a = r.dP_dF[(3 * i + J, 3 * k + L)];
                assert!((A - a).abs() < 1e-13 * r.dP_dF.amax(), "A{i}{J}{k}{L}");
            }
        }
    }

    #[test]
    fn inverted_point_is_rejected() {
        let F = Matrix3::new(-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert!(LAW.stress(&F, 0.0).is_none());
    }
}
