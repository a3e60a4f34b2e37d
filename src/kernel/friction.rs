//! Friction in a medium cell: the Coulomb slip term of [`crate::material::friction`] added to
//! the medium's own terms (which the bulk kernel assembles), and the heat its slip makes.
//!
//! r_u(I,i) = ∫ P_f,iJ ∂N_I/∂X_J dV,   r_θ(I) = −∫ (η/Δt) D N_I dV,
//!
//! with D = τ · (g − gₙ) the step's dissipation per reference volume and η the fraction of it
//! that becomes heat. The tangent is exact and unsymmetric (Coulomb's limit moves with the
//! normal traction). History per quadrature point: the slip g (3 values), the work
//! dissipated so far (1 value), the slip of the step, g − gₙ (3 values, for output) and the
//! normal traction p_n (1 value, the limit's where it is lagged), read from the last accepted
//! step and written for the trial.
#![allow(non_snake_case)]

use super::point::{Point, point};
use super::{Active, KernelError};
use crate::dofs::{CellState, Layout};
use crate::element::RefElement;
use crate::material::friction::{
    Friction, MediumStress, plane_shear as shear_of, plane_stress, shear_modulus,
};
use crate::material::{SolidLaw, Tensor4};
use nalgebra::{Matrix3, Vector3};

/// History values per quadrature point: the slip (x, y, z), the work the point has dissipated
/// so far (its dissipation per reference volume times its share of the cell's volume, as the
/// heat source takes it: a cell whose reference changes keeps what it dissipated), the slip
/// of the step (x, y, z) and the normal traction p_n, from these offsets.
pub const HISTORY_PER_POINT: usize = 8;
const WORK: usize = 3;
const STEP: usize = 4;
const P_N: usize = 7;

/// The friction of a medium region (its slip planes are per cell: see `normal` of
/// [`friction`]).
#[derive(Clone, Copy, Debug)]
pub struct FrictionMaterial {
    /// Coulomb's coefficient μ_f ≥ 0.
    pub mu: f64,
    /// The medium's own law: the normal traction across the plane is its stress, and the
    /// friction modulus scales with its bulk modulus.
    pub medium: SolidLaw,
    /// c_f of the friction modulus G_f ([`shear_modulus`]).
    pub c_f: f64,
    /// η_s, the slip's viscosity (0: rate-independent).
    pub viscosity: f64,
    /// The Coulomb limit from the last accepted step's normal traction (fixed within a step)
    /// where that pressed the plane; from the current one where it did not (at the start, and
    /// where the medium was open), so that nothing slips freely while the plane first closes.
    pub lagged: bool,
    /// The medium's own law taken at the elastic part of its deformation, F_e = F A with
    /// A = I − gₙ⊗N (gₙ the last accepted step's slip), instead of at F: the slip the plane has
    /// accepted is no longer the medium's distortion, so the medium neither resists the slide
    /// nor pushes the faces apart as it is sheared. The bulk kernel assembles the law at F;
    /// this kernel adds the difference (P(F A) Aᵀ − P(F), and its exact derivative in F), and
    /// the plane's normal traction is taken from P(F A) Aᵀ.
    pub forget_slip: bool,
    /// The plane carries its traction alone, P = F τ ⊗ N
    /// ([`crate::material::friction::plane_stress`]): a medium made again.
    pub traction_only: bool,
}

/// The medium's own stress at the elastic part F A of the deformation F (A = I − slip⊗N),
/// as a function of F: P(F A) Aᵀ, its derivative in F (9×9, (3i + J, 3k + L)) and in θ.
fn at_elastic_part(
    law: &SolidLaw,
    F: &Matrix3<f64>,
    theta: f64,
    slip: &Vector3<f64>,
    normal: &Vector3<f64>,
) -> Option<(Matrix3<f64>, Tensor4, Matrix3<f64>)> {
    let A = Matrix3::identity() - slip * normal.transpose();
    let m = law.stress(&(F * A), theta)?;
    // ∂(P(F A) Aᵀ)_iJ/∂F_kL = Σ_MN ∂P_iM/∂F_kN A_LN A_JM
    let dP = Tensor4::from_fn(|row, col| {
        let (i, J, k, L) = (row / 3, row % 3, col / 3, col % 3);
        let mut v = 0.0;
        for M in 0..3 {
            for Nn in 0..3 {
                v += m.dP_dF[(3 * i + M, 3 * k + Nn)] * A[(L, Nn)] * A[(J, M)];
            }
        }
        v
    });
    Some((m.P * A.transpose(), dP, m.dP_dtheta * A.transpose()))
}

/// The plane's shear per reference thickness, γ = P C N, at each of the cell's quadrature
/// points (`gamma`, 3 values per point), with slip-plane unit normal `normal`.
pub fn plane_shear<const N: usize, const D: usize, E: RefElement<N, D>>(
    normal: &Vector3<f64>,
    lay: &Layout,
    s: &CellState<N>,
    gamma: &mut [f64],
) -> Result<(), KernelError> {
    for (q, (xi, w)) in E::quadrature().iter().enumerate() {
        let F = point::<N, D, E>(xi, *w, lay, s, 0.0)?.F;
        let shear = shear_of(&F, normal);
        gamma[3 * q..3 * q + 3].copy_from_slice(shear.as_slice());
    }
    Ok(())
}

/// The cell's volume ratio J at its first quadrature point.
pub fn volume_ratio<const N: usize, const D: usize, E: RefElement<N, D>>(
    lay: &Layout,
    s: &CellState<N>,
) -> Result<f64, KernelError> {
    let (xi, w) = &E::quadrature()[0];
    Ok(point::<N, D, E>(xi, *w, lay, s, 0.0)?.F.determinant())
}

/// Shift the slip of one cell's history (`HISTORY_PER_POINT` values per point) by `shift`
/// (3 values per point): a cell whose reference configuration moves measures the plane's
/// shear from elsewhere, and its elastic shear γ − g must stay what it was.
pub fn shift_slip(history: &mut [f64], shift: &[f64]) {
    for (h, d) in history.chunks_mut(HISTORY_PER_POINT).zip(shift.chunks(3)) {
        for i in 0..3 {
            h[i] += d[i];
        }
    }
}

/// What a point with history `h` (the last accepted step's) transmits across its slip plane
/// of unit normal `normal` at the deformation `F`: its traction F τ as a share φ ∈ [0, 1] of
/// its Coulomb limit μ p_n, and that traction's direction in the current configuration (zero
/// where it carries none). A medium made again carries these on ([`carried_cell`]): a share
/// of the limit, not a traction, so that a point that slipped slips on at its own limit
/// wherever the new cells put the normal traction. The direction is that of the traction on
/// the side the plane's current normal n points to, given as e ⊗ n (n's sign is the normal's,
/// which a new cell may have the other way round).
pub fn transmitted(
    mat: &FrictionMaterial,
    normal: &Vector3<f64>,
    F: &Matrix3<f64>,
    h: &[f64],
) -> (f64, Matrix3<f64>) {
    let J = F.determinant();
    let limit = mat.mu * h[P_N];
    let none = (0.0, Matrix3::zeros());
    let Some(Finv) = F.try_inverse() else {
        return none;
    };
    if J <= 0.0 || limit.is_nan() || limit <= 0.0 {
        return none;
    }
    let (G, _) = shear_modulus(mat.c_f, mat.medium.bulk_modulus(), J);
    let t = F * ((shear_of(F, normal) - Vector3::new(h[0], h[1], h[2])) * G);
    let n = (Finv.transpose() * normal).normalize();
    match t.norm() {
        size if size > 0.0 => ((size / limit).min(1.0), t * n.transpose() / size),
        _ => none,
    }
}

/// The history of one new friction cell (state `s`, slip-plane unit normal `normal`) of a
/// medium made again, into `out` (`HISTORY_PER_POINT` values per point), and its points'
/// reference volumes into `dV`. `old(y)` says what the medium it replaces transmitted at the
/// current place y ([`transmitted`]): the share φ of the Coulomb limit and the traction's
/// direction e ⊗ n. Each point's slip g is set so that its traction F τ, τ = G_f(J) (γ − g),
/// is φ of its own limit μ p_n (p_n from the medium's stress at its F), along e (taken on the
/// side its own n points to) as it lies in the point's plane; where its plane is open, τ = 0.
/// Its step's slip is nil, its normal traction its p_n, its work nil (the caller shares out
/// the old medium's).
pub fn carried_cell<const N: usize, const D: usize, E: RefElement<N, D>>(
    mat: &FrictionMaterial,
    normal: &Vector3<f64>,
    lay: &Layout,
    s: &CellState<N>,
    old: impl Fn(&[f64; 3]) -> (f64, Matrix3<f64>),
    out: &mut [f64],
    dV: &mut [f64],
) -> Result<(), KernelError> {
    for (q, (xi, w)) in E::quadrature().iter().enumerate() {
        let p = point::<N, D, E>(xi, *w, lay, s, mat.medium.theta0())?;
        let inverted = KernelError::Inverted {
            J: p.F.determinant(),
        };
        let m = mat.medium.stress(&p.F, p.theta).ok_or(inverted)?;
        let Finv = p.F.try_inverse().ok_or(inverted)?;
        let n = (Finv.transpose() * normal).normalize();
        let p_n = -n.dot(&(m.P * normal));
        let (phi, en) = old(&place::<N, D, E>(s, xi));
        let e = en * n;
        // the direction as it lies in this point's plane, F τ ⊥ n (τ ⊥ N)
        let along = e - n * n.dot(&e);
        let tau = match along.norm() {
            size if p_n > 0.0 && phi > 0.0 && size > 0.0 => {
                Finv * along * (phi * mat.mu * p_n / size)
            }
            _ => Vector3::zeros(),
        };
        let (G, _) = shear_modulus(mat.c_f, mat.medium.bulk_modulus(), m.J);
        let slip = shear_of(&p.F, normal) - tau / G;
        let h = &mut out[q * HISTORY_PER_POINT..(q + 1) * HISTORY_PER_POINT];
        h.fill(0.0);
        h[..3].copy_from_slice(slip.as_slice());
        h[P_N] = p_n;
        dV[q] = p.dV;
    }
    Ok(())
}

/// The current place of the point ξ of the cell `s`.
fn place<const N: usize, const D: usize, E: RefElement<N, D>>(
    s: &CellState<N>,
    xi: &[f64; D],
) -> [f64; 3] {
    let shape = E::shape(xi);
    std::array::from_fn(|i| (0..N).map(|I| shape[I] * (s.X[I][i] + s.u[I][i])).sum())
}

/// Give the points of a history (`HISTORY_PER_POINT` values per point) the work
/// `per_volume` times their reference volumes `dV`.
pub fn share_work(history: &mut [f64], dV: &[f64], per_volume: f64) {
    for (h, v) in history.chunks_mut(HISTORY_PER_POINT).zip(dV) {
        h[WORK] = per_volume * v;
    }
}

/// Residual and (optionally) tangent of the friction term of one medium cell with slip-plane
/// unit normal `normal`, from the history `committed` of the last accepted step; writes the
/// trial history to `trial`. `heat_rate` is
/// η/Δt (0 where no heat is made). `r` and `k` (row-major, the cell's u (and θ) layout) are
/// overwritten.
#[allow(clippy::too_many_arguments)]
pub fn friction<const N: usize, const D: usize, E: RefElement<N, D>>(
    mat: &FrictionMaterial,
    normal: &Vector3<f64>,
    heat_rate: f64,
    inv_dt: f64,
    lay: &Layout,
    s: &CellState<N>,
    committed: &[f64],
    trial: &mut [f64],
    act: Active,
    r: &mut [f64],
    mut k: Option<&mut [f64]>,
) -> Result<(), KernelError> {
    let nd = lay.ndof();
    super::zero_local(nd, r, k.as_deref_mut());
    let mechanics = lay.has_u && act.mechanics;
    let heat = lay.has_theta && act.heat && heat_rate > 0.0;
    for (q, (xi, w)) in E::quadrature().iter().enumerate() {
        let Point {
            g,
            Nv,
            dV,
            F,
            theta,
            ..
        } = point::<N, D, E>(xi, *w, lay, s, mat.medium.theta0())?;
        let inverted = KernelError::Inverted { J: F.determinant() };
        let m = mat.medium.stress(&F, theta).ok_or(inverted)?;
        let h = &committed[q * HISTORY_PER_POINT..(q + 1) * HISTORY_PER_POINT];
        let slip = Vector3::new(h[0], h[1], h[2]);
        // the law's stress at F_e where the slip is forgotten, and what it adds to the bulk's
        let elastic = match mat.forget_slip {
            true => Some(at_elastic_part(&mat.medium, &F, theta, &slip, normal).ok_or(inverted)?),
            false => None,
        };
        let (mP, mdP, mdT) = elastic
            .as_ref()
            .map_or((&m.P, &m.dP_dF, &m.dP_dtheta), |(P, dP, dT)| (P, dP, dT));
        let law = Friction {
            mu: mat.mu,
            normal: *normal,
            rate: mat.viscosity * inv_dt,
            lagged: mat.lagged.then_some(h[P_N]).filter(|&p| p > 0.0),
            traction_only: mat.traction_only,
        };
        let medium = MediumStress {
            P: mP,
            dP_dF: mdP,
            dP_dtheta: mdT,
        };
        let f = law
            .respond::<D>(
                &F,
                &slip,
                shear_modulus(mat.c_f, mat.medium.bulk_modulus(), m.J),
                &medium,
            )
            .ok_or(inverted)?;
        let now = &mut trial[q * HISTORY_PER_POINT..(q + 1) * HISTORY_PER_POINT];
        now[..3].copy_from_slice(f.slip.as_slice());
        now[WORK] = h[WORK] + f.dissipated * dV;
        for (d, (g1, g0)) in now[STEP..P_N].iter_mut().zip(f.slip.iter().zip(&slip)) {
            *d = g1 - g0;
        }
        now[P_N] = f.p_n;
        // the stress this kernel assembles: the plane's, and the law's at F_e less at F
        let corrected = elastic.as_ref().map(|(P, dP, dT)| {
            (
                f.P + P - m.P,
                f.dP_dF + dP - m.dP_dF,
                f.dP_dtheta + dT - m.dP_dtheta,
            )
        });
        let (P, dP_dF, dP_dtheta) = corrected
            .as_ref()
            .map_or((&f.P, &f.dP_dF, &f.dP_dtheta), |(P, dP, dT)| (P, dP, dT));
        if mechanics {
            for I in 0..N {
                for i in 0..D {
                    let v: f64 = (0..D).map(|J| P[(i, J)] * g[I][J]).sum();
                    r[lay.u(I, i)] += v * dV;
                }
            }
        }
        if heat {
            let source = heat_rate * f.dissipated * dV;
            for I in 0..N {
                r[lay.theta(I)] -= source * Nv[I];
            }
        }
        let Some(k) = k.as_deref_mut() else {
            continue;
        };
        if mechanics {
            for I in 0..N {
                for i in 0..D {
                    let row = lay.u(I, i) * nd;
                    for K in 0..N {
                        for kk in 0..D {
                            let mut v = 0.0;
                            for J in 0..D {
                                for L in 0..D {
                                    v += g[I][J] * dP_dF[(3 * i + J, 3 * kk + L)] * g[K][L];
                                }
                            }
                            k[row + lay.u(K, kk)] += v * dV;
                        }
                    }
                    if lay.has_theta {
                        let v: f64 = (0..D).map(|J| dP_dtheta[(i, J)] * g[I][J]).sum();
                        for K in 0..N {
                            k[row + lay.theta(K)] += v * Nv[K] * dV;
                        }
                    }
                }
            }
        }
        if heat {
            let c = heat_rate * dV;
            for I in 0..N {
                let row = lay.theta(I) * nd;
                for K in 0..N {
                    k[row + lay.theta(K)] -= c * f.ddissipated_dtheta * Nv[I] * Nv[K];
                    if mechanics {
                        for kk in 0..D {
                            let v: f64 = (0..D).map(|L| f.ddissipated_dF[(kk, L)] * g[K][L]).sum();
                            k[row + lay.u(K, kk)] -= c * v * Nv[I];
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// The work dissipated by slip in one cell so far, Σ over its points of ∫ D dV, from its
/// history.
pub fn dissipated_work(history: &[f64]) -> f64 {
    (history.chunks(HISTORY_PER_POINT)).map(|h| h[WORK]).sum()
}

/// A friction cell's state for output: volume averages over its points.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SlipFields {
    /// The slip g, a shear per reference thickness of the medium (dimensionless).
    pub slip: [f64; 3],
    /// The slip of the last accepted step, g − gₙ.
    pub increment: [f64; 3],
    /// The share of the cell's volume that slipped in that step: 0 stick, 1 full slip.
    pub slipping: f64,
    /// The Cauchy stress the slip plane adds to the medium's own, σ_f = F S_f Fᵀ / J.
    pub stress: [[f64; 3]; 3],
}

/// The state of one friction cell with slip-plane unit normal `normal` for output, at the
/// accepted state `s` whose history is `history`. Its stress is the plane's at that state:
/// τ = G_f(J) (γ − g), S_f = N⊗τ + τ⊗N, since the slip the return left makes τ the elastic
/// shear the step ended with.
pub fn slip_fields<const N: usize, const D: usize, E: RefElement<N, D>>(
    mat: &FrictionMaterial,
    normal: &Vector3<f64>,
    lay: &Layout,
    s: &CellState<N>,
    history: &[f64],
) -> Result<SlipFields, KernelError> {
    let mut out = SlipFields::default();
    let mut volume = 0.0;
    let mut stress = Matrix3::zeros();
    for (q, (xi, w)) in E::quadrature().iter().enumerate() {
        let Point { dV, F, theta, .. } = point::<N, D, E>(xi, *w, lay, s, mat.medium.theta0())?;
        let J = F.determinant();
        if J <= 0.0 {
            return Err(KernelError::Inverted { J });
        }
        let h = &history[q * HISTORY_PER_POINT..(q + 1) * HISTORY_PER_POINT];
        let slip = Vector3::new(h[0], h[1], h[2]);
        let (G, _) = shear_modulus(mat.c_f, mat.medium.bulk_modulus(), J);
        let tau = (shear_of(&F, normal) - slip) * G;
        stress += F * plane_stress(normal, &tau, mat.traction_only) * F.transpose() / J * dV;
        if mat.forget_slip {
            // the accepted state's slip is this history's: the law's stress at that F_e, less
            // the bulk's at F, as a Cauchy stress
            let inverted = KernelError::Inverted { J };
            let prior = slip - Vector3::new(h[STEP], h[STEP + 1], h[STEP + 2]);
            let (Pe, _, _) =
                at_elastic_part(&mat.medium, &F, theta, &prior, normal).ok_or(inverted)?;
            let P = mat.medium.stress(&F, theta).ok_or(inverted)?.P;
            stress += (Pe - P) * F.transpose() / J * dV;
        }
        for d in 0..3 {
            out.slip[d] += h[d] * dV;
            out.increment[d] += h[STEP + d] * dV;
        }
        if h[STEP..P_N].iter().any(|&d| d != 0.0) {
            out.slipping += dV;
        }
        volume += dV;
    }
    for d in 0..3 {
        out.slip[d] /= volume;
        out.increment[d] /= volume;
        for e in 0..3 {
            out.stress[d][e] = stress[(d, e)] / volume;
        }
    }
    out.slipping /= volume;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{Hex8, Quad4, Tet4, Tri3};

    const NORMAL: Vector3<f64> = Vector3::new(0.0, 1.0, 0.0);
    const MATERIAL: FrictionMaterial = FrictionMaterial {
        mu: 0.3,
        medium: SolidLaw::NeoHooke(crate::material::ThermoElastic {
            K: 1e-2,
            mu: 1e-2,
            alpha: 1e-2,
            theta0: 10.0,
        }),
        c_f: 1.0,
        viscosity: 0.0,
        lagged: false,
        forget_slip: false,
        traction_only: false,
    };

    /// 1/Δt of the checks' step (the slip viscosity acts over it).
    const INV_DT: f64 = 4.0;

    /// A cell closed to a fifth of its height, slid along x and distorted a little, at
    /// temperatures that vary over it; every point's previous slip is 0.01 along x and its
    /// previous normal traction 0.05.
    fn state<const N: usize, const D: usize, E: RefElement<N, D>>() -> (CellState<N>, Vec<f64>) {
        let mut s = CellState::<N>::zero();
        for (I, xi) in E::nodes().iter().enumerate() {
            for d in 0..D {
                s.X[I][d] = 0.5 * xi[d] + 0.04 * ((I * 7 + d * 3) % 5) as f64 / 5.0;
            }
            let y = s.X[I][1];
            s.u[I][0] = 0.3 * y + 0.01 * ((I * 3) % 4) as f64;
            s.u[I][1] = -0.8 * y + 0.005 * ((I * 5) % 3) as f64;
            s.theta[I] = 10.0 + 30.0 * ((I * 5) % 4) as f64;
        }
        let nq = E::quadrature().len();
        let mut h = vec![0.0; nq * HISTORY_PER_POINT];
        for q in 0..nq {
            h[q * HISTORY_PER_POINT] = 0.01;
            h[q * HISTORY_PER_POINT + P_N] = 0.05;
            h[q * HISTORY_PER_POINT + WORK] = 0.7;
        }
        (s, h)
    }

    /// A cell's accepted state handed to a new cell that is the same cell: each point's
    /// share of its limit and its traction's direction ([`transmitted`]) give back the slip
    /// and the normal traction the step left ([`carried_cell`]), and the plane's stress
    /// N⊗τ + τ⊗N is the same when the new cell's normal points the other way.
    fn carried_round_trip<const N: usize, const D: usize, E: RefElement<N, D>>(
        mat: &FrictionMaterial,
    ) {
        let (s, committed) = state::<N, D, E>();
        let lay = Layout {
            n: N,
            dim: D,
            has_u: true,
            has_theta: false,
            np: 0,
        };
        let (_, trial) = residual_of::<N, D, E>(mat, 0.0, &lay, &s, &committed);
        let nq = E::quadrature().len();
        let mut sent = Vec::new();
        for (q, (xi, w)) in E::quadrature().iter().enumerate() {
            let p = point::<N, D, E>(xi, *w, &lay, &s, mat.medium.theta0()).unwrap();
            let h = &trial[q * HISTORY_PER_POINT..(q + 1) * HISTORY_PER_POINT];
            let y = place::<N, D, E>(&s, xi);
            sent.push((y, transmitted(mat, &NORMAL, &p.F, h), p.F));
        }
        let old = |y: &[f64; 3]| {
            let d = |a: &[f64; 3]| (0..3).map(|i| (a[i] - y[i]).powi(2)).sum::<f64>();
            let k = (0..sent.len())
                .min_by(|&a, &b| d(&sent[a].0).total_cmp(&d(&sent[b].0)))
                .unwrap();
            sent[k].1
        };
        for normal in [NORMAL, -NORMAL] {
            let (mut out, mut dV) = (vec![0.0; nq * HISTORY_PER_POINT], vec![0.0; nq]);
            carried_cell::<N, D, E>(mat, &normal, &lay, &s, old, &mut out, &mut dV).unwrap();
            for q in 0..nq {
                let (h, c) = (
                    &trial[q * HISTORY_PER_POINT..(q + 1) * HISTORY_PER_POINT],
                    &out[q * HISTORY_PER_POINT..(q + 1) * HISTORY_PER_POINT],
                );
                let F = sent[q].2;
                let (G, _) = shear_modulus(mat.c_f, mat.medium.bulk_modulus(), F.determinant());
                let stress = |n: &Vector3<f64>, g: &[f64]| {
                    crate::material::friction::plane_pair(
                        n,
                        &((shear_of(&F, n) - Vector3::new(g[0], g[1], g[2])) * G),
                    )
                };
                let (was, is) = (stress(&NORMAL, h), stress(&normal, c));
                assert!(
                    (was - is).norm() <= 1e-9 * was.norm(),
                    "{normal:?}: {was} then {is}"
                );
                assert!(
                    (c[P_N] - h[P_N]).abs() <= 1e-12 * h[P_N].abs(),
                    "p_n {} then {}",
                    h[P_N],
                    c[P_N]
                );
                assert!(dV[q] > 0.0 && c[WORK] == 0.0);
            }
        }
    }

    #[test]
    fn a_cell_handed_its_own_state_carries_its_slip_and_stress() {
        // slipping (μ = 0.3) and sticking (μ large) points
        for mu in [0.3, 50.0] {
            let mat = FrictionMaterial { mu, ..MATERIAL };
            carried_round_trip::<3, 2, Tri3>(&mat);
            carried_round_trip::<4, 2, Quad4>(&mat);
            carried_round_trip::<4, 3, Tet4>(&mat);
            carried_round_trip::<8, 3, Hex8>(&mat);
        }
    }

    /// The friction residual of the cell `s` under `mat` from the history `committed` (heat
    /// made at `heat_rate`), without its tangent, and the trial history it wrote.
    fn residual_of<const N: usize, const D: usize, E: RefElement<N, D>>(
        mat: &FrictionMaterial,
        heat_rate: f64,
        lay: &Layout,
        s: &CellState<N>,
        committed: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        let mut trial = committed.to_vec();
        let mut r = vec![0.0; lay.ndof()];
        friction::<N, D, E>(
            mat,
            &NORMAL,
            heat_rate,
            INV_DT,
            lay,
            s,
            committed,
            &mut trial,
            Active::ALL,
            &mut r,
            None,
        )
        .unwrap();
        (r, trial)
    }

    /// Central differences of the residual (u rows and the heat) against the tangent, for a
    /// material under which the cell `slips` or sticks.
    fn check<const N: usize, const D: usize, E: RefElement<N, D>>(
        mat: &FrictionMaterial,
        slips: bool,
    ) {
        let lay = Layout {
            n: N,
            dim: D,
            has_u: true,
            has_theta: true,
            np: 0,
        };
        let nd = lay.ndof();
        let (s, committed) = state::<N, D, E>();
        let mut trial = committed.clone();
        let (mut r, mut k) = (vec![0.0; nd], vec![0.0; nd * nd]);
        let heat_rate = 2.5;
        friction::<N, D, E>(
            mat,
            &NORMAL,
            heat_rate,
            INV_DT,
            &lay,
            &s,
            &committed,
            &mut trial,
            Active::ALL,
            &mut r,
            Some(&mut k),
        )
        .unwrap();
        // whether the points slipped: their slip moved and work was dissipated
        for q in 0..E::quadrature().len() {
            let h = &trial[q * HISTORY_PER_POINT..];
            assert_eq!(h[0] != 0.01, slips, "{N} nodes: point {q} slip {}", h[0]);
            assert_eq!(
                h[WORK] > 0.7,
                slips,
                "{N} nodes: point {q} work {}",
                h[WORK]
            );
        }
        // the cell's output: every point slipped or none did, by g − gₙ
        let cell = slip_fields::<N, D, E>(mat, &NORMAL, &lay, &s, &trial).unwrap();
        assert_eq!(cell.slipping, if slips { 1.0 } else { 0.0 }, "{N} nodes");
        // its stress is the one the residual carries: on a cell of one point (a linear
        // simplex, F constant) P_f = J σ_f F⁻ᵀ gives the residual's u rows back
        if E::quadrature().len() == 1 {
            let (xi, w) = &E::quadrature()[0];
            let Point { g, dV, F, .. } = point::<N, D, E>(xi, *w, &lay, &s, 0.0).unwrap();
            let sigma = Matrix3::from_fn(|i, j| cell.stress[i][j]);
            let P = sigma * F.transpose().try_inverse().unwrap() * F.determinant();
            let size = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for I in 0..N {
                for i in 0..D {
                    let v: f64 = (0..D).map(|J| P[(i, J)] * g[I][J]).sum::<f64>() * dV;
                    assert!(
                        (v - r[lay.u(I, i)]).abs() < 1e-12 * size,
                        "{N} nodes: node {I}, {i}: {v} against {}",
                        r[lay.u(I, i)]
                    );
                }
            }
        }
        for d in 0..3 {
            let before = if d == 0 { 0.01 } else { 0.0 };
            let step = cell.slip[d] - before;
            assert!(
                (cell.increment[d] - step).abs() < 1e-14,
                "{N} nodes: {cell:?}"
            );
            assert_eq!(
                cell.increment[d] != 0.0,
                slips && step != 0.0,
                "{N} nodes: {cell:?}"
            );
        }
        let scale = k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let h = 1e-7;
        let (mut rp, mut rm) = (vec![0.0; nd], vec![0.0; nd]);
        let mut scratch = committed.clone();
        for b in 0..nd {
            let perturb = |e: f64| {
                let mut t = s;
                if b < N * D {
                    t.u[b / D][b % D] += e;
                } else {
                    t.theta[b - N * D] += e;
                }
                t
            };
            for (out, e) in [(&mut rp, h), (&mut rm, -h)] {
                let t = perturb(e);
                friction::<N, D, E>(
                    mat,
                    &NORMAL,
                    heat_rate,
                    INV_DT,
                    &lay,
                    &t,
                    &committed,
                    &mut scratch,
                    Active::ALL,
                    out,
                    None,
                )
                .unwrap();
            }
            for a in 0..nd {
                let fd = (rp[a] - rm[a]) / (2.0 * h);
                assert!(
                    (fd - k[a * nd + b]).abs() < 1e-6 * scale,
                    "{N} nodes, slipping {slips}: K[{a},{b}] = {} vs FD {fd}",
                    k[a * nd + b]
                );
            }
        }
        // the heat rows: the source while slipping, nothing in stick
        let heat: f64 = (0..N).map(|I| -r[lay.theta(I)]).sum();
        assert_eq!(heat > 0.0, slips, "heat {heat}");
        if slips {
            // Σ_I of the source is the rate times the step's dissipation, ∫ D dV
            let work = dissipated_work(&trial) - dissipated_work(&committed);
            assert!(
                (heat - heat_rate * work).abs() < 1e-12 * heat,
                "{heat} vs {work}"
            );
        }
    }

    #[test]
    fn a_lagged_limit_takes_the_current_traction_where_the_last_did_not_press() {
        let lay = Layout {
            n: 4,
            dim: 2,
            has_u: true,
            has_theta: true,
            np: 0,
        };
        let (s, mut committed) = state::<4, 2, Quad4>();
        let residual = |mat: &FrictionMaterial, committed: &[f64]| {
            residual_of::<4, 2, Quad4>(mat, 2.5, &lay, &s, committed).0
        };
        let lagged = FrictionMaterial {
            lagged: true,
            ..MATERIAL
        };
        // pressed at the last step (0.05): the limit differs from the current one's
        assert_ne!(
            residual(&lagged, &committed),
            residual(&MATERIAL, &committed)
        );
        // not pressed (open, or the start): the current one, exactly
        for q in 0..Quad4::quadrature().len() {
            committed[q * HISTORY_PER_POINT + P_N] = -0.01;
        }
        assert_eq!(
            residual(&lagged, &committed),
            residual(&MATERIAL, &committed)
        );
    }

    #[test]
    fn the_friction_tangent_is_the_derivative_of_its_residual_in_slip_and_in_stick() {
        // μ = 0.3: the sheared cell slides, with a viscosity too; μ = 100: it sticks
        let stuck = FrictionMaterial {
            mu: 100.0,
            ..MATERIAL
        };
        let viscous = FrictionMaterial {
            viscosity: 0.05,
            ..MATERIAL
        };
        check::<4, 2, Quad4>(&viscous, true);
        check::<8, 3, Hex8>(&viscous, true);
        let lagged = FrictionMaterial {
            lagged: true,
            ..MATERIAL
        };
        check::<3, 2, Tri3>(&lagged, true);
        check::<8, 3, Hex8>(&lagged, true);
        check::<3, 2, Tri3>(&MATERIAL, true);
        check::<4, 2, Quad4>(&MATERIAL, true);
        check::<4, 3, Tet4>(&MATERIAL, true);
        check::<8, 3, Hex8>(&MATERIAL, true);
        check::<3, 2, Tri3>(&stuck, false);
        check::<4, 2, Quad4>(&stuck, false);
        check::<8, 3, Hex8>(&stuck, false);
        // the medium's law at the elastic part F (I − gₙ⊗N), and the plane's traction alone
        // (a medium made again), in slip and in stick
        for mat in [MATERIAL, stuck, viscous] {
            let slips = mat.mu < 1.0;
            for variant in [
                FrictionMaterial {
                    forget_slip: true,
                    ..mat
                },
                FrictionMaterial {
                    traction_only: true,
                    ..mat
                },
            ] {
                check::<3, 2, Tri3>(&variant, slips);
                check::<4, 2, Quad4>(&variant, slips);
                check::<4, 3, Tet4>(&variant, slips);
                check::<8, 3, Hex8>(&variant, slips);
            }
        }
    }

    #[test]
    fn a_forgotten_slip_is_the_medium_s_law_at_its_elastic_part() {
        // with the slip forgotten the kernel adds P(F A) Aᵀ − P(F) to the plane's stress,
        // A = I − gₙ⊗N: with no accepted slip (gₙ = 0) that is nothing, and with one it is the
        // law's difference, read on a one-point cell at μ = 0 (where the plane carries nothing)
        let lay = Layout {
            n: 3,
            dim: 2,
            has_u: true,
            has_theta: true,
            np: 0,
        };
        let (s, committed) = state::<3, 2, Tri3>();
        let residual = |mat: &FrictionMaterial, committed: &[f64]| {
            residual_of::<3, 2, Tri3>(mat, 0.0, &lay, &s, committed).0
        };
        let free = FrictionMaterial {
            mu: 0.0,
            ..MATERIAL
        };
        let forgetting = FrictionMaterial {
            forget_slip: true,
            ..free
        };
        let mut none = committed.clone();
        none.iter_mut()
            .step_by(HISTORY_PER_POINT)
            .for_each(|g| *g = 0.0);
        assert_eq!(residual(&forgetting, &none), residual(&free, &none));
        let (xi, w) = &Tri3::quadrature()[0];
        let Point {
            g, dV, F, theta, ..
        } = point::<3, 2, Tri3>(xi, *w, &lay, &s, MATERIAL.medium.theta0()).unwrap();
        let slip = Vector3::new(0.01, 0.0, 0.0);
        let A = Matrix3::identity() - slip * NORMAL.transpose();
        let law = |F: &Matrix3<f64>| MATERIAL.medium.stress(F, theta).unwrap().P;
        let difference = law(&(F * A)) * A.transpose() - law(&F);
        let (with, without) = (
            residual(&forgetting, &committed),
            residual(&free, &committed),
        );
        let size = difference.iter().fold(0.0f64, |a, v| a.max(v.abs())) * dV;
        assert!(size > 0.0, "the accepted slip changes the law's stress");
        for I in 0..3 {
            for i in 0..2 {
                let v: f64 = (0..2).map(|J| difference[(i, J)] * g[I][J]).sum::<f64>() * dV;
                let seen = with[lay.u(I, i)] - without[lay.u(I, i)];
                assert!(
                    (seen - v).abs() < 1e-12 * size,
                    "node {I}, {i}: {seen} against the law's {v}"
                );
            }
        }
    }
}
