//! The medium's own plane faces made again in 3D. A medium made again keeps its boundary
//! triangles, but those that are no solid's face (a symmetry plane, the box around the bodies)
//! would then stay Lagrangian: where a thin layer between two bodies meets a symmetry plane,
//! its triangles on that plane are sheared without end as the bodies slide. Each plane patch
//! of such faces is triangulated again between its own nodes at their current places (a
//! constrained Delaunay triangulation of the patch, no node added), and the facets that
//! carried its boundary conditions with it. A patch's inner node that a solid's face has come
//! near ([`NEAR`]) is dropped: the bodies pressed together over the plane would otherwise hold
//! it in the closed layer between them, where it stays as they slide on.

use super::faces::{joined_by_edges, sides, triangle_key as key};
use super::{Block, CellKind, Mesh};
use nalgebra::Vector3;
use std::collections::{HashMap, HashSet};

/// A patch's inner node nearer a solid's edge of the patch than this share of the edge's
/// length is dropped. The hemisphere dragged with friction over its plate (h = 0.25, μ = 0.3)
/// stopped where the contact's leading edge had swept over such nodes of its symmetry plane:
/// each in the closed layer, its cells at J = 4e-4 to 1e-2, Newton's residual largest there.
const NEAR: f64 = 0.25;

/// The faces of the tetrahedra of every block but `medium`.
fn solid_faces(mesh: &Mesh, medium: &[usize]) -> HashSet<[usize; 3]> {
    let mut faces = HashSet::new();
    for (b, blk) in mesh.cells.iter().enumerate() {
        if medium.contains(&b) || blk.kind != CellKind::Tet4 {
            continue;
        }
        for c in 0..blk.n_cells() {
            let cell = blk.cell(c);
            faces.extend(
                sides(CellKind::Tet4)
                    .iter()
                    .map(|f| key([0, 1, 2].map(|i| cell[f[i]]))),
            );
        }
    }
    faces
}

fn at(x: &[[f64; 3]], n: usize) -> Vector3<f64> {
    Vector3::new(x[n][0], x[n][1], x[n][2])
}

/// The unit normal of triangle `f` at the places `x` (zero for a flat one).
fn normal(x: &[[f64; 3]], f: [usize; 3]) -> Vector3<f64> {
    let n = (at(x, f[1]) - at(x, f[0])).cross(&(at(x, f[2]) - at(x, f[0])));
    n.try_normalize(0.0).unwrap_or_else(Vector3::zeros)
}

/// The boundary triangles `faces` of a medium region (turned outward, blocks `medium`) with
/// each plane patch of its own faces triangulated again at the places `x`; the facets of a
/// patch (in `facets`) replaced by its new triangles. A patch whose facets lie in several
/// blocks, or which cannot be triangulated again, is kept as it is.
pub fn own_planes_again(
    mesh: &Mesh,
    medium: &[usize],
    faces: Vec<[usize; 3]>,
    facets: &mut [Block],
    x: &[[f64; 3]],
) -> Vec<[usize; 3]> {
    let solid = solid_faces(mesh, medium);
    let on_solid = mesh.nodes_in(|b| !medium.contains(&b));
    let own: Vec<[usize; 3]> = (faces.iter())
        .filter(|&&f| !solid.contains(&key(f)))
        .copied()
        .collect();
    let tol = 1e-9 * super::extent_of(x).max(f64::MIN_POSITIVE);
    let normals: Vec<Vector3<f64>> = own.iter().map(|&f| normal(x, f)).collect();
    // a patch: own faces on one plane, joined by their edges
    let coplanar = |i: usize, j: usize| {
        let n = normals[i];
        let d = n.dot(&at(x, own[i][0]));
        normals[j].dot(&n) > 1.0 - 1e-10
            && own[j].iter().all(|&m| (n.dot(&at(x, m)) - d).abs() < tol)
    };
    let mut out: Vec<[usize; 3]> = Vec::with_capacity(faces.len());
    let mut again_made = HashSet::new();
    for patch in joined_by_edges(&own, coplanar) {
        if patch.len() < 2 {
            continue;
        }
        let old: Vec<[usize; 3]> = patch.iter().map(|&i| own[i]).collect();
        if let Some(new) = again(&old, normals[patch[0]], x, &on_solid)
            && replace_facets(facets, &old, &new)
        {
            again_made.extend(old.iter().map(|&f| key(f)));
            out.extend(new);
        }
    }
    out.extend(faces.into_iter().filter(|&f| !again_made.contains(&key(f))));
    out
}

/// The triangles of a constrained Delaunay triangulation of the plane patch `old` (normal
/// `n`, turned as its triangles are) between its own nodes at the places `x`, turned as
/// `old`'s, but for its inner nodes near an edge of solids' nodes (`on_solid`, see [`NEAR`]);
/// `None` where they do not cover the same area.
fn again(
    old: &[[usize; 3]],
    n: Vector3<f64>,
    x: &[[f64; 3]],
    on_solid: &[bool],
) -> Option<Vec<[usize; 3]>> {
    use spade::{
        AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
    };
    let seed = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = n.cross(&seed).normalize();
    let e2 = n.cross(&e1);
    let flat = |m: usize| Point2::new(e1.dot(&at(x, m)), e2.dot(&at(x, m)));
    let area = |t: [usize; 3]| {
        let (a, b, c) = (flat(t[0]), flat(t[1]), flat(t[2]));
        0.5 * ((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y))
    };
    // the patch's boundary: the edges of one of its triangles only
    let mut directed = HashSet::new();
    for t in old {
        for e in 0..3 {
            directed.insert((t[e], t[(e + 1) % 3]));
        }
    }
    // in the order of their nodes, not the set's (which differs from one process to the
    // next): constraints added in another order may split the patch otherwise where its
    // nodes stand on one circle, and a run and its rerun would then part
    let mut boundary: Vec<(usize, usize)> = (directed.iter().copied())
        .filter(|&(a, b)| !directed.contains(&(b, a)))
        .collect();
    boundary.sort_unstable();
    let dropped = near_solids(old, &boundary, on_solid, flat);
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let mut handle = HashMap::new();
    let mut node_of = HashMap::new();
    for &m in old.iter().flatten() {
        if handle.contains_key(&m) || dropped.contains(&m) {
            continue;
        }
        let before = cdt.num_vertices();
        let v = cdt.insert(flat(m)).ok()?;
        if cdt.num_vertices() == before {
            return None;
        }
        handle.insert(m, v);
        node_of.insert(v, m);
    }
    for (a, b) in boundary {
        let (va, vb) = (handle[&a], handle[&b]);
        if !cdt.can_add_constraint(va, vb) {
            return None;
        }
        cdt.add_constraint(va, vb);
    }
    let params = RefinementParameters::<f64>::new()
        .exclude_outer_faces(true)
        .keep_constraint_edges()
        .with_angle_limit(AngleLimit::from_deg(0.0))
        .with_max_additional_vertices(0);
    let refined = cdt.refine(params);
    if cdt.num_vertices() != handle.len() {
        return None;
    }
    let outer: HashSet<_> = refined.excluded_faces.into_iter().collect();
    let turn = old.iter().map(|&t| area(t)).sum::<f64>().signum();
    let mut new = Vec::new();
    for f in cdt.inner_faces().filter(|f| !outer.contains(&f.fix())) {
        let [a, b, c] = f.vertices().map(|v| node_of[&v.fix()]);
        new.push(if area([a, b, c]) * turn > 0.0 {
            [a, b, c]
        } else {
            [a, c, b]
        });
    }
    let (was, is): (f64, f64) = (
        old.iter().map(|&t| area(t).abs()).sum(),
        new.iter().map(|&t| area(t).abs()).sum(),
    );
    ((was - is).abs() <= 1e-9 * was).then_some(new)
}

/// The inner nodes of the plane patch `old` (its `boundary` edges given, its nodes' places in
/// its plane `flat`) that are no solid's (`on_solid`) and stand nearer an edge of the
/// boundary between two solids' nodes than [`NEAR`] of its length.
fn near_solids(
    old: &[[usize; 3]],
    boundary: &[(usize, usize)],
    on_solid: &[bool],
    flat: impl Fn(usize) -> spade::Point2<f64>,
) -> HashSet<usize> {
    let on_edge: HashSet<usize> = boundary.iter().flat_map(|&(a, b)| [a, b]).collect();
    let solid_edges: Vec<(usize, usize)> = (boundary.iter().copied())
        .filter(|&(a, b)| on_solid[a] && on_solid[b])
        .collect();
    let near = |m: usize| {
        let p = flat(m);
        solid_edges.iter().any(|&(a, b)| {
            let (a, b) = (flat(a), flat(b));
            let (dx, dy) = (b.x - a.x, b.y - a.y);
            let length2 = dx * dx + dy * dy;
            let s = (((p.x - a.x) * dx + (p.y - a.y) * dy) / length2).clamp(0.0, 1.0);
            let (ex, ey) = (p.x - a.x - s * dx, p.y - a.y - s * dy);
            ex * ex + ey * ey < NEAR * NEAR * length2
        })
    };
    (old.iter().flatten().copied())
        .filter(|&m| !on_edge.contains(&m) && !on_solid[m])
        .filter(|&m| near(m))
        .collect()
}

/// The facets `old` (a plane patch's triangles) replaced by `new` in the facet block that holds
/// them; false (nothing changed) where they lie in several blocks or only some are facets.
fn replace_facets(facets: &mut [Block], old: &[[usize; 3]], new: &[[usize; 3]]) -> bool {
    let keys: HashSet<[usize; 3]> = old.iter().map(|&f| key(f)).collect();
    let held = |blk: &Block, c: usize| keys.contains(&key([0, 1, 2].map(|i| blk.cell(c)[i])));
    // per facet block of triangles, how many of the patch's it holds
    let holders: Vec<(usize, usize)> = (facets.iter().enumerate())
        .filter(|(_, blk)| blk.kind == CellKind::Tri3)
        .map(|(b, blk)| (b, (0..blk.n_cells()).filter(|&c| held(blk, c)).count()))
        .filter(|&(_, n)| n > 0)
        .collect();
    let &[(b, n)] = holders.as_slice() else {
        return holders.is_empty();
    };
    if n != keys.len() {
        return false;
    }
    let blk = &facets[b];
    let mut conn = Vec::with_capacity(blk.conn.len() - 3 * n + 3 * new.len());
    for c in (0..blk.n_cells()).filter(|&c| !held(blk, c)) {
        conn.extend_from_slice(blk.cell(c));
    }
    new.iter().for_each(|t| conn.extend_from_slice(t));
    facets[b].conn = conn;
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_face_of_the_medium_is_triangulated_again_with_its_facets() {
        // a unit cube of medium, six tetrahedra about its diagonal from 0 to 7; its bottom's
        // two triangles a facet block (a boundary condition's group)
        let (coords, tets) = crate::mesh::kuhn_tetrahedra(1);
        let conn = tets.into_iter().flat_map(|(_, t)| t).collect();
        let tets = Block {
            kind: CellKind::Tet4,
            groups: vec![0],
            conn,
        };
        let mut mesh = Mesh::of_cells(3, coords, vec![tets]);
        let faces = crate::mesh::faces::outer_triangles(&mesh, &[0]).unwrap();
        assert_eq!(faces.len(), 12);
        let bottom: Vec<usize> = (faces.iter())
            .filter(|f| f.iter().all(|&n| n & 4 == 0))
            .flat_map(|f| f.iter().copied())
            .collect();
        assert_eq!(bottom.len(), 6);
        mesh.facets.push(Block {
            kind: CellKind::Tri3,
            groups: vec![1],
            conn: bottom,
        });
        // the bottom's corner 1 moved along it, past where the other diagonal is Delaunay's
        let mut x = mesh.coords.clone();
        x[1] = [0.8, 0.7, 0.0];
        let mut facets = mesh.facets.clone();
        let again = own_planes_again(&mesh, &[0], faces.clone(), &mut facets, &x);
        assert_eq!(again.len(), 12);
        let on_bottom: HashSet<[usize; 3]> = (again.iter())
            .filter(|f| f.iter().all(|&n| n & 4 == 0))
            .map(|&f| key(f))
            .collect();
        let held: HashSet<[usize; 3]> = (0..2)
            .map(|c| key([0, 1, 2].map(|i| facets[0].cell(c)[i])))
            .collect();
        assert_eq!(on_bottom, held, "the facets follow the faces");
        // the other diagonal (1–2, not 0–3), turned outward (down) as before
        assert!(
            held.contains(&[0, 1, 2]) && held.contains(&[1, 2, 3]),
            "{held:?}"
        );
        for f in again.iter().filter(|f| f.iter().all(|&n| n & 4 == 0)) {
            assert!(normal(&x, *f).z < -0.99);
        }
    }

    #[test]
    fn a_patch_s_inner_node_near_a_solid_s_edge_is_dropped() {
        // the unit square, its bottom edge 0–4–1 a solid's; inner node 5 a twentieth above
        // it, node 6 well inside
        let x = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.0, 0.0],
            [0.5, 0.05, 0.0],
            [0.5, 0.6, 0.0],
        ];
        let old = [
            [0, 4, 5],
            [4, 1, 5],
            [1, 6, 5],
            [1, 2, 6],
            [2, 3, 6],
            [3, 0, 6],
            [0, 5, 6],
        ];
        let solid = [true, true, false, false, true, false, false];
        let new = again(&old, Vector3::z(), &x, &solid).unwrap();
        let nodes: HashSet<usize> = new.iter().flatten().copied().collect();
        assert!(!nodes.contains(&5) && nodes.contains(&6), "{new:?}");
        for f in &new {
            assert!(normal(&x, *f).z > 0.99, "turned as before: {f:?}");
        }
        // nothing near a solid: every node kept
        let all = again(&old, Vector3::z(), &x, &[false; 7]).unwrap();
        assert_eq!(
            all.iter().flatten().copied().collect::<HashSet<_>>().len(),
            7
        );
    }
}
