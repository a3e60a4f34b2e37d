//! Facet kernels: integrals over boundary facets (lines of a 2D mesh, faces of a 3D one),
//! residual and tangent in the facet's own local layout: the heat a boundary law lets out
//! (convection h (θ − θ∞), radiation ε σ (θ⁴ − θ∞⁴)),
//!
//! r_θ(I) = ∫ N_I q(θ) da,   da = |∂x/∂ξ| dξ (line) or |∂x/∂ξ₁ × ∂x/∂ξ₂| dξ (face),
//!
//! on the current (deformed) facet x = X + u: Nanson's J |F⁻ᵀ N| dA, computed from the facet's
//! own nodes. The tangent has ∂r_θ/∂θ (symmetric) and, where u is an unknown, ∂(da)/∂u.
#![allow(non_snake_case)]

use super::{Active, KernelError};
use crate::dofs::{CellState, Layout};
use crate::element::RefElement;
use crate::material::BoundaryFlux;

/// The current area element |∂x/∂ξ| (D = 1) or |∂x/∂ξ₁ × ∂x/∂ξ₂| (D = 2) at one point, and
/// its derivative with respect to the current position of each node, `dm[K][k]`.
#[inline]
fn area_element<const N: usize, const D: usize>(
    dN: &[[f64; D]; N],
    x: &[[f64; 3]; N],
) -> (f64, [[f64; 3]; N]) {
    let mut t = [[0.0; 3]; 2];
    for (g, xi) in dN.iter().zip(x) {
        for j in 0..D.min(2) {
            for i in 0..3 {
                t[j][i] += xi[i] * g[j];
            }
        }
    }
    let mut dm = [[0.0; 3]; N];
    // ∂N_K/∂ξ_j, zero beyond the facet's dimension
    let dN_at = |K: usize, j: usize| dN[K].get(j).copied().unwrap_or(0.0);
    match D {
        1 => {
            let m = t[0].iter().map(|v| v * v).sum::<f64>().sqrt();
            for K in 0..N {
                for k in 0..3 {
                    dm[K][k] = t[0][k] / m * dN_at(K, 0);
                }
            }
            (m, dm)
        }
        2 => {
            let (a, b) = (t[0], t[1]);
            let n = cross(a, b);
            let m = n.iter().map(|v| v * v).sum::<f64>().sqrt();
            let nh = n.map(|v| v / m);
            // ∂m/∂x_K = (t₂ × n̂) ∂N_K/∂ξ₁ + (n̂ × t₁) ∂N_K/∂ξ₂
            let (bn, na) = (cross(b, nh), cross(nh, a));
            for K in 0..N {
                for k in 0..3 {
                    dm[K][k] = bn[k] * dN_at(K, 0) + na[k] * dN_at(K, 1);
                }
            }
            (m, dm)
        }
        _ => (1.0, dm), // a point (a facet of a 1D mesh): unit measure
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Residual and (optionally) tangent of a boundary flux on one facet: `r` and `k`
/// (row-major, `ndof × ndof`) are overwritten. Fills the θ rows when `act.heat` (their u
/// columns also when `act.mechanics`), nothing else.
pub fn boundary_flux<const N: usize, const D: usize, E: RefElement<N, D>>(
    law: &BoundaryFlux,
    lay: &Layout,
    s: &CellState<N>,
    act: Active,
    r: &mut [f64],
    mut k: Option<&mut [f64]>,
) -> Result<(), KernelError> {
    let nd = lay.ndof();
    super::zero_local(nd, r, k.as_deref_mut());
    if !(lay.has_theta && act.heat) {
        return Ok(());
    }
    let x: [[f64; 3]; N] = std::array::from_fn(|I| {
        std::array::from_fn(|i| s.X[I][i] + if lay.has_u { s.u[I][i] } else { 0.0 })
    });
    let with_u = lay.has_u && act.mechanics;
    for (xi, w) in E::quadrature() {
        let Nv = E::shape(xi);
        let (m, dm) = area_element::<N, D>(&E::grad(xi), &x);
        if !(m > 0.0) || !m.is_finite() {
            return Err(KernelError::BadGeometry);
        }
        let theta: f64 = Nv.iter().zip(&s.theta).map(|(a, b)| a * b).sum();
        let (q, dq) = law.flux(theta).ok_or(KernelError::NotAbsolute { theta })?;
        for I in 0..N {
            r[lay.theta(I)] += w * Nv[I] * q * m;
        }
        let Some(k) = k.as_deref_mut() else { continue };
        for I in 0..N {
            let row = lay.theta(I) * nd;
            for K in 0..N {
                k[row + lay.theta(K)] += w * Nv[I] * dq * Nv[K] * m;
                if with_u {
                    for c in 0..lay.dim {
                        k[row + lay.u(K, c)] += w * Nv[I] * q * dm[K][c];
                    }
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{Line2, Line3, Quad4, Quad9, Tri3, Tri6};

    use crate::material::{Convection, Radiation};

    const LAW: BoundaryFlux = BoundaryFlux::Convection(Convection {
        h: 3.5,
        theta_inf: 15.0,
    });

    /// σ scaled up so that the radiated heat is of the convected heat's size.
    const RADIATION: BoundaryFlux = BoundaryFlux::Radiation(Radiation {
        emissivity: 0.8,
        theta_inf: 15.0,
        sigma: 1e-4,
    });

    /// A facet of a `dim`-D mesh: distorted, displaced, at varied temperatures.
    fn state<const N: usize, const D: usize, E: RefElement<N, D>>(dim: usize) -> CellState<N> {
        let mut s = CellState::<N>::zero();
        for (I, xi) in E::nodes().iter().enumerate() {
            for d in 0..D {
                s.X[I][d] = 0.7 * xi[d] + 0.05 * ((I * 3 + d) % 4) as f64;
            }
            // tilted out of its plane (3D) or off the axis (2D)
            s.X[I][dim - 1] += 0.2 * xi[0] + 0.03 * I as f64;
            for c in 0..dim {
                s.u[I][c] = 0.1 * (((I * 5 + c * 3) % 7) as f64 / 7.0 - 0.4);
            }
            s.theta[I] = 20.0 + 7.0 * ((I * 3) % 5) as f64;
        }
        s
    }

    /// Central differences of the residual against the tangent, u and θ columns.
    fn check<const N: usize, const D: usize, E: RefElement<N, D>>(dim: usize, law: &BoundaryFlux) {
        let lay = Layout {
            n: N,
            dim,
            has_u: true,
            has_theta: true,
            np: 0,
        };
        let nd = lay.ndof();
        let s = state::<N, D, E>(dim);
        let (mut r, mut k) = (vec![0.0; nd], vec![0.0; nd * nd]);
        boundary_flux::<N, D, E>(law, &lay, &s, Active::ALL, &mut r, Some(&mut k)).unwrap();
        let scale = k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(scale > 0.0);
        let h = 1e-6;
        let (mut rp, mut rm) = (vec![0.0; nd], vec![0.0; nd]);
        let mut du_seen = 0.0f64;
        for b in 0..nd {
            let perturb = |e: f64| {
                let mut t = s;
                if b < lay.theta_off() {
                    t.u[b / dim][b % dim] += e;
                } else {
                    t.theta[b - lay.theta_off()] += e;
                }
                t
            };
            boundary_flux::<N, D, E>(law, &lay, &perturb(h), Active::ALL, &mut rp, None).unwrap();
            boundary_flux::<N, D, E>(law, &lay, &perturb(-h), Active::ALL, &mut rm, None).unwrap();
            for a in 0..nd {
                let fd = (rp[a] - rm[a]) / (2.0 * h);
                assert!(
                    (fd - k[a * nd + b]).abs() < 1e-7 * scale,
                    "{} K[{a},{b}] = {} vs FD {fd}",
                    std::any::type_name::<E>(),
                    k[a * nd + b]
                );
                if b < lay.theta_off() {
                    du_seen = du_seen.max(fd.abs());
                }
            }
        }
        // the deformation changes the area: ∂r/∂u is not zero
        assert!(du_seen > 1e-3 * scale, "{du_seen}");
        // the θ–θ block is symmetric
        for a in lay.theta_off()..nd {
            for b in lay.theta_off()..nd {
                assert!((k[a * nd + b] - k[b * nd + a]).abs() < 1e-14 * scale);
            }
        }
    }

    #[test]
    fn boundary_flux_tangent_matches_finite_differences() {
        for law in [&LAW, &RADIATION] {
            check::<2, 1, Line2>(2, law);
            check::<3, 1, Line3>(2, law);
            check::<3, 2, Tri3>(3, law);
            check::<4, 2, Quad4>(3, law);
            check::<6, 2, Tri6>(3, law);
            check::<9, 2, Quad9>(3, law);
        }
    }

    #[test]
    fn a_radiating_facet_at_or_below_zero_is_an_error() {
        let lay = Layout {
            n: 2,
            dim: 2,
            has_u: false,
            has_theta: true,
            np: 0,
        };
        let mut s = state::<2, 1, Line2>(2);
        s.theta = [-3.0; 2];
        let mut r = vec![0.0; lay.ndof()];
        match boundary_flux::<2, 1, Line2>(&RADIATION, &lay, &s, Active::ALL, &mut r, None) {
            Err(KernelError::NotAbsolute { theta }) => assert!((theta + 3.0).abs() < 1e-12),
            other => panic!("{other:?}"),
        }
        // convection has no such limit
        boundary_flux::<2, 1, Line2>(&LAW, &lay, &s, Active::ALL, &mut r, None).unwrap();
    }

    #[test]
    fn convection_on_an_undeformed_facet_is_h_theta_minus_ambient_times_area() {
        // unit square face at uniform θ: the nodal residuals sum to h (θ − θ∞) A
        let lay = Layout {
            n: 4,
            dim: 3,
            has_u: false,
            has_theta: true,
            np: 0,
        };
        let mut s = state::<4, 2, Quad4>(3);
        for (I, xi) in Quad4::nodes().iter().enumerate() {
            s.X[I] = [0.5 * (xi[0] + 1.0), 0.5 * (xi[1] + 1.0), 0.0];
            s.theta[I] = 40.0;
        }
        let mut r = vec![0.0; lay.ndof()];
        boundary_flux::<4, 2, Quad4>(&LAW, &lay, &s, Active::ALL, &mut r, None).unwrap();
        let total: f64 = r.iter().sum();
        assert!((total - 3.5 * 25.0).abs() < 1e-12, "{total}");
        // only the mechanical rows wanted: nothing
        let mech = Active {
            mechanics: true,
            heat: false,
        };
        boundary_flux::<4, 2, Quad4>(&LAW, &lay, &s, mech, &mut r, None).unwrap();
        assert!(r.iter().all(|&v| v == 0.0));
    }
}
