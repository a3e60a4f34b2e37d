//! Assembly: the sparsity pattern (built once per mesh) and the global residual and tangent.
//!
//! Parallel over cells without locks: each block's cells are cut into one contiguous chunk
//! per thread, and each chunk adds into its own copy of the arrays (the first into the
//! result itself), summed at the end. On few cores this beats colouring (one parallel region
//! per colour, each too small to pay for its scheduling) and keeps cells in mesh order for
//! locality; the copies cost (threads − 1) × nnz values, so at most 8 threads assemble.
//!
//! The system is reduced to the free equations; a prescribed dof's column is moved to the
//! right-hand side with its increment ("lifting"), so symmetric tangents stay symmetric.
#![allow(non_snake_case)]

use crate::dofs::NONE;
use crate::element::RefElement;
use crate::kernel::{Active, KernelError, bulk};
use crate::model::Model;
use rayon::prelude::*;

/// At most this many threads assemble (each beyond the first holds a copy of the arrays).
const MAX_ASSEMBLY_THREADS: usize = 8;

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
    /// NaN or infinity in the residual.
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

/// The arrays one assembly thread adds into.
struct Arrays {
    values: Vec<f64>,
    r_full: Vec<f64>,
    lift: Vec<f64>,
}

/// Assembler state reused across calls: pattern, value and vector storage.
pub struct Assembler {
    pub pattern: Pattern,
    /// Per model block, per cell, row-major over the cell's local dofs (a, b) like the kernel's
    /// tangent: the position in `values` of entry (row a, column b), or `NO_SLOT` where either
    /// is prescribed.
    /// Built once per mesh, so the scatter is a load and an add per entry, not a search.
    slots: Vec<Vec<u32>>,
    /// The arrays of threads 1.. (thread 0 adds into the result).
    private: Vec<Arrays>,
    /// Tangent values (CSC, free equations).
    pub values: Vec<f64>,
    /// Internal-minus-external force on every dof (reactions on prescribed dofs).
    pub r_full: Vec<f64>,
    /// Lifted right-hand side contribution Σ K_fd Δx_d on the free equations.
    pub lift: Vec<f64>,
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

/// `v` ← 0, in parallel (the tangent's values are tens of MB on 3D meshes).
fn zero(v: &mut [f64]) {
    v.par_chunks_mut(PASS_CHUNK).for_each(|c| c.fill(0.0));
}

/// `dst` += every array of `srcs` (the threads' partial sums), in one parallel pass that also
/// tells whether the result is finite everywhere.
fn gather<'a>(dst: &mut [f64], srcs: impl Iterator<Item = &'a Vec<f64>>) -> bool {
    let srcs: Vec<&Vec<f64>> = srcs.collect();
    dst.par_chunks_mut(PASS_CHUNK)
        .enumerate()
        .map(|(i, d)| {
            let span = i * PASS_CHUNK..i * PASS_CHUNK + d.len();
            for s in &srcs {
                for (a, b) in d.iter_mut().zip(&s[span.clone()]) {
                    *a += *b;
                }
            }
            d.iter().all(|v| v.is_finite())
        })
        .reduce(|| true, |a, b| a && b)
}

/// Marks a tangent entry that is not in the free system.
const NO_SLOT: u32 = u32::MAX;

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

/// The slot map of every block (see `Assembler::slots`).
fn build_slots(model: &Model, pattern: &Pattern) -> Vec<Vec<u32>> {
    let eq = &model.cons.eq;
    (0..model.blocks.len())
        .map(|bi| {
            let blk = &model.mesh.cells[model.blocks[bi].block];
            let nd = model.blocks[bi].layout.ndof();
            let mut slots = vec![NO_SLOT; blk.n_cells() * nd * nd];
            if nd == 0 {
                return slots;
            }
            slots.par_chunks_mut(nd * nd).enumerate().for_each_init(
                || (vec![0u32; nd], Vec::with_capacity(nd)),
                |(ld, rows), (c, cell)| {
                    local_dofs(model, bi, blk.cell(c), ld);
                    // the cell's free rows in increasing order: each column is walked
                    // once, front to back
                    rows.clear();
                    rows.extend((0..nd).filter_map(|a| {
                        let e = eq[ld[a] as usize];
                        (e != NONE).then_some((e as usize, a))
                    }));
                    rows.sort_unstable();
                    for b in 0..nd {
                        let col = eq[ld[b] as usize];
                        if col == NONE {
                            continue;
                        }
                        let mut q = pattern.col_ptr[col as usize];
                        for &(row, a) in rows.iter() {
                            while pattern.row_idx[q] != row {
                                q += 1;
                            }
                            cell[a * nd + b] = q as u32;
                        }
                    }
                },
            );
            slots
        })
        .collect()
}

impl Assembler {
    pub fn new(model: &Model) -> Assembler {
        let pattern = build_pattern(model);
        assert!(
            pattern.nnz() < NO_SLOT as usize,
            "more than 2³² − 1 tangent entries"
        );
        let slots = build_slots(model, &pattern);
        let nnz = pattern.nnz();
        let arrays = || Arrays {
            values: vec![0.0; nnz],
            r_full: vec![0.0; model.dofs.n_dofs],
            lift: vec![0.0; pattern.n],
        };
        let cells: usize = model.mesh.cells.iter().map(|b| b.n_cells()).sum();
        // no thread gets fewer than 256 cells
        let threads = rayon::current_num_threads()
            .min(MAX_ASSEMBLY_THREADS)
            .min(cells / 256)
            .max(1);
        let main = arrays();
        Assembler {
            private: (1..threads).map(|_| arrays()).collect(),
            values: main.values,
            r_full: main.r_full,
            lift: main.lift,
            pattern,
            slots,
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
        self.r_full.fill(0.0);
        if tangent {
            zero(&mut self.values);
        }
        self.lift.fill(0.0);
        // a failed call may have left partial sums in the threads' arrays
        for p in &mut self.private {
            if tangent {
                zero(&mut p.values);
            }
            p.r_full.fill(0.0);
            p.lift.fill(0.0);
        }
        let mut stats = AssemblyStats {
            min_J_solid: f64::INFINITY,
            min_J_medium: f64::INFINITY,
            energy: 0.0,
        };
        for (bi, info) in model.blocks.iter().enumerate() {
            let kind = model.mesh.cells[info.block].kind;
            let res = crate::with_cell!(kind, |N, D, E| {
                self.block::<N, D, E>(model, bi, x, tangent, dx_prescribed, act)
            });
            let region = || model.regions[info.region].0.clone();
            let (min_j, energy) = res.map_err(|(e, cell)| match e {
                KernelError::Inverted { J } => AssemblyError::Inverted {
                    region: region(),
                    J,
                },
                KernelError::BadGeometry => AssemblyError::BadMesh {
                    region: region(),
                    cell,
                },
                KernelError::Singular => AssemblyError::Singular { region: region() },
            })?;
            if info.mat.medium {
                stats.min_J_medium = stats.min_J_medium.min(min_j);
            } else {
                stats.min_J_solid = stats.min_J_solid.min(min_j);
            }
            stats.energy += energy;
        }
        let private = &self.private;
        let finite = (!tangent || gather(&mut self.values, private.iter().map(|p| &p.values)))
            & gather(&mut self.r_full, private.iter().map(|p| &p.r_full))
            & gather(&mut self.lift, private.iter().map(|p| &p.lift));
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

    /// One block: its cells cut into one contiguous chunk per thread, each chunk adding into
    /// its thread's arrays. Returns (min J, energy).
    fn block<const N: usize, const D: usize, E: RefElement<N, D>>(
        &mut self,
        model: &Model,
        bi: usize,
        x: &[f64],
        tangent: bool,
        dx_prescribed: Option<&[f64]>,
        act: Active,
    ) -> Result<(f64, f64), (KernelError, usize)> {
        let info = &model.blocks[bi];
        let blk = &model.mesh.cells[info.block];
        let lay = info.layout;
        let nd = lay.ndof();
        let eq = &model.cons.eq;
        let slots = &self.slots[bi];
        let mut targets = vec![(
            Shared(self.values.as_mut_ptr()),
            Shared(self.r_full.as_mut_ptr()),
            Shared(self.lift.as_mut_ptr()),
        )];
        for p in &mut self.private {
            targets.push((
                Shared(p.values.as_mut_ptr()),
                Shared(p.r_full.as_mut_ptr()),
                Shared(p.lift.as_mut_ptr()),
            ));
        }
        let n_cells = blk.n_cells();
        let chunk = n_cells.div_ceil(targets.len()).max(1);
        let work = |(values, r_full, lift): (Shared, Shared, Shared),
                    cells: std::ops::Range<usize>| {
            let mut r = vec![0.0; nd];
            let mut k = vec![0.0; if tangent { nd * nd } else { 0 }];
            let mut ld = vec![0u32; nd];
            let (mut mj, mut en) = (f64::INFINITY, 0.0);
            for c in cells {
                let nodes = blk.cell(c);
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
                // SAFETY: each chunk writes only into its own thread's arrays, at positions
                // the pattern and the dof map give (in bounds by construction).
                unsafe {
                    for a in 0..nd {
                        *r_full.at(ld[a] as usize) += r[a];
                    }
                    if !tangent {
                        continue;
                    }
                    let cell = &slots[c * nd * nd..(c + 1) * nd * nd];
                    for (&q, &v) in cell.iter().zip(k.iter()) {
                        if q != NO_SLOT {
                            *values.at(q as usize) += v;
                        }
                    }
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
                }
            }
            Ok((mj, en))
        };
        // chunks summed in their order, so the energy does not depend on work stealing
        let parts: Vec<(f64, f64)> = targets
            .into_par_iter()
            .enumerate()
            .map(|(i, tg)| work(tg, (i * chunk).min(n_cells)..((i + 1) * chunk).min(n_cells)))
            .collect::<Result<_, _>>()?;
        Ok(parts
            .into_iter()
            .fold((f64::INFINITY, 0.0), |a, b| (a.0.min(b.0), a.1 + b.1)))
    }
}
