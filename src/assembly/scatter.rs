//! Where each cell's tangent entries go: a slot map per block, built once per mesh, so the
//! scatter is a load and an add (or a store, for the first writer) per entry.
#![allow(non_snake_case)]

use crate::dofs::{DofMap, Layout, NONE, Pattern};
use crate::mesh::Block;
use crate::model::Model;
use rayon::prelude::*;

#[derive(Clone, Copy)]
pub(super) struct Shared(pub(super) *mut f64);
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

impl Shared {
    /// Pointer to entry `i`. Callers guarantee exclusive access to that entry.
    #[inline]
    pub(super) fn at(&self, i: usize) -> *mut f64 {
        // SAFETY: in bounds by construction of the pattern and dof map
        unsafe { self.0.add(i) }
    }
}

/// Marks a tangent entry that is not in the free system.
pub(super) const NO_SLOT: u32 = u32::MAX;
/// Flag of a slot-map entry: this cell is the first to write the rows it writes there, so
/// it stores instead of adding (the assembly needs no zeroing pass over the tangent).
pub(super) const FIRST: u32 = 1 << 31;

/// The global dofs of a cell's local dofs, in the kernel's layout.
pub(super) fn local_dofs(dofs: &DofMap, lay: &Layout, nodes: &[usize], ld: &mut [u32]) {
    let D = lay.dim;
    for (I, &n) in nodes.iter().enumerate() {
        if lay.has_u {
            for i in 0..D {
                ld[lay.u(I, i)] = dofs.u[n * D + i];
            }
        }
        if lay.has_theta {
            ld[lay.theta(I)] = dofs.theta[n];
        }
        for c in 0..lay.np {
            ld[lay.p(I, c)] = dofs.p[n * lay.np + c];
        }
    }
}

/// Where one block's cells add their tangent, node by node. A node's free equations are
/// consecutive, so in any column of the pattern its rows sit at consecutive positions: the
/// entry (local row a of node A, local column b) is at `base[A][b] + offset[a]`. Four to seven
/// times smaller than a position per entry (1 KB per H1 u+θ cell instead of 4 KB): the map is
/// streamed from memory at every assembly.
pub(super) struct Slots {
    /// Nodes per cell.
    n: usize,
    /// Local dofs per cell.
    nd: usize,
    /// Per cell, `n × nd`, row-major: position in `values` of node A's first free row in the
    /// column of local dof b, with the flag `FIRST`; or `NO_SLOT` (b prescribed, or A without
    /// free dofs).
    base: Vec<u32>,
    /// Per cell, `nd`: local row a's place among its node's free rows, or `NO_ROW` (prescribed).
    offset: Vec<u8>,
    /// Node of each local dof.
    node: Vec<usize>,
}

/// Marks a local row that is not in the free system.
const NO_ROW: u8 = u8::MAX;

impl Slots {
    /// The slots of block `blk` (cells or facets) with local layout `lay`, for the cells
    /// `mine` keeps (the others' stay `NO_SLOT`: `pattern` may lack their entries).
    pub(super) fn new(
        model: &Model,
        blk: &Block,
        lay: Layout,
        pattern: &Pattern,
        mine: impl Fn(usize) -> bool + Sync,
    ) -> Slots {
        let eq = &model.cons.eq;
        let (n, nd) = (blk.kind.n_nodes(), lay.ndof());
        let mut node = vec![0; nd];
        for I in 0..n {
            if lay.has_u {
                for i in 0..lay.dim {
                    node[lay.u(I, i)] = I;
                }
            }
            if lay.has_theta {
                node[lay.theta(I)] = I;
            }
            for c in 0..lay.np {
                node[lay.p(I, c)] = I;
            }
        }
        let cells = blk.n_cells();
        let mut base = vec![NO_SLOT; cells * n * nd];
        let mut offset = vec![NO_ROW; cells * nd];
        if nd > 0 {
            base.par_chunks_mut(n * nd)
                .zip(offset.par_chunks_mut(nd))
                .enumerate()
                .for_each_init(
                    || (vec![0u32; nd], vec![NONE; n]),
                    |(ld, first), (c, (base, offset))| {
                        if !mine(c) {
                            return;
                        }
                        local_dofs(&model.dofs, &lay, blk.cell(c), ld);
                        // each node's first free equation
                        first.fill(NONE);
                        for a in 0..nd {
                            let e = eq[ld[a] as usize];
                            if e != NONE {
                                first[node[a]] = first[node[a]].min(e);
                            }
                        }
                        for a in 0..nd {
                            let e = eq[ld[a] as usize];
                            if e != NONE {
                                let o = e - first[node[a]];
                                assert!(o < NO_ROW as u32, "more than 254 unknowns on a node");
                                offset[a] = o as u8;
                            }
                        }
                        for b in 0..nd {
                            let col = eq[ld[b] as usize];
                            if col == NONE {
                                continue;
                            }
                            let (lo, hi) = (
                                pattern.col_ptr[col as usize],
                                pattern.col_ptr[col as usize + 1],
                            );
                            for (A, &row) in first.iter().enumerate() {
                                if row == NONE {
                                    continue;
                                }
                                let q = lo
                                    + pattern.row_idx[lo..hi]
                                        .binary_search(&(row as usize))
                                        .expect("a cell's entries are in the pattern");
                                base[A * nd + b] = q as u32;
                            }
                        }
                        // the node's other free rows follow its first one in every column
                        debug_assert!((0..nd).all(|a| offset[a] == NO_ROW
                            || (0..nd).all(|b| base[node[a] * nd + b] == NO_SLOT
                                || pattern.row_idx
                                    [(base[node[a] * nd + b] + offset[a] as u32) as usize]
                                    == eq[ld[a] as usize] as usize)));
                    },
                );
        }
        Slots {
            n,
            nd,
            base,
            offset,
            node,
        }
    }

    /// Add the row-major `nd × nd` tangent `k` of cell `c` into `values` (store, where the
    /// cell writes first). Returns whether every entry it wrote is finite: an entry that ends
    /// up not finite was not finite when last written, so this replaces a pass over `values`.
    ///
    /// # Safety
    /// No other thread may be adding at the same positions (another cell sharing a node).
    #[inline]
    pub(super) unsafe fn add(&self, c: usize, k: &[f64], values: Shared) -> bool {
        let (n, nd) = (self.n, self.nd);
        if nd == 0 {
            return true; // a block without unknowns (a scene with no physics active)
        }
        let base = &self.base[c * n * nd..(c + 1) * n * nd];
        let offset = &self.offset[c * nd..(c + 1) * nd];
        let mut finite = true;
        for (a, ka) in k.chunks_exact(nd).enumerate() {
            let o = offset[a];
            if o == NO_ROW {
                continue;
            }
            let row = &base[self.node[a] * nd..(self.node[a] + 1) * nd];
            for (&q, &v) in row.iter().zip(ka) {
                if q != NO_SLOT {
                    // SAFETY: in bounds by construction; exclusive by the caller
                    let p = values.at((q & !FIRST) as usize + o as usize);
                    let s = unsafe {
                        let old = *p;
                        let s = if q & FIRST != 0 { v } else { old + v };
                        *p = s;
                        s
                    };
                    finite &= s.is_finite();
                }
            }
        }
        finite
    }

    /// Ask for the cache lines cell `c` will add into, so that they arrive (in L2) while the
    /// kernel computes the cell: the tangent is larger than L2, and the scatter would
    /// otherwise wait on each line from memory or L3.
    #[inline]
    pub(super) fn prefetch(&self, c: usize, values: Shared) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T1, _mm_prefetch};
            let (n, nd) = (self.n, self.nd);
            let last = nd / n - 1;
            for &q in &self.base[c * n * nd..(c + 1) * n * nd] {
                if q != NO_SLOT {
                    // the node's first and (at most) last row in this column
                    let p = values.0.wrapping_add((q & !FIRST) as usize);
                    // SAFETY: a prefetch reads nothing and never faults
                    unsafe {
                        _mm_prefetch::<_MM_HINT_T1>(p as *const i8);
                        _mm_prefetch::<_MM_HINT_T1>(p.wrapping_add(last) as *const i8);
                    }
                }
            }
        }
    }

    /// Flag each cell's first writes, visiting the cells in `order` (an order consistent with
    /// every order the schedule may run them in): a node's rows in a column get `FIRST` in the
    /// cell that writes all of them first. The entries a cell writes first without the flag
    /// (a medium node's p rows, where a solid cell without p came first) are pushed to `zero`.
    pub(super) fn flag_first(
        slots: &mut [Slots],
        order: &[(usize, usize)],
        nnz: usize,
        zero: &mut Vec<u32>,
    ) {
        let mut written = vec![false; nnz];
        let mut rows = Vec::new();
        for &(bi, c) in order {
            let s = &mut slots[bi];
            let (n, nd) = (s.n, s.nd);
            let offset = &s.offset[c * nd..(c + 1) * nd];
            for A in 0..n {
                rows.clear();
                rows.extend(
                    (0..nd)
                        .filter(|&a| s.node[a] == A && offset[a] != NO_ROW)
                        .map(|a| offset[a] as usize),
                );
                for q in &mut s.base[(c * n + A) * nd..(c * n + A + 1) * nd] {
                    if *q == NO_SLOT {
                        continue;
                    }
                    let at = |o: &usize| *q as usize + o;
                    let all_first = rows.iter().all(|o| !written[at(o)]);
                    for o in &rows {
                        if !written[at(o)] {
                            written[at(o)] = true;
                            if !all_first {
                                zero.push(at(o) as u32);
                            }
                        }
                    }
                    if all_first {
                        *q |= FIRST;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One cell of two nodes with u (3) and θ in the field-major local layout, the free
    /// equations node by node (4 per node), the pattern dense 8 × 8. Node 1's θ row is
    /// prescribed when `prescribed`.
    fn two_node_slots(prescribed: bool) -> (Slots, impl Fn(usize) -> Option<usize>) {
        let (n, nd) = (2, 8);
        let node = [0, 0, 0, 1, 1, 1, 0, 1];
        let within = [0u8, 1, 2, 0, 1, 2, 3, 3];
        let eq =
            move |a: usize| (!(prescribed && a == 7)).then_some(4 * node[a] + within[a] as usize);
        let mut base = vec![NO_SLOT; n * nd];
        for A in 0..n {
            for b in 0..nd {
                if let Some(col) = eq(b) {
                    base[A * nd + b] = (col * 8 + 4 * A) as u32;
                }
            }
        }
        let offset = (0..nd)
            .map(|a| eq(a).map_or(NO_ROW, |_| within[a]))
            .collect();
        let slots = Slots {
            n,
            nd,
            base,
            offset,
            node: node.to_vec(),
        };
        (slots, eq)
    }

    /// The scatter puts k(a, b) at (row of a, column of b), stores where flagged first and
    /// adds elsewhere, leaves prescribed rows and columns alone, and reports a NaN or an
    /// infinity among the entries it writes.
    #[test]
    fn the_scatter_puts_each_entry_in_its_place() {
        let cases = (0..2).flat_map(|fresh| [false, true].map(|p| (fresh, p)));
        for (fresh, prescribed) in cases {
            let (mut slots, eq) = two_node_slots(prescribed);
            // node `fresh`'s rows are written first: stored over the garbage there; the
            // other node's rows are added to a previous sum
            for q in &mut slots.base[fresh * 8..fresh * 8 + 8] {
                if *q != NO_SLOT {
                    *q |= FIRST;
                }
            }
            let k: Vec<f64> = (0..64).map(|i| 1.0 + (i * 37 % 64) as f64 / 8.0).collect();
            let old = |row: usize| if row / 4 == fresh { f64::NAN } else { 0.5 };
            let mut values: Vec<f64> = (0..64).map(|i| old(i % 8)).collect();
            let shared = Shared(values.as_mut_ptr());
            // SAFETY: one thread; positions in bounds
            assert!(unsafe { slots.add(0, &k, shared) });
            for a in 0..8 {
                for b in 0..8 {
                    let (Some(row), Some(col)) = (eq(a), eq(b)) else {
                        continue;
                    };
                    let sum = if row / 4 == fresh { 0.0 } else { 0.5 } + k[a * 8 + b];
                    assert_eq!(values[col * 8 + row], sum, "({a}, {b})");
                }
            }
            if prescribed {
                // the prescribed row and column are left alone
                for i in 0..8 {
                    for (row, col) in [(7, i), (i, 7)] {
                        let v = values[col * 8 + row];
                        assert!(v.to_bits() == old(row).to_bits(), "{row} {col}");
                    }
                }
            }
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                for at in [0, 6 * 8 + 3, 5 * 8 + 1] {
                    let mut kb = k.clone();
                    kb[at] = bad;
                    values.fill(0.5);
                    let shared = Shared(values.as_mut_ptr());
                    // SAFETY: as above
                    assert!(!unsafe { slots.add(0, &kb, shared) }, "{bad} at {at}");
                }
            }
        }
    }
}
