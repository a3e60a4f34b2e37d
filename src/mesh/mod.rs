//! Meshes: nodes, cell blocks per element type and physical group, boundary facets.
//!
//! Everything a user names is a gmsh physical group; raw numeric ids never leave this module.

pub mod cache;
mod child;
pub mod faces;
pub mod geo_text;
pub mod gmsh;
mod gmshc;
pub mod msh;
pub mod partition;
pub mod plane_faces;
pub mod remesh;
pub mod strip;

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Element types tmc reads from `.msh` files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum CellKind {
    Point1,
    Line2,
    Tri3,
    Quad4,
    Tet4,
    Hex8,
    Line3,
    Tri6,
    Quad8,
    Quad9,
    Tet10,
    Hex20,
    Hex27,
}

impl CellKind {
    /// Topological dimension.
    pub fn dim(self) -> usize {
        match self {
            CellKind::Point1 => 0,
            CellKind::Line2 | CellKind::Line3 => 1,
            CellKind::Tri3
            | CellKind::Quad4
            | CellKind::Tri6
            | CellKind::Quad8
            | CellKind::Quad9 => 2,
            CellKind::Tet4
            | CellKind::Hex8
            | CellKind::Tet10
            | CellKind::Hex20
            | CellKind::Hex27 => 3,
        }
    }

    pub fn n_nodes(self) -> usize {
        match self {
            CellKind::Point1 => 1,
            CellKind::Line2 => 2,
            CellKind::Tri3 => 3,
            CellKind::Quad4 | CellKind::Tet4 => 4,
            CellKind::Hex8 => 8,
            CellKind::Line3 => 3,
            CellKind::Tri6 => 6,
            CellKind::Quad8 => 8,
            CellKind::Quad9 => 9,
            CellKind::Tet10 => 10,
            CellKind::Hex20 => 20,
            CellKind::Hex27 => 27,
        }
    }

    /// Polynomial order of the shape functions.
    pub fn order(self) -> usize {
        match self {
            CellKind::Point1
            | CellKind::Line2
            | CellKind::Tri3
            | CellKind::Quad4
            | CellKind::Tet4
            | CellKind::Hex8 => 1,
            _ => 2,
        }
    }

    /// Node permutation that reverses the orientation of a 2D cell (corners, edges along).
    pub fn flip(self) -> &'static [usize] {
        match self {
            CellKind::Tri3 => &[0, 2, 1],
            CellKind::Quad4 => &[0, 3, 2, 1],
            CellKind::Tri6 => &[0, 2, 1, 5, 4, 3],
            CellKind::Quad8 => &[0, 3, 2, 1, 7, 6, 5, 4],
            CellKind::Quad9 => &[0, 3, 2, 1, 7, 6, 5, 4, 8],
            _ => &[],
        }
    }

    /// Number of corner nodes (the first ones in tmc's order).
    pub fn corners(self) -> usize {
        match self {
            CellKind::Point1 => 1,
            CellKind::Line2 | CellKind::Line3 => 2,
            CellKind::Tri3 | CellKind::Tri6 => 3,
            CellKind::Quad4
            | CellKind::Quad8
            | CellKind::Quad9
            | CellKind::Tet4
            | CellKind::Tet10 => 4,
            CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => 8,
        }
    }

    /// VTK's node order: VTK node i is tmc (gmsh) node `vtk_order()[i]`.
    pub fn vtk_order(self) -> Option<&'static [usize]> {
        match self {
            CellKind::Tet10 => Some(&[0, 1, 2, 3, 4, 5, 6, 7, 9, 8]),
            CellKind::Hex20 => Some(&[
                0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15,
            ]),
            CellKind::Hex27 => Some(&[
                0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15, 22, 23, 21,
                24, 20, 25, 26,
            ]),
            _ => None,
        }
    }

    /// The element's name as the paper and the docs use it.
    pub fn name(self) -> &'static str {
        match self {
            CellKind::Point1 => "point",
            CellKind::Line2 => "line2",
            CellKind::Tri3 => "T1 (tri3)",
            CellKind::Quad4 => "Q1 (quad4)",
            CellKind::Tet4 => "tet4",
            CellKind::Hex8 => "H1 (hex8)",
            CellKind::Line3 => "line3",
            CellKind::Tri6 => "T2 (tri6)",
            CellKind::Quad8 => "Q2S (quad8)",
            CellKind::Quad9 => "Q2 (quad9)",
            CellKind::Tet10 => "tet10",
            CellKind::Hex20 => "H2S (hex20)",
            CellKind::Hex27 => "H2 (hex27)",
        }
    }

    /// VTK cell type id.
    pub fn vtk_id(self) -> u8 {
        match self {
            CellKind::Point1 => 1,
            CellKind::Line2 => 3,
            CellKind::Tri3 => 5,
            CellKind::Quad4 => 9,
            CellKind::Tet4 => 10,
            CellKind::Hex8 => 12,
            CellKind::Line3 => 21,
            CellKind::Tri6 => 22,
            CellKind::Quad8 => 23,
            CellKind::Quad9 => 28,
            CellKind::Tet10 => 24,
            CellKind::Hex20 => 25,
            CellKind::Hex27 => 29,
        }
    }

    /// From gmsh's element type number; `None` for types tmc does not support.
    pub fn from_gmsh(t: u32) -> Option<CellKind> {
        Some(match t {
            15 => CellKind::Point1,
            1 => CellKind::Line2,
            2 => CellKind::Tri3,
            3 => CellKind::Quad4,
            4 => CellKind::Tet4,
            5 => CellKind::Hex8,
            8 => CellKind::Line3,
            9 => CellKind::Tri6,
            16 => CellKind::Quad8,
            10 => CellKind::Quad9,
            11 => CellKind::Tet10,
            17 => CellKind::Hex20,
            12 => CellKind::Hex27,
            _ => return None,
        })
    }
}

/// gmsh's name for an element type number, for error messages.
pub fn gmsh_type_name(t: u32) -> String {
    match t {
        8 => "line3".into(),
        9 => "tri6".into(),
        10 => "quad9".into(),
        11 => "tet10".into(),
        12 => "hex27".into(),
        16 => "quad8".into(),
        17 => "hex20".into(),
        6 => "prism6".into(),
        7 => "pyramid5".into(),
        _ => format!("gmsh element type {t}"),
    }
}

/// A gmsh physical group.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhysicalGroup {
    pub name: String,
    pub dim: usize,
    pub tag: i32,
}

/// Cells of one element type from one gmsh entity, with the physical groups they belong to.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Block {
    pub kind: CellKind,
    /// Indices into [`Mesh::groups`].
    pub groups: Vec<usize>,
    /// Flat connectivity, `kind.n_nodes()` node indices per cell.
    pub conn: Vec<usize>,
}

impl Block {
    pub fn n_cells(&self) -> usize {
        self.conn.len() / self.kind.n_nodes()
    }
    pub fn cell(&self, c: usize) -> &[usize] {
        let n = self.kind.n_nodes();
        &self.conn[c * n..(c + 1) * n]
    }
}

/// A finite-element mesh of dimension 2 or 3 (as a restart file holds a medium made again:
/// without the file it was read from and what its reader found).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Mesh {
    pub dim: usize,
    /// Node coordinates (z = 0 in 2D).
    pub coords: Vec<[f64; 3]>,
    /// Cells of the mesh's dimension.
    pub cells: Vec<Block>,
    /// Lower-dimensional elements (boundary facets, points) that carry physical groups.
    pub facets: Vec<Block>,
    pub groups: Vec<PhysicalGroup>,
    /// File the mesh was read from.
    #[serde(skip)]
    pub source: PathBuf,
    /// What the reader found suspicious but valid (e.g. coincident nodes).
    #[serde(skip)]
    pub warnings: Vec<String>,
}

impl Mesh {
    /// A mesh of these cells alone: no facets, no physical groups, read from no file.
    pub fn of_cells(dim: usize, coords: Vec<[f64; 3]>, cells: Vec<Block>) -> Mesh {
        Mesh {
            dim,
            coords,
            cells,
            facets: Vec::new(),
            groups: Vec::new(),
            source: PathBuf::new(),
            warnings: Vec::new(),
        }
    }

    pub fn group(&self, name: &str) -> Option<usize> {
        self.groups.iter().position(|g| g.name == name)
    }

    pub fn n_cells(&self) -> usize {
        self.cells.iter().map(Block::n_cells).sum()
    }

    /// Sorted, unique node indices of all cells and facets in group `g`.
    pub fn group_nodes(&self, g: usize) -> Vec<usize> {
        let mut nodes: Vec<usize> = self
            .cells
            .iter()
            .chain(&self.facets)
            .filter(|b| b.groups.contains(&g))
            .flat_map(|b| b.conn.iter().copied())
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// Largest extent of the undeformed mesh's bounding box (eq. 21).
    pub fn extent(&self) -> f64 {
        extent_of(&self.coords)
    }

    /// Per node, whether a cell of a block (an index into [`Mesh::cells`]) `keep` accepts has
    /// it.
    pub fn nodes_in(&self, keep: impl Fn(usize) -> bool) -> Vec<bool> {
        nodes_of(&self.cells, self.coords.len(), |i, _| keep(i))
    }

    /// The connected sets of cells among the blocks (indices into [`Mesh::cells`]) `keep`
    /// accepts (cells sharing a node are connected): per node, the index of its set, or
    /// `usize::MAX` for a node of no kept cell.
    pub fn components(&self, keep: impl Fn(usize) -> bool) -> Vec<usize> {
        let n = self.coords.len();
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(p: &mut [usize], mut a: usize) -> usize {
            while p[a] != a {
                p[a] = p[p[a]];
                a = p[a];
            }
            a
        }
        let mut used = vec![false; n];
        for (_, b) in self.cells.iter().enumerate().filter(|&(i, _)| keep(i)) {
            for c in 0..b.n_cells() {
                let cell = b.cell(c);
                used[cell[0]] = true;
                for &m in &cell[1..] {
                    used[m] = true;
                    let (ra, rb) = (find(&mut parent, cell[0]), find(&mut parent, m));
                    if ra != rb {
                        parent[ra.max(rb)] = ra.min(rb);
                    }
                }
            }
        }
        let mut label = vec![usize::MAX; n];
        let mut next = 0;
        let mut comp = vec![usize::MAX; n];
        for a in 0..n {
            if !used[a] {
                continue;
            }
            let r = find(&mut parent, a);
            if label[r] == usize::MAX {
                label[r] = next;
                next += 1;
            }
            comp[a] = label[r];
        }
        comp
    }

    /// The bodies (connected cells of one physical group) that no lower-dimensional physical
    /// group touches, as warnings for `tmc mesh`: a case can put no condition on them, so only
    /// the group they are joined to holds them and sets their temperature. The trap: a body
    /// given no boundary group at all rests on the third medium alone and slides on it. A group
    /// joined to two or more others (a medium between bodies) is left out. (With a case,
    /// `model::held` says which bodies the medium alone holds.)
    pub fn untouched_bodies(&self) -> Vec<String> {
        let touched = nodes_of(&self.facets, self.coords.len(), |_, b| !b.groups.is_empty());
        let bodies: Vec<(usize, Vec<bool>)> = (0..self.groups.len())
            .filter(|&g| self.groups[g].dim == self.dim)
            .map(|g| (g, self.nodes_in(|b| self.cells[b].groups.contains(&g))))
            .collect();
        let mut warnings = Vec::new();
        for &(g, _) in &bodies {
            let comp = self.components(|b| self.cells[b].groups.contains(&g));
            let n_comp = comp
                .iter()
                .filter(|&&c| c != usize::MAX)
                .max()
                .map_or(0, |&m| m + 1);
            let mut nodes = vec![Vec::new(); n_comp];
            for (n, &c) in comp.iter().enumerate() {
                if c != usize::MAX {
                    nodes[c].push(n);
                }
            }
            for body in nodes.iter().filter(|b| !b.iter().any(|&n| touched[n])) {
                let joined: Vec<String> = bodies
                    .iter()
                    .filter(|(o, of)| *o != g && body.iter().any(|&n| of[n]))
                    .map(|(o, _)| format!("\"{}\"", self.groups[*o].name))
                    .collect();
                if joined.len() > 1 {
                    continue;
                }
                let which = if n_comp > 1 {
                    "a body of group"
                } else {
                    "group"
                };
                let held = if joined.is_empty() {
                    "it is joined to nothing: nothing holds it".to_string()
                } else {
                    format!(
                        "only {} holds it (a solid in the third medium alone slides on it)",
                        joined[0]
                    )
                };
                warnings.push(format!(
                    "{which} \"{}\" ({} nodes around {}) touches no boundary group, so no \
                     condition can be put on it: {held}; a Physical {} on its boundary gives it \
                     supports",
                    self.groups[g].name,
                    body.len(),
                    point_text(&centroid(&self.coords, body), self.dim),
                    if self.dim == 2 { "Curve" } else { "Surface" }
                ));
            }
        }
        warnings
    }

    /// Cells per element type, in order of first appearance.
    pub fn cell_counts(&self) -> Vec<(CellKind, usize)> {
        self.cell_kinds()
            .into_iter()
            .map(|k| {
                let n = self
                    .cells
                    .iter()
                    .filter(|b| b.kind == k)
                    .map(Block::n_cells)
                    .sum();
                (k, n)
            })
            .collect()
    }

    /// Element types present among the cells, in order of first appearance.
    pub fn cell_kinds(&self) -> Vec<CellKind> {
        let mut kinds = Vec::new();
        for b in &self.cells {
            if !kinds.contains(&b.kind) {
                kinds.push(b.kind);
            }
        }
        kinds
    }
}

/// The signed volume of the tetrahedron with corners `q`: positive where the fourth stands on
/// the side the first three face by the right hand.
pub fn tet_volume(q: [[f64; 3]; 4]) -> f64 {
    let d = |k: usize| [0, 1, 2].map(|i| q[k][i] - q[0][i]);
    let (a, b, c) = (d(1), d(2), d(3));
    let cross = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    (cross[0] * c[0] + cross[1] * c[1] + cross[2] * c[2]) / 6.0
}

/// The mean of the nodes' coordinates (a cell's centre, a body's centre).
pub fn centroid(coords: &[[f64; 3]], nodes: &[usize]) -> [f64; 3] {
    let mut m = [0.0; 3];
    for &n in nodes {
        for (mi, xi) in m.iter_mut().zip(&coords[n]) {
            *mi += xi;
        }
    }
    m.map(|v| v / nodes.len() as f64)
}

/// Per node (of `nodes`), whether a block of `blocks` that `keep` accepts (by index and block)
/// has it.
fn nodes_of(blocks: &[Block], nodes: usize, keep: impl Fn(usize, &Block) -> bool) -> Vec<bool> {
    let mut on = vec![false; nodes];
    for (_, b) in blocks.iter().enumerate().filter(|&(i, b)| keep(i, b)) {
        b.conn.iter().for_each(|&n| on[n] = true);
    }
    on
}

/// The largest side of the bounding box of `points` (0 for none).
pub fn extent_of<'a>(points: impl IntoIterator<Item = &'a [f64; 3]>) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for x in points {
        for i in 0..3 {
            lo[i] = lo[i].min(x[i]);
            hi[i] = hi[i].max(x[i]);
        }
    }
    (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f64::max)
}

/// A point for a message: its `dim` coordinates to 4 decimals, "(x, y)" or "(x, y, z)".
pub fn point_text(x: &[f64; 3], dim: usize) -> String {
    let xs: Vec<String> = x[..dim].iter().map(|v| format!("{v:.4}")).collect();
    format!("({})", xs.join(", "))
}

/// Checks of a mesh as read: every coordinate finite and every cell of non-zero measure
/// (errors naming the cell's group and centre); coincident nodes (the mesh is cut there: a
/// crack or geometry that was not merged) are a warning.
pub fn check_geometry(mesh: &Mesh) -> Result<Vec<String>, String> {
    if let Some((n, x)) = mesh
        .coords
        .iter()
        .enumerate()
        .find(|(_, x)| x.iter().any(|v| !v.is_finite()))
    {
        return Err(format!("node {n} has a non-finite coordinate {x:?}"));
    }
    let h = mesh.extent();
    if h <= 0.0 {
        return Err("all nodes coincide".into());
    }
    let tol = 1e-12 * h.powi(mesh.dim as i32);
    for b in &mesh.cells {
        for c in 0..b.n_cells() {
            let corners = &b.cell(c)[..b.kind.corners()];
            let x: Vec<[f64; 3]> = corners.iter().map(|&n| mesh.coords[n]).collect();
            if min_corner_measure(b.kind, &x).abs() <= tol {
                let group = b
                    .groups
                    .first()
                    .map(|&g| mesh.groups[g].name.as_str())
                    .unwrap_or("(no group)");
                let at = centroid(&mesh.coords, corners);
                return Err(format!(
                    "a {} cell of group \"{group}\" at {} is degenerate (zero {})",
                    b.kind.name(),
                    point_text(&at, mesh.dim),
                    if mesh.dim == 2 { "area" } else { "volume" }
                ));
            }
        }
    }
    Ok(coincident_nodes(mesh, h).into_iter().collect())
}

/// The smallest signed measure among a cell's corner simplices (twice the area of a corner
/// triangle in 2D, six times the volume of a corner tetrahedron in 3D): zero when corners
/// coincide or a face collapses.
fn min_corner_measure(kind: CellKind, x: &[[f64; 3]]) -> f64 {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let tri = |o: usize, p: usize, q: usize| {
        let (a, b) = (sub(x[p], x[o]), sub(x[q], x[o]));
        a[0] * b[1] - a[1] * b[0]
    };
    let tet = |o: usize, p: usize, q: usize, r: usize| {
        let (a, b, c) = (sub(x[p], x[o]), sub(x[q], x[o]), sub(x[r], x[o]));
        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0])
    };
    // 2D cells may be stored either way round (they are oriented later): compare magnitudes
    match kind.dim() {
        2 => {
            let k = x.len();
            (0..k)
                .map(|i| tri(i, (i + 1) % k, (i + k - 1) % k).abs())
                .fold(f64::INFINITY, f64::min)
        }
        3 if x.len() == 4 => tet(0, 1, 2, 3).abs(),
        3 => {
            // hexahedron: the tetrahedron at each corner spanned by its three edges
            const EDGES: [[usize; 4]; 8] = [
                [0, 1, 3, 4],
                [1, 2, 0, 5],
                [2, 3, 1, 6],
                [3, 0, 2, 7],
                [4, 7, 5, 0],
                [5, 4, 6, 1],
                [6, 5, 7, 2],
                [7, 6, 4, 3],
            ];
            EDGES
                .iter()
                .map(|e| tet(e[0], e[1], e[2], e[3]).abs())
                .fold(f64::INFINITY, f64::min)
        }
        _ => f64::INFINITY,
    }
}

/// A warning when distinct nodes share a position (to 1e-10 of the extent `h`).
fn coincident_nodes(mesh: &Mesh, h: f64) -> Option<String> {
    let q = 1e-10 * h;
    let mut keys: Vec<([i64; 3], usize)> = mesh
        .coords
        .iter()
        .enumerate()
        .map(|(n, x)| (x.map(|v| (v / q).round() as i64), n))
        .collect();
    keys.sort_unstable();
    let pairs: Vec<usize> = keys
        .windows(2)
        .filter(|w| w[0].0 == w[1].0)
        .map(|w| w[0].1)
        .collect();
    let &first = pairs.first()?;
    Some(format!(
        "{} nodes share their position with another node (the first at {:?}): the mesh is cut \
         there and the cells on either side are not connected (a crack, or geometry that was not \
         merged with Coherence / BooleanFragments)",
        pairs.len(),
        mesh.coords[first]
    ))
}

/// A tetrahedron of [`kuhn_tetrahedra`]: the cube (i, j, k) it is in, and its four nodes.
#[cfg(test)]
pub(crate) type CubeTet = ([usize; 3], [usize; 4]);

/// For the tests: the cube [0, n]³ of n³ unit cubes, each cut into six tetrahedra about its
/// diagonal (Kuhn's triangulation, the same in every cube, so conforming). The grid's nodes,
/// numbered x fastest (node i + (n + 1)(j + (n + 1)k) at (i, j, k)), and each tetrahedron
/// (of positive volume) with the cube (i, j, k) it is in.
#[cfg(test)]
pub(crate) fn kuhn_tetrahedra(n: usize) -> (Vec<[f64; 3]>, Vec<CubeTet>) {
    let id = |[i, j, k]: [usize; 3]| (k * (n + 1) + j) * (n + 1) + i;
    let grid = |m: usize| {
        (0..m).flat_map(move |k| (0..m).flat_map(move |j| (0..m).map(move |i| [i, j, k])))
    };
    let coords = grid(n + 1).map(|p| p.map(|c| c as f64)).collect();
    let paths = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut tets = Vec::new();
    for cube in grid(n) {
        for path in paths {
            // from the cube's first corner to its last, one axis at a time
            let mut at = cube;
            let mut tet = [id(cube); 4];
            for (v, axis) in path.into_iter().enumerate() {
                at[axis] += 1;
                tet[v + 1] = id(at);
            }
            // positive volume: an odd permutation of the axes turns it over
            if matches!(path, [0, 2, 1] | [1, 0, 2] | [2, 1, 0]) {
                tet.swap(2, 3);
            }
            tets.push((cube, tet));
        }
    }
    (coords, tets)
}
