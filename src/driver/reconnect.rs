//! A medium layer whose cells are joined again as its faces slide past each other
//! (`reconnect` of a friction region): a 2D layer one cell across, between a bottom row of
//! nodes (the face slid on) and a top row (a solid's face, and the open medium's free top
//! beside it), the two rows of equal length. The top row is shifted against the bottom one
//! by whole cells as the solid slides: the open medium's free top nodes move to stand above
//! their new partners (those shifted past one end come round to the other), their place
//! across the layer, θ and p taken from the top row as it was. A quadrilateral keeps its
//! bottom edge and takes for its top edge the pair of top-row nodes that stands above it
//! now. A triangle keeps its edge on one row and takes for its apex a node of the other, the
//! two rows zipped together where they stand node by node, so a face need not slide as one.
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

/// A quadrilateral of the layer: (mesh block, cell), the bottom row's index of its first
/// bottom node, and per corner whether it is on the top row and its offset along the row from
/// that index.
struct Cell {
    block: usize,
    cell: usize,
    first: usize,
    corners: [(bool, usize); 4],
}

/// A triangle of the layer: (mesh block, cell) and its edge on a row, which it keeps.
struct Triangle {
    block: usize,
    cell: usize,
    edge: Edge,
}

/// A triangle's edge: on the bottom row (the index of its first node, the other next along),
/// or on the top row (its two nodes, as they stand along it now).
#[derive(Clone, Copy, PartialEq)]
enum Edge {
    Bottom(usize),
    Top(usize, usize),
}

/// The reconnected layer of a model.
pub struct Layer {
    bottom: Vec<usize>,
    top: Vec<usize>,
    /// Top nodes on a solid (they slide with it; never moved).
    on_solid: Vec<bool>,
    cells: Vec<Cell>,
    triangles: Vec<Triangle>,
    /// Whether the mesh's triangles turn counter-clockwise (in the plane's x, y).
    counter_clockwise: bool,
    /// The top row's shift against the bottom row, in cells (positive along `along`).
    shift: i64,
    /// Each top node's place along the layer past its partner's when last joined.
    leaned: Vec<f64>,
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
        if let Some(f) = blocks.iter().find(|f| {
            !matches!(
                model.mesh.cells[f.block].kind,
                CellKind::Quad4 | CellKind::Tri3
            )
        }) {
            return refuse(format!(
                "joins a layer of linear quadrilaterals (Q1) or triangles (T1) again; its \
                 cells are {}",
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
        let (mut triangles, mut counter_clockwise) = (Vec::new(), true);
        for f in &blocks {
            let blk = &model.mesh.cells[f.block];
            for c in (0..blk.n_cells()).filter(|_| blk.kind == CellKind::Tri3) {
                let nodes = blk.cell(c);
                let Some(edge) = triangle_edge(&bottom, &top, nodes) else {
                    return refuse(format!(
                        "joins a layer one cell across; its triangle {c} (centre {}) does \
                         not have an edge on one row and its third corner on the other",
                        centre(model, nodes)
                    ));
                };
                counter_clockwise = signed_area(coords, nodes) > 0.0;
                triangles.push(Triangle {
                    block: f.block,
                    cell: c,
                    edge,
                });
            }
            for c in (0..blk.n_cells()).filter(|_| blk.kind == CellKind::Quad4) {
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
        let leaned = vec![0.0; bottom.len()];
        Ok(Some(Layer {
            bottom,
            top,
            on_solid,
            cells,
            triangles,
            counter_clockwise,
            shift: 0,
            leaned,
            along,
            width,
        }))
    }

    /// The layer in words, for `tmc check`.
    pub fn describe(&self) -> String {
        let how = match self.triangles.is_empty() {
            true => "",
            false => " (triangles, zipped node by node)",
        };
        format!(
            "friction layer joined again as it slides: {} cells between rows of {} nodes, \
             {} of them on the solid{how}",
            self.cells.len() + self.triangles.len(),
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

    /// The shift the solid's slide at the state `x` calls for, when the layer is to be joined
    /// again: the top row moves on by a cell once the solid's nodes stand, on average, a whole
    /// cell past their partners; triangles are zipped again (at the same shift, if the mean
    /// has not moved a cell) once any of the solid's nodes has slid a cell since the last
    /// join. Never while a solid's node stands past the bottom face's end.
    pub fn due(&self, model: &Model, x: &[f64]) -> Option<i64> {
        let m = self.top.len();
        let solid: Vec<usize> = (0..m).filter(|&j| self.on_solid[j]).collect();
        let lean: Vec<f64> = solid.iter().map(|&j| self.lean(model, x, j)).collect();
        let mean = lean.iter().sum::<f64>() / lean.len() as f64;
        // triangles are zipped node by node: joined again once any of the solid's nodes has
        // slid a cell since they were last joined
        let slid = !self.triangles.is_empty()
            && (solid.iter().zip(&lean)).any(|(&j, l)| (l - self.leaned[j]).abs() >= self.width);
        let by = (mean / self.width).trunc() as i64;
        // a solid's node never comes round, nor is a triangle zipped to a solid's node past the
        // bottom face's end: there the layer stays as it is
        let within = (solid.iter()).all(|&j| {
            let i = j as i64 + self.shift + by;
            (0..m as i64).contains(&i)
        });
        let ends =
            [self.bottom[0], self.bottom[m - 1]].map(|n| self.along.dot(&Self::place(model, x, n)));
        let over = (solid.iter()).any(|&j| {
            let s = self.along.dot(&Self::place(model, x, self.top[j]));
            s < ends[0] || s > ends[1]
        });
        ((by != 0 || slid) && within && !over).then_some(self.shift + by)
    }

    /// Top node `j`'s place along the layer past its partner's at the state `x`.
    fn lean(&self, model: &Model, x: &[f64], j: usize) -> f64 {
        let below = self.bottom[self.partner(j)];
        self.along
            .dot(&(Self::place(model, x, self.top[j]) - Self::place(model, x, below)))
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
        // each top node's place along the layer once joined
        let mut along_top = vec![0.0; m];
        for b in 0..m {
            let j = self.above(b);
            let n = self.top[j];
            if self.on_solid[j] {
                behind = self.along.dot(&Self::place(model, x, n));
                along_top[j] = behind;
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
            along_top[j] = s;
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
        for j in (0..m).filter(|&j| self.on_solid[j]) {
            self.leaned[j] = self.lean(model, x, j);
        }
        if !self.triangles.is_empty() {
            let along_bottom: Vec<f64> = (self.bottom.iter())
                .map(|&n| self.along.dot(&Self::place(model, x, n)))
                .collect();
            self.zip(mesh, &along_bottom, &along_top);
        }
    }

    /// Join the triangles node by node: the rows, the bottom one at `along_bottom` and the
    /// top one at `along_top` (places along the layer, by row index), are zipped together in
    /// the order their nodes stand along the layer. Each triangle keeps its edge on a row (a
    /// top edge that is no longer one, next to a free node that came round, takes one that is
    /// new) and takes for its apex the node of the other row that the zip puts beside it.
    fn zip(&mut self, mesh: &mut Mesh, along_bottom: &[f64], along_top: &[f64]) {
        let m = self.top.len();
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by(|&a, &b| along_top[a].total_cmp(&along_top[b]));
        let top: Vec<usize> = order.iter().map(|&j| self.top[j]).collect();
        // the apex of each bottom edge and of each top edge (by its first node's place in
        // `top`): step along whichever row's next node stands first
        let (mut bottom_apex, mut top_apex) = (vec![0; m - 1], vec![0; m - 1]);
        let (mut i, mut j) = (0, 0);
        while i + 1 < m || j + 1 < m {
            let bottom_next = match (i + 1 < m, j + 1 < m) {
                (true, true) => along_bottom[i + 1] <= along_top[order[j + 1]],
                (more, _) => more,
            };
            if bottom_next {
                bottom_apex[i] = top[j];
                i += 1;
            } else {
                top_apex[j] = self.bottom[i];
                j += 1;
            }
        }
        // top edges kept where their nodes still stand side by side; the others take the
        // new ones left, in order
        let edges: Vec<(usize, usize)> = top.windows(2).map(|w| (w[0], w[1])).collect();
        let kept: Vec<Option<usize>> = (self.triangles.iter())
            .map(|t| match t.edge {
                Edge::Top(a, b) => edges.iter().position(|&e| e == (a, b) || e == (b, a)),
                Edge::Bottom(_) => None,
            })
            .collect();
        let free: Vec<usize> = (0..edges.len())
            .filter(|k| !kept.contains(&Some(*k)))
            .collect();
        let mut left = free.into_iter();
        // (along, across) turns the other way from (x, y): an edge taken forward along the
        // layer with its apex above (a bottom edge's) turns clockwise in (x, y), with its
        // apex below (a top edge's) counter-clockwise
        let ccw = self.counter_clockwise;
        for (t, kept) in self.triangles.iter_mut().zip(kept) {
            let (a, b, apex, forward) = match t.edge {
                Edge::Bottom(i) => (self.bottom[i], self.bottom[i + 1], bottom_apex[i], !ccw),
                Edge::Top(..) => {
                    let k = kept
                        .or_else(|| left.next())
                        .expect("as many top edges as before");
                    t.edge = Edge::Top(edges[k].0, edges[k].1);
                    (edges[k].0, edges[k].1, top_apex[k], ccw)
                }
            };
            let conn = &mut mesh.cells[t.block].conn[t.cell * 3..(t.cell + 1) * 3];
            conn.copy_from_slice(&match forward {
                true => [a, b, apex],
                false => [b, a, apex],
            });
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

/// The edge on a row of the triangle `nodes` whose third corner is on the other row, if it
/// has one: two nodes next to each other on one row (`bottom` or `top`, in order along the
/// layer) and one on the other.
fn triangle_edge(bottom: &[usize], top: &[usize], nodes: &[usize]) -> Option<Edge> {
    let on = |row: &[usize]| -> Vec<usize> {
        let mut at: Vec<usize> = (nodes.iter())
            .filter_map(|&n| row.iter().position(|&m| m == n))
            .collect();
        at.sort_unstable();
        at
    };
    let (b, t) = (on(bottom), on(top));
    match (b.as_slice(), t.as_slice()) {
        ([i, k], [_]) if *k == i + 1 => Some(Edge::Bottom(*i)),
        ([_], [j, k]) if *k == j + 1 => Some(Edge::Top(top[*j], top[*k])),
        _ => None,
    }
}

/// Twice the signed area of the triangle `nodes` in the plane's x, y.
fn signed_area(coords: &[[f64; 3]], nodes: &[usize]) -> f64 {
    let [a, b, c] = [coords[nodes[0]], coords[nodes[1]], coords[nodes[2]]];
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Block;

    /// A strip of triangles between a bottom row at y = 0 and a top row at y = 1, both of m
    /// nodes along x = −along (the slip plane's normal +y: along it runs towards −x), each
    /// cell between two columns split as gmsh splits a transfinite quadrilateral.
    fn strip(m: usize) -> (Layer, Mesh) {
        let mut coords = Vec::new();
        for y in [0.0, 1.0] {
            coords.extend((0..m).map(|i| [-(i as f64), y, 0.0]));
        }
        let (bottom, top): (Vec<usize>, Vec<usize>) = ((0..m).collect(), (m..2 * m).collect());
        let mut conn = Vec::new();
        for i in 0..m - 1 {
            conn.extend([bottom[i + 1], bottom[i], top[i + 1]]);
            conn.extend([top[i + 1], bottom[i], top[i]]);
        }
        let cells = vec![Block {
            kind: CellKind::Tri3,
            groups: vec![],
            conn,
        }];
        let mesh = Mesh::of_cells(2, coords, cells);
        let blk = &mesh.cells[0];
        let triangles = (0..blk.n_cells())
            .map(|c| Triangle {
                block: 0,
                cell: c,
                edge: triangle_edge(&bottom, &top, blk.cell(c)).expect("a row edge"),
            })
            .collect();
        let counter_clockwise = signed_area(&mesh.coords, blk.cell(0)) > 0.0;
        let layer = Layer {
            bottom,
            top,
            on_solid: vec![true; m],
            cells: vec![],
            triangles,
            counter_clockwise,
            shift: 0,
            leaned: vec![0.0; m],
            along: Vector3::new(-1.0, 0.0, 0.0),
            width: 1.0,
        };
        (layer, mesh)
    }

    #[test]
    fn a_top_row_that_slid_unevenly_is_zipped_into_triangles_that_tile_the_layer() {
        let m = 8;
        let (mut layer, mut mesh) = strip(m);
        assert!(
            mesh.cells[0]
                .conn
                .chunks(3)
                .all(|c| { (signed_area(&mesh.coords, c) > 0.0) == layer.counter_clockwise })
        );
        // the top row slid along by 0.3 … 2.6 cells, its ends by the least and the most
        let slid = [0.3, 0.4, 1.2, 1.3, 1.9, 2.2, 2.5, 2.6];
        let along_bottom: Vec<f64> = (0..m).map(|i| i as f64).collect();
        let along_top: Vec<f64> = (0..m).map(|j| j as f64 + slid[j]).collect();
        for (j, s) in along_top.iter().enumerate() {
            mesh.coords[m + j][0] = -s;
        }
        layer.zip(&mut mesh, &along_bottom, &along_top);
        // every triangle turns as the mesh's did and has its edge on a row
        let blk = &mesh.cells[0];
        for c in blk.conn.chunks(3) {
            let area = signed_area(&mesh.coords, c);
            assert!(
                area != 0.0 && (area > 0.0) == layer.counter_clockwise,
                "{c:?}"
            );
            assert!(
                triangle_edge(&layer.bottom, &layer.top, c).is_some(),
                "{c:?}"
            );
        }
        // and together they tile the strip between the rows: their areas add up to its
        let area: f64 = (blk.conn.chunks(3))
            .map(|c| signed_area(&mesh.coords, c).abs() / 2.0)
            .sum();
        let strip = (m - 1) as f64 + 0.5 * (slid[m - 1] - slid[0]);
        assert!((area - strip).abs() < 1e-12, "{area} vs {strip}");
        // each row edge keeps its triangle
        for (t, c) in layer.triangles.iter().zip(blk.conn.chunks(3)) {
            assert!(triangle_edge(&layer.bottom, &layer.top, c) == Some(t.edge));
        }
    }
}
