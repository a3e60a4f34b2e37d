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

/// The forces a cell puts on its nodes through its material law, per node −∫ P ∇_X N_a dV,
/// with `extra` a Cauchy stress added to the law's throughout the cell (a slip plane's):
/// the bulk law's share of the cell's residual, turned round (the regularization's is not in
/// it). Where the cell meets a solid, what it puts on the solid's nodes.
pub fn nodal_forces<const N: usize, const D: usize, E: RefElement<N, D>>(
    mat: &CellMaterial,
    lay: &Layout,
    s: &CellState<N>,
    extra: Option<&[[f64; 3]; 3]>,
) -> Result<[[f64; 3]; N], KernelError> {
    let mut f = [[0.0; 3]; N];
    let extra = extra.map(|e| Matrix3::from_fn(|i, j| e[i][j]));
    for (xi, w) in E::quadrature() {
        let Point {
            g, dV, F, theta, ..
        } = point::<N, D, E>(xi, *w, lay, s, mat.law.theta0())?;
        let m = mat
            .law
            .stress(&F, theta)
            .ok_or(KernelError::Inverted { J: F.determinant() })?;
        // P = J σ F⁻ᵀ of the added stress
        let P = match (&extra, F.try_inverse()) {
            (Some(e), Some(Fi)) => m.P + m.J * e * Fi.transpose(),
            _ => m.P,
        };
        for (fa, ga) in f.iter_mut().zip(&g) {
            for (i, fi) in fa.iter_mut().enumerate() {
                *fi -= (0..D).map(|J| P[(i, J)] * ga[J]).sum::<f64>() * dV;
            }
        }
    }
    Ok(f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{Hex8, Quad4, Tet4, Tri3};
    use crate::kernel::bulk::tests::{SOLID, distorted_cell};
    use crate::kernel::{Active, bulk};

    /// The nodal forces are the bulk residual's displacement rows turned round, and a cell's
    /// forces sum to nothing.
    fn check<const N: usize, const D: usize, E: RefElement<N, D>>() {
        let (s, lay) = distorted_cell::<N, D, E>(0);
        let mut r = vec![0.0; lay.ndof()];
        bulk::<N, D, E>(&SOLID, &lay, &s, Active::ALL, &mut r, None).unwrap();
        let f = nodal_forces::<N, D, E>(&SOLID, &lay, &s, None).unwrap();
        let scale = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for a in 0..N {
            for d in 0..D {
                assert!((f[a][d] + r[a * D + d]).abs() < 1e-13 * scale, "{a} {d}");
            }
        }
        for d in 0..3 {
            assert!(f.iter().map(|fa| fa[d]).sum::<f64>().abs() < 1e-13 * scale);
        }
    }

    #[test]
    fn nodal_forces_are_the_bulk_residual_turned_round() {
        check::<3, 2, Tri3>();
        check::<4, 2, Quad4>();
        check::<4, 3, Tet4>();
        check::<8, 3, Hex8>();
    }

    #[test]
    fn an_added_stress_pushes_on_the_faces_it_acts_across() {
        // the unit right triangle (0,0) (1,0) (0,1), undeformed, at θ0: no stress of its own;
        // a compression of 2 along y added pushes (0,0) down by 1 and (0,1) up by 1
        // (−∫ σ ∇N dv, ∇N = (−1,−1), (1,0), (0,1), area ½); (1,0)'s gradient has no y
        let mut s = CellState::<3>::zero();
        s.X = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        s.theta = [10.0; 3];
        let (_, lay) = distorted_cell::<3, 2, Tri3>(0);
        let sigma = [[0.0; 3], [0.0, -2.0, 0.0], [0.0; 3]];
        let f = nodal_forces::<3, 2, Tri3>(&SOLID, &lay, &s, Some(&sigma)).unwrap();
        let want = [[0.0, -1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        for (a, w) in f.iter().zip(&want) {
            for d in 0..3 {
                assert!((a[d] - w[d]).abs() < 1e-14, "{f:?}");
            }
        }
    }
}
