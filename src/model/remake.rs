//! The medium made again as the bodies move (`remake` of a medium region). A Lagrangian medium
//! between bodies that slide past each other is sheared without end: ahead of a body it is
//! ploughed, and a closed layer drags the faces it joins. The medium is fictitious, so nothing
//! physical is lost when its cells and its reference are renewed. The medium's cells are made
//! again between the bodies as they are (`mesh/remesh.rs`: triangles in 2D, tetrahedra in 3D)
//! once any of its cells' faces have slid [`SLID`] of a cell past each other, or a sliver's
//! node (a layer one cell across) would pass the end of the edge across from it in the next
//! step (in 3D, a thin tetrahedron's corner the face across it, or its edge the edge across
//! it: [`ThinTet`]). Each new cell
//! starts from a reference of its own (as a reconnected layer's cells do,
//! `assembly/reference.rs`):
//!
//! - a layer one cell across (triangles whose nodes are all on solids) that was closed
//!   somewhere (J below [`CLOSED`]) from its current shape stretched across itself to one
//!   thickness of reference for the whole layer, the median of what its closed cells had
//!   (see [`Layers`]): the contact pressure depends on the gap alone, as exact contact's
//!   does, and does not travel with the cells as the bodies slide;
//! - the open medium from its current shape, stress-free: what removes the ploughing; a sliver
//!   from its shape opened across its long edge to a slenderness of [`THINNEST`], so that it
//!   is not a stiff cell;
//! - where no layer has closed yet, a squeezed cell (J < [`CLOSED`] at the new cell's centre
//!   or half way to its nodes, the smallest) from its current shape stretched back by 1/J,
//!   so that it carries its compression without its shear (F₀ = I + (J − 1) n⊗n, n the
//!   direction the old cell was squeezed most);
//! - temperatures at the new nodes from the old cells where they stand; the regularization's
//!   p fields at zero (a new cell's F₀ is symmetric: it has no rotation to measure).
//!
//! The solids' nodes, cells and histories stay as they are.
#![allow(non_snake_case)]

use super::{Model, RegionKind};
use crate::dofs::{CellState, Field, NONE, gather, rebase};
use crate::element::{RefElement, centre, local_coords, physical_gradients};
use crate::kernel::friction::HISTORY_PER_POINT;
use crate::mesh::Mesh;
use crate::mesh::remesh::{Mesher, RemeshError, boundary_loops, remesh, supported};
use nalgebra::{Matrix2, Matrix3, SymmetricEigen, Vector2, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};

/// How far (in cell sizes, see [`Medium::slid_cells`]) a medium cell's faces may slide past
/// each other before the medium is made again.
pub const SLID: f64 = 0.5;

/// The relative residual (of each field, as Newton measures it) to which the mechanics are
/// settled after a remake where the medium asks (`settle`), or where the first step from it
/// fails: the state the remake's change is measured at (in percent) and the next step starts
/// from, a millionth out of balance at most (the steps' own `tol` where that is looser).
/// Otherwise the next step starts from the state as carried, with the same steps and forces
/// (docs/notes/2026-12-05-a-remake-goes-on-unsettled.md). Settled to the steps' 1e-9, the
/// README cylinder's settlings (slid 0.5) took 2.4 Newton iterations each, most of them from
/// below 1e-6 already; to 1e-6, 0.85 (docs/notes/2026-12-04-what-a-remake-costs.md).
pub const SETTLED: f64 = 1e-6;

/// The J below which a medium cell is a closed layer, whose compression a new cell carries.
pub const CLOSED: f64 = 0.5;

/// In 3D, the weight of the rotation penalty's β1 on a remade medium's cells beside a body (a
/// node on one). A body's face along its slide shears the cells beside it by the slide since
/// the last remake, and their penalty, 1e4 times the medium's own stiffness at γ = 1e-4, held
/// the square pad in a box at 0.005 of its normal force without friction, the floor under its
/// spikes (0.0011 at a tenth; 0.0007 at a hundredth, where the sphere's box folds). Not in
/// 2D, which has no such faces and whose pads need the penalty at their corners
/// (docs/notes/2026-12-06-the-penalty-beside-a-sliding-face.md).
pub const BESIDE: f64 = 0.1;

/// Per mesh block, its cells' own reference node coordinates (N per cell, in cell order), or
/// `None` for a block measured from the mesh: a model's as made ([`Model::cell_reference`]),
/// or a run's, whose closed layers have taken their slide into them since.
pub type CellReferences = [Option<Vec<[f64; 3]>>];

/// A medium region whose `remake` cannot be done, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct RemakeError {
    pub region: String,
    pub why: String,
}

impl std::fmt::Display for RemakeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "region \"{}\": `remake` {}", self.region, self.why)
    }
}

impl std::error::Error for RemakeError {}

/// The medium of a model whose cells are made again as the bodies move, and its watch of the
/// slivers, which a checkpoint keeps so that a restart decides as the run would have.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Medium {
    /// The medium's mesh blocks.
    blocks: Vec<usize>,
    /// The slivers among its triangles (slenderness below [`THINNEST`] where they were last
    /// looked at): their block and cell, the nodes (local) of their longest edge and of the
    /// node across it, and where along that edge the node stood at the last accepted state.
    slivers: Vec<Sliver>,
    /// The slivers among its tetrahedra, in 3D.
    #[serde(default)]
    thin: Vec<ThinTet>,
    /// The pseudo-time of the last accepted state, and how fast (length per unit of it) a
    /// sliver's node moved along its edge at most over the last step.
    t: f64,
    pub rate: f64,
    /// Whether the medium was last made before a pass its watch saw coming ([`FRESH`]),
    /// which it is then not made again before: made again once more just before the pass,
    /// each node is joined across the edge it has not yet passed, as it was. Set by any
    /// remake while a pass is coming; cleared by one after a pass or with none coming, or
    /// once a node has gone a whole edge since (a checkpoint before then keeps it).
    #[serde(default)]
    pub made_for_pass: bool,
    /// Which of gmsh's meshers fills a 3D medium first: Delaunay, HXT for the remake at a
    /// state the run stuck at ([`Medium::stuck`]). A checkpoint is never taken between the
    /// two, so it keeps none.
    #[serde(skip)]
    mesher: Mesher,
    /// The J each cell of the medium as made again had when it was made
    /// ([`Medium::made_cells`]' order), from which [`Medium::crushed`] measures its squeeze: a
    /// closed layer's cell starts from its compression, a sliver from a reference opened
    /// across it.
    #[serde(default)]
    made_j: Vec<f64>,
    /// In 3D, per cell in the same order, whether it has a node on a body's edge (see
    /// [`body_edges`]); none from a checkpoint from before it was kept.
    #[serde(default)]
    at_edge: Vec<bool>,
}

/// How far (in lengths of its edge) a sliver's node may have gone along the edge across it
/// since the medium was made for the medium to be made again after the node's next pass
/// rather than before it. Made only after each pass, the frictionless pad in a box met 0.076
/// of its normal force (0.007 otherwise) as a node neared the end of a face it had gone 0.4
/// of along (docs/notes/2026-12-04-a-remake-after-the-pass.md).
const FRESH: f64 = 0.05;

/// How far (in lengths of its edge) a sliver's node may stand past the end of the edge across
/// it while the next step takes others past theirs: the medium is then made again once, after
/// the last of them, not after each. A layer's nodes pass their ends a little apart (the two
/// faces' nodes, spaced alike when drawn, are not so under load): made again after each pass,
/// the frictionless pad in a box dragged one width was made again 49 times, 29 so; the README
/// cylinder 19 times, 13 so, its largest F_t/F_n 0.1043 and 0.1045. Let stand twice as far,
/// the cylinder's remakes changed its rim's force by 2.3 % (1.3 % so)
/// (docs/notes/2026-12-05-a-node-past-its-end-waits-for-its-group.md).
const PAST_END: f64 = 0.05;

/// Whether the medium is to be made again now, and when a sliver's node next reaches the end
/// of the edge across it (infinite if the next step takes none there), from where each node
/// stands along its edge at the accepted state at `t` and how fast it moves (`along`: edge
/// lengths per unit of pseudo-time), the next step ending at `target`. A node past its end by
/// more than [`PAST_END`] asks for the medium now; one past it by less waits for the nodes
/// the next step takes past theirs before it gets that far (the step then ends at the last of
/// them); with none such, it asks now.
fn passing(along: &[(f64, f64)], t: f64, target: f64) -> (bool, f64) {
    let inside = |at: f64| (0.0..=1.0).contains(&at);
    // the earliest a node gets PAST_END beyond its end
    let mut limit = f64::INFINITY;
    // when each node still inside reaches its end, where the next step takes it there
    let mut coming = Vec::new();
    let (mut past, mut beyond) = (false, false);
    for &(at, speed) in along {
        past |= !inside(at);
        beyond |= !(-PAST_END..=1.0 + PAST_END).contains(&at);
        if speed != 0.0 {
            let end = if speed > 0.0 {
                1.0 + PAST_END
            } else {
                -PAST_END
            };
            limit = limit.min(t + (end - at) / speed);
        }
        let next = at + speed * (target - t);
        if inside(at) && !inside(next) {
            let end = if next > 1.0 { 1.0 } else { 0.0 };
            coming.push(t + (end - at) / speed);
        }
    }
    let first = coming.iter().copied().fold(f64::INFINITY, f64::min);
    let last_before = (coming.iter().copied())
        .filter(|&p| p <= limit)
        .fold(f64::NEG_INFINITY, f64::max);
    match (past, last_before.is_finite()) {
        _ if beyond => (true, first),
        (true, true) => (false, last_before),
        (true, false) => (true, first),
        (false, _) => (false, first),
    }
}

/// What the medium's watch asks after an accepted state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Watch {
    /// Make the medium again now.
    Remake,
    /// A sliver's node reaches the end of the edge across it at this pseudo-time, at the
    /// speed of the last step: the next step is to take it just past, and the medium is made
    /// again there.
    Until(f64),
    /// Go on.
    Go,
}

/// A thin triangle: a node across a long edge (a layer one cell across).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Sliver {
    block: usize,
    cell: usize,
    edge: [usize; 2],
    across: usize,
    at: f64,
    /// Where along its edge the node stood when the medium was made.
    #[serde(default)]
    from: f64,
}

/// A thin tetrahedron (a layer one cell across): three corners on one face and one across,
/// or two and two, as its corners stand along its thinnest direction when it was first
/// looked at. Each stays such while the numbers [`ThinTet::standing`] gives stay positive.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct ThinTet {
    block: usize,
    cell: usize,
    /// Its corners (local), the first `first` (1 or 2) on one side.
    corners: [usize; 4],
    first: usize,
    /// What [`ThinTet::standing`] gave at the last accepted state.
    room: Vec<f64>,
    /// What it gave when the medium was made (a checkpoint's from before it was kept: none).
    #[serde(default)]
    from: Vec<f64>,
    /// Its volume at the last accepted state, and when the medium was made (a checkpoint's
    /// from before they were kept: zero).
    #[serde(default)]
    volume: f64,
    #[serde(default)]
    made_volume: f64,
}

impl ThinTet {
    /// The thin tetrahedron `c` of block `b` with corners at `p`, if it is one.
    fn of(b: usize, c: usize, p: &[[f64; 3]]) -> Option<ThinTet> {
        if slenderness3(p) >= THINNEST {
            return None;
        }
        let q: Vec<Vector3<f64>> = p.iter().map(|c| Vector3::new(c[0], c[1], c[2])).collect();
        let (corners, first) = split(&q);
        Some(ThinTet {
            block: b,
            cell: c,
            corners,
            first,
            room: Vec::new(),
            from: Vec::new(),
            volume: 0.0,
            made_volume: 0.0,
        })
    }

    /// Its volume at the state `x` (signed, its corners in the order it keeps them).
    fn volume(&self, model: &Model, x: &[f64]) -> f64 {
        let nodes = model.mesh.cells[self.block].cell(self.cell);
        crate::mesh::tet_volume(self.corners.map(|i| model.placed(nodes[i], x)))
    }

    /// Whether, at the speed of the last step (`dt` long), it would be squeezed below
    /// [`CLOSED`] of the volume it was made with by the end of the next (`ahead` long), from
    /// its volume `now` at the accepted state (with no volume kept: yes).
    fn squeezed_by(&self, now: f64, dt: f64, ahead: f64) -> bool {
        let speed = if dt > 0.0 {
            (now - self.volume) / dt
        } else {
            0.0
        };
        self.made_volume == 0.0 || (now + speed * ahead) / self.made_volume < CLOSED
    }

    /// Where its corners stand on each other at the state `x`: for one corner across three,
    /// the barycentric coordinates of the one's foot on the three's plane; for two and two,
    /// where along each edge its point nearest the other edge is (s, 1 − s, u, 1 − u). Each
    /// is positive while the sliver spans the faces it was made across; also its longest edge.
    fn standing(&self, model: &Model, x: &[f64]) -> (Vec<f64>, f64) {
        let nodes = model.mesh.cells[self.block].cell(self.cell);
        let q = self.corners.map(|i| {
            let p = model.placed(nodes[i], x);
            Vector3::new(p[0], p[1], p[2])
        });
        let p = q.map(|v| [v.x, v.y, v.z]);
        (standing_of(q, self.first), longest_edge3(&p))
    }
}

/// [`ThinTet::standing`] of a tetrahedron with corners at `q`, the first `first` on one side.
fn standing_of(q: [Vector3<f64>; 4], first: usize) -> Vec<f64> {
    match first {
        1 => {
            let (k, a) = (q[0], q[1]);
            let (v0, v1, v2) = (q[2] - a, q[3] - a, k - a);
            let (d00, d01, d11) = (v0.dot(&v0), v0.dot(&v1), v1.dot(&v1));
            let (d20, d21) = (v2.dot(&v0), v2.dot(&v1));
            let den = (d00 * d11 - d01 * d01).max(f64::MIN_POSITIVE);
            let lb = (d11 * d20 - d01 * d21) / den;
            let lc = (d00 * d21 - d01 * d20) / den;
            vec![1.0 - lb - lc, lb, lc]
        }
        _ => {
            let (d1, d2, r) = (q[1] - q[0], q[3] - q[2], q[0] - q[2]);
            let (a, e, b) = (d1.dot(&d1), d2.dot(&d2), d1.dot(&d2));
            let (c, f) = (d1.dot(&r), d2.dot(&r));
            let den = (a * e - b * b).max(f64::MIN_POSITIVE);
            let s = (b * f - c * e) / den;
            let u = (a * f - b * c) / den;
            vec![s, 1.0 - s, u, 1.0 - u]
        }
    }
}

/// A medium made again: the new mesh, the new medium cells' references, and what the new
/// nodes carry.
pub struct Remade {
    pub mesh: Mesh,
    /// Per block of the new mesh, its own reference node coordinates per cell (the new medium
    /// blocks), or `None`.
    pub reference: Vec<Option<Vec<[f64; 3]>>>,
    /// Per node of the new mesh, the old node it is (`None`: new, inside the medium).
    old_of: Vec<Option<usize>>,
    /// Per node of the new mesh, its temperature where it is new.
    theta: Vec<f64>,
    /// Per node of the new mesh, where it is one of the medium's own kept nodes, its new
    /// displacement (`Medium::own_places`).
    own: Vec<Option<[f64; 3]>>,
}

/// The deformation gradient of the cell `s` at ξ (a 2D cell's as a plane strain's, F₃₃ = 1).
fn cell_F<const N: usize, const D: usize, E: RefElement<N, D>>(
    s: &CellState<N>,
    xi: &[f64; D],
) -> Option<Matrix3<f64>> {
    let (g, _) = physical_gradients::<N, D>(&E::grad(xi), &s.X)?;
    let mut F = Matrix3::identity();
    for I in 0..N {
        for i in 0..D {
            for j in 0..D {
                F[(i, j)] += s.u[I][i] * g[I][j];
            }
        }
    }
    Some(F)
}

/// Each cell of mesh block `b`, given to `visit` with its reference corners and its
/// deformation gradient at its centre at the state `x` (measured from `reference`; none where
/// the cell is degenerate): what the medium's watch measures its cells by.
fn at_centres(
    model: &Model,
    reference: &CellReferences,
    x: &[f64],
    b: usize,
    mut visit: impl FnMut(&[[f64; 3]], Option<Matrix3<f64>>),
) {
    let blk = &model.mesh.cells[b];
    crate::with_cell!(blk.kind, |N, D, E| {
        let xi = centre::<N, D, E>();
        for c in 0..blk.n_cells() {
            let s = model.cell_state_in::<N>(reference, b, c, x);
            visit(&s.X, cell_F::<N, D, E>(&s, &xi));
        }
    });
}

/// A 2D cell's height over its length, (area / longest edge²), times 2 for a triangle: √3/2
/// for an equilateral one, small for a sliver.
fn slenderness(X: &[[f64; 3]], simplex: bool) -> f64 {
    let k = if simplex { 3 } else { 4 };
    let f = if simplex { 2.0 } else { 1.0 };
    (f * area(X, k) / longest_edge(X, k).1.max(f64::MIN_POSITIVE)).min(1.0)
}

/// The area of a 2D cell with `k` corners `p` in order.
fn area(p: &[[f64; 3]], k: usize) -> f64 {
    let twice: f64 = (0..k)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % k]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    0.5 * twice.abs()
}

/// The edge from corner `i` of a 2D cell with `k` corners `p` in order to the next.
fn edge(p: &[[f64; 3]], k: usize, i: usize) -> Vector2<f64> {
    let (a, b) = (p[i], p[(i + 1) % k]);
    Vector2::new(b[0] - a[0], b[1] - a[1])
}

/// The longest edge of a 2D cell with `k` corners `p` in order (the first of equals): the
/// corner it starts at, and its length squared.
fn longest_edge(p: &[[f64; 3]], k: usize) -> (usize, f64) {
    (0..k).fold((0, 0.0), |(best, l2), i| {
        let e2 = edge(p, k, i).norm_squared();
        if e2 > l2 { (i, e2) } else { (best, l2) }
    })
}

/// The unit normal of a 2D cell's edge `e`.
fn normal_to(e: Vector2<f64>) -> Vector2<f64> {
    let along = e / e.norm().max(f64::MIN_POSITIVE);
    Vector2::new(-along[1], along[0])
}

/// The shear of the deformation gradient `F`: sqrt((λ₂ − 1)(1 − λ₁)) with λ₁ ≤ λ₂ the
/// eigenvalues of F Fᵀ, about γ for a simple shear γ of a layer however squeezed, and zero for
/// a rotation and for a compression along one axis.
pub fn shear(F: &Matrix2<f64>) -> f64 {
    let e = SymmetricEigen::new(F * F.transpose()).eigenvalues;
    let (l1, l2) = (e[0].min(e[1]), e[0].max(e[1]));
    ((l2 - 1.0) * (1.0 - l1)).max(0.0).sqrt()
}

/// [`shear`] in 3D: λ₁ and λ₂ the smallest and the largest eigenvalue of F Fᵀ.
pub fn shear3(F: &Matrix3<f64>) -> f64 {
    let e = SymmetricEigen::new(F * F.transpose()).eigenvalues;
    let (l1, l2) = (e.min(), e.max());
    ((l2 - 1.0) * (1.0 - l1)).max(0.0).sqrt()
}

/// The plane part of a 2D cell's deformation gradient (see [`cell_F`]).
fn plane(F: &Matrix3<f64>) -> Matrix2<f64> {
    F.fixed_view::<2, 2>(0, 0).into_owned()
}

/// A 2D map as the 3D one that leaves the third axis alone.
fn embed(m: Matrix2<f64>) -> Matrix3<f64> {
    let mut e = Matrix3::identity();
    e.fixed_view_mut::<2, 2>(0, 0).copy_from(&m);
    e
}

/// J of a cell's deformation gradient `F` in `dim` dimensions.
fn volume_ratio(F: &Matrix3<f64>, dim: usize) -> f64 {
    match dim {
        2 => plane(F).determinant(),
        _ => F.determinant(),
    }
}

/// A tetrahedron's thinnest direction and its thickness along it. Its corners `p` are split
/// in two where they stand farthest apart along the direction they spread least (the smallest
/// principal axis of their scatter): one across three, whose height over the three's plane it
/// is, or two and two, the distance between the lines of their edges.
fn thinnest(p: &[[f64; 3]]) -> (f64, Vector3<f64>) {
    let q: Vec<Vector3<f64>> = p.iter().map(|c| Vector3::new(c[0], c[1], c[2])).collect();
    let (order, first) = split(&q);
    let [a, b, c, d] = order.map(|i| q[i]);
    let n = match first {
        1 => (c - b).cross(&(d - b)),
        _ => (b - a).cross(&(d - c)),
    };
    let n = n.try_normalize(0.0).unwrap_or_else(Vector3::z);
    (n.dot(&(a - c)).abs(), n)
}

/// A tetrahedron's corners `q` in order along the direction they spread least, split where
/// they stand farthest apart: the order (the first `first` on one side; one corner alone
/// first) and `first` (1 or 2).
fn split(q: &[Vector3<f64>]) -> ([usize; 4], usize) {
    let m = q.iter().sum::<Vector3<f64>>() / q.len() as f64;
    let scatter: Matrix3<f64> = q.iter().map(|c| (c - m) * (c - m).transpose()).sum();
    let e = SymmetricEigen::new(scatter);
    let n: Vector3<f64> = e.eigenvectors.column(e.eigenvalues.imin()).into();
    let mut order = [0, 1, 2, 3];
    order.sort_by(|&i, &j| n.dot(&q[i]).total_cmp(&n.dot(&q[j])));
    let gap = |i: usize| n.dot(&q[order[i]]) - n.dot(&q[order[i - 1]]);
    let first = (1..4)
        .max_by(|&a, &b| gap(a).total_cmp(&gap(b)))
        .unwrap_or(1);
    match first {
        3 => ([order[3], order[0], order[1], order[2]], 1),
        f => (order, f),
    }
}

/// A tetrahedron's thickness (see [`thinnest`]) over its longest edge: about 0.7–0.8 for a
/// regular one, small for a sliver (three corners on one face and one on a face close to it,
/// or two and two).
fn slenderness3(p: &[[f64; 3]]) -> f64 {
    (thinnest(p).0 / longest_edge3(p).max(f64::MIN_POSITIVE)).min(1.0)
}

/// The length of the longest edge between the corners `p` of a cell.
fn longest_edge3(p: &[[f64; 3]]) -> f64 {
    let mut longest = 0.0f64;
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let l2: f64 = (0..3).map(|k| (p[i][k] - p[j][k]).powi(2)).sum();
            longest = longest.max(l2);
        }
    }
    longest.sqrt()
}

impl Model {
    /// Whether this is a 3D medium that slides without friction: its thin tetrahedra's passes
    /// ask for a remake only where they squeeze them, its crushed cells ask, and its open
    /// cells beside a body let go of their shear (the assembler's `References::release_beside`).
    /// With friction every pass asks, and nothing else does: tried with friction, these rules
    /// held μ no closer (docs/notes/2026-12-07-friction-in-3d-and-a-drag-at-each-row-of-nodes.md).
    pub fn slides_freely_in_3d(&self) -> bool {
        self.mesh.dim == 3 && !self.rubs()
    }

    /// Cell `c` of mesh block `block` at the state `x`, measured from its own reference where
    /// it has one.
    pub fn cell_state<const N: usize>(&self, block: usize, c: usize, x: &[f64]) -> CellState<N> {
        self.cell_state_in::<N>(&self.cell_reference, block, c, x)
    }

    /// As [`Model::cell_state`], the cells measured from `reference` (per block, its own
    /// reference node coordinates per cell, where it has them) instead of the model's: those
    /// a run's closed layers have moved since ([`CellReferences`]).
    pub fn cell_state_in<const N: usize>(
        &self,
        reference: &CellReferences,
        block: usize,
        c: usize,
        x: &[f64],
    ) -> CellState<N> {
        let nodes = self.mesh.cells[block].cell(c);
        let mut s = gather::<N>(&self.mesh.coords, &self.dofs, nodes, x);
        if let Some(r) = &reference[block] {
            rebase(&mut s, &r[c * N..(c + 1) * N]);
        }
        s
    }

    /// The medium made again: its cells' own references (per block), and in 3D the rotation
    /// penalty of the blocks made beside a body weighed by [`BESIDE`].
    pub fn made_again(&mut self, reference: Vec<Option<Vec<[f64; 3]>>>) {
        self.cell_reference = reference;
        if self.mesh.dim != 3 {
            return;
        }
        let on = self.on_solids();
        for info in &mut self.blocks {
            // a block made again (a solid's is not) that carries the penalty
            let (true, Some(reg)) = (
                self.cell_reference[info.block].is_some(),
                info.mat.reg.as_mut(),
            ) else {
                continue;
            };
            let blk = &self.mesh.cells[info.block];
            let beside = blk
                .conn
                .chunks(blk.kind.n_nodes())
                .all(|c| c.iter().any(|&n| on[n]));
            if beside {
                reg.beta1 *= BESIDE;
            }
        }
    }

    /// Per node, whether it is a node of a solid's cell (not of the medium's alone).
    pub(crate) fn on_solids(&self) -> Vec<bool> {
        self.nodes_of(RegionKind::Solid)
    }

    /// Node `n`'s place at the state `x`.
    pub(crate) fn placed(&self, n: usize, x: &[f64]) -> [f64; 3] {
        let d = self.dofs.dim;
        let mut p = self.mesh.coords[n];
        if !self.dofs.u.is_empty() {
            for (i, pi) in p.iter_mut().enumerate().take(d) {
                *pi += x[self.dofs.u[n * d + i] as usize];
            }
        }
        p
    }
}

/// The old medium's cells where they are, to find which one holds a point.
struct Locator<'a> {
    model: &'a Model,
    reference: &'a CellReferences,
    x: &'a [f64],
    /// (block, cell) of every medium cell, and its nodes' places.
    cells: Vec<(usize, usize, Vec<[f64; 3]>)>,
    lo: [f64; 3],
    size: f64,
    /// The buckets along each axis (one along the third in 2D).
    dims: [usize; 3],
    buckets: Vec<Vec<usize>>,
}

impl<'a> Locator<'a> {
    fn new(
        model: &'a Model,
        reference: &'a CellReferences,
        blocks: &[usize],
        x: &'a [f64],
    ) -> Locator<'a> {
        let dim = model.mesh.dim;
        let mut cells = Vec::new();
        for &b in blocks {
            let blk = &model.mesh.cells[b];
            for c in 0..blk.n_cells() {
                let p: Vec<[f64; 3]> = blk.cell(c).iter().map(|&n| model.placed(n, x)).collect();
                cells.push((b, c, p));
            }
        }
        let (mut lo, mut hi) = ([0.0; 3], [0.0; 3]);
        lo[..dim].fill(f64::INFINITY);
        hi[..dim].fill(f64::NEG_INFINITY);
        let mut diam = 0.0;
        for (_, _, p) in &cells {
            let (mut clo, mut chi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for q in p {
                for i in 0..dim {
                    clo[i] = clo[i].min(q[i]);
                    chi[i] = chi[i].max(q[i]);
                }
            }
            for i in 0..dim {
                lo[i] = lo[i].min(clo[i]);
                hi[i] = hi[i].max(chi[i]);
            }
            diam += (0..dim)
                .map(|i| chi[i] - clo[i])
                .fold(f64::NEG_INFINITY, f64::max);
        }
        let n = cells.len().max(1) as f64;
        let mut size = (diam / n).max(1e-12 * (hi[0] - lo[0]).abs());
        if dim == 3 {
            // no more buckets than about eight per cell
            let volume: f64 = (0..3).map(|i| (hi[i] - lo[i]).max(0.0)).product();
            size = size.max((volume / (8.0 * n)).cbrt());
        }
        let dims = [0, 1, 2].map(|i| match i < dim {
            true => (((hi[i] - lo[i]) / size).ceil() as usize).clamp(1, 4096),
            false => 1,
        });
        let mut loc = Locator {
            model,
            reference,
            x,
            cells: Vec::new(),
            lo,
            size,
            dims,
            buckets: vec![Vec::new(); dims[0] * dims[1] * dims[2]],
        };
        for (k, (_, _, p)) in cells.iter().enumerate() {
            let (mut a, mut z) = ([usize::MAX; 3], [0; 3]);
            for q in p {
                let ijk = loc.bucket_of(q);
                for i in 0..3 {
                    a[i] = a[i].min(ijk[i]);
                    z[i] = z[i].max(ijk[i]);
                }
            }
            for l in a[2]..=z[2] {
                for j in a[1]..=z[1] {
                    for i in a[0]..=z[0] {
                        let at = loc.index([i, j, l]);
                        loc.buckets[at].push(k);
                    }
                }
            }
        }
        loc.cells = cells;
        loc
    }

    fn bucket_of(&self, p: &[f64; 3]) -> [usize; 3] {
        [0, 1, 2].map(|i| {
            (((p[i] - self.lo[i]) / self.size).floor().max(0.0) as usize).min(self.dims[i] - 1)
        })
    }

    fn index(&self, [i, j, l]: [usize; 3]) -> usize {
        (l * self.dims[1] + j) * self.dims[0] + i
    }

    /// The old cell that holds `p` (or, past the medium's edge by round-off, the nearest one
    /// around it), and a value of its state there: what `at` computes from the cell's state
    /// and the point's ξ.
    fn value<T>(&self, p: &[f64; 3], at: impl Fn(&dyn CellAt) -> Option<T>) -> Option<T> {
        let mut best: Option<(f64, usize)> = None;
        for &k in &self.buckets[self.index(self.bucket_of(p))] {
            let kind = self.model.mesh.cells[self.cells[k].0].kind;
            let out = crate::with_cell!(kind, |N, D, E| outside::<N, D, E>(&self.cells[k].2, p));
            if best.is_none_or(|(o, _)| out < o) {
                best = Some((out, k));
            }
            if out <= 1e-9 {
                break;
            }
        }
        let (_, k) = best?;
        let (b, c, places) = &self.cells[k];
        let kind = self.model.mesh.cells[*b].kind;
        crate::with_cell!(kind, |N, D, E| {
            let X: [[f64; 3]; N] = std::array::from_fn(|I| places[I]);
            let xi = local_coords::<N, D, E>(&X, p)?;
            let s = (self.model).cell_state_in::<N>(self.reference, *b, *c, self.x);
            let nodes = self.model.mesh.cells[*b].cell(*c);
            at(&At::<N, D, E> {
                s,
                xi,
                cell: (*b, *c),
                nodes,
                model: self.model,
                x: self.x,
                _e: std::marker::PhantomData,
            })
        })
    }
}

/// How far the point `p` is outside the cell with nodes at `places` (in reference
/// coordinates; 0 inside).
fn outside<const N: usize, const D: usize, E: RefElement<N, D>>(
    places: &[[f64; 3]],
    p: &[f64; 3],
) -> f64 {
    let X: [[f64; 3]; N] = std::array::from_fn(|I| places[I]);
    let Some(xi) = local_coords::<N, D, E>(&X, p) else {
        return f64::INFINITY;
    };
    if E::SIMPLEX {
        let last = 1.0 - xi.iter().sum::<f64>();
        xi.iter()
            .chain([&last])
            .map(|&v| (-v).max(0.0))
            .fold(0.0, f64::max)
    } else {
        xi.iter()
            .map(|&v| (v.abs() - 1.0).max(0.0))
            .fold(0.0, f64::max)
    }
}

/// An old cell at a point: its deformation gradient and its interpolated temperature there,
/// the cell (block and index) and its quadrature point nearest the point.
trait CellAt {
    fn F(&self) -> Option<Matrix3<f64>>;
    fn theta(&self) -> f64;
    fn cell(&self) -> (usize, usize);
    fn nearest_point(&self) -> usize;
}

struct At<'a, const N: usize, const D: usize, E> {
    s: CellState<N>,
    xi: [f64; D],
    /// The cell's block and index.
    cell: (usize, usize),
    nodes: &'a [usize],
    model: &'a Model,
    x: &'a [f64],
    _e: std::marker::PhantomData<E>,
}

impl<const N: usize, const D: usize, E: RefElement<N, D>> CellAt for At<'_, N, D, E> {
    fn F(&self) -> Option<Matrix3<f64>> {
        cell_F::<N, D, E>(&self.s, &self.xi)
    }
    fn cell(&self) -> (usize, usize) {
        self.cell
    }
    fn nearest_point(&self) -> usize {
        let d2 = |q: &[f64; D]| (0..D).map(|i| (q[i] - self.xi[i]).powi(2)).sum::<f64>();
        (E::quadrature().iter().enumerate())
            .min_by(|a, b| d2(&a.1.0).total_cmp(&d2(&b.1.0)))
            .map_or(0, |(q, _)| q)
    }
    fn theta(&self) -> f64 {
        let th = &self.model.dofs.theta;
        if th.is_empty() {
            return 0.0;
        }
        let w = E::shape(&self.xi);
        (self.nodes.iter().zip(w))
            .map(|(&n, w)| w * self.x[th[n] as usize])
            .sum()
    }
}

impl Medium {
    /// The model's medium, where a medium region (`asked`, its name) asks to be made again
    /// as the bodies move (`remake`); an error says why it cannot be.
    pub fn find(model: &Model, asked: Option<&str>) -> Result<Option<Medium>, RemakeError> {
        let Some(region) = asked else {
            return Ok(None);
        };
        let refuse = |why: &str| {
            Err(RemakeError {
                region: region.to_owned(),
                why: why.to_owned(),
            })
        };
        if model.reconnects() {
            return refuse(
                "cannot be given with a friction layer's `reconnect`: they are two ways to \
                 follow a slide; give one",
            );
        }
        if !model.physics.mechanics {
            return refuse("needs mechanics; this scene has none");
        }
        let blocks: Vec<usize> = (model.blocks.iter())
            .filter(|b| model.regions[b.region].1 == RegionKind::Medium)
            .map(|b| b.block)
            .collect();
        if model.friction_blocks.iter().any(|f| f.mat.forget_slip) {
            return refuse(
                "cannot be given with `friction.forget_slip`: a remade medium starts from its \
                 current shape, with nothing of the slip to forget; leave out `forget_slip`",
            );
        }
        if let Err(why) = supported(&model.mesh, &blocks) {
            return refuse(&why);
        }
        Ok(Some(Medium {
            blocks,
            slivers: Vec::new(),
            thin: Vec::new(),
            t: 0.0,
            rate: 0.0,
            made_for_pass: false,
            mesher: Mesher::default(),
            made_j: Vec::new(),
            at_edge: Vec::new(),
        }))
    }

    /// How far, in cell sizes, the medium's cells have slid at the state `x`: the largest
    /// over its cells of the shear (see [`shear`]) times the cell's height over its length
    /// in its reference (a layer of height H and length L sheared by γ has slid γ H, or
    /// γ H / L cells). In 2D a cell longer than the medium's median cell counts in that
    /// median's lengths: the long thin cells a remake lays along a contact let the README's
    /// cylinder slide 0.18 (its cells are 0.1) between two remakes while the rim's heat flow
    /// drifted by 12 %, and the remake that ended it changed the flow by 8 % (with the
    /// rotation penalty weighed by J²; docs/notes/2026-12-03-a-pad-in-a-box-slides.md).
    pub fn slid_cells(&self, model: &Model, reference: &CellReferences, x: &[f64]) -> f64 {
        let mut most = 0.0f64;
        // in 2D, per cell: its slide γ H and its length L
        let mut slides: Vec<(f64, f64)> = Vec::new();
        for &b in &self.blocks {
            let corners = model.mesh.cells[b].kind.corners();
            at_centres(model, reference, x, b, |X, F| {
                let Some(F) = F else { return };
                if model.mesh.dim == 2 {
                    let L = longest_edge(X, corners).1.sqrt();
                    slides.push((shear(&plane(&F)) * slenderness(X, corners == 3) * L, L));
                } else {
                    most = most.max(shear3(&F) * slenderness3(X));
                }
            });
        }
        let mut lengths: Vec<f64> = slides.iter().map(|&(_, L)| L).collect();
        lengths.sort_by(f64::total_cmp);
        if let Some(&median) = lengths.get(lengths.len() / 2) {
            for (slide, L) in slides {
                most = most.max(slide / L.min(median));
            }
        }
        most
    }

    /// The places the medium's own boundary nodes (of its cells and of no solid's, on its
    /// outer faces: those a remake keeps) take at a remake, at the state `x`: the displacement
    /// of the solids' nodes on that boundary spread over it, each own node at the mean of its
    /// neighbours along the boundary (what a condition prescribes kept), and where no solid
    /// touches a part of it, that part where the mesh put it. The medium is fictitious: its
    /// outer faces, followed as the bodies drag what is around them, carried the box a user
    /// drew along with a body (a pad slid 2.5 of its widths pulled its box's top 1.6 above
    /// where it was drawn, and the run stopped there).
    ///
    /// In 3D an own node that shares a cell with a solid's node and that a condition holds in
    /// some direction (on a symmetry plane) stays where it is; so, until none is left, does
    /// each node of a triangle that placed would turn over ([`FOLD`]), close onto its
    /// neighbour across an edge ([`CREASE`]) or cross another triangle ([`crossing`]), which
    /// gmsh refuses. Kept where the run left them all, the nodes beside a body were pushed out
    /// of the box's free faces step after step (the sphere dragged three radii: one out by
    /// 6.1, its cells needles); placed all, the sphere turned a cell inside out behind it, by
    /// its symmetry plane; placed but there, the faces between the two folded over, and gmsh
    /// refused them (docs/notes/2026-12-06-a-3d-press-made-again-step-after-step.md).
    /// `on_solid`: per node, whether it is a solid's.
    fn own_places(
        &self,
        model: &Model,
        x: &[f64],
        on_solid: &[bool],
    ) -> Result<Vec<Option<[f64; 3]>>, String> {
        let mesh = &model.mesh;
        let outer = match mesh.dim {
            3 => crate::mesh::faces::outer_triangles(mesh, &self.blocks)?,
            _ => Vec::new(),
        };
        // each boundary node's neighbours: along its loop in 2D, across the edges of the
        // outer triangles in 3D
        let mut next: Vec<Vec<usize>> = vec![Vec::new(); mesh.coords.len()];
        for f in &outer {
            for i in 0..3 {
                let (a, b) = (f[i], f[(i + 1) % 3]);
                next[a].push(b);
                next[b].push(a);
            }
        }
        for around in &mut next {
            around.sort_unstable();
            around.dedup();
        }
        if mesh.dim == 2 {
            for lp in boundary_loops(mesh, &self.blocks)? {
                let k = lp.len();
                for i in 0..k {
                    next[lp[i]] = vec![lp[(i + k - 1) % k], lp[(i + 1) % k]];
                }
            }
        }
        let d = model.dofs.dim;
        // the own nodes kept where the run left them: in 3D, first those beside a solid's
        // node that a condition holds
        let mut kept = vec![false; mesh.coords.len()];
        let blocks = if mesh.dim == 3 { &self.blocks[..] } else { &[] };
        for blk in blocks.iter().map(|&b| &mesh.cells[b]) {
            for cell in (0..blk.n_cells()).map(|c| blk.cell(c)) {
                if cell.iter().any(|&n| on_solid[n]) {
                    for &n in cell
                        .iter()
                        .filter(|&&n| (0..d).any(|i| model.held_along(n, i)))
                    {
                        kept[n] = true;
                    }
                }
            }
        }
        let own: Vec<usize> = (0..mesh.coords.len())
            .filter(|&n| !next[n].is_empty() && !on_solid[n])
            .collect();
        let hinges = hinges(&outer);
        loop {
            let places = place_own(model, x, &next, &own, on_solid, &kept)?;
            let at = |n: usize| places[n].unwrap_or_else(|| model.placed(n, x));
            let now = |n: usize| model.placed(n, x);
            // the nodes of triangles turned over, the far corners of two on an edge closed
            // onto each other, and the nodes of two that cross
            let turned = (outer.iter()).filter(|f| folds(f.map(now), f.map(at)));
            let shut = (hinges.iter()).filter(|h| closes(h.map(now), h.map(at)));
            let mut folded: Vec<usize> = turned.flatten().copied().collect();
            folded.extend(shut.flat_map(|h| [h[2], h[3]]));
            let moved = |f: &[usize; 3]| f.iter().any(|&n| places[n].is_some() && !kept[n]);
            folded.extend(crossing(&outer, moved, at).into_iter().flatten());
            folded.retain(|&n| !on_solid[n] && !kept[n]);
            if folded.is_empty() {
                return Ok(places);
            }
            folded.into_iter().for_each(|n| kept[n] = true);
        }
    }

    /// The medium in words, for `tmc check`.
    pub fn describe(&self, model: &Model) -> String {
        let cells: usize = self
            .blocks
            .iter()
            .map(|&b| model.mesh.cells[b].n_cells())
            .sum();
        let new = match model.mesh.dim {
            3 => "tetrahedra (gmsh's, between the medium's faces)",
            _ => "triangles",
        };
        format!(
            "medium made again as the bodies move: its {cells} cells replaced by new {new} \
             once any cell's faces have slid {SLID} of a cell past each other"
        )
    }

    /// Whether the medium is to be made again at the accepted state `x`, or the next step cut.
    ///
    /// A sliver's node that passes the end of the edge across from it stands over the next
    /// face, and the sliver, squeezed to hold a contact, opens (or inverts) as it goes on.
    /// Each sliver's node is followed from one accepted state (at `t`) to the next; where the
    /// next step (to `target`), at the speed of the last, would take one past an end, the
    /// medium is made again now if a node has gone [`FRESH`] of its edge since it was made;
    /// else the watch says when the node gets there ([`Watch::Until`]), the run cuts the step
    /// to end just past it, and the medium is made again after it, the node joined to the
    /// next face. (Made again just before, the node would be joined across the same edge
    /// again, and due again at the next step.) A node found past an end is due at once, unless
    /// the next step takes others past theirs before it is [`PAST_END`] beyond: then it waits
    /// for the last of them (see [`passing`]). In 3D a thin tetrahedron's corner the next step
    /// would take past the face across is due at once: without friction, once a thin
    /// tetrahedron has gone [`FRESH`] since the medium was made.
    pub fn due(
        &mut self,
        model: &Model,
        reference: &CellReferences,
        x: &[f64],
        t: f64,
        target: f64,
    ) -> Watch {
        let dt = t - self.t;
        let mut rate = 0.0f64;
        // how far a node has gone along its face since the medium was made (edge lengths)
        let mut travel = 0.0f64;
        let mut along = Vec::with_capacity(self.slivers.len());
        for s in &mut self.slivers {
            let (at, length) = along_edge(model, s, x);
            travel = travel.max((at - s.from).abs());
            let speed = if dt > 0.0 { (at - s.at) / dt } else { 0.0 };
            along.push((at, speed));
            rate = rate.max(speed.abs() * length);
            s.at = at;
        }
        let (mut passed, passes) = passing(&along, t, target);
        let rubs = !model.slides_freely_in_3d();
        let mut thin_passed = false;
        for s in &mut self.thin {
            let (now, length) = s.standing(model, x);
            if s.from.is_empty() {
                // a checkpoint's watch from before it was kept: from where it stood then
                s.from = s.room.clone();
            }
            let mut passing = false;
            for ((v, before), made) in now.iter().zip(&s.room).zip(&s.from) {
                let speed = if dt > 0.0 { (v - before) / dt } else { 0.0 };
                // made again before the pass: in 3D a corner taken past it, as after it,
                // stopped the sphere of `sphere-drag` dragged three radii
                passing |= *v < 0.0 || v + speed * (target - t) < 0.0;
                rate = rate.max(speed.abs() * length);
                travel = travel.max((v - made).abs());
            }
            // without friction a pass asks only where it squeezes the tetrahedron: a corner
            // that passes an edge between faces that stay parallel leaves its volume as it
            // is, and in the closed layer under the square pad such passes asked at nearly
            // every step (199 remakes in 229 steps)
            let volume = s.volume(model, x);
            passing &= rubs || s.squeezed_by(volume, dt, target - t);
            thin_passed |= passing;
            s.volume = volume;
            s.room = now;
        }
        // without friction a thin tetrahedron's pass asks once one has gone [`FRESH`] since
        // the medium was made: a corner gmsh made beside an edge across, crawling past it,
        // asked at each step of a press and got the same tetrahedron back. With friction at
        // once: so gated, the 3D square pad at μ = 0.3 stalled at a drag of 0.43 of 1.
        passed |= thin_passed && (travel >= FRESH || rubs);
        self.t = t;
        self.rate = rate;
        // made for a pass that has not come once a node has gone a whole edge since
        self.made_for_pass &= travel < 1.0;
        // a node about to pass where the medium was made long ago: made again before it,
        // once
        let stale = passes.is_finite() && travel >= FRESH && !self.made_for_pass;
        // the cells' slide and squeeze are looked at only where nothing else has asked already
        let remake = stale
            || passed
            || self.slid_cells(model, reference, x) >= SLID
            || self.crushed(model, reference, x, travel >= FRESH)
            || self.thin_quadrilateral(model, x);
        if remake {
            // made while a pass is coming, before it: fresh for it, whatever asked
            self.made_for_pass = passes.is_finite() && !passed;
            Watch::Remake
        } else if passes.is_finite() {
            Watch::Until(passes)
        } else {
            Watch::Go
        }
    }

    /// Whether a body has crushed the medium at the state `x`: in 2D, a cell of the medium as
    /// made again (the drawn medium closes its gaps this way in a press), its J at its centre
    /// fallen below [`CLOSED`] times what it was made with. The watch follows the layers'
    /// slivers and the cells' slide, and neither sees a body's face run onto a node of the
    /// medium ahead of it, nor a corner dig into the face it slides on. The pad in a box on
    /// triangles at μ = 0.5 (h = 0.1, steps of 0.01) slid 0.079 onto such a node, 0.065 ahead
    /// of its leading face when the medium was made, and stopped at a drag of 1.517 of 5 with
    /// the cell between them flat
    /// (docs/notes/2026-12-07-a-face-that-runs-onto-the-medium-and-the-2d-pad-s-drag.md). At
    /// μ = 1 its leading corner pressed the closed layer's cell under it from J = 3.4e-3 to
    /// 1.0e-3 over a slide of 0.11 with no remake, and the drag stopped at 0.152 of its width
    /// (docs/notes/2026-12-07-the-pad-at-mu-1-and-a-residual-that-stays-met.md).
    ///
    /// In 3D without friction too, since its thin tetrahedra's passes ask only where they
    /// squeeze them: a cell with a node on a body's edge ([`Medium::at_edge`]) at once (the
    /// square pad's leading face runs onto the plate's nodes ahead of it), any other once the
    /// bodies have slid (`slid`: a thin tetrahedron has gone [`FRESH`] since the medium was
    /// made). Asked at once, a hemisphere's press, whose gap closes over the plate's nodes,
    /// was made again 12 times in 80 load steps (3 in 52 so gated; 2 in 49 without the
    /// watch).
    fn crushed(&self, model: &Model, reference: &CellReferences, x: &[f64], slid: bool) -> bool {
        let now = self.made_cells(model, reference, x);
        // a checkpoint from before each cell's J was kept: measured from the next remake
        let watched = |i: usize| model.mesh.dim == 2 || slid || self.at_edge.get(i) == Some(&true);
        now.len() == self.made_j.len()
            && (now.iter().zip(&self.made_j).enumerate())
                .any(|(i, (&J, &made))| J < CLOSED * made && watched(i))
    }

    /// The J at the state `x` at the centre of each cell of the medium as made again, block by
    /// block (none before a remake, nor in 3D with friction, whose thin tetrahedra's passes
    /// all ask).
    fn made_cells(&self, model: &Model, reference: &CellReferences, x: &[f64]) -> Vec<f64> {
        let mut J = Vec::new();
        let dim = model.mesh.dim;
        if dim == 3 && !model.slides_freely_in_3d() {
            return J;
        }
        for &b in (self.blocks.iter()).filter(|&&b| model.cell_reference[b].is_some()) {
            at_centres(model, reference, x, b, |_, F| {
                J.push(F.map_or(1.0, |F| volume_ratio(&F, dim)))
            });
        }
        J
    }

    /// Per cell in [`Medium::made_cells`]' order, whether it has a node on a body's edge at the
    /// state `x` (in 3D; none in 2D).
    fn cells_at_edges(&self, model: &Model, x: &[f64]) -> Vec<bool> {
        if !model.slides_freely_in_3d() {
            return Vec::new();
        }
        let edge = body_edges(model, &self.blocks, x);
        let mut at = Vec::new();
        for &b in (self.blocks.iter()).filter(|&&b| model.cell_reference[b].is_some()) {
            let blk = &model.mesh.cells[b];
            at.extend((0..blk.n_cells()).map(|c| blk.cell(c).iter().any(|&n| edge[n])));
        }
        at
    }

    /// Whether one of the medium's quadrilaterals has become thin at the state `x` (its
    /// slenderness below [`THINNEST`], as a layer closing makes it). Its faces' nodes then
    /// pass each other inside one cell, which no sliver's watch follows: a pad's corner went
    /// through the plate's face inside one before the first remake was due (a slide of 0.02).
    /// A medium made again is of triangles, whose slivers are followed.
    fn thin_quadrilateral(&self, model: &Model, x: &[f64]) -> bool {
        self.blocks.iter().any(|&b| {
            let blk = &model.mesh.cells[b];
            blk.kind == crate::mesh::CellKind::Quad4
                && (0..blk.n_cells()).any(|c| {
                    let p: Vec<[f64; 3]> =
                        blk.cell(c).iter().map(|&n| model.placed(n, x)).collect();
                    slenderness(&p, false) < THINNEST
                })
        })
    }

    /// The run stuck on the medium as made (a step failed twice from one state): in 3D the
    /// remake that follows fills the medium with the other mesher first (the medium made then
    /// starts again from Delaunay's). Returns whether it changed.
    pub fn stuck(&mut self, model: &Model) -> bool {
        let swap = model.mesh.dim == 3;
        if swap {
            self.mesher = self.mesher.other();
        }
        swap
    }

    /// Which of gmsh's meshers fills the medium first at its next remake.
    pub fn mesher(&self) -> Mesher {
        self.mesher
    }

    /// Start following the medium's slivers at the state `x` at `t` (the initial state, or the
    /// one the medium was just made again at), their nodes taken to move along their edges
    /// at most at `rate`, the speed of the last step. Returns the longest step (in
    /// pseudo-time) that takes none of them past an end at that speed.
    pub fn start(&mut self, model: &Model, x: &[f64], t: f64, rate: f64) -> f64 {
        self.slivers.clear();
        self.thin.clear();
        let on_solid = model.on_solids();
        self.made_j = self.made_cells(model, &model.cell_reference, x);
        self.at_edge = self.cells_at_edges(model, x);
        self.t = t;
        self.rate = rate;
        let mut room = f64::INFINITY;
        for &b in &self.blocks {
            let blk = &model.mesh.cells[b];
            if blk.kind == crate::mesh::CellKind::Tet4 {
                // the thin tetrahedra across a gap between solids' faces, as made
                for c in 0..blk.n_cells() {
                    let nodes = blk.cell(c);
                    if !nodes.iter().all(|&n| on_solid[n]) {
                        continue;
                    }
                    let p: Vec<[f64; 3]> = nodes.iter().map(|&n| model.placed(n, x)).collect();
                    let Some(mut s) = ThinTet::of(b, c, &p) else {
                        continue;
                    };
                    let (now, length) = s.standing(model, x);
                    let least = now.iter().fold(f64::INFINITY, |a, &v| a.min(v));
                    if least > 0.0 {
                        s.volume = s.volume(model, x);
                        s.made_volume = s.volume;
                        room = room.min(least * length);
                        s.from = now.clone();
                        s.room = now;
                        self.thin.push(s);
                    }
                }
            }
            if blk.kind != crate::mesh::CellKind::Tri3 {
                continue;
            }
            for c in 0..blk.n_cells() {
                let p: Vec<[f64; 3]> = blk.cell(c).iter().map(|&n| model.placed(n, x)).collect();
                if slenderness(&p, true) >= THINNEST {
                    continue;
                }
                let (i, _) = longest_edge(&p, 3);
                let mut s = Sliver {
                    block: b,
                    cell: c,
                    edge: [i, (i + 1) % 3],
                    across: (i + 2) % 3,
                    at: 0.0,
                    from: 0.0,
                };
                let (at, length) = along_edge(model, &s, x);
                s.at = at;
                s.from = at;
                room = room.min(at.min(1.0 - at).max(0.0) * length);
                self.slivers.push(s);
            }
        }
        match rate > 0.0 {
            true => room / rate,
            false => f64::INFINITY,
        }
    }

    /// The medium made again at the accepted state `x` of `model`.
    ///
    /// The medium's own outer faces are placed anew (`own_places`) where the new medium can be
    /// made between them and the solids; where it cannot (they would cross a body that left
    /// the box drawn around it), they stay where they are.
    pub fn remake(
        &self,
        model: &Model,
        reference: &CellReferences,
        x: &[f64],
    ) -> Result<Remade, RemeshError> {
        failing_by_request()?;
        let here = vec![None; model.mesh.coords.len()];
        let on_solid = model.on_solids();
        let at = |own: &[Option<[f64; 3]>]| self.remake_at(model, reference, x, own, &on_solid);
        match self.own_places(model, x, &on_solid) {
            Ok(own) => at(&own).or_else(|_| at(&here)),
            Err(_) => at(&here),
        }
    }

    /// The medium made again at the accepted state `x` of `model`, its own outer nodes at
    /// `own`'s places where given (`on_solid`: per node, whether it is a solid's).
    fn remake_at(
        &self,
        model: &Model,
        reference: &CellReferences,
        x: &[f64],
        own: &[Option<[f64; 3]>],
        on_solid: &[bool],
    ) -> Result<Remade, RemeshError> {
        let placed: Vec<[f64; 3]> = (0..model.mesh.coords.len())
            .map(|n| own[n].unwrap_or_else(|| model.placed(n, x)))
            .collect();
        let r = remesh(&model.mesh, &placed, &self.blocks, on_solid, self.mesher)?;
        let find = Locator::new(model, reference, &self.blocks, x);
        let here = |n: usize| match r.old_of[n] {
            Some(o) => placed[o],
            None => r.mesh.coords[n],
        };
        let dim = r.mesh.dim;
        // the bodies: the blocks not made again, the solids' (a case gives `remake` on every
        // medium region or on none). The old squeeze is looked up where it is used: over the
        // cells across a gap (all their corners on solids), whose squeeze gives a layer its
        // thickness, and over the rest only where no layer was closed (a sliding run's medium
        // is mostly the rest)
        let body = r.mesh.components(|b| !r.medium.contains(&b));
        let across = |b: usize, c: usize| spans_gap(r.mesh.cells[b].cell(c), &body, dim);
        // each new cell's old state looked up on its own: over the threads the run has
        let at: Vec<(usize, usize)> = (r.medium.iter())
            .flat_map(|&b| (0..r.mesh.cells[b].n_cells()).map(move |c| (b, c)))
            .collect();
        let mut cells: Vec<NewCell> = (at.into_par_iter())
            .map(|(b, c)| {
                let p: Vec<[f64; 3]> = r.mesh.cells[b].cell(c).iter().map(|&n| here(n)).collect();
                let k = p.len() as f64;
                let mid = std::array::from_fn(|i| p.iter().map(|q| q[i]).sum::<f64>() / k);
                let F = match across(b, c) {
                    true => squeezed(&find, &p, mid),
                    false => Matrix3::identity(),
                };
                NewCell { b, c, p, mid, F }
            })
            .collect();
        let mut layers = Layers::of(&r.mesh, &body, &cells);
        if dim == 3 {
            let normals = solid_normals(&r.mesh, &r.medium, &body, here)?;
            layers.unface(&r.mesh, &body, &cells, &normals);
        }
        if !layers.closed() {
            (cells.par_iter_mut())
                .filter(|cell| !across(cell.b, cell.c))
                .for_each(|cell| cell.F = squeezed(&find, &cell.p, cell.mid));
        }
        let mut reference: Vec<Option<Vec<[f64; 3]>>> = vec![None; r.mesh.cells.len()];
        for &b in &r.medium {
            reference[b] = Some(Vec::with_capacity(r.mesh.cells[b].conn.len()));
        }
        for (k, cell) in cells.iter().enumerate() {
            let (p, mid) = (&cell.p, cell.mid);
            let stretch = match layers.carried(k, p) {
                Some(back) => back,
                // beside a closed layer the medium is open: its old squeeze is what ploughs
                None if layers.closed() => opened(p, dim),
                None => carried_stretch(&cell.F, dim).unwrap_or_else(|| opened(p, dim)),
            };
            let refs = reference[cell.b].as_mut().expect("a medium block");
            for q in p {
                refs.push(match dim {
                    2 => {
                        let X = plane(&stretch) * Vector2::new(q[0] - mid[0], q[1] - mid[1]);
                        [mid[0] + X[0], mid[1] + X[1], 0.0]
                    }
                    _ => {
                        let X = stretch * Vector3::new(q[0] - mid[0], q[1] - mid[1], q[2] - mid[2]);
                        [mid[0] + X[0], mid[1] + X[1], mid[2] + X[2]]
                    }
                });
            }
        }
        let theta = (0..r.mesh.coords.len())
            .into_par_iter()
            .map(|n| match r.old_of[n] {
                Some(_) => 0.0,
                None => find.value(&here(n), |at| Some(at.theta())).unwrap_or(0.0),
            })
            .collect();
        let own = (r.old_of.iter())
            .map(|o| {
                let c = model.mesh.coords[(*o)?];
                own[(*o)?].map(|p| [p[0] - c[0], p[1] - c[1], p[2] - c[2]])
            })
            .collect();
        Ok(Remade {
            mesh: r.mesh,
            reference,
            old_of: r.old_of,
            theta,
            own,
        })
    }
}

/// For the tests of a remake that fails (`tests/it/sliding.rs`): whether this remake (from 1)
/// is one of those `TMC_TEST_REMAKE_FAILS` lists, by commas, and how: `N` as the mesher
/// fails (the run may go on a step), `N!` as a medium whose boundary crosses itself (it may
/// not). Unset in any real run.
fn failing_by_request() -> Result<(), RemeshError> {
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let Ok(list) = std::env::var("TMC_TEST_REMAKE_FAILS") else {
        return Ok(());
    };
    let call = (CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1).to_string();
    let why = "the remake was asked to fail (TMC_TEST_REMAKE_FAILS)".to_string();
    for item in list.split(',').map(str::trim) {
        match item.strip_suffix('!') {
            Some(n) if n == call => return Err(RemeshError { why, mesher: false }),
            None if item == call => return Err(RemeshError { why, mesher: true }),
            _ => {}
        }
    }
    Ok(())
}

/// Where a triangle of the medium's outer faces counts as turned over when placed: its normal
/// turned by more than this (in radians) from the one it has at the state, or its area gone.
const FOLD: f64 = std::f64::consts::FRAC_PI_3;

/// Whether the triangle at `now` turns over where placed at `placed` (see [`FOLD`]).
fn folds(now: [[f64; 3]; 3], placed: [[f64; 3]; 3]) -> bool {
    let normal = |p: [[f64; 3]; 3]| {
        let v = p.map(Vector3::from);
        (v[1] - v[0]).cross(&(v[2] - v[0]))
    };
    let (a, b) = (normal(now), normal(placed));
    let size = a.norm() * b.norm();
    !(size > 0.0 && a.dot(&b) > FOLD.cos() * size)
}

/// Each edge that two of the `triangles` share, as [a, b, c, d]: the edge a–b, c and d the
/// two triangles' third corners.
fn hinges(triangles: &[[usize; 3]]) -> Vec<[usize; 4]> {
    let mut sides: Vec<([usize; 2], usize)> = (triangles.iter())
        .flat_map(|f| (0..3).map(move |i| (f[i], f[(i + 1) % 3], f[(i + 2) % 3])))
        .map(|(a, b, c)| ([a.min(b), a.max(b)], c))
        .collect();
    sides.sort_unstable();
    (sides.windows(2))
        .filter(|w| w[0].0 == w[1].0)
        .map(|w| [w[0].0[0], w[0].0[1], w[0].1, w[1].1])
        .collect()
}

/// Where two triangles on an edge count as closed onto each other: the angle between them
/// (about the edge) below this, in radians.
const CREASE: f64 = 0.25;

/// Whether the two triangles of the hinge [a, b, c, d] (see [`hinges`]) close onto each other
/// where placed at `placed`, from their angle at `now` (see [`CREASE`]).
fn closes(now: [[f64; 3]; 4], placed: [[f64; 3]; 4]) -> bool {
    let angle = |p: [[f64; 3]; 4]| {
        let v = p.map(Vector3::from);
        let e = (v[1] - v[0]).normalize();
        let across = |w: Vector3<f64>| {
            let r = w - v[0];
            r - e * e.dot(&r)
        };
        across(v[2]).angle(&across(v[3]))
    };
    let after = angle(placed);
    after < CREASE && after < angle(now)
}

/// The triangles of `faces` (at the places `at`) that cross another of them, among those that
/// `moved` and any other: two that share no corner and one of whose edges goes through the
/// other (what gmsh refuses as "a segment and a facet intersect").
fn crossing(
    faces: &[[usize; 3]],
    moved: impl Fn(&[usize; 3]) -> bool,
    at: impl Fn(usize) -> [f64; 3],
) -> Vec<[usize; 3]> {
    let corners = |f: &[usize; 3]| f.map(|n| Vector3::from(at(n)));
    let boxes: Vec<([f64; 3], [f64; 3])> = (faces.iter())
        .map(|f| {
            let p = f.map(&at);
            let lo = std::array::from_fn(|i| p.iter().map(|q| q[i]).fold(f64::INFINITY, f64::min));
            let hi =
                std::array::from_fn(|i| p.iter().map(|q| q[i]).fold(f64::NEG_INFINITY, f64::max));
            (lo, hi)
        })
        .collect();
    // the triangles in a grid of cells about as large as the median one
    let mut sizes: Vec<f64> = boxes
        .iter()
        .map(|(lo, hi)| (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f64::max))
        .collect();
    sizes.sort_by(f64::total_cmp);
    let Some(&size) = sizes.get(sizes.len() / 2).filter(|&&s| s > 0.0) else {
        return Vec::new();
    };
    let key = |p: [f64; 3]| p.map(|v| (v / size).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (k, (lo, hi)) in boxes.iter().enumerate() {
        let (a, b) = (key(*lo), key(*hi));
        for i in a[0]..=b[0] {
            for j in a[1]..=b[1] {
                for l in a[2]..=b[2] {
                    grid.entry([i, j, l]).or_default().push(k);
                }
            }
        }
    }
    let overlap = |k: usize, m: usize| {
        (0..3).all(|i| boxes[k].0[i] <= boxes[m].1[i] && boxes[m].0[i] <= boxes[k].1[i])
    };
    let mut out = Vec::new();
    let mut seen = HashSet::new();
    for members in grid.values() {
        for (i, &k) in members.iter().enumerate() {
            for &m in &members[i + 1..] {
                let (f, g) = (&faces[k], &faces[m]);
                if !(moved(f) || moved(g)) || f.iter().any(|n| g.contains(n)) || !overlap(k, m) {
                    continue;
                }
                if seen.insert((k.min(m), k.max(m))) && triangles_cross(corners(f), corners(g)) {
                    out.extend([*f, *g]);
                }
            }
        }
    }
    out
}

/// Whether an edge of either triangle goes through the other.
fn triangles_cross(a: [Vector3<f64>; 3], b: [Vector3<f64>; 3]) -> bool {
    let through = |t: &[Vector3<f64>; 3], p: Vector3<f64>, q: Vector3<f64>| {
        let vol = |a: Vector3<f64>, b: Vector3<f64>, c: Vector3<f64>, d: Vector3<f64>| {
            (b - a).cross(&(c - a)).dot(&(d - a))
        };
        let (s, e) = (vol(t[0], t[1], t[2], p), vol(t[0], t[1], t[2], q));
        if s * e >= 0.0 {
            return false;
        }
        let sides = [
            vol(p, q, t[0], t[1]),
            vol(p, q, t[1], t[2]),
            vol(p, q, t[2], t[0]),
        ];
        sides.iter().all(|&v| v > 0.0) || sides.iter().all(|&v| v < 0.0)
    };
    (0..3).any(|i| through(&b, a[i], a[(i + 1) % 3]) || through(&a, b[i], b[(i + 1) % 3]))
}

/// The places of the medium's `own` boundary nodes (see `Medium::own_places`) at the state
/// `x`, `next` each node's neighbours along the boundary: per component, the solids' nodes
/// (`on_solid`), the `kept` and what is prescribed hold; the rest is the mean of its
/// neighbours, a little held to where the mesh put it (so that a part no solid touches stays
/// there).
fn place_own(
    model: &Model,
    x: &[f64],
    next: &[Vec<usize>],
    own: &[usize],
    on_solid: &[bool],
    kept: &[bool],
) -> Result<Vec<Option<[f64; 3]>>, String> {
    let mesh = &model.mesh;
    let d = model.dofs.dim;
    let u_of = |n: usize, i: usize| model.dofs.u.get(n * d + i).map(|&u| u as usize);
    let mut places = vec![None; mesh.coords.len()];
    for i in 0..d {
        let held = |n: usize| on_solid[n] || kept[n] || model.held_along(n, i);
        let value = |n: usize| u_of(n, i).map_or(0.0, |u| x[u]);
        let free: Vec<usize> = own.iter().copied().filter(|&n| !held(n)).collect();
        let mut at = vec![usize::MAX; mesh.coords.len()];
        free.iter().enumerate().for_each(|(k, &n)| at[n] = k);
        let weight = |n: usize| next[n].len() as f64 * (1.0 + 1e-9);
        let rhs: Vec<f64> = (free.iter())
            .map(|&n| {
                next[n]
                    .iter()
                    .filter(|&&m| held(m))
                    .map(|&m| value(m))
                    .sum()
            })
            .collect();
        let apply = |v: &[f64], out: &mut [f64]| {
            for (k, &n) in free.iter().enumerate() {
                let around: f64 = (next[n].iter())
                    .filter(|&&m| at[m] != usize::MAX)
                    .map(|&m| v[at[m]])
                    .sum();
                out[k] = weight(n) * v[k] - around;
            }
        };
        let diagonal: Vec<f64> = free.iter().map(|&n| weight(n)).collect();
        let u = mean_of_neighbours(apply, &diagonal, &rhs)
            .ok_or("the medium's outer faces could not be placed")?;
        for (k, &n) in free.iter().enumerate() {
            places[n].get_or_insert(mesh.coords[n])[i] += u[k];
        }
        for &n in own.iter().filter(|&&n| held(n)) {
            places[n].get_or_insert(mesh.coords[n])[i] += value(n);
        }
    }
    Ok(places)
}

/// The solution v of A v = b, A symmetric positive definite given by its product `apply`
/// and its diagonal (the medium's outer faces' graph Laplacian, `Medium::own_places`), by
/// conjugate gradients preconditioned by the diagonal, to 1e-12 of b; `None` if that was not
/// reached in as many iterations as unknowns and a hundred more.
fn mean_of_neighbours(
    apply: impl Fn(&[f64], &mut [f64]),
    diagonal: &[f64],
    b: &[f64],
) -> Option<Vec<f64>> {
    let n = b.len();
    let dot = |p: &[f64], q: &[f64]| p.iter().zip(q).map(|(a, b)| a * b).sum::<f64>();
    let mut v = vec![0.0; n];
    let mut r = b.to_vec();
    let tol = 1e-12 * dot(b, b).sqrt();
    let mut z: Vec<f64> = r.iter().zip(diagonal).map(|(r, d)| r / d).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; n];
    for _ in 0..n + 100 {
        if dot(&r, &r).sqrt() <= tol {
            return Some(v);
        }
        apply(&p, &mut ap);
        let alpha = rz / dot(&p, &ap);
        v.iter_mut().zip(&p).for_each(|(v, p)| *v += alpha * p);
        r.iter_mut().zip(&ap).for_each(|(r, a)| *r -= alpha * a);
        z.iter_mut()
            .zip(r.iter().zip(diagonal))
            .for_each(|(z, (r, d))| *z = r / d);
        let next = dot(&r, &z);
        let beta = next / rz;
        rz = next;
        p.iter_mut().zip(&z).for_each(|(p, z)| *p = z + beta * *p);
    }
    (dot(&r, &r).sqrt() <= tol).then_some(v)
}

/// The friction history of every friction block of `new`, the model of a medium made again,
/// at its state `x` (one slab per block, in the order of `new.friction_blocks`): each new point
/// carries on what the old medium (`old` at the state `old_x`, its cells measured from
/// `old_reference`, the committed history `old_slabs` per friction block of `old`)
/// transmitted where it stands, the share of its
/// Coulomb limit and its traction's direction (`kernel::friction::carried_cell`). The work a
/// region's old cells dissipated is shared among its new points by their volume, so that the
/// run's friction work and heat go on whole.
pub fn carried_friction(
    old: &Model,
    old_reference: &CellReferences,
    old_x: &[f64],
    old_slabs: &[&[f64]],
    new: &Model,
    x: &[f64],
) -> Result<Vec<Vec<f64>>, String> {
    use crate::kernel::friction::{carried_cell, dissipated_work, share_work, transmitted};
    let mut slabs = Vec::with_capacity(new.friction_blocks.len());
    let mut volumes = Vec::with_capacity(new.friction_blocks.len());
    for fb in &new.friction_blocks {
        let olds: Vec<usize> = (0..old.friction_blocks.len())
            .filter(|&k| old.friction_blocks[k].region == fb.region)
            .collect();
        let blocks: Vec<usize> = olds.iter().map(|&k| old.friction_blocks[k].block).collect();
        let find = Locator::new(old, old_reference, &blocks, old_x);
        let at = |y: &[f64; 3]| {
            find.value(y, |cell| {
                let (b, c) = cell.cell();
                let k = olds[blocks.iter().position(|&o| o == b)?];
                let ofb = &old.friction_blocks[k];
                let width = old_slabs[k].len() / old.mesh.cells[b].n_cells();
                let q = width * c + cell.nearest_point() * HISTORY_PER_POINT;
                let F = cell.F()?;
                let h = &old_slabs[k][q..q + HISTORY_PER_POINT];
                Some(transmitted(&ofb.mat, ofb.normals.of(c), &F, h))
            })
            .unwrap_or((0.0, Matrix3::zeros()))
        };
        let blk = &new.mesh.cells[fb.block];
        let (slab, dV) = crate::with_cell!(blk.kind, |N, D, E| {
            let points = E::quadrature().len();
            let mut slab = vec![0.0; blk.n_cells() * points * HISTORY_PER_POINT];
            let mut dV = vec![0.0; blk.n_cells() * points];
            // each cell looked up on its own: over the threads the run has
            (slab.par_chunks_mut(points * HISTORY_PER_POINT))
                .zip(dV.par_chunks_mut(points))
                .enumerate()
                .try_for_each(|(c, (h, v))| {
                    let s = new.cell_state::<N>(fb.block, c, x);
                    carried_cell::<N, D, E>(&fb.mat, fb.normals.of(c), &fb.layout, &s, at, h, v)
                        .map_err(|e| format!("cell {c} of the new medium: {e:?}"))
                })?;
            Ok::<_, String>((slab, dV))
        })?;
        slabs.push(slab);
        volumes.push(dV);
    }
    for (f, fb) in new.friction_blocks.iter().enumerate() {
        let same = |g: &&crate::model::FrictionBlock| g.region == fb.region;
        let work: f64 = (old.friction_blocks.iter().zip(old_slabs))
            .filter(|(g, _)| same(g))
            .map(|(_, h)| dissipated_work(h))
            .sum();
        let volume: f64 = (new.friction_blocks.iter().zip(&volumes))
            .filter(|(g, _)| same(g))
            .map(|(_, v)| v.iter().sum::<f64>())
            .sum();
        let per_volume = if volume > 0.0 { work / volume } else { 0.0 };
        share_work(&mut slabs[f], &volumes[f], per_volume);
    }
    Ok(slabs)
}

/// Where along its edge a sliver's node across it stands at the state `x` (0 and 1 at the
/// edge's ends), and the edge's length.
fn along_edge(model: &Model, s: &Sliver, x: &[f64]) -> (f64, f64) {
    let nodes = model.mesh.cells[s.block].cell(s.cell);
    let [a, b, k] = [s.edge[0], s.edge[1], s.across].map(|i| model.placed(nodes[i], x));
    let e = [b[0] - a[0], b[1] - a[1]];
    let l2 = (e[0] * e[0] + e[1] * e[1]).max(f64::MIN_POSITIVE);
    (
        ((k[0] - a[0]) * e[0] + (k[1] - a[1]) * e[1]) / l2,
        l2.sqrt(),
    )
}

/// F₀⁻¹ of a new cell whose centre stood where the old medium's deformation gradient was
/// `F` (in `dim` dimensions): a closed layer (J < [`CLOSED`]) stretched back by 1/J along the
/// direction F squeezed most; the identity elsewhere.
fn carried_stretch(F: &Matrix3<f64>, dim: usize) -> Option<Matrix3<f64>> {
    let J = volume_ratio(F, dim);
    if !(J > 0.0 && J < CLOSED) {
        return None;
    }
    if dim == 3 {
        let e = SymmetricEigen::new(F * F.transpose());
        let n: Vector3<f64> = e.eigenvectors.column(e.eigenvalues.imin()).into();
        return Some(Matrix3::identity() + (1.0 / J - 1.0) * n * n.transpose());
    }
    let F = plane(F);
    let e = SymmetricEigen::new(F * F.transpose());
    let i = if e.eigenvalues[0] <= e.eigenvalues[1] {
        0
    } else {
        1
    };
    let n: Vector2<f64> = e.eigenvectors.column(i).into();
    Some(embed(
        Matrix2::identity() + (1.0 / J - 1.0) * n * n.transpose(),
    ))
}

/// A new medium cell: its block and number, its nodes' places and their mean, and the old
/// medium's most squeezed deformation gradient over it (the identity where it is not used: a
/// cell not across a gap, where a layer was closed).
struct NewCell {
    b: usize,
    c: usize,
    p: Vec<[f64; 3]>,
    mid: [f64; 3],
    F: Matrix3<f64>,
}

/// The old medium's most squeezed state over a new cell with nodes at `p` and centre `mid`
/// (the smallest J there and half way to each node): a closed layer's cell that has just
/// opened beside others still closed does not speak for the layer.
fn squeezed(find: &Locator, p: &[[f64; 3]], mid: [f64; 3]) -> Matrix3<f64> {
    let dim = find.model.mesh.dim;
    (std::iter::once(mid).chain(
        p.iter()
            .map(|q| std::array::from_fn(|i| 0.5 * (mid[i] + q[i]))),
    ))
    .filter_map(|at| find.value(&at, |cell| cell.F()))
    .min_by(|a, b| volume_ratio(a, dim).total_cmp(&volume_ratio(b, dim)))
    .unwrap_or_else(Matrix3::identity)
}

/// A sliver across a closed layer squeezed more than this many times (thinner than its
/// layer's thickness of reference over this) is asked whether its faces face each other
/// ([`Layers::unface`]). The square pad in 3D slid without friction met the plate's rows with
/// slivers squeezed 30 to 900 times along the slide. Asked from 8, the hemisphere dragged three
/// radii (the wedge around its contact holds slivers squeezed a few times across it) met
/// 0.0304 where it met 0.0300; from 20, 0.0299.
const UNFACED: f64 = 20.0;

/// Whether the way across a cell, `n`, runs between faces that face each other: within 60° of
/// the normal of each body's faces at the cell (`sides`, the sum of its nodes' normals).
fn facing(n: Vector3<f64>, mut sides: impl Iterator<Item = Vector3<f64>>) -> bool {
    let half = std::f64::consts::FRAC_PI_3.cos();
    sides.all(|m| {
        m.try_normalize(0.0)
            .is_some_and(|m| m.dot(&n).abs() >= half)
    })
}

/// Where two faces of one body meet at an angle past this, a node between them is on the
/// body's edge: a pad's corners and edges are; a hemisphere's facets on a coarse mesh are not.
const EDGE_ANGLE: f64 = std::f64::consts::FRAC_PI_6;

/// Per node of `model`'s mesh, whether it is on a body's edge at the state `x`: a node where
/// two faces of one body that border the `medium` blocks meet at more than [`EDGE_ANGLE`]. The
/// medium's own faces on a symmetry plane with their three nodes on solids (across a gap) are
/// not a body's. Faces that cannot be told (a medium the remake made could not be walked):
/// none.
fn body_edges(model: &Model, medium: &[usize], x: &[f64]) -> Vec<bool> {
    let mesh = &model.mesh;
    let body = mesh.components(|b| !medium.contains(&b));
    let faces = bodies_faces(mesh, medium, &body).unwrap_or_default();
    let mut normals: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); mesh.coords.len()];
    for f in faces {
        let v = f.map(|n| Vector3::from(model.placed(n, x)));
        if let Some(a) = (v[1] - v[0]).cross(&(v[2] - v[0])).try_normalize(0.0) {
            f.iter().for_each(|&n| normals[n].push(a));
        }
    }
    let cos = EDGE_ANGLE.cos();
    let bent = |ns: &Vec<Vector3<f64>>| ns.iter().any(|a| ns.iter().any(|b| a.dot(b) < cos));
    normals.iter().map(bent).collect()
}

/// The faces of the `medium` blocks that are faces of one body (`body`, per node, as
/// [`Mesh::components`] gives it): not the medium's own outer faces, nor a symmetry plane's
/// medium triangle between two bodies.
fn bodies_faces(mesh: &Mesh, medium: &[usize], body: &[usize]) -> Result<Vec<[usize; 3]>, String> {
    let mut faces = crate::mesh::faces::outer_triangles(mesh, medium)?;
    faces.retain(|f| {
        f.iter()
            .all(|&n| body[n] != usize::MAX && body[n] == body[f[0]])
    });
    Ok(faces)
}

/// Per node of `mesh`, the unit normal of the solids' faces that border the medium `medium`
/// there (the sum of their areas' normals at the places `here`; zero off them): each face of
/// one body (`body`), so not a symmetry plane's medium triangle between two bodies.
fn solid_normals(
    mesh: &Mesh,
    medium: &[usize],
    body: &[usize],
    here: impl Fn(usize) -> [f64; 3],
) -> Result<Vec<Vector3<f64>>, RemeshError> {
    let mut normals = vec![Vector3::zeros(); mesh.coords.len()];
    for f in bodies_faces(mesh, medium, body)? {
        let v = f.map(|n| Vector3::from(here(n)));
        let a = (v[1] - v[0]).cross(&(v[2] - v[0]));
        f.iter().for_each(|&n| normals[n] += a);
    }
    Ok(normals
        .into_iter()
        .map(|n| n.try_normalize(0.0).unwrap_or_else(Vector3::zeros))
        .collect())
}

/// The new medium's layers one cell across: triangles whose three nodes are on solids, so
/// that each spans the gap between two faces. Those that touch one another make a layer (a
/// contact and its sides), and a layer that was closed somewhere (an old J below [`CLOSED`]
/// over one of its cells) has one thickness of reference: the median over its closed cells
/// of the thickness each had before the squeeze (its height over the old J). Each of its cells
/// thinner than that starts squeezed to it. The pressure across the layer then depends on the
/// gap alone, not on where each old cell stood: as the bodies slide, a cell that rides along
/// an inclined face (its apex on one body, its base on the other) would otherwise carry into
/// the contact the reference of the place it came from.
struct Layers {
    /// Per new cell: its height and the normal to its longest edge, if it spans a gap, and
    /// the layer it belongs to.
    across: Vec<Option<(f64, Vector3<f64>, usize)>>,
    /// Per layer, its thickness of reference (none where it was nowhere closed).
    thickness: Vec<Option<f64>>,
    /// Per new cell, whether it is a sliver between faces that do not face each other across
    /// it (see [`Layers::unface`]), which starts as the open medium does.
    unfaced: Vec<bool>,
    dim: usize,
}

impl Layers {
    /// The layers of the new medium's `cells`, `body` giving each node of `mesh` its solid
    /// body (the solids' cells joined where they share a node; `usize::MAX` for the medium's
    /// own nodes, as [`Mesh::components`] gives it).
    fn of(mesh: &Mesh, body: &[usize], cells: &[NewCell]) -> Layers {
        let dim = mesh.dim;
        fn top(root: &mut [usize], mut k: usize) -> usize {
            while root[k] != k {
                root[k] = root[root[k]];
                k = root[k];
            }
            k
        }
        // the layers: the cells across, joined where they share a node
        let mut root: Vec<usize> = (0..cells.len()).collect();
        let mut first_at: std::collections::HashMap<usize, usize> = Default::default();
        let mut height = vec![None; cells.len()];
        for (k, cell) in cells.iter().enumerate() {
            let nodes = mesh.cells[cell.b].cell(cell.c);
            if !spans_gap(nodes, body, dim) {
                continue;
            }
            let bodies: Vec<usize> = nodes.iter().map(|&n| body[n]).collect();
            height[k] = Some(across_gap(&cell.p, &bodies));
            for &n in nodes {
                let j = *first_at.entry(n).or_insert(k);
                let (a, b) = (top(&mut root, j), top(&mut root, k));
                root[a.max(b)] = a.min(b);
            }
        }
        let mut layer_of = vec![usize::MAX; cells.len()];
        let mut before: Vec<Vec<f64>> = Vec::new();
        let mut index: std::collections::HashMap<usize, usize> = Default::default();
        for (k, h) in height.iter().enumerate() {
            let Some((t, _)) = h else { continue };
            let r = top(&mut root, k);
            let l = *index.entry(r).or_insert_with(|| {
                before.push(Vec::new());
                before.len() - 1
            });
            layer_of[k] = l;
            let J = volume_ratio(&cells[k].F, dim);
            if J > 0.0 && J < CLOSED {
                before[l].push(t / J);
            }
        }
        let thickness = (before.into_iter())
            .map(|mut g| {
                g.sort_by(f64::total_cmp);
                g.get(g.len() / 2).copied()
            })
            .collect();
        let across = (height.into_iter().zip(layer_of))
            .map(|(h, l)| h.map(|(t, n)| (t, n, l)))
            .collect();
        Layers {
            across,
            thickness,
            unfaced: vec![false; cells.len()],
            dim,
        }
    }

    /// Marks the slivers across a closed layer (squeezed more than [`UNFACED`] times from its
    /// thickness of reference) whose way across runs along a body's faces rather than between
    /// faces that face each other (`normals`, per solid node, see [`solid_normals`];
    /// [`facing`]). A sliver between a pad's leading face and the plate's nodes just ahead of
    /// it, thin along the slide, would otherwise start squeezed to the layer's thickness along
    /// the slide, by up to 900 times, and push the pad back as it comes over each row of the
    /// plate's nodes (docs/notes/2026-12-06-a-sliver-squeezed-along-the-slide.md).
    fn unface(&mut self, mesh: &Mesh, body: &[usize], cells: &[NewCell], normals: &[Vector3<f64>]) {
        for (k, cell) in cells.iter().enumerate() {
            let Some((t, n, l)) = self.across[k] else {
                continue;
            };
            if self.thickness[l].is_none_or(|g| t * UNFACED >= g) {
                continue;
            }
            let mut sides: Vec<(usize, Vector3<f64>)> = Vec::new();
            for &m in mesh.cells[cell.b].cell(cell.c) {
                match sides.iter_mut().find(|(b, _)| *b == body[m]) {
                    Some((_, v)) => *v += normals[m],
                    None => sides.push((body[m], normals[m])),
                }
            }
            self.unfaced[k] = !facing(n, sides.into_iter().map(|(_, v)| v));
        }
    }

    /// Whether any layer was closed.
    fn closed(&self) -> bool {
        self.thickness.iter().any(Option::is_some)
    }

    /// F₀⁻¹ of new cell `k` if it is a cell across a layer that was closed: its current shape
    /// stretched across the layer to the layer's thickness of reference where it is thinner
    /// (the identity, or a sliver opened, where it is not); `None` for any other cell.
    fn carried(&self, k: usize, p: &[[f64; 3]]) -> Option<Matrix3<f64>> {
        let (t, n, l) = self.across[k]?;
        let g = self.thickness[l]?;
        if self.unfaced[k] {
            return Some(opened(p, self.dim));
        }
        Some(match t > 0.0 && t < g {
            true if self.dim == 2 => {
                let n = Vector2::new(n[0], n[1]);
                embed(Matrix2::identity() + (g / t - 1.0) * n * n.transpose())
            }
            true => Matrix3::identity() + (g / t - 1.0) * n * n.transpose(),
            false => opened(p, self.dim),
        })
    }
}

/// Whether a medium cell with `nodes` spans a gap: a simplex whose corners all stand on solids
/// (`body`, as [`Layers::of`] takes it).
fn spans_gap(nodes: &[usize], body: &[usize], dim: usize) -> bool {
    nodes.len() == dim + 1 && nodes.iter().all(|&n| body[n] != usize::MAX)
}

/// The thickness of a simplex `p` whose corners all stand on solids (`bodies`: each corner's
/// body, a solid's cells joined through their nodes)
/// and the normal across it: over the face whose corners are all on one body where the corner
/// on the other stands over that face (the gap lies across the body's face, whatever the
/// cell's shape: a right triangle between two faces 0.028 apart, its corners 0.05 apart
/// along them, is thinnest across its slanted edge, and a closed layer carried across that
/// is sheared along the faces, which the slide taken into a closed layer's reference then
/// takes out of its squeeze); else over its longest edge (2D) or along its thinnest
/// direction (3D), as where the faces meet at an angle (a cylinder on its plate: its corner
/// beyond the face, measured across that face's line, the press's force changed 9 % at a
/// remake).
fn across_gap(p: &[[f64; 3]], bodies: &[usize]) -> (f64, Vector3<f64>) {
    let k = p.len();
    let alone = (0..k).find(|&i| {
        let others: Vec<usize> = (0..k).filter(|&j| j != i).collect();
        others.iter().all(|&j| bodies[j] == bodies[others[0]]) && bodies[i] != bodies[others[0]]
    });
    if k == 3 {
        // the edge across from the lone corner (it starts at the next), or the longest
        let side = match alone {
            Some(i) if foot_within(p, i) => (i + 1) % 3,
            _ => longest_edge(p, 3).0,
        };
        let (t, n) = height_over(p, side);
        return (t, Vector3::new(n[0], n[1], 0.0));
    }
    let v = |i: usize| Vector3::new(p[i][0], p[i][1], p[i][2]);
    let Some(i) = alone else {
        return thinnest(p);
    };
    let f: Vec<usize> = (0..4).filter(|&j| j != i).collect();
    let (a, b, c) = (v(f[0]), v(f[1]), v(f[2]));
    match (b - a).cross(&(c - a)).try_normalize(0.0) {
        Some(n) if over_face(v(i), [a, b, c], n) => (n.dot(&(v(i) - a)).abs(), n),
        _ => thinnest(p),
    }
}

/// Whether the foot of the perpendicular from corner `i` of the triangle `p` to the line of
/// the edge across from it falls on that edge (to a tenth of its length past either end).
fn foot_within(p: &[[f64; 3]], i: usize) -> bool {
    let a = (i + 1) % 3;
    (-0.1..=1.1).contains(&crate::mesh::remesh::along(p[a], p[(a + 1) % 3], p[i]))
}

/// Whether the foot of the perpendicular from `apex` to the plane of the triangle `t` (unit
/// normal `n`) falls inside it (each barycentric coordinate above −0.1).
fn over_face(apex: Vector3<f64>, t: [Vector3<f64>; 3], n: Vector3<f64>) -> bool {
    let area = |p: Vector3<f64>, q: Vector3<f64>, r: Vector3<f64>| (q - p).cross(&(r - p)).dot(&n);
    let whole = area(t[0], t[1], t[2]);
    let foot = apex - n * n.dot(&(apex - t[0]));
    whole != 0.0
        && [
            area(foot, t[1], t[2]),
            area(t[0], foot, t[2]),
            area(t[0], t[1], foot),
        ]
        .iter()
        .all(|w| w / whole >= -0.1)
}

/// A triangle's height over its edge from corner `i`, and that edge's normal.
fn height_over(p: &[[f64; 3]], i: usize) -> (f64, Vector2<f64>) {
    let e = edge(p, 3, i);
    (
        2.0 * area(p, 3) / e.norm().max(f64::MIN_POSITIVE),
        normal_to(e),
    )
}

/// The slenderness (see [`slenderness`]) below which a new cell of the open medium starts
/// from a reference opened across its thin direction.
pub const THINNEST: f64 = 0.2;

/// F₀⁻¹ of a new open cell with nodes at `p`: the identity, or for a sliver (slenderness
/// s < [`THINNEST`]) a stretch by THINNEST / s across its longest edge, so that no reference is
/// thinner than that: a sliver measured from itself would be a stiff cell, its faces unable
/// to move along each other.
/// In 3D (`dim`), a tetrahedron is opened along its thinnest direction ([`thinnest`],
/// [`slenderness3`]).
fn opened(p: &[[f64; 3]], dim: usize) -> Matrix3<f64> {
    let k = p.len();
    if dim == 3 {
        let s = slenderness3(p);
        if s >= THINNEST || s <= 0.0 {
            return Matrix3::identity();
        }
        let n = thinnest(p).1;
        return Matrix3::identity() + (THINNEST / s - 1.0) * n * n.transpose();
    }
    let s = slenderness(p, k == 3);
    if s >= THINNEST || s <= 0.0 {
        return Matrix3::identity();
    }
    let n = normal_to(edge(p, k, longest_edge(p, k).0));
    embed(Matrix2::identity() + (THINNEST / s - 1.0) * n * n.transpose())
}

impl Remade {
    /// Per dof of `new` (the model built on the remade mesh), the dof of `old` it is, or
    /// [`NONE`] (a new node's, or a p field, which starts again at zero).
    pub fn old_dofs(&self, old: &Model, new: &Model) -> Vec<u32> {
        let mut from = vec![NONE; new.dofs.n_dofs];
        let d = new.dofs.dim;
        for (n, o) in self.old_of.iter().enumerate() {
            let Some(o) = *o else { continue };
            if !new.dofs.u.is_empty() {
                for i in 0..d {
                    from[new.dofs.u[n * d + i] as usize] = old.dofs.u[o * d + i];
                }
            }
            if !new.dofs.theta.is_empty() && new.dofs.theta[n] != NONE {
                from[new.dofs.theta[n] as usize] = old.dofs.theta[o];
            }
        }
        from
    }

    /// The state `x` of `old` on `new`: what kept nodes carry, new nodes at rest where they
    /// stand with the temperature where they stand, the p fields at zero.
    pub fn state(&self, old: &Model, x: &[f64], new: &Model) -> Vec<f64> {
        let from = self.old_dofs(old, new);
        let mut y: Vec<f64> = (from.iter())
            .map(|&f| if f == NONE { 0.0 } else { x[f as usize] })
            .collect();
        if !new.dofs.u.is_empty() {
            let d = new.dofs.dim;
            for (n, u) in self.own.iter().enumerate() {
                for (i, v) in u.iter().flat_map(|u| u.iter().take(d).enumerate()) {
                    y[new.dofs.u[n * d + i] as usize] = *v;
                }
            }
        }
        if new.dofs.has(Field::Theta) {
            for (n, o) in self.old_of.iter().enumerate() {
                if o.is_none() && new.dofs.theta[n] != NONE {
                    y[new.dofs.theta[n] as usize] = self.theta[n];
                }
            }
        }
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_node_just_past_its_end_waits_for_the_others_the_next_step_takes_past_theirs() {
        // at t = 1, the next step to 1.1; speeds in edge lengths per unit of t
        let (t, target) = (1.0, 1.1);
        // nothing past an end: the first the next step takes to its end (t + 0.02 / 0.5)
        let (now, next) = passing(&[(0.98, 0.5), (0.5, 0.5)], t, target);
        assert!(!now);
        assert!((next - 1.04).abs() < 1e-12);
        // one just past its end, another reaching its own at 1.04, before the first is
        // PAST_END beyond (at 1 + 0.04 / 0.5): the medium waits, the step ends at 1.04
        let (now, next) = passing(&[(1.01, 0.5), (0.98, 0.5), (0.5, 0.5)], t, target);
        assert!(!now);
        assert!((next - 1.04).abs() < 1e-12);
        // so does one past the end at 0 moving back along its edge
        let (now, _) = passing(&[(-0.01, -0.5), (0.02, -0.5)], t, target);
        assert!(!now);
        // the next step takes the other to its end only after the first is PAST_END beyond
        // (1 + 0.025 / 0.3 against 1 + 0.04 / 0.5): made now
        let (now, _) = passing(&[(1.01, 0.5), (0.975, 0.3)], t, target);
        assert!(now);
        // no other coming: made now
        let (now, next) = passing(&[(1.01, 0.5), (0.5, 0.5)], t, target);
        assert!(now);
        assert!(next.is_infinite());
        // past by more than PAST_END: made now whatever is coming
        let (now, _) = passing(&[(1.0 + 1.5 * PAST_END, 0.5), (0.98, 0.5)], t, target);
        assert!(now);
        // standing still past its end, it gets no further: it waits as long as another comes
        let (now, _) = passing(&[(1.01, 0.0), (0.98, 0.5)], t, target);
        assert!(!now);
        let (now, _) = passing(&[(1.01, 0.0), (0.5, 0.5)], t, target);
        assert!(now);
    }

    #[test]
    fn a_2d_medium_made_again_is_due_where_a_cell_is_crushed() {
        let mut model = super::super::tests::model_of("pad-box-slide", &[("h", 0.2)]);
        let mut m = Medium::find(&model, Some("medium")).unwrap().unwrap();
        let on_solid = model.on_solids();
        // a medium cell with a corner on a solid and one on none, that corner taken 0.6 of the
        // way to the middle of the others: the cell left with 0.4 of its area
        let (b, c) = (m.blocks.iter())
            .flat_map(|&b| (0..model.mesh.cells[b].n_cells()).map(move |c| (b, c)))
            .find(|&(b, c)| {
                let cell = model.mesh.cells[b].cell(c);
                cell.iter().any(|&n| on_solid[n]) && cell.iter().any(|&n| !on_solid[n])
            })
            .unwrap();
        let cell = model.mesh.cells[b].cell(c).to_vec();
        let open = *cell.iter().find(|&&n| !on_solid[n]).unwrap();
        let rest: Vec<usize> = cell.iter().copied().filter(|&n| n != open).collect();
        let d = model.dofs.dim;
        let x0 = model.initial_state();
        let mut x = x0.clone();
        for i in 0..2 {
            let mid = 0.5 * (model.mesh.coords[rest[0]][i] + model.mesh.coords[rest[1]][i]);
            x[model.dofs.u[open * d + i] as usize] = 0.6 * (mid - model.mesh.coords[open][i]);
        }
        // the drawn medium closes its gaps this way in a press: not asked
        assert!(!m.crushed(&model, &model.cell_reference, &x, false));
        // made again (each cell its own reference as it stands): asked once crushed
        let reference = (0..model.mesh.cells.len())
            .map(|k| {
                m.blocks.contains(&k).then(|| {
                    let blk = &model.mesh.cells[k];
                    blk.conn.iter().map(|&n| model.mesh.coords[n]).collect()
                })
            })
            .collect();
        model.made_again(reference);
        // before its watch starts on it, a medium made again has no J at making to measure
        // from (a checkpoint from before they were kept): not asked
        assert!(!m.crushed(&model, &model.cell_reference, &x, false));
        m.start(&model, &x0, 1.0, 0.0);
        assert!(!m.crushed(&model, &model.cell_reference, &x0, false));
        assert!(m.crushed(&model, &model.cell_reference, &x, false));
        // a quarter of the way: 0.75 of its area, not crushed
        let mut quarter = x.clone();
        for i in 0..2 {
            let k = model.dofs.u[open * d + i] as usize;
            quarter[k] *= 0.25 / 0.6;
        }
        assert!(!m.crushed(&model, &model.cell_reference, &quarter, false));
        // a cell made as squeezed (a sliver's opened reference) is measured from how it was
        // made: the medium made at `x` is not due again at once
        m.start(&model, &x, 1.0, 0.0);
        assert!(!m.crushed(&model, &model.cell_reference, &x, false));
    }

    #[test]
    fn a_run_stuck_on_a_3d_medium_has_it_made_again_by_the_other_mesher_once() {
        // in 2D the triangles are spade's: nothing to swap
        let cylinder = super::super::tests::model_of("cylinder-slide", &[("h", 0.2)]);
        let mut flat = Medium::find(&cylinder, Some("medium")).unwrap().unwrap();
        assert!(!flat.stuck(&cylinder));
        assert_eq!(flat.mesher(), Mesher::Delaunay);
        let sphere = super::super::tests::model_of("sphere-drag", &[("h", 0.3)]);
        let mut m = Medium::find(&sphere, Some("medium")).unwrap().unwrap();
        assert_eq!(m.mesher(), Mesher::Delaunay);
        let x = sphere.initial_state();
        let cells = |m: &Medium| {
            let r = m.remake(&sphere, &sphere.cell_reference, &x).unwrap();
            // the medium's block: the one whose cells have their own references
            let medium: Vec<&crate::mesh::Block> = (r.reference.iter().zip(&r.mesh.cells))
                .filter(|(refs, _)| refs.is_some())
                .map(|(_, b)| b)
                .collect();
            // apart from the bodies and beside them
            assert_eq!(medium.len(), 2);
            let mut tets: Vec<[usize; 4]> = (medium.iter())
                .flat_map(|b| (0..b.n_cells()).map(|c| b.cell(c)))
                .map(|cell| {
                    let mut t: [usize; 4] = std::array::from_fn(|i| cell[i]);
                    t.sort_unstable();
                    t
                })
                .collect();
            tets.sort_unstable();
            (r.mesh.coords.len(), tets)
        };
        // Delaunay's cells are the same each time (a restart makes the run's)
        let delaunay = cells(&m);
        assert_eq!(cells(&m), delaunay);
        // stuck: the remake there fills the medium with HXT's tetrahedra, other cells
        assert!(m.stuck(&sphere));
        assert_eq!(m.mesher(), Mesher::Hxt);
        assert_ne!(cells(&m), delaunay);
        // the medium made then starts again from Delaunay's, and its checkpoint says nothing
        let made = Medium::find(&sphere, Some("medium")).unwrap().unwrap();
        assert_eq!(made.mesher(), Mesher::Delaunay);
        let kept = serde_json::to_value(&m).unwrap();
        assert!(kept.get("mesher").is_none(), "{kept}");
    }

    #[test]
    fn a_3d_medium_made_again_weighs_its_penalty_less_beside_a_body_and_a_2d_one_does_not() {
        for (name, h, weighed) in [("sphere-drag", 0.3, BESIDE), ("cylinder-slide", 0.2, 1.0)] {
            let (case, model) = super::super::tests::case_and_model_of(name, &[("h", h)]);
            let m = Medium::find(&model, Some("medium")).unwrap().unwrap();
            let x = model.initial_state();
            let r = m.remake(&model, &model.cell_reference, &x).unwrap();
            let mut new = super::super::build::build_with_extent(&case, r.mesh, model.d).unwrap();
            let before: Vec<Option<f64>> = new
                .blocks
                .iter()
                .map(|i| i.mat.reg.map(|r| r.beta1))
                .collect();
            new.made_again(r.reference);
            let on = new.on_solids();
            let mut seen = [false; 2];
            for (info, was) in new.blocks.iter().zip(before) {
                let blk = &new.mesh.cells[info.block];
                let Some(reg) = info.mat.reg else {
                    assert!(was.is_none(), "{name}: a solid's block");
                    continue;
                };
                let near = (0..blk.n_cells()).map(|c| blk.cell(c).iter().any(|&n| on[n]));
                let near: Vec<bool> = near.collect();
                let beside = near.iter().all(|&b| b);
                assert!(
                    beside || weighed == 1.0 || near.iter().all(|&b| !b),
                    "{name}"
                );
                seen[beside as usize] = true;
                let expected = if beside { weighed } else { 1.0 };
                assert_eq!(reg.beta1, was.unwrap() * expected, "{name}");
            }
            assert!(seen[1] || weighed == 1.0, "{name}: no cell beside a body");
        }
    }

    /// A triangle's height over its longest edge, and that edge's normal: its thinnest way.
    fn height_across(p: &[[f64; 3]]) -> (f64, Vector2<f64>) {
        height_over(p, longest_edge(p, 3).0)
    }

    #[test]
    fn the_shear_measure_sees_shear_and_not_rotation_or_squeeze() {
        let rot = |a: f64| Matrix2::new(a.cos(), -a.sin(), a.sin(), a.cos());
        assert!(shear(&rot(0.7)) < 1e-7);
        // a layer squeezed to a twentieth of its thickness, and turned
        let squeezed = rot(0.3) * Matrix2::new(1.0, 0.0, 0.0, 0.05);
        assert!(shear(&squeezed) < 1e-7);
        // simple shear γ of a squeezed layer: about γ
        for g in [0.5, 1.0, 3.0] {
            let F = Matrix2::new(1.0, g, 0.0, 0.05);
            let s = shear(&F);
            assert!((s - g).abs() < 0.05 * g, "γ {g}: {s}");
        }
    }

    #[test]
    fn a_closed_layer_is_stretched_back_across_itself_and_keeps_no_shear() {
        // a layer normal to y, squeezed to J = 0.05 and sheared by 2 along x
        let F = Matrix2::new(1.0, 2.0 * 0.05, 0.0, 0.05);
        let back = carried_stretch(&embed(F), 2).unwrap();
        // the new cell's F₀ = back⁻¹: J as before, symmetric, no shear
        let F0 = plane(&back.try_inverse().unwrap());
        assert!((F0.determinant() - F.determinant()).abs() < 1e-12);
        assert!((F0 - F0.transpose()).norm() < 1e-12);
        assert!(shear(&F0) < 1e-7);
        // squeezed along (about) the layer's normal
        let n = Vector2::new(0.0, 1.0);
        assert!(((F0 * n).norm() - 0.05).abs() < 0.01);
        // an open cell starts stress-free
        let open = Matrix2::new(1.0, 0.8, 0.0, 0.7);
        assert_eq!(carried_stretch(&embed(open), 2), None);
    }

    /// Two solids (a triangle below, one above) facing each other across a layer of four
    /// triangles, each cell of the layer given the old J it stood in.
    fn layer(gap: [f64; 3], old_J: [f64; 4]) -> (Mesh, Vec<NewCell>) {
        use crate::mesh::{Block, CellKind};
        let mut coords = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        coords.extend((0..3).map(|i| [i as f64, gap[i], 0.0]));
        coords.push([1.0, -1.0, 0.0]);
        coords.push([1.0, 2.0, 0.0]);
        let tri = |conn: Vec<usize>| Block {
            kind: CellKind::Tri3,
            groups: vec![],
            conn,
        };
        let medium = vec![0, 1, 3, 1, 4, 3, 1, 2, 4, 2, 5, 4];
        let mesh = Mesh::of_cells(
            2,
            coords,
            vec![
                tri(vec![0, 6, 1, 1, 6, 2]),
                tri(vec![3, 4, 7, 4, 5, 7]),
                tri(medium.clone()),
            ],
        );
        let cells = (0..4)
            .map(|c| NewCell {
                b: 2,
                c,
                p: medium[3 * c..3 * c + 3]
                    .iter()
                    .map(|&n| mesh.coords[n])
                    .collect(),
                mid: [0.0; 3],
                F: embed(Matrix2::new(1.0, 0.0, 0.0, old_J[c])),
            })
            .collect();
        (mesh, cells)
    }

    #[test]
    fn a_closed_layer_starts_from_one_thickness_whatever_each_old_cell_had() {
        // the gap 1e-3 to 3e-3 along the layer; the old cells closed to J = 0.01 (thickness
        // 0.1 before, at the gap of 1e-3), 0.02 (0.1 at 2e-3) and 0.06 (about 0.04 and 0.05)
        let (mesh, cells) = layer([1e-3, 2e-3, 3e-3], [0.01, 0.02, 0.06, 0.06]);
        let layers = Layers::of(&mesh, &mesh.components(|b| b != 2), &cells);
        assert_eq!(layers.thickness.len(), 1, "one layer");
        let g = layers.thickness[0].unwrap();
        // each cell's height across the gap: over the face of the body two of its corners are
        // on (nodes 0–2 the lower solid's, 3–5 the upper's)
        let across = |k: usize| {
            let bodies: Vec<usize> = (mesh.cells[2].cell(k).iter()).map(|&n| n / 3).collect();
            let (t, n) = across_gap(&cells[k].p, &bodies);
            (t, Vector2::new(n.x, n.y))
        };
        let before: Vec<f64> = (0..4)
            .map(|k| across(k).0 / plane(&cells[k].F).determinant())
            .collect();
        let mut sorted = before.clone();
        sorted.sort_by(f64::total_cmp);
        assert_eq!(g, sorted[2], "the median of {before:?}");
        for (k, cell) in cells.iter().enumerate() {
            let F0 = plane(&layers.carried(k, &cell.p).unwrap().try_inverse().unwrap());
            // squeezed from the layer's thickness to the cell's height, without shear
            let (t, n) = across(k);
            assert!((F0.determinant() - t / g).abs() < 1e-9 * t / g, "cell {k}");
            assert!(((F0 * n).norm() - t / g).abs() < 1e-9, "cell {k}");
            assert!(shear(&F0) < 1e-7);
        }
        assert!(layers.closed());
        // a layer nowhere closed carries nothing of its own: the cells' old squeeze decides
        let (mesh, cells) = layer([0.1, 0.1, 0.1], [0.9, 0.6, 0.7, 0.8]);
        let layers = Layers::of(&mesh, &mesh.components(|b| b != 2), &cells);
        assert!(!layers.closed());
        assert!((0..4).all(|k| layers.carried(k, &cells[k].p).is_none()));
    }

    #[test]
    fn a_cell_across_a_gap_is_measured_across_the_face_its_corner_stands_over() {
        // the pad in a box of quadrilaterals (h = 0.05) remade mid-press: a right triangle,
        // two corners 0.05 apart on the plate and one on the pad 0.028 above the second
        let (plate, pad) = (0, 1);
        let p = [[1.0, 0.5, 0.0], [1.05, 0.5, 0.0], [1.05, 0.528, 0.0]];
        let (t, n) = across_gap(&p, &[plate, plate, pad]);
        assert!(
            (t - 0.028).abs() < 1e-12 && (n.y.abs() - 1.0).abs() < 1e-12,
            "{t} {n:?}"
        );
        // thinnest across its slanted edge, which the rule it replaces took
        let (h, m) = height_across(&p);
        assert!(h < 0.025 && m.x.abs() > 0.4, "{h} {m:?}");
        // a corner beyond the face (faces meeting at an angle): as before, the thinnest way
        let wedge = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.01, 0.0]];
        let (t, n) = across_gap(&wedge, &[plate, plate, pad]);
        let (h, m) = height_across(&wedge);
        assert!(t == h && n.xy() == m);
        // all on one body: the thinnest way
        assert_eq!(across_gap(&p, &[pad, pad, pad]).0, height_across(&p).0);
        // in 3D, three corners on the plate and one over them 0.02 up
        let q = [
            [0.0, 0.0, 0.0],
            [0.05, 0.0, 0.0],
            [0.0, 0.05, 0.0],
            [0.015, 0.015, 0.02],
        ];
        let (t, n) = across_gap(&q, &[plate, plate, plate, pad]);
        assert!(
            (t - 0.02).abs() < 1e-12 && (n.z.abs() - 1.0).abs() < 1e-12,
            "{t} {n:?}"
        );
        // its corner far beyond the face: the thinnest way
        let far = [q[0], q[1], q[2], [0.3, 0.3, 0.02]];
        assert_eq!(
            across_gap(&far, &[plate, plate, plate, pad]),
            thinnest(&far)
        );
    }

    #[test]
    fn a_sliver_of_the_open_medium_starts_from_a_reference_no_thinner_than_the_thinnest() {
        // a triangle 1 long and 0.01 high, its long edge tilted
        let (c, s) = (0.6f64, 0.8f64);
        let at = |x: f64, y: f64| [c * x - s * y, s * x + c * y, 0.0];
        let p = [at(0.0, 0.0), at(1.0, 0.0), at(0.3, 0.01)];
        assert!((slenderness(&p, true) - 0.01).abs() < 1e-12);
        let back = plane(&opened(&p, 2));
        let mid: Vector2<f64> = p
            .iter()
            .map(|q| Vector2::new(q[0], q[1]))
            .sum::<Vector2<f64>>()
            / 3.0;
        let r: Vec<[f64; 3]> = (p.iter())
            .map(|q| {
                let X = mid + back * (Vector2::new(q[0], q[1]) - mid);
                [X[0], X[1], 0.0]
            })
            .collect();
        assert!((slenderness(&r, true) - THINNEST).abs() < 1e-12);
        // the long edge keeps its length; a well-shaped triangle keeps its shape
        let len = |a: [f64; 3], b: [f64; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
        assert!((len(r[0], r[1]) - 1.0).abs() < 1e-12);
        let fine = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.8, 0.0]];
        assert_eq!(opened(&fine, 2), Matrix3::identity());
    }

    #[test]
    fn a_sliver_along_a_body_s_face_is_no_layer_and_one_between_facing_faces_is() {
        let v = |x: f64, y: f64, z: f64| Vector3::new(x, y, z);
        // under a pad: the way across is the plate's normal and the pad's
        assert!(facing(
            v(0.0, 0.0, 1.0),
            [v(0.0, 0.0, 1.0), v(0.0, 0.0, -1.0)].into_iter()
        ));
        // between a pad's leading face (and its bottom edge) and the plate's node ahead of
        // it, thin along the slide: across the plate's normal
        let edge = v(1.0, 0.0, -1.0) + v(2.0, 0.0, 0.0);
        assert!(!facing(
            v(1.0, 0.0, 0.0),
            [edge, v(0.0, 0.0, 1.0)].into_iter()
        ));
        // the wedge beside a sphere's contact: its face 50° over, the way across 25° over
        let (a, b) = (50f64.to_radians(), 25f64.to_radians());
        let sphere = v(-a.sin(), 0.0, -a.cos());
        assert!(facing(
            v(b.sin(), 0.0, b.cos()),
            [sphere, v(0.0, 0.0, 1.0)].into_iter()
        ));
        // a body with no face there says no
        assert!(!facing(v(0.0, 0.0, 1.0), [Vector3::zeros()].into_iter()));
    }

    #[test]
    fn in_3d_the_shear_measure_and_the_carried_squeeze_are_those_of_the_plane() {
        // a simple shear γ of a layer normal to z, squeezed to 0.05: about γ
        for g in [0.5, 1.0, 3.0] {
            let F = Matrix3::new(1.0, 0.0, g, 0.0, 1.0, 0.0, 0.0, 0.0, 0.05);
            assert!((shear3(&F) - g).abs() < 0.05 * g);
        }
        // a rotation has none
        let (c, s) = (0.6, 0.8);
        assert!(shear3(&Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)) < 1e-12);
        // squeezed to J = 0.05 and sheared by 2: stretched back along (about) z, no shear
        let F = Matrix3::new(1.0, 0.0, 0.1, 0.0, 1.0, 0.0, 0.0, 0.0, 0.05);
        let F0 = carried_stretch(&F, 3).unwrap().try_inverse().unwrap();
        assert!((F0.determinant() - 0.05).abs() < 1e-12);
        assert!((F0 - F0.transpose()).norm() < 1e-12 && shear3(&F0) < 1e-7);
        assert!(((F0 * Vector3::z()).norm() - 0.05).abs() < 0.01);
        assert_eq!(carried_stretch(&Matrix3::identity(), 3), None);
    }

    #[test]
    fn a_thin_tetrahedron_is_opened_across_itself_and_followed_until_it_passes() {
        // three corners on z = 0, one 0.01 above, inside the three
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.3, 0.3, 0.01],
        ];
        // its height over the three, along z
        let (t, n) = thinnest(&p);
        assert!(
            (t - 0.01).abs() < 1e-15 && (n.z.abs() - 1.0).abs() < 1e-15,
            "{t} {n:?}"
        );
        assert!((slenderness3(&p) - 0.01 / 2f64.sqrt()).abs() < 1e-15);
        let back = opened(&p, 3);
        let r: Vec<[f64; 3]> = p
            .iter()
            .map(|q| {
                let X = back * Vector3::new(q[0], q[1], q[2]);
                [X[0], X[1], X[2]]
            })
            .collect();
        assert!(
            (slenderness3(&r) - THINNEST).abs() < 1e-12,
            "{}",
            slenderness3(&r)
        );
        let regular = [
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ];
        assert!(slenderness3(&regular) > 0.7);
        assert_eq!(opened(&regular, 3), Matrix3::identity());
        // the one across three: its foot's barycentric coordinates
        let s = ThinTet::of(0, 0, &p).unwrap();
        assert_eq!((s.corners[0], s.first), (3, 1));
        // two and two: an edge along x on z = 0, one along y 0.01 above, crossing it
        let q = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.4, -0.5, 0.01],
            [0.4, 0.5, 0.01],
        ];
        let s = ThinTet::of(0, 0, &q).unwrap();
        assert_eq!(s.first, 2);
        assert!((thinnest(&q).0 - 0.01).abs() < 1e-15);
        // followed: positive while the one stands over the three, the edges across each other
        let v = |c: [[f64; 3]; 4], order: [usize; 4], first| {
            standing_of(
                order.map(|i| Vector3::new(c[i][0], c[i][1], c[i][2])),
                first,
            )
        };
        let over = v(p, [3, 0, 1, 2], 1);
        assert!(over.iter().all(|&x| x > 0.0) && (over.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let mut passed = p;
        passed[3][0] = -0.1;
        assert!(v(passed, [3, 0, 1, 2], 1).iter().any(|&x| x < 0.0));
        // where each edge passes the other (the edges in either order)
        let mut at = v(q, s.corners, 2);
        at.sort_by(f64::total_cmp);
        assert!(
            (0..4).all(|i| (at[i] - [0.4, 0.5, 0.5, 0.6][i]).abs() < 1e-12),
            "{at:?}"
        );
        let mut slid = q;
        slid[2][0] = 1.2;
        slid[3][0] = 1.2;
        assert!(v(slid, s.corners, 2).iter().any(|&x| x < 0.0));
    }

    #[test]
    fn placed_outer_faces_that_turn_over_close_up_or_cross_are_found() {
        let tri = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| [a, b, c];
        let (o, ex, ey) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        // a triangle tilted by less than FOLD stands; turned past it, or flat, it folds
        assert!(!folds(tri(o, ex, ey), tri(o, ex, [0.0, 1.0, 1.0])));
        assert!(folds(tri(o, ex, ey), tri(o, ex, [0.0, 0.5, 1.0])));
        assert!(folds(tri(o, ex, ey), tri(o, ex, [0.0, -1.0, 0.0])));
        assert!(folds(tri(o, ex, ey), tri(o, ex, [2.0, 0.0, 0.0])));
        // two triangles on one edge, found as a hinge
        assert_eq!(
            hinges(&[[0, 1, 2], [1, 0, 3], [2, 4, 5]]),
            vec![[0, 1, 2, 3]]
        );
        let open = [o, ex, [0.5, 1.0, 0.0], [0.5, -1.0, 0.1]];
        // closed below CREASE about the edge, the more shut than they were
        let shut = [o, ex, [0.5, 1.0, 0.0], [0.5, 1.0, 0.2]];
        assert!(closes(open, shut));
        assert!(!closes(shut, shut), "no closer than it was");
        assert!(!closes(open, [o, ex, [0.5, 1.0, 0.0], [0.5, 0.0, 1.0]]));
        // a triangle through another, one beside it, one sharing a corner
        let at = |n: usize| {
            [
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.2, 0.2, -0.5],
                [0.2, 0.2, 0.5],
                [0.6, 0.6, 0.5],
                [3.0, 3.0, -0.5],
                [3.0, 3.0, 0.5],
            ][n]
        };
        let faces = [[0, 1, 2], [3, 4, 5], [6, 7, 5], [0, 4, 3]];
        let crossed = crossing(&faces, |_| true, at);
        assert_eq!(crossed, vec![[0, 1, 2], [3, 4, 5]]);
        assert!(
            crossing(&faces, |f| f[0] == 6, at).is_empty(),
            "only moved ones"
        );
    }

    #[test]
    fn a_3d_watch_knows_a_body_s_edges_and_a_pass_that_squeezes() {
        // the square pad in its box: x in [0.5, 1.5], y in [0, 0.5] (y = 0 a symmetry plane,
        // not the medium's), z in [0.6, 1.1] on a plate whose top (z = 0.5) is its one face
        // in the medium
        let model = super::super::tests::model_of("pad-box-slide-3d", &[("h", 0.3)]);
        let m = Medium::find(&model, Some("medium")).unwrap().unwrap();
        let x = model.initial_state();
        let edge = body_edges(&model, &m.blocks, &x);
        let on = model.on_solids();
        let at = |v: f64, w: f64| (v - w).abs() < 1e-9;
        let mut seen = [0; 2];
        for (n, p) in model.mesh.coords.iter().enumerate().filter(|&(n, _)| on[n]) {
            let pad = p[2] > 0.55;
            let faces = [
                at(p[0], 0.5),
                at(p[0], 1.5),
                at(p[1], 0.5),
                at(p[2], 0.6),
                at(p[2], 1.1),
            ];
            let on_edge = pad && faces.iter().filter(|&&f| f).count() >= 2;
            assert_eq!(edge[n], on_edge, "node {n} at {p:?}");
            seen[on_edge as usize] += 1;
        }
        assert!(seen[0] > 0 && seen[1] > 0, "{seen:?}");

        // a corner over the other three by the right hand: positive
        let unit = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(crate::mesh::tet_volume(unit), 1.0 / 6.0);
        assert_eq!(
            crate::mesh::tet_volume([unit[1], unit[0], unit[2], unit[3]]),
            -1.0 / 6.0
        );

        // a thin tetrahedron made with volume 1: a pass that keeps it asks nothing, one that
        // squeezes it below half by the next step's end does, and one kept from before its
        // volume was does
        let mut thin = ThinTet::of(
            0,
            0,
            &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.2, 0.3, 0.05]],
        )
        .expect("thin");
        (thin.volume, thin.made_volume) = (1.0, 1.0);
        assert!(!thin.squeezed_by(1.0, 0.1, 0.1));
        assert!(!thin.squeezed_by(0.8, 0.1, 0.1));
        assert!(thin.squeezed_by(0.8, 0.1, 0.2));
        (thin.volume, thin.made_volume) = (-1.0, -1.0);
        assert!(thin.squeezed_by(-0.8, 0.1, 0.2) && !thin.squeezed_by(-1.0, 0.1, 0.2));
        thin.made_volume = 0.0;
        assert!(thin.squeezed_by(1.0, 0.1, 0.1));
    }

    #[test]
    fn a_3d_medium_made_again_lets_its_open_cells_beside_a_body_go_of_their_shear() {
        let (case, model) =
            super::super::tests::case_and_model_of("pad-box-slide-3d", &[("h", 0.3)]);
        let m = Medium::find(&model, Some("medium")).unwrap().unwrap();
        let r = m
            .remake(&model, &model.cell_reference, &model.initial_state())
            .unwrap();
        let mut new = super::super::build::build_with_extent(&case, r.mesh, model.d).unwrap();
        new.made_again(r.reference);
        // every node sheared by g along x over its height: J = 1 in every cell
        let g = 0.3;
        let mut x = new.initial_state();
        for (n, p) in new.mesh.coords.iter().enumerate() {
            x[new.dofs.u[n * 3] as usize] = g * p[2];
        }
        let mut refs = crate::assembly::References::new(&new);
        let on = new.on_solids();
        let gradients = |refs: &crate::assembly::References| {
            let mut all = Vec::new();
            for b in (0..new.mesh.cells.len()).filter(|&b| new.cell_reference[b].is_some()) {
                let blk = &new.mesh.cells[b];
                let mut c = 0;
                at_centres(&new, refs.blocks(), &x, b, |_, F| {
                    all.push((blk.cell(c).iter().any(|&n| on[n]), F.unwrap()));
                    c += 1;
                });
            }
            all
        };
        let before = gradients(&refs);
        refs.release_beside(&new, &x, CLOSED);
        // beside a body and open: no shear left, its J kept; elsewhere as it was, sheared
        let mut seen = [0; 2];
        for (c, ((beside, F), (_, was))) in gradients(&refs).into_iter().zip(before).enumerate() {
            let J = was.determinant();
            let released = beside && J >= CLOSED;
            let expected = if released {
                Matrix3::identity() * J.cbrt()
            } else {
                was
            };
            assert!(
                (F - expected).norm() < 1e-9,
                "cell {c} beside {beside}: {F}"
            );
            assert!(
                beside || (was - Matrix3::identity()).norm() > 0.1 * g,
                "cell {c}"
            );
            seen[beside as usize] += 1;
        }
        assert!(seen[0] > 0 && seen[1] > 0, "{seen:?}");
    }
}
