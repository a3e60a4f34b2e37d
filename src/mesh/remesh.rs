//! The medium's cells made again between the bodies as they are: each medium region's cells
//! are replaced by new ones covering the region at the nodes' current places, between the
//! region's boundary nodes, which stay the nodes they are (the solids' faces, the medium's
//! outer faces), refined inside where it is open. This is topology and geometry only: what
//! the new cells carry is `model/remake.rs`'s.
//!
//! In 2D the new cells are the triangles of a constrained Delaunay triangulation, spade's, in
//! this process: gmsh, forked for each remake, took 10–25 ms of a remake's 16–45 ms on the
//! sliding cylinder, the triangulation takes about 1 ms (docs/notes/2026-12-02-remake-cost.md).
//! In 3D they are gmsh's tetrahedra between the region's boundary triangles, each closed
//! shell a discrete surface gmsh keeps as it is; the medium's own plane faces (a symmetry
//! plane) are triangulated again first (`plane_faces.rs`).

use super::{Block, CellKind, Mesh};
use std::collections::HashMap;

/// Which of gmsh's tetrahedral meshers fills a 3D medium first (the other where it fails).
/// Each leaves, now and then, a medium from which no step converges where the other's goes on
/// (the square pad in 3D at μ = 0.5 stopped at a slide of 0.24 on Delaunay's cells and slid
/// its width on HXT's, which stop the hemisphere sooner than Delaunay's;
/// docs/notes/2026-12-04-the-other-mesher-where-a-3d-drag-sticks.md), so the remake at a state
/// a run stuck at is HXT's. HXT's cells depend on the addresses it works at (the same faces,
/// two calls in one process: other cells), so it meshes in a process of its own started with
/// the address space's randomisation off, where they are the same each time
/// (`gmsh::mesh_geo_apart`); Delaunay, the same each time in the meshing child, comes first.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mesher {
    /// gmsh's Delaunay (`Mesh.Algorithm3D = 1`), HXT where it leaves a flat tetrahedron.
    #[default]
    Delaunay,
    /// gmsh's HXT (`Mesh.Algorithm3D = 10`), Delaunay where it fails.
    Hxt,
}

impl Mesher {
    /// The other one.
    pub fn other(self) -> Mesher {
        match self {
            Mesher::Delaunay => Mesher::Hxt,
            Mesher::Hxt => Mesher::Delaunay,
        }
    }

    /// Its name, for the console.
    pub fn name(self) -> &'static str {
        match self {
            Mesher::Delaunay => "gmsh's Delaunay",
            Mesher::Hxt => "gmsh's HXT",
        }
    }

    /// gmsh's `Mesh.Algorithm3D` numbers, in the order tried.
    fn algorithms(self) -> [u32; 2] {
        match self {
            Mesher::Delaunay => [DELAUNAY, HXT],
            Mesher::Hxt => [HXT, DELAUNAY],
        }
    }
}

/// Delaunay's and HXT's numbers in gmsh's `Mesh.Algorithm3D`.
const DELAUNAY: u32 = 1;
const HXT: u32 = 10;

/// Why a medium could not be made again: its shape (its boundary crosses itself, a body
/// passed the end of its base) or the mesher, which may mesh the next state (`mesher`).
#[derive(Clone, Debug, PartialEq)]
pub struct RemeshError {
    pub why: String,
    pub mesher: bool,
}

impl RemeshError {
    fn mesher(why: String) -> RemeshError {
        RemeshError { why, mesher: true }
    }
}

impl From<String> for RemeshError {
    fn from(why: String) -> RemeshError {
        RemeshError { why, mesher: false }
    }
}

impl From<&str> for RemeshError {
    fn from(why: &str) -> RemeshError {
        RemeshError::from(why.to_owned())
    }
}

impl std::fmt::Display for RemeshError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.why)
    }
}

impl std::error::Error for RemeshError {}

/// A mesh whose medium regions were made again.
pub struct Remeshed {
    pub mesh: Mesh,
    /// Per node of the new mesh, the node of the old one it is; `None` for a new node inside
    /// the medium.
    pub old_of: Vec<Option<usize>>,
    /// The new mesh's medium blocks (indices into its `cells`).
    pub medium: Vec<usize>,
}

/// A region's boundary edges (corner nodes, the region on their left in the current places),
/// and the closed loops they make; an error says why they make none.
pub fn boundary_loops(mesh: &Mesh, blocks: &[usize]) -> Result<Vec<Vec<usize>>, String> {
    let mut edges: HashMap<(usize, usize), (usize, usize, usize)> = HashMap::new();
    for &b in blocks {
        let blk = &mesh.cells[b];
        let k = blk.kind.corners();
        for c in 0..blk.n_cells() {
            let cell = blk.cell(c);
            for i in 0..k {
                let (a, b) = (cell[i], cell[(i + 1) % k]);
                let e = edges.entry((a.min(b), a.max(b))).or_insert((a, b, 0));
                e.2 += 1;
            }
        }
    }
    let mut next: HashMap<usize, usize> = HashMap::new();
    for &(a, b, count) in edges.values() {
        if count == 1 && next.insert(a, b).is_some() {
            return Err(format!(
                "the medium's boundary passes twice through node {a} (two parts of the medium \
                 touch at a point)"
            ));
        }
    }
    let mut starts: Vec<usize> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen = std::collections::HashSet::new();
    let mut loops = Vec::new();
    for s in starts {
        if seen.contains(&s) {
            continue;
        }
        let mut lp = vec![s];
        seen.insert(s);
        let mut n = next[&s];
        while n != s {
            if !seen.insert(n) {
                return Err(format!("the medium's boundary does not close at node {n}"));
            }
            lp.push(n);
            n = *next
                .get(&n)
                .ok_or_else(|| format!("the medium's boundary ends at node {n}"))?;
        }
        loops.push(lp);
    }
    Ok(loops)
}

/// The mesh `mesh` with the cells of its medium blocks `medium` made again at the nodes'
/// places `x`: the blocks of each set of physical groups meshed together as one region,
/// between their boundary nodes; triangles in 2D (spade, in this process), tetrahedra in 3D
/// (gmsh, between the region's boundary triangles, `mesher` first). Linear cells only (a
/// caller checks first with [`supported`]). In 3D each region's new cells come in two
/// blocks: those apart from the solids and those beside one (a node `on_solid`, per node of
/// `mesh`), as `Model::made_again` weighs them.
pub fn remesh(
    mesh: &Mesh,
    x: &[[f64; 3]],
    medium: &[usize],
    on_solid: &[bool],
    mesher: Mesher,
) -> Result<Remeshed, RemeshError> {
    let regions = regions_of(mesh, medium);
    let mut given = Vec::new();
    let mut facets = mesh.facets.clone();
    let (made, mut on_boundary, kind) = match mesh.dim {
        3 => {
            let mut faces = Vec::with_capacity(regions.len());
            for r in &regions {
                let own = super::faces::outer_triangles(mesh, &r.1)?;
                faces.push(super::plane_faces::own_planes_again(
                    mesh,
                    medium,
                    own,
                    &mut facets,
                    x,
                ));
            }
            let made = tetrahedralize_between(&faces, x, mesher).map_err(RemeshError::mesher)?;
            let nodes: Vec<usize> = faces.iter().flatten().flatten().copied().collect();
            given = faces;
            (made, nodes, CellKind::Tet4)
        }
        _ => {
            let loops: Vec<Vec<Vec<usize>>> = (regions.iter())
                .map(|r| boundary_loops(mesh, &r.1))
                .collect::<Result<_, _>>()?;
            let made = triangulate_between(&loops, x)?;
            let nodes: Vec<usize> = loops.iter().flatten().flatten().copied().collect();
            (made, nodes, CellKind::Tri3)
        }
    };
    // the boundary nodes, found again by their places
    on_boundary.sort_unstable();
    on_boundary.dedup();
    let find = finder(x, &on_boundary);
    let (new_of, mut old_of, mut coords) = kept_nodes(mesh, medium, &facets, &on_boundary);
    // the made mesh's nodes: a boundary node is the old one, any other is new
    let mut made_to_new = Vec::with_capacity(made.coords.len());
    for &p in &made.coords {
        match find(p) {
            Some(n) => made_to_new.push(new_of[n]),
            None => {
                made_to_new.push(coords.len());
                coords.push(p);
                old_of.push(None);
            }
        }
    }
    let remap = |blk: &Block| Block {
        kind: blk.kind,
        groups: blk.groups.clone(),
        conn: blk.conn.iter().map(|&n| new_of[n]).collect(),
    };
    let mut cells: Vec<Block> = (mesh.cells.iter().enumerate())
        .filter(|(b, _)| !medium.contains(b))
        .map(|(_, blk)| remap(blk))
        .collect();
    let mut new_medium = Vec::new();
    // in 3D the cells beside a solid (a node on one) apart from the rest: they weigh the
    // rotation penalty less (`Model::made_again`); a medium not made again is no solid
    let new_on_solid = (mesh.dim == 3).then(|| {
        let mut on = vec![false; coords.len()];
        for (n, _) in on_solid.iter().enumerate().filter(|(_, s)| **s) {
            if let Some(v) = on.get_mut(new_of[n]) {
                *v = true;
            }
        }
        on
    });
    for (r, (groups, _)) in regions.iter().enumerate() {
        let name = format!("medium{r}");
        let g = made
            .group(&name)
            .ok_or("no cells were made in a medium region")?;
        let mut conn = Vec::new();
        for blk in made.cells.iter().filter(|b| b.groups.contains(&g)) {
            if blk.kind != kind {
                return Err(RemeshError::mesher(format!(
                    "{} cells were made, not {}",
                    blk.kind.name(),
                    kind.name()
                )));
            }
            conn.extend(blk.conn.iter().map(|&n| made_to_new[n]));
        }
        if conn.contains(&usize::MAX) {
            return Err("a boundary node of the medium was not kept".into());
        }
        if let Some(faces) = given.get(r) {
            same_boundary(faces, &conn, &new_of).map_err(RemeshError::mesher)?;
        }
        let parts = match &new_on_solid {
            Some(on) => beside_and_apart(conn, kind.n_nodes(), on),
            None => [conn, Vec::new()],
        };
        for conn in parts.into_iter().filter(|c| !c.is_empty()) {
            new_medium.push(cells.len());
            cells.push(Block {
                kind,
                groups: groups.clone(),
                conn,
            });
        }
    }
    let facets = facets.iter().map(remap).collect();
    let new = Mesh {
        dim: mesh.dim,
        coords,
        cells,
        facets,
        groups: mesh.groups.clone(),
        source: mesh.source.clone(),
        warnings: Vec::new(),
    };
    Ok(Remeshed {
        mesh: new,
        old_of,
        medium: new_medium,
    })
}

/// The cells of `conn` (`n` nodes each) apart from those beside a body (a node `on` one), and
/// those beside one, each in the order they had.
fn beside_and_apart(conn: Vec<usize>, n: usize, on: &[bool]) -> [Vec<usize>; 2] {
    let (mut apart, mut beside) = (Vec::new(), Vec::new());
    for cell in conn.chunks(n) {
        match cell.iter().any(|&v| on[v]) {
            true => beside.extend_from_slice(cell),
            false => apart.extend_from_slice(cell),
        }
    }
    [apart, beside]
}

/// The medium blocks `medium` grouped by their physical groups: (groups, blocks) per region.
fn regions_of(mesh: &Mesh, medium: &[usize]) -> Vec<(Vec<usize>, Vec<usize>)> {
    let mut regions: Vec<(Vec<usize>, Vec<usize>)> = Vec::new();
    for &b in medium {
        let groups = &mesh.cells[b].groups;
        match regions.iter_mut().find(|r| &r.0 == groups) {
            Some(r) => r.1.push(b),
            None => regions.push((groups.clone(), vec![b])),
        }
    }
    regions
}

/// Twice the signed area of loop `lp` at the places `x` (positive: counter-clockwise).
fn signed_area(lp: &[usize], x: &[[f64; 3]]) -> f64 {
    (0..lp.len())
        .map(|i| {
            let (p, q) = (x[lp[i]], x[lp[(i + 1) % lp.len()]]);
            p[0] * q[1] - q[0] * p[1]
        })
        .sum()
}

/// The triangles of a constrained Delaunay triangulation between the boundary `loops` (nodes
/// at their places `x`; the region is where a point is inside an odd number of loops),
/// refined inside (Ruppert's refinement, spade's): no boundary edge split, no angle below 30°
/// where the boundary allows it, none larger than an equilateral triangle on the median
/// boundary edge (the longest would follow the medium's free faces as they are stretched,
/// remake after remake); triangles smaller than one on a tenth of the shortest edge are left as
/// they are (a closed layer's, one cell across between the bodies' faces); a body's corner
/// pressed onto another's face is joined over that face's edges (`fans`). One region per
/// entry of `loops`, its cells in group `medium{r}`, counter-clockwise.
fn triangulate_between(loops: &[Vec<Vec<usize>>], x: &[[f64; 3]]) -> Result<Mesh, String> {
    use spade::{AngleLimit, RefinementParameters, Triangulation};
    let mut coords: Vec<[f64; 3]> = Vec::new();
    let mut cells = Vec::new();
    let mut groups = Vec::new();
    let equilateral = 3f64.sqrt() / 4.0;
    for (r, region) in loops.iter().enumerate() {
        let (mut cdt, vertex, mut lengths) = boundary_of(region, x)?;
        lengths.sort_by(f64::total_cmp);
        let (shortest, median) = (lengths[0], lengths[lengths.len() / 2]);
        let largest = equilateral * median * median;
        // the nodes the refinement may add: spade's default, ten times the boundary's, is too
        // few where the region's area grows faster than its boundary (a mesh made finer);
        // the loops turn with the region on their left, so their signed areas sum to its own
        let area = 0.5 * region.iter().map(|lp| signed_area(lp, x)).sum::<f64>();
        let inside = (4.0 * area.abs() / largest).ceil() as usize;
        let params = RefinementParameters::<f64>::new()
            .exclude_outer_faces(true)
            .keep_constraint_edges()
            .with_angle_limit(AngleLimit::from_deg(30.0))
            .with_max_allowed_area(largest)
            .with_min_required_area(equilateral * (0.1 * shortest).powi(2))
            .with_max_additional_vertices(10 * vertex.len() + inside);
        let refined = cdt.refine(params);
        if !refined.refinement_complete {
            return Err(format!(
                "its triangles' refinement stopped at {} nodes, the most it may add to the {} \
                 of its boundary",
                cdt.num_vertices(),
                vertex.len()
            ));
        }
        let inside = fanned_inside(&mut cdt, region, &vertex, x);
        let first = coords.len();
        coords.extend(
            cdt.vertices()
                .map(|v| [v.position().x, v.position().y, 0.0]),
        );
        let mut conn = Vec::new();
        for f in cdt.inner_faces().filter(|f| inside[f.fix().index()]) {
            conn.extend(f.vertices().map(|v| first + v.fix().index()));
        }
        groups.push(super::PhysicalGroup {
            name: format!("medium{r}"),
            dim: 2,
            tag: r as i32 + 1,
        });
        cells.push(Block {
            kind: CellKind::Tri3,
            groups: vec![r],
            conn,
        });
    }
    Ok(Mesh {
        dim: 2,
        coords,
        cells,
        facets: Vec::new(),
        groups,
        source: std::path::PathBuf::from("medium"),
        warnings: Vec::new(),
    })
}

/// The constrained Delaunay triangulation of a region's boundary `region` (closed loops of
/// nodes at their places `x`): the triangulation, its vertex of each node, and the lengths of
/// the boundary's edges; an error where two nodes stand at one place, the boundary crosses
/// itself or a node stands on one of its edges.
#[allow(clippy::type_complexity)]
fn boundary_of(
    region: &[Vec<usize>],
    x: &[[f64; 3]],
) -> Result<
    (
        spade::ConstrainedDelaunayTriangulation<spade::Point2<f64>>,
        HashMap<usize, spade::handles::FixedVertexHandle>,
        Vec<f64>,
    ),
    String,
> {
    use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let mut vertex: HashMap<usize, spade::handles::FixedVertexHandle> = HashMap::new();
    let mut lengths = Vec::new();
    for lp in region {
        for &n in lp {
            if vertex.contains_key(&n) {
                continue;
            }
            let before = cdt.num_vertices();
            let v = (cdt.insert(Point2::new(x[n][0], x[n][1])))
                .map_err(|e| format!("node {n} at {:?}: {e:?}", x[n]))?;
            if cdt.num_vertices() == before {
                return Err(format!(
                    "two of the medium's boundary nodes stand at one place, {:?}",
                    x[n]
                ));
            }
            vertex.insert(n, v);
        }
    }
    for lp in region {
        for i in 0..lp.len() {
            let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
            let l = (0..2).map(|k| (x[a][k] - x[b][k]).powi(2)).sum::<f64>();
            lengths.push(l.sqrt());
            let (va, vb) = (vertex[&a], vertex[&b]);
            if !cdt.can_add_constraint(va, vb) {
                return Err(format!(
                    "the medium's boundary crosses itself at its edge from {:?} to {:?}",
                    x[a], x[b]
                ));
            }
            cdt.add_constraint(va, vb);
            if cdt.get_edge_from_neighbors(va, vb).is_none() {
                return Err(format!(
                    "a node stands on the medium's boundary edge from {:?} to {:?}",
                    x[a], x[b]
                ));
            }
        }
    }
    Ok((cdt, vertex, lengths))
}

/// The region's corners pressed on faces joined over them in `cdt` (`fans`, `joined_ahead`;
/// `vertex` the triangulation's vertex of each boundary node), then which of its faces lie
/// inside the region the loops `region` bound (`inside_faces`).
fn fanned_inside(
    cdt: &mut spade::ConstrainedDelaunayTriangulation<spade::Point2<f64>>,
    region: &[Vec<usize>],
    vertex: &HashMap<usize, spade::handles::FixedVertexHandle>,
    x: &[[f64; 3]],
) -> Vec<bool> {
    let walls: std::collections::HashSet<(usize, usize)> = (region.iter())
        .flat_map(|lp| (0..lp.len()).map(move |i| (lp[i], lp[(i + 1) % lp.len()])))
        .map(|(a, b)| {
            let (i, j) = (vertex[&a].index(), vertex[&b].index());
            (i.min(j), i.max(j))
        })
        .collect();
    let corner = corners(region, x);
    for (n, m) in fans(&corner, x).into_iter().chain(joined_ahead(&corner, x)) {
        let (vn, vm) = (vertex[&n], vertex[&m]);
        if cdt.can_add_constraint(vn, vm) {
            cdt.add_constraint(vn, vm);
        }
    }
    inside_faces(cdt, &walls)
}

/// Which faces of `cdt` (by index) lie inside the region whose boundary edges are `walls`
/// (pairs of vertex indices, the smaller first): reached from the outside, a face is inside
/// after crossing an odd number of them. Other constraint edges (`fans`) do not count.
fn inside_faces<T: spade::Triangulation>(
    cdt: &T,
    walls: &std::collections::HashSet<(usize, usize)>,
) -> Vec<bool> {
    let n = cdt.num_all_faces();
    let mut inside: Vec<Option<bool>> = vec![None; n];
    let mut across: Vec<Vec<(usize, bool)>> = vec![Vec::new(); n];
    let mut stack = Vec::new();
    for f in cdt.inner_faces() {
        let i = f.fix().index();
        for e in f.adjacent_edges() {
            let (a, b) = (e.from().fix().index(), e.to().fix().index());
            let wall = walls.contains(&(a.min(b), a.max(b)));
            match e.rev().face().as_inner() {
                Some(g) => across[i].push((g.fix().index(), wall)),
                None if inside[i].is_none() => {
                    inside[i] = Some(wall);
                    stack.push(i);
                }
                None => {}
            }
        }
    }
    while let Some(i) = stack.pop() {
        let here = inside[i].expect("set before pushed");
        for &(g, wall) in &across[i] {
            if inside[g].is_none() {
                inside[g] = Some(here ^ wall);
                stack.push(g);
            }
        }
    }
    inside.into_iter().map(|v| v.unwrap_or(false)).collect()
}

/// The medium-side angle of a boundary loop's corner at `v` (from the edge to its next node
/// turning counter-clockwise to the edge from its last, the region on the loop's left).
fn medium_angle(prev: [f64; 3], v: [f64; 3], next: [f64; 3]) -> f64 {
    let a = (next[1] - v[1]).atan2(next[0] - v[0]);
    let b = (prev[1] - v[1]).atan2(prev[0] - v[0]);
    (b - a).rem_euclid(std::f64::consts::TAU)
}

/// Twice the signed area of the triangle (a, b, c).
fn orient(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
}

/// How much larger a corner's medium-side angle is than that of the node it is pressed on
/// for it to be joined over that node's edges (`fans`): a body's corner (a right angle's
/// 270° on a face's 180°), not the facets of a curved face (a few degrees apart).
const SHARPER: f64 = std::f64::consts::FRAC_PI_4;

/// Where two boundary nodes of a region stand closer than a quarter of the edges at one of
/// them (`m`), the other (`n`, a body's corner pressed onto a face) is joined to `m` and to
/// both of `m`'s neighbours, so that the cells at the contact are a node over the face, which
/// stay whole as the node slides along it, and not a sliver between the corner's own faces
/// and `m`, which a slide turns inside out. Of two such nodes the one whose medium-side angle
/// is the larger (the sharper corner of its body) is the one joined over the other's edges.
/// `corner`: the region's boundary nodes as [`corners`] gives them.
fn fans(corner: &[Corner], x: &[[f64; 3]]) -> Vec<(usize, usize)> {
    let dist = |a: usize, b: usize| (x[a][0] - x[b][0]).hypot(x[a][1] - x[b][1]);
    // the corners by squares as wide as the farthest reach, to look only at the next ones
    let side = corner
        .iter()
        .fold(0.0f64, |r, c| r.max(c.3))
        .max(f64::MIN_POSITIVE);
    let square = |n: usize| {
        [
            (x[n][0] / side).floor() as i64,
            (x[n][1] / side).floor() as i64,
        ]
    };
    let mut by_square: HashMap<[i64; 2], Vec<usize>> = HashMap::new();
    for (k, c) in corner.iter().enumerate() {
        by_square.entry(square(c.1)).or_default().push(k);
    }
    let mut out = Vec::new();
    for &(p, m, q, reach, angle) in corner {
        let [i, j] = square(m);
        let near = (-1..=1).flat_map(|a| (-1..=1).map(move |b| [i + a, j + b]));
        for k in near.flat_map(|s| by_square.get(&s).into_iter().flatten()) {
            let (_, n, _, _, other) = corner[*k];
            if n == m || n == p || n == q || dist(n, m) >= reach || other <= angle + SHARPER {
                continue;
            }
            if orient(x[p], x[m], x[n]) > 0.0 && orient(x[m], x[q], x[n]) > 0.0 {
                out.extend([(n, p), (n, m), (n, q)]);
            }
        }
    }
    out
}

/// A boundary node with its neighbours along its loop, its reach and its medium-side angle
/// (see [`corners`]).
type Corner = (usize, usize, usize, f64, f64);

/// Each boundary node `v` of the loops `region`, in their order, with its last and next
/// nodes along its loop and a quarter of its shorter edge: (last, v, next, reach, the
/// medium-side angle at v).
fn corners(region: &[Vec<usize>], x: &[[f64; 3]]) -> Vec<Corner> {
    let dist = |a: usize, b: usize| (x[a][0] - x[b][0]).hypot(x[a][1] - x[b][1]);
    let mut corner = Vec::new();
    for lp in region {
        let k = lp.len();
        for i in 0..k {
            let (p, v, q) = (lp[(i + k - 1) % k], lp[i], lp[(i + 1) % k]);
            let reach = 0.25 * dist(p, v).min(dist(v, q));
            corner.push((p, v, q, reach, medium_angle(x[p], x[v], x[q])));
        }
    }
    corner
}

/// Where a body's corner `c` (a medium-side angle [`SHARPER`] past a straight one) stands
/// over the edge (a, b) of another face, at most a quarter of the edges there above it, the
/// pairs that join it also over that face's next edge on its open side (away from the
/// corner's own face along the layer): (c, b) and (c, b's next node). Made by Delaunay's
/// rule alone, the cell ahead of the corner is (c, b, a node above): as the corner slides
/// towards b it closes to nothing and drags b along (the pad in a box at μ = 0.3 met 0.331
/// of its normal force there, the plate's node under the corner carrying a shear of 0.51 at
/// a pressure of 0.96); joined over b's next edge, the cell is a layer's, whose thickness
/// the slide keeps, until the medium is made again after the corner passes b
/// (docs/notes/2026-12-05-a-corner-joined-ahead-and-one-remake-before-a-pass.md).
/// `around`: the region's boundary nodes as [`corners`] gives them.
fn joined_ahead(around: &[Corner], x: &[[f64; 3]]) -> Vec<(usize, usize)> {
    let dist = |a: usize, b: usize| (x[a][0] - x[b][0]).hypot(x[a][1] - x[b][1]);
    let last: HashMap<usize, usize> = around.iter().map(|&(l, n, ..)| (n, l)).collect();
    let next: HashMap<usize, usize> = around.iter().map(|&(_, n, m, ..)| (n, m)).collect();
    let mut out = Vec::new();
    for &(p, c, q, reach, angle) in around {
        if angle < std::f64::consts::PI + SHARPER {
            continue;
        }
        // the edge (a, b), a loop's edge in its order, that c stands closest over, its foot
        // on the edge
        let mut over: Option<(f64, usize, usize)> = None;
        for &(_, a, b, ..) in around {
            if [a, b].iter().any(|n| [c, p, q].contains(n)) {
                continue;
            }
            let l = dist(a, b);
            let (t, height) = (along(x[a], x[b], x[c]), orient(x[a], x[b], x[c]) / l);
            let close = height > 0.0 && height <= reach.min(0.25 * l);
            if (0.0..=1.0).contains(&t) && close && over.is_none_or(|(h, ..)| height < h) {
                over = Some((height, a, b));
            }
        }
        let Some((_, a, b)) = over else { continue };
        // the corner's own face along the layer is its side nearer the edge's line
        let off = |n: usize| orient(x[a], x[b], x[n]).abs();
        let own = if off(p) < off(q) { p } else { q };
        let (near, beyond) = match along(x[a], x[b], x[own]) < along(x[a], x[b], x[c]) {
            true => (b, next[&b]),
            false => (a, last[&a]),
        };
        // the edge beyond in its loop's order, with the corner on its medium side
        let (from, to) = if near == b {
            (near, beyond)
        } else {
            (beyond, near)
        };
        if beyond != c && orient(x[from], x[to], x[c]) > 0.0 {
            out.extend([(c, near), (c, beyond)]);
        }
    }
    out
}

/// Where the foot of `c` stands along the edge from `a` to `b` (in their plane x, y): 0 at a,
/// 1 at b (0 on an edge of no length).
pub(crate) fn along(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let length2 = ab[0] * ab[0] + ab[1] * ab[1];
    ((c[0] - a[0]) * ab[0] + (c[1] - a[1]) * ab[1]) / length2.max(f64::MIN_POSITIVE)
}

/// Whether the tetrahedra `conn` (new node numbers) have the boundary `faces` (old node
/// numbers, `new_of` the new number of each): a mesher that split a boundary face would leave
/// the solid beside it joined to the medium by nothing.
fn same_boundary(faces: &[[usize; 3]], conn: &[usize], new_of: &[usize]) -> Result<(), String> {
    let tets = Mesh::of_cells(
        3,
        Vec::new(),
        vec![Block {
            kind: CellKind::Tet4,
            groups: Vec::new(),
            conn: conn.to_vec(),
        }],
    );
    let key = super::faces::triangle_key;
    let mut made: Vec<[usize; 3]> = super::faces::outer_triangles(&tets, &[0])?
        .into_iter()
        .map(key)
        .collect();
    let mut wanted: Vec<[usize; 3]> = faces.iter().map(|f| key(f.map(|n| new_of[n]))).collect();
    made.sort_unstable();
    wanted.sort_unstable();
    match made == wanted {
        true => Ok(()),
        false => Err(format!(
            "the new tetrahedra do not keep the medium's boundary ({} faces of {} kept)",
            made.iter()
                .filter(|f| wanted.binary_search(f).is_ok())
                .count(),
            wanted.len()
        )),
    }
}

/// The closed shells of the triangles `faces`: those joined by their edges.
fn shells_of(faces: &[[usize; 3]]) -> Vec<Vec<[usize; 3]>> {
    (super::faces::joined_by_edges(faces, |_, _| true).into_iter())
        .map(|members| members.into_iter().map(|i| faces[i]).collect())
        .collect()
}

/// Six times the volume the triangle `f` (at the places `x`) closes with the origin: summed
/// over a closed shell turned outward, six times the volume it holds.
fn held_volume(x: &[[f64; 3]], f: [usize; 3]) -> f64 {
    let [a, b, c] = f.map(|n| x[n]);
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// A folder for one remake's files, removed with what is in it when dropped.
struct Scratch(std::path::PathBuf);

impl Scratch {
    fn new() -> Result<Scratch, String> {
        static COUNT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("tmc-remake-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        Ok(Scratch(dir))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The tetrahedra gmsh makes between the boundary triangles `faces` of each region (nodes at
/// their places `x`), which it keeps as they are (a discrete surface is not meshed again): the
/// region is what they enclose, its cells in group `medium{r}`. gmsh runs in a child process
/// (`mesh::gmsh::mesh_geo`), on files in a folder of its own.
fn tetrahedralize_between(
    faces: &[Vec<[usize; 3]>],
    x: &[[f64; 3]],
    mesher: Mesher,
) -> Result<Mesh, String> {
    use std::fmt::Write;
    let mut number: HashMap<usize, usize> = HashMap::new();
    let mut nodes = String::new();
    for &n in faces.iter().flatten().flatten() {
        if !number.contains_key(&n) {
            number.insert(n, number.len() + 1);
            let p = x[n];
            let _ = writeln!(nodes, "{} {:e} {:e} {:e}", number.len(), p[0], p[1], p[2]);
        }
    }
    // each closed shell of a region's boundary a surface of its own: gmsh tells the medium
    // from the holes in it (the bodies) by its surface loops
    let mut elements = String::new();
    let (mut count, mut surface) = (0, 0);
    let mut loops = String::from("Merge \"boundary.msh\";\n");
    for (r, region) in faces.iter().enumerate() {
        if region.is_empty() {
            return Err("a medium region has no boundary".into());
        }
        let mut shells = shells_of(region);
        // the outer shell first: its faces turn outward from what it holds (a positive
        // volume), a hole's inward
        let held = |s: &Vec<[usize; 3]>| -> f64 { s.iter().map(|f| held_volume(x, *f)).sum() };
        shells.sort_by(|a, b| held(b).total_cmp(&held(a)));
        let first = surface + 1;
        for shell in &shells {
            surface += 1;
            for f in shell {
                count += 1;
                let [a, b, c] = f.map(|n| number[&n]);
                let _ = writeln!(elements, "{count} 2 2 0 {surface} {a} {b} {c}");
            }
            let _ = writeln!(loops, "Surface Loop({surface}) = {{{surface}}};");
        }
        let all: Vec<String> = (first..=surface).map(|s| s.to_string()).collect();
        let _ = writeln!(
            loops,
            "Volume({v}) = {{{}}};\nPhysical Volume(\"medium{r}\") = {{{v}}};",
            all.join(", "),
            v = r + 1
        );
    }
    let msh = format!(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n{}\n{nodes}$EndNodes\n\
         $Elements\n{count}\n{elements}$EndElements\n",
        number.len()
    );
    let dir = Scratch::new()?;
    let write = |name: &str, text: &str| {
        let path = dir.0.join(name);
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
    };
    write("boundary.msh", &msh)?;
    let options = super::gmsh::MeshOptions {
        order: 1,
        ..Default::default()
    };
    // `mesher`, then the other where it fails (Delaunay leaves a flat tetrahedron where a
    // thin layer meets a plane face); one thread, so that a run and its restart make the same
    // cells
    let mut failed = Vec::new();
    for algorithm in mesher.algorithms() {
        let geo = format!("Mesh.Algorithm3D = {algorithm};\nGeneral.NumThreads = 1;\n{loops}");
        write("medium.geo", &geo)?;
        let (geo, msh) = (dir.0.join("medium.geo"), dir.0.join("medium.msh"));
        // HXT's cells depend on the addresses it works at: made apart, where they are alike
        let apart = (algorithm == HXT).then(|| super::gmsh::mesh_geo_apart(&geo, &msh));
        let made = match apart.flatten() {
            Some(made) => made,
            None => super::gmsh::mesh_geo(&geo, &msh, &options)
                .map(|made| made.mesh)
                .map_err(|e| e.to_string()),
        };
        match made {
            Ok(mesh) => return Ok(mesh),
            Err(e) => failed.push(e),
        }
    }
    Err(format!(
        "{}; and with {}: {}",
        failed[0],
        mesher.other().name(),
        failed[1]
    ))
}

/// The node of `nodes` standing at a place (to 1e-9 of the extent of `x`), if any.
fn finder(x: &[[f64; 3]], nodes: &[usize]) -> impl Fn([f64; 3]) -> Option<usize> {
    let scale = super::extent_of(x).max(f64::MIN_POSITIVE);
    let tol = 1e-9 * scale;
    let key = move |p: [f64; 3]| p.map(|v| (v / tol).round() as i64);
    let mut at: HashMap<[i64; 3], usize> = HashMap::new();
    for &n in nodes {
        at.insert(key(x[n]), n);
    }
    move |p: [f64; 3]| {
        let [i, j, k] = key(p);
        (-1..=1)
            .flat_map(|a| (-1..=1).flat_map(move |b| (-1..=1).map(move |c| [i + a, j + b, k + c])))
            .find_map(|q| at.get(&q).copied())
    }
}

/// The old nodes kept (those of every other cell, of the `facets` as the medium made again
/// has them, and of the medium's boundary `on_boundary`), numbered anew in their order: the
/// new number of each old node (`usize::MAX` if dropped), the old node of each new one, and
/// their coordinates.
#[allow(clippy::type_complexity)]
fn kept_nodes(
    mesh: &Mesh,
    medium: &[usize],
    facets: &[Block],
    on_boundary: &[usize],
) -> (Vec<usize>, Vec<Option<usize>>, Vec<[f64; 3]>) {
    let n_old = mesh.coords.len();
    let mut keep = mesh.nodes_in(|b| !medium.contains(&b));
    for blk in facets {
        blk.conn.iter().for_each(|&n| keep[n] = true);
    }
    on_boundary.iter().for_each(|&n| keep[n] = true);
    let mut new_of = vec![usize::MAX; n_old];
    let mut old_of = Vec::new();
    let mut coords = Vec::new();
    for n in (0..n_old).filter(|&n| keep[n]) {
        new_of[n] = coords.len();
        coords.push(mesh.coords[n]);
        old_of.push(Some(n));
    }
    (new_of, old_of, coords)
}

/// Whether the medium blocks `medium` of `mesh` can be made again, and if not, why.
pub fn supported(mesh: &Mesh, medium: &[usize]) -> Result<(), String> {
    for &b in medium {
        let kind = mesh.cells[b].kind;
        if kind.order() != 1 {
            return Err(format!(
                "works with linear cells only so far; this medium has {} cells",
                kind.name()
            ));
        }
        if mesh.dim == 3 && kind != CellKind::Tet4 {
            return Err(format!(
                "works in 3D with tetrahedra (tet4) only so far; this medium has {} cells \
                 (mesh the medium with tetrahedra: no Recombine on its volumes)",
                kind.name()
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether the point `p` is inside loop `lp` at the places `x` (crossing count).
    fn inside(p: [f64; 3], lp: &[usize], x: &[[f64; 3]]) -> bool {
        let mut odd = false;
        for i in 0..lp.len() {
            let (a, b) = (x[lp[i]], x[lp[(i + 1) % lp.len()]]);
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let s = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p[0] < s {
                    odd = !odd;
                }
            }
        }
        odd
    }

    /// A square of medium (4 × 4 quads over [0, 4]²) with a hole of one cell at its middle
    /// left out: the boundary is an outer loop (counter-clockwise) and a hole (clockwise).
    fn square_with_hole() -> Mesh {
        let mut coords = Vec::new();
        for j in 0..5 {
            for i in 0..5 {
                coords.push([i as f64, j as f64, 0.0]);
            }
        }
        let mut conn = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                if (i, j) == (1, 1) {
                    continue;
                }
                let n = j * 5 + i;
                conn.extend([n, n + 1, n + 6, n + 5]);
            }
        }
        Mesh::of_cells(
            2,
            coords,
            vec![Block {
                kind: CellKind::Quad4,
                groups: vec![0],
                conn,
            }],
        )
    }

    #[test]
    fn a_region_with_a_hole_has_an_outer_loop_and_a_hole() {
        let mesh = square_with_hole();
        let loops = boundary_loops(&mesh, &[0]).unwrap();
        assert_eq!(loops.len(), 2);
        let areas: Vec<f64> = loops.iter().map(|l| signed_area(l, &mesh.coords)).collect();
        let mut sorted = areas.clone();
        sorted.sort_by(f64::total_cmp);
        assert_eq!(sorted, vec![-2.0, 32.0]);
        let hole = &loops[areas.iter().position(|&a| a < 0.0).unwrap()];
        let outer = &loops[areas.iter().position(|&a| a > 0.0).unwrap()];
        assert_eq!(outer.len(), 16);
        assert!(inside(mesh.coords[hole[0]], outer, &mesh.coords));
        assert!(!inside([5.0, 1.0, 0.0], outer, &mesh.coords));
    }

    #[test]
    fn the_medium_made_again_keeps_its_boundary_and_covers_its_area() {
        let mut mesh = square_with_hole();
        mesh.groups.push(crate::mesh::PhysicalGroup {
            name: "medium".into(),
            dim: 2,
            tag: 1,
        });
        // the nodes moved: a shear of the whole square
        let x: Vec<[f64; 3]> = (mesh.coords.iter())
            .map(|p| [p[0] + 0.3 * p[1], p[1], 0.0])
            .collect();
        let on_solid = mesh.nodes_in(|b| b != 0);
        let r = remesh(&mesh, &x, &[0], &on_solid, Mesher::Delaunay).unwrap();
        // the 20 boundary nodes kept, the 5 inside the medium made again
        let kept = r.old_of.iter().filter(|o| o.is_some()).count();
        assert_eq!(kept, 20);
        let place = |n: usize| match r.old_of[n] {
            Some(o) => x[o],
            None => r.mesh.coords[n],
        };
        let blk = &r.mesh.cells[r.medium[0]];
        let areas: Vec<f64> = (0..blk.n_cells())
            .map(|c| {
                let q: Vec<[f64; 3]> = blk.cell(c).iter().map(|&n| place(n)).collect();
                0.5 * ((q[1][0] - q[0][0]) * (q[2][1] - q[0][1])
                    - (q[2][0] - q[0][0]) * (q[1][1] - q[0][1]))
            })
            .collect();
        assert!(areas.iter().all(|&a| a > 0.0));
        let area: f64 = areas.iter().sum();
        // every triangle counter-clockwise, together the sheared square less its hole
        assert!((area - 15.0).abs() < 1e-9, "area {area}");
    }

    /// Two rows of nodes `gap` apart, bottom (0..=n, 0) and top (n..=0, gap), closed at the
    /// ends: the region between as one loop.
    fn layer(n: usize, gap: f64) -> (Vec<Vec<usize>>, Vec<[f64; 3]>) {
        let mut x: Vec<[f64; 3]> = (0..=n).map(|i| [i as f64 * 0.1, 0.0, 0.0]).collect();
        // the top row shifted by a third of a cell, as a slid layer's is
        x.extend((0..=n).rev().map(|i| [(i as f64 + 0.3) * 0.1, gap, 0.0]));
        (vec![(0..x.len()).collect()], x)
    }

    #[test]
    fn a_closed_layer_is_made_one_cell_across() {
        // a layer closed to 1e-4 of its cells' length: no node inside it, each triangle with
        // corners on both rows, together its area
        let n = 10;
        let (lp, x) = layer(n, 1e-4);
        let made = triangulate_between(&[lp], &x).unwrap();
        assert_eq!(made.coords.len(), x.len(), "no node added");
        let blk = &made.cells[0];
        assert_eq!(blk.n_cells(), 2 * n);
        let mut area = 0.0;
        for c in 0..blk.n_cells() {
            let q: Vec<[f64; 3]> = blk.cell(c).iter().map(|&k| made.coords[k]).collect();
            assert!(q.iter().any(|p| p[1] == 0.0) && q.iter().any(|p| p[1] > 0.0));
            let a = 0.5
                * ((q[1][0] - q[0][0]) * (q[2][1] - q[0][1])
                    - (q[2][0] - q[0][0]) * (q[1][1] - q[0][1]));
            assert!(a > 0.0, "counter-clockwise");
            area += a;
        }
        // a trapezoid: the rows 1.0 long, the top shifted 0.03
        assert!((area - 1e-4).abs() < 1e-12, "area {area}");
    }

    #[test]
    fn an_open_region_is_filled_with_cells_of_its_boundary_s_size() {
        // a square of side 1, ten edges a side: nodes inside, triangles about as large as an
        // equilateral one on the boundary's edge (0.1), none with an angle below 30°
        let corner = |k: usize| [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]][k % 4];
        let x: Vec<[f64; 3]> = (0..40)
            .map(|i| {
                let (a, b, s) = (corner(i / 10), corner(i / 10 + 1), (i % 10) as f64 / 10.0);
                [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), 0.0]
            })
            .collect();
        let lp: Vec<usize> = (0..40).collect();
        let made = triangulate_between(&[vec![lp]], &x).unwrap();
        assert!(
            made.coords.len() > x.len() + 40,
            "{} nodes",
            made.coords.len()
        );
        let blk = &made.cells[0];
        let largest = 3f64.sqrt() / 4.0 * 0.1 * 0.1;
        let (mut area, mut most, mut sharpest) = (0.0, 0f64, 90f64);
        for c in 0..blk.n_cells() {
            let q: Vec<[f64; 3]> = blk.cell(c).iter().map(|&k| made.coords[k]).collect();
            let a = 0.5
                * ((q[1][0] - q[0][0]) * (q[2][1] - q[0][1])
                    - (q[2][0] - q[0][0]) * (q[1][1] - q[0][1]));
            assert!(a > 0.0, "cell {c}: {q:?}");
            most = most.max(a / largest);
            let l: Vec<f64> = (0..3)
                .map(|i| {
                    let (p, r) = (q[i], q[(i + 1) % 3]);
                    ((p[0] - r[0]).powi(2) + (p[1] - r[1]).powi(2)).sqrt()
                })
                .collect();
            // the smallest angle, opposite the shortest edge
            let (s, long) = (l[0].min(l[1]).min(l[2]), l[0].max(l[1]).max(l[2]));
            let mid = l[0] + l[1] + l[2] - s - long;
            let cos = (long * long + mid * mid - s * s) / (2.0 * long * mid);
            sharpest = sharpest.min(cos.acos().to_degrees());
            area += a;
        }
        // measured: 1.25 times the equilateral triangle at most (beside the boundary, whose
        // edges are not split), 30.6° the smallest angle
        assert!(most < 1.3 && sharpest > 30.0, "{most}, {sharpest}°");
        assert!((area - 1.0).abs() < 1e-9, "area {area}");
    }

    #[test]
    fn a_region_finer_than_ten_times_its_boundary_is_filled() {
        // a unit square of 100 edges a side (400 boundary nodes): its inside needs some
        // 11 000 nodes, more than the ten times the boundary that spade adds by default
        let corner = |k: usize| [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]][k % 4];
        let x: Vec<[f64; 3]> = (0..400)
            .map(|i| {
                let (a, b, s) = (
                    corner(i / 100),
                    corner(i / 100 + 1),
                    (i % 100) as f64 / 100.0,
                );
                [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), 0.0]
            })
            .collect();
        let made = triangulate_between(&[vec![(0..400).collect()]], &x).unwrap();
        assert!(made.coords.len() > 4400, "{} nodes", made.coords.len());
    }

    /// A plate's face (y = 0, nodes every 0.1 from 0 to 1) in a box 0.5 high, under a pad from
    /// x = `left` to `right`, 0.3 high, its bottom 5e-4 over the face with nodes at `bottom`
    /// too (its bottom right corner the hole's fifth node): the outer loop, the hole and the
    /// places.
    fn pad_over_plate(
        left: f64,
        right: f64,
        bottom: &[f64],
    ) -> (Vec<usize>, Vec<usize>, Vec<[f64; 3]>) {
        let mut x: Vec<[f64; 3]> = (0..=10).map(|i| [i as f64 * 0.1, 0.0, 0.0]).collect();
        x.extend([[1.0, 0.5, 0.0], [0.0, 0.5, 0.0]]);
        let outer: Vec<usize> = (0..x.len()).collect();
        let g = 5e-4;
        let first = x.len();
        let corners = [
            [left, g],
            [left, 0.3],
            [right, 0.3],
            [right, 0.1],
            [right, g],
        ];
        x.extend(corners.map(|p| [p[0], p[1], 0.0]));
        x.extend(bottom.iter().map(|&b| [b, g, 0.0]));
        (outer, (first..x.len()).collect(), x)
    }

    #[test]
    fn a_corner_pressed_past_a_face_s_node_is_joined_over_that_face() {
        // a plate's face (y = 0, nodes every 0.1) under a square pad whose bottom right corner
        // C stands 5e-4 over it, just past the plate's node B at x = 0.5: the cells at the
        // corner are C over the plate's edges beside B, and none joins B to the corner's own
        // faces (a sliver the slide turns inside out)
        let (outer, hole, x) = pad_over_plate(0.2, 0.505, &[0.4, 0.3]);
        let (b, c) = (5, hole[4]);
        let made = triangulate_between(&[vec![outer, hole]], &x).unwrap();
        let at = |n: usize| made.coords.iter().position(|p| *p == x[n]).unwrap();
        let blk = &made.cells[0];
        let cells: Vec<Vec<usize>> = (0..blk.n_cells()).map(|k| blk.cell(k).to_vec()).collect();
        let with = |n: &[usize]| -> Vec<&Vec<usize>> {
            let n: Vec<usize> = n.iter().map(|&k| at(k)).collect();
            cells
                .iter()
                .filter(|q| n.iter().all(|k| q.contains(k)))
                .collect()
        };
        assert_eq!(with(&[c, b, 4]).len(), 1, "C over the edge behind B");
        assert_eq!(with(&[c, b, 6]).len(), 1, "C over the edge ahead of B");
        assert_eq!(with(&[c, b]).len(), 2);
        // every cell counter-clockwise
        for q in &cells {
            let p: Vec<[f64; 3]> = q.iter().map(|&k| made.coords[k]).collect();
            assert!(orient(p[0], p[1], p[2]) > 0.0, "{p:?}");
        }
    }

    /// Whether `made` has a cell on the nodes `n` (by their places in `x`).
    fn has_cell(made: &Mesh, x: &[[f64; 3]], n: [usize; 3]) -> bool {
        let n = n.map(|k| made.coords.iter().position(|p| *p == x[k]).unwrap());
        let blk = &made.cells[0];
        (0..blk.n_cells()).any(|k| n.iter().all(|m| blk.cell(k).contains(m)))
    }

    #[test]
    fn a_corner_over_a_face_s_edge_is_joined_over_the_next_edge_on_its_open_side() {
        // the pad of the test above, its bottom right corner C 5e-4 over the middle of the
        // plate's edge from x = 0.4 to 0.5: C is over that edge and over the next one on its
        // open side (0.5 to 0.6), so that no cell ahead of it closes as it slides to 0.5;
        // behind it, under the pad, the layer is Delaunay's (C over no edge before 0.4)
        let (outer, hole, x) = pad_over_plate(0.15, 0.45, &[0.35, 0.25]);
        let c = hole[4];
        let made = triangulate_between(&[vec![outer.clone(), hole.clone()]], &x).unwrap();
        let has = |n: [usize; 3]| has_cell(&made, &x, n);
        let blk = &made.cells[0];
        assert!(has([4, 5, c]), "C over the edge it stands over");
        assert!(has([5, 6, c]), "C over the next edge ahead");
        assert!(!has([3, 4, c]), "C over no edge behind");
        for k in 0..blk.n_cells() {
            let p: Vec<[f64; 3]> = blk.cell(k).iter().map(|&n| made.coords[n]).collect();
            assert!(orient(p[0], p[1], p[2]) > 0.0, "{p:?}");
        }
        // the pad mirrored (its corner C at its left, open to the left): over 0.3 to 0.4
        let mirrored: Vec<[f64; 3]> = x.iter().map(|p| [1.0 - p[0], p[1], 0.0]).collect();
        let (outer, hole) = (
            outer.iter().rev().copied().collect(),
            hole.iter().rev().copied().collect(),
        );
        let made = triangulate_between(&[vec![outer, hole]], &mirrored).unwrap();
        let has = |n: [usize; 3]| has_cell(&made, &mirrored, n);
        assert!(
            has([5, 6, c]) && has([4, 5, c]),
            "C over its edge and the next ahead"
        );
        assert!(!has([3, 4, c]), "C over no edge behind");
    }

    #[test]
    fn boundary_nodes_at_one_place_are_refused() {
        let (lp, mut x) = layer(4, 1e-3);
        x[2] = x[1];
        let e = triangulate_between(&[lp], &x).unwrap_err();
        assert!(e.contains("stand at one place"), "{e}");
    }
}

#[cfg(test)]
mod tests3 {
    use super::*;

    /// The nodes of every block but the medium's (block 0).
    fn solid_nodes(mesh: &Mesh) -> Vec<bool> {
        mesh.nodes_in(|b| b != 0)
    }

    /// A cube [0, 4]³ of 4³ cubes cut into six tetrahedra each ([`crate::mesh::kuhn_tetrahedra`]):
    /// the medium, with a solid of the middle 2³ cubes, its own block.
    fn box_around_a_block() -> Mesh {
        let (coords, tets) = crate::mesh::kuhn_tetrahedra(4);
        let (mut medium, mut solid) = (Vec::new(), Vec::new());
        for (cube, tet) in tets {
            match cube.iter().all(|&c| (1..3).contains(&c)) {
                true => solid.extend(tet),
                false => medium.extend(tet),
            }
        }
        let block = |groups: Vec<usize>, conn: Vec<usize>| Block {
            kind: CellKind::Tet4,
            groups,
            conn,
        };
        let mut mesh = Mesh::of_cells(
            3,
            coords,
            vec![block(vec![0], medium), block(vec![1], solid)],
        );
        for (tag, name) in [(1, "medium"), (2, "solid")] {
            mesh.groups.push(crate::mesh::PhysicalGroup {
                name: name.into(),
                dim: 3,
                tag,
            });
        }
        mesh
    }

    fn volume(x: &[[f64; 3]], t: &[usize]) -> f64 {
        let d = |a: usize| [0, 1, 2].map(|i| x[t[a]][i] - x[t[0]][i]);
        let (u, v, w) = (d(1), d(2), d(3));
        (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
            + u[2] * (v[0] * w[1] - v[1] * w[0]))
            / 6.0
    }

    #[test]
    fn a_3d_medium_made_again_keeps_its_boundary_and_fills_its_volume() {
        let mesh = box_around_a_block();
        assert!(
            mesh.cells
                .iter()
                .all(|b| (0..b.n_cells()).all(|c| volume(&mesh.coords, b.cell(c)) > 0.0))
        );
        // the solid block slid 0.3 along x, its neighbours in the medium with it halfway
        let x: Vec<[f64; 3]> = (mesh.coords.iter())
            .map(|p| {
                let inside = p.iter().all(|&c| (1.0..=3.0).contains(&c));
                [p[0] + if inside { 0.3 } else { 0.0 }, p[1], p[2]]
            })
            .collect();
        let faces = crate::mesh::faces::outer_triangles(&mesh, &[0]).unwrap();
        // the box's 6 × 32 faces and the block's 6 × 8
        assert_eq!(faces.len(), 6 * 32 + 6 * 8);
        let [delaunay, hxt] =
            [Mesher::Delaunay, Mesher::Hxt].map(|m| either_mesher_fills_the_box(&mesh, &x, m));
        // the other mesher is another medium: what a run stuck on one's cells goes on with
        assert_ne!(delaunay, hxt);
    }

    /// Whether this kernel lets a process start with its addresses not randomised (a
    /// container's filter may not).
    fn fixed_addresses_allowed() -> bool {
        use std::os::unix::process::CommandExt;
        let mut t = std::process::Command::new("true");
        // SAFETY: one system call on the child between fork and exec
        unsafe {
            t.pre_exec(
                || match libc::personality(crate::mesh::gmsh::ADDR_NO_RANDOMIZE) {
                    -1 => Err(std::io::Error::last_os_error()),
                    _ => Ok(()),
                },
            );
        }
        t.status().is_ok_and(|s| s.success())
    }

    #[test]
    fn hxt_makes_the_same_cells_each_time_it_is_asked() {
        // in one process two calls gave other cells before HXT meshed in a process of its own
        // with the addresses fixed (a run and its restart, or two runs, went other ways)
        if !fixed_addresses_allowed() {
            eprintln!("this kernel keeps the addresses randomised: HXT's cells may differ");
            return;
        }
        let mesh = box_around_a_block();
        let x: Vec<[f64; 3]> = (mesh.coords.iter())
            .map(|p| {
                let inside = p.iter().all(|&c| (1.0..=3.0).contains(&c));
                [p[0] + if inside { 0.2 } else { 0.0 }, p[1], p[2]]
            })
            .collect();
        let first = either_mesher_fills_the_box(&mesh, &x, Mesher::Hxt);
        for k in 1..4 {
            let again = either_mesher_fills_the_box(&mesh, &x, Mesher::Hxt);
            let kept = again
                .iter()
                .filter(|c| first.binary_search(c).is_ok())
                .count();
            assert!(
                again == first,
                "call {k}: {kept} of its {} cells among the first call's {}",
                again.len(),
                first.len()
            );
        }
    }

    /// The box of [`box_around_a_block`] made again at `x` by `mesher` first: its boundary
    /// kept, every new cell turned one way, the box less the block filled. Returns the new
    /// cells' places, each cell's corners sorted, the cells sorted.
    fn either_mesher_fills_the_box(
        mesh: &Mesh,
        x: &[[f64; 3]],
        mesher: Mesher,
    ) -> Vec<[[i64; 3]; 4]> {
        let r = remesh(mesh, x, &[0], &solid_nodes(mesh), mesher).unwrap();
        // the cells apart from the block, and those beside it (a node on it)
        assert_eq!(r.medium.len(), 2);
        let [apart, beside] = [0, 1].map(|k| &r.mesh.cells[r.medium[k]]);
        let on_solid = r.mesh.nodes_in(|b| !r.medium.contains(&b));
        for (blk, near) in [(apart, false), (beside, true)] {
            assert!(blk.n_cells() > 0 && blk.groups == vec![0]);
            let nears = (0..blk.n_cells()).map(|c| blk.cell(c).iter().any(|&n| on_solid[n]));
            assert!(nears.into_iter().all(|b| b == near));
        }
        let here = |n: usize| match r.old_of[n] {
            Some(o) => x[o],
            None => r.mesh.coords[n],
        };
        let placed: Vec<[f64; 3]> = (0..r.mesh.coords.len()).map(here).collect();
        let new = Block {
            conn: [&apart.conn[..], &beside.conn[..]].concat(),
            ..apart.clone()
        };
        assert_eq!(new.kind, CellKind::Tet4);
        let vols: Vec<f64> = (0..new.n_cells())
            .map(|c| volume(&placed, new.cell(c)))
            .collect();
        // every new cell turned one way, and together the box less the block
        let total: f64 = vols.iter().map(|v| v.abs()).sum();
        assert!((total - (64.0 - 8.0)).abs() < 1e-9, "{total}");
        let sign = vols[0].signum();
        assert!(
            vols.iter().all(|v| v * sign > 1e-6),
            "a flat or turned cell"
        );
        // the solid's cells and nodes as they were
        let solid = r.mesh.cells.iter().find(|b| b.groups == vec![1]).unwrap();
        assert_eq!(solid.n_cells(), 8 * 6);
        for c in 0..solid.n_cells() {
            for &n in solid.cell(c) {
                assert!(r.old_of[n].is_some());
            }
        }
        let key = |n: usize| placed[n].map(|v| (v * 1e6).round() as i64);
        let mut cells: Vec<[[i64; 3]; 4]> = (0..new.n_cells())
            .map(|c| {
                let mut k: [[i64; 3]; 4] = std::array::from_fn(|i| key(new.cell(c)[i]));
                k.sort_unstable();
                k
            })
            .collect();
        cells.sort_unstable();
        cells
    }

    /// A second medium region that is not made again is no body: the new cells beside it
    /// alone are apart, as `Model::made_again` weighs them (it looks at the solids' nodes).
    #[test]
    fn a_3d_medium_made_again_beside_another_medium_counts_only_the_solid_as_a_body() {
        let mut mesh = box_around_a_block();
        // the cubes of the last layer along x, a medium of their own (block 2) not made again
        let (coords, tets) = crate::mesh::kuhn_tetrahedra(4);
        let layer: Vec<usize> = (tets.into_iter())
            .filter(|(cube, _)| cube[0] == 3)
            .flat_map(|(_, t)| t)
            .collect();
        assert_eq!(coords, mesh.coords);
        let own: std::collections::HashSet<Vec<usize>> = (layer.chunks(4))
            .map(|t| {
                let mut t = t.to_vec();
                t.sort_unstable();
                t
            })
            .collect();
        let blk = &mesh.cells[0];
        let (kept, cut): (Vec<usize>, Vec<usize>) = (0..blk.n_cells()).partition(|&c| {
            let mut t = blk.cell(c).to_vec();
            t.sort_unstable();
            !own.contains(&t)
        });
        assert_eq!(cut.len(), 16 * 6);
        let conn = |cells: &[usize]| -> Vec<usize> {
            cells.iter().flat_map(|&c| blk.cell(c).to_vec()).collect()
        };
        let other = Block {
            kind: CellKind::Tet4,
            groups: vec![2],
            conn: conn(&cut),
        };
        mesh.cells[0].conn = conn(&kept);
        mesh.cells.push(other);
        mesh.groups.push(crate::mesh::PhysicalGroup {
            name: "medium2".into(),
            dim: 3,
            tag: 3,
        });
        let x = mesh.coords.clone();
        let on_solid = mesh.nodes_in(|b| b == 1);
        let r = remesh(&mesh, &x, &[0], &on_solid, Mesher::Delaunay).unwrap();
        assert_eq!(r.medium.len(), 2);
        let solid = (r.mesh.cells.iter())
            .position(|b| b.groups == vec![1])
            .unwrap();
        let on = r.mesh.nodes_in(|b| b == solid);
        let second = r.mesh.nodes_in(|b| r.mesh.cells[b].groups == vec![2]);
        let [apart, beside] = [0, 1].map(|k| &r.mesh.cells[r.medium[k]]);
        for (blk, near) in [(apart, false), (beside, true)] {
            let nears = (0..blk.n_cells()).map(|c| blk.cell(c).iter().any(|&n| on[n]));
            assert!(nears.into_iter().all(|b| b == near));
        }
        // and some cells apart from the solid touch the medium not made again
        assert!(
            (0..apart.n_cells()).any(|c| apart.cell(c).iter().any(|&n| second[n])),
            "no new cell beside the other medium"
        );
    }

    #[test]
    fn a_hexahedral_medium_in_3d_is_refused_with_what_to_do() {
        let mut mesh = box_around_a_block();
        mesh.cells[0].kind = CellKind::Hex8;
        let why = supported(&mesh, &[0]).unwrap_err();
        assert!(why.contains("tetrahedra") && why.contains("hex8"), "{why}");
        assert!(supported(&box_around_a_block(), &[0]).is_ok());
    }
}
