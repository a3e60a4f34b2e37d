//! Heat conduction: the Fourier law pulled back to the reference configuration (eq. 10) with
//! a conductivity that may depend on the volume ratio J (the medium's, eq. 15 as
//! docs/THEORY.md reads it).
#![allow(non_snake_case)]

use super::{Real, Tensor3};
use nalgebra::{Matrix3, Vector3};

/// Most points of a conductivity table.
pub const TABLE_POINTS: usize = 8;

/// Conductivity as a function of the volume ratio J: k(J) and dk/dJ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Conductivity {
    /// Constant k (solids, eq. 10).
    Constant(f64),
    /// Third medium: k(J) = min(k_TM (1 + (ln J)²), k_max) — THEORY.md's reading of eq. (15).
    Medium { k_tm: f64, k_max: f64 },
    /// A medium's k(J) as a table: linear in J between its `n` points (J increasing), the
    /// end values beyond them.
    Table {
        n: usize,
        J: [f64; TABLE_POINTS],
        k: [f64; TABLE_POINTS],
    },
    /// The paper's law with the conductance across a closed layer bounded by h_c:
    /// k(J) = min(k_TM (1 + (ln J)²), k_max, h_c t0 J), t0 the layer's undeformed thickness
    /// (`hc_t0` = h_c t0). A layer of thickness t0 squeezed to J t0 conducts k / (J t0) per
    /// area and degree: at most h_c.
    Closed { k_tm: f64, k_max: f64, hc_t0: f64 },
}

impl Conductivity {
    /// (k, dk/dJ).
    #[inline(always)]
    pub fn eval<S: Real>(&self, J: S) -> (S, S) {
        match *self {
            Conductivity::Constant(k) => (S::splat(k), S::splat(0.0)),
            Conductivity::Medium { k_tm, k_max } => {
                let l = J.ln();
                let k = S::splat(k_tm) * (S::splat(1.0) + l * l);
                let cap = S::splat(k_max);
                (
                    k.select_ge(cap, cap, k),
                    k.select_ge(cap, S::splat(0.0), S::splat(2.0 * k_tm) * l / J),
                )
            }
            Conductivity::Table {
                n,
                J: ref js,
                k: ref ks,
            } => {
                // the last point at or below J decides
                let (mut k, mut dk) = (S::splat(ks[0]), S::splat(0.0));
                for i in 0..n - 1 {
                    let slope = (ks[i + 1] - ks[i]) / (js[i + 1] - js[i]);
                    let at = S::splat(js[i]);
                    let line = S::splat(ks[i]) + S::splat(slope) * (J - at);
                    k = J.select_ge(at, line, k);
                    dk = J.select_ge(at, S::splat(slope), dk);
                }
                let last = S::splat(js[n - 1]);
                (
                    J.select_ge(last, S::splat(ks[n - 1]), k),
                    J.select_ge(last, S::splat(0.0), dk),
                )
            }
            Conductivity::Closed { k_tm, k_max, hc_t0 } => {
                let (k, dk) = Conductivity::Medium { k_tm, k_max }.eval(J);
                let closed = S::splat(hc_t0) * J;
                (
                    k.select_ge(closed, closed, k),
                    k.select_ge(closed, S::splat(hc_t0), dk),
                )
            }
        }
    }

    /// The largest k the law gives.
    pub fn k_max(&self) -> f64 {
        match *self {
            Conductivity::Constant(k) => k,
            Conductivity::Medium { k_max, .. } | Conductivity::Closed { k_max, .. } => k_max,
            Conductivity::Table { n, k, .. } => k[..n].iter().fold(0.0, |a: f64, &b| a.max(b)),
        }
    }

    /// The pulled-back conductance of Q = −(J k) C⁻¹ ∇_X θ: (k, J k, (k + J k') J), the last
    /// being the factor of ∂(J k)/∂F = (k + J k') J F⁻ᵀ.
    #[inline(always)]
    pub fn conductance<S: Real>(&self, J: S) -> (S, S, S) {
        let (k, dk) = self.eval(J);
        (k, J * k, (k + J * dk) * J)
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
    let (k, Jk, dJk) = law.conductance(J);
    let h = Cinv * grad_theta; // C⁻¹ g
    let Q = -h * Jk;
    let fg = Finv.transpose() * grad_theta; // F⁻ᵀ g
    // d(J k)/dF_kL = dJk F⁻ᵀ_kL
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
    use crate::material::sample_F;

    #[test]
    fn inverted_point_is_rejected() {
        let F = Matrix3::new(-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
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

    /// A table through (0.01, 2), (0.1, 0.5), (1, 0.1).
    fn table() -> Conductivity {
        let (mut J, mut k) = ([0.0; TABLE_POINTS], [0.0; TABLE_POINTS]);
        J[..3].copy_from_slice(&[0.01, 0.1, 1.0]);
        k[..3].copy_from_slice(&[2.0, 0.5, 0.1]);
        Conductivity::Table { n: 3, J, k }
    }

    #[test]
    fn a_table_is_linear_between_its_points_and_constant_beyond() {
        let law = table();
        for (J, k) in [(0.01, 2.0), (0.1, 0.5), (1.0, 0.1), (1e-4, 2.0), (3.0, 0.1)] {
            assert!((law.eval(J).0 - k).abs() < 1e-15, "k({J})");
        }
        // between (0.1, 0.5) and (0.01, 2): 0.5 + 1.5 × 0.05 / 0.09
        assert!((law.eval(0.05).0 - (0.5 + 1.5 * 0.05 / 0.09)).abs() < 1e-14);
        for J in [0.003, 0.05, 0.4, 2.0] {
            let (_, dk) = law.eval(J);
            let h = 1e-7 * J;
            let fd = (law.eval(J + h).0 - law.eval(J - h).0) / (2.0 * h);
            assert!(
                (fd - dk).abs() < 1e-6 * (1.0 + dk.abs()),
                "dk/dJ at {J}: {dk} vs {fd}"
            );
        }
        assert_eq!(law.k_max(), 2.0);
        for plane in [false, true] {
            check_fourier(law, sample_F(plane));
        }
    }

    #[test]
    fn a_closed_layer_conducts_at_most_h_c() {
        let (k_tm, k_max, hc, t0) = (0.1, 100.0, 50.0, 0.25);
        let law = Conductivity::Closed {
            k_tm,
            k_max,
            hc_t0: hc * t0,
        };
        // open: the paper's law; squeezed: the conductance k / (J t0) is h_c
        assert_eq!(law.eval(1.0).0, k_tm);
        for J in [1e-2, 1e-3, 1e-5] {
            let (k, dk) = law.eval(J);
            assert!((k / (J * t0) - hc).abs() < 1e-12 * hc, "J = {J}");
            assert_eq!(dk, hc * t0);
        }
        let F = Matrix3::from_diagonal(&Vector3::new(1.0, 1e-3, 1.0));
        check_fourier(law, F);
        check_fourier(law, sample_F(false));
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
