//! Element kernels: from a cell's reference data and local unknowns, the local residual and
//! tangent. Only the assembler touches global arrays.
//!
//! Local dof order is field-blocked: u (node-major, `D` components), then θ, then p.
#![allow(non_snake_case)]

pub mod lanes;

use crate::element::{RefElement, invert_small, physical_gradients};
use crate::material::{
    Conductivity, Regularization, ThermoElastic, fourier, rotation_measure, rotation_measure_d3,
};
use nalgebra::{Matrix3, Vector3};

/// Material of a cell block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellMaterial {
    pub law: ThermoElastic,
    pub cond: Conductivity,
    pub medium: bool,
    /// Regularization of a linear medium cell (eq. 20); used when the layout carries p.
    pub reg: Option<Regularization>,
    /// Weight c = γ α_r of the direct regularization of a quadratic medium cell (eq. 18).
    pub reg_direct: Option<f64>,
}

/// Which fields a cell carries locally.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub n: usize,
    pub dim: usize,
    pub has_u: bool,
    pub has_theta: bool,
    /// Regularization components on this cell's nodes (0 outside the medium).
    pub np: usize,
}

impl Layout {
    pub fn u(&self, node: usize, c: usize) -> usize {
        node * self.dim + c
    }
    pub fn theta_off(&self) -> usize {
        if self.has_u { self.n * self.dim } else { 0 }
    }
    pub fn theta(&self, node: usize) -> usize {
        self.theta_off() + node
    }
    pub fn p_off(&self) -> usize {
        self.theta_off() + if self.has_theta { self.n } else { 0 }
    }
    pub fn p(&self, node: usize, c: usize) -> usize {
        self.p_off() + node * self.np + c
    }
    pub fn ndof(&self) -> usize {
        self.p_off() + self.n * self.np
    }
}

/// Nodal data of one cell.
#[derive(Clone, Copy, Debug)]
pub struct CellState<const N: usize> {
    pub X: [[f64; 3]; N],
    pub u: [[f64; 3]; N],
    pub theta: [f64; N],
    /// Regularization unknowns p_i per node (components beyond `Layout::np` unused).
    pub p: [[f64; 3]; N],
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KernelError {
    /// The undeformed cell has a non-positive Jacobian (broken mesh).
    BadGeometry,
    /// J ≤ 0 (or not finite) at a quadrature point.
    Inverted { J: f64 },
    /// A rotation measure of the regularization is unbounded (F_aa + F_bb = 0).
    Singular,
}

/// What a kernel call reports besides r and K.
#[derive(Clone, Copy, Debug)]
pub struct CellSummary {
    pub min_J: f64,
    /// Stored mechanical energy ∫ Ψ dV.
    pub energy: f64,
}

/// Deformation gradient (plane strain in 2D) and temperature gradient at a point.
#[inline(always)]
fn kinematics<const N: usize, const D: usize>(
    g: &[[f64; D]; N],
    s: &CellState<N>,
    has_u: bool,
) -> (Matrix3<f64>, Vector3<f64>) {
    let mut F = Matrix3::identity();
    let mut gt = Vector3::zeros();
    for I in 0..N {
        for J in 0..D {
            if has_u {
                for i in 0..D {
                    F[(i, J)] += s.u[I][i] * g[I][J];
                }
            }
            gt[J] += s.theta[I] * g[I][J];
        }
    }
    (F, gt)
}

/// Everything a law needs at one quadrature point.
struct Point<const N: usize, const D: usize> {
    /// Physical shape gradients ∂N_I/∂X.
    g: [[f64; D]; N],
    Nv: [f64; N],
    dV: f64,
    F: Matrix3<f64>,
    grad_theta: Vector3<f64>,
    theta: f64,
}

#[inline(always)]
fn point<const N: usize, const D: usize, E: RefElement<N, D>>(
    xi: &[f64; D],
    w: f64,
    lay: &Layout,
    s: &CellState<N>,
    theta_ref: f64,
) -> Result<Point<N, D>, KernelError> {
    let (g, detJ) =
        physical_gradients::<N, D>(&E::grad(xi), &s.X).ok_or(KernelError::BadGeometry)?;
    let Nv = E::shape(xi);
    let (F, grad_theta) = kinematics(&g, s, lay.has_u);
    // without temperature unknowns the body stays at θ0 (no expansion)
    let theta = if lay.has_theta {
        Nv.iter().zip(&s.theta).map(|(a, b)| a * b).sum()
    } else {
        theta_ref
    };
    Ok(Point {
        g,
        Nv,
        dV: w * detJ,
        F,
        grad_theta,
        theta,
    })
}

/// A node-by-node matrix: `[I][K]` couples node I's equation with node K's unknown.
type NodeBlock<const N: usize> = [[f64; N]; N];
/// ∂r_u/∂u by component pair: `[i][k]`, blocks i ≤ k only (K_uu is symmetric).
type UuBlocks<const N: usize> = [[NodeBlock<N>; 3]; 3];

/// The regularization's own tangent blocks: ∂r_u(a)/∂p(c) (K_pu is its transpose) and
/// ∂r_p(c)/∂p(c).
struct PBlocks<const N: usize> {
    up: [[NodeBlock<N>; 3]; 3],
    pp: [NodeBlock<N>; 3],
}

/// Which equations a kernel call fills: a one-way coupled solve needs only the mechanical rows
/// while it iterates on mechanics, and only the thermal rows (with their θ columns) after.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Active {
    pub mechanics: bool,
    pub heat: bool,
}

impl Active {
    pub const ALL: Active = Active {
        mechanics: true,
        heat: true,
    };
}

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
    #[cfg(target_arch = "x86_64")]
    if avx2_fma() {
        // SAFETY: the CPU has the features the function is compiled for (checked above)
        return unsafe { bulk_avx2::<N, D, E>(mat, lay, s, act, r, k) };
    }
    bulk_body::<N, D, E, Separate>(mat, lay, s, act, r, k)
}

/// Whether this CPU has AVX2 and FMA, the features the fast kernels are compiled for (the
/// check is cached by the standard library).
fn avx2_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// [`bulk`] compiled for AVX2 and FMA: the node-block loops (eight or four unknowns wide)
/// become 256-bit fused multiply-adds.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn bulk_avx2<const N: usize, const D: usize, E: RefElement<N, D>>(
    mat: &CellMaterial,
    lay: &Layout,
    s: &CellState<N>,
    act: Active,
    r: &mut [f64],
    k: Option<&mut [f64]>,
) -> Result<CellSummary, KernelError> {
    bulk_body::<N, D, E, Fused>(mat, lay, s, act, r, k)
}

/// a b + c, fused into one rounding where the instruction set has it.
trait MulAdd {
    fn mul_add(a: f64, b: f64, c: f64) -> f64;
}

/// One instruction (only where the caller is compiled with FMA: elsewhere a library call).
struct Fused;
/// A multiply and an add.
struct Separate;

impl MulAdd for Fused {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a.mul_add(b, c)
    }
}

impl MulAdd for Separate {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a * b + c
    }
}

#[inline(always)]
fn bulk_body<const N: usize, const D: usize, E: RefElement<N, D>, M: MulAdd>(
    mat: &CellMaterial,
    lay: &Layout,
    s: &CellState<N>,
    act: Active,
    r: &mut [f64],
    mut k: Option<&mut [f64]>,
) -> Result<CellSummary, KernelError> {
    let nd = lay.ndof();
    r[..nd].fill(0.0);
    if let Some(k) = k.as_deref_mut() {
        k[..nd * nd].fill(0.0);
    }
    let mut summary = CellSummary {
        min_J: f64::INFINITY,
        energy: 0.0,
    };
    let theta_ref = mat.law.theta0;
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
            let m = mat
                .law
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

/// Regularization of a linear medium cell at one quadrature point, eq. (20): adds
/// ∂Ψ_Rf/∂(u, p) dV to `r` and its exact derivative (symmetric) to `k`; returns Ψ_Rf dV.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn regularization<const N: usize, const D: usize, M: MulAdd>(
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
        for I in 0..N {
            for a in 0..D {
                r[lay.u(I, a)] += d1[0] * Bf[a][I] * dV;
            }
            let gg: f64 = (0..D).map(|J| gp[J] * g[I][J]).sum();
            r[lay.p(I, c)] += (d1[1] * Nv[I] + reg.beta2 * gg) * dV;
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
    Ok(energy)
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
/// second derivatives `hX`. Adds the residual and exact tangent; returns Ψ_R dV.
#[allow(clippy::too_many_arguments)]
fn direct_regularization<const N: usize, const D: usize>(
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

/// Cell averages for output.
#[derive(Clone, Copy, Debug, Default)]
pub struct CellFields {
    pub J: f64,
    /// Cauchy stress σ = P Fᵀ / J.
    pub sigma: [[f64; 3]; 3],
    /// Current heat flux q = F Q / J.
    pub q: [f64; 3],
    pub k: f64,
}

/// Volume averages of J, σ, q and k over a cell.
pub fn cell_fields<const N: usize, const D: usize, E: RefElement<N, D>>(
    mat: &CellMaterial,
    lay: &Layout,
    s: &CellState<N>,
) -> Result<CellFields, KernelError> {
    let mut out = CellFields::default();
    let mut vol = 0.0;
    let mut sigma = Matrix3::zeros();
    let mut q = Vector3::zeros();
    for (xi, w) in E::quadrature() {
        let Point {
            dV,
            F,
            grad_theta: gt,
            theta,
            ..
        } = point::<N, D, E>(xi, *w, lay, s, mat.law.theta0)?;
        let m = mat
            .law
            .stress(&F, theta)
            .ok_or(KernelError::Inverted { J: F.determinant() })?;
        let h = fourier(&F, &gt, &mat.cond).ok_or(KernelError::Inverted { J: m.J })?;
        out.J += m.J * dV;
        sigma += m.P * F.transpose() / m.J * dV;
        if lay.has_theta {
            q += F * h.Q / m.J * dV;
        }
        out.k += h.k * dV;
        vol += dV;
    }
    out.J /= vol;
    out.k /= vol;
    sigma /= vol;
    q /= vol;
    for i in 0..3 {
        out.q[i] = q[i];
        for j in 0..3 {
            out.sigma[i][j] = sigma[(i, j)];
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{Hex8, Quad4, Tet4, Tri3};

    const SOLID: CellMaterial = CellMaterial {
        law: ThermoElastic {
            K: 20.0,
            mu: 10.0,
            alpha: 2e-3,
            theta0: 10.0,
        },
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
        law: ThermoElastic {
            K: 1e-2,
            mu: 1e-2,
            alpha: 1e-3,
            theta0: 10.0,
        },
        cond: Conductivity::Medium {
            k_tm: 0.5,
            k_max: 50.0,
        },
        medium: true,
        reg: Some(Regularization {
            beta1: 1.0,
            beta2: 0.3,
            d: 1.7,
        }),
        reg_direct: None,
    };

    /// A quadratic medium cell with the direct regularization of eq. 18 (no p fields).
    const MEDIUM_DIRECT: CellMaterial = CellMaterial {
        reg: None,
        reg_direct: Some(0.3),
        ..MEDIUM
    };

    /// Central differences of the residual against the tangent, column by column.
    fn check<const N: usize, const D: usize, E: RefElement<N, D>>(mat: &CellMaterial) {
        let np = if mat.reg.is_some() && mat.reg_direct.is_none() {
            if D == 2 { 1 } else { 3 }
        } else {
            0
        };
        let mut s = CellState::<N> {
            X: [[0.0; 3]; N],
            u: [[0.0; 3]; N],
            theta: [0.0; N],
            p: [[0.0; 3]; N],
        };
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
        let nd = lay.ndof();
        let mut r = vec![0.0; nd];
        let mut k = vec![0.0; nd * nd];
        bulk::<N, D, E>(mat, &lay, &s, Active::ALL, &mut r, Some(&mut k)).unwrap();
        // the instruction-set variant `bulk` dispatched to agrees with the portable one to
        // round-off (fused multiply-adds round once)
        let (mut r0, mut k0) = (vec![0.0; nd], vec![0.0; nd * nd]);
        bulk_body::<N, D, E, Separate>(mat, &lay, &s, Active::ALL, &mut r0, Some(&mut k0)).unwrap();
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
        let mut st = CellState::<9> {
            X: [[0.0; 3]; 9],
            u: [[0.0; 3]; 9],
            theta: [0.0; 9],
            p: [[0.0; 3]; 9],
        };
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

    #[test]
    fn medium_with_regularization_tangent_matches_finite_differences() {
        check::<3, 2, Tri3>(&MEDIUM);
        check::<4, 2, Quad4>(&MEDIUM);
        check::<4, 3, Tet4>(&MEDIUM);
        check::<8, 3, Hex8>(&MEDIUM);
    }
}
