//! What a law needs at one quadrature point: physical shape gradients, dV, F, θ and ∇θ.
#![allow(non_snake_case)]

use super::KernelError;
use crate::dofs::{CellState, Layout};
use crate::element::{RefElement, physical_gradients};
use nalgebra::{Matrix3, Vector3};

/// Deformation gradient (plane strain in 2D) and temperature gradient at a point.
#[inline(always)]
pub(super) fn kinematics<const N: usize, const D: usize>(
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
pub(super) struct Point<const N: usize, const D: usize> {
    /// Physical shape gradients ∂N_I/∂X.
    pub(super) g: [[f64; D]; N],
    pub(super) Nv: [f64; N],
    pub(super) dV: f64,
    pub(super) F: Matrix3<f64>,
    pub(super) grad_theta: Vector3<f64>,
    pub(super) theta: f64,
}

#[inline(always)]
pub(super) fn point<const N: usize, const D: usize, E: RefElement<N, D>>(
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
