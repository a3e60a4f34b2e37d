//! A cell's local view of the unknowns: which fields it carries and in what order
//! ([`Layout`]), and its nodal values gathered from the global vector ([`CellState`]).
#![allow(non_snake_case)]

use super::{DofMap, NONE};

/// Which fields a cell carries locally.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub n: usize,
    pub dim: usize,
    pub has_u: bool,
    pub has_theta: bool,
    /// Regularization components on this cell's nodes (0 outside the medium).
    pub np: usize,
}

impl Layout {
    pub fn u(&self, node: usize, c: usize) -> usize {
        node * self.dim + c
    }
    pub fn theta_off(&self) -> usize {
        if self.has_u { self.n * self.dim } else { 0 }
    }
    pub fn theta(&self, node: usize) -> usize {
        self.theta_off() + node
    }
    pub fn p_off(&self) -> usize {
        self.theta_off() + if self.has_theta { self.n } else { 0 }
    }
    pub fn p(&self, node: usize, c: usize) -> usize {
        self.p_off() + node * self.np + c
    }
    pub fn ndof(&self) -> usize {
        self.p_off() + self.n * self.np
    }
}

/// Nodal data of one cell.
#[derive(Clone, Copy, Debug)]
pub struct CellState<const N: usize> {
    pub X: [[f64; 3]; N],
    pub u: [[f64; 3]; N],
    pub theta: [f64; N],
    /// Regularization unknowns p_i per node (components beyond `Layout::np` unused).
    pub p: [[f64; 3]; N],
}

impl<const N: usize> CellState<N> {
    /// All zero: at the origin, undeformed, at θ = 0.
    pub fn zero() -> CellState<N> {
        CellState {
            X: [[0.0; 3]; N],
            u: [[0.0; 3]; N],
            theta: [0.0; N],
            p: [[0.0; 3]; N],
        }
    }
}

/// Measure the cell `s` from the reference node coordinates `X` instead of its own (a
/// medium whose reference configuration has been remapped): the current positions X + u stay
/// where they are.
pub fn rebase<const N: usize>(s: &mut CellState<N>, X: &[[f64; 3]]) {
    for (I, XI) in X.iter().enumerate().take(N) {
        for i in 0..3 {
            s.u[I][i] += s.X[I][i] - XI[i];
        }
        s.X[I] = *XI;
    }
}

/// Gather the nodal state of cell `nodes` from the global vector.
pub fn gather<const N: usize>(
    coords: &[[f64; 3]],
    dofs: &DofMap,
    nodes: &[usize],
    x: &[f64],
) -> CellState<N> {
    let d = dofs.dim;
    let mut s = CellState::<N>::zero();
    for (I, &n) in nodes.iter().enumerate() {
        s.X[I] = coords[n];
        if !dofs.u.is_empty() {
            for i in 0..d {
                s.u[I][i] = x[dofs.u[n * d + i] as usize];
            }
        }
        if !dofs.theta.is_empty() {
            s.theta[I] = x[dofs.theta[n] as usize];
        }
        let np = dofs.np;
        for c in 0..np {
            let dof = dofs.p[n * np + c];
            if dof != NONE {
                s.p[I][c] = x[dof as usize];
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rebase_keeps_every_node_where_it_is() {
        let mut s = CellState::<4>::zero();
        s.X = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        s.u = [
            [0.1, 0.0, 0.0],
            [0.2, -0.1, 0.0],
            [0.7, -0.9, 0.0],
            [0.5, -0.95, 0.0],
        ];
        s.theta = [1.0, 2.0, 3.0, 4.0];
        let place: Vec<[f64; 3]> = (0..4)
            .map(|i| std::array::from_fn(|k| s.X[i][k] + s.u[i][k]))
            .collect();
        let other = [
            [0.5, 0.0, 0.0],
            [1.5, 0.0, 0.0],
            [1.5, 1.0, 0.0],
            [0.5, 1.0, 0.0],
        ];
        rebase(&mut s, &other);
        for i in 0..4 {
            assert_eq!(s.X[i], other[i]);
            for k in 0..3 {
                assert!((s.X[i][k] + s.u[i][k] - place[i][k]).abs() < 1e-15);
            }
        }
        assert_eq!(s.theta, [1.0, 2.0, 3.0, 4.0]);
    }
}
