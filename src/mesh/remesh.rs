//! The medium's cells made again between the bodies as they are: each medium region's cells
//! are replaced by triangles gmsh makes in the region they cover at the nodes' current places,
//! between the region's boundary nodes, which stay the nodes they are (the solids' faces, the
//! medium's outer faces). The new nodes inside the medium stand where gmsh put them. This is
//! topology and geometry only: what the new cells carry is `model/remake.rs`'s.

use super::gmsh::{MeshOptions, mesh_geo};
use super::{Block, CellKind, Mesh};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

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

/// Twice the signed area of loop `lp` at the places `x` (positive: counter-clockwise).
fn signed_area(lp: &[usize], x: &[[f64; 3]]) -> f64 {
    (0..lp.len())
        .map(|i| {
            let (p, q) = (x[lp[i]], x[lp[(i + 1) % lp.len()]]);
            p[0] * q[1] - q[0] * p[1]
        })
        .sum()
}

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

/// The `.geo` text of the medium regions `regions` (each its loops, at the places `x`): a
/// plane surface per outer loop with the holes it holds, each boundary edge a line of its two
/// nodes alone, the size at a node its edges' mean length. Returns the text and the node of
/// each gmsh point, in point order.
fn geo_text(regions: &[Vec<Vec<usize>>], x: &[[f64; 3]]) -> (String, Vec<usize>) {
    let mut text = String::from(
        "Mesh.MeshSizeFromCurvature = 0;\nMesh.MeshSizeExtendFromBoundary = 1;\n\
         Mesh.Algorithm = 6;\n",
    );
    let mut point: HashMap<usize, usize> = HashMap::new();
    let mut nodes = Vec::new();
    let mut size: HashMap<usize, (f64, usize)> = HashMap::new();
    for lp in regions.iter().flatten() {
        for i in 0..lp.len() {
            let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
            let l = (0..2)
                .map(|k| (x[a][k] - x[b][k]).powi(2))
                .sum::<f64>()
                .sqrt();
            for n in [a, b] {
                let s = size.entry(n).or_insert((0.0, 0));
                s.0 += l;
                s.1 += 1;
            }
        }
    }
    let mut lines: HashMap<(usize, usize), i64> = HashMap::new();
    let mut n_lines = 0;
    let mut n_loops = 0;
    for (r, loops) in regions.iter().enumerate() {
        let mut loop_tags = Vec::new();
        for lp in loops {
            let mut tags = Vec::new();
            for i in 0..lp.len() {
                let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
                for n in [a, b] {
                    if let std::collections::hash_map::Entry::Vacant(e) = point.entry(n) {
                        nodes.push(n);
                        e.insert(nodes.len());
                        let (s, k) = size[&n];
                        let _ = writeln!(
                            text,
                            "Point({}) = {{{:e}, {:e}, 0, {:e}}};",
                            nodes.len(),
                            x[n][0],
                            x[n][1],
                            s / k as f64
                        );
                    }
                }
                let tag = match (lines.get(&(a, b)), lines.get(&(b, a))) {
                    (Some(&t), _) => t,
                    (_, Some(&t)) => -t,
                    _ => {
                        n_lines += 1;
                        let _ = writeln!(
                            text,
                            "Line({n_lines}) = {{{}, {}}};\nTransfinite Curve{{{n_lines}}} = 2;",
                            point[&a], point[&b]
                        );
                        lines.insert((a, b), n_lines);
                        n_lines
                    }
                };
                tags.push(tag.to_string());
            }
            n_loops += 1;
            let _ = writeln!(text, "Curve Loop({n_loops}) = {{{}}};", tags.join(", "));
            loop_tags.push((n_loops, signed_area(lp, x), lp));
        }
        // outer loops (counter-clockwise) each with the holes (clockwise) whose nearest outer
        // loop they are
        let outers: Vec<_> = loop_tags.iter().filter(|l| l.1 > 0.0).collect();
        let mut surfaces = Vec::new();
        for o in &outers {
            let holes: Vec<String> = (loop_tags.iter())
                .filter(|h| h.1 < 0.0)
                .filter(|h| {
                    let p = x[h.2[0]];
                    let holder = (outers.iter())
                        .filter(|c| inside(p, c.2, x))
                        .min_by(|a, b| a.1.total_cmp(&b.1));
                    holder.is_some_and(|c| c.0 == o.0)
                })
                .map(|h| h.0.to_string())
                .collect();
            let wires: Vec<String> = std::iter::once(o.0.to_string()).chain(holes).collect();
            let s = format!("{}{}", r + 1, surfaces.len() + 1);
            let _ = writeln!(text, "Plane Surface({s}) = {{{}}};", wires.join(", "));
            surfaces.push(s);
        }
        let _ = writeln!(
            text,
            "Physical Surface(\"medium{r}\") = {{{}}};",
            surfaces.join(", ")
        );
    }
    (text, nodes)
}

/// The mesh `mesh` with the cells of its medium blocks `medium` made again at the nodes'
/// places `x`: the blocks of each set of physical groups meshed together as one region, by
/// gmsh, between their boundary nodes. Files are written in the folder `scratch`. 2D, linear
/// cells only (a caller checks first with [`supported`]).
pub fn remesh(
    mesh: &Mesh,
    x: &[[f64; 3]],
    medium: &[usize],
    scratch: &Path,
) -> Result<Remeshed, String> {
    let regions = regions_of(mesh, medium);
    let loops: Vec<Vec<Vec<usize>>> = (regions.iter())
        .map(|r| boundary_loops(mesh, &r.1))
        .collect::<Result<_, _>>()?;
    let made = gmsh_between(&loops, x, scratch)?;
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
            .ok_or("gmsh made no cells in a medium region")?;
        let mut conn = Vec::new();
        for blk in made.cells.iter().filter(|b| b.groups.contains(&g)) {
            if blk.kind != CellKind::Tri3 {
                return Err(format!("gmsh made {} cells", blk.kind.name()));
            }
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

/// The triangles gmsh makes inside the boundary `loops` (nodes at their places `x`), through
/// a `.geo` written under `scratch`.
fn gmsh_between(loops: &[Vec<Vec<usize>>], x: &[[f64; 3]], scratch: &Path) -> Result<Mesh, String> {
    let (text, _) = geo_text(loops, x);
    std::fs::create_dir_all(scratch).map_err(|e| format!("{}: {e}", scratch.display()))?;
    let geo = scratch.join("medium.geo");
    std::fs::write(&geo, text).map_err(|e| format!("{}: {e}", geo.display()))?;
    Ok(
        mesh_geo(&geo, &scratch.join("medium.msh"), &MeshOptions::default())
            .map_err(|e| e.to_string())?
            .mesh,
    )
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
        let dir = std::env::temp_dir().join(format!("tmc-remesh-{}", std::process::id()));
        let r = remesh(&mesh, &x, &[0], &dir).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
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
}
