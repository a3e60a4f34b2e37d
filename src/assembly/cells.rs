//! The cells of one block through their kernel, one cell or four (SIMD lanes) per call, their
//! residuals and tangents added into the global arrays; and the inversion check before an
//! assembly.
#![allow(non_snake_case)]

use super::reference::cell_state;
use super::scatter::{Shared, Slots, local_dofs};
use super::{AssemblyError, MIN_PART_CELLS, References, cell_error};
use crate::dofs::{CellState, Layout, NONE};
use crate::element::RefElement;
use crate::kernel::{self, Active, CellMaterial, KernelError, bulk, lanes};
use crate::mesh::Block;
use crate::model::Model;
use rayon::prelude::*;

/// The first medium cell (in block and cell order, whatever the threads) that `x` inverts,
/// as the assembly would report it. Only the medium: it is where updates invert cells, and
/// it is a small part of the mesh (a whole-mesh look costs a quarter of an assembly); an
/// inverted solid cell is still found by the assembly.
pub fn check_inversion(
    model: &Model,
    references: &References,
    x: &[f64],
) -> Result<(), AssemblyError> {
    for (bi, info) in model.blocks.iter().enumerate() {
        if !info.layout.has_u || !info.mat.medium {
            continue;
        }
        let blk = &model.mesh.cells[info.block];
        let found = crate::with_cell!(blk.kind, |N, D, E| {
            (0..blk.n_cells())
                .into_par_iter()
                .with_min_len(MIN_PART_CELLS)
                .map(|c| {
                    let s = references.state::<N>(model, info.block, c, x);
                    kernel::inversion::<N, D, E>(&s).map_err(|e| (e, c))
                })
                .find_first(Result::is_err)
        });
        if let Some(Err((e, cell))) = found {
            return Err(cell_error(model, bi, e, cell));
        }
    }
    Ok(())
}

/// The global arrays the cells add into.
#[derive(Clone, Copy)]
pub(super) struct Arrays {
    pub(super) values: Shared,
    pub(super) r_full: Shared,
    pub(super) lift: Shared,
}

/// One block's history during an assembly: read the committed values, write the trial ones
/// (each cell only its own `width` values).
#[derive(Clone, Copy)]
pub struct SlabView<'a> {
    pub(super) width: usize,
    pub(super) committed: &'a [f64],
    pub(super) trial: Shared,
}

impl SlabView<'_> {
    /// Cell `cell`'s committed values, and its trial values to write.
    ///
    /// # Safety
    /// No other thread may hold cell `cell`'s trial values (each cell runs once per assembly,
    /// and writes only its own).
    #[allow(clippy::mut_from_ref)]
    unsafe fn cell(&self, cell: usize) -> (&[f64], &mut [f64]) {
        let w = self.width;
        // SAFETY: in bounds by construction; exclusive by the caller's promise
        let trial = unsafe { std::slice::from_raw_parts_mut(self.trial.at(cell * w), w) };
        (&self.committed[cell * w..(cell + 1) * w], trial)
    }
}

/// What the cells (or facets) of one assembler block need to add their part.
#[derive(Clone, Copy)]
pub struct Cells<'a> {
    pub(super) model: &'a Model,
    /// The block's connectivity and local layout.
    pub(super) blk: &'a Block,
    pub(super) lay: Layout,
    /// Global number of the block's first cell.
    pub(super) first: u32,
    pub(super) slots: &'a Slots,
    pub(super) x: &'a [f64],
    pub(super) tangent: bool,
    pub(super) dx_prescribed: Option<&'a [f64]>,
    pub(super) act: Active,
    pub(super) arrays: Arrays,
    /// Prefetch each cell's scatter targets before its kernel runs.
    pub(super) prefetch: bool,
    /// The block's reference node coordinates per cell where its medium is reconnected
    /// (`None`: the mesh's).
    pub(super) reference: Option<&'a [[f64; 3]]>,
}

impl Cells<'_> {
    /// Cell `c`'s nodal state, measured from its reference configuration.
    #[inline]
    fn state<const N: usize>(&self, c: usize) -> CellState<N> {
        cell_state(self.model, self.blk.cell(c), self.reference, c, self.x)
    }

    /// Add cell `c`'s residual `r` and tangent `k` (row-major, nd × nd; ignored without
    /// `tangent`) at its global dofs `ld`, and the lifting of prescribed increments. Returns
    /// whether the tangent entries written are finite.
    ///
    /// # Safety
    /// No other thread may be adding at this cell's nodes (the schedule's promise).
    #[inline]
    unsafe fn add(&self, c: usize, ld: &[u32], r: &[f64], k: &[f64]) -> bool {
        let nd = self.lay.ndof();
        let eq = &self.model.cons.eq;
        let Arrays {
            values,
            r_full,
            lift,
        } = self.arrays;
        // SAFETY: the schedule never runs two cells that share a node at once, and a cell
        // writes only at its own nodes' rows (in bounds by construction).
        unsafe {
            for a in 0..nd {
                *r_full.at(ld[a] as usize) += r[a];
            }
            if !self.tangent {
                return true;
            }
            let finite = self.slots.add(c, k, values);
            // prescribed columns: their increments lifted to the right-hand side
            if let Some(dx) = self.dx_prescribed {
                for b in 0..nd {
                    let gb = ld[b] as usize;
                    if eq[gb] != NONE || dx[gb] == 0.0 {
                        continue;
                    }
                    for a in 0..nd {
                        let row = eq[ld[a] as usize];
                        if row != NONE {
                            *lift.at(row as usize) += k[a * nd + b] * dx[gb];
                        }
                    }
                }
            }
            finite
        }
    }

    /// Add the cells `cells` (global numbers, all of this block) of material `mat`. Returns
    /// (min J, energy, whether the tangent entries written are finite), or the kernel's error
    /// with the block's cell number.
    pub(super) fn run<const N: usize, const D: usize, E: RefElement<N, D>>(
        self,
        mat: &CellMaterial,
        cells: &[u32],
    ) -> Result<(f64, f64, bool), (KernelError, usize)> {
        let (model, blk, lay, first) = (self.model, self.blk, self.lay, self.first);
        let (tangent, values) = (self.tangent, self.arrays.values);
        let nd = lay.ndof();
        let mut ld = vec![0u32; nd];
        let (mut mj, mut en, mut finite) = (f64::INFINITY, 0.0, true);
        let lane_block = lanes::LaneBlock::new(mat, &lay, self.act);
        if let Some(lane_block) = lane_block.filter(|_| lanes::available()) {
            // W cells per kernel call; a short last group repeats its last cell
            const W: usize = lanes::W;
            let mut r = vec![0.0; W * nd];
            let mut k = vec![0.0; if tangent { W * nd * nd } else { 0 }];
            for group in cells.chunks(W) {
                let cell = |l: usize| (group[l.min(group.len() - 1)] - first) as usize;
                if self.prefetch {
                    for l in 0..group.len() {
                        self.slots.prefetch(cell(l), values);
                    }
                }
                let s: [CellState<N>; W] = std::array::from_fn(|l| self.state::<N>(cell(l)));
                let kl = if tangent { Some(&mut k[..]) } else { None };
                let out = lanes::bulk_lanes::<N, D, E>(&lane_block, &s, &mut r, kl)
                    .map_err(|(e, l)| (e, cell(l)))?;
                for l in 0..group.len() {
                    let c = cell(l);
                    mj = mj.min(out[l].min_J);
                    en += out[l].energy;
                    local_dofs(&model.dofs, &lay, blk.cell(c), &mut ld);
                    let kc = if tangent {
                        &k[l * nd * nd..(l + 1) * nd * nd]
                    } else {
                        &[]
                    };
                    // SAFETY: the schedule's promise (see `add`)
                    finite &= unsafe { self.add(c, &ld, &r[l * nd..(l + 1) * nd], kc) };
                }
            }
            return Ok((mj, en, finite));
        }
        let mut r = vec![0.0; nd];
        let mut k = vec![0.0; if tangent { nd * nd } else { 0 }];
        for &g in cells {
            let c = (g - first) as usize;
            let nodes = blk.cell(c);
            if self.prefetch {
                self.slots.prefetch(c, values);
            }
            let s = self.state::<N>(c);
            local_dofs(&model.dofs, &lay, nodes, &mut ld);
            let out = bulk::<N, D, E>(
                mat,
                &lay,
                &s,
                self.act,
                &mut r,
                if tangent { Some(&mut k) } else { None },
            )
            .map_err(|e| (e, c))?;
            mj = mj.min(out.min_J);
            en += out.energy;
            // SAFETY: the schedule's promise (see `add`)
            finite &= unsafe { self.add(c, &ld, &r, &k) };
        }
        Ok((mj, en, finite))
    }

    /// Run `kernel` on each of the cells `cells` (global numbers, all of this block) with the
    /// cell's number, its gathered state and the local r and k to fill (k only with
    /// `tangent`), and add the results. Returns whether the tangent entries written are
    /// finite, or the kernel's error with the block's cell number.
    pub(super) fn each_cell<const N: usize>(
        self,
        cells: &[u32],
        mut kernel: impl FnMut(
            usize,
            &CellState<N>,
            &mut [f64],
            Option<&mut [f64]>,
        ) -> Result<(), KernelError>,
    ) -> Result<bool, (KernelError, usize)> {
        let nd = self.lay.ndof();
        let (mut ld, mut r) = (vec![0u32; nd], vec![0.0; nd]);
        let mut k = vec![0.0; if self.tangent { nd * nd } else { 0 }];
        let mut finite = true;
        for &g in cells {
            let c = (g - self.first) as usize;
            let nodes = self.blk.cell(c);
            let s = self.state::<N>(c);
            local_dofs(&self.model.dofs, &self.lay, nodes, &mut ld);
            let kc = if self.tangent { Some(&mut k[..]) } else { None };
            kernel(c, &s, &mut r, kc).map_err(|e| (e, c))?;
            // SAFETY: the schedule's promise (see `add`)
            finite &= unsafe { self.add(c, &ld, &r, &k) };
        }
        Ok(finite)
    }

    /// [`Cells::each_cell`] for a term with history per point: `kernel` also gets the cell's
    /// committed history and its trial values to fill.
    pub(super) fn each_cell_with_history<const N: usize>(
        self,
        slab: &SlabView,
        cells: &[u32],
        mut kernel: impl FnMut(
            usize,
            &CellState<N>,
            &[f64],
            &mut [f64],
            &mut [f64],
            Option<&mut [f64]>,
        ) -> Result<(), KernelError>,
    ) -> Result<bool, (KernelError, usize)> {
        self.each_cell::<N>(cells, |cell, s, r, k| {
            // SAFETY: a cell runs once per assembly
            let (committed, trial) = unsafe { slab.cell(cell) };
            kernel(cell, s, committed, trial, r, k)
        })
    }
}
