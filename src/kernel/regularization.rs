//! The third medium's regularization at one quadrature point: with auxiliary p fields on linear
//! cells (eq. 20) or directly through second derivatives on quadratic ones (eq. 18).
#![allow(non_snake_case)]

use super::{KernelError, MulAdd, PBlocks, UuBlocks};
use crate::dofs::{CellState, Layout};
use crate::element::{RefElement, invert_small};
use crate::material::{Regularization, rotation_measure, rotation_measure_d3};
use nalgebra::Matrix3;

/// Regularization of a linear medium cell at one quadrature point, eq. (20): adds
/// ∂Ψ_Rf/∂(u, p) dV to `r` and its exact derivative (symmetric) to `k`; returns Ψ_Rf dV.
/// Weighed by the volume ratio ([`Regularization::volume_power`] k > 0) the same with
/// Ψ_Rf J^k dV.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn regularization<const N: usize, const D: usize, M: MulAdd>(
    reg: &Regularization,
    lay: &Layout,
    s: &CellState<N>,
    F: &Matrix3<f64>,
    (g, gT): (&[[f64; D]; N], &[[f64; N]; 3]),
    Nv: &[f64; N],
    dV: f64,
    r: &mut [f64],
    tangent: Option<(&mut UuBlocks<N>, &mut PBlocks<N>)>,
) -> Result<f64, KernelError> {
    // weighed by J^k: J and h_I = F⁻ᵀ ∇_X N_I (∂J/∂u(I,a) = J h_Ia); the terms below are
    // then weighed by J^k dV, and Ψ ∂(J^k) with its derivatives is added after them
    let current = if reg.volume_power > 0 {
        let inv = F
            .try_inverse()
            .ok_or(KernelError::Inverted { J: F.determinant() })?;
        let h: [[f64; D]; N] = std::array::from_fn(|I| {
            std::array::from_fn(|a| (0..D).map(|J| g[I][J] * inv[(J, a)]).sum())
        });
        Some((F.determinant(), h))
    } else {
        None
    };
    let k = reg.volume_power as f64;
    let dV = current.map_or(dV, |(J, _)| J.powf(k) * dV);
    let mut parts = Parts::<N> {
        psi: 0.0,
        du: [[0.0; N]; 3],
        dp: [[0.0; N]; 3],
    };
    let mut energy = 0.0;
    let mut tangent = tangent;
    for c in 0..lay.np {
        let rm = rotation_measure(F, c).ok_or(KernelError::Singular)?;
        let mut p = 0.0;
        let mut gp = [0.0; D];
        for I in 0..N {
            p += Nv[I] * s.p[I][c];
            for J in 0..D {
                gp[J] += g[I][J] * s.p[I][c];
            }
        }
        let (psi, d1, d2) = reg.penalty(rm.f, p);
        let gp2: f64 = gp.iter().map(|v| v * v).sum();
        energy += (psi + 0.5 * reg.beta2 * gp2) * dV;
        // Bf[a][I] = ∂f/∂F_aJ ∂N_I/∂X_J = ∂f/∂u_Ia
        let mut Bf = [[0.0; N]; 3];
        for (q, &(a, J)) in rm.entries.iter().enumerate() {
            for I in 0..N {
                Bf[a][I] += rm.grad[q] * g[I][J];
            }
        }
        // weighed by J^k, Ψ and its first derivatives are kept without dV as well
        let keep = current.is_some();
        if keep {
            parts.psi += psi + 0.5 * reg.beta2 * gp2;
        }
        for I in 0..N {
            for a in 0..D {
                let du = d1[0] * Bf[a][I];
                r[lay.u(I, a)] += du * dV;
                if keep {
                    parts.du[a][I] += du;
                }
            }
            let gg: f64 = (0..D).map(|J| gp[J] * g[I][J]).sum();
            let dp = d1[1] * Nv[I] + reg.beta2 * gg;
            r[lay.p(I, c)] += dp * dV;
            if keep {
                parts.dp[c][I] += dp;
            }
        }
        let Some((uu, pb)) = tangent.as_mut() else {
            continue;
        };
        for a in 0..D {
            for b in a..D {
                // d²ψ/df² ∂f/∂u ⊗ ∂f/∂u
                for I in 0..N {
                    let w = d2[0][0] * Bf[a][I] * dV;
                    for K in 0..N {
                        uu[a][b][I][K] = M::mul_add(w, Bf[b][K], uu[a][b][I][K]);
                    }
                }
            }
            // K_up (K_pu is its transpose)
            for I in 0..N {
                let w = d2[0][1] * Bf[a][I] * dV;
                for K in 0..N {
                    pb.up[a][c][I][K] = M::mul_add(w, Nv[K], pb.up[a][c][I][K]);
                }
            }
        }
        // dψ/df Σ_qt ∂²f/∂F_q∂F_t (∇N_I)_Jq (∇N_K)_Jt, blocks a ≤ b (∂²f is symmetric)
        for (q, &(a, Jq)) in rm.entries.iter().enumerate() {
            for (t, &(b, Js)) in rm.entries.iter().enumerate() {
                let h = rm.hess[q][t];
                if h == 0.0 || a > b {
                    continue;
                }
                for I in 0..N {
                    let w = d1[0] * h * gT[Jq][I] * dV;
                    for K in 0..N {
                        uu[a][b][I][K] = M::mul_add(w, gT[Js][K], uu[a][b][I][K]);
                    }
                }
            }
        }
        for I in 0..N {
            let w = d2[1][1] * Nv[I] * dV;
            for K in 0..N {
                let gg: f64 = (0..D).map(|J| gT[J][I] * gT[J][K]).sum();
                pb.pp[c][I][K] += w * Nv[K] + reg.beta2 * gg * dV;
            }
        }
    }
    if let Some((_, h)) = current {
        add_volume_terms::<N, D>(lay, &h, &parts, k, dV, r, tangent);
    }
    Ok(energy)
}

/// Ψ_Rf at a point and its derivatives by u (`du[a][I]`) and p (`dp[c][I]`), without dV.
struct Parts<const N: usize> {
    psi: f64,
    du: [[f64; N]; 3],
    dp: [[f64; N]; 3],
}

/// The terms of Ψ J^k beyond J^k times those of Ψ: Ψ ∂(J^k) = k Ψ J^k h in the residual,
/// and k J^k (h ⊗ ∂Ψ + ∂Ψ ⊗ h) + Ψ ∂²(J^k) in the tangent, with ∂J/∂u(I,a) = J h_Ia,
/// ∂²J/∂u(I,a)∂u(K,b) = J (h_Ia h_Kb − h_Ib h_Ka), hence
/// ∂²(J^k) = J^k (k² h_Ia h_Kb − k h_Ib h_Ka); `JdV` is J^k dV.
fn add_volume_terms<const N: usize, const D: usize>(
    lay: &Layout,
    h: &[[f64; D]; N],
    parts: &Parts<N>,
    k: f64,
    JdV: f64,
    r: &mut [f64],
    tangent: Option<(&mut UuBlocks<N>, &mut PBlocks<N>)>,
) {
    for I in 0..N {
        for a in 0..D {
            r[lay.u(I, a)] += k * parts.psi * h[I][a] * JdV;
        }
    }
    let Some((uu, pb)) = tangent else {
        return;
    };
    for a in 0..D {
        for b in a..D {
            for I in 0..N {
                for K in 0..N {
                    let v = k * (h[I][a] * parts.du[b][K] + parts.du[a][I] * h[K][b])
                        + parts.psi * k * (k * h[I][a] * h[K][b] - h[I][b] * h[K][a]);
                    uu[a][b][I][K] += v * JdV;
                }
            }
        }
        for c in 0..lay.np {
            for I in 0..N {
                for K in 0..N {
                    pb.up[a][c][I][K] += k * h[I][a] * parts.dp[c][K] * JdV;
                }
            }
        }
    }
}

/// Second derivatives ∂²N_I/∂X_J∂X_K at ξ, with the geometry-map term of curved cells:
/// H_X = J⁻ᵀ (H_ξ − Σ_m ∂N/∂X_m ∂²X_m/∂ξ∂ξ) J⁻¹, J = ∂X/∂ξ.
#[allow(clippy::type_complexity)]
pub fn physical_hessians<const N: usize, const D: usize, E: RefElement<N, D>>(
    xi: &[f64; D],
    X: &[[f64; 3]; N],
    g: &[[f64; D]; N],
) -> Result<[[[f64; D]; D]; N], KernelError> {
    let (gxi, hxi) = (E::grad(xi), E::hessian(xi));
    let mut jac = [[0.0; D]; D];
    let mut x2 = [[[0.0; D]; D]; D];
    for I in 0..N {
        for m in 0..D {
            for j in 0..D {
                jac[m][j] += X[I][m] * gxi[I][j];
                for k in 0..D {
                    x2[m][j][k] += X[I][m] * hxi[I][j][k];
                }
            }
        }
    }
    let (_, jinv) = invert_small(&jac).ok_or(KernelError::BadGeometry)?;
    let mut out = [[[0.0; D]; D]; N];
    for I in 0..N {
        let mut t = [[0.0; D]; D];
        for j in 0..D {
            for k in 0..D {
                t[j][k] = hxi[I][j][k] - (0..D).map(|m| g[I][m] * x2[m][j][k]).sum::<f64>();
            }
        }
        for J in 0..D {
            for K in 0..D {
                let mut v = 0.0;
                for j in 0..D {
                    for k in 0..D {
                        v += jinv[j][J] * t[j][k] * jinv[k][K];
                    }
                }
                out[I][J][K] = v;
            }
        }
    }
    Ok(out)
}

/// Direct regularization of a quadratic medium cell at one quadrature point, eq. (18):
/// Ψ_R = c/2 Σ_i |∇_X f_i|² with ∇_X f_i = ∂f_i/∂F : ∇_X F and ∇_X F from the physical
/// second derivatives `hX`. Adds the residual and exact tangent; returns Ψ_R dV. The tangent
/// is built as a low-rank product in one pass (hence the length): one matrix product per
/// point instead of the O(N²) loops per plane.
#[allow(clippy::too_many_arguments)]
pub(super) fn direct_regularization<const N: usize, const D: usize>(
    c: f64,
    lay: &Layout,
    s: &CellState<N>,
    F: &Matrix3<f64>,
    g: &[[f64; D]; N],
    hX: &[[[f64; D]; D]; N],
    dV: f64,
    r: &mut [f64],
    k: Option<&mut [f64]>,
) -> Result<f64, KernelError> {
    let nd = lay.ndof();
    let nu = N * D; // local u dofs come first: α = I D + b
    assert!(
        nu <= MAX_U,
        "at most {MAX_U} displacement unknowns per cell"
    );
    let mut energy = 0.0;
    let planes = if D == 2 { 1 } else { 3 };
    let tangent = k.is_some();
    // The tangent is Σ_planes L Rᵀ with, per plane, L_α = [A_α, pm_α + V_α, P_α] and
    // R_α = [A_α, P_α, V_α] (see below): rank 11 at most, one matrix product per point.
    let mut L = [[0.0; RANK]; MAX_U];
    let mut R = [[0.0; RANK]; MAX_U];
    for i in 0..planes {
        let rm = rotation_measure(F, i).ok_or(KernelError::Singular)?;
        let d3 = rotation_measure_d3(F, i).ok_or(KernelError::Singular)?;
        // T[q][K] = ∂F_(a_q J_q)/∂X_K;  P[α][t] = ∂F_(a_t J_t)/∂u_α;  ∂T[q][K]/∂u_α is
        // hX[I][J_q][K] where α = (I, a_q), 0 otherwise
        let mut T = [[0.0; D]; 4];
        let mut P = [[0.0; 4]; MAX_U];
        for (q, &(a, J)) in rm.entries.iter().enumerate() {
            for I in 0..N {
                P[I * D + a][q] = g[I][J];
                for K in 0..D {
                    T[q][K] += s.u[I][a] * hX[I][J][K];
                }
            }
        }
        let G: [f64; D] = std::array::from_fn(|K| (0..4).map(|q| rm.grad[q] * T[q][K]).sum());
        energy += 0.5 * c * G.iter().map(|v| v * v).sum::<f64>() * dV;
        // HT[t][K] = Σ_q hess[q][t] T[q][K]; GT[q] = Σ_K G_K T[q][K]
        let HT: [[f64; D]; 4] = std::array::from_fn(|t| {
            std::array::from_fn(|K| (0..4).map(|q| rm.hess[q][t] * T[q][K]).sum())
        });
        let GT: [f64; 4] = std::array::from_fn(|q| (0..D).map(|K| G[K] * T[q][K]).sum());
        // Mbar[t][w] = Σ_q d3[q][t][w] GT[q]
        let Mbar: [[f64; 4]; 4] = std::array::from_fn(|t| {
            std::array::from_fn(|w| (0..4).map(|q| d3[q][t][w] * GT[q]).sum())
        });
        let col = i * RANK_PER_PLANE;
        for I in 0..N {
            for a in 0..D {
                let al = I * D + a;
                let Pa = &P[al];
                // A[α][K] = ∂G_K/∂u_α = Σ_t P[α][t] HT[t][K] + Σ_(q: a_q = a) grad[q] hX[I][J_q][K]
                let mut A = [0.0; D];
                for (K, AK) in A.iter_mut().enumerate() {
                    *AK = (0..4).map(|t| Pa[t] * HT[t][K]).sum();
                }
                // V[α][w] = Σ_K G_K Σ_(q: a_q = a) hess[q][w] hX[I][J_q][K]
                let mut V = [0.0; 4];
                for (q, &(aq, J)) in rm.entries.iter().enumerate() {
                    if aq != a {
                        continue;
                    }
                    let h = &hX[I][J];
                    let gh: f64 = (0..D).map(|K| G[K] * h[K]).sum();
                    for K in 0..D {
                        A[K] += rm.grad[q] * h[K];
                    }
                    for (w, Vw) in V.iter_mut().enumerate() {
                        *Vw += rm.hess[q][w] * gh;
                    }
                }
                let ga: f64 = (0..D).map(|K| G[K] * A[K]).sum();
                r[lay.u(I, a)] += c * ga * dV;
                if !tangent {
                    continue;
                }
                let (l, rr) = (
                    &mut L[al][col..col + RANK_PER_PLANE],
                    &mut R[al][col..col + RANK_PER_PLANE],
                );
                l[..D].copy_from_slice(&A);
                rr[..D].copy_from_slice(&A);
                for w in 0..4 {
                    let pm: f64 = (0..4).map(|t| Pa[t] * Mbar[t][w]).sum();
                    l[3 + w] = pm + V[w];
                    l[7 + w] = Pa[w];
                    rr[3 + w] = Pa[w];
                    rr[7 + w] = V[w];
                }
            }
        }
    }
    if let Some(k) = k {
        // k_uu += c dV L Rᵀ (the u block is the leading nu × nu one, row stride nd)
        let width = planes * RANK_PER_PLANE;
        let lhs = faer::MatRef::from_row_major_slice_with_stride(L.as_flattened(), nu, width, RANK);
        let rhs = faer::MatRef::from_row_major_slice_with_stride(R.as_flattened(), nu, width, RANK);
        let dst = faer::MatMut::from_row_major_slice_with_stride_mut(
            &mut k[..(nu - 1) * nd + nu],
            nu,
            nu,
            nd,
        );
        faer::linalg::matmul::matmul(
            dst,
            faer::Accum::Add,
            lhs,
            rhs.transpose(),
            c * dV,
            faer::Par::Seq,
        );
    }
    Ok(energy)
}

/// Displacement unknowns of the largest cell (hex27).
const MAX_U: usize = 81;
/// Columns of one rotation plane's factors: A (up to 3), then two groups of 4.
const RANK_PER_PLANE: usize = 11;
/// Columns of the factors of all three planes.
const RANK: usize = 3 * RANK_PER_PLANE;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{Hex8, Quad4, physical_gradients};

    /// On a curved cell, d/dξ of the physical gradients equals H_X ∂X/∂ξ.
    fn check_hessians<const N: usize, const D: usize, E: RefElement<N, D>>() {
        let mut X = [[0.0; 3]; N];
        for (I, xi) in E::nodes().iter().enumerate() {
            for d in 0..D {
                X[I][d] = 0.5 * xi[d] + 0.06 * (((I * 7 + d * 3) % 5) as f64 / 5.0 - 0.5);
            }
        }
        let xi: [f64; D] = std::array::from_fn(|d| 0.21 + 0.03 * d as f64);
        let (g, _) = physical_gradients::<N, D>(&E::grad(&xi), &X).unwrap();
        let hX = physical_hessians::<N, D, E>(&xi, &X, &g).unwrap();
        let gx = E::grad(&xi);
        for k in 0..D {
            let h = 1e-6;
            let (mut p, mut m) = (xi, xi);
            p[k] += h;
            m[k] -= h;
            let gp = physical_gradients::<N, D>(&E::grad(&p), &X).unwrap().0;
            let gm = physical_gradients::<N, D>(&E::grad(&m), &X).unwrap().0;
            for I in 0..N {
                for J in 0..D {
                    let fd = (gp[I][J] - gm[I][J]) / (2.0 * h);
                    // ∂X_K/∂ξ_k = Σ_L X_LK ∂N_L/∂ξ_k
                    let chain: f64 = (0..D)
                        .map(|K| hX[I][J][K] * (0..N).map(|L| X[L][K] * gx[L][k]).sum::<f64>())
                        .sum();
                    assert!(
                        (fd - chain).abs() < 1e-6 * (1.0 + fd.abs()),
                        "{I} {J} {k}: {fd} vs {chain}"
                    );
                }
            }
        }
    }

    #[test]
    fn physical_second_derivatives_on_curved_cells() {
        use crate::element::{Hex20, Hex27, Quad8, Quad9, Tet10, Tri6};
        check_hessians::<4, 2, Quad4>();
        check_hessians::<6, 2, Tri6>();
        check_hessians::<8, 2, Quad8>();
        check_hessians::<9, 2, Quad9>();
        check_hessians::<10, 3, Tet10>();
        check_hessians::<20, 3, Hex20>();
        check_hessians::<27, 3, Hex27>();
        check_hessians::<8, 3, Hex8>();
    }
}
