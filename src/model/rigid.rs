//! The rigid motions of the discrete problem: the translations and rotations under which a
//! free body stores no energy, with the values the regularization fields p take under them
//! (p_i = d f_i of the rotation). An algebraic multigrid for the mechanics must keep them on
//! its coarse levels (PETSc's near null space); restricted to an aggregate of one body they
//! are that body's own rigid motions.

use super::Model;
use crate::dofs::NONE;
use crate::material::regularization::rotation_measure_of;
use crate::mesh::centroid;

/// How many rigid motions a body has: 2 translations and 1 rotation in 2D, 3 and 3 in 3D.
pub fn count(dim: usize) -> usize {
    if dim == 2 { 3 } else { 6 }
}

/// The axis (0 = x, 1 = y, 2 = z) rigid motion `m ≥ dim` turns about: z in 2D.
pub fn axis(dim: usize, m: usize) -> usize {
    if dim == 2 { 2 } else { m - 3 }
}

/// The displacement of rigid motion `m` at `r` (from the centre of rotation): the unit vector
/// of axis m for a translation (m < dim), else e_axis × r.
pub fn motion(dim: usize, m: usize, r: &[f64; 3]) -> [f64; 3] {
    let mut u = [0.0; 3];
    if m < dim {
        u[m] = 1.0;
    } else {
        let a = axis(dim, m);
        let (b, e) = ((a + 1) % 3, (a + 2) % 3);
        u[b] = -r[e];
        u[e] = r[b];
    }
    u
}

/// The rigid motions as values of every free equation, `modes[k][e]` (see [`motion`]; θ
/// equations hold 0), rotations about the mesh's centroid; empty without mechanics.
pub fn rigid_motions(model: &Model) -> Vec<Vec<f64>> {
    let (dofs, cons, mesh) = (&model.dofs, &model.cons, &model.mesh);
    if dofs.u.is_empty() {
        return Vec::new();
    }
    let (dim, np) = (dofs.dim, dofs.np);
    let all: Vec<usize> = (0..mesh.coords.len()).collect();
    let c = centroid(&mesh.coords, &all);
    // the regularization fields under each motion: p_i = d f_i(I + ∇u), ∇u constant
    let p: Vec<Vec<f64>> = (0..count(dim))
        .map(|m| {
            let at_0 = motion(dim, m, &[0.0; 3]);
            let mut g = [[0.0; 3]; 3];
            for j in 0..3 {
                let mut x = [0.0; 3];
                x[j] = 1.0;
                let u = motion(dim, m, &x);
                for i in 0..3 {
                    g[i][j] = (i == j) as u8 as f64 + u[i] - at_0[i];
                }
            }
            (0..np)
                .map(|i| model.d * rotation_measure_of(&g, i).f)
                .collect()
        })
        .collect();
    let mut modes = vec![vec![0.0; cons.n_eq]; count(dim)];
    let eq = |d: u32| {
        (d != NONE)
            .then(|| cons.eq[d as usize])
            .filter(|&e| e != NONE)
    };
    for (node, x) in mesh.coords.iter().enumerate() {
        let r = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
        for (m, mode) in modes.iter_mut().enumerate() {
            let u = motion(dim, m, &r);
            for (k, &d) in dofs.u[node * dim..(node + 1) * dim].iter().enumerate() {
                if let Some(e) = eq(d) {
                    mode[e as usize] = u[k];
                }
            }
            for i in 0..np {
                if let Some(e) = eq(dofs.p[node * np + i]) {
                    mode[e as usize] = p[m][i];
                }
            }
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
