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

/// The law's scalar functions of J, tr C and θ, from which its stress and tangent are built:
/// P = a F⁻ᵀ + m (F − ⅓ tr C F⁻ᵀ), and ∂P/∂F as in [`ThermoElastic::stress`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scalars {
    pub psi: f64,
    /// Coefficient of F⁻ᵀ from the volumetric and thermal parts: K ln J − 3 α (θ − θ0) K.
    pub a: f64,
    /// μ J^(−2/3).
    pub m: f64,
}

impl ThermoElastic {
    /// Ψ, a and m at J > 0, I1 = tr C and θ.
    #[inline(always)]
    pub fn scalars(&self, J: f64, I1: f64, theta: f64) -> Scalars {
        let lnJ = J.ln();
        let Jm23 = J.powf(-2.0 / 3.0);
        let c = 3.0 * self.alpha * (theta - self.theta0) * self.K;
        Scalars {
            psi: 0.5 * self.K * lnJ * lnJ + 0.5 * self.mu * (Jm23 * I1 - 3.0) - c * lnJ,
            a: self.K * lnJ - c,
            m: self.mu * Jm23,
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
        let Scalars { psi, a, m } = self.scalars(J, I1, theta);
        let P = H * a + (F - H * (I1 / 3.0)) * m;
        // A_iJkL = K H_kL H_iJ − a H_iL H_kJ
        //        + m (δ_ik δ_JL − ⅔ H_kL dev_iJ − ⅔ F_kL H_iJ + ⅓ I1 H_iL H_kJ),
        // dev = F − ⅓ I1 H, gathered as H_kL α_iJ + F_kL β_iJ + γ H_iL H_kJ + m δ_ik δ_JL
        let alpha = (H * self.K) - (F - H * (I1 / 3.0)) * (2.0 / 3.0 * m);
        let beta = H * (-2.0 / 3.0 * m);
        let gamma = m * I1 / 3.0 - a;
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
#[inline(always)]
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

/// Planes (a, b) of the rotation measures of eq. (16)–(17): f1 about z, f2 about y, f3 about x.
pub const ROTATION_PLANES: [(usize, usize); 3] = [(0, 1), (0, 2), (1, 2)];

/// A rotation measure f = (F_ab − F_ba)/(F_aa + F_bb) (= tan φ for a pure rotation in the
/// plane (a, b)) with its derivatives with respect to the four entries of F it depends on.
#[derive(Clone, Copy, Debug)]
pub struct RotationMeasure {
    pub f: f64,
    /// Entries (row, column) of F in the order ab, ba, aa, bb.
    pub entries: [(usize, usize); 4],
    /// ∂f/∂F at those entries.
    pub grad: [f64; 4],
    /// ∂²f/∂F∂F at those entries.
    pub hess: [[f64; 4]; 4],
}

/// The rotation measure of plane `ROTATION_PLANES[i]`; `None` when F_aa + F_bb = 0 (a rotation
/// of 90° in that plane, where tan φ is unbounded).
pub fn rotation_measure(F: &Matrix3<f64>, i: usize) -> Option<RotationMeasure> {
    let (a, b) = ROTATION_PLANES[i];
    let n = F[(a, b)] - F[(b, a)];
    let s = F[(a, a)] + F[(b, b)];
    if !(s.abs() > 1e-12) {
        return None;
    }
    let f = n / s;
    let (is, is2) = (1.0 / s, 1.0 / (s * s));
    let c = 2.0 * f * is2; // ∂²f/∂s² = 2 n / s³
    Some(RotationMeasure {
        f,
        entries: [(a, b), (b, a), (a, a), (b, b)],
        grad: [is, -is, -f * is, -f * is],
        hess: [
            [0.0, 0.0, -is2, -is2],
            [0.0, 0.0, is2, is2],
            [-is2, is2, c, c],
            [-is2, is2, c, c],
        ],
    })
}

/// Third derivatives of the rotation measure `i` with respect to its four entries of F (in
/// the order of [`RotationMeasure::entries`]); `None` where the measure is unbounded.
/// With n = F_ab − F_ba and s = F_aa + F_bb, f = n/s has f_nss = 2/s³ and f_sss = −6n/s⁴.
pub fn rotation_measure_d3(F: &Matrix3<f64>, i: usize) -> Option<[[[f64; 4]; 4]; 4]> {
    let (a, b) = ROTATION_PLANES[i];
    let n = F[(a, b)] - F[(b, a)];
    let s = F[(a, a)] + F[(b, b)];
    if !(s.abs() > 1e-12) {
        return None;
    }
    let dn = [1.0, -1.0, 0.0, 0.0];
    let ds = [0.0, 0.0, 1.0, 1.0];
    let (f_nss, f_sss) = (2.0 / (s * s * s), -6.0 * n / (s * s * s * s));
    Some(std::array::from_fn(|p| {
        std::array::from_fn(|q| {
            std::array::from_fn(|r| {
                f_sss * ds[p] * ds[q] * ds[r]
                    + f_nss
                        * (dn[p] * ds[q] * ds[r] + ds[p] * dn[q] * ds[r] + ds[p] * ds[q] * dn[r])
            })
        })
    }))
}

/// Regularization of the linear medium elements, eq. (20):
///
/// Ψ_Rf = Σ_i β1/2 (f_i − p_i/d)² + β2/2 |∇_X p_i|²
///
/// with auxiliary nodal fields p_i and d the largest extent of the undeformed mesh (eq. 21).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Regularization {
    pub beta1: f64,
    pub beta2: f64,
    pub d: f64,
}

impl Regularization {
    /// Energy density of one component and its first and second derivatives with respect to
    /// (f, p): returns (ψ, [∂ψ/∂f, ∂ψ/∂p], [[∂²ψ/∂f², ∂²ψ/∂f∂p], [·, ∂²ψ/∂p²]]) for the
    /// penalty part; the gradient part β2/2 |∇p|² is quadratic and handled by the caller.
    pub fn penalty(&self, f: f64, p: f64) -> (f64, [f64; 2], [[f64; 2]; 2]) {
        let id = 1.0 / self.d;
        let e = f - p * id;
        let b = self.beta1;
        (
            0.5 * b * e * e,
            [b * e, -b * e * id],
            [[b, -b * id], [-b * id, b * id * id]],
        )
    }
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
    #[test]
    fn rotation_measures_match_finite_differences() {
        for plane in [false, true] {
            let F = sample_F(plane);
            let n = if plane { 1 } else { 3 };
            for i in 0..n {
                let m = rotation_measure(&F, i).unwrap();
                // a rotation by φ in the plane gives tan φ
                let (a, b) = ROTATION_PLANES[i];
                let phi: f64 = 0.3;
                let mut R = Matrix3::identity();
                R[(a, a)] = phi.cos();
                R[(b, b)] = phi.cos();
                R[(a, b)] = phi.sin();
                R[(b, a)] = -phi.sin();
                assert!((rotation_measure(&R, i).unwrap().f - phi.tan()).abs() < 1e-14);
                let h = 1e-6;
                for (q, &(r, c)) in m.entries.iter().enumerate() {
                    let (mut p, mut mm) = (F, F);
                    p[(r, c)] += h;
                    mm[(r, c)] -= h;
                    let (fp, fm) = (
                        rotation_measure(&p, i).unwrap(),
                        rotation_measure(&mm, i).unwrap(),
                    );
                    let fd = (fp.f - fm.f) / (2.0 * h);
                    assert!((fd - m.grad[q]).abs() < 1e-8, "f{i} grad {q}");
                    for s in 0..4 {
                        let fd2 = (fp.grad[s] - fm.grad[s]) / (2.0 * h);
                        assert!((fd2 - m.hess[s][q]).abs() < 1e-7, "f{i} hess {s}{q}");
                    }
                }
                // entries outside the four do not change f
                for r in 0..3 {
                    for c in 0..3 {
                        if !m.entries.contains(&(r, c)) {
                            let mut p = F;
                            p[(r, c)] += 0.1;
                            assert_eq!(rotation_measure(&p, i).unwrap().f, m.f);
                        }
                    }
                }
            }
        }
        let mut F = Matrix3::identity();
        F[(0, 0)] = -1.0;
        assert!(rotation_measure(&F, 0).is_none());
    }

    #[test]
    fn rotation_measure_third_derivatives() {
        for plane in [false, true] {
            let F = sample_F(plane);
            for i in 0..if plane { 1 } else { 3 } {
                let m = rotation_measure(&F, i).unwrap();
                let d3 = rotation_measure_d3(&F, i).unwrap();
                let h = 1e-5;
                for (q, &(r, c)) in m.entries.iter().enumerate() {
                    let (mut p, mut mm) = (F, F);
                    p[(r, c)] += h;
                    mm[(r, c)] -= h;
                    let (hp, hm) = (
                        rotation_measure(&p, i).unwrap().hess,
                        rotation_measure(&mm, i).unwrap().hess,
                    );
                    for a in 0..4 {
                        for b in 0..4 {
                            let fd = (hp[a][b] - hm[a][b]) / (2.0 * h);
                            assert!((fd - d3[a][b][q]).abs() < 1e-6, "f{i} d3 {a}{b}{q}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn regularization_penalty_derivatives() {
        let reg = Regularization {
            beta1: 1.3,
            beta2: 1e-2,
            d: 2.5,
        };
        let (f, p) = (0.2, -0.4);
        let (_, g, hess) = reg.penalty(f, p);
        let h = 1e-6;
        let fd_f = (reg.penalty(f + h, p).0 - reg.penalty(f - h, p).0) / (2.0 * h);
        let fd_p = (reg.penalty(f, p + h).0 - reg.penalty(f, p - h).0) / (2.0 * h);
        assert!((fd_f - g[0]).abs() < 1e-8 && (fd_p - g[1]).abs() < 1e-8);
        for (a, da) in [(0, [h, 0.0]), (1, [0.0, h])] {
            let gp = reg.penalty(f + da[0], p + da[1]).1;
            let gm = reg.penalty(f - da[0], p - da[1]).1;
            for b in 0..2 {
                assert!(((gp[b] - gm[b]) / (2.0 * h) - hess[b][a]).abs() < 1e-8);
            }
        }
        // p = d f makes the penalty vanish
        assert!(reg.penalty(f, reg.d * f).0.abs() < 1e-30);
    }
}
