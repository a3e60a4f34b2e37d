//! The cell fields written with each step: averages of J, Cauchy stress, current heat flux and
//! conductivity, cell by cell.
#![allow(non_snake_case)]

use crate::dofs::gather;
use crate::element::RefElement;
use crate::kernel::{CellFields, KernelError, cell_fields};
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

fn block<const N: usize, const D: usize, E: RefElement<N, D>>(
    model: &Model,
    info: &crate::model::BlockInfo,
    x: &[f64],
) -> Result<Vec<CellFields>, KernelError> {
    let blk = &model.mesh.cells[info.block];
    (0..blk.n_cells())
        .into_par_iter()
        .map(|c| {
            cell_fields::<N, D, E>(
                &info.mat,
                &info.layout,
                &gather::<N>(&model.mesh.coords, &model.dofs, blk.cell(c), x),
            )
        })
        .collect()
}
