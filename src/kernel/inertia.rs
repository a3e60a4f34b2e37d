//! Inertia: ρ ü by backward Euler in displacement and velocity,
//!
//! v = (u − uₙ)/Δt,   a = (v − vₙ)/Δt = (u − uₙ − Δt vₙ)/Δt²,
//!
//! r_u(I) = ∫ ρ a N_I dV,   ∂r_u(I)_i/∂u(K)_j = ∫ ρ/Δt² N_I N_K δ_ij dV,
//!
//! per reference volume (ρ is a mass per reference volume, so the term is linear in u). uₙ and
//! vₙ are the history of each quadrature point: u and v of the last accepted step there. A body
//! moving at constant velocity meets no force (a = 0); a body whose quasi-static path turns
//! (a slip event) meets a stiffness ρ/Δt² that grows as the step is cut, so the step problem
//! stays well posed while the body accelerates through the event. Backward Euler damps what it
//! cannot resolve (a period shorter than the step), as a quasi-static path wants.
#![allow(non_snake_case)]

use super::{Active, KernelError};
use crate::dofs::{CellState, Layout};
use crate::element::{RefElement, physical_gradients};

/// History values per quadrature point of a cell of dimension `d`: u, then v.
pub const fn history_per_point(d: usize) -> usize {
    2 * d
}

/// Residual and (optionally) tangent of the inertia term of one cell, with the mass density
/// `rho` and `inv_dt` = 1/Δt (0: no time passes, no inertia, the velocity kept), the history
/// `hist_n` (u then v at each quadrature point) and the trial history `hist_now` (filled
/// with this state's u and v). `r` and `k` (the cell's u-only layout, row-major) are
/// overwritten; without `act.mechanics` they are zero.
#[allow(clippy::too_many_arguments)]
pub fn inertia<const N: usize, const D: usize, E: RefElement<N, D>>(
    rho: f64,
    inv_dt: f64,
    lay: &Layout,
    s: &CellState<N>,
    hist_n: &[f64],
    hist_now: &mut [f64],
    act: Active,
    r: &mut [f64],
    mut k: Option<&mut [f64]>,
) -> Result<(), KernelError> {
    let nd = lay.ndof();
    let w_h = history_per_point(D);
    super::zero_local(nd, r, k.as_deref_mut());
    for (q, (xi, w)) in E::quadrature().iter().enumerate() {
        let Nv = E::shape(xi);
        let (un, vn) = hist_n[q * w_h..(q + 1) * w_h].split_at(D);
        let now = &mut hist_now[q * w_h..(q + 1) * w_h];
        let mut a = [0.0; D];
        for i in 0..D {
            let u: f64 = Nv.iter().zip(&s.u).map(|(n, u)| n * u[i]).sum();
            let v = if inv_dt > 0.0 {
                (u - un[i]) * inv_dt
            } else {
                vn[i]
            };
            a[i] = (v - vn[i]) * inv_dt;
            now[i] = u;
            now[D + i] = v;
        }
        if !act.mechanics || inv_dt == 0.0 {
            continue;
        }
        let (_, detJ) =
            physical_gradients::<N, D>(&E::grad(xi), &s.X).ok_or(KernelError::BadGeometry)?;
        let m = rho * w * detJ;
        for I in 0..N {
            for i in 0..D {
                r[lay.u(I, i)] += m * a[i] * Nv[I];
            }
        }
        if let Some(k) = k.as_deref_mut() {
            let c = m * inv_dt * inv_dt;
            for I in 0..N {
                for K in 0..N {
                    let kIK = c * Nv[I] * Nv[K];
                    for i in 0..D {
                        k[lay.u(I, i) * nd + lay.u(K, i)] += kIK;
                    }
                }
            }
        }
    }
    Ok(())
}

/// Kinetic energy of one cell with undeformed coordinates `X`, ½ ∫ ρ |v|² dV, from its
/// history `hist` (u then v per point).
pub fn kinetic_energy<const N: usize, const D: usize, E: RefElement<N, D>>(
    rho: f64,
    X: &[[f64; 3]; N],
    hist: &[f64],
) -> Result<f64, KernelError> {
    let w_h = history_per_point(D);
    let mut e = 0.0;
    for (q, (xi, w)) in E::quadrature().iter().enumerate() {
        let (_, detJ) =
            physical_gradients::<N, D>(&E::grad(xi), X).ok_or(KernelError::BadGeometry)?;
        let v = &hist[q * w_h + D..(q + 1) * w_h];
        e += 0.5 * rho * v.iter().map(|v| v * v).sum::<f64>() * w * detJ;
    }
    Ok(e)
}
