//! Inertia, ρ ü by backward Euler, with the displacement and velocity per point as history
//! (`kernel/inertia.rs`).

use super::{Cells, Integrand, Slab, SlabView, geometric, kept};
use crate::assembly::{AssemblyError, AssemblyStats, References, reference};
use crate::kernel::inertia;
use crate::model::{InertiaBlock, Model, StepContext};

impl Integrand for InertiaBlock {
    /// At rest and undisplaced at first (zero).
    fn history_per_point(&self, model: &Model) -> usize {
        inertia::history_per_point(model.mesh.dim)
    }

    /// The displacement per point from the state as joined, at rest relative to it.
    fn rejoined(&self, model: &Model, references: &References, x: &[f64], slab: &mut Slab) {
        crate::with_cell!(model.mesh.cells[self.block].kind, |N, D, E| {
            reference::inertia_at_state::<N, D, E>(model, references, self.block, x, slab)
        });
    }

    fn add(
        &self,
        cells: Cells,
        history: Option<&SlabView>,
        these: &[u32],
        step: &StepContext,
    ) -> Result<AssemblyStats, AssemblyError> {
        let slab = kept(history);
        let (lay, act, rho, inv_dt) = (cells.lay, cells.act, self.rho, step.inv_dt());
        let res = crate::with_cell!(cells.blk.kind, |N, D, E| cells.each_cell_with_history::<N>(
            slab,
            these,
            |_, s, hist_n, hist_now, r, k| {
                inertia::inertia::<N, D, E>(rho, inv_dt, &lay, s, hist_n, hist_now, act, r, k)
            }
        ));
        geometric(&cells, self.region, res)
    }
}
