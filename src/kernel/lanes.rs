//! The bulk kernel of [`super::bulk`] for four cells at once, one per SIMD lane (AVX2: four
//! doubles): the solids and the linear medium with its p fields, most of a mesh.
//!
//! The laws are not here: they are `material`'s, evaluated in the lane type `V` (which
//! implements `material::Real`), the same code the one-cell kernel runs in `f64` — a solid
//! law's `Stress::isotropic_form`, `Conductivity::conductance`, `rotation_measure_of` and
//! `Regularization::penalty`. What this file does is move data: the four cells' nodal values
//! into lanes, the kinematics per point, the contraction of the laws' coefficients with the
//! shape gradients, and the lanes back into each cell's r and K.
//! With g_I the physical shape gradients, h_I = F⁻ᵀ g_I and f_I = F g_I:
//!
//! - r_u(I) = ∫ P g_I = ∫ c_H h_I + m f_I,
//! - ∂r_u(I,i)/∂u(K,k) = ∫ c1 h_Ii h_Kk + c2 h_Ki h_Ik + t (f_Ii h_Kk + h_Ii f_Kk)
//!   \+ m δ_ik g_I·g_K (the law's ∂P/∂F contracted with g_I and g_K),
//! - ∂r_u(I,i)/∂θ_K = ∫ e h_Ii N_K,
//! - for a solid law without that form (`isotropic_form` is `None`, e.g. Mooney-Rivlin): its
//!   P, ∂P/∂F and ∂P/∂θ from `Stress::stress`, lane by lane, and r_u(I,i) = ∫ P_iJ g_IJ,
//!   ∂r_u(I,i)/∂u(K,k) = ∫ A_iJkL g_IJ g_KL, ∂r_u(I,i)/∂θ_K = ∫ ∂P_iJ/∂θ g_IJ N_K,
//! - with Q = −(J k) C⁻¹ ∇θ, w = F⁻ᵀ ∇θ, v = C⁻¹ ∇θ = F⁻¹ w:
//!   r_θ(I) = ∫ J k v·g_I, ∂r_θ(I)/∂θ_K = ∫ J k h_I·h_K, and
//!   ∂r_θ(I)/∂u(K,k) = ∫ (k + J k') J (v·g_I) h_Kk − J k h_Ik (v·g_K) − J k w_k h_I·h_K;
//! - the regularization of eq. (20) per rotation plane (a, b): f and its derivatives involve
//!   only the gradients' a and b components, so every u–u term is a 2 × 2 bilinear form in
//!   (g_Ia, g_Ib) ⊗ (g_Ka, g_Kb).
//!
//! Which blocks may run here is decided once, by [`LaneBlock::new`]: there is no other way
//! in. Results equal the one-cell kernel's to round-off, on every CPU (the portable build is
//! tested where AVX2 is missing); the one-cell kernel stays the reference with its
//! finite-difference checks. The point loop is long on purpose: split into functions it
//! would pass its lane arrays (kilobytes per point) through memory.
#![allow(non_snake_case, clippy::needless_range_loop)]

use super::{Active, CellMaterial, CellSummary, KernelError};
use crate::dofs::{CellState, Layout};
use crate::element::RefElement;
use crate::material::regularization::{rotation_denominator, rotation_measure_of};
use crate::material::{Coefficients, Real, Stress};

/// Cells per call.
pub const W: usize = 4;

/// One value per lane.
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(32))]
struct V([f64; W]);

impl V {
    #[inline(always)]
    fn splat(x: f64) -> V {
        V([x; W])
    }
    /// self · b + c, fused.
    #[inline(always)]
    fn mul_add(self, b: V, c: V) -> V {
        let mut o = [0.0; W];
        for l in 0..W {
            o[l] = self.0[l].mul_add(b.0[l], c.0[l]);
        }
        V(o)
    }
}

macro_rules! lane_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl std::ops::$tr for V {
            type Output = V;
            #[inline(always)]
            fn $f(self, b: V) -> V {
                let mut o = [0.0; W];
                for l in 0..W {
                    o[l] = self.0[l] $op b.0[l];
                }
                V(o)
            }
        }
    };
}
lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl std::ops::Neg for V {
    type Output = V;
    #[inline(always)]
    fn neg(self) -> V {
        V(self.0.map(|x| -x))
    }
}

/// The laws evaluate four cells at once in this type (`material::Real`).
impl Real for V {
    #[inline(always)]
    fn splat(x: f64) -> V {
        V([x; W])
    }
    #[inline(always)]
    fn ln(self) -> V {
        V(self.0.map(f64::ln))
    }
    #[inline(always)]
    fn powf(self, e: f64) -> V {
        V(self.0.map(|x| x.powf(e)))
    }
    #[inline(always)]
    fn mul_add(self, b: V, c: V) -> V {
        V::mul_add(self, b, c)
    }
    #[inline(always)]
    fn select_ge(self, bound: V, a: V, b: V) -> V {
        V(std::array::from_fn(|l| {
            if self.0[l] >= bound.0[l] {
                a.0[l]
            } else {
                b.0[l]
            }
        }))
    }
}

/// Whether this CPU runs the lane kernel (AVX2 and FMA; elsewhere the one-cell kernel runs).
pub fn available() -> bool {
    super::avx2_fma()
}

/// A block of cells the lane kernel can run, and the only way to call it: u (with θ or
/// without, with the linear medium's p fields or without, their penalty per reference
/// volume), no direct regularization, and
/// every equation of the cell wanted. The laws themselves are the one-cell kernel's
/// (`material`, generic over the scalar), so any law a material holds is computed right.
#[derive(Clone, Copy, Debug)]
pub struct LaneBlock {
    mat: CellMaterial,
    lay: Layout,
}

impl LaneBlock {
    /// `Some` where the lanes can compute the block's cells with equations `act`.
    pub fn new(mat: &CellMaterial, lay: &Layout, act: Active) -> Option<LaneBlock> {
        let ok = lay.has_u
            && (lay.np == 0
                || (mat.reg.is_some_and(|r| r.volume_power == 0)
                    && lay.np == lay.dim * (lay.dim - 1) / 2))
            && mat.reg_direct.is_none()
            && act.mechanics
            && (!lay.has_theta || act.heat);
        ok.then_some(LaneBlock {
            mat: *mat,
            lay: *lay,
        })
    }
}

/// Residuals and, with `k`, tangents of the `W` cells `s` (lane l's in `r[l nd..]` and
/// `k[l nd²..]`, row-major, overwritten), and their summaries. On failure, the error and the
/// lowest lane it occurred in. Compiled for AVX2 and FMA where
/// the CPU has them ([`available`]: the assembly uses the lanes only there), portable
/// elsewhere.
pub fn bulk_lanes<const N: usize, const D: usize, E: RefElement<N, D>>(
    blk: &LaneBlock,
    s: &[CellState<N>; W],
    r: &mut [f64],
    k: Option<&mut [f64]>,
) -> Result<[CellSummary; W], (KernelError, usize)> {
    #[cfg(target_arch = "x86_64")]
    if available() {
        // SAFETY: the CPU has the features the function is compiled for (checked above)
        return unsafe {
            match k {
                Some(k) => bulk_lanes_avx2::<N, D, E, true>(blk, s, r, k),
                None => bulk_lanes_avx2::<N, D, E, false>(blk, s, r, &mut []),
            }
        };
    }
    bulk_lanes_portable::<N, D, E>(blk, s, r, k)
}

/// [`bulk_lanes`] without instruction-set features: the same lane code, compiled for any CPU,
/// with a plain transpose of the interleaved tangent.
pub fn bulk_lanes_portable<const N: usize, const D: usize, E: RefElement<N, D>>(
    blk: &LaneBlock,
    s: &[CellState<N>; W],
    r: &mut [f64],
    k: Option<&mut [f64]>,
) -> Result<[CellSummary; W], (KernelError, usize)> {
    let Some(k) = k else {
        return body::<N, D, E, false>(blk, s, r, &mut []);
    };
    let mut kw = vec![0.0; k.len()];
    let out = body::<N, D, E, true>(blk, s, r, &mut kw)?;
    let n = kw.len() / W;
    for i in 0..n {
        for l in 0..W {
            k[l * n + i] = kw[W * i + l];
        }
    }
    Ok(out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn bulk_lanes_avx2<
    const N: usize,
    const D: usize,
    E: RefElement<N, D>,
    const TANGENT: bool,
>(
    blk: &LaneBlock,
    s: &[CellState<N>; W],
    r: &mut [f64],
    k: &mut [f64],
) -> Result<[CellSummary; W], (KernelError, usize)> {
    if !TANGENT {
        return body::<N, D, E, TANGENT>(blk, s, r, k);
    }
    // The body writes each tangent entry of the four cells with one store, lane-interleaved;
    // 4 × 4 transposes then give each cell its row-major tangent. Cheaper than four scalar
    // stores per entry.
    thread_local! {
        static INTERLEAVED: std::cell::Cell<Vec<f64>> = const { std::cell::Cell::new(Vec::new()) };
    }
    let mut kw = INTERLEAVED.take();
    kw.resize(k.len(), 0.0);
    let out = body::<N, D, E, TANGENT>(blk, s, r, &mut kw);
    if out.is_ok() {
        // SAFETY: the CPU has AVX2 (this function's features)
        unsafe { deinterleave(&kw, k) };
    }
    INTERLEAVED.set(kw);
    out
}

/// `k[l n + i] = kw[W i + l]` for the `W` lanes and `n = kw.len() / W` entries, four entries
/// of the four lanes at a time by a 4 × 4 transpose.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn deinterleave(kw: &[f64], k: &mut [f64]) {
    use std::arch::x86_64::*;
    assert!(W == 4 && kw.len() == k.len() && kw.len().is_multiple_of(W));
    let n = kw.len() / W;
    let tiles = n / 4;
    let (src, dst) = (kw.as_ptr(), k.as_mut_ptr());
    for t in 0..tiles {
        let i = 4 * t;
        // SAFETY: entries i..i + 4 of every lane are in bounds (i + 4 ≤ n)
        unsafe {
            // e_j: entry i + j of the four lanes
            let e0 = _mm256_loadu_pd(src.add(W * i));
            let e1 = _mm256_loadu_pd(src.add(W * (i + 1)));
            let e2 = _mm256_loadu_pd(src.add(W * (i + 2)));
            let e3 = _mm256_loadu_pd(src.add(W * (i + 3)));
            let lo01 = _mm256_unpacklo_pd(e0, e1);
            let hi01 = _mm256_unpackhi_pd(e0, e1);
            let lo23 = _mm256_unpacklo_pd(e2, e3);
            let hi23 = _mm256_unpackhi_pd(e2, e3);
            _mm256_storeu_pd(dst.add(i), _mm256_permute2f128_pd(lo01, lo23, 0x20));
            _mm256_storeu_pd(dst.add(n + i), _mm256_permute2f128_pd(hi01, hi23, 0x20));
            _mm256_storeu_pd(dst.add(2 * n + i), _mm256_permute2f128_pd(lo01, lo23, 0x31));
            _mm256_storeu_pd(dst.add(3 * n + i), _mm256_permute2f128_pd(hi01, hi23, 0x31));
        }
    }
    for i in 4 * tiles..n {
        for l in 0..W {
            k[l * n + i] = kw[W * i + l];
        }
    }
}

/// Lowest lane where `bad` holds.
#[inline(always)]
fn first_lane(v: V, bad: impl Fn(f64) -> bool) -> Option<usize> {
    (0..W).find(|&l| bad(v.0[l]))
}

/// Determinant and inverse of a 3×3 matrix of lanes (by cofactors).
#[inline(always)]
fn det_inv(a: &[[V; 3]; 3]) -> (V, [[V; 3]; 3]) {
    let cof = cofactors(a);
    let det = a[0][0] * cof[0][0] + a[0][1] * cof[0][1] + a[0][2] * cof[0][2];
    let mut one_over = [0.0; W];
    for l in 0..W {
        one_over[l] = 1.0 / det.0[l];
    }
    let one_over = V(one_over);
    let mut inv = [[V::default(); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            inv[i][j] = cof[j][i] * one_over;
        }
    }
    (det, inv)
}

/// cof[i][j] = ∂ det a / ∂a_ij.
#[inline(always)]
fn cofactors(a: &[[V; 3]; 3]) -> [[V; 3]; 3] {
    let m =
        |r0: usize, c0: usize, r1: usize, c1: usize| a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0];
    [
        [m(1, 1, 2, 2), m(1, 2, 2, 0), m(1, 0, 2, 1)],
        [m(2, 1, 0, 2), m(2, 2, 0, 0), m(2, 0, 0, 1)],
        [m(0, 1, 1, 2), m(0, 2, 1, 0), m(0, 0, 1, 1)],
    ]
}

/// On failure, the error and the lowest lane it occurred in.
type LaneResult<T> = Result<T, (KernelError, usize)>;

/// P, ∂P/∂F (9 × 9, index pair (i, J) ↦ 3 i + J) and ∂P/∂θ, lane by lane: a solid law's
/// response at one point where it has no [`Stress::isotropic_form`].
struct FullStress {
    P: [[V; 3]; 3],
    A: [[V; 9]; 9],
    dP_dtheta: [[V; 3]; 3],
}

/// The energy of `law` at F and θ, and its coefficient form where it has one; otherwise
/// `None`, with [`Stress::stress`] per lane in `full`.
#[inline(always)]
fn point_stress<L: Stress>(
    law: &L,
    F: &[[V; 3]; 3],
    (J, I1, theta): (V, V, V),
    full: &mut FullStress,
) -> LaneResult<(V, Option<Coefficients<V>>)> {
    if let Some((psi, co)) = law.isotropic_form(J, I1, theta) {
        return Ok((psi, Some(co)));
    }
    let mut psi = V::default();
    for l in 0..W {
        let Fl = nalgebra::Matrix3::from_fn(|i, j| F[i][j].0[l]);
        let Some(resp) = law.stress(&Fl, theta.0[l]) else {
            return Err((KernelError::Inverted { J: J.0[l] }, l));
        };
        psi.0[l] = resp.psi;
        for i in 0..3 {
            for j in 0..3 {
                full.P[i][j].0[l] = resp.P[(i, j)];
                full.dP_dtheta[i][j].0[l] = resp.dP_dtheta[(i, j)];
            }
        }
        for a in 0..9 {
            for b in 0..9 {
                full.A[a][b].0[l] = resp.dP_dF[(a, b)];
            }
        }
    }
    Ok((psi, None))
}

/// r_u(I,i) += ∫ P_iJ g_IJ and, with `TANGENT`, the upper blocks of
/// ∂r_u(I,i)/∂u(K,k) += ∫ A_iJkL g_IJ g_KL, for a law's full tensors.
#[inline(always)]
fn contract_full<const N: usize, const D: usize, const TANGENT: bool>(
    fs: &FullStress,
    g: &[[V; 3]; N],
    dV: V,
    ru: &mut [[V; 3]; N],
    kuu: &mut [[[[V; 3]; 3]; N]; N],
) {
    let zero = V::default();
    for I in 0..N {
        for i in 0..D {
            let mut pg = zero;
            for J in 0..D {
                pg = fs.P[i][J].mul_add(g[I][J], pg);
            }
            ru[I][i] = pg.mul_add(dV, ru[I][i]);
        }
    }
    if !TANGENT {
        return;
    }
    // ag[I][i][k][L] = dV Σ_J A_iJkL g_IJ, then contracted with g_KL
    let mut ag = [[[[zero; 3]; 3]; 3]; N];
    for I in 0..N {
        for i in 0..D {
            for k in 0..D {
                for L in 0..D {
                    let mut a = zero;
                    for J in 0..D {
                        a = fs.A[3 * i + J][3 * k + L].mul_add(g[I][J], a);
                    }
                    ag[I][i][k][L] = a * dV;
                }
            }
        }
    }
    for I in 0..N {
        for K in I..N {
            let blk = &mut kuu[I][K];
            for i in 0..D {
                for k in 0..D {
                    for L in 0..D {
                        blk[i][k] = ag[I][i][k][L].mul_add(g[K][L], blk[i][k]);
                    }
                }
            }
        }
    }
}

/// The point loop of [`body_of`] for the law the block holds, compiled per law.
#[inline(always)]
fn body<const N: usize, const D: usize, E: RefElement<N, D>, const TANGENT: bool>(
    blk: &LaneBlock,
    s: &[CellState<N>; W],
    r: &mut [f64],
    k: &mut [f64],
) -> Result<[CellSummary; W], (KernelError, usize)> {
    crate::with_solid_law!(&blk.mat.law, |law| body_of::<N, D, E, TANGENT, _>(
        law, blk, s, r, k
    ))
}

#[inline(always)]
fn body_of<const N: usize, const D: usize, E: RefElement<N, D>, const TANGENT: bool, L: Stress>(
    law: &L,
    blk: &LaneBlock,
    s: &[CellState<N>; W],
    r: &mut [f64],
    k: &mut [f64],
) -> Result<[CellSummary; W], (KernelError, usize)> {
    let (mat, lay) = (&blk.mat, &blk.lay);
    let nd = lay.ndof();
    let thermal = lay.has_theta;
    let zero = V::default();
    // the cells' nodal data, lane by lane
    let mut X = [[zero; 3]; N];
    let mut U = [[zero; 3]; N];
    let mut T = [zero; N];
    let np = lay.np;
    let mut Pn = [[zero; 3]; N];
    for l in 0..W {
        for I in 0..N {
            for c in 0..D {
                X[I][c].0[l] = s[l].X[I][c];
                U[I][c].0[l] = s[l].u[I][c];
            }
            T[I].0[l] = s[l].theta[I];
            for c in 0..np {
                Pn[I][c].0[l] = s[l].p[I][c];
            }
        }
    }
    // tangent blocks summed over the points: kuu[I][K] (K ≥ I) = ∂r_u(I)/∂u(K),
    // kut[I][i][K] = ∂r_u(I,i)/∂θ_K, ktu[I][K][k] = ∂r_θ(I)/∂u(K,k), ktt[I][K] (K ≥ I)
    let mut kuu = [[[[zero; 3]; 3]; N]; N];
    let mut kut = [[[zero; N]; 3]; N];
    let mut ktu = [[[zero; 3]; N]; N];
    let mut ktt = [[zero; N]; N];
    // regularization: kup[c][I][K][x] = ∂r_u(I, x-th component of plane c)/∂p(K, c),
    // kpp[c][I][K] (K ≥ I)
    let mut kup = [[[[zero; 2]; N]; N]; 3];
    let mut kpp = [[[zero; N]; N]; 3];
    let mut ru = [[zero; 3]; N];
    let mut rt = [zero; N];
    let mut rp = [[zero; 3]; N];
    let mut energy = zero;
    let mut min_J = V::splat(f64::INFINITY);
    // a law's full tensors at the point, where it has no coefficient form
    let mut full = FullStress {
        P: [[zero; 3]; 3],
        A: [[zero; 9]; 9],
        dP_dtheta: [[zero; 3]; 3],
    };
    for (xi, w) in E::quadrature() {
        let dN = E::grad(xi);
        let Nv = E::shape(xi);
        // ∂X/∂ξ, padded to 3×3 in 2D
        let mut jac = [[zero; 3]; 3];
        for c in D..3 {
            jac[c][c] = V::splat(1.0);
        }
        for I in 0..N {
            for i in 0..D {
                for j in 0..D {
                    jac[i][j] = X[I][i].mul_add(V::splat(dN[I][j]), jac[i][j]);
                }
            }
        }
        let (det, inv) = det_inv(&jac);
        if let Some(l) = first_lane(det, |d| !(d > 0.0)) {
            return Err((KernelError::BadGeometry, l));
        }
        let dV = det * V::splat(*w);
        // physical gradients g[I][c] = Σ_j ∂N_I/∂ξ_j ∂ξ_j/∂X_c (zero beyond D)
        let mut g = [[zero; 3]; N];
        for I in 0..N {
            for c in 0..D {
                for j in 0..D {
                    g[I][c] = V::splat(dN[I][j]).mul_add(inv[j][c], g[I][c]);
                }
            }
        }
        let mut F = [[zero; 3]; 3];
        for c in 0..3 {
            F[c][c] = V::splat(1.0);
        }
        let mut theta = V::splat(law.theta0());
        let mut gt = [zero; 3];
        for I in 0..N {
            for i in 0..D {
                for J in 0..D {
                    F[i][J] = U[I][i].mul_add(g[I][J], F[i][J]);
                }
            }
        }
        if thermal {
            theta = zero;
            for I in 0..N {
                theta = V::splat(Nv[I]).mul_add(T[I], theta);
                for J in 0..D {
                    gt[J] = T[I].mul_add(g[I][J], gt[J]);
                }
            }
        }
        let cof = cofactors(&F);
        let J = F[0][0] * cof[0][0] + F[0][1] * cof[0][1] + F[0][2] * cof[0][2];
        if let Some(l) = first_lane(J, |j| !(j > 0.0) || !j.is_finite()) {
            return Err((KernelError::Inverted { J: J.0[l] }, l));
        }
        let mut I1 = zero;
        for i in 0..3 {
            for j in 0..3 {
                I1 = F[i][j].mul_add(F[i][j], I1);
            }
        }
        // the solid law, evaluated for the four cells at once
        let (psi, iso) = point_stress(law, &F, (J, I1, theta), &mut full)?;
        for l in 0..W {
            min_J.0[l] = min_J.0[l].min(J.0[l]);
        }
        energy = psi.mul_add(dV, energy);
        let mut Jinv = [0.0; W];
        for l in 0..W {
            Jinv[l] = 1.0 / J.0[l];
        }
        let Jinv = V(Jinv);
        // H = F⁻ᵀ
        let mut H = [[zero; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                H[i][j] = cof[i][j] * Jinv;
            }
        }
        // h_I = H g_I, f_I = F g_I
        let mut h = [[zero; 3]; N];
        let mut f = [[zero; 3]; N];
        for I in 0..N {
            for c in 0..3 {
                for L in 0..D {
                    h[I][c] = H[c][L].mul_add(g[I][L], h[I][c]);
                    f[I][c] = F[c][L].mul_add(g[I][L], f[I][c]);
                }
            }
        }
        if let Some(co) = &iso {
            // P g_I = c_H h_I + m f_I
            let mdV = co.m * dV;
            let c_h = co.c_H * dV;
            for I in 0..N {
                for i in 0..D {
                    ru[I][i] = c_h.mul_add(h[I][i], mdV.mul_add(f[I][i], ru[I][i]));
                }
            }
            if TANGENT {
                // ∂r_u/∂u: per node e_I = c1 h_I + t f_I, q_I = c2 h_I, t_I = t h_I (all × dV)
                let c1 = co.c1 * dV;
                let c2 = co.c2 * dV;
                let tw = co.t * dV;
                let mut e = [[zero; 3]; N];
                let mut q = [[zero; 3]; N];
                let mut t = [[zero; 3]; N];
                for I in 0..N {
                    for i in 0..3 {
                        e[I][i] = c1.mul_add(h[I][i], tw * f[I][i]);
                        q[I][i] = c2 * h[I][i];
                        t[I][i] = tw * h[I][i];
                    }
                }
                for I in 0..N {
                    for K in I..N {
                        let mut gg = zero;
                        for c in 0..D {
                            gg = g[I][c].mul_add(g[K][c], gg);
                        }
                        let blk = &mut kuu[I][K];
                        for i in 0..D {
                            for kk in 0..D {
                                blk[i][kk] = e[I][i].mul_add(
                                    h[K][kk],
                                    q[K][i]
                                        .mul_add(h[I][kk], t[I][i].mul_add(f[K][kk], blk[i][kk])),
                                );
                            }
                            blk[i][i] = mdV.mul_add(gg, blk[i][i]);
                        }
                    }
                }
            }
        } else {
            contract_full::<N, D, TANGENT>(&full, &g, dV, &mut ru, &mut kuu);
        }
        if np > 0 {
            let reg = mat.reg.expect("a cell with p fields has a regularization");
            let b2 = V::splat(reg.beta2);
            for c in 0..np {
                let (xa, xb) = crate::material::ROTATION_PLANES[c];
                let sden = rotation_denominator(&F, c);
                if let Some(l) = first_lane(sden, |v| !(v.abs() > 1e-12)) {
                    return Err((KernelError::Singular, l));
                }
                let rm = rotation_measure_of(&F, c);
                // p and ∇p of this component
                let mut pv = zero;
                let mut gp = [zero; 3];
                for I in 0..N {
                    pv = V::splat(Nv[I]).mul_add(Pn[I][c], pv);
                    for J in 0..D {
                        gp[J] = Pn[I][c].mul_add(g[I][J], gp[J]);
                    }
                }
                let (psi, d1, d2) = reg.penalty(rm.f, pv);
                let (d1f, d1p) = (d1[0] * dV, d1[1] * dV);
                let (d2ff, d2fp, d2pp) = (d2[0][0] * dV, d2[0][1] * dV, d2[1][1] * dV);
                let mut gp2 = zero;
                for J in 0..D {
                    gp2 = gp[J].mul_add(gp[J], gp2);
                }
                energy = (psi + V::splat(0.5) * b2 * gp2).mul_add(dV, energy);
                // the measure's entries of F by (component x of the plane, gradient
                // component u): row (a, b)[x], column (a, b)[u]; ∂f/∂u(I, x) = Σ_u
                // bf[x][u] g_I(u), and ∂²f is read from the same entries
                const AT: [[usize; 2]; 2] = [[2, 0], [1, 3]];
                let bf: [[V; 2]; 2] =
                    std::array::from_fn(|x| std::array::from_fn(|u| rm.grad[AT[x][u]]));
                // the 2 × 2 bilinear forms M[x][y][u][v] (u: I's vector, v: K's vector) of
                // d²ψ/df² ∂f ⊗ ∂f + dψ/df ∂²f
                let mut M = [[[[zero; 2]; 2]; 2]; 2];
                for x in 0..2 {
                    for y in 0..2 {
                        for u in 0..2 {
                            for v in 0..2 {
                                let h2 = rm.hess[AT[x][u]][AT[y][v]];
                                M[x][y][u][v] = (d2ff * bf[x][u]).mul_add(bf[y][v], d1f * h2);
                            }
                        }
                    }
                }
                let xs = [xa, xb];
                let gab = |I: usize| [g[I][xa], g[I][xb]];
                for I in 0..N {
                    let gi = gab(I);
                    // r_u, r_p
                    for x in 0..2 {
                        let dfdu = bf[x][0].mul_add(gi[0], bf[x][1] * gi[1]);
                        ru[I][xs[x]] = d1f.mul_add(dfdu, ru[I][xs[x]]);
                        if TANGENT {
                            for K in 0..N {
                                kup[c][I][K][x] =
                                    (d2fp * dfdu).mul_add(V::splat(Nv[K]), kup[c][I][K][x]);
                            }
                        }
                    }
                    let mut gpg = zero;
                    for J in 0..D {
                        gpg = gp[J].mul_add(g[I][J], gpg);
                    }
                    rp[I][c] = (b2 * dV).mul_add(gpg, d1p.mul_add(V::splat(Nv[I]), rp[I][c]));
                    if !TANGENT {
                        continue;
                    }
                    // A[x][y][v] = Σ_u M[x][y][u][v] g_I(u)
                    let mut A = [[[zero; 2]; 2]; 2];
                    for x in 0..2 {
                        for y in 0..2 {
                            for v in 0..2 {
                                A[x][y][v] = M[x][y][0][v].mul_add(gi[0], M[x][y][1][v] * gi[1]);
                            }
                        }
                    }
                    for K in I..N {
                        let gk = gab(K);
                        let blk = &mut kuu[I][K];
                        for x in 0..2 {
                            for y in 0..2 {
                                blk[xs[x]][xs[y]] = A[x][y][0]
                                    .mul_add(gk[0], A[x][y][1].mul_add(gk[1], blk[xs[x]][xs[y]]));
                            }
                        }
                        let mut gg = zero;
                        for J in 0..D {
                            gg = g[I][J].mul_add(g[K][J], gg);
                        }
                        kpp[c][I][K] = (d2pp * V::splat(Nv[I]))
                            .mul_add(V::splat(Nv[K]), (b2 * dV).mul_add(gg, kpp[c][I][K]));
                    }
                }
            }
        }
        if thermal {
            // w = F⁻ᵀ ∇θ, v = F⁻¹ w = C⁻¹ ∇θ
            let mut wv = [zero; 3];
            for c in 0..3 {
                for L in 0..D {
                    wv[c] = H[c][L].mul_add(gt[L], wv[c]);
                }
            }
            let mut v = [zero; 3];
            for Jc in 0..3 {
                for c in 0..3 {
                    v[Jc] = H[c][Jc].mul_add(wv[c], v[Jc]);
                }
            }
            let (_, Jk, dJk) = mat.cond.conductance(J);
            let (Jk, dJk) = (Jk * dV, dJk * dV);
            let mut sv = [zero; N];
            for I in 0..N {
                for c in 0..D {
                    sv[I] = v[c].mul_add(g[I][c], sv[I]);
                }
                rt[I] = Jk.mul_add(sv[I], rt[I]);
            }
            if !TANGENT {
                continue;
            }
            for I in 0..N {
                for i in 0..D {
                    // ∂(P g_I)_i/∂θ dV
                    let a_i = match &iso {
                        Some(co) => co.e * dV * h[I][i],
                        None => {
                            let mut a = zero;
                            for J in 0..D {
                                a = full.dP_dtheta[i][J].mul_add(g[I][J], a);
                            }
                            a * dV
                        }
                    };
                    for K in 0..N {
                        kut[I][i][K] = a_i.mul_add(V::splat(Nv[K]), kut[I][i][K]);
                    }
                }
            }
            let mut Jkw = [zero; 3];
            for c in 0..D {
                Jkw[c] = Jk * wv[c];
            }
            for I in 0..N {
                let dJk_sv = dJk * sv[I];
                for K in 0..N {
                    let mut hh = zero;
                    for c in 0..D {
                        hh = h[I][c].mul_add(h[K][c], hh);
                    }
                    if K >= I {
                        ktt[I][K] = Jk.mul_add(hh, ktt[I][K]);
                    }
                    let Jk_svK = Jk * sv[K];
                    for kk in 0..D {
                        ktu[I][K][kk] =
                            ktu[I][K][kk] + dJk_sv * h[K][kk] - Jk_svK * h[I][kk] - Jkw[kk] * hh;
                    }
                }
            }
        }
    }
    // lanes back to the cells' residuals; the tangent stays lane-interleaved: one store per
    // entry for all four cells
    let th = |I: usize| lay.theta(I);
    let mut out = [CellSummary {
        min_J: 0.0,
        energy: 0.0,
    }; W];
    for l in 0..W {
        out[l] = CellSummary {
            min_J: min_J.0[l],
            energy: energy.0[l],
        };
        let r = &mut r[l * nd..(l + 1) * nd];
        for c in 0..np {
            for I in 0..N {
                r[lay.p(I, c)] = rp[I][c].0[l];
            }
        }
        for I in 0..N {
            for i in 0..D {
                r[lay.u(I, i)] = ru[I][i].0[l];
            }
            if thermal {
                r[th(I)] = rt[I].0[l];
            }
        }
    }
    if !TANGENT {
        return Ok(out);
    }
    // entry (a, b) of lane l at k[(a nd + b) W + l]; every entry is written
    let mut put = |a: usize, b: usize, v: V| {
        let at = (a * nd + b) * W;
        k[at..at + W].copy_from_slice(&v.0);
    };
    if np > 0 {
        // the p blocks are sparse (one plane's components, one p component each)
        for a in 0..nd {
            for b in 0..nd {
                put(a, b, zero);
            }
        }
        for c in 0..np {
            let (xa, xb) = crate::material::ROTATION_PLANES[c];
            for I in 0..N {
                for K in 0..N {
                    for (x, comp) in [xa, xb].into_iter().enumerate() {
                        let v = kup[c][I][K][x];
                        put(lay.u(I, comp), lay.p(K, c), v);
                        put(lay.p(K, c), lay.u(I, comp), v);
                    }
                    let v = if K >= I { kpp[c][I][K] } else { kpp[c][K][I] };
                    put(lay.p(I, c), lay.p(K, c), v);
                }
            }
        }
    }
    for I in 0..N {
        for K in I..N {
            let blk = &kuu[I][K];
            for i in 0..D {
                for kk in 0..D {
                    put(lay.u(I, i), lay.u(K, kk), blk[i][kk]);
                    put(lay.u(K, kk), lay.u(I, i), blk[i][kk]);
                }
            }
        }
    }
    if thermal {
        for I in 0..N {
            for i in 0..D {
                for K in 0..N {
                    put(lay.u(I, i), th(K), kut[I][i][K]);
                }
            }
            for K in 0..N {
                for kk in 0..D {
                    put(th(I), lay.u(K, kk), ktu[I][K][kk]);
                }
                put(th(I), th(K), if K >= I { ktt[I][K] } else { ktt[K][I] });
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{Hex8, Hex20, Hex27, Quad4, Quad9, Tet4, Tet10, Tri3};
    use crate::kernel::bulk;
    use crate::material::{Conductivity, MooneyRivlin, Regularization, SolidLaw, ThermoElastic};

    /// A rubber: a law without the coefficient form, contracted from its full ∂P/∂F.
    fn rubber(cond: Conductivity) -> CellMaterial {
        CellMaterial {
            law: SolidLaw::MooneyRivlin(MooneyRivlin {
                C10: 3.0,
                C01: 2.0,
                K: 20.0,
                alpha: 2e-3,
                theta0: 10.0,
            }),
            ..material(cond)
        }
    }

    fn material(cond: Conductivity) -> CellMaterial {
        CellMaterial {
            law: SolidLaw::NeoHooke(ThermoElastic {
                K: 20.0,
                mu: 10.0,
                alpha: 2e-3,
                theta0: 10.0,
            }),
            cond,
            medium: false,
            reg: None,
            reg_direct: None,
        }
    }

    /// Lane l's cell: a distorted, deformed and heated copy of the reference cell.
    fn state<const N: usize, const D: usize, E: RefElement<N, D>>(l: usize) -> CellState<N> {
        let mut s = CellState::<N>::zero();
        for (I, xi) in E::nodes().iter().enumerate() {
            for d in 0..D {
                s.X[I][d] =
                    (0.5 + 0.1 * l as f64) * xi[d] + 0.07 * ((I * 7 + d * 3 + l) % 5) as f64 / 5.0;
                s.u[I][d] = 0.08 * (((I * 3 + d * 5 + 2 * l) % 7) as f64 / 7.0 - 0.5);
            }
            s.theta[I] = 10.0 + 30.0 * ((I * 5 + l) % 4) as f64;
            for c in 0..3 {
                s.p[I][c] = 0.2 * (((I * 5 + c * 3 + l) % 7) as f64 / 7.0 - 0.5);
            }
        }
        s
    }

    /// The lanes give each cell what the one-cell kernel gives it, to round-off: the portable
    /// build on every CPU, and the AVX2 build where the CPU has it.
    fn same_as_one_cell<const N: usize, const D: usize, E: RefElement<N, D>>() {
        same_as_one_cell_with::<N, D, E>(bulk_lanes_portable::<N, D, E>);
        if available() {
            same_as_one_cell_with::<N, D, E>(bulk_lanes::<N, D, E>);
        }
    }

    type LaneKernel<const N: usize> = fn(
        &LaneBlock,
        &[CellState<N>; W],
        &mut [f64],
        Option<&mut [f64]>,
    ) -> Result<[CellSummary; W], (KernelError, usize)>;

    fn same_as_one_cell_with<const N: usize, const D: usize, E: RefElement<N, D>>(
        lanes: LaneKernel<N>,
    ) {
        let medium = Conductivity::Medium {
            k_tm: 3.0,
            k_max: 50.0,
        };
        let regularized = CellMaterial {
            reg: Some(Regularization {
                beta1: 0.7,
                beta2: 0.3,
                d: 1.7,
                volume_power: 0,
            }),
            medium: true,
            ..material(medium)
        };
        for (mat, np) in [
            (material(Conductivity::Constant(3.0)), 0),
            (material(medium), 0),
            (regularized, D * (D - 1) / 2),
            (rubber(Conductivity::Constant(3.0)), 0),
        ] {
            for has_theta in [true, false] {
                let lay = Layout {
                    n: N,
                    dim: D,
                    has_u: true,
                    has_theta,
                    np,
                };
                let blk = LaneBlock::new(&mat, &lay, Active::ALL).expect("lanes run it");
                for part in [
                    Active {
                        mechanics: true,
                        heat: false,
                    },
                    Active {
                        mechanics: false,
                        heat: true,
                    },
                ] {
                    assert_eq!(
                        LaneBlock::new(&mat, &lay, part).is_some(),
                        !has_theta && part.mechanics
                    );
                }
                let nd = lay.ndof();
                let s: [CellState<N>; W] = std::array::from_fn(state::<N, D, E>);
                let (mut r, mut k) = (vec![f64::NAN; W * nd], vec![f64::NAN; W * nd * nd]);
                let out = lanes(&blk, &s, &mut r, Some(&mut k)).unwrap();
                // without the tangent: the same residuals and summaries
                let mut r_only = vec![f64::NAN; W * nd];
                let out_r = lanes(&blk, &s, &mut r_only, None).unwrap();
                assert_eq!(r_only, r);
                for l in 0..W {
                    assert_eq!(out_r[l].energy, out[l].energy);
                    assert_eq!(out_r[l].min_J, out[l].min_J);
                }
                for l in 0..W {
                    let (mut r1, mut k1) = (vec![0.0; nd], vec![0.0; nd * nd]);
                    let one =
                        bulk::<N, D, E>(&mat, &lay, &s[l], Active::ALL, &mut r1, Some(&mut k1))
                            .unwrap();
                    let close = |a: &[f64], b: &[f64]| {
                        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                        for (i, (x, y)) in a.iter().zip(b).enumerate() {
                            assert!(
                                (x - y).abs() <= 1e-12 * scale,
                                "{} lane {l} entry {i}: {x} vs {y}",
                                std::any::type_name::<E>()
                            );
                        }
                    };
                    close(&r[l * nd..(l + 1) * nd], &r1);
                    close(&k[l * nd * nd..(l + 1) * nd * nd], &k1);
                    assert!((out[l].energy - one.energy).abs() <= 1e-12 * one.energy.abs());
                    assert!((out[l].min_J - one.min_J).abs() <= 1e-14 * one.min_J);
                }
            }
        }
    }

    #[test]
    fn lanes_match_the_one_cell_kernel() {
        same_as_one_cell::<3, 2, Tri3>();
        same_as_one_cell::<4, 2, Quad4>();
        same_as_one_cell::<9, 2, Quad9>();
        same_as_one_cell::<4, 3, Tet4>();
        same_as_one_cell::<8, 3, Hex8>();
        same_as_one_cell::<10, 3, Tet10>();
        same_as_one_cell::<20, 3, Hex20>();
        same_as_one_cell::<27, 3, Hex27>();
    }

    /// A hex8 solid's layout: u and θ.
    const HEX8_U_THETA: Layout = Layout {
        n: 8,
        dim: 3,
        has_u: true,
        has_theta: true,
        np: 0,
    };

    /// Every solid law runs in lanes: the law is not what decides.
    #[test]
    fn any_solid_law_runs_in_lanes() {
        for mat in [
            material(Conductivity::Constant(1.0)),
            rubber(Conductivity::Constant(1.0)),
        ] {
            assert!(LaneBlock::new(&mat, &HEX8_U_THETA, Active::ALL).is_some());
        }
    }

    #[test]
    fn an_inverted_lane_is_reported() {
        for mat in [
            material(Conductivity::Constant(1.0)),
            rubber(Conductivity::Constant(1.0)),
        ] {
            inverted_lane_is_reported(&mat);
        }
    }

    fn inverted_lane_is_reported(mat: &CellMaterial) {
        let lay = HEX8_U_THETA;
        let mut s: [CellState<8>; W] = std::array::from_fn(state::<8, 3, Hex8>);
        // lane 2 squashed through itself along z
        for I in 0..8 {
            s[2].u[I][2] = -2.0 * s[2].X[I][2];
        }
        let nd = lay.ndof();
        let (mut r, mut k) = (vec![0.0; W * nd], vec![0.0; W * nd * nd]);
        for lanes in [bulk_lanes::<8, 3, Hex8>, bulk_lanes_portable::<8, 3, Hex8>] {
            let blk = LaneBlock::new(mat, &lay, Active::ALL).unwrap();
            match lanes(&blk, &s, &mut r, Some(&mut k)) {
                Err((KernelError::Inverted { J }, 2)) => assert!(J <= 0.0),
                other => panic!("{other:?}"),
            }
        }
    }
}
