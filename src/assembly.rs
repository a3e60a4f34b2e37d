//! Assembly: the sparsity pattern (built once per mesh) and the global residual and tangent.
//!
//! Parallel over cells without locks and without per-thread copies of the arrays: the cells of
//! all blocks together are cut in two by recursive coordinate bisection (one level per
//! doubling of the threads), and the two halves run at once. Of each half, only the cells that share a node
//! with the other half can add into the same entries; the left half runs its shared cells
//! first, the right half its own last, after the left's are done. So no two cells that share
//! a node ever run at once, every entry is summed in the same order whatever the scheduling,
//! and the arrays are written once, in place (copies per thread cost a zeroing and a
//! summing pass over the tangent's tens of MB per assembly, more than the cells' scatter).
//!
//! The system is reduced to the free equations; a prescribed dof's column is moved to the
//! right-hand side with its increment ("lifting"), so symmetric tangents stay symmetric.
#![allow(non_snake_case)]

use crate::dofs::NONE;
use crate::element::RefElement;
use crate::kernel::{self, Active, CellState, KernelError, bulk, lanes};
use crate::model::Model;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// A block is not split into parts of fewer cells than this (a part's scheduling costs more
/// than its cells save).
const MIN_PART_CELLS: usize = 256;

/// CSC pattern of the free equations, rows sorted within each column.
#[derive(Clone, Debug)]
pub struct Pattern {
    pub n: usize,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
}

impl Pattern {
    /// Position of entry (row, col) in the value array.
    #[inline]
    pub fn slot(&self, row: usize, col: usize) -> usize {
        let (a, b) = (self.col_ptr[col], self.col_ptr[col + 1]);
        a + self.row_idx[a..b]
            .binary_search(&row)
            .expect("entry in pattern")
    }
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }
}

/// Build the pattern from the node graph: every dof of a node couples with every dof of the
/// nodes it shares a cell with.
pub fn build_pattern(model: &Model) -> Pattern {
    let mesh = &model.mesh;
    let nn = mesh.coords.len();
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); nn];
    for b in &mesh.cells {
        for c in 0..b.n_cells() {
            let cell = b.cell(c);
            for &a in cell {
                adj[a].extend(cell.iter().map(|&x| x as u32));
            }
        }
    }
    adj.par_iter_mut().for_each(|v| {
        v.sort_unstable();
        v.dedup();
    });
    let eq = &model.cons.eq;
    let mut node_eqs: Vec<Vec<usize>> = Vec::with_capacity(nn);
    let mut buf = Vec::new();
    for n in 0..nn {
        model.dofs.node_dofs(n, &mut buf);
        let mut e: Vec<usize> = buf
            .iter()
            .map(|&d| eq[d as usize])
            .filter(|&e| e != NONE)
            .map(|e| e as usize)
            .collect();
        e.sort_unstable();
        node_eqs.push(e);
    }
    let n = model.cons.n_eq;
    // column of equation e (of node a) = equations of all neighbours of a
    let mut col_of_eq: Vec<(usize, usize)> = Vec::with_capacity(n); // (node, unused)
    col_of_eq.resize(n, (usize::MAX, 0));
    for (a, es) in node_eqs.iter().enumerate() {
        for &e in es {
            col_of_eq[e] = (a, 0);
        }
    }
    let cols: Vec<Vec<usize>> = col_of_eq
        .par_iter()
        .map(|&(a, _)| {
            let mut rows: Vec<usize> = adj[a]
                .iter()
                .flat_map(|&b| node_eqs[b as usize].iter().copied())
                .collect();
            rows.sort_unstable();
            rows
        })
        .collect();
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0);
    let mut row_idx = Vec::with_capacity(cols.iter().map(Vec::len).sum());
    for c in cols {
        row_idx.extend(c);
        col_ptr.push(row_idx.len());
    }
    Pattern {
        n,
        col_ptr,
        row_idx,
    }
}

/// Failure found while assembling.
#[derive(Clone, Debug, PartialEq)]
pub enum AssemblyError {
    /// J ≤ 0 at a quadrature point of a cell of `region`.
    Inverted { region: String, J: f64 },
    /// A cell of the undeformed mesh is inverted or degenerate.
    BadMesh { region: String, cell: usize },
    /// A regularization rotation measure is unbounded (a medium cell rotated by 90°).
    Singular { region: String },
    /// NaN or infinity in the residual or the tangent.
    NotFinite,
}

impl std::fmt::Display for AssemblyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AssemblyError::Inverted { region, J } => {
                write!(f, "J = {J:.3e} ≤ 0 in region \"{region}\"")
            }
            AssemblyError::BadMesh { region, cell } => {
                write!(
                    f,
                    "cell {cell} of region \"{region}\" is inverted or degenerate in the undeformed mesh"
                )
            }
            AssemblyError::Singular { region } => write!(
                f,
                "a cell of region \"{region}\" is rotated by 90° (regularization unbounded)"
            ),
            AssemblyError::NotFinite => write!(f, "the residual is not finite"),
        }
    }
}

impl AssemblyError {
    /// The state is outside the admissible set (a shorter update may be fine), as opposed to a
    /// broken mesh.
    pub fn is_inadmissible(&self) -> bool {
        !matches!(self, AssemblyError::BadMesh { .. })
    }
}

/// Per-call results besides the arrays.
#[derive(Clone, Copy, Debug)]
pub struct AssemblyStats {
    pub min_J_solid: f64,
    pub min_J_medium: f64,
    pub energy: f64,
}

/// The order a block's cells are assembled in, and which of them may run at once.
#[derive(Debug)]
enum Schedule {
    /// Cells run one after another.
    Cells(Vec<u32>),
    /// Two halves that run at once. `first`: the left half's cells sharing a node with the
    /// right half, run before the rest of the left; `last`: the right half's cells sharing a
    /// node with the left half, run after the rest of the right and after `first`.
    Split {
        first: Vec<u32>,
        left: Box<Schedule>,
        right: Box<Schedule>,
        last: Vec<u32>,
    },
}

impl Schedule {
    /// Split `cells` (`nodes` gives each one's mesh nodes) `depth` times by coordinate
    /// bisection of their centroids along the widest extent. `mark` (one entry per mesh node)
    /// is scratch.
    fn build<'m>(
        nodes: &impl Fn(u32) -> &'m [usize],
        coords: &[[f64; 3]],
        mut cells: Vec<u32>,
        depth: usize,
        mark: &mut [u32],
        stamp: &mut u32,
    ) -> Schedule {
        if depth == 0 || cells.len() < 2 * MIN_PART_CELLS {
            cells.sort_unstable();
            return Schedule::Cells(cells);
        }
        let centroid = |c: u32| -> [f64; 3] {
            let nodes = nodes(c);
            let mut m = [0.0; 3];
            for &n in nodes {
                for (mi, xi) in m.iter_mut().zip(&coords[n]) {
                    *mi += xi;
                }
            }
            m.map(|v| v / nodes.len() as f64)
        };
        let mut keyed: Vec<([f64; 3], u32)> = cells.iter().map(|&c| (centroid(c), c)).collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for (m, _) in &keyed {
            for i in 0..3 {
                lo[i] = lo[i].min(m[i]);
                hi[i] = hi[i].max(m[i]);
            }
        }
        let axis = (0..3)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
            .unwrap_or(0);
        keyed.sort_by(|a, b| a.0[axis].total_cmp(&b.0[axis]).then(a.1.cmp(&b.1)));
        cells = keyed.into_iter().map(|(_, c)| c).collect();
        let right = cells.split_off(cells.len() / 2);
        let left = cells;
        // the cells of one half with a node in a cell of the other
        let mut shared_with = |of: &[u32], other: &[u32]| -> (Vec<u32>, Vec<u32>) {
            *stamp += 1;
            for &c in other {
                for &n in nodes(c) {
                    mark[n] = *stamp;
                }
            }
            let (mut shared, rest): (Vec<u32>, Vec<u32>) = of
                .iter()
                .partition(|&&c| nodes(c).iter().any(|&n| mark[n] == *stamp));
            shared.sort_unstable();
            (shared, rest)
        };
        let (first, left_rest) = shared_with(&left, &right);
        let (last, right_rest) = shared_with(&right, &left);
        Schedule::Split {
            first,
            left: Box::new(Schedule::build(
                nodes,
                coords,
                left_rest,
                depth - 1,
                mark,
                stamp,
            )),
            right: Box::new(Schedule::build(
                nodes,
                coords,
                right_rest,
                depth - 1,
                mark,
                stamp,
            )),
            last,
        }
    }

    /// All cells, in an order consistent with every order `run` may run them in: two cells
    /// sharing a node come in the order they run in.
    fn order(&self, out: &mut Vec<u32>) {
        match self {
            Schedule::Cells(c) => out.extend(c),
            Schedule::Split {
                first,
                left,
                right,
                last,
            } => {
                // `first` runs before `left` and `last`; `last` after `right`; `left` shares no
                // node with `right` or `last`, nor `first` with `right`
                out.extend(first);
                left.order(out);
                right.order(out);
                out.extend(last);
            }
        }
    }

    /// Run `cells` on every part, halves at once; results combined in a fixed order.
    fn run<T: Send, E: Send>(
        &self,
        cells: &(impl Fn(&[u32]) -> Result<T, E> + Sync),
        combine: &(impl Fn(T, T) -> T + Sync),
    ) -> Result<T, E> {
        match self {
            Schedule::Cells(c) => cells(c),
            Schedule::Split {
                first,
                left,
                right,
                last,
            } => {
                let first_done = AtomicBool::new(false);
                let (a, b) = rayon::join(
                    || {
                        // set even on failure, or the right half would wait forever
                        let a = cells(first);
                        first_done.store(true, Ordering::Release);
                        Ok(combine(a?, left.run(cells, combine)?))
                    },
                    || {
                        let b = right.run(cells, combine)?;
                        // `first` runs at once on the thread that called join (never waiting
                        // itself), so this wait ends; it is normally over before it starts
                        while !first_done.load(Ordering::Acquire) {
                            std::thread::yield_now();
                        }
                        Ok(combine(b, cells(last)?))
                    },
                );
                Ok(combine(a?, b?))
            }
        }
    }
}

/// Assembler state reused across calls: pattern, value and vector storage.
pub struct Assembler {
    pub pattern: Pattern,
    /// Per model block, where its cells' tangent entries go (built once per mesh, so the
    /// scatter is a load and an add per entry, not a search).
    slots: Vec<Slots>,
    /// The order the cells run in, by global number (a model block's cells follow those of
    /// the blocks before it, from `first_cell[block]`).
    schedule: Schedule,
    first_cell: Vec<u32>,
    /// Entries of `values` zeroed before each tangent assembly: those whose first writer
    /// adds (see `Slots::flag_first`). Entries no cell writes stay at their initial zero.
    zero_first: Vec<u32>,
    /// Tangent values (CSC, free equations).
    pub values: Vec<f64>,
    /// Internal-minus-external force on every dof (reactions on prescribed dofs).
    pub r_full: Vec<f64>,
    /// Lifted right-hand side contribution Σ K_fd Δx_d on the free equations.
    pub lift: Vec<f64>,
    /// Ask for the cache lines each cell's tangent goes to before its kernel runs (on by
    /// default; off only to measure what it saves).
    pub prefetch: bool,
}

#[derive(Clone, Copy)]
struct Shared(*mut f64);
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

impl Shared {
    /// Pointer to entry `i`. Callers guarantee exclusive access to that entry.
    #[inline]
    fn at(&self, i: usize) -> *mut f64 {
        // SAFETY: in bounds by construction of the pattern and dof map
        unsafe { self.0.add(i) }
    }
}

/// Length of the pieces the whole-array passes below are cut into, one task each.
const PASS_CHUNK: usize = 1 << 15;

/// Whether every entry of `v` is finite, in parallel.
fn all_finite(v: &[f64]) -> bool {
    v.par_chunks(PASS_CHUNK)
        .all(|c| c.iter().fold(true, |ok, x| ok & x.is_finite()))
}

/// Marks a tangent entry that is not in the free system.
const NO_SLOT: u32 = u32::MAX;
/// Flag of a slot-map entry: this cell is the first to write the rows it writes there, so
/// it stores instead of adding (the assembly needs no zeroing pass over the tangent).
const FIRST: u32 = 1 << 31;

/// The global dofs of a cell's local dofs, in the kernel's layout.
fn local_dofs(model: &Model, bi: usize, nodes: &[usize], ld: &mut [u32]) {
    let lay = model.blocks[bi].layout;
    let (dofs, D) = (&model.dofs, lay.dim);
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
struct Slots {
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
    fn new(model: &Model, bi: usize, pattern: &Pattern) -> Slots {
        let eq = &model.cons.eq;
        let blk = &model.mesh.cells[model.blocks[bi].block];
        let lay = model.blocks[bi].layout;
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
                        local_dofs(model, bi, blk.cell(c), ld);
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
    unsafe fn add(&self, c: usize, k: &[f64], values: Shared) -> bool {
        let (n, nd) = (self.n, self.nd);
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
    fn prefetch(&self, c: usize, values: Shared) {
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
    fn flag_first(slots: &mut [Slots], order: &[(usize, usize)], nnz: usize, zero: &mut Vec<u32>) {
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

impl Assembler {
    pub fn new(model: &Model) -> Assembler {
        let pattern = build_pattern(model);
        assert!(
            pattern.nnz() < FIRST as usize,
            "more than 2³¹ tangent entries"
        );
        let mut slots: Vec<Slots> = (0..model.blocks.len())
            .map(|bi| Slots::new(model, bi, &pattern))
            .collect();
        // one level of halves per doubling of the threads
        let depth = rayon::current_num_threads()
            .next_power_of_two()
            .trailing_zeros() as usize;
        let mesh = &model.mesh;
        let mut first_cell = vec![0u32];
        for info in &model.blocks {
            let n = mesh.cells[info.block].n_cells() as u32;
            first_cell.push(first_cell.last().unwrap() + n);
        }
        let nodes = |g: u32| -> &[usize] {
            let bi = first_cell.partition_point(|&f| f <= g) - 1;
            mesh.cells[model.blocks[bi].block].cell((g - first_cell[bi]) as usize)
        };
        let cells = (0..*first_cell.last().unwrap()).collect();
        let (mut mark, mut stamp) = (vec![0u32; mesh.coords.len()], 0);
        let schedule = Schedule::build(&nodes, &mesh.coords, cells, depth, &mut mark, &mut stamp);
        let mut order = Vec::new();
        schedule.order(&mut order);
        let order: Vec<(usize, usize)> = order
            .into_iter()
            .map(|g| {
                let bi = first_cell.partition_point(|&f| f <= g) - 1;
                (bi, (g - first_cell[bi]) as usize)
            })
            .collect();
        let mut zero_first = Vec::new();
        Slots::flag_first(&mut slots, &order, pattern.nnz(), &mut zero_first);
        Assembler {
            zero_first,
            values: vec![0.0; pattern.nnz()],
            r_full: vec![0.0; model.dofs.n_dofs],
            lift: vec![0.0; pattern.n],
            pattern,
            slots,
            schedule,
            first_cell,
            prefetch: true,
        }
    }

    /// Assemble at the state `x` (all dofs) and pseudo-time `t` (see `LoadPath`). With `tangent`, fills
    /// `values`; with `dx_prescribed`, also the lifting of those prescribed increments.
    pub fn assemble(
        &mut self,
        model: &Model,
        x: &[f64],
        t: f64,
        tangent: bool,
        dx_prescribed: Option<&[f64]>,
    ) -> Result<AssemblyStats, AssemblyError> {
        self.assemble_part(model, x, t, tangent, dx_prescribed, Active::ALL)
    }

    /// As [`Assembler::assemble`], filling only the equations `act` names (the others' rows
    /// and residuals are left at zero).
    pub fn assemble_part(
        &mut self,
        model: &Model,
        x: &[f64],
        t: f64,
        tangent: bool,
        dx_prescribed: Option<&[f64]>,
        act: Active,
    ) -> Result<AssemblyStats, AssemblyError> {
        if tangent {
            // an update that inverted a cell costs this pass, not a whole assembly
            check_inversion(model, x)?;
        }
        self.r_full.fill(0.0);
        if tangent {
            for &i in &self.zero_first {
                self.values[i as usize] = 0.0;
            }
        }
        self.lift.fill(0.0);
        let first_cell = &self.first_cell;
        let prefetch = tangent && self.prefetch;
        let slots = &self.slots;
        let arrays = Arrays {
            values: Shared(self.values.as_mut_ptr()),
            r_full: Shared(self.r_full.as_mut_ptr()),
            lift: Shared(self.lift.as_mut_ptr()),
        };
        let empty = AssemblyStats {
            min_J_solid: f64::INFINITY,
            min_J_medium: f64::INFINITY,
            energy: 0.0,
        };
        // a part's cells, sorted: runs of one model block each
        let run = |cells: &[u32]| -> Result<AssemblyStats, AssemblyError> {
            let mut stats = empty;
            let mut rest = cells;
            while let Some(&g) = rest.first() {
                let bi = first_cell.partition_point(|&f| f <= g) - 1;
                let len = rest.partition_point(|&h| h < first_cell[bi + 1]);
                let (these, next) = rest.split_at(len);
                rest = next;
                let info = &model.blocks[bi];
                let kind = model.mesh.cells[info.block].kind;
                let job = Cells {
                    model,
                    bi,
                    first: first_cell[bi],
                    slots: &slots[bi],
                    x,
                    tangent,
                    dx_prescribed,
                    act,
                    arrays,
                    prefetch,
                };
                let res = crate::with_cell!(kind, |N, D, E| job.run::<N, D, E>(these));
                let (min_j, energy, finite) =
                    res.map_err(|(e, cell)| cell_error(model, bi, e, cell))?;
                if !finite {
                    return Err(AssemblyError::NotFinite);
                }
                if info.mat.medium {
                    stats.min_J_medium = stats.min_J_medium.min(min_j);
                } else {
                    stats.min_J_solid = stats.min_J_solid.min(min_j);
                }
                stats.energy += energy;
            }
            Ok(stats)
        };
        let stats = self
            .schedule
            .run(&run, &|a: AssemblyStats, b: AssemblyStats| AssemblyStats {
                min_J_solid: a.min_J_solid.min(b.min_J_solid),
                min_J_medium: a.min_J_medium.min(b.min_J_medium),
                energy: a.energy + b.energy,
            })?;
        // the tangent's entries were checked as they were written
        let finite = all_finite(&self.r_full) && all_finite(&self.lift);
        if !finite {
            return Err(AssemblyError::NotFinite);
        }
        let mut fe = vec![0.0; model.dofs.n_dofs];
        model.f_ext(t, &mut fe);
        for (r, f) in self.r_full.iter_mut().zip(&fe) {
            *r -= f;
        }
        Ok(stats)
    }
}

/// The assembly error of a kernel's failure in cell `cell` of model block `bi`.
fn cell_error(model: &Model, bi: usize, e: KernelError, cell: usize) -> AssemblyError {
    let region = || model.regions[model.blocks[bi].region].0.clone();
    match e {
        KernelError::Inverted { J } => AssemblyError::Inverted {
            region: region(),
            J,
        },
        KernelError::BadGeometry => AssemblyError::BadMesh {
            region: region(),
            cell,
        },
        KernelError::Singular => AssemblyError::Singular { region: region() },
    }
}

/// The first medium cell (in block and cell order, whatever the threads) that `x` inverts,
/// as the assembly would report it. Only the medium: it is where updates invert cells, and
/// it is a small part of the mesh (a whole-mesh look costs a quarter of an assembly); an
/// inverted solid cell is still found by the assembly.
pub fn check_inversion(model: &Model, x: &[f64]) -> Result<(), AssemblyError> {
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
                    let s = crate::post::gather::<N>(model, blk.cell(c), x);
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
struct Arrays {
    values: Shared,
    r_full: Shared,
    lift: Shared,
}

/// What the cells of one model block need to add their part.
#[derive(Clone, Copy)]
struct Cells<'a> {
    model: &'a Model,
    bi: usize,
    /// Global number of the block's first cell.
    first: u32,
    slots: &'a Slots,
    x: &'a [f64],
    tangent: bool,
    dx_prescribed: Option<&'a [f64]>,
    act: Active,
    arrays: Arrays,
    /// Prefetch each cell's scatter targets before its kernel runs.
    prefetch: bool,
}

impl Cells<'_> {
    /// Add the cells `cells` (global numbers, all of this block). Returns (min J, energy,
    /// whether the tangent entries written are finite), or the kernel's error with the
    /// block's cell number.
    fn run<const N: usize, const D: usize, E: RefElement<N, D>>(
        self,
        cells: &[u32],
    ) -> Result<(f64, f64, bool), (KernelError, usize)> {
        let Cells {
            model,
            bi,
            first,
            slots,
            x,
            tangent,
            dx_prescribed,
            act,
            arrays:
                Arrays {
                    values,
                    r_full,
                    lift,
                },
            prefetch,
        } = self;
        let info = &model.blocks[bi];
        let blk = &model.mesh.cells[info.block];
        let lay = info.layout;
        let nd = lay.ndof();
        let eq = &model.cons.eq;
        // add a cell's residual and tangent (row-major, nd × nd) into the global arrays
        let add = |c: usize, ld: &[u32], r: &[f64], k: &[f64]| -> bool {
            // SAFETY: the schedule never runs two cells that share a node at once, and a
            // cell writes only at its own nodes' rows (in bounds by construction).
            unsafe {
                for a in 0..nd {
                    *r_full.at(ld[a] as usize) += r[a];
                }
                if !tangent {
                    return true;
                }
                let finite = slots.add(c, k, values);
                // prescribed columns: their increments lifted to the right-hand side
                if let Some(dx) = dx_prescribed {
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
        };
        let mut ld = vec![0u32; nd];
        let (mut mj, mut en, mut finite) = (f64::INFINITY, 0.0, true);
        if lanes::available() && lanes::eligible(&info.mat, &lay, act) {
            // W cells per kernel call; a short last group repeats its last cell
            const W: usize = lanes::W;
            let mut r = vec![0.0; W * nd];
            let mut k = vec![0.0; if tangent { W * nd * nd } else { 0 }];
            for group in cells.chunks(W) {
                let cell = |l: usize| (group[l.min(group.len() - 1)] - first) as usize;
                if prefetch {
                    for l in 0..group.len() {
                        slots.prefetch(cell(l), values);
                    }
                }
                let s: [CellState<N>; W] =
                    std::array::from_fn(|l| crate::post::gather::<N>(model, blk.cell(cell(l)), x));
                let kl = if tangent { Some(&mut k[..]) } else { None };
                let out = lanes::bulk_lanes::<N, D, E>(&info.mat, &lay, &s, &mut r, kl)
                    .map_err(|(e, l)| (e, cell(l)))?;
                for l in 0..group.len() {
                    let c = cell(l);
                    mj = mj.min(out[l].min_J);
                    en += out[l].energy;
                    local_dofs(model, bi, blk.cell(c), &mut ld);
                    finite &= add(
                        c,
                        &ld,
                        &r[l * nd..(l + 1) * nd],
                        if tangent {
                            &k[l * nd * nd..(l + 1) * nd * nd]
                        } else {
                            &[]
                        },
                    );
                }
            }
            return Ok((mj, en, finite));
        }
        let mut r = vec![0.0; nd];
        let mut k = vec![0.0; if tangent { nd * nd } else { 0 }];
        for &g in cells {
            let c = (g - first) as usize;
            let nodes = blk.cell(c);
            if prefetch {
                slots.prefetch(c, values);
            }
            let s = crate::post::gather::<N>(model, nodes, x);
            local_dofs(model, bi, nodes, &mut ld);
            let out = bulk::<N, D, E>(
                &info.mat,
                &lay,
                &s,
                act,
                &mut r,
                if tangent { Some(&mut k) } else { None },
            )
            .map_err(|e| (e, c))?;
            mj = mj.min(out.min_J);
            en += out.energy;
            finite &= add(c, &ld, &r, &k);
        }
        Ok((mj, en, finite))
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

    /// Every cell once; the cells that may run at once (one half with its `first`, against
    /// the other half with its `last`, except `first` against `last`) share no node.
    fn check(s: &Schedule, nodes: &dyn Fn(u32) -> Vec<usize>, seen: &mut Vec<u32>) {
        let all = |s: &Schedule| {
            let mut v = Vec::new();
            check(s, nodes, &mut v);
            v
        };
        match s {
            Schedule::Cells(c) => seen.extend(c),
            Schedule::Split {
                first,
                left,
                right,
                last,
            } => {
                let (l, r) = (all(left), all(right));
                let node_set = |cells: &[&[u32]]| -> std::collections::HashSet<usize> {
                    cells
                        .iter()
                        .flat_map(|c| c.iter())
                        .flat_map(|&c| nodes(c))
                        .collect()
                };
                let a = node_set(&[first, &l]);
                assert!(
                    node_set(&[&r]).is_disjoint(&a),
                    "left and right share a node"
                );
                assert!(node_set(&[last]).is_disjoint(&node_set(&[&l])));
                // a real split: both halves have work that runs at once
                assert!(!l.is_empty() && !r.is_empty());
                seen.extend(first.iter().chain(&l).chain(&r).chain(last));
            }
        }
    }

    #[test]
    fn schedule_never_runs_cells_sharing_a_node_at_once() {
        // a 40 × 30 grid of quads, cells numbered in a scrambled order
        let (nx, ny) = (40usize, 30usize);
        let coords: Vec<[f64; 3]> = (0..(nx + 1) * (ny + 1))
            .map(|n| [(n % (nx + 1)) as f64, (n / (nx + 1)) as f64, 0.0])
            .collect();
        let n_cells = nx * ny;
        let conn: Vec<Vec<usize>> = (0..n_cells)
            .map(|c| (c * 7919) % n_cells)
            .map(|c| {
                let (i, j) = (c % nx, c / nx);
                let n0 = j * (nx + 1) + i;
                vec![n0, n0 + 1, n0 + nx + 2, n0 + nx + 1]
            })
            .collect();
        let nodes = |c: u32| -> &[usize] { &conn[c as usize] };
        for depth in 0..4 {
            let (mut mark, mut stamp) = (vec![0u32; coords.len()], 0);
            let cells = (0..n_cells as u32).collect();
            let s = Schedule::build(&nodes, &coords, cells, depth, &mut mark, &mut stamp);
            let mut seen = Vec::new();
            check(&s, &|c| nodes(c).to_vec(), &mut seen);
            seen.sort_unstable();
            assert_eq!(seen, (0..n_cells as u32).collect::<Vec<_>>());
            // the halves are cut across the grid's long side: few cells are shared
            if let Schedule::Split { first, last, .. } = &s {
                assert!(first.len() + last.len() <= 2 * ny, "{}", first.len());
            }
        }
    }
}
