//! Where a body comes up against the edge of the medium drawn around it: a node of the
//! medium's free edge (its outer boundary where it borders no other cell and no condition
//! holds it) close against a solid's face towards the medium. Past that edge nothing is in
//! contact, and the medium there is pushed ahead of the body: in 2D a pad dragged past the
//! end of the box of medium drawn around it pushed the box's side 3.5 beyond where it was
//! drawn before the run stopped, and the stop told of friction, or of nothing
//! (docs/notes/2026-12-06-a-body-at-the-medium-s-edge.md). (In 3D a medium made again took
//! the box's end face along with the square pad, 1.0 out, and the run went on: nothing was
//! close against it, and nothing is said.)

use crate::case::RegionKind;
use crate::mesh::faces::sides;
use crate::model::Model;
use nalgebra::Vector3;
use std::collections::HashMap;

/// How close to a solid's face a node of the medium's free edge stands when the body has
/// come up against it, in lengths of the node's shortest edge along the free edge. Faces
/// with a corner at one of the node's neighbours along the edge (where the edge meets a body
/// as drawn) do not count; a mesh as drawn has no node closer than about one such length to
/// any other face. The pad dragged past its box's end stopped with its face 0.38 of an edge
/// from the box's side, its corner on the plate's end.
pub const REACHED: f64 = 0.5;

/// How nearly a solid's face turns towards the medium's free edge when the body has come up
/// against it: the cosine of the angle between the face's outward normal and the edge's
/// outward normal as drawn, at least. Where a body's face passes over the end of the medium
/// under it (the paper's block, pressed onto a medium as wide as it, bulges past its end; a
/// block dragged past it), the medium's free side is squeezed between the face and nothing,
/// closed along the face, which turns across the side's normal: the body has not come up
/// against the edge, and a first watch without this said it had in five of the shipped
/// scenes.
pub const FACING: f64 = 0.5;

/// The medium's free edge and the solids' faces towards the medium, to watch.
pub struct MediumEdge {
    free: Vec<FreeNode>,
    /// The solids' faces towards the medium as triangles (a segment in 2D: the third corner
    /// repeats the second; a quadrilateral as two), their corners turned as their solid cell
    /// turns them (so that [`normal_of`] points out of the solid), each with its solid region.
    faces: Vec<([usize; 3], usize)>,
}

/// A node of the medium's free edge, its neighbours along the edge, and the edge's outward
/// unit normal there as drawn.
struct FreeNode {
    node: usize,
    around: Vec<usize>,
    normal: Vector3<f64>,
}

/// A node of the medium's free edge, at `at`, that stands `distance` from a face of the solid
/// `region` (an index into `Model::regions`).
#[derive(Clone, Debug, PartialEq)]
pub struct Against {
    pub at: [f64; 3],
    pub distance: f64,
    pub region: usize,
}

impl MediumEdge {
    /// The medium's free edge in `model` and the solids' faces towards the medium (none where
    /// the scene has no medium or no mechanics).
    pub fn of(model: &Model) -> MediumEdge {
        let has_medium = (model.regions.iter()).any(|r| r.1 == RegionKind::Medium);
        if !has_medium || model.dofs.u.is_empty() {
            return MediumEdge {
                free: Vec::new(),
                faces: Vec::new(),
            };
        }
        let (sides, faces) = sides_of(model);
        MediumEdge {
            free: free_nodes(model, &sides),
            faces,
        }
    }

    /// Where, at the state `x`, a body has come up against the medium's free edge: the node
    /// of the edge closest against a solid's face turned towards the edge ([`FACING`]),
    /// within [`REACHED`] of its shortest edge along the free edge, if any (a face with a
    /// corner at one of the node's neighbours along the edge does not count).
    pub fn watch(&self, model: &Model, x: &[f64]) -> Option<Against> {
        if self.free.is_empty() || self.faces.is_empty() {
            return None;
        }
        let at = |n: usize| Vector3::from(model.placed(n, x));
        // each face's corners, bounding box and index, by the least x of its corners, for
        // those near a point
        type Placed = ([Vector3<f64>; 3], Vector3<f64>, Vector3<f64>, usize);
        let mut faces: Vec<Placed> = (self.faces.iter().enumerate())
            .map(|(k, (f, _))| {
                let p = f.map(at);
                let lo = p[0].inf(&p[1]).inf(&p[2]);
                let hi = p[0].sup(&p[1]).sup(&p[2]);
                (p, lo, hi, k)
            })
            .collect();
        faces.sort_by(|a, b| a.1.x.total_cmp(&b.1.x));
        let widest = faces.iter().map(|f| f.2.x - f.1.x).fold(0.0, f64::max);
        let mut found: Option<(f64, [f64; 3], usize)> = None;
        for free in &self.free {
            let p = at(free.node);
            let length = (free.around.iter())
                .map(|&m| (at(m) - p).norm())
                .fold(f64::INFINITY, f64::min);
            let reach = REACHED * length;
            let first = faces.partition_point(|f| f.1.x < p.x - reach - widest);
            for (corners, lo, hi, k) in &faces[first..] {
                if lo.x > p.x + reach {
                    break;
                }
                let apart = (0..3).any(|i| lo[i] > p[i] + reach || hi[i] < p[i] - reach);
                let (f, region) = self.faces[*k];
                if apart || f.iter().any(|m| free.around.contains(m)) {
                    continue;
                }
                let distance = (p - nearest_on_triangle(p, *corners)).norm();
                let turned = match f[1] == f[2] {
                    true => normal_of(&f[..2], at),
                    false => normal_of(&f, at),
                };
                let facing = turned.normalize().dot(&free.normal) >= FACING;
                if distance < reach && facing && found.is_none_or(|(d, _, _)| distance < d) {
                    found = Some((distance, [p.x, p.y, p.z], region));
                }
            }
        }
        let (distance, at, region) = found?;
        Some(Against {
            at,
            distance,
            region,
        })
    }
}

/// The medium's sides that border no other cell (its free edge, and where a condition holds
/// it), each as its corners and its outward unit normal as drawn ([`normal_of`]: a side's
/// corners in its cell's order turn it out of the cell, whose corners turn positively); and the
/// solids' faces towards the medium, as triangles (a segment in 2D: the third corner repeats
/// the second; a quadrilateral as two), each with its solid region.
#[allow(clippy::type_complexity)]
fn sides_of(model: &Model) -> (Vec<(Vec<usize>, Vector3<f64>)>, Vec<([usize; 3], usize)>) {
    let mesh = &model.mesh;
    let point = |n: usize| Vector3::from(mesh.coords[n]);
    let medium = |i: usize| model.regions[model.blocks[i].region].1 == RegionKind::Medium;
    let ends = |(i, c, k): (usize, usize, usize)| -> Vec<usize> {
        let blk = &mesh.cells[model.blocks[i].block];
        let nodes = blk.cell(c);
        sides(blk.kind)[k].iter().map(|&j| nodes[j]).collect()
    };
    // the sides of every cell whose corners are all the medium's, by their sorted corners:
    // how many cells have each, and the first two as (block info, cell, side)
    let on_medium = model.nodes_of(RegionKind::Medium);
    type Owner = (usize, usize, usize);
    let mut by_key: HashMap<[usize; 4], (usize, Owner, Owner)> = HashMap::new();
    for (i, info) in model.blocks.iter().enumerate() {
        let blk = &mesh.cells[info.block];
        for c in 0..blk.n_cells() {
            let nodes = blk.cell(c);
            for (k, side) in sides(blk.kind).iter().enumerate() {
                if !side.iter().all(|&j| on_medium[nodes[j]]) {
                    continue;
                }
                let mut key = [usize::MAX; 4];
                side.iter().zip(&mut key).for_each(|(&j, v)| *v = nodes[j]);
                key.sort_unstable();
                let e = by_key.entry(key).or_insert((0, (i, c, k), (i, c, k)));
                e.0 += 1;
                if e.0 == 2 {
                    e.2 = (i, c, k);
                }
            }
        }
    }
    let (mut free, mut faces) = (Vec::new(), Vec::new());
    for (count, a, b) in by_key.into_values() {
        match count {
            1 if medium(a.0) => {
                let side = ends(a);
                let normal = normal_of(&side, point).try_normalize(0.0);
                free.push((side, normal.unwrap_or_else(Vector3::zeros)));
            }
            2 if medium(a.0) != medium(b.0) => {
                let solid = if medium(a.0) { b } else { a };
                let region = model.blocks[solid.0].region;
                match ends(solid)[..] {
                    [a, b] => faces.push(([a, b, b], region)),
                    [a, b, c] => faces.push(([a, b, c], region)),
                    [a, b, c, e] => faces.extend([([a, b, c], region), ([a, c, e], region)]),
                    _ => {}
                }
            }
            _ => {}
        }
    }
    free.sort_by(|a, b| a.0.cmp(&b.0));
    faces.sort_unstable();
    (free, faces)
}

/// A normal to the side `ends` with its nodes at `at(n)`: in 2D its edge turned a right
/// angle clockwise, in 3D the cross product of its first two edges from its first corner.
fn normal_of(ends: &[usize], at: impl Fn(usize) -> Vector3<f64>) -> Vector3<f64> {
    let (a, b) = (at(ends[0]), at(ends[1]));
    match ends.len() {
        2 => Vector3::new(b.y - a.y, a.x - b.x, 0.0),
        _ => (b - a).cross(&(at(ends[2]) - a)),
    }
}

/// The nodes of the medium's free `sides` (as [`sides_of`] gives them) that are no solid's
/// and that no condition holds in any direction (a plane of symmetry's are held), each with
/// its neighbours along the sides.
fn free_nodes(model: &Model, sides: &[(Vec<usize>, Vector3<f64>)]) -> Vec<FreeNode> {
    let on_solid = model.nodes_of(RegionKind::Solid);
    let held = |n: usize| (0..model.dofs.dim).any(|i| model.held_along(n, i));
    let mut by_node: HashMap<usize, (Vec<usize>, Vector3<f64>)> = HashMap::new();
    for (ends, normal) in sides {
        let k = ends.len();
        for (i, &n) in ends.iter().enumerate() {
            let (around, sum) = by_node.entry(n).or_insert((Vec::new(), Vector3::zeros()));
            around.extend([ends[(i + 1) % k], ends[(i + k - 1) % k]]);
            *sum += normal;
        }
    }
    let mut free: Vec<FreeNode> = (by_node.into_iter())
        .filter(|(n, _)| !on_solid[*n] && !held(*n))
        .map(|(node, (mut around, sum))| {
            around.sort_unstable();
            around.dedup();
            FreeNode {
                node,
                around,
                normal: sum.try_normalize(0.0).unwrap_or_else(Vector3::zeros),
            }
        })
        .collect();
    free.sort_by_key(|f| f.node);
    free
}

/// The point of the triangle `t` (a segment where two corners coincide) nearest to `p`.
fn nearest_on_triangle(p: Vector3<f64>, [a, b, c]: [Vector3<f64>; 3]) -> Vector3<f64> {
    let (ab, ac) = (b - a, c - a);
    let normal = ab.cross(&ac);
    let area2 = normal.norm_squared();
    if area2 <= 1e-24 * (ab.norm_squared() + ac.norm_squared()).powi(2) {
        // a segment: from a to the farther of b and c
        let e = if ab.norm_squared() >= ac.norm_squared() {
            b
        } else {
            c
        };
        return nearest_on_segment(p, a, e);
    }
    // the foot on the triangle's plane, where it is inside the triangle
    let q = p - normal * ((p - a).dot(&normal) / area2);
    let edges = [(a, b), (b, c), (c, a)];
    if (edges.iter()).all(|&(u, v)| (v - u).cross(&(q - u)).dot(&normal) >= 0.0) {
        return q;
    }
    (edges.iter())
        .map(|&(u, v)| nearest_on_segment(p, u, v))
        .min_by(|u, v| (p - u).norm_squared().total_cmp(&(p - v).norm_squared()))
        .unwrap_or(a)
}

/// The point of the segment from `a` to `b` nearest to `p`.
fn nearest_on_segment(p: Vector3<f64>, a: Vector3<f64>, b: Vector3<f64>) -> Vector3<f64> {
    let e = b - a;
    let s = match e.norm_squared() {
        l2 if l2 > 0.0 => ((p - a).dot(&e) / l2).clamp(0.0, 1.0),
        _ => 0.0,
    };
    a + e * s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pad in a box (`cases/pad-box-slide.toml` on h = 0.2, its plate and box 3 long):
    /// nothing at the edge as drawn, nor with the pad moved a cell short of the box's end
    /// (its face 0.3 from the box's side); the pad, with its face 0.02 from the side, is.
    #[test]
    fn the_pad_is_found_against_the_end_of_its_box_and_not_before() {
        let model = crate::model::tests::model_of("pad-box-slide", &[("h", 0.2), ("L", 3.0)]);
        let edge = MediumEdge::of(&model);
        let pad = (model.regions.iter()).position(|r| r.0 == "pad").unwrap();
        let on_pad = model
            .mesh
            .nodes_in(|b| (model.blocks.iter()).any(|i| i.block == b && i.region == pad));
        let moved = |by: f64| {
            let mut x = vec![0.0; model.dofs.n_dofs];
            for n in (0..on_pad.len()).filter(|&n| on_pad[n]) {
                x[model.dofs.u[n * 2] as usize] = by;
            }
            x
        };
        assert_eq!(edge.watch(&model, &moved(0.0)), None);
        assert_eq!(edge.watch(&model, &moved(1.2)), None);
        let found = edge
            .watch(&model, &moved(1.48))
            .expect("against the box's side");
        assert_eq!(found.region, pad);
        assert!((found.distance - 0.02).abs() < 1e-9, "{found:?}");
        assert!(
            (found.at[0] - 3.0).abs() < 1e-12 && (0.59..1.11).contains(&found.at[1]),
            "{found:?}"
        );
    }

    /// The paper's block (`cases/block.toml`, n = m = 16, l = 4) pressed flat onto its medium
    /// as wide as it, its left face bulged 0.024 past the medium's end: the medium's free
    /// side is squeezed flat under the block's bottom face, which turns across the side's
    /// normal as drawn. The block has not come up against the edge, though the side's nodes
    /// stand within a fortieth of an edge of its face.
    #[test]
    fn a_block_bulged_past_the_end_of_its_medium_has_not_come_up_against_it() {
        let model = crate::model::tests::model_of("block", &[("n", 16.0), ("m", 16.0), ("l", 4.0)]);
        let edge = MediumEdge::of(&model);
        let on_solid = model.nodes_of(RegionKind::Solid);
        let mut x = vec![0.0; model.dofs.n_dofs];
        for (n, p) in model.mesh.coords.iter().enumerate() {
            let bulge = -0.024 * (1.0 - p[0] / 2.0);
            let (ux, uy) = match on_solid[n] {
                true => (bulge, 3e-4 - 0.25),
                false => (bulge * p[1] / 0.25, p[1] * (1.2e-3 - 1.0)),
            };
            x[model.dofs.u[2 * n] as usize] = ux;
            x[model.dofs.u[2 * n + 1] as usize] = uy;
        }
        // the side's nodes 7.5e-5 and more under the block's face, its edges 6e-3 long (a
        // watch without [`FACING`] found one 1.5e-4 from the face, within its reach of 3e-3)
        let to_faces = |p: Vector3<f64>| {
            (edge.faces.iter())
                .map(|(t, _)| {
                    let t = t.map(|m| Vector3::from(model.placed(m, &x)));
                    (p - nearest_on_triangle(p, t)).norm()
                })
                .fold(f64::INFINITY, f64::min)
        };
        let near = (edge.free.iter())
            .map(|f| to_faces(Vector3::from(model.placed(f.node, &x))))
            .fold(f64::INFINITY, f64::min);
        assert!(near < 1e-4, "{near}");
        assert_eq!(edge.watch(&model, &x), None);
    }

    #[test]
    fn distances_to_a_triangle_and_a_segment() {
        let v = |x: f64, y: f64, z: f64| Vector3::new(x, y, z);
        let to_triangle = |p: Vector3<f64>, t| (p - nearest_on_triangle(p, t)).norm();
        let t = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        // above the inside, beside an edge, past a corner
        assert!((to_triangle(v(0.2, 0.2, 0.5), t) - 0.5).abs() < 1e-14);
        assert!((to_triangle(v(0.5, -0.3, 0.4), t) - 0.5).abs() < 1e-14);
        assert!((to_triangle(v(-0.3, -0.4, 0.0), t) - 0.5).abs() < 1e-14);
        assert!((to_triangle(v(0.6, 0.6, 0.0), t) - 0.1 * 2f64.sqrt()).abs() < 1e-14);
        // a segment (2D), a point beside it and one past its end
        let s = [v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(2.0, 0.0, 0.0)];
        assert!((to_triangle(v(1.0, 0.3, 0.0), s) - 0.3).abs() < 1e-14);
        assert!((to_triangle(v(2.3, 0.4, 0.0), s) - 0.5).abs() < 1e-14);
    }
}
