//! A medium layer whose cells are joined again as its faces slide past each other
//! (`reconnect` of a friction region): a 2D layer of quadrilaterals one cell across, between
//! a bottom row of nodes (the face slid on) and a top row (a solid's face, and the open
//! medium's free top beside it), the two rows of equal length. Each cell keeps its bottom
//! edge; its top edge is the pair of top-row nodes that stands above it now, the top row
//! shifted against the bottom one by whole cells as the solid slides. The open medium's free
//! top nodes move to stand above their new partners (those shifted past one end come round to
//! the other), their place across the layer, θ and p taken from the top row as it was.
//!
//! A Lagrangian layer cannot be slid further than a cell: the cell ahead of the solid's
//! leading corner has the bottom face's nodes for its bottom edge and the corner for a top
//! one, and inverts once the corner has passed that edge's far node (docs/THEORY.md, "A layer
//! joined again as it slides").

use super::SolveError;
use crate::dofs::NONE;
use crate::mesh::{CellKind, Mesh, centroid, point_text};
use crate::model::{Model, RegionKind, SlipNormals};
use nalgebra::Vector3;

/// A cell of the layer: (mesh block, cell), the bottom row's index of its first bottom node,
/// and per corner whether it is on the top row and its offset along the row from that index.
struct Cell {
    block: usize,
    cell: usize,
    first: usize,
    corners: [(bool, usize); 4],
}

/// The reconnected layer of a model.
pub struct Layer {
    bottom: Vec<usize>,
    top: Vec<usize>,
    /// Top nodes on a solid (they slide with it; never moved).
    on_solid: Vec<bool>,
    cells: Vec<Cell>,
    /// The top row's shift against the bottom row, in cells (positive along `along`).
    shift: i64,
    /// The direction along the layer, and its cells' mean width.
    along: Vector3<f64>,
    width: f64,
}

impl Layer {
    /// The model's reconnected layer, if a friction region asks for one; an error names the
    /// region whose layer is not one this can join again.
    pub fn find(model: &Model) -> Result<Option<Layer>, SolveError> {
        let blocks: Vec<_> = model
            .friction_blocks
            .iter()
            .filter(|f| f.reconnect)
            .collect();
        let Some(first) = blocks.first() else {
            return Ok(None);
        };
        let region = &model.regions[first.region].0;
        let refuse = |why: String| {
            Err(SolveError::Setup(format!(
                "region \"{region}\": `friction.reconnect` {why}"
            )))
        };
        if model.mesh.dim != 2 {
            return refuse("joins a 2D layer's cells again; this mesh is 3D".into());
        }
        let SlipNormals::Given(normal) = first.normals else {
            return refuse("needs the layer's `normal` given".into());
        };
        if blocks
            .iter()
            .any(|f| !matches!(f.normals, SlipNormals::Given(n) if n == normal))
        {
            return refuse("needs every reconnected region to have the same `normal`".into());
        }
        if let Some(f) = blocks
            .iter()
            .find(|f| model.mesh.cells[f.block].kind != CellKind::Quad4)
        {
            return refuse(format!(
                "joins a layer of linear quadrilaterals (Q1) again; its cells are {}",
                model.mesh.cells[f.block].kind.name()
            ));
        }
        let along = Vector3::new(-normal[1], normal[0], 0.0);
        let coords = &model.mesh.coords;
        let across = |n: usize| normal.dot(&Vector3::from(coords[n]));
        let at = |n: usize| along.dot(&Vector3::from(coords[n]));
        let mut nodes: Vec<usize> = (blocks.iter())
            .flat_map(|f| model.mesh.cells[f.block].conn.iter().copied())
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        let low = nodes
            .iter()
            .map(|&n| across(n))
            .fold(f64::INFINITY, f64::min);
        let high = nodes
            .iter()
            .map(|&n| across(n))
            .fold(f64::NEG_INFINITY, f64::max);
        let (mut bottom, mut top): (Vec<usize>, Vec<usize>) =
            (nodes.iter()).partition(|&&n| across(n) < low + 1e-6 * (high - low));
        bottom.sort_by(|a, b| at(*a).total_cmp(&at(*b)));
        top.sort_by(|a, b| at(*a).total_cmp(&at(*b)));
        if bottom.len() != top.len() || bottom.len() < 2 {
            return refuse(format!(
                "joins a layer one cell across between two rows of nodes of equal length; this \
                 one has {} nodes on its bottom face (along the normal) and {} above it",
                bottom.len(),
                top.len()
            ));
        }
        let index = |row: &[usize], n: usize| row.iter().position(|&m| m == n);
        let mut cells = Vec::new();
        for f in &blocks {
            let blk = &model.mesh.cells[f.block];
            for c in 0..blk.n_cells() {
                let rows: Vec<(bool, usize)> = (blk.cell(c).iter())
                    .map(|&n| match index(&bottom, n) {
                        Some(i) => (false, i),
                        None => (true, index(&top, n).expect("a node of the layer")),
                    })
                    .collect();
                let lowest = rows.iter().filter(|r| !r.0).map(|r| r.1).min();
                let spans = |on_top: bool| {
                    let mut at: Vec<usize> = (rows.iter().filter(|r| r.0 == on_top))
                        .map(|r| r.1)
                        .collect();
                    at.sort_unstable();
                    at.len() == 2 && at[1] == at[0] + 1
                };
                let (Some(first), true, true) = (lowest, spans(false), spans(true)) else {
                    return refuse(format!(
                        "joins a layer one cell across; its cell {c} (centre {}) does not \
                         span it from one row to the next",
                        centre(model, blk.cell(c))
                    ));
                };
                let mut corners = [(false, 0); 4];
                for (k, &(on_top, i)) in rows.iter().enumerate() {
                    match i.checked_sub(first).filter(|&o| o <= 1) {
                        Some(o) => corners[k] = (on_top, o),
                        None => {
                            return refuse(format!(
                                "joins cells that stand upright between the rows; cell {c} \
                                 (centre {}) leans over more than itself",
                                centre(model, blk.cell(c))
                            ));
                        }
                    }
                }
                cells.push(Cell {
                    block: f.block,
                    cell: c,
                    first,
                    corners,
                });
            }
        }
        let solid = model.nodes_of(RegionKind::Solid);
        let on_solid: Vec<bool> = top.iter().map(|&n| solid[n]).collect();
        if !on_solid.iter().any(|&s| s) {
            return refuse("joins a layer under a solid; no solid touches its top row".into());
        }
        let width = (at(bottom[bottom.len() - 1]) - at(bottom[0])) / (bottom.len() - 1) as f64;
        Ok(Some(Layer {
            bottom,
            top,
            on_solid,
            cells,
            shift: 0,
            along,
            width,
        }))
    }

    /// The layer in words, for `tmc check`.
    pub fn describe(&self) -> String {
        format!(
            "friction layer joined again as it slides: {} cells between rows of {} nodes, \
             {} of them on the solid",
            self.cells.len(),
            self.top.len(),
            self.on_solid.iter().filter(|&&s| s).count()
        )
    }

    /// Node `n`'s place at the state `x`.
    fn place(model: &Model, x: &[f64], n: usize) -> Vector3<f64> {
        let d = model.dofs.dim;
        Vector3::from_fn(|i, _| match i < d {
            true => model.mesh.coords[n][i] + x[model.dofs.u[n * d + i] as usize],
            false => 0.0,
        })
    }

    /// The shift the solid's slide at the state `x` calls for, if not the present one: the
    /// top row moves on by a cell once the solid's nodes stand, on average, a whole cell past
    /// their partners.
    pub fn due(&self, model: &Model, x: &[f64]) -> Option<i64> {
        let m = self.top.len();
        let lean: Vec<f64> = (0..m)
            .filter(|&j| self.on_solid[j])
            .map(|j| {
                let below = self.bottom[self.partner(j)];
                self.along
                    .dot(&(Self::place(model, x, self.top[j]) - Self::place(model, x, below)))
            })
            .collect();
        let mean = lean.iter().sum::<f64>() / lean.len() as f64;
        let by = (mean / self.width).trunc() as i64;
        // a solid's node never comes round: past the bottom face's end the layer stays as it is
        let within = (0..m).filter(|&j| self.on_solid[j]).all(|j| {
            let i = j as i64 + self.shift + by;
            (0..m as i64).contains(&i)
        });
        (by != 0 && within).then_some(self.shift + by)
    }

    /// The bottom row's index of top node `j`'s partner.
    fn partner(&self, j: usize) -> usize {
        (j as i64 + self.shift).rem_euclid(self.top.len() as i64) as usize
    }

    /// The top row's index of the node that stands above bottom node `i` (of whose
    /// [`Layer::partner`] is `i`).
    fn above(&self, i: usize) -> usize {
        (i as i64 - self.shift).rem_euclid(self.top.len() as i64) as usize
    }

    /// Join the layer's cells with shift `k`: the mesh's connectivity, the free top nodes'
    /// coordinates, and their unknowns in `x` (the state of `model`, whose mesh `mesh` was).
    pub fn join(&mut self, model: &Model, mesh: &mut Mesh, x: &mut [f64], k: i64) {
        let m = self.top.len();
        let (d, dofs) = (model.dofs.dim, &model.dofs);
        // what the top row carries, by its place along the layer
        let mut row: Vec<(f64, Vector3<f64>, Vec<f64>)> = (self.top.iter())
            .map(|&n| {
                let p = Self::place(model, x, n);
                let values = carried(model, n)
                    .map(|dof| if dof == NONE { 0.0 } else { x[dof as usize] })
                    .collect();
                (self.along.dot(&p), p, values)
            })
            .collect();
        row.sort_by(|a, b| a.0.total_cmp(&b.0));
        let normal = Vector3::new(self.along[1], -self.along[0], 0.0);
        let row_at = |s: f64| -> (f64, Vec<f64>) {
            let i = row.partition_point(|r| r.0 <= s);
            let (a, b) = match i {
                0 => (&row[0], &row[0]),
                i if i == row.len() => (&row[i - 1], &row[i - 1]),
                i => (&row[i - 1], &row[i]),
            };
            let t = if b.0 > a.0 {
                (s - a.0) / (b.0 - a.0)
            } else {
                0.0
            };
            let height = normal.dot(&(a.1 + (b.1 - a.1) * t));
            (
                height,
                a.2.iter().zip(&b.2).map(|(u, v)| u + t * (v - u)).collect(),
            )
        };
        self.shift = k;
        // the free top nodes above their partners, in the new row's order, kept between the
        // solid's nodes beside them
        let gap = 0.1 * self.width;
        let mut behind = f64::NEG_INFINITY;
        for b in 0..m {
            let j = self.above(b);
            let n = self.top[j];
            if self.on_solid[j] {
                behind = self.along.dot(&Self::place(model, x, n));
                continue;
            }
            let next = (j + 1) % m;
            let ahead = match b + 1 < m && self.on_solid[next] {
                true => self.along.dot(&Self::place(model, x, self.top[next])),
                false => f64::INFINITY,
            };
            let wanted = self.along.dot(&Self::place(model, x, self.bottom[b]));
            let s = match ahead - behind < 2.0 * gap {
                true => 0.5 * (behind + ahead),
                false => wanted.clamp(behind + gap, ahead - gap),
            };
            behind = s;
            let (height, values) = row_at(s);
            // the node's mesh place: at s along the layer, where it was across it
            let X = Vector3::from(mesh.coords[n]);
            let X_new = X + self.along * (s - self.along.dot(&X));
            let u = normal * (height - normal.dot(&X_new));
            for i in 0..3 {
                mesh.coords[n][i] = X_new[i];
            }
            for i in 0..d {
                x[dofs.u[n * d + i] as usize] = u[i];
            }
            for (dof, v) in carried(model, n).zip(values) {
                if dof != NONE {
                    x[dof as usize] = v;
                }
            }
        }
        for cell in &self.cells {
            let conn = &mut mesh.cells[cell.block].conn[cell.cell * 4..(cell.cell + 1) * 4];
            for (corner, &(on_top, offset)) in conn.iter_mut().zip(&cell.corners) {
                let i = cell.first + offset;
                *corner = match on_top {
                    true => self.top[self.above(i)],
                    false => self.bottom[i],
                };
            }
        }
    }
}

/// The unknowns node `n` carries besides its displacement (its p, then its θ), `NONE` where
/// it has none.
fn carried(model: &Model, n: usize) -> impl Iterator<Item = u32> + '_ {
    let dofs = &model.dofs;
    let theta = dofs.theta.get(n).copied().unwrap_or(NONE);
    (0..dofs.np)
        .map(move |c| dofs.p[n * dofs.np + c])
        .chain([theta])
}

/// Cell `nodes`'s centre, in words.
fn centre(model: &Model, nodes: &[usize]) -> String {
    point_text(&centroid(&model.mesh.coords, nodes), model.mesh.dim)
}
