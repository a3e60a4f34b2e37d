//! The contact as the solids feel it: the traction the medium puts on the faces a solid shares
//! with it, split into the contact pressure and the shear, at the nodes of those faces for the
//! step files; and the contact's normal, by which a group's reaction splits into F_n and F_t
//! for `history.csv`.
//!
//! A node's traction is the force the medium's cells around it put on it through their law
//! (−∫ P ∇N dV over each cell, a friction cell's slip plane's stress included where given:
//! their share of the residual, so the forces sum to what the medium carries), over the node's
//! share of the faces around it (each face's measure shared equally among its nodes). The
//! contact pressure is −f·n / A with n the nodes' current unit normal out of the solid
//! (positive where the medium presses on the solid), the shear (f − (f·n) n) / A.
#![allow(non_snake_case)]

use crate::assembly::{AssemblyError, References, cell_error};
use crate::case::RegionKind;
use crate::dofs::Field;
use crate::kernel::nodal_forces;
use crate::mesh::faces::{Side, shared_sides};
use crate::model::Model;
use crate::post::FrictionCell;

/// Where the solids meet the medium: their faces, the nodes on them, and the medium's cells
/// that bear on those nodes.
pub struct ContactFaces {
    /// Each face: `a` the solid's cell, `b` the medium's.
    sides: Vec<Side>,
    /// Each face's nodes (corners, and mid-side nodes of quadratic cells: those its two cells
    /// share), as indices into `nodes`.
    face_nodes: Vec<Vec<usize>>,
    /// The mesh nodes on those faces, increasing.
    nodes: Vec<usize>,
    /// Each mesh node's index in `nodes` (`usize::MAX` off the faces).
    slot: Vec<usize>,
    /// The medium's cells with a node in `nodes`, as (model block, cell).
    cells: Vec<(usize, usize)>,
    /// Each of `nodes`: its unit normal out of the solid in the undeformed mesh, and its body
    /// (the connected solid cells it belongs to, numbered from 0).
    normal0: Vec<[f64; 3]>,
    body: Vec<usize>,
    /// Each mesh node's body (`usize::MAX` off the solids).
    node_body: Vec<usize>,
    /// Each model block's first cell in the cell order of a step's fields.
    first_cell: Vec<usize>,
}

/// The contact at one state, per node of [`ContactFaces`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Contact {
    /// −f·n / A: positive where the medium presses on the solid.
    pub pressure: Vec<f64>,
    /// (f − (f·n) n) / A.
    pub shear: Vec<[f64; 3]>,
    /// The node's share A of the faces around it, now.
    pub area: Vec<f64>,
}

impl ContactFaces {
    /// The faces of a model with mechanics where a solid meets the medium (`None` without any).
    pub fn of(model: &Model) -> Option<ContactFaces> {
        if !model.dofs.has(Field::U) {
            return None;
        }
        let mesh = &model.mesh;
        let of_kind = |kind: RegionKind| -> Vec<usize> {
            (model.blocks.iter())
                .filter(|b| model.regions[b.region].1 == kind)
                .map(|b| b.block)
                .collect()
        };
        let solid = of_kind(RegionKind::Solid);
        let sides = shared_sides(mesh, &solid, &of_kind(RegionKind::Medium));
        if sides.is_empty() {
            return None;
        }
        let on_faces: Vec<Vec<usize>> = (sides.iter())
            .map(|s| {
                let medium = mesh.cells[s.b.0].cell(s.b.1);
                let solid = mesh.cells[s.a.0].cell(s.a.1);
                (solid.iter().copied())
                    .filter(|n| medium.contains(n))
                    .collect()
            })
            .collect();
        let mut slot = vec![usize::MAX; mesh.coords.len()];
        on_faces.iter().flatten().for_each(|&n| slot[n] = 0);
        let nodes: Vec<usize> = (0..slot.len()).filter(|&n| slot[n] == 0).collect();
        for (i, &n) in nodes.iter().enumerate() {
            slot[n] = i;
        }
        let face_nodes: Vec<Vec<usize>> = (on_faces.iter())
            .map(|f| f.iter().map(|&n| slot[n]).collect())
            .collect();
        let mut cells = Vec::new();
        let mut first_cell = Vec::with_capacity(model.blocks.len());
        let mut count = 0;
        for (bi, info) in model.blocks.iter().enumerate() {
            first_cell.push(count);
            let blk = &mesh.cells[info.block];
            count += blk.n_cells();
            if model.regions[info.region].1 != RegionKind::Medium || !info.layout.has_u {
                continue;
            }
            for c in 0..blk.n_cells() {
                if blk.cell(c).iter().any(|&n| slot[n] != usize::MAX) {
                    cells.push((bi, c));
                }
            }
        }
        let node_body = mesh.components(|b| solid.contains(&b));
        let faces = ContactFaces {
            sides,
            face_nodes,
            body: nodes.iter().map(|&n| node_body[n]).collect(),
            nodes,
            slot,
            cells,
            normal0: Vec::new(),
            node_body,
            first_cell,
        };
        let (normal0, _) = faces.normals_and_areas(model, |n| mesh.coords[n]);
        Some(ContactFaces { normal0, ..faces })
    }

    /// Each node's unit normal out of the solid (the mean of its faces', weighted by their
    /// measures) and its share of their measures, with the nodes at `x(n)`.
    fn normals_and_areas(
        &self,
        model: &Model,
        x: impl Fn(usize) -> [f64; 3] + Copy,
    ) -> (Vec<[f64; 3]>, Vec<f64>) {
        let mut normal = vec![[0.0; 3]; self.nodes.len()];
        let mut area = vec![0.0; self.nodes.len()];
        for (s, on) in self.sides.iter().zip(&self.face_nodes) {
            let (n, measure) = s.normal_and_measure(&model.mesh, x);
            for &i in on {
                area[i] += measure / on.len() as f64;
                for k in 0..3 {
                    normal[i][k] += measure * n[k];
                }
            }
        }
        for n in &mut normal {
            let length = n.iter().map(|v| v * v).sum::<f64>().sqrt();
            if length > 0.0 {
                *n = n.map(|v| v / length);
            }
        }
        (normal, area)
    }

    /// The contact at the state `x`, the cells measured from `references`; `plane`: each
    /// cell's slip state (in a step's cell order), whose slip plane's stress the medium's
    /// carries too.
    pub fn at(
        &self,
        model: &Model,
        references: &References,
        x: &[f64],
        plane: Option<&[Option<FrictionCell>]>,
    ) -> Result<Contact, AssemblyError> {
        let forces = self.forces(model, references, x, plane, None)?;
        Ok(self.from_forces(model, x, &forces))
    }

    /// The force the medium's cells put on each node of the faces at the state `x` (as
    /// [`ContactFaces::at`]), of the cells `mine` marks (in a step's cell order; all without
    /// it): on several ranks each sums its own cells', and the ranks' sums are the whole.
    pub fn forces(
        &self,
        model: &Model,
        references: &References,
        x: &[f64],
        plane: Option<&[Option<FrictionCell>]>,
        mine: Option<&[bool]>,
    ) -> Result<Vec<[f64; 3]>, AssemblyError> {
        let mut force = vec![[0.0; 3]; self.nodes.len()];
        for &(bi, c) in &self.cells {
            let at = self.first_cell[bi] + c;
            if mine.is_some_and(|m| !m[at]) {
                continue;
            }
            let info = &model.blocks[bi];
            let blk = &model.mesh.cells[info.block];
            let extra = plane.and_then(|p| p[at].as_ref()).map(|f| &f.state.stress);
            let f = crate::with_cell!(blk.kind, |N, D, E| nodal_forces::<N, D, E>(
                &info.mat,
                &info.layout,
                &references.state::<N>(model, info.block, c, x),
                extra,
            )
            .map(|f| f.to_vec()))
            .map_err(|e| cell_error(model, bi, e, c))?;
            for (&n, fa) in blk.cell(c).iter().zip(&f) {
                if let Some(i) = Some(self.slot[n]).filter(|&i| i != usize::MAX) {
                    for k in 0..3 {
                        force[i][k] += fa[k];
                    }
                }
            }
        }
        Ok(force)
    }

    /// The contact at the state `x` whose medium puts `force` on the faces' nodes.
    pub fn from_forces(&self, model: &Model, x: &[f64], force: &[[f64; 3]]) -> Contact {
        let (normal, area) = self.normals_and_areas(model, |n| model.placed(n, x));
        let mut out = Contact {
            area,
            ..Default::default()
        };
        for ((f, n), &a) in force.iter().zip(&normal).zip(&out.area) {
            let fn_: f64 = (0..3).map(|k| f[k] * n[k]).sum();
            let per = if a > 0.0 { 1.0 / a } else { 0.0 };
            out.pressure.push(-fn_ * per);
            out.shear
                .push(std::array::from_fn(|k| (f[k] - fn_ * n[k]) * per));
        }
        out
    }

    /// How many nodes the faces have (the length of [`ContactFaces::forces`]).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The contact pressure and shear of every mesh node (zero off the faces).
    pub fn at_nodes(&self, n_nodes: usize, c: &Contact) -> (Vec<f64>, Vec<[f64; 3]>) {
        let mut pressure = vec![0.0; n_nodes];
        let mut shear = vec![[0.0; 3]; n_nodes];
        for (i, &n) in self.nodes.iter().enumerate() {
            pressure[n] = c.pressure[i];
            shear[n] = c.shear[i];
        }
        (pressure, shear)
    }

    /// The body the node `n` belongs to, if it is on a solid.
    pub fn body_of(&self, n: usize) -> Option<usize> {
        self.node_body.get(n).copied().filter(|&b| b != usize::MAX)
    }

    /// The contact's normal as body `body` meets it: the mean, weighted by each node's
    /// pressure times area now, of the undeformed normals of the nodes the other bodies press
    /// with (out of them, so towards `body`); where no other body presses, the body's own
    /// turned round. A cylinder on a plate thus splits its force along the plate's normal,
    /// whatever its own faces' slant and however the plate's face is dented. `None` where
    /// nothing presses.
    pub fn contact_normal(&self, body: usize, c: &Contact) -> Option<[f64; 3]> {
        let mean = |others: bool, sign: f64| -> Option<[f64; 3]> {
            let mut n = [0.0; 3];
            for i in 0..self.nodes.len() {
                let p = c.pressure[i] * c.area[i];
                if (self.body[i] != body) == others && p > 0.0 {
                    for k in 0..3 {
                        n[k] += sign * p * self.normal0[i][k];
                    }
                }
            }
            let length = n.iter().map(|v| v * v).sum::<f64>().sqrt();
            (length > 0.0).then(|| n.map(|v| v / length))
        };
        mean(true, 1.0).or_else(|| mean(false, -1.0))
    }
}
