//! Cell averages for output: J, Cauchy stress, current heat flux and conductivity.
#![allow(non_snake_case)]

use super::point::{Point, point};
use super::{CellMaterial, KernelError};
use crate::dofs::{CellState, Layout};
use crate::element::RefElement;
use crate::material::fourier;
use nalgebra::{Matrix3, Vector3};

/// Cell averages for output.
#[derive(Clone, Copy, Debug, Default)]
pub struct CellFields {
    pub J: f64,
    /// Cauchy stress σ = P Fᵀ / J.
    pub sigma: [[f64; 3]; 3],
    /// Current heat flux q = F Q / J.
    pub q: [f64; 3],
    pub k: f64,
    /// Reference volume (area in 2D) of the cell: the weight of its values in nodal averages.
    pub volume: f64,
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
        } = point::<N, D, E>(xi, *w, lay, s, mat.law.theta0())?;
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
    out.volume = vol;
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
