//! Point values written with each step: the cell averages of Cauchy stress and heat flux
//! carried to the nodes, and the stress measures a user reads (von Mises, principal stresses).

use crate::kernel::CellFields;
use crate::mesh::Mesh;
use nalgebra::{Matrix3, SymmetricEigen};

/// Cauchy stress and current heat flux at every node.
pub struct NodalFields {
    pub sigma: Vec<[[f64; 3]; 3]>,
    pub q: Vec<[f64; 3]>,
}

/// Volume-weighted mean of the cell averages over the cells that share each node, body by
/// body: a node that touches a solid takes only its solid cells (the medium's stress and flux
/// at a contact surface are not the body's), a node inside the medium takes the medium's.
/// `medium` is per cell in mesh block order, as `cells`.
pub fn nodal_fields(mesh: &Mesh, cells: &[CellFields], medium: &[bool]) -> NodalFields {
    let n = mesh.coords.len();
    // per node: weight and sums of solid cells, then of medium cells
    let mut w = vec![[0.0f64; 2]; n];
    let mut sigma = vec![[[[0.0f64; 3]; 3]; 2]; n];
    let mut q = vec![[[0.0f64; 3]; 2]; n];
    let cells_of_blocks = mesh
        .cells
        .iter()
        .flat_map(|b| (0..b.n_cells()).map(move |c| b.cell(c)));
    for ((nodes, f), &m) in cells_of_blocks.zip(cells).zip(medium) {
        let k = m as usize;
        for &node in nodes {
            w[node][k] += f.volume;
            for i in 0..3 {
                q[node][k][i] += f.volume * f.q[i];
                for j in 0..3 {
                    sigma[node][k][i][j] += f.volume * f.sigma[i][j];
                }
            }
        }
    }
    let mut out = NodalFields {
        sigma: vec![[[0.0; 3]; 3]; n],
        q: vec![[0.0; 3]; n],
    };
    for node in 0..n {
        // solid first; nodes of no cell stay zero
        let Some(k) = (0..2).find(|&k| w[node][k] > 0.0) else {
            continue;
        };
        let inv = 1.0 / w[node][k];
        for i in 0..3 {
            out.q[node][i] = q[node][k][i] * inv;
            for j in 0..3 {
                out.sigma[node][i][j] = sigma[node][k][i][j] * inv;
            }
        }
    }
    out
}

/// Von Mises stress √(3/2 s:s) of a Cauchy stress, s its deviator.
pub fn von_mises(sigma: &[[f64; 3]; 3]) -> f64 {
    let s = sigma;
    let d = (s[0][0] - s[1][1]).powi(2) + (s[1][1] - s[2][2]).powi(2) + (s[2][2] - s[0][0]).powi(2);
    let shear = s[0][1] * s[1][0] + s[1][2] * s[2][1] + s[2][0] * s[0][2];
    (0.5 * d + 3.0 * shear).max(0.0).sqrt()
}

/// Principal stresses σ1 ≥ σ2 ≥ σ3 (eigenvalues of the symmetric part).
pub fn principal(sigma: &[[f64; 3]; 3]) -> [f64; 3] {
    let m = Matrix3::from_fn(|i, j| 0.5 * (sigma[i][j] + sigma[j][i]));
    let mut e: Vec<f64> = SymmetricEigen::new(m).eigenvalues.iter().copied().collect();
    e.sort_by(|a, b| b.total_cmp(a));
    [e[0], e[1], e[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn von_mises_and_principal_stresses_of_known_states() {
        // uniaxial: σ_vm = |σ|; pure shear τ: σ_vm = √3 τ, principal ±τ; hydrostatic: 0
        let uni = [[3.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]];
        assert!((von_mises(&uni) - 3.0).abs() < 1e-14);
        assert_eq!(principal(&uni), [3.0, 0.0, 0.0]);
        let shear = [[0.0, 2.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 0.0]];
        assert!((von_mises(&shear) - 2.0 * 3f64.sqrt()).abs() < 1e-14);
        let p = principal(&shear);
        assert!((p[0] - 2.0).abs() < 1e-14 && p[1].abs() < 1e-14 && (p[2] + 2.0).abs() < 1e-14);
        let hyd = [[-5.0, 0.0, 0.0], [0.0, -5.0, 0.0], [0.0, 0.0, -5.0]];
        assert!(von_mises(&hyd).abs() < 1e-14);
        // invariant under rotation: a rotated uniaxial state keeps σ_vm and its principal values
        let (c, s) = (0.6f64, 0.8f64);
        let r = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        let u = Matrix3::new(3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0);
        let rot = r * u * r.transpose();
        let a: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| rot[(i, j)]));
        assert!(
            (von_mises(&a) - von_mises(&[[3.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]]))
                .abs()
                < 1e-13
        );
        let p = principal(&a);
        for (x, y) in p.iter().zip([3.0, 0.0, -1.0]) {
            assert!((x - y).abs() < 1e-13, "{p:?}");
        }
    }
}
