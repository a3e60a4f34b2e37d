//! A region's cells: mechanics, conduction and the medium's regularization
//! (`kernel/bulk.rs`, four cells at a time in `kernel/lanes.rs`).

use super::{Cells, Integrand, SlabView, cell_failure, finite};
use crate::assembly::{AssemblyError, AssemblyStats};
use crate::model::{BlockInfo, StepContext};

impl Integrand for BlockInfo {
    fn add(
        &self,
        cells: Cells,
        _history: Option<&SlabView>,
        these: &[u32],
        _step: &StepContext,
    ) -> Result<AssemblyStats, AssemblyError> {
        let res = crate::with_cell!(cells.blk.kind, |N, D, E| cells
            .run::<N, D, E>(&self.mat, these));
        let (min_j, energy, ok) = res.map_err(|f| cell_failure(&cells, self.region, f))?;
        finite(ok)?;
        let mut stats = AssemblyStats::EMPTY;
        if self.mat.medium {
            stats.min_J_medium = min_j;
        } else {
            stats.min_J_solid = min_j;
        }
        stats.energy = energy;
        Ok(stats)
    }
}
