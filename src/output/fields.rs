//! The cell fields written with each step: averages of J, Cauchy stress, current heat flux and
//! conductivity, cell by cell.
#![allow(non_snake_case)]

use crate::assembly::{AssemblyError, References, cell_error};
use crate::element::RefElement;
use crate::kernel::{CellFields, cell_fields};
use crate::model::Model;
use rayon::prelude::*;

/// Cell fields for every cell, in mesh block order, each cell measured from its reference in
/// `references`. A failing cell is named by region, index and position.
pub fn all_cell_fields(
    model: &Model,
    references: &References,
    x: &[f64],
) -> Result<Vec<CellFields>, AssemblyError> {
    let mut out = Vec::with_capacity(model.mesh.n_cells());
    for (bi, info) in model.blocks.iter().enumerate() {
        let kind = model.mesh.cells[info.block].kind;
        let v = crate::with_cell!(kind, |N, D, E| block::<N, D, E>(model, references, bi, x)?);
        out.extend(v);
    }
    Ok(out)
}

fn block<const N: usize, const D: usize, E: RefElement<N, D>>(
    model: &Model,
    references: &References,
    bi: usize,
    x: &[f64],
) -> Result<Vec<CellFields>, AssemblyError> {
    let info = &model.blocks[bi];
    let blk = &model.mesh.cells[info.block];
    (0..blk.n_cells())
        .into_par_iter()
        .map(|c| {
            cell_fields::<N, D, E>(
                &info.mat,
                &info.layout,
                &references.state::<N>(model, info.block, c, x),
            )
            .map_err(|e| cell_error(model, bi, e, c))
        })
        .collect()
}
