//! The medium's cells made again between the bodies as they are: each medium region's cells
//! are replaced by triangles of a constrained Delaunay triangulation of the region they cover
//! at the nodes' current places, between the region's boundary nodes, which stay the nodes they
//! are (the solids' faces, the medium's outer faces), refined inside where it is open. This is
//! topology and geometry only: what the new cells carry is `model/remake.rs`'s.
//!
//! The triangulation is spade's, in this process: gmsh, forked for each remake, took 10–25 ms
//! of a remake's 16–45 ms on the sliding cylinder, the triangulation takes about 1 ms
//! (docs/notes/2026-12-02-remake-cost.md).

use super::{Block, CellKind, Mesh};
use std::collections::HashMap;

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
fn boundary_loops(mesh: &Mesh, blocks: &[usize]) -> Result<Vec<Vec<usize>>, String> {
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
/// places `x`: the blocks of each set of physical groups triangulated together as one region,
/// between their boundary nodes. 2D, linear cells only (a caller checks first with
/// [`supported`]).
pub fn remesh(mesh: &Mesh, x: &[[f64; 3]], medium: &[usize]) -> Result<Remeshed, String> {
    let regions = regions_of(mesh, medium);
    let loops: Vec<Vec<Vec<usize>>> = (regions.iter())
        .map(|r| boundary_loops(mesh, &r.1))
        .collect::<Result<_, _>>()?;
    let made = triangulate_between(&loops, x)?;
    // the boundary nodes, found again by their places
    let on_boundary: Vec<usize> = {
        let mut b: Vec<usize> = loops.iter().flatten().flatten().copied().collect();
        b.sort_unstable();
        b.dedup();
        b
    };
    let find = finder(x, &on_boundary);
    let (new_of, mut old_of, mut coords) = kept_nodes(mesh, medium, &on_boundary);
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
    for (r, (groups, _)) in regions.iter().enumerate() {
        let name = format!("medium{r}");
        let g = made
            .group(&name)
            .ok_or("no cells were made in a medium region")?;
        let mut conn = Vec::new();
        for blk in made.cells.iter().filter(|b| b.groups.contains(&g)) {
            conn.extend(blk.conn.iter().map(|&n| made_to_new[n]));
        }
        if conn.contains(&usize::MAX) {
            return Err("a boundary node of the medium was not kept".into());
        }
        new_medium.push(cells.len());
        cells.push(Block {
            kind: CellKind::Tri3,
            groups: groups.clone(),
            conn,
        });
    }
    let facets = mesh.facets.iter().map(remap).collect();
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
/// they are (a closed layer's, one cell across between the bodies' faces). One region per
/// entry of `loops`, its cells in group `medium{r}`, counter-clockwise.
fn triangulate_between(loops: &[Vec<Vec<usize>>], x: &[[f64; 3]]) -> Result<Mesh, String> {
    use spade::{
        AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
    };
    let mut coords: Vec<[f64; 3]> = Vec::new();
    let mut cells = Vec::new();
    let mut groups = Vec::new();
    let equilateral = 3f64.sqrt() / 4.0;
    for (r, region) in loops.iter().enumerate() {
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
        let outer: std::collections::HashSet<_> = refined.excluded_faces.into_iter().collect();
        let first = coords.len();
        coords.extend(
            cdt.vertices()
                .map(|v| [v.position().x, v.position().y, 0.0]),
        );
        let mut conn = Vec::new();
        for f in cdt.inner_faces().filter(|f| !outer.contains(&f.fix())) {
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

/// The node of `nodes` standing at a place (to 1e-9 of the extent of `x`), if any.
fn finder(x: &[[f64; 3]], nodes: &[usize]) -> impl Fn([f64; 3]) -> Option<usize> {
    let scale = super::extent_of(x).max(f64::MIN_POSITIVE);
    let tol = 1e-9 * scale;
    let key = move |p: [f64; 3]| ((p[0] / tol).round() as i64, (p[1] / tol).round() as i64);
    let mut at: HashMap<(i64, i64), usize> = HashMap::new();
    for &n in nodes {
        at.insert(key(x[n]), n);
    }
    move |p: [f64; 3]| {
        let (i, j) = key(p);
        (-1..=1)
            .flat_map(|a| (-1..=1).map(move |b| (i + a, j + b)))
            .find_map(|k| at.get(&k).copied())
    }
}

/// The old nodes kept (those of every other cell and facet, and the medium's boundary
/// `on_boundary`), numbered anew in their order: the new number of each old node
/// (`usize::MAX` if dropped), the old node of each new one, and their coordinates.
#[allow(clippy::type_complexity)]
fn kept_nodes(
    mesh: &Mesh,
    medium: &[usize],
    on_boundary: &[usize],
) -> (Vec<usize>, Vec<Option<usize>>, Vec<[f64; 3]>) {
    let n_old = mesh.coords.len();
    let mut keep = vec![false; n_old];
    for (b, blk) in mesh.cells.iter().enumerate() {
        if !medium.contains(&b) {
            blk.conn.iter().for_each(|&n| keep[n] = true);
        }
    }
    for blk in &mesh.facets {
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
    if mesh.dim != 2 {
        return Err("works in 2D only so far; this mesh is 3D".into());
    }
    for &b in medium {
        let kind = mesh.cells[b].kind;
        if kind.order() != 1 {
            return Err(format!(
                "works with linear cells only so far; this medium has {} cells",
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
        let r = remesh(&mesh, &x, &[0]).unwrap();
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

    #[test]
    fn boundary_nodes_at_one_place_are_refused() {
        let (lp, mut x) = layer(4, 1e-3);
        x[2] = x[1];
        let e = triangulate_between(&[lp], &x).unwrap_err();
        assert!(e.contains("stand at one place"), "{e}");
    }
}
