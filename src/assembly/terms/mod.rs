//! The terms of the discrete problem as the assembler runs them: each an [`Integrand`] over the
//! cells (or facets) of one mesh block (the model's [`Term::block`]), which owns its parameters (the model's block of that
//! kind), its history per point and its kernel. One file per term; [`integrand`] is the one
//! place that maps the model's list of terms onto them.

mod bulk;
mod capacity;
mod flux;
mod friction;
mod inertia;

use super::cells::{Cells, SlabView};
use super::history::Slab;
use super::{AssemblyError, AssemblyStats, References, cell_error_in};
use crate::element::RefElement;
use crate::kernel::KernelError;
use crate::mesh::{Block, centroid};
use crate::model::{Model, StepContext, Term};

/// One integrand of the discrete problem over the cells of one mesh block (MFEM's nonlinear
/// form integrators are the pattern): its local residual and tangent per cell, run by the
/// assembler over the cells it is given, with the step's context and, where the term keeps
/// one, its history per point (committed values read, trial values written).
pub trait Integrand: Sync {
    /// Values of history per quadrature point (0: it keeps none).
    fn history_per_point(&self, _model: &Model) -> usize {
        0
    }

    /// Its committed history at the initial state `x0` (zero unless it says otherwise).
    fn initial_history(&self, _model: &Model, _x0: &[f64], _slab: &mut Slab) {}

    /// Its history after the layer it lies in was joined again at the state `x`, its cells
    /// measured from `references` (as it was, unless it says otherwise).
    fn rejoined(&self, _model: &Model, _references: &References, _x: &[f64], _slab: &mut Slab) {}

    /// Add the cells `these` (global numbers, all of its block) of `cells` at the end of
    /// `step`: their residuals, and tangents where asked for.
    fn add(
        &self,
        cells: Cells,
        history: Option<&SlabView>,
        these: &[u32],
        step: &StepContext,
    ) -> Result<AssemblyStats, AssemblyError>;
}

/// The integrand of the model's term `term`.
pub fn integrand(model: &Model, term: Term) -> &dyn Integrand {
    match term {
        Term::Bulk(b) => &model.blocks[b],
        Term::Flux(f) => &model.facet_blocks[f],
        Term::Capacity(c) => &model.capacity_blocks[c],
        Term::Friction(f) => &model.friction_blocks[f],
        Term::Inertia(i) => &model.inertia_blocks[i],
    }
}

/// Quadrature points per cell of a block.
pub fn points_per_cell(blk: &Block) -> usize {
    crate::with_cell!(blk.kind, |N, D, E| <E as RefElement<N, D>>::quadrature()
        .len())
}

/// The slab of a term that keeps a history ([`Integrand::history_per_point`] > 0).
fn kept<'h, 'a>(history: Option<&'h SlabView<'a>>) -> &'h SlabView<'a> {
    history.expect("initial_history gives every term with history its slab")
}

/// The assembly error of a kernel's failure `(e, cell)` in a cell of `cells` of `region`.
fn cell_failure(cells: &Cells, region: usize, (e, cell): (KernelError, usize)) -> AssemblyError {
    let (model, blk) = (cells.model, cells.blk);
    let at = centroid(&model.mesh.coords, blk.cell(cell));
    cell_error_in(&model.regions[region].0, e, cell, at)
}

/// Nothing assembled but residuals and tangents, whose entries are finite (`ok`).
fn finite(ok: bool) -> Result<AssemblyStats, AssemblyError> {
    match ok {
        true => Ok(AssemblyStats::EMPTY),
        false => Err(AssemblyError::NotFinite),
    }
}

/// The result of a term whose kernel fails only on a cell's geometry (capacity, inertia):
/// an error names the cell of `region`.
fn geometric(
    cells: &Cells,
    region: usize,
    res: Result<bool, (KernelError, usize)>,
) -> Result<AssemblyStats, AssemblyError> {
    let (model, blk) = (cells.model, cells.blk);
    let ok = res.map_err(|(_, cell)| AssemblyError::BadMesh {
        region: model.regions[region].0.clone(),
        cell,
        at: centroid(&model.mesh.coords, blk.cell(cell)),
    })?;
    finite(ok)
}
