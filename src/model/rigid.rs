//! The rigid motions of the discrete problem: the translations and rotations under which a
//! free body stores no energy, with the values the regularization fields p take under them
//! (p_i = d f_i of the rotation). An algebraic multigrid for the mechanics must keep them on
//! its coarse levels (PETSc's near null space); restricted to an aggregate of one body they
//! are that body's own rigid motions.

use super::Model;
use crate::dofs::{Field, NONE};
use crate::material::regularization::{ROTATION_PLANES, rotation_measure_of};

/// The rigid motions (2 translations and 1 rotation in 2D, 3 and 3 in 3D) as values of every
/// free equation, `modes[k][e]`; θ equations hold 0. Rotations are about the mesh's centroid.
pub fn rigid_motions(model: &Model) -> Vec<Vec<f64>> {
    let (dofs, cons, mesh) = (&model.dofs, &model.cons, &model.mesh);
    let dim = dofs.dim;
    let planes = if dim == 2 { 1 } else { 3 };
    let n = mesh.coords.len().max(1) as f64;
    let mut centroid = [0.0; 3];
    for x in &mesh.coords {
        for c in 0..3 {
            centroid[c] += x[c] / n;
        }
    }
    // the regularization fields under rotation `r` (F = I + W, W skew in plane r): p_i = d f_i
    let p_of = |r: usize, i: usize| -> f64 {
        let (a, b) = ROTATION_PLANES[r];
        let mut g = [[0.0; 3]; 3];
        for (c, row) in g.iter_mut().enumerate() {
            row[c] = 1.0;
        }
        g[a][b] = 1.0;
        g[b][a] = -1.0;
        model.d * rotation_measure_of(&g, i).f
    };
    let mut modes = vec![vec![0.0; cons.n_eq]; dim + planes];
    let node_of_dof = dofs.node_of_dof();
    for (d, &e) in cons.eq.iter().enumerate() {
        if e == NONE {
            continue;
        }
        let (e, node) = (e as usize, node_of_dof[d] as usize);
        let x = mesh.coords[node];
        match dofs.field[d] {
            Field::U => {
                let c = (0..dim)
                    .find(|&c| dofs.u[node * dim + c] == d as u32)
                    .unwrap();
                modes[c][e] = 1.0;
                for (r, &(a, b)) in ROTATION_PLANES[..planes].iter().enumerate() {
                    // u_a = X_b, u_b = −X_a: ∂u_a/∂X_b = 1 = −∂u_b/∂X_a
                    if c == a {
                        modes[dim + r][e] = x[b] - centroid[b];
                    } else if c == b {
                        modes[dim + r][e] = -(x[a] - centroid[a]);
                    }
                }
            }
            Field::P => {
                let np = dofs.np;
                let i = (0..np)
                    .find(|&i| dofs.p[node * np + i] == d as u32)
                    .unwrap();
                for r in 0..planes {
                    modes[dim + r][e] = p_of(r, i);
                }
            }
            Field::Theta => {}
        }
    }
    modes
}

#[cfg(test)]
mod tests {
    use crate::material::regularization::{ROTATION_PLANES, rotation_measure_of};

    /// The rotation of each plane moves its own measure by 1 and leaves the others at 0.
    #[test]
    fn each_rotation_moves_its_own_measure() {
        for r in 0..3 {
            let (a, b) = ROTATION_PLANES[r];
            let mut g = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            let eps = 1e-7;
            g[a][b] = eps;
            g[b][a] = -eps;
            for i in 0..3 {
                let f = rotation_measure_of(&g, i).f / eps;
                let want = if i == r { 1.0 } else { 0.0 };
                assert!((f - want).abs() < 1e-9, "plane {r} measure {i}: {f}");
            }
        }
    }
}
