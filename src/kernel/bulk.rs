//! The one-cell bulk kernel: residual and exact tangent of a solid or medium cell (eq. 5, 6,
//! 28, 29), the reference the lane kernel and every assembled tangent are checked against.
#![allow(non_snake_case)]

use super::point::{Point, kinematics, point};
use super::regularization::{direct_regularization, physical_hessians, regularization};
use super::{
    Active, CellMaterial, CellSummary, Fused, KernelError, MulAdd, PBlocks, Separate, UuBlocks,
    avx2_fma,
};
use crate::dofs::{CellState, Layout};
use crate::element::{RefElement, physical_gradients};
use crate::material::{Stress, fourier};

/// The inversion check of [`bulk`] alone, without the law: `Inverted` with the J of the
/// first quadrature point where J ≤ 0 (or is not finite). Cheap enough to look before an
/// assembly whether a Newton update left the admissible set.
pub fn inversion<const N: usize, const D: usize, E: RefElement<N, D>>(
    s: &CellState<N>,
) -> Result<(), KernelError> {
    for (xi, _) in E::quadrature() {
        let (g, _) =
            physical_gradients::<N, D>(&E::grad(xi), &s.X).ok_or(KernelError::BadGeometry)?;
        let (F, _) = kinematics(&g, s, true);
        let J = F.determinant();
        if !(J > 0.0) || !J.is_finite() {
            return Err(KernelError::Inverted { J });
        }
    }
    Ok(())
}

/// Residual and (optionally) tangent of one cell of the bulk (solid or medium):
///
/// r_u = ∫ P : ∇δu dV,  r_θ = ∫ −Q · ∇δθ dV  (eq. 5, 6, without external loads),
/// K = ∂r/∂(u, θ) exactly (eq. 28–29), unsymmetric where both couplings act.
///
/// `r` and `k` (row-major, `ndof × ndof`) are overwritten.
pub fn bulk<const N: usize, const D: usize, E: RefElement<N, D>>(
    mat: &CellMaterial,
    lay: &Layout,
    s: &CellState<N>,
    act: Active,
    r: &mut [f64],
    k: Option<&mut [f64]>,
) -> Result<CellSummary, KernelError> {
    // the law list's choice made once per cell: the body is compiled for each law
    crate::with_solid_law!(&mat.law, |l| bulk_of::<N, D, E, _>(
        l, mat, lay, s, act, r, k
    ))
}

/// [`bulk`] with the solid law `law` (`mat`'s).
#[inline(always)]
fn bulk_of<const N: usize, const D: usize, E: RefElement<N, D>, L: Stress>(
    law: &L,
    mat: &CellMaterial,
    lay: &Layout,
    s: &CellState<N>,
    act: Active,
    r: &mut [f64],
    k: Option<&mut [f64]>,
) -> Result<CellSummary, KernelError> {
    #[cfg(target_arch = "x86_64")]
    if avx2_fma() {
        // SAFETY: the CPU has the features the function is compiled for (checked above)
        return unsafe { bulk_avx2::<N, D, E, L>(law, mat, lay, s, act, r, k) };
    }
    bulk_body::<N, D, E, Separate, L>(law, mat, lay, s, act, r, k)
}

/// [`bulk`] compiled for AVX2 and FMA: the node-block loops (eight or four unknowns wide)
/// become 256-bit fused multiply-adds.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn bulk_avx2<const N: usize, const D: usize, E: RefElement<N, D>, L: Stress>(
    law: &L,
    mat: &CellMaterial,
    lay: &Layout,
    s: &CellState<N>,
    act: Active,
    r: &mut [f64],
    k: Option<&mut [f64]>,
) -> Result<CellSummary, KernelError> {
    bulk_body::<N, D, E, Fused, L>(law, mat, lay, s, act, r, k)
}

/// The body of [`bulk`]: per quadrature point the law, then the residual and the tangent
/// blocks, summed over the points in node-by-node arrays and added to `k` at the end. One
/// long function on purpose: the blocks (kilobytes for a hex) stay in registers and cache
/// across the point loop instead of passing through memory between functions.
#[inline(always)]
fn bulk_body<const N: usize, const D: usize, E: RefElement<N, D>, M: MulAdd, L: Stress>(
    law: &L,
    mat: &CellMaterial,
    lay: &Layout,
    s: &CellState<N>,
    act: Active,
    r: &mut [f64],
    mut k: Option<&mut [f64]>,
) -> Result<CellSummary, KernelError> {
    let nd = lay.ndof();
    super::zero_local(nd, r, k.as_deref_mut());
    let mut summary = CellSummary {
        min_J: f64::INFINITY,
        energy: 0.0,
    };
    let theta_ref = law.theta0();
    let tangent = k.is_some();
    // The cell's tangent blocks, summed over the quadrature points and added to `k` at the
    // end: node-by-node matrices whose inner loops run over the second node (vectorisable).
    // kuu[i][kk][I][K] = ∂r_u(I,i)/∂u(K,kk) (blocks i ≤ kk; the others are their transposes,
    // ∂P/∂F having major symmetry), kut[i][I][K] = ∂r_u(I,i)/∂θ_K,
    // ktu[kk][I][K] = ∂r_θ(I)/∂u(K,kk), ktt[I][K] = ∂r_θ(I)/∂θ_K.
    let mut kuu: UuBlocks<N> = [[[[0.0; N]; N]; 3]; 3];
    let mut kp = if tangent && lay.np > 0 {
        Some(PBlocks::<N> {
            up: [[[[0.0; N]; N]; 3]; 3],
            pp: [[[0.0; N]; N]; 3],
        })
    } else {
        None
    };
    let mut kut = [[[0.0; N]; N]; 3];
    let mut ktu = [[[0.0; N]; N]; 3];
    let mut ktt = [[0.0; N]; N];
    for (xi, w) in E::quadrature() {
        let Point {
            g,
            Nv,
            dV,
            F,
            grad_theta: gt,
            theta,
        } = point::<N, D, E>(xi, *w, lay, s, theta_ref)?;
        // gT[J][K] = ∂N_K/∂X_J
        let mut gT = [[0.0; N]; 3];
        for K in 0..N {
            for J in 0..D {
                gT[J][K] = g[K][J];
            }
        }
        if lay.has_u && act.mechanics {
            let m = law
                .stress(&F, theta)
                .ok_or(KernelError::Inverted { J: F.determinant() })?;
            summary.min_J = summary.min_J.min(m.J);
            summary.energy += m.psi * dV;
            for I in 0..N {
                for i in 0..D {
                    let v: f64 = (0..D).map(|J| m.P[(i, J)] * g[I][J]).sum();
                    r[lay.u(I, i)] += v * dV;
                }
            }
            if tangent {
                for i in 0..D {
                    for kk in i..D {
                        // c[J][K] = Σ_L A_iJkL ∂N_K/∂X_L dV, then block += Σ_J ∂N_I/∂X_J c[J]
                        let mut c = [[0.0; N]; 3];
                        for (J, cJ) in c.iter_mut().enumerate().take(D) {
                            for L in 0..D {
                                let a = m.dP_dF[(3 * i + J, 3 * kk + L)] * dV;
                                for K in 0..N {
                                    cJ[K] = M::mul_add(a, gT[L][K], cJ[K]);
                                }
                            }
                        }
                        // a diagonal block is symmetric: its upper triangle (K ≥ I) only
                        if i == kk {
                            add_gradient_product::<N, D, M, true>(&mut kuu[i][kk], &gT, &c);
                        } else {
                            add_gradient_product::<N, D, M, false>(&mut kuu[i][kk], &gT, &c);
                        }
                    }
                }
                if lay.has_theta {
                    // ∂r_u(I,i)/∂θ_K = ∫ ∂P_iJ/∂θ ∂N_I/∂X_J N_K
                    for (i, kut_i) in kut.iter_mut().enumerate().take(D) {
                        for (I, row) in kut_i.iter_mut().enumerate() {
                            let v: f64 = (0..D).map(|J| m.dP_dtheta[(i, J)] * g[I][J]).sum();
                            let v = v * dV;
                            for K in 0..N {
                                row[K] = M::mul_add(v, Nv[K], row[K]);
                            }
                        }
                    }
                }
            }
            if lay.np > 0 {
                let reg = mat.reg.expect("a cell with p fields has a regularization");
                summary.energy += regularization::<N, D, M>(
                    &reg,
                    lay,
                    s,
                    &F,
                    (&g, &gT),
                    &Nv,
                    dV,
                    r,
                    kp.as_mut().map(|kp| (&mut kuu, kp)),
                )?;
            }
            if let Some(c) = mat.reg_direct {
                let hX = physical_hessians::<N, D, E>(xi, &s.X, &g)?;
                summary.energy +=
                    direct_regularization::<N, D>(c, lay, s, &F, &g, &hX, dV, r, k.as_deref_mut())?;
            }
        } else {
            summary.min_J = summary.min_J.min(F.determinant());
        }
        if lay.has_theta && act.heat {
            let h =
                fourier(&F, &gt, &mat.cond).ok_or(KernelError::Inverted { J: F.determinant() })?;
            for I in 0..N {
                let v: f64 = (0..D).map(|J| h.Q[J] * g[I][J]).sum();
                r[lay.theta(I)] -= v * dV;
            }
            if tangent {
                // ∂r_θ(I)/∂θ_K = −∫ ∂N_I/∂X_J ∂Q_J/∂(∇θ)_L ∂N_K/∂X_L
                let mut c = [[0.0; N]; 3];
                for (J, cJ) in c.iter_mut().enumerate().take(D) {
                    for L in 0..D {
                        let a = -h.dQ_dgrad[(J, L)] * dV;
                        for K in 0..N {
                            cJ[K] = M::mul_add(a, gT[L][K], cJ[K]);
                        }
                    }
                }
                // ∂Q/∂∇θ = −J k C⁻¹ is symmetric, and so is this block
                add_gradient_product::<N, D, M, true>(&mut ktt, &gT, &c);
                if lay.has_u && act.mechanics {
                    // ∂r_θ(I)/∂u(K,kk) = −∫ ∂N_I/∂X_J ∂Q_J/∂F_kkL ∂N_K/∂X_L
                    for (kk, ktu_k) in ktu.iter_mut().enumerate().take(D) {
                        let mut c = [[0.0; N]; 3];
                        for (J, cJ) in c.iter_mut().enumerate().take(D) {
                            for L in 0..D {
                                let a = -h.dQ_dF[(J, 3 * kk + L)] * dV;
                                for K in 0..N {
                                    cJ[K] = M::mul_add(a, gT[L][K], cJ[K]);
                                }
                            }
                        }
                        add_gradient_product::<N, D, M, false>(ktu_k, &gT, &c);
                    }
                }
            }
        }
    }
    if let (Some(k), Some(kp)) = (k.as_deref_mut(), &kp) {
        for c in 0..lay.np {
            for I in 0..N {
                let row = lay.p(I, c) * nd;
                for K in 0..N {
                    k[row + lay.p(K, c)] += kp.pp[c][I][K];
                }
                for a in 0..D {
                    let ua = lay.u(I, a);
                    for K in 0..N {
                        let v = kp.up[a][c][I][K];
                        k[ua * nd + lay.p(K, c)] += v;
                        k[lay.p(K, c) * nd + ua] += v;
                    }
                }
            }
        }
    }
    if let Some(k) = k {
        let th = |I: usize| lay.theta(I);
        for I in 0..N {
            for i in 0..D {
                let row = lay.u(I, i) * nd;
                if lay.has_u && act.mechanics {
                    for kk in 0..D {
                        for K in 0..N {
                            // blocks i ≤ kk stored; of a diagonal one, its upper triangle
                            k[row + lay.u(K, kk)] += if i < kk || (i == kk && K >= I) {
                                kuu[i][kk][I][K]
                            } else {
                                kuu[kk][i][K][I]
                            };
                        }
                    }
                    if lay.has_theta {
                        for K in 0..N {
                            k[row + th(K)] += kut[i][I][K];
                        }
                    }
                }
            }
            if lay.has_theta && act.heat {
                let row = th(I) * nd;
                for K in 0..N {
                    k[row + th(K)] += if K >= I { ktt[I][K] } else { ktt[K][I] };
                }
                if lay.has_u && act.mechanics {
                    for kk in 0..D {
                        for K in 0..N {
                            k[row + lay.u(K, kk)] += ktu[kk][I][K];
                        }
                    }
                }
            }
        }
    }
    Ok(summary)
}

/// block[I][K] += Σ_J ∂N_I/∂X_J c[J][K] (J < D), the inner loop over K; with `UPPER`, for
/// K ≥ I only (a symmetric block's other half is its transpose).
#[inline(always)]
fn add_gradient_product<const N: usize, const D: usize, M: MulAdd, const UPPER: bool>(
    block: &mut [[f64; N]; N],
    gT: &[[f64; N]; 3],
    c: &[[f64; N]; 3],
) {
    for (I, row) in block.iter_mut().enumerate() {
        for J in 0..D {
            let gIJ = gT[J][I];
            for K in if UPPER { I } else { 0 }..N {
                row[K] = M::mul_add(gIJ, c[J][K], row[K]);
            }
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::element::{Hex8, Quad4, Tet4, Tri3};
    use crate::material::{Conductivity, Regularization, SolidLaw, ThermoElastic};

    pub(in crate::kernel) const SOLID: CellMaterial = CellMaterial {
        law: SolidLaw::NeoHooke(ThermoElastic {
            K: 20.0,
            mu: 10.0,
            alpha: 2e-3,
            theta0: 10.0,
        }),
        cond: Conductivity::Medium {
            k_tm: 3.0,
            k_max: 50.0,
        },
        medium: false,
        reg: None,
        reg_direct: None,
    };

    /// A soft medium whose regularization dominates, so that its terms are what is checked.
    const MEDIUM: CellMaterial = CellMaterial {
        law: SolidLaw::NeoHooke(ThermoElastic {
            K: 1e-2,
            mu: 1e-2,
            alpha: 1e-3,
            theta0: 10.0,
        }),
        cond: Conductivity::Medium {
            k_tm: 0.5,
            k_max: 50.0,
        },
        medium: true,
        reg: Some(Regularization {
            beta1: 1.0,
            beta2: 0.3,
            d: 1.7,
            volume_power: 0,
        }),
        reg_direct: None,
    };

    /// A quadratic medium cell with the direct regularization of eq. 18 (no p fields).
    const MEDIUM_DIRECT: CellMaterial = CellMaterial {
        reg: None,
        reg_direct: Some(0.3),
        ..MEDIUM
    };

    /// A distorted, strained and heated cell with `np` regularization fields per node, and
    /// its layout.
    pub(in crate::kernel) fn distorted_cell<const N: usize, const D: usize, E: RefElement<N, D>>(
        np: usize,
    ) -> (CellState<N>, Layout) {
        let mut s = CellState::<N>::zero();
        for (I, xi) in E::nodes().iter().enumerate() {
            for d in 0..D {
                // distorted but valid geometry
                s.X[I][d] = 0.5 * xi[d] + 0.07 * ((I * 7 + d * 3) % 5) as f64 / 5.0;
                s.u[I][d] = 0.05 * (((I * 3 + d * 5) % 7) as f64 / 7.0 - 0.5);
            }
            s.theta[I] = 10.0 + 30.0 * ((I * 5) % 4) as f64;
            for c in 0..np {
                s.p[I][c] = 0.2 * (((I * 5 + c * 3) % 7) as f64 / 7.0 - 0.5);
            }
        }
        let lay = Layout {
            n: N,
            dim: D,
            has_u: true,
            has_theta: true,
            np,
        };
        (s, lay)
    }

    /// Central differences of the residual against the tangent, column by column.
    fn check<const N: usize, const D: usize, E: RefElement<N, D>>(mat: &CellMaterial) {
        let np = if mat.reg.is_some() && mat.reg_direct.is_none() {
            if D == 2 { 1 } else { 3 }
        } else {
            0
        };
        let (s, lay) = distorted_cell::<N, D, E>(np);
        let nd = lay.ndof();
        let mut r = vec![0.0; nd];
        let mut k = vec![0.0; nd * nd];
        bulk::<N, D, E>(mat, &lay, &s, Active::ALL, &mut r, Some(&mut k)).unwrap();
        // the instruction-set variant `bulk` dispatched to agrees with the portable one to
        // round-off (fused multiply-adds round once)
        let (mut r0, mut k0) = (vec![0.0; nd], vec![0.0; nd * nd]);
        crate::with_solid_law!(&mat.law, |l| bulk_body::<N, D, E, Separate, _>(
            l,
            mat,
            &lay,
            &s,
            Active::ALL,
            &mut r0,
            Some(&mut k0)
        ))
        .unwrap();
        let scale = k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (a, b) in k.iter().zip(&k0) {
            assert!(
                (a - b).abs() <= 1e-12 * scale,
                "tangent {a} vs portable {b}"
            );
        }
        let r_scale = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (a, b) in r.iter().zip(&r0) {
            assert!(
                (a - b).abs() <= 1e-12 * r_scale,
                "residual {a} vs portable {b}"
            );
        }
        let h = 1e-7;
        let (mut rp, mut rm) = (vec![0.0; nd], vec![0.0; nd]);
        for b in 0..nd {
            let perturb = |s: &CellState<N>, e: f64| {
                let mut t = *s;
                if b < lay.theta_off() + N {
                    if b < N * D {
                        t.u[b / D][b % D] += e;
                    } else {
                        t.theta[b - N * D] += e;
                    }
                } else {
                    let q = b - lay.p_off();
                    t.p[q / np][q % np] += e;
                }
                t
            };
            bulk::<N, D, E>(mat, &lay, &perturb(&s, h), Active::ALL, &mut rp, None).unwrap();
            bulk::<N, D, E>(mat, &lay, &perturb(&s, -h), Active::ALL, &mut rm, None).unwrap();
            for a in 0..nd {
                let fd = (rp[a] - rm[a]) / (2.0 * h);
                assert!(
                    (fd - k[a * nd + b]).abs() < 1e-6 * scale,
                    "K[{a},{b}] = {} vs FD {fd}",
                    k[a * nd + b]
                );
            }
        }
        if np > 0 {
            // the regularization blocks (u–p, p–p) are symmetric
            for a in 0..nd {
                for b in lay.p_off()..nd {
                    assert!((k[a * nd + b] - k[b * nd + a]).abs() < 1e-12 * scale);
                }
            }
            // and they matter: without them the p rows would be empty
            let prow = lay.p_off() * nd;
            assert!(k[prow..prow + nd].iter().any(|v| v.abs() > 1e-3 * scale));
        }
    }

    #[test]
    fn bulk_tangent_matches_finite_differences() {
        check::<3, 2, Tri3>(&SOLID);
        check::<4, 2, Quad4>(&SOLID);
        check::<4, 3, Tet4>(&SOLID);
        check::<8, 3, Hex8>(&SOLID);
        // a law without the coefficient form: the same checks
        let rubber = CellMaterial {
            law: SolidLaw::MooneyRivlin(crate::material::MooneyRivlin {
                C10: 3.0,
                C01: 2.0,
                K: 20.0,
                alpha: 2e-3,
                theta0: 10.0,
            }),
            ..SOLID
        };
        check::<4, 2, Quad4>(&rubber);
        check::<8, 3, Hex8>(&rubber);
    }

    #[test]
    fn quadratic_medium_with_direct_regularization_tangent_matches_finite_differences() {
        use crate::element::{Hex20, Hex27, Quad8, Quad9, Tet10, Tri6};
        check::<6, 2, Tri6>(&MEDIUM_DIRECT);
        check::<8, 2, Quad8>(&MEDIUM_DIRECT);
        check::<9, 2, Quad9>(&MEDIUM_DIRECT);
        check::<10, 3, Tet10>(&MEDIUM_DIRECT);
        check::<20, 3, Hex20>(&MEDIUM_DIRECT);
        check::<27, 3, Hex27>(&MEDIUM_DIRECT);
        // and the term is there: it changes the residual of a bent quad9 a lot
        let lay = Layout {
            n: 9,
            dim: 2,
            has_u: true,
            has_theta: false,
            np: 0,
        };
        let mut st = CellState::<9>::zero();
        for (I, xi) in Quad9::nodes().iter().enumerate() {
            st.X[I] = [xi[0], xi[1], 0.0];
            st.u[I][1] = 0.1 * xi[0] * xi[0]; // bending: ∇F ≠ 0
        }
        let (mut r1, mut r0) = (vec![0.0; 18], vec![0.0; 18]);
        let e1 =
            bulk::<9, 2, Quad9>(&MEDIUM_DIRECT, &lay, &st, Active::ALL, &mut r1, None).unwrap();
        let plain = CellMaterial {
            reg_direct: None,
            ..MEDIUM_DIRECT
        };
        let e0 = bulk::<9, 2, Quad9>(&plain, &lay, &st, Active::ALL, &mut r0, None).unwrap();
        assert!(
            e1.energy > 10.0 * e0.energy,
            "{} vs {}",
            e1.energy,
            e0.energy
        );
        let diff: f64 = r1.iter().zip(&r0).map(|(a, b)| (a - b).abs()).sum();
        assert!(diff > 1e-2, "{diff}");
    }

    #[test]
    fn medium_with_regularization_tangent_matches_finite_differences() {
        check::<3, 2, Tri3>(&MEDIUM);
        check::<4, 2, Quad4>(&MEDIUM);
        check::<4, 3, Tet4>(&MEDIUM);
        check::<8, 3, Hex8>(&MEDIUM);
    }

    /// A remade medium's penalty weighed by J^k (k = 1 and k = 2): the exact tangent, and the
    /// energy the reference-volume penalty's times J^k on a cell of uniform F.
    #[test]
    fn medium_with_regularization_weighed_by_the_volume_ratio_tangent_and_energy() {
        let reg = MEDIUM.reg.unwrap();
        let weighed = |volume_power| CellMaterial {
            reg: Some(Regularization {
                volume_power,
                ..reg
            }),
            ..MEDIUM
        };
        for k in [1, 2] {
            check::<3, 2, Tri3>(&weighed(k));
            check::<4, 2, Quad4>(&weighed(k));
            check::<4, 3, Tet4>(&weighed(k));
            check::<8, 3, Hex8>(&weighed(k));
        }
        // a triangle squeezed to J = 0.04 and sheared, its p fields off the rotation
        let mut s = CellState::<3>::zero();
        for (I, xi) in Tri3::nodes().iter().enumerate() {
            s.X[I] = [xi[0], xi[1], 0.0];
            s.u[I] = [0.3 * xi[1], -0.96 * xi[1], 0.0];
            s.p[I][0] = 0.1 * I as f64;
        }
        let lay = |np| Layout {
            n: 3,
            dim: 2,
            has_u: true,
            has_theta: false,
            np,
        };
        let energy = |mat: &CellMaterial, np| {
            let mut r = vec![0.0; lay(np).ndof()];
            bulk::<3, 2, Tri3>(mat, &lay(np), &s, Active::ALL, &mut r, None)
                .unwrap()
                .energy
        };
        let bare = CellMaterial {
            reg: None,
            ..MEDIUM
        };
        let (e0, e_ref) = (energy(&bare, 0), energy(&MEDIUM, 1));
        let psi_ref = e_ref - e0;
        assert!(psi_ref > 1e-3, "the penalty is there: {psi_ref}");
        for (k, J_k) in [(1, 0.04), (2, 0.04 * 0.04)] {
            let psi = energy(&weighed(k), 1) - e0;
            assert!(
                (psi - J_k * psi_ref).abs() < 1e-12 * psi_ref,
                "weighed by J^{k}: {psi} against J^{k} × per reference volume {}",
                J_k * psi_ref
            );
        }
    }
}
