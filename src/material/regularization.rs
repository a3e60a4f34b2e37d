//! Regularization of the third medium: the rotation measures of eq. (16)–(17) with their
//! derivatives, and the penalty of the linear elements' auxiliary fields (eq. 20).
#![allow(non_snake_case)]

use super::Real;
use nalgebra::Matrix3;

/// Planes (a, b) of the rotation measures of eq. (16)–(17): f1 about z, f2 about y, f3 about x.
pub const ROTATION_PLANES: [(usize, usize); 3] = [(0, 1), (0, 2), (1, 2)];

/// A rotation measure f = (F_ab − F_ba)/(F_aa + F_bb) (= tan φ for a pure rotation in the
/// plane (a, b)) with its derivatives with respect to the four entries of F it depends on.
#[derive(Clone, Copy, Debug)]
pub struct RotationMeasure<S = f64> {
    pub f: S,
    /// Entries (row, column) of F in the order ab, ba, aa, bb.
    pub entries: [(usize, usize); 4],
    /// ∂f/∂F at those entries.
    pub grad: [S; 4],
    /// ∂²f/∂F∂F at those entries.
    pub hess: [[S; 4]; 4],
}

/// The denominator F_aa + F_bb of rotation measure `i`: the measure is unbounded where it
/// vanishes (a rotation by 90° in that plane).
#[inline(always)]
pub fn rotation_denominator<S: Real>(F: &[[S; 3]; 3], i: usize) -> S {
    let (a, b) = ROTATION_PLANES[i];
    F[a][a] + F[b][b]
}

/// The rotation measure of plane `ROTATION_PLANES[i]` with its derivatives, for any scalar;
/// check [`rotation_denominator`] first.
#[inline(always)]
pub fn rotation_measure_of<S: Real>(F: &[[S; 3]; 3], i: usize) -> RotationMeasure<S> {
    let (a, b) = ROTATION_PLANES[i];
    let n = F[a][b] - F[b][a];
    let s = F[a][a] + F[b][b];
    let is = S::splat(1.0) / s;
    let f = n * is;
    let is2 = is * is;
    let c = S::splat(2.0) * f * is2; // ∂²f/∂s² = 2 n / s³
    let z = S::splat(0.0);
    RotationMeasure {
        f,
        entries: [(a, b), (b, a), (a, a), (b, b)],
        grad: [is, -is, -f * is, -f * is],
        hess: [
            [z, z, -is2, -is2],
            [z, z, is2, is2],
            [-is2, is2, c, c],
            [-is2, is2, c, c],
        ],
    }
}

/// The rotation measure of plane `ROTATION_PLANES[i]`; `None` when F_aa + F_bb = 0 (a rotation
/// of 90° in that plane, where tan φ is unbounded).
pub fn rotation_measure(F: &Matrix3<f64>, i: usize) -> Option<RotationMeasure> {
    let F: [[f64; 3]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| F[(r, c)]));
    if !(rotation_denominator(&F, i).abs() > 1e-12) {
        return None;
    }
    Some(rotation_measure_of(&F, i))
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
    /// k of Ψ_Rf weighed by the volume ratio, ∫ Ψ_Rf J^k dV (0: eq. 20 as written). k = 2 for
    /// a medium made again as the bodies move (`remake`), whose reference is renewed at every
    /// remake: the penalty does not depend on which reference it was given, and a layer
    /// closed between the bodies (J → 0) neither holds their slide through the rotation its
    /// shear reads as (∂Ψ J^k → 0) nor pulls them together by it (Ψ ∂J^k/∂J → 0; with k = 1
    /// the pull is Ψ per area whatever the squeeze).
    pub volume_power: u32,
}

impl Regularization {
    /// Energy density of one component and its first and second derivatives with respect to
    /// (f, p): returns (ψ, [∂ψ/∂f, ∂ψ/∂p], [[∂²ψ/∂f², ∂²ψ/∂f∂p], [·, ∂²ψ/∂p²]]) for the
    /// penalty part; the gradient part β2/2 |∇p|² is quadratic and handled by the caller.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    pub fn penalty<S: Real>(&self, f: S, p: S) -> (S, [S; 2], [[S; 2]; 2]) {
        let id = 1.0 / self.d;
        let e = f - p * S::splat(id);
        let b = S::splat(self.beta1);
        let (bid, bid2) = (S::splat(self.beta1 * id), S::splat(self.beta1 * id * id));
        (
            S::splat(0.5) * b * e * e,
            [b * e, -(bid * e)],
            [[b, -bid], [-bid, bid2]],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::sample_F;

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
            volume_power: 0,
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
