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
        self.find(row, col).expect("entry in pattern")
    }

    /// Position of entry (row, col) in the value array, if the pattern has it.
    #[inline]
    pub fn find(&self, row: usize, col: usize) -> Option<usize> {
        let (a, b) = (self.col_ptr[col], self.col_ptr[col + 1]);
        self.row_idx[a..b].binary_search(&row).ok().map(|i| a + i)
    }
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }
}

/// Build the pattern from the node graph: every dof of a node couples with every dof of the
/// nodes it shares a cell with.
pub fn build_pattern(mesh: &Mesh, dofs: &DofMap, cons: &Constraints) -> Pattern {
    let cells = mesh
        .cells
        .iter()
        .flat_map(|b| (0..b.n_cells()).map(move |c| b.cell(c)));
    build_pattern_of(mesh.coords.len(), cells, |_| true, dofs, cons)
}

/// The pattern of the couplings that `cells` (node lists, over `nn` nodes) make, in the
/// columns of the equations of the nodes `column` keeps; the other columns are empty. The
/// equations keep their numbers. With all cells and all nodes: [`build_pattern`]; with one
/// rank's cells: the entries that rank adds; with all cells and one rank's nodes: the whole
/// rows of its equations (the pattern is structurally symmetric), whatever cells add to them.
pub fn build_pattern_of<'c>(
    nn: usize,
    cells: impl Iterator<Item = &'c [usize]>,
    column: impl Fn(usize) -> bool,
    dofs: &DofMap,
    cons: &Constraints,
) -> Pattern {
    let kept: Vec<bool> = (0..nn).map(column).collect();
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); nn];
    for cell in cells {
        for &a in cell.iter().filter(|&&a| kept[a]) {
            adj[a].extend(cell.iter().map(|&x| x as u32));
        }
    }
    adj.par_iter_mut().for_each(|v| {
        v.sort_unstable();
        v.dedup();
        v.shrink_to_fit();
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
    // node of each equation
    let mut node_of_eq = vec![usize::MAX; n];
    for (a, es) in node_eqs.iter().enumerate() {
        for &e in es {
            node_of_eq[e] = a;
        }
    }
    // column of equation e (of node a) = equations of all neighbours of a
    let count = |a: usize| -> usize { adj[a].iter().map(|&b| node_eqs[b as usize].len()).sum() };
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0);
    for &a in &node_of_eq {
        col_ptr.push(col_ptr.last().unwrap() + count(a));
    }
    let mut row_idx = vec![0usize; *col_ptr.last().unwrap()];
    // fill the columns in parallel, each in its own slice of row_idx
    let mut rest = &mut row_idx[..];
    let mut slices = Vec::with_capacity(n);
    for e in 0..n {
        let (head, tail) = rest.split_at_mut(col_ptr[e + 1] - col_ptr[e]);
        slices.push(head);
        rest = tail;
    }
    slices
        .into_par_iter()
        .zip(node_of_eq.par_iter())
        .for_each(|(col, &a)| {
            let rows = adj[a]
                .iter()
                .flat_map(|&b| node_eqs[b as usize].iter().copied());
            for (r, e) in col.iter_mut().zip(rows) {
                *r = e;
            }
            col.sort_unstable();
        });
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
    /// How a direct solver orders the node graph to keep its factor's fill low.
    pub ordering: Ordering,
}

impl Structure {
    /// Each equation's mesh node and whether it is thermal, ordered by nested dissection.
    pub fn new(node: Vec<u32>, thermal: Vec<bool>) -> Structure {
        Structure {
            node,
            thermal,
            ordering: Ordering::default(),
        }
    }
}

/// How a direct solver orders its equations (their mesh nodes' graph) against fill.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Ordering {
    /// METIS's nested dissection: the least fill, found once for a run's many factorisations.
    #[default]
    NestedDissection,
    /// faer's approximate minimum degree: found several times faster, with about as little
    /// fill on a 2D mesh; for a run that plans its solver anew every few steps (a medium made
    /// again as the bodies move).
    MinimumDegree,
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
    Structure::new(node, thermal)
}
