//! The sparsity pattern of the free equations (built once per mesh) and what a linear solver
//! needs to know of each equation besides it.

use super::{Constraints, DofMap, Field, NONE};
use crate::mesh::Mesh;
use rayon::prelude::*;

/// CSC pattern of the free equations, rows sorted within each column.
#[derive(Clone, Debug)]
pub struct Pattern {
    pub n: usize,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
}

impl Pattern {
    /// Position of entry (row, col) in the value array.
    #[inline]
    pub fn slot(&self, row: usize, col: usize) -> usize {
        let (a, b) = (self.col_ptr[col], self.col_ptr[col + 1]);
        a + self.row_idx[a..b]
            .binary_search(&row)
            .expect("entry in pattern")
    }
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }
}

/// Build the pattern from the node graph: every dof of a node couples with every dof of the
/// nodes it shares a cell with.
pub fn build_pattern(mesh: &Mesh, dofs: &DofMap, cons: &Constraints) -> Pattern {
    let nn = mesh.coords.len();
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); nn];
    for b in &mesh.cells {
        for c in 0..b.n_cells() {
            let cell = b.cell(c);
            for &a in cell {
                adj[a].extend(cell.iter().map(|&x| x as u32));
            }
        }
    }
    adj.par_iter_mut().for_each(|v| {
        v.sort_unstable();
        v.dedup();
    });
    let eq = &cons.eq;
    let mut node_eqs: Vec<Vec<usize>> = Vec::with_capacity(nn);
    let mut buf = Vec::new();
    for n in 0..nn {
        dofs.node_dofs(n, &mut buf);
        let mut e: Vec<usize> = buf
            .iter()
            .map(|&d| eq[d as usize])
            .filter(|&e| e != NONE)
            .map(|e| e as usize)
            .collect();
        e.sort_unstable();
        node_eqs.push(e);
    }
    let n = cons.n_eq;
    // column of equation e (of node a) = equations of all neighbours of a
    let mut col_of_eq: Vec<(usize, usize)> = Vec::with_capacity(n); // (node, unused)
    col_of_eq.resize(n, (usize::MAX, 0));
    for (a, es) in node_eqs.iter().enumerate() {
        for &e in es {
            col_of_eq[e] = (a, 0);
        }
    }
    let cols: Vec<Vec<usize>> = col_of_eq
        .par_iter()
        .map(|&(a, _)| {
            let mut rows: Vec<usize> = adj[a]
                .iter()
                .flat_map(|&b| node_eqs[b as usize].iter().copied())
                .collect();
            rows.sort_unstable();
            rows
        })
        .collect();
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0);
    let mut row_idx = Vec::with_capacity(cols.iter().map(Vec::len).sum());
    for c in cols {
        row_idx.extend(c);
        col_ptr.push(row_idx.len());
    }
    Pattern {
        n,
        col_ptr,
        row_idx,
    }
}

/// What the solver needs to know about the equations besides the pattern.
#[derive(Clone, Debug)]
pub struct Structure {
    /// Mesh node of each equation (for the nested-dissection ordering of the node graph).
    pub node: Vec<u32>,
    /// Per equation: `true` for temperature, `false` for mechanics (u and p).
    pub thermal: Vec<bool>,
}

/// Mesh node and field kind of every free equation, for the linear solver.
pub fn equation_structure(dofs: &DofMap, cons: &Constraints) -> Structure {
    let node_of_dof = dofs.node_of_dof();
    let n = cons.n_eq;
    let (mut node, mut thermal) = (vec![0u32; n], vec![false; n]);
    for (d, &e) in cons.eq.iter().enumerate() {
        if e != NONE {
            node[e as usize] = node_of_dof[d];
            thermal[e as usize] = dofs.field[d] == Field::Theta;
        }
    }
    Structure { node, thermal }
}
