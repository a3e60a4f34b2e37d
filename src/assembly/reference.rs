//! The reference configuration of a medium layer whose cells are joined again as its faces
//! slide past each other (`reconnect` of a friction region): one copy of the reference node
//! coordinates per cell. The medium is fictitious, so its reference is free; what it must
//! remember is how far the layer has closed (across the slip plane) and the elastic shear of
//! the points that stick. When the layer is joined again, every cell first takes the slide
//! into its reference ([`References::absorb`]: each node at its current place along the
//! plane, its reference place across it, and the slip shifted so that every point's elastic
//! shear stays what it was), and the re-joined cells then start from the state as it is
//! ([`References::reset`]). Cells need not agree on a shared node's reference, as with a
//! plastic deformation per cell. A medium made again as the bodies move (`remake`) measures
//! its cells from their own references too, and its closed layers take their slide into them
//! at every accepted step ([`References::absorb`]), the way a layer does before it is
//! joined again.
#![allow(non_snake_case)]

use super::history::Slab;
use crate::dofs::{CellState, gather, rebase};
use crate::element::RefElement;
use crate::kernel::friction::{HISTORY_PER_POINT, plane_shear, shift_slip, volume_ratio};
use crate::material::friction::along_plane;
use crate::mesh::{Block, CellKind, tet_volume};
use crate::model::{FrictionBlock, Model};
use nalgebra::Vector3;

/// The reference node coordinates per cell (N per cell, in cell order) of each mesh block
/// whose medium is reconnected; `None` for a block measured from the mesh.
#[derive(Clone, Debug, Default)]
pub struct References {
    blocks: Vec<Option<Vec<[f64; 3]>>>,
}

impl References {
    /// The model's own references per cell (a medium made again), and the friction blocks
    /// with `reconnect`, starting from the mesh's coordinates.
    pub fn new(model: &Model) -> References {
        let mut blocks = model.cell_reference.clone();
        for fb in model.friction_blocks.iter().filter(|fb| fb.reconnect) {
            let blk = &model.mesh.cells[fb.block];
            blocks[fb.block] = Some(blk.conn.iter().map(|&n| model.mesh.coords[n]).collect());
        }
        References { blocks }
    }

    /// Mesh block `block`'s reference node coordinates per cell, if it has its own.
    pub fn of(&self, block: usize) -> Option<&[[f64; 3]]> {
        self.blocks.get(block).and_then(|b| b.as_deref())
    }

    /// Cell `c` of mesh block `block` at the state `x`, measured from its reference.
    pub fn state<const N: usize>(
        &self,
        model: &Model,
        block: usize,
        c: usize,
        x: &[f64],
    ) -> CellState<N> {
        cell_state(model, model.mesh.cells[block].cell(c), self.of(block), c, x)
    }

    /// Cell `c` of mesh block `block`'s reference node coordinates.
    pub fn coords<const N: usize>(&self, model: &Model, block: usize, c: usize) -> [[f64; 3]; N] {
        match self.of(block) {
            Some(r) => std::array::from_fn(|I| r[c * N + I]),
            None => {
                let nodes = model.mesh.cells[block].cell(c);
                std::array::from_fn(|I| model.mesh.coords[nodes[I]])
            }
        }
    }

    /// Friction block `fb`'s cells whose volume ratio J is below `closed` (every cell for
    /// `f64::INFINITY`; a closed layer for [`crate::model::remake::CLOSED`]) take the slide at
    /// the accepted state `x` into their reference (each node at its place along the plane,
    /// X' = X + P u), and the slip in its history `slab` (committed and trial) is shifted by
    /// what that takes off the plane's shear, so that every point's elastic shear stays what
    /// it was.
    pub fn absorb(
        &mut self,
        model: &Model,
        fb: &FrictionBlock,
        slab: &mut Slab,
        x: &[f64],
        closed: f64,
    ) {
        let Some(reference) = self.blocks[fb.block].as_mut() else {
            return;
        };
        let blk = &model.mesh.cells[fb.block];
        crate::with_cell!(blk.kind, |N, D, E| absorb_block::<N, D, E>(
            model, fb, blk, reference, slab, x, closed
        ));
    }

    /// A 3D medium made again, without friction: each of its open cells beside a body (a node
    /// on a solid, J at least `closed` at the accepted state `x`) takes its shear and rotation
    /// into its reference, which becomes the cell as it stands shrunk about its centre by
    /// J^(1/3). Its J is kept (the watch measures a cell's squeeze by it); the rest is let go.
    /// A body's face along the slide shears these cells by the slide since the last remake,
    /// and their rotation penalty holds the body back: with fewer remakes the square pad's
    /// median F_t/F_n was 0.0023 against 0.0011
    /// (docs/notes/2026-12-07-a-3d-pass-that-squeezes-and-the-cells-beside-a-body.md).
    pub fn release_beside(&mut self, model: &Model, x: &[f64], closed: f64) {
        let on_solid = model.on_solids();
        for (b, blk) in model.mesh.cells.iter().enumerate() {
            let Some(reference) = self.blocks[b].as_mut() else {
                continue;
            };
            if blk.kind != CellKind::Tet4 {
                continue;
            }
            for (c, r) in reference.chunks_exact_mut(4).enumerate() {
                let nodes = blk.cell(c);
                if !nodes.iter().any(|&n| on_solid[n]) {
                    continue;
                }
                let p: [[f64; 3]; 4] = std::array::from_fn(|i| model.placed(nodes[i], x));
                let J = tet_volume(p) / tet_volume(std::array::from_fn(|i| r[i]));
                if !(J >= closed) {
                    continue;
                }
                let p = p.map(Vector3::from);
                let (centre, k) = (p.iter().sum::<Vector3<f64>>() / 4.0, J.cbrt());
                for (q, p) in r.iter_mut().zip(&p) {
                    *q = (centre + (p - centre) / k).into();
                }
            }
        }
    }

    /// Every block's reference node coordinates per cell, where it has its own.
    pub fn blocks(&self) -> &[Option<Vec<[f64; 3]>>] {
        &self.blocks
    }

    /// Take `blocks` (as [`References::blocks`] gave them) as the blocks' own references.
    pub fn set_blocks(&mut self, blocks: Vec<Option<Vec<[f64; 3]>>>) {
        self.blocks = blocks;
    }

    /// Every reconnected cell's reference at the state `x` along its plane (X' = X + P u from
    /// the mesh's coordinates), at its mesh place across it; its history as it is (after
    /// [`References::absorb`], the slip is the elastic shear's negative, and a cell whose
    /// reference is the state has no shear).
    pub fn reset(&mut self, model: &Model, x: &[f64]) {
        for fb in model.friction_blocks.iter().filter(|fb| fb.reconnect) {
            let blk = &model.mesh.cells[fb.block];
            let reference = self.blocks[fb.block].as_mut().expect("a reconnected block");
            crate::with_cell!(blk.kind, |N, _D, _E| reset_block::<N>(
                model, fb, blk, reference, x
            ));
        }
    }
}

/// The state of the cell `c` with nodes `nodes` at `x`, measured from `reference` (its
/// block's reference coordinates per cell) where given, else from the mesh.
pub(super) fn cell_state<const N: usize>(
    model: &Model,
    nodes: &[usize],
    reference: Option<&[[f64; 3]]>,
    c: usize,
    x: &[f64],
) -> CellState<N> {
    let mut s = gather::<N>(&model.mesh.coords, &model.dofs, nodes, x);
    if let Some(r) = reference {
        rebase(&mut s, &r[c * N..(c + 1) * N]);
    }
    s
}

/// Friction cell `c`'s nodes in state `s`, each at its place along the cell's slip plane and
/// at its reference place across it: X + P u.
fn slid_along<const N: usize>(fb: &FrictionBlock, c: usize, s: &CellState<N>) -> [[f64; 3]; N] {
    let along = along_plane(fb.normals.of(c));
    std::array::from_fn(|I| {
        let shift = along * Vector3::from(s.u[I]);
        std::array::from_fn(|i| s.X[I][i] + shift[i])
    })
}

fn reset_block<const N: usize>(
    model: &Model,
    fb: &FrictionBlock,
    blk: &Block,
    reference: &mut [[f64; 3]],
    x: &[f64],
) {
    for c in 0..blk.n_cells() {
        let s = cell_state::<N>(model, blk.cell(c), None, c, x);
        reference[c * N..(c + 1) * N].copy_from_slice(&slid_along(fb, c, &s));
    }
}

fn absorb_block<const N: usize, const D: usize, E: RefElement<N, D>>(
    model: &Model,
    fb: &FrictionBlock,
    blk: &Block,
    reference: &mut [[f64; 3]],
    slab: &mut Slab,
    x: &[f64],
    closed: f64,
) {
    let points = E::quadrature().len();
    let w = HISTORY_PER_POINT * points;
    let (mut before, mut after) = (vec![0.0; 3 * points], vec![0.0; 3 * points]);
    for c in 0..blk.n_cells() {
        let mut s = cell_state::<N>(model, blk.cell(c), Some(reference), c, x);
        if !volume_ratio::<N, D, E>(&fb.layout, &s).is_ok_and(|J| J < closed) {
            continue;
        }
        let moved = slid_along(fb, c, &s);
        let normal = fb.normals.of(c);
        // an accepted state inverts no cell, and the move keeps each node's place across the
        // plane, so neither measure fails; were one to, the cell would keep its reference
        if plane_shear::<N, D, E>(normal, &fb.layout, &s, &mut before).is_err() {
            continue;
        }
        rebase(&mut s, &moved);
        if plane_shear::<N, D, E>(normal, &fb.layout, &s, &mut after).is_err() {
            continue;
        }
        for (a, b) in after.iter_mut().zip(&before) {
            *a -= b;
        }
        shift_slip(&mut slab.committed[c * w..(c + 1) * w], &after);
        shift_slip(&mut slab.trial[c * w..(c + 1) * w], &after);
        reference[c * N..(c + 1) * N].copy_from_slice(&moved);
    }
}

/// The displacement at each quadrature point of an inertia block's history (the first D of
/// each point's values, committed and trial) taken from the state `x`, each cell measured from
/// its reference in `references`: after the layer is joined again, a point's neighbours are
/// other nodes, and what they carry is where the point is, not a motion.
pub fn inertia_at_state<const N: usize, const D: usize, E: RefElement<N, D>>(
    model: &Model,
    references: &References,
    block: usize,
    x: &[f64],
    slab: &mut Slab,
) {
    let points = E::quadrature();
    let per = slab.width / points.len();
    for c in 0..model.mesh.cells[block].n_cells() {
        let s = references.state::<N>(model, block, c, x);
        for (q, (xi, _)) in points.iter().enumerate() {
            let Nv = E::shape(xi);
            for i in 0..D {
                let u: f64 = (0..N).map(|I| Nv[I] * s.u[I][i]).sum();
                let at = c * slab.width + q * per + i;
                slab.committed[at] = u;
                slab.trial[at] = u;
            }
        }
    }
}

/// The temperature at each quadrature point of a capacity block's history (committed and
/// trial) taken from the state `x`: after the layer is joined again, a point's neighbours are
/// other nodes, and what they carry is the temperature there, not a change of it.
pub fn theta_at_state<const N: usize, const D: usize, E: RefElement<N, D>>(
    model: &Model,
    references: &References,
    block: usize,
    x: &[f64],
    slab: &mut Slab,
) {
    let w = slab.width;
    for c in 0..model.mesh.cells[block].n_cells() {
        let s = references.state::<N>(model, block, c, x);
        crate::kernel::capacity::theta_at_points::<N, D, E>(
            &s,
            &mut slab.committed[c * w..(c + 1) * w],
        );
        slab.trial[c * w..(c + 1) * w].copy_from_slice(&slab.committed[c * w..(c + 1) * w]);
    }
}
