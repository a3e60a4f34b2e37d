//! A boundary heat flux (convection, radiation) on a facet block (`kernel/facet.rs`).

use super::{Cells, Integrand, SlabView, finite};
use crate::assembly::{AssemblyError, AssemblyStats, facet_error};
use crate::kernel::facet;
use crate::model::{FacetBlock, StepContext};

impl Integrand for FacetBlock {
    fn add(
        &self,
        cells: Cells,
        _history: Option<&SlabView>,
        these: &[u32],
        _step: &StepContext,
    ) -> Result<AssemblyStats, AssemblyError> {
        let (lay, act, model) = (cells.lay, cells.act, cells.model);
        let res = crate::with_element!(cells.blk.kind, |N, D, E| cells
            .each_cell::<N>(these, |_, s, r, k| facet::boundary_flux::<N, D, E>(
                &self.law, &lay, s, act, r, k
            )));
        finite(res.map_err(|(e, facet)| facet_error(model, self, e, facet))?)
    }
}
