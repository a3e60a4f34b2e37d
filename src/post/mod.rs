//! What an accepted state holds besides its unknowns, for the records: the heat stored and
//! the heat convected in, the work friction dissipated and each friction cell's slip, the
//! kinetic energy, the medium cells a solid's corner has passed into, and where a body has
//! come up against the medium's edge ([`edge`]). Read from the state, the model and the
//! assembler's committed history per point; nothing here assembles.
#![allow(non_snake_case)]

pub mod edge;

use crate::assembly::{Assembler, AssemblyError, MIN_PART_CELLS, References, facet_error};
use crate::kernel::Active;
use crate::kernel::friction::SlipFields;
use crate::mesh::centroid;
use crate::model::{Model, Term};
use rayon::prelude::*;

/// Heat stored in the capacity blocks at the state `x`: Σ ∫ ρc (θ − θ0) dV.
pub fn heat_stored(
    model: &Model,
    references: &References,
    x: &[f64],
) -> Result<f64, AssemblyError> {
    let mut e = 0.0;
    for cb in &model.capacity_blocks {
        let blk = &model.mesh.cells[cb.block];
        for c in 0..blk.n_cells() {
            let nodes = blk.cell(c);
            e += crate::with_cell!(blk.kind, |N, D, E| {
                let s = references.state::<N>(model, cb.block, c, x);
                crate::kernel::capacity::stored_heat::<N, D, E>(cb.rho_c, cb.theta_ref, &s)
            })
            .map_err(|_| AssemblyError::BadMesh {
                region: model.regions[cb.region].0.clone(),
                cell: c,
                at: centroid(&model.mesh.coords, nodes),
            })?;
        }
    }
    Ok(e)
}

/// How many medium cells the state `x` inverts at a corner node that also belongs to a
/// solid: there the solid has passed into the medium's cell between its quadrature points,
/// where the medium's stiffening does not act (a bilinear or higher cell's J varies over it
/// and can change sign at a corner while it stays positive at every point; a linear
/// triangle's or tetrahedron's is one number, so those are not looked at).
pub fn corners_through_medium(model: &Model, references: &References, x: &[f64]) -> usize {
    use crate::mesh::CellKind;
    let solid = model.nodes_of(crate::model::RegionKind::Solid);
    let mut cells = 0;
    for info in &model.blocks {
        let blk = &model.mesh.cells[info.block];
        let simplex = matches!(blk.kind, CellKind::Tri3 | CellKind::Tet4);
        if !info.layout.has_u || !info.mat.medium || simplex {
            continue;
        }
        let corners = blk.kind.corners();
        cells += crate::with_cell!(blk.kind, |N, D, E| {
            (0..blk.n_cells())
                .into_par_iter()
                .with_min_len(MIN_PART_CELLS)
                .filter(|&c| {
                    let nodes = blk.cell(c);
                    let s = references.state::<N>(model, info.block, c, x);
                    let deformed =
                        std::array::from_fn(|i| std::array::from_fn(|k| s.X[i][k] + s.u[i][k]));
                    let looked_at = |k: usize| solid[nodes[k]];
                    let worst = crate::element::worst_corner::<N, D, E>(
                        &s.X, &deformed, corners, looked_at,
                    );
                    worst.1 <= 0.0
                })
                .count()
        });
    }
    cells
}

/// The committed history of every friction cell this rank owns: (friction block, cell, its
/// history).
fn committed_friction<'a>(
    model: &'a Model,
    asm: &'a Assembler,
) -> impl Iterator<Item = (usize, usize, &'a [f64])> + 'a {
    (asm.slabs())
        .filter_map(|(t, slab)| match t {
            Term::Friction(f) => Some((f, slab)),
            _ => None,
        })
        .flat_map(move |(f, slab)| {
            let fb = &model.friction_blocks[f];
            let blk = &model.mesh.cells[fb.block];
            (0..blk.n_cells())
                .filter(move |&c| asm.owns_cell(fb.block, c))
                .map(move |c| {
                    let h = &slab.committed[c * slab.width..(c + 1) * slab.width];
                    (f, c, h)
                })
        })
}

/// The kinetic energy at the last accepted step, ½ Σ ∫ ρ |v|² dV (of every rank's cells).
pub fn kinetic_energy(model: &Model, asm: &Assembler) -> f64 {
    let mut e = [0.0];
    for (t, slab) in asm.slabs() {
        let Term::Inertia(i) = t else {
            continue;
        };
        let ib = &model.inertia_blocks[i];
        let blk = &model.mesh.cells[ib.block];
        for c in (0..blk.n_cells()).filter(|&c| asm.owns_cell(ib.block, c)) {
            let h = &slab.committed[c * slab.width..(c + 1) * slab.width];
            e[0] += crate::with_cell!(blk.kind, |N, D, E| {
                let X = asm.reference.coords::<N>(model, ib.block, c);
                crate::kernel::inertia::kinetic_energy::<N, D, E>(ib.rho, &X, h)
            })
            .unwrap_or(f64::NAN);
        }
    }
    asm.ranks.sum_into(&mut e);
    e[0]
}

/// The work dissipated by friction so far, per friction block (indexed like
/// `model.friction_blocks`), from the committed history: Σ ∫ w dV (of every rank's cells).
pub fn friction_work(model: &Model, asm: &Assembler) -> Vec<f64> {
    let mut work = vec![0.0; model.friction_blocks.len()];
    for (f, _, h) in committed_friction(model, asm) {
        work[f] += crate::kernel::friction::dissipated_work(h);
    }
    asm.ranks.sum_into(&mut work);
    work
}

/// A friction cell's slip state and its slip plane's unit normal, for output.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrictionCell {
    pub state: SlipFields,
    pub normal: [f64; 3],
}

/// The slip state of every cell this rank owns at the last accepted step, whose state is
/// `x`, in mesh block order (`None` for cells without friction, and for other ranks' cells).
pub fn friction_cells(model: &Model, asm: &Assembler, x: &[f64]) -> Vec<Option<FrictionCell>> {
    let mut first = Vec::with_capacity(model.mesh.cells.len());
    let mut n = 0;
    for b in &model.mesh.cells {
        first.push(n);
        n += b.n_cells();
    }
    let mut out = vec![None; n];
    for (f, c, h) in committed_friction(model, asm) {
        let fb = &model.friction_blocks[f];
        let normal = fb.normals.of(c);
        let state = crate::with_cell!(model.mesh.cells[fb.block].kind, |N, D, E| {
            let s = asm.reference.state::<N>(model, fb.block, c, x);
            crate::kernel::friction::slip_fields::<N, D, E>(&fb.mat, normal, &fb.layout, &s, h)
        })
        .unwrap_or(SlipFields {
            slip: [f64::NAN; 3],
            increment: [f64::NAN; 3],
            slipping: f64::NAN,
            stress: [[f64::NAN; 3]; 3],
        });
        out[first[fb.block] + c] = Some(FrictionCell {
            state,
            normal: [normal[0], normal[1], normal[2]],
        });
    }
    out
}

/// Heat supplied to the body through each convecting group at the state `x`, indexed like
/// `model.flux_groups`: −Σ of the convection residual over the group's free θ dofs (at a node
/// shared with a prescribed θ, the heat is in that group's reaction).
pub fn convection_heat(model: &Model, x: &[f64]) -> Result<Vec<f64>, AssemblyError> {
    let mut heat = vec![0.0; model.flux_groups.len()];
    for fb in &model.facet_blocks {
        let blk = &model.mesh.facets[fb.block];
        let lay = fb.layout;
        let mut r = vec![0.0; lay.ndof()];
        for c in 0..blk.n_cells() {
            let nodes = blk.cell(c);
            crate::with_element!(blk.kind, |N, D, E| {
                let s = crate::dofs::gather::<N>(&model.mesh.coords, &model.dofs, nodes, x);
                crate::kernel::facet::boundary_flux::<N, D, E>(
                    &fb.law,
                    &lay,
                    &s,
                    Active::ALL,
                    &mut r,
                    None,
                )
                .map_err(|e| facet_error(model, fb, e, c))?;
            });
            for (I, &n) in nodes.iter().enumerate() {
                let dof = model.dofs.theta[n] as usize;
                if model.cons.prescribed[dof].is_none() {
                    heat[fb.group] -= r[lay.theta(I)];
                }
            }
        }
    }
    Ok(heat)
}
