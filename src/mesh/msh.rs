//! Reading gmsh MSH 4.1 files with mshio, plus our own parse of `$PhysicalNames` (which mshio
//! skips).

use super::{Block, CellKind, Mesh, PhysicalGroup, gmsh_type_name};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum MshError {
    #[error("cannot read mesh file {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "{path}: not a readable MSH 4.1 file ({msg}); re-mesh with `tmc mesh` or gmsh -format msh41"
    )]
    Parse { path: PathBuf, msg: String },
    #[error("{path}: {msg}")]
    Invalid { path: PathBuf, msg: String },
}

/// Read a `.msh` (MSH 4.1, ASCII or binary) into a [`Mesh`].
pub fn read_msh(path: &Path) -> Result<Mesh, MshError> {
    let bytes = std::fs::read(path).map_err(|source| MshError::Io {
        path: path.to_owned(),
        source,
    })?;
    let invalid = |msg: String| MshError::Invalid {
        path: path.to_owned(),
        msg,
    };
    let groups = physical_names(&bytes).map_err(invalid)?;
    let msh = mshio::parse_msh_bytes(&bytes).map_err(|e| MshError::Parse {
        path: path.to_owned(),
        msg: first_line(&format!("{e}")),
    })?;
    if groups.is_empty() {
        return Err(invalid(
            "the mesh has no named physical groups; tag solids, medium and boundaries with \
             Physical Surface/Volume/Curve(\"name\") in the .geo"
                .into(),
        ));
    }
    let entities = msh
        .data
        .entities
        .as_ref()
        .ok_or_else(|| invalid("no $Entities section".into()))?;
    let nodes = msh
        .data
        .nodes
        .as_ref()
        .ok_or_else(|| invalid("no $Nodes section".into()))?;
    let elements = msh
        .data
        .elements
        .as_ref()
        .ok_or_else(|| invalid("no $Elements section".into()))?;
    let (node_index, raw_coords) = read_nodes(nodes);
    let dim = elements
        .element_blocks
        .iter()
        .map(|b| b.entity_dim)
        .max()
        .unwrap_or(0);
    if dim < 2 {
        return Err(invalid("the mesh has no 2D or 3D cells".into()));
    }
    let physicals = entity_physicals(entities);
    let (mut cells, mut facets) =
        read_blocks(elements, dim, &physicals, &groups, &node_index).map_err(invalid)?;
    let coords = renumber(&mut cells, &mut facets, &raw_coords, &groups, dim).map_err(invalid)?;
    if dim == 2
        && let Some(x) = coords
            .iter()
            .find(|x| x[2].abs() > 1e-12 * (1.0 + x[0].abs() + x[1].abs()))
    {
        return Err(invalid(format!(
            "2D mesh must lie in the plane z = 0; node at {x:?}"
        )));
    }
    let mut mesh = Mesh {
        dim: dim as usize,
        coords,
        cells,
        facets,
        groups,
        source: path.to_owned(),
    };
    orient_cells(&mut mesh);
    Ok(mesh)
}

/// (dim, entity tag) → the entity's physical tags.
fn entity_physicals(entities: &mshio::Entities<i32, f64>) -> HashMap<(i32, i32), Vec<i32>> {
    let mut entity_phys: HashMap<(i32, i32), Vec<i32>> = HashMap::new();
    for p in &entities.points {
        entity_phys.insert((0, p.tag), p.physical_tags.clone());
    }
    for c in &entities.curves {
        entity_phys.insert((1, c.tag), c.physical_tags.clone());
    }
    for s in &entities.surfaces {
        entity_phys.insert((2, s.tag), s.physical_tags.clone());
    }
    for v in &entities.volumes {
        entity_phys.insert((3, v.tag), v.physical_tags.clone());
    }
    entity_phys
}

/// Node tag → index, and the coordinates in file order.
fn read_nodes(nodes: &mshio::Nodes<u64, i32, f64>) -> (HashMap<u64, usize>, Vec<[f64; 3]>) {
    let mut node_index: HashMap<u64, usize> = HashMap::new();
    let mut raw_coords: Vec<[f64; 3]> = Vec::new();
    let mut next_tag = nodes.min_node_tag;
    for block in &nodes.node_blocks {
        match &block.node_tags {
            Some(tags) => {
                let mut by_index: Vec<(usize, u64)> = tags.iter().map(|(&t, &i)| (i, t)).collect();
                by_index.sort_unstable();
                for (i, t) in by_index {
                    let n = &block.nodes[i];
                    node_index.insert(t, raw_coords.len());
                    raw_coords.push([n.x, n.y, n.z]);
                }
            }
            None => {
                // dense tags: consecutive from min_node_tag in file order
                for n in &block.nodes {
                    node_index.insert(next_tag, raw_coords.len());
                    raw_coords.push([n.x, n.y, n.z]);
                    next_tag += 1;
                }
            }
        }
    }

    (node_index, raw_coords)
}

/// The element blocks as cell blocks (of dimension `dim`) and facet blocks (lower, tagged),
/// their nodes as indices into the file's nodes.
fn read_blocks(
    elements: &mshio::Elements<u64, i32>,
    dim: i32,
    entity_phys: &HashMap<(i32, i32), Vec<i32>>,
    groups: &[PhysicalGroup],
    node_index: &HashMap<u64, usize>,
) -> Result<(Vec<Block>, Vec<Block>), String> {
    let invalid = |msg: String| msg;
    let group_of = |d: i32, tag: i32| {
        groups
            .iter()
            .position(|g| g.dim as i32 == d && g.tag == tag)
    };
    let mut cells = Vec::new();
    let mut facets = Vec::new();
    for block in &elements.element_blocks {
        let gtype = block.element_type as u32;
        let kind = CellKind::from_gmsh(gtype).ok_or_else(|| {
            invalid(format!(
                "element type {} (entity {} of dim {}) is not supported; tmc reads tri3, quad4, tet4, hex8",
                gmsh_type_name(gtype),
                block.entity_tag,
                block.entity_dim
            ))
        })?;
        if kind.dim() as i32 != block.entity_dim {
            return Err(invalid(format!(
                "element type {} in an entity of dimension {}",
                kind.name(),
                block.entity_dim
            )));
        }
        let phys = entity_phys
            .get(&(block.entity_dim, block.entity_tag))
            .cloned()
            .unwrap_or_default();
        let bgroups: Vec<usize> = phys
            .iter()
            .filter_map(|&t| group_of(block.entity_dim, t))
            .collect();
        if bgroups.is_empty() && block.entity_dim < dim {
            continue; // an untagged lower-dimensional entity carries nothing
        }
        let mut conn = Vec::with_capacity(block.elements.len() * kind.n_nodes());
        for e in &block.elements {
            if e.nodes.len() != kind.n_nodes() {
                return Err(invalid(format!(
                    "element {} has {} nodes",
                    e.element_tag,
                    e.nodes.len()
                )));
            }
            for t in &e.nodes {
                let &i = node_index.get(t).ok_or_else(|| {
                    invalid(format!(
                        "element {} refers to unknown node {t}",
                        e.element_tag
                    ))
                })?;
                conn.push(i);
            }
        }
        let b = Block {
            kind,
            groups: bgroups,
            conn,
        };
        if block.entity_dim == dim {
            cells.push(b);
        } else {
            facets.push(b);
        }
    }

    Ok((cells, facets))
}

/// Keep only the nodes that belong to a cell, numbered in order of first use; every facet
/// node must be one of them. Returns the coordinates.
fn renumber(
    cells: &mut [Block],
    facets: &mut [Block],
    raw_coords: &[[f64; 3]],
    groups: &[PhysicalGroup],
    dim: i32,
) -> Result<Vec<[f64; 3]>, String> {
    let mut new_index = vec![usize::MAX; raw_coords.len()];
    let mut coords = Vec::new();
    for b in cells.iter_mut() {
        for n in &mut b.conn {
            if new_index[*n] == usize::MAX {
                new_index[*n] = coords.len();
                coords.push(raw_coords[*n]);
            }
            *n = new_index[*n];
        }
    }
    for b in facets.iter_mut() {
        for n in &mut b.conn {
            if new_index[*n] == usize::MAX {
                let g = b
                    .groups
                    .first()
                    .map(|&g| groups[g].name.as_str())
                    .unwrap_or("?");
                return Err(format!(
                    "physical group \"{g}\" has a node at {:?} that belongs to no {dim}D cell",
                    raw_coords[*n]
                ));
            }
            *n = new_index[*n];
        }
    }
    Ok(coords)
}

/// gmsh may write 2D cells clockwise (e.g. surfaces whose normal points along −z); flip them so
/// every reference map has a positive Jacobian.
fn orient_cells(mesh: &mut Mesh) {
    if mesh.dim != 2 {
        return;
    }
    for b in &mut mesh.cells {
        let (n, k) = (b.kind.n_nodes(), b.kind.corners());
        let flip = b.kind.flip();
        for c in b.conn.chunks_mut(n) {
            let area2: f64 = (0..k)
                .map(|i| {
                    let (p, q) = (mesh.coords[c[i]], mesh.coords[c[(i + 1) % k]]);
                    p[0] * q[1] - q[0] * p[1]
                })
                .sum();
            if area2 < 0.0 {
                let old: Vec<usize> = c.to_vec();
                for (new, &from) in c.iter_mut().zip(flip) {
                    *new = old[from];
                }
            }
        }
    }
}

fn first_line(s: &str) -> String {
    s.lines().next().unwrap_or("").chars().take(200).collect()
}

/// Parse the `$PhysicalNames` section: lines `dim tag "name"`.
fn physical_names(bytes: &[u8]) -> Result<Vec<PhysicalGroup>, String> {
    let start_tag = b"$PhysicalNames";
    let Some(start) = bytes.windows(start_tag.len()).position(|w| w == start_tag) else {
        return Ok(Vec::new());
    };
    let rest = &bytes[start + start_tag.len()..];
    let end_tag = b"$EndPhysicalNames";
    let end = rest
        .windows(end_tag.len())
        .position(|w| w == end_tag)
        .ok_or("unterminated $PhysicalNames section")?;
    let text = std::str::from_utf8(&rest[..end]).map_err(|_| "$PhysicalNames is not UTF-8")?;
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let n: usize = lines
        .next()
        .and_then(|l| l.parse().ok())
        .ok_or("bad count in $PhysicalNames")?;
    let mut groups = Vec::with_capacity(n);
    for line in lines.take(n) {
        let mut it = line.splitn(3, char::is_whitespace);
        let dim: usize = it
            .next()
            .and_then(|s| s.parse().ok())
            .ok_or("bad dim in $PhysicalNames")?;
        let tag: i32 = it
            .next()
            .and_then(|s| s.parse().ok())
            .ok_or("bad tag in $PhysicalNames")?;
        let name = it.next().unwrap_or("").trim().trim_matches('"').to_string();
        if groups.iter().any(|g: &PhysicalGroup| g.name == name) {
            return Err(format!("physical name \"{name}\" is used by two groups"));
        }
        groups.push(PhysicalGroup { name, dim, tag });
    }
    Ok(groups)
}
