//! Heat storage: the capacity term of transient conduction by backward Euler,
//!
//! r_θ(I) = ∫ ρc (θ − θₙ)/Δt N_I dV,   ∂r_θ(I)/∂θ_K = ∫ ρc/Δt N_I N_K dV,
//!
//! per reference volume (ρc is a heat capacity per reference volume), so it does not depend on
//! u. θₙ is the history of each quadrature point: θ of the last accepted step there.
#![allow(non_snake_case)]

use super::{Active, KernelError};
use crate::dofs::{CellState, Layout};
use crate::element::{RefElement, physical_gradients};

/// Residual and (optionally) tangent of the capacity term of one cell, with `c = ρc/Δt`, the
/// history `theta_n` (one value per quadrature point) and the trial history `theta_now`
/// (filled with θ at each point). `r` and `k` (the cell's θ-only layout, row-major) are
/// overwritten; without `act.heat` they are zero.
#[allow(clippy::too_many_arguments)]
pub fn capacity<const N: usize, const D: usize, E: RefElement<N, D>>(
    c: f64,
    lay: &Layout,
    s: &CellState<N>,
    theta_n: &[f64],
    theta_now: &mut [f64],
    act: Active,
    r: &mut [f64],
    mut k: Option<&mut [f64]>,
) -> Result<(), KernelError> {
    let nd = lay.ndof();
    super::zero_local(nd, r, k.as_deref_mut());
    for (q, (xi, w)) in E::quadrature().iter().enumerate() {
        let Nv = E::shape(xi);
        let theta: f64 = Nv.iter().zip(&s.theta).map(|(a, b)| a * b).sum();
        theta_now[q] = theta;
        if !act.heat {
            continue;
        }
        let (_, detJ) =
            physical_gradients::<N, D>(&E::grad(xi), &s.X).ok_or(KernelError::BadGeometry)?;
        let cdV = c * w * detJ;
        for I in 0..N {
            r[lay.theta(I)] += cdV * (theta - theta_n[q]) * Nv[I];
        }
        if let Some(k) = k.as_deref_mut() {
            for I in 0..N {
                let row = lay.theta(I) * nd;
                for K in 0..N {
                    k[row + lay.theta(K)] += cdV * Nv[I] * Nv[K];
                }
            }
        }
    }
    Ok(())
}

/// θ at each quadrature point of a cell (the history the capacity term starts from).
pub fn theta_at_points<const N: usize, const D: usize, E: RefElement<N, D>>(
    s: &CellState<N>,
    out: &mut [f64],
) {
    for (o, (xi, _)) in out.iter_mut().zip(E::quadrature()) {
        *o = E::shape(xi).iter().zip(&s.theta).map(|(a, b)| a * b).sum();
    }
}

/// Heat stored in one cell, ∫ ρc (θ − θ_ref) dV.
pub fn stored_heat<const N: usize, const D: usize, E: RefElement<N, D>>(
    rho_c: f64,
    theta_ref: f64,
    s: &CellState<N>,
) -> Result<f64, KernelError> {
    let mut e = 0.0;
    for (xi, w) in E::quadrature() {
        let Nv = E::shape(xi);
        let theta: f64 = Nv.iter().zip(&s.theta).map(|(a, b)| a * b).sum();
        let (_, detJ) =
            physical_gradients::<N, D>(&E::grad(xi), &s.X).ok_or(KernelError::BadGeometry)?;
        e += rho_c * (theta - theta_ref) * w * detJ;
    }
    Ok(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{Hex8, Quad4, Quad9, Tet10, Tri3};

    fn check<const N: usize, const D: usize, E: RefElement<N, D>>() {
        let lay = Layout {
            n: N,
            dim: D,
            has_u: false,
            has_theta: true,
            np: 0,
        };
        let mut s = CellState::<N>::zero();
        for (I, xi) in E::nodes().iter().enumerate() {
            for d in 0..D {
                s.X[I][d] = 0.6 * xi[d] + 0.05 * ((I * 7 + d * 3) % 5) as f64 / 5.0;
            }
            s.theta[I] = 10.0 + 13.0 * ((I * 5) % 7) as f64;
        }
        let nq = E::quadrature().len();
        let theta_n: Vec<f64> = (0..nq).map(|q| 3.0 + q as f64).collect();
        let mut now = vec![0.0; nq];
        let (c, nd) = (2.5, lay.ndof());
        let (mut r, mut k) = (vec![0.0; nd], vec![0.0; nd * nd]);
        capacity::<N, D, E>(
            c,
            &lay,
            &s,
            &theta_n,
            &mut now,
            Active::ALL,
            &mut r,
            Some(&mut k),
        )
        .unwrap();
        // the trial history is θ at the points
        for (q, (xi, _)) in E::quadrature().iter().enumerate() {
            let th: f64 = E::shape(xi).iter().zip(&s.theta).map(|(a, b)| a * b).sum();
            assert_eq!(now[q], th);
        }
        // ∂r/∂θ by central differences (r is linear in θ: exact up to round-off)
        let scale = k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let h = 1e-3;
        for b in 0..nd {
            let (mut sp, mut sm) = (s, s);
            sp.theta[b] += h;
            sm.theta[b] -= h;
            let (mut rp, mut rm) = (vec![0.0; nd], vec![0.0; nd]);
            capacity::<N, D, E>(c, &lay, &sp, &theta_n, &mut now, Active::ALL, &mut rp, None)
                .unwrap();
            capacity::<N, D, E>(c, &lay, &sm, &theta_n, &mut now, Active::ALL, &mut rm, None)
                .unwrap();
            for a in 0..nd {
                let fd = (rp[a] - rm[a]) / (2.0 * h);
                assert!((fd - k[a * nd + b]).abs() < 1e-10 * scale, "K[{a},{b}]");
                assert!((k[a * nd + b] - k[b * nd + a]).abs() < 1e-14 * scale);
            }
        }
        // Σ_I r_I = c ∫ (θ − θₙ) dV = d/dt of the stored heat over the step
        let (e1, e0) = (
            stored_heat::<N, D, E>(c, 0.0, &s).unwrap(),
            theta_n
                .iter()
                .zip(E::quadrature())
                .map(|(tn, (xi, w))| {
                    let (_, det) = physical_gradients::<N, D>(&E::grad(xi), &s.X).unwrap();
                    c * tn * w * det
                })
                .sum::<f64>(),
        );
        let total: f64 = r.iter().sum();
        assert!(
            (total - (e1 - e0)).abs() < 1e-12 * e1.abs(),
            "{total} vs {}",
            e1 - e0
        );
    }

    #[test]
    fn capacity_tangent_and_stored_heat() {
        check::<3, 2, Tri3>();
        check::<4, 2, Quad4>();
        check::<9, 2, Quad9>();
        check::<8, 3, Hex8>();
        check::<10, 3, Tet10>();
    }
}
