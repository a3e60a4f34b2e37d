//! A strip: a 2D layer of cells one cell across, between a bottom row of nodes and a top row
//! of equal length, whose cells can be joined again with the top row shifted against the
//! bottom one. The topology only: which node stands where in the rows, and how a cell's
//! corners follow a shift. What moves the nodes and carries their values is the model's
//! (`model::rejoin`).
//!
//! A quadrilateral keeps its bottom edge and takes for its top edge the pair of top-row nodes
//! that stands above it at the shift. A triangle keeps its edge on one row and takes for its
//! apex a node of the other, the two rows zipped together where they stand node by node, so a
//! face need not slide as one.

use super::{CellKind, Mesh, centroid, point_text};
use nalgebra::Vector3;

/// A quadrilateral of the strip: (mesh block, cell), the bottom row's index of its first
/// bottom node, and per corner whether it is on the top row and its offset along the row from
/// that index.
struct Quad {
    block: usize,
    cell: usize,
    first: usize,
    corners: [(bool, usize); 4],
}

/// A triangle of the strip: (mesh block, cell) and its edge on a row, which it keeps.
struct Triangle {
    block: usize,
    cell: usize,
    edge: Edge,
}

/// A triangle's edge: on the bottom row (the index of its first node, the other next along),
/// or on the top row (its two nodes, as they stand along it now).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Edge {
    Bottom(usize),
    Top(usize, usize),
}

/// The strip of some cell blocks of a mesh.
pub struct Strip {
    /// The rows' nodes, in order along the strip.
    pub bottom: Vec<usize>,
    pub top: Vec<usize>,
    quads: Vec<Quad>,
    triangles: Vec<Triangle>,
    /// Whether the mesh's triangles turn counter-clockwise (in the plane's x, y).
    counter_clockwise: bool,
    /// The top row's shift against the bottom row, in cells (positive along `along`).
    pub shift: i64,
    /// The direction along the strip, and its cells' mean width.
    pub along: Vector3<f64>,
    pub width: f64,
}

impl Strip {
    /// The strip of the mesh's cell blocks `blocks` (2D, linear quadrilaterals or triangles),
    /// its bottom row the nodes lowest along `normal`; the reason in words where they are not
    /// one ("joins a layer one cell across; …").
    pub fn find(mesh: &Mesh, blocks: &[usize], normal: Vector3<f64>) -> Result<Strip, String> {
        Self::planar(mesh)?;
        if let Some(&b) = (blocks.iter())
            .find(|&&b| !matches!(mesh.cells[b].kind, CellKind::Quad4 | CellKind::Tri3))
        {
            return Err(format!(
                "joins a layer of linear quadrilaterals (Q1) or triangles (T1) again; its \
                 cells are {}",
                mesh.cells[b].kind.name()
            ));
        }
        let along = Vector3::new(-normal[1], normal[0], 0.0);
        let coords = &mesh.coords;
        let across = |n: usize| normal.dot(&Vector3::from(coords[n]));
        let at = |n: usize| along.dot(&Vector3::from(coords[n]));
        let mut nodes: Vec<usize> = (blocks.iter())
            .flat_map(|&b| mesh.cells[b].conn.iter().copied())
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
            return Err(format!(
                "joins a layer one cell across between two rows of nodes of equal length; this \
                 one has {} nodes on its bottom face (along the normal) and {} above it",
                bottom.len(),
                top.len()
            ));
        }
        let (quads, triangles, counter_clockwise) = cells_of(mesh, blocks, &bottom, &top)?;
        let width = (at(bottom[bottom.len() - 1]) - at(bottom[0])) / (bottom.len() - 1) as f64;
        Ok(Strip {
            bottom,
            top,
            quads,
            triangles,
            counter_clockwise,
            shift: 0,
            along,
            width,
        })
    }

    /// Whether `mesh` can hold a strip (2D); the reason in words where not.
    pub fn planar(mesh: &Mesh) -> Result<(), String> {
        match mesh.dim {
            2 => Ok(()),
            _ => Err("joins a 2D layer's cells again; this mesh is 3D".into()),
        }
    }

    /// Nodes per row.
    pub fn len(&self) -> usize {
        self.top.len()
    }

    /// Whether the rows are empty (never, for a strip that [`Strip::find`] found).
    pub fn is_empty(&self) -> bool {
        self.top.is_empty()
    }

    /// The strip's cells.
    pub fn n_cells(&self) -> usize {
        self.quads.len() + self.triangles.len()
    }

    /// Whether it has triangles (zipped node by node).
    pub fn has_triangles(&self) -> bool {
        !self.triangles.is_empty()
    }

    /// The bottom row's index of top node `j`'s partner at the current shift.
    pub fn partner(&self, j: usize) -> usize {
        (j as i64 + self.shift).rem_euclid(self.top.len() as i64) as usize
    }

    /// The top row's index of the node that stands above bottom node `i` (of whose
    /// [`Strip::partner`] is `i`).
    pub fn above(&self, i: usize) -> usize {
        (i as i64 - self.shift).rem_euclid(self.top.len() as i64) as usize
    }

    /// Join the cells at the current shift in `mesh`'s connectivity: each quadrilateral to
    /// the top nodes above its bottom edge; the triangles zipped, the bottom row standing at
    /// `along_bottom` and the top one at `along_top` (places along the strip, by row index).
    pub fn connect(&mut self, mesh: &mut Mesh, along_bottom: &[f64], along_top: &[f64]) {
        for quad in &self.quads {
            let conn = &mut mesh.cells[quad.block].conn[quad.cell * 4..(quad.cell + 1) * 4];
            for (corner, &(on_top, offset)) in conn.iter_mut().zip(&quad.corners) {
                let i = quad.first + offset;
                *corner = match on_top {
                    true => self.top[self.above(i)],
                    false => self.bottom[i],
                };
            }
        }
        if !self.triangles.is_empty() {
            self.zip(mesh, along_bottom, along_top);
        }
    }

    /// Join the triangles node by node: the rows, the bottom one at `along_bottom` and the
    /// top one at `along_top`, are zipped together in the order their nodes stand along the
    /// strip. Each triangle keeps its edge on a row (a top edge that is no longer one, next
    /// to a free node that came round, takes one that is new) and takes for its apex the
    /// node of the other row that the zip puts beside it.
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
        // strip with its apex above (a bottom edge's) turns clockwise in (x, y), with its
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

/// The strip's cells in the mesh's cell blocks `blocks`, between the rows `bottom` and `top`:
/// its quadrilaterals, its triangles and whether they turn counter-clockwise; the reason in
/// words where a cell does not span the strip from one row to the next.
#[allow(clippy::type_complexity)]
fn cells_of(
    mesh: &Mesh,
    blocks: &[usize],
    bottom: &[usize],
    top: &[usize],
) -> Result<(Vec<Quad>, Vec<Triangle>, bool), String> {
    let coords = &mesh.coords;
    let centre = |nodes: &[usize]| point_text(&centroid(coords, nodes), mesh.dim);
    let index = |row: &[usize], n: usize| row.iter().position(|&m| m == n);
    let mut quads = Vec::new();
    let (mut triangles, mut counter_clockwise) = (Vec::new(), true);
    for &b in blocks {
        let blk = &mesh.cells[b];
        for c in (0..blk.n_cells()).filter(|_| blk.kind == CellKind::Tri3) {
            let nodes = blk.cell(c);
            let Some(edge) = triangle_edge(bottom, top, nodes) else {
                return Err(format!(
                    "joins a layer one cell across; its triangle {c} (centre {}) does \
                         not have an edge on one row and its third corner on the other",
                    centre(nodes)
                ));
            };
            counter_clockwise = signed_area(coords, nodes) > 0.0;
            triangles.push(Triangle {
                block: b,
                cell: c,
                edge,
            });
        }
        for c in (0..blk.n_cells()).filter(|_| blk.kind == CellKind::Quad4) {
            let rows: Vec<(bool, usize)> = (blk.cell(c).iter())
                .map(|&n| match index(bottom, n) {
                    Some(i) => (false, i),
                    None => (true, index(top, n).expect("a node of the layer")),
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
                return Err(format!(
                    "joins a layer one cell across; its cell {c} (centre {}) does not \
                         span it from one row to the next",
                    centre(blk.cell(c))
                ));
            };
            let mut corners = [(false, 0); 4];
            for (k, &(on_top, i)) in rows.iter().enumerate() {
                match i.checked_sub(first).filter(|&o| o <= 1) {
                    Some(o) => corners[k] = (on_top, o),
                    None => {
                        return Err(format!(
                            "joins cells that stand upright between the rows; cell {c} \
                                 (centre {}) leans over more than itself",
                            centre(blk.cell(c))
                        ));
                    }
                }
            }
            quads.push(Quad {
                block: b,
                cell: c,
                first,
                corners,
            });
        }
    }
    Ok((quads, triangles, counter_clockwise))
}

/// The edge on a row of the triangle `nodes` whose third corner is on the other row, if it
/// has one: two nodes next to each other on one row (`bottom` or `top`, in order along the
/// strip) and one on the other.
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
    fn strip(m: usize) -> (Strip, Mesh) {
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
        let strip = Strip::find(&mesh, &[0], Vector3::new(0.0, 1.0, 0.0)).expect("a strip");
        assert_eq!((strip.bottom.clone(), strip.top.clone()), (bottom, top));
        assert_eq!(strip.width, 1.0);
        (strip, mesh)
    }

    #[test]
    fn a_top_row_that_slid_unevenly_is_zipped_into_triangles_that_tile_the_layer() {
        let m = 8;
        let (mut strip, mut mesh) = strip(m);
        assert!(
            mesh.cells[0]
                .conn
                .chunks(3)
                .all(|c| { (signed_area(&mesh.coords, c) > 0.0) == strip.counter_clockwise })
        );
        // the top row slid along by 0.3 … 2.6 cells, its ends by the least and the most
        let slid = [0.3, 0.4, 1.2, 1.3, 1.9, 2.2, 2.5, 2.6];
        let along_bottom: Vec<f64> = (0..m).map(|i| i as f64).collect();
        let along_top: Vec<f64> = (0..m).map(|j| j as f64 + slid[j]).collect();
        for (j, s) in along_top.iter().enumerate() {
            mesh.coords[m + j][0] = -s;
        }
        strip.connect(&mut mesh, &along_bottom, &along_top);
        // every triangle turns as the mesh's did and has its edge on a row
        let blk = &mesh.cells[0];
        for c in blk.conn.chunks(3) {
            let area = signed_area(&mesh.coords, c);
            assert!(
                area != 0.0 && (area > 0.0) == strip.counter_clockwise,
                "{c:?}"
            );
            assert!(
                triangle_edge(&strip.bottom, &strip.top, c).is_some(),
                "{c:?}"
            );
        }
        // and together they tile the strip between the rows: their areas add up to its
        let area: f64 = (blk.conn.chunks(3))
            .map(|c| signed_area(&mesh.coords, c).abs() / 2.0)
            .sum();
        let whole = (m - 1) as f64 + 0.5 * (slid[m - 1] - slid[0]);
        assert!((area - whole).abs() < 1e-12, "{area} vs {whole}");
        // each row edge keeps its triangle
        for (t, c) in strip.triangles.iter().zip(blk.conn.chunks(3)) {
            assert!(triangle_edge(&strip.bottom, &strip.top, c) == Some(t.edge));
        }
    }

    #[test]
    fn a_layer_that_is_not_one_cell_across_is_refused_with_its_reason() {
        let (_, mut mesh) = strip(4);
        // a node of the top row lifted off it: three nodes above, four below
        mesh.coords.push([-1.5, 2.0, 0.0]);
        mesh.cells[0].conn.extend([4, 5, 8]);
        let why = Strip::find(&mesh, &[0], Vector3::new(0.0, 1.0, 0.0))
            .err()
            .expect("refused");
        assert!(why.contains("rows of nodes of equal length"), "{why}");
    }
}
