//! The faces between two sets of cells (a solid's surface against the medium), their unit
//! normals and measures, and the nearest of them to a point.
//!
//! A face is a cell's side of one dimension less: an edge of a 2D cell, a triangle or a
//! quadrilateral of a 3D one, found by its corner nodes (quadratic cells' mid-side nodes play
//! no part: a face is taken as flat between its corners).

use super::{CellKind, Mesh, centroid};
use std::collections::HashMap;

/// A face shared by a cell of one set and a cell of the other.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// Mean of the corners.
    pub centre: [f64; 3],
    /// Unit normal, pointing out of the first set's cell.
    pub normal: [f64; 3],
}

/// The sides of a cell, as its local corner numbers (gmsh's node order).
pub fn sides(kind: CellKind) -> &'static [&'static [usize]] {
    match kind {
        CellKind::Tri3 | CellKind::Tri6 => &[&[0, 1], &[1, 2], &[2, 0]],
        CellKind::Quad4 | CellKind::Quad8 | CellKind::Quad9 => {
            &[&[0, 1], &[1, 2], &[2, 3], &[3, 0]]
        }
        CellKind::Tet4 | CellKind::Tet10 => &[&[0, 2, 1], &[0, 1, 3], &[0, 3, 2], &[1, 2, 3]],
        CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => &[
            &[0, 3, 2, 1],
            &[0, 1, 5, 4],
            &[0, 4, 7, 3],
            &[1, 2, 6, 5],
            &[2, 3, 7, 6],
            &[4, 5, 6, 7],
        ],
        CellKind::Point1 | CellKind::Line2 | CellKind::Line3 => &[],
    }
}

/// A triangle's nodes in order: a key that does not depend on how it turns.
pub fn triangle_key(f: [usize; 3]) -> [usize; 3] {
    let mut k = f;
    k.sort_unstable();
    k
}

/// The boundary of the tetrahedra of the blocks `blocks`: the faces that no other of them
/// shares, turned as their cells turn them (an error names another kind of cell).
pub fn outer_triangles(mesh: &Mesh, blocks: &[usize]) -> Result<Vec<[usize; 3]>, String> {
    let mut faces: HashMap<[usize; 3], ([usize; 3], usize)> = HashMap::new();
    for &b in blocks {
        let blk = &mesh.cells[b];
        if blk.kind != CellKind::Tet4 {
            return Err(format!("has {} cells, not tet4", blk.kind.name()));
        }
        for c in 0..blk.n_cells() {
            let cell = blk.cell(c);
            for f in sides(CellKind::Tet4) {
                let face = [0, 1, 2].map(|i| cell[f[i]]);
                faces.entry(triangle_key(face)).or_insert((face, 0)).1 += 1;
            }
        }
    }
    let mut out: Vec<[usize; 3]> = (faces.into_values())
        .filter(|&(_, count)| count == 1)
        .map(|(face, _)| face)
        .collect();
    out.sort_unstable();
    Ok(out)
}

/// The triangles `faces` (indices) in sets joined by their edges, where `join(i, j)` lets
/// triangle `j` join triangle `i`'s set across the edge they share.
pub fn joined_by_edges(
    faces: &[[usize; 3]],
    join: impl Fn(usize, usize) -> bool,
) -> Vec<Vec<usize>> {
    let mut by_edge: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for (i, f) in faces.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            by_edge.entry((a.min(b), a.max(b))).or_default().push(i);
        }
    }
    let mut placed = vec![false; faces.len()];
    let mut sets = Vec::new();
    for start in 0..faces.len() {
        if placed[start] {
            continue;
        }
        let mut members = vec![start];
        placed[start] = true;
        let mut k = 0;
        while k < members.len() {
            let i = members[k];
            k += 1;
            for e in 0..3 {
                let (a, b) = (faces[i][e], faces[i][(e + 1) % 3]);
                for &j in &by_edge[&(a.min(b), a.max(b))] {
                    if !placed[j] && join(i, j) {
                        placed[j] = true;
                        members.push(j);
                    }
                }
            }
        }
        sets.push(members);
    }
    sets
}

/// A face shared by two cells, each named by its mesh block and its index there.
#[derive(Clone, Debug, PartialEq)]
pub struct Side {
    /// The cell of the first set and of the second, as (block in `mesh.cells`, cell).
    pub a: (usize, usize),
    pub b: (usize, usize),
    /// The face's corner nodes, in the order of `a`'s side.
    pub corners: Vec<usize>,
}

/// The sides where a cell of the blocks `a` meets a cell of the blocks `b` (indices into
/// `mesh.cells`), each once, in the order of `a`'s cells.
pub fn shared_sides(mesh: &Mesh, a: &[usize], b: &[usize]) -> Vec<Side> {
    let key = |nodes: &[usize], side: &[usize]| {
        let mut k: Vec<usize> = side.iter().map(|&i| nodes[i]).collect();
        k.sort_unstable();
        k
    };
    // a shared side's nodes are all on cells of both: only such sides are looked up
    let (on_a, on_b) = (
        mesh.nodes_in(|i| a.contains(&i)),
        mesh.nodes_in(|i| b.contains(&i)),
    );
    let mut in_b: HashMap<Vec<usize>, (usize, usize)> = HashMap::new();
    for &bi in b {
        let blk = &mesh.cells[bi];
        for c in 0..blk.n_cells() {
            let nodes = blk.cell(c);
            for side in sides(blk.kind) {
                if side.iter().all(|&i| on_a[nodes[i]]) {
                    in_b.insert(key(nodes, side), (bi, c));
                }
            }
        }
    }
    let mut out = Vec::new();
    for &ai in a {
        let blk = &mesh.cells[ai];
        for c in 0..blk.n_cells() {
            let nodes = blk.cell(c);
            for side in sides(blk.kind) {
                if !side.iter().all(|&i| on_b[nodes[i]]) {
                    continue;
                }
                if let Some(other) = in_b.remove(&key(nodes, side)) {
                    let corners = side.iter().map(|&i| nodes[i]).collect();
                    out.push(Side {
                        a: (ai, c),
                        b: other,
                        corners,
                    });
                }
            }
        }
    }
    out
}

/// The faces where a cell of the blocks `a` meets a cell of the blocks `b` (indices into
/// `mesh.cells`), each once, in the order of `a`'s cells, normals out of `a`.
pub fn shared_faces(mesh: &Mesh, a: &[usize], b: &[usize]) -> Vec<Face> {
    let at = |n: usize| mesh.coords[n];
    (shared_sides(mesh, a, b).iter())
        .map(|s| {
            let (normal, _) = s.normal_and_measure(mesh, at);
            let centre = centroid(&mesh.coords, &s.corners);
            Face { centre, normal }
        })
        .collect()
}

impl Side {
    /// The side's unit normal out of its cell `a` and its measure (length in 2D, area in 3D),
    /// with the nodes at `x(n)` (the mesh's coordinates, or where the nodes have moved). A
    /// quadrilateral is taken as flat: its normal and area from its diagonals.
    pub fn normal_and_measure(
        &self,
        mesh: &Mesh,
        x: impl Fn(usize) -> [f64; 3],
    ) -> ([f64; 3], f64) {
        let p = |i: usize| x(self.corners[i]);
        let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
        let (n, measure_of_n) = match self.corners.len() {
            // an edge of a 2D cell: its direction turned by a right angle
            2 => {
                let t = sub(p(1), p(0));
                ([t[1], -t[0], 0.0], 1.0)
            }
            // a triangle: the cross product of two edges; a quadrilateral: of its diagonals
            k => {
                let (u, v) = if k == 3 {
                    (sub(p(1), p(0)), sub(p(2), p(0)))
                } else {
                    (sub(p(2), p(0)), sub(p(3), p(1)))
                };
                let n = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                (n, 0.5)
            }
        };
        let blk = &mesh.cells[self.a.0];
        let cell = &blk.cell(self.a.1)[..blk.kind.corners()];
        let mid = |ns: &[usize]| -> [f64; 3] {
            std::array::from_fn(|i| ns.iter().map(|&m| x(m)[i]).sum::<f64>() / ns.len() as f64)
        };
        let inward = sub(mid(cell), mid(&self.corners));
        let dot: f64 = (0..3).map(|i| n[i] * inward[i]).sum();
        let length = n.iter().map(|v| v * v).sum::<f64>().sqrt();
        let sign = if dot > 0.0 { -1.0 } else { 1.0 };
        (n.map(|v| sign * v / length), measure_of_n * length)
    }
}

/// The faces sorted along x, for the nearest one to a point.
pub struct NearestFace<'a> {
    faces: &'a [Face],
    /// Face numbers sorted by their centres' x.
    by_x: Vec<usize>,
}

impl<'a> NearestFace<'a> {
    pub fn new(faces: &'a [Face]) -> Self {
        let mut by_x: Vec<usize> = (0..faces.len()).collect();
        by_x.sort_by(|&i, &j| faces[i].centre[0].total_cmp(&faces[j].centre[0]));
        NearestFace { faces, by_x }
    }

    /// The face whose centre is nearest to `x` (`None` with no faces): from the faces nearest
    /// in x outwards, until the distance in x alone exceeds the best found.
    pub fn to(&self, x: &[f64; 3]) -> Option<&'a Face> {
        let start = self
            .by_x
            .partition_point(|&i| self.faces[i].centre[0] < x[0]);
        let distance2 = |f: &Face| (0..3).map(|i| (f.centre[i] - x[i]).powi(2)).sum::<f64>();
        let mut best: Option<(f64, usize)> = None;
        let (mut up, mut down) = (start, start);
        loop {
            let gap_up = self.by_x.get(up).map(|&i| self.faces[i].centre[0] - x[0]);
            let gap_down = down
                .checked_sub(1)
                .map(|d| x[0] - self.faces[self.by_x[d]].centre[0]);
            // the nearer side in x next
            let (gap, i) = match (gap_up, gap_down) {
                (None, None) => break,
                (Some(u), Some(d)) if d < u => {
                    down -= 1;
                    (d, self.by_x[down])
                }
                (Some(u), _) => {
                    up += 1;
                    (u, self.by_x[up - 1])
                }
                (None, Some(d)) => {
                    down -= 1;
                    (d, self.by_x[down])
                }
            };
            if best.is_some_and(|(b, _)| gap * gap > b) {
                break;
            }
            let d2 = distance2(&self.faces[i]);
            // ties go to the lower face number, whichever side they were met from
            if best.is_none_or(|(b, j)| d2 < b || (d2 == b && i < j)) {
                best = Some((d2, i));
            }
        }
        best.map(|(_, i)| &self.faces[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Block;

    fn brute(faces: &[Face], x: &[f64; 3]) -> usize {
        let d2 = |f: &Face| (0..3).map(|i| (f.centre[i] - x[i]).powi(2)).sum::<f64>();
        (0..faces.len())
            .min_by(|&i, &j| d2(&faces[i]).total_cmp(&d2(&faces[j])).then(i.cmp(&j)))
            .unwrap()
    }

    #[test]
    fn the_nearest_face_is_the_one_a_search_of_all_finds() {
        // centres on a scrambled spiral, queries on a grid around it
        let faces: Vec<Face> = (0..200)
            .map(|k| {
                let t = (k * 37 % 200) as f64 * 0.1;
                Face {
                    centre: [
                        t.cos() * (1.0 + 0.05 * t),
                        t.sin() * (1.0 + 0.05 * t),
                        0.3 * t,
                    ],
                    normal: [1.0, 0.0, 0.0],
                }
            })
            .collect();
        let near = NearestFace::new(&faces);
        for q in 0..400 {
            let x = [
                -2.5 + 0.25 * (q % 20) as f64,
                -2.5 + 0.25 * (q / 20) as f64,
                0.1 * (q % 7) as f64,
            ];
            let found = near.to(&x).unwrap() as *const Face;
            assert_eq!(found, &faces[brute(&faces, &x)] as *const Face, "at {x:?}");
        }
        assert!(NearestFace::new(&[]).to(&[0.0; 3]).is_none());
    }

    fn mesh(dim: usize, coords: Vec<[f64; 3]>, cells: Vec<Block>) -> Mesh {
        Mesh::of_cells(dim, coords, cells)
    }

    #[test]
    fn a_tilted_edge_between_a_quad_and_a_triangle_has_its_normal_out_of_the_first() {
        // a quad (0,0) (1,0) (1.5,1) (0,1) and a triangle on its slanted right side
        let coords = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.5, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [2.0, 0.0, 0.0],
        ];
        let quad = Block {
            kind: CellKind::Quad4,
            groups: vec![],
            conn: vec![0, 1, 2, 3],
        };
        let tri = Block {
            kind: CellKind::Tri3,
            groups: vec![],
            conn: vec![1, 4, 2],
        };
        let m = mesh(2, coords, vec![quad, tri]);
        let faces = shared_faces(&m, &[0], &[1]);
        assert_eq!(faces.len(), 1);
        let s = 1.0 / 1.25f64.sqrt();
        let want = [s, -0.5 * s, 0.0];
        for i in 0..3 {
            assert!(
                (faces[0].normal[i] - want[i]).abs() < 1e-15,
                "{:?}",
                faces[0]
            );
        }
        assert_eq!(faces[0].centre, [1.25, 0.5, 0.0]);
        // its length, and where the nodes have moved (the side's upper end pulled up to
        // (1.5, 3): the side along (0.5, 3))
        let side = &shared_sides(&m, &[0], &[1])[0];
        assert_eq!(
            (side.a, side.b, side.corners.clone()),
            ((0, 0), (1, 0), vec![1, 2])
        );
        let moved = |n: usize| if n == 2 { [1.5, 3.0, 0.0] } else { m.coords[n] };
        let (normal, length) = side.normal_and_measure(&m, moved);
        let l = 9.25f64.sqrt();
        assert!((length - l).abs() < 1e-15);
        let want = [3.0 / l, -0.5 / l, 0.0];
        assert!(
            (0..3).all(|i| (normal[i] - want[i]).abs() < 1e-15),
            "{normal:?}"
        );
        // out of the triangle, the other way
        let back = shared_faces(&m, &[1], &[0]);
        assert_eq!(back[0].normal.map(|v| -v), faces[0].normal);
    }

    #[test]
    fn the_face_between_two_stacked_hexes_points_up_out_of_the_lower() {
        // unit cubes at z in [0, 1] and [1, 2], gmsh's node order
        let mut coords = Vec::new();
        for z in 0..3 {
            for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                coords.push([x, y, z as f64]);
            }
        }
        let hex = |lo: usize| Block {
            kind: CellKind::Hex8,
            groups: vec![],
            conn: (lo..lo + 8).collect(),
        };
        let m = mesh(3, coords, vec![hex(0), hex(4)]);
        let faces = shared_faces(&m, &[0], &[1]);
        assert_eq!(faces.len(), 1);
        assert_eq!(faces[0].normal, [0.0, 0.0, 1.0]);
        assert_eq!(faces[0].centre, [0.5, 0.5, 1.0]);
        let side = &shared_sides(&m, &[0], &[1])[0];
        assert_eq!(side.normal_and_measure(&m, |n| m.coords[n]).1, 1.0);
        // tetrahedra: the faces of one tet against another sharing (1, 2, 3)
        let tets = mesh(
            3,
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 1.0, 1.0],
            ],
            vec![
                Block {
                    kind: CellKind::Tet4,
                    groups: vec![],
                    conn: vec![0, 1, 2, 3],
                },
                Block {
                    kind: CellKind::Tet4,
                    groups: vec![],
                    conn: vec![4, 2, 1, 3],
                },
            ],
        );
        let f = shared_faces(&tets, &[0], &[1]);
        assert_eq!(f.len(), 1);
        let s = 1.0 / 3f64.sqrt();
        for v in f[0].normal {
            assert!((v - s).abs() < 1e-15, "{:?}", f[0]);
        }
        let side = &shared_sides(&tets, &[0], &[1])[0];
        let area = side.normal_and_measure(&tets, |n| tets.coords[n]).1;
        assert!((area - 0.75f64.sqrt()).abs() < 1e-15, "{area}");
    }
}
