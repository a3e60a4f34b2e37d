//! Pure material laws: functions of a point's kinematics returning stresses, fluxes and their
//! exact derivatives. They know nothing of meshes or dofs.
//!
//! Tensors are 3×3 even in 2D (plane strain: F33 = 1, 3D invariants). Fourth-order tangents
//! are stored as 9×9 matrices with the index pair (i, J) ↦ 3 i + J.
#![allow(non_snake_case)]

use nalgebra::{Matrix3, SMatrix, Vector3};

/// 9×9 storage of a fourth-order tensor A_iJkL at (3i+J, 3k+L).
pub type Tensor4 = SMatrix<f64, 9, 9>;
/// 3×9 storage of a third-order tensor B_I,kL at (I, 3k+L).
pub type Tensor3 = SMatrix<f64, 3, 9>;

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

impl ThermoElastic {
    /// Energy, stress and tangents; `None` when J ≤ 0 or not finite.
    pub fn stress(&self, F: &Matrix3<f64>, theta: f64) -> Option<StressResponse> {
        let J = F.determinant();
        if !(J > 0.0) || !J.is_finite() {
            return None;
        }
        let Finv = F.try_inverse()?;
        let H = Finv.transpose(); // F⁻ᵀ = ∂J/∂F / J
        let lnJ = J.ln();
        let I1 = F.norm_squared(); // tr C
        let Jm23 = J.powf(-2.0 / 3.0);
        let c = 3.0 * self.alpha * (theta - self.theta0) * self.K;
        let psi = 0.5 * self.K * lnJ * lnJ + 0.5 * self.mu * (Jm23 * I1 - 3.0) - c * lnJ;
        let a = self.K * lnJ - c; // coefficient of F⁻ᵀ from the volumetric and thermal parts
        let m = self.mu * Jm23;
        let P = H * a + (F - H * (I1 / 3.0)) * m;
        let mut A = Tensor4::zeros();
        for i in 0..3 {
            for Jc in 0..3 {
                let r = 3 * i + Jc;
                let dev = F[(i, Jc)] - I1 / 3.0 * H[(i, Jc)];
                for k in 0..3 {
                    for L in 0..3 {
                        let s = 3 * k + L;
                        let mut v = self.K * H[(k, L)] * H[(i, Jc)] - a * H[(i, L)] * H[(k, Jc)];
                        let mut w = -2.0 / 3.0 * H[(k, L)] * dev
                            - 2.0 / 3.0 * F[(k, L)] * H[(i, Jc)]
                            + I1 / 3.0 * H[(i, L)] * H[(k, Jc)];
                        if i == k && Jc == L {
                            w += 1.0;
                        }
                        v += m * w;
                        A[(r, s)] = v;
                    }
                }
            }
        }
        let dP_dtheta = H * (-3.0 * self.alpha * self.K);
        Some(StressResponse {
            psi,
            P,
            dP_dF: A,
            dP_dtheta,
            J,
        })
    }
}

/// Conductivity as a function of the volume ratio J: k(J) and dk/dJ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Conductivity {
    /// Constant k (solids, eq. 10).
    Constant(f64),
    /// Third medium: k(J) = min(k_TM (1 + (ln J)²), k_max) — SPEC's reading of eq. (15).
    Medium { k_tm: f64, k_max: f64 },
}

impl Conductivity {
    /// (k, dk/dJ).
    pub fn eval(&self, J: f64) -> (f64, f64) {
        match *self {
            Conductivity::Constant(k) => (k, 0.0),
            Conductivity::Medium { k_tm, k_max } => {
                let l = J.ln();
                let k = k_tm * (1.0 + l * l);
                if k >= k_max {
                    (k_max, 0.0)
                } else {
                    (k, 2.0 * k_tm * l / J)
                }
            }
        }
    }
}

/// Heat flux response at one point.
#[derive(Clone, Debug)]
pub struct HeatResponse {
    /// Nominal heat flux Q = −J k(J) C⁻¹ ∇_X θ (eq. 10, 14).
    pub Q: Vector3<f64>,
    /// ∂Q/∂(∇_X θ) = −J k C⁻¹.
    pub dQ_dgrad: Matrix3<f64>,
    /// ∂Q/∂F.
    pub dQ_dF: Tensor3,
    /// Effective conductivity k(J).
    pub k: f64,
}

/// Pulled-back Fourier law Q = −J k(J) C⁻¹ ∇_X θ and its exact derivatives.
pub fn fourier(
    F: &Matrix3<f64>,
    grad_theta: &Vector3<f64>,
    law: &Conductivity,
) -> Option<HeatResponse> {
    let J = F.determinant();
    if !(J > 0.0) || !J.is_finite() {
        return None;
    }
    let Finv = F.try_inverse()?;
    let Cinv = Finv * Finv.transpose();
    let (k, dk_dJ) = law.eval(J);
    let Jk = J * k;
    let h = Cinv * grad_theta; // C⁻¹ g
    let Q = -h * Jk;
    let fg = Finv.transpose() * grad_theta; // F⁻ᵀ g
    // d(J k)/dF_kL = (k + J dk/dJ) J F⁻ᵀ_kL
    let dJk = (k + J * dk_dJ) * J;
    let mut B = Tensor3::zeros();
    for I in 0..3 {
        for kk in 0..3 {
            for L in 0..3 {
                // d(C⁻¹ g)_I/dF_kL = −F⁻¹_Ik (C⁻¹g)_L − C⁻¹_IL (F⁻ᵀ g)_k
                let dh = -Finv[(I, kk)] * h[L] - Cinv[(I, L)] * fg[kk];
                B[(I, 3 * kk + L)] = -(dJk * Finv[(L, kk)] * h[I] + Jk * dh);
            }
        }
    }
    Some(HeatResponse {
        Q,
        dQ_dgrad: -Cinv * Jk,
        dQ_dF: B,
        k,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_F(plane: bool) -> Matrix3<f64> {
        if plane {
            Matrix3::new(1.2, 0.3, 0.0, -0.15, 0.8, 0.0, 0.0, 0.0, 1.0)
        } else {
            Matrix3::new(1.1, 0.2, -0.1, 0.05, 0.9, 0.15, -0.2, 0.1, 1.3)
        }
    }

    const LAW: ThermoElastic = ThermoElastic {
        K: 20.0,
        mu: 10.0,
        alpha: 1e-2,
        theta0: 20.0,
    };

    #[test]
    fn stress_is_derivative_of_energy() {
        for plane in [false, true] {
            let F = sample_F(plane);
            let r = LAW.stress(&F, 70.0).unwrap();
            let h = 1e-6;
            for i in 0..3 {
                for j in 0..3 {
                    let (mut p, mut m) = (F, F);
                    p[(i, j)] += h;
                    m[(i, j)] -= h;
                    let fd = (LAW.stress(&p, 70.0).unwrap().psi
                        - LAW.stress(&m, 70.0).unwrap().psi)
                        / (2.0 * h);
                    assert!(
                        (fd - r.P[(i, j)]).abs() < 1e-7 * (1.0 + fd.abs()),
                        "P{i}{j}: {fd} vs {}",
                        r.P[(i, j)]
                    );
                }
            }
        }
    }

    #[test]
    fn tangent_is_derivative_of_stress() {
        for plane in [false, true] {
            let F = sample_F(plane);
            let r = LAW.stress(&F, 70.0).unwrap();
            let h = 1e-6;
            for k in 0..3 {
                for l in 0..3 {
                    let (mut p, mut m) = (F, F);
                    p[(k, l)] += h;
                    m[(k, l)] -= h;
                    let dP = (LAW.stress(&p, 70.0).unwrap().P - LAW.stress(&m, 70.0).unwrap().P)
                        / (2.0 * h);
                    for i in 0..3 {
                        for j in 0..3 {
                            let a = r.dP_dF[(3 * i + j, 3 * k + l)];
                            assert!(
                                (dP[(i, j)] - a).abs() < 1e-6 * (1.0 + a.abs()),
                                "A{i}{j}{k}{l}"
                            );
                        }
                    }
                }
            }
            // major symmetry (hyperelastic)
            assert!((r.dP_dF - r.dP_dF.transpose()).norm() < 1e-12);
            // θ coupling
            let h = 1e-4;
            let dP = (LAW.stress(&F, 70.0 + h).unwrap().P - LAW.stress(&F, 70.0 - h).unwrap().P)
                / (2.0 * h);
            assert!((dP - r.dP_dtheta).norm() < 1e-9);
        }
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
    fn inverted_point_is_rejected() {
        let F = Matrix3::new(-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert!(LAW.stress(&F, 0.0).is_none());
        assert!(fourier(&F, &Vector3::x(), &Conductivity::Constant(1.0)).is_none());
    }

    fn check_fourier(law: Conductivity, F: Matrix3<f64>) {
        let g = Vector3::new(0.7, -1.3, 0.4);
        let r = fourier(&F, &g, &law).unwrap();
        // step relative to the smallest stretch, so a strongly compressed F is resolved
        let h = 1e-6 * F.singular_values().min();
        for k in 0..3 {
            for l in 0..3 {
                let (mut p, mut m) = (F, F);
                p[(k, l)] += h;
                m[(k, l)] -= h;
                let dQ = (fourier(&p, &g, &law).unwrap().Q - fourier(&m, &g, &law).unwrap().Q)
                    / (2.0 * h);
                let scale = r.dQ_dF.amax();
                for i in 0..3 {
                    let b = r.dQ_dF[(i, 3 * k + l)];
                    assert!(
                        (dQ[i] - b).abs() < 1e-6 * scale,
                        "B{i}{k}{l}: {} vs {b}",
                        dQ[i]
                    );
                }
            }
        }
        // Q is linear in ∇θ: a large step is exact up to round-off
        let h = 1e-2;
        for j in 0..3 {
            let mut e = Vector3::zeros();
            e[j] = h;
            let dQ = (fourier(&F, &(g + e), &law).unwrap().Q
                - fourier(&F, &(g - e), &law).unwrap().Q)
                / (2.0 * h);
            assert!((dQ - r.dQ_dgrad.column(j)).norm() < 1e-10 * r.dQ_dgrad.amax());
        }
        // the conduction tangent is symmetric and negative definite in ∇θ
        assert!((r.dQ_dgrad - r.dQ_dgrad.transpose()).norm() < 1e-12);
        assert!(r.dQ_dgrad.symmetric_eigenvalues().iter().all(|&v| v < 0.0));
    }

    #[test]
    fn heat_flux_derivatives() {
        for plane in [false, true] {
            check_fourier(Conductivity::Constant(3.0), sample_F(plane));
            check_fourier(
                Conductivity::Medium {
                    k_tm: 0.5,
                    k_max: 100.0,
                },
                sample_F(plane),
            );
            // compressed medium at the cap: k = k_max, dk/dJ = 0
            let F = Matrix3::from_diagonal(&Vector3::new(1.0, 1e-3, 1.0));
            check_fourier(
                Conductivity::Medium {
                    k_tm: 0.5,
                    k_max: 10.0,
                },
                F,
            );
        }
    }

    #[test]
    fn medium_conductivity_rises_from_k_tm_to_k_max() {
        let law = Conductivity::Medium {
            k_tm: 1.0,
            k_max: 100.0,
        };
        assert_eq!(law.eval(1.0).0, 1.0);
        assert!(law.eval(0.1).0 > 1.0);
        assert_eq!(law.eval(1e-6).0, 100.0);
        let (k, dk) = law.eval(0.5);
        let h = 1e-7;
        let fd = (law.eval(0.5 + h).0 - law.eval(0.5 - h).0) / (2.0 * h);
        assert!((fd - dk).abs() < 1e-6 && k > 1.0);
    }
}
