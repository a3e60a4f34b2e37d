//! Coulomb friction in a medium's slip planes, with the slip per point as history
//! (`kernel/friction.rs`), and the heat its work makes.

use super::{Cells, Integrand, SlabView, cell_failure, finite, kept};
use crate::assembly::{AssemblyError, AssemblyStats};
use crate::kernel::friction::{self, HISTORY_PER_POINT};
use crate::model::{FrictionBlock, Model, StepContext};

impl Integrand for FrictionBlock {
    /// No slip and no work dissipated at first (zero).
    fn history_per_point(&self, _model: &Model) -> usize {
        HISTORY_PER_POINT
    }

    fn add(
        &self,
        cells: Cells,
        history: Option<&SlabView>,
        these: &[u32],
        step: &StepContext,
    ) -> Result<AssemblyStats, AssemblyError> {
        let slab = kept(history);
        let (lay, act, blk) = (cells.lay, cells.act, cells.blk);
        let inv_dt = step.inv_dt();
        // η/Δt: the heat the dissipated work makes, per time
        let heat_rate = self.heat_fraction * inv_dt;
        let res = crate::with_cell!(blk.kind, |N, D, E| cells.each_cell_with_history::<N>(
            slab,
            these,
            |cell, s, committed, trial, r, k| {
                friction::friction::<N, D, E>(
                    &self.mat,
                    self.normals.of(cell),
                    heat_rate,
                    inv_dt,
                    &lay,
                    s,
                    committed,
                    trial,
                    act,
                    r,
                    k,
                )
            }
        ));
        finite(res.map_err(|f| cell_failure(&cells, self.region, f))?)
    }
}
