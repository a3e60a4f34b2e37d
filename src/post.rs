//! Post-processing: cell averages of J, Cauchy stress, current heat flux and conductivity.
#![allow(non_snake_case)]

use crate::element::RefElement;
use crate::kernel::{CellFields, CellState, KernelError, cell_fields};
use crate::model::Model;
use rayon::prelude::*;

/// Cell fields for every cell, in mesh block order.
pub fn all_cell_fields(model: &Model, x: &[f64]) -> Result<Vec<CellFields>, KernelError> {
    let mut out = Vec::with_capacity(model.mesh.n_cells());
    for info in &model.blocks {
        let kind = model.mesh.cells[info.block].kind;
        let v = crate::with_cell!(kind, |N, D, E| block::<N, D, E>(model, info, x)?);
        out.extend(v);
    }
    Ok(out)
}

/// Gather the nodal state of cell `nodes` from the global vector.
pub fn gather<const N: usize>(model: &Model, nodes: &[usize], x: &[f64]) -> CellState<N> {
    let d = model.dofs.dim;
    let mut s = CellState::<N> {
        X: [[0.0; 3]; N],
        u: [[0.0; 3]; N],
        theta: [0.0; N],
        p: [[0.0; 3]; N],
    };
    for (I, &n) in nodes.iter().enumerate() {
        s.X[I] = model.mesh.coords[n];
        if !model.dofs.u.is_empty() {
            for i in 0..d {
                s.u[I][i] = x[model.dofs.u[n * d + i] as usize];
            }
        }
        if !model.dofs.theta.is_empty() {
            s.theta[I] = x[model.dofs.theta[n] as usize];
        }
        let np = model.dofs.np;
        for c in 0..np {
            let dof = model.dofs.p[n * np + c];
            if dof != crate::dofs::NONE {
                s.p[I][c] = x[dof as usize];
            }
        }
    }
    s
}

fn block<const N: usize, const D: usize, E: RefElement<N, D>>(
    model: &Model,
    info: &crate::model::BlockInfo,
    x: &[f64],
) -> Result<Vec<CellFields>, KernelError> {
    let blk = &model.mesh.cells[info.block];
    (0..blk.n_cells())
        .into_par_iter()
        .map(|c| {
            cell_fields::<N, D, E>(&info.mat, &info.layout, &gather::<N>(model, blk.cell(c), x))
        })
        .collect()
}
