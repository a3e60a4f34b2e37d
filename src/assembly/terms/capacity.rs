//! Heat stored, ρc (θ − θₙ)/Δt, with θₙ per point as history (`kernel/capacity.rs`).

use super::{Cells, Integrand, Slab, SlabView, geometric, kept, points_per_cell};
use crate::assembly::{AssemblyError, AssemblyStats, References, reference};
use crate::kernel::capacity;
use crate::model::{CapacityBlock, Model, StepContext};

impl Integrand for CapacityBlock {
    fn history_per_point(&self, _model: &Model) -> usize {
        1
    }

    /// θ0 at every point.
    fn initial_history(&self, model: &Model, x0: &[f64], slab: &mut Slab) {
        let blk = &model.mesh.cells[self.block];
        let width = points_per_cell(blk);
        for c in 0..blk.n_cells() {
            let nodes = blk.cell(c);
            let out = &mut slab.committed[c * width..(c + 1) * width];
            crate::with_cell!(blk.kind, |N, D, E| {
                let s = crate::dofs::gather::<N>(&model.mesh.coords, &model.dofs, nodes, x0);
                capacity::theta_at_points::<N, D, E>(&s, out);
            });
        }
        slab.trial.copy_from_slice(&slab.committed);
    }

    /// A medium's heat stored (where it has a ρc) from the state's temperature.
    fn rejoined(&self, model: &Model, references: &References, x: &[f64], slab: &mut Slab) {
        if references.of(self.block).is_some() {
            crate::with_cell!(model.mesh.cells[self.block].kind, |N, D, E| {
                reference::theta_at_state::<N, D, E>(model, references, self.block, x, slab)
            });
        }
    }

    fn add(
        &self,
        cells: Cells,
        history: Option<&SlabView>,
        these: &[u32],
        step: &StepContext,
    ) -> Result<AssemblyStats, AssemblyError> {
        let slab = kept(history);
        let (lay, act, c) = (cells.lay, cells.act, self.rho_c * step.inv_dt());
        let res = crate::with_cell!(cells.blk.kind, |N, D, E| cells.each_cell_with_history::<N>(
            slab,
            these,
            |_, s, theta_n, theta_now, r, k| {
                capacity::capacity::<N, D, E>(c, &lay, s, theta_n, theta_now, act, r, k)
            }
        ));
        geometric(&cells, self.region, res)
    }
}
