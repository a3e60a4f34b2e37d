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
    read_msh_bytes(path, &bytes)
}

/// Read MSH 4.1 `bytes`; `path` names the file in errors.
pub fn read_msh_bytes(path: &Path, bytes: &[u8]) -> Result<Mesh, MshError> {
    let invalid = |msg: String| MshError::Invalid {
        path: path.to_owned(),
        msg,
    };
    check_sections(bytes).map_err(|msg| MshError::Parse {
        path: path.to_owned(),
        msg,
    })?;
    let groups = physical_names(bytes).map_err(invalid)?;
    // mshio unwraps in a few places (e.g. a header number too large for its type): a panic
    // there is a parse error of this file, not of tmc
    let parsed = std::panic::catch_unwind(|| {
        mshio::parse_msh_bytes(bytes).map_err(|e| parse_message(bytes, &e))
    });
    let msh = match parsed {
        Ok(r) => r,
        Err(_) => Err("the MSH reader stopped on a malformed number".to_string()),
    }
    .map_err(|msg| MshError::Parse {
        path: path.to_owned(),
        msg,
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
            .filter(|x| x.iter().all(|v| v.is_finite()))
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
        warnings: Vec::new(),
    };
    mesh.warnings = super::check_geometry(&mesh).map_err(&invalid)?;
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
                "element type {} (entity {} of dim {}) is not supported; tmc reads tri3, quad4, tet4, hex8 and their second-order kinds tri6, quad8, quad9, tet10, hex20, hex27 (no prisms or pyramids: mesh with tetrahedra or hexahedra only)",
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

/// 1-based line number of byte `offset`.
fn line_of(bytes: &[u8], offset: usize) -> usize {
    1 + bytes[..offset.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// mshio's error as "line N: what (in section, block …)".
fn parse_message(bytes: &[u8], e: &mshio::error::MshParserError<&[u8]>) -> String {
    let trace = e.filtered_backtrace();
    let Some((at, kind)) = trace.first() else {
        return "malformed file".into();
    };
    let offset = (at.as_ptr() as usize).saturating_sub(bytes.as_ptr() as usize);
    let context: Vec<String> = trace[1..]
        .iter()
        .rev()
        .map(|(_, k)| {
            k.context()
                .map(str::to_string)
                .unwrap_or_else(|| k.to_string())
        })
        .collect();
    let what = kind.to_string();
    if context.is_empty() {
        format!("line {}: {what}", line_of(bytes, offset))
    } else {
        format!(
            "line {}: {what} (in {})",
            line_of(bytes, offset),
            context.join(", in ")
        )
    }
}

/// Every `$Section` line must be closed by its `$EndSection` before the next section opens:
/// a truncated or spliced file is named by its section and line, before any parsing.
/// (Binary data may hold `$` bytes, so only the text before `$Nodes`/`$Elements` data of a
/// binary file is scanned line by line: those sections are found by their end markers.)
fn check_sections(bytes: &[u8]) -> Result<(), String> {
    if !bytes.starts_with(b"$MeshFormat") {
        return Err("not a gmsh mesh: the file must start with $MeshFormat".into());
    }
    let header = bytes
        .split(|&b| b == b'\n')
        .nth(1)
        .and_then(|l| std::str::from_utf8(l).ok())
        .unwrap_or("");
    let fields: Vec<&str> = header.split_whitespace().collect();
    match fields.as_slice() {
        ["4.1", "0" | "1", "4" | "8"] => {}
        [v, ..] if *v != "4.1" => {
            return Err(format!(
                "line 2: MSH version {v}; tmc reads MSH 4.1 (gmsh -format msh41)"
            ));
        }
        _ => {
            return Err(format!(
                "line 2: \"{}\" is not a MSH 4.1 header (version, 0 or 1 for ASCII or binary, size of size_t)",
                header.trim().chars().take(60).collect::<String>()
            ));
        }
    }
    let binary = fields[1] == "1";
    let mut open: Option<(&[u8], usize)> = None;
    let mut line = 0usize;
    let mut pos = 0usize;
    while pos < bytes.len() {
        line += 1;
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |k| pos + k);
        let l = bytes[pos..end]
            .strip_suffix(b"\r")
            .unwrap_or(&bytes[pos..end]);
        if let Some(name) = l.strip_prefix(b"$")
            && !name.is_empty()
            && name.iter().all(|b| b.is_ascii_alphanumeric())
        {
            match open {
                Some((sec, _)) if name.strip_prefix(b"End") == Some(sec) => open = None,
                Some((sec, start)) if !binary => {
                    return Err(format!(
                        "line {line}: ${} inside section ${} opened at line {start}, which has no ${}{} (a truncated or spliced file?)",
                        String::from_utf8_lossy(name),
                        String::from_utf8_lossy(sec),
                        "End",
                        String::from_utf8_lossy(sec),
                    ));
                }
                Some(_) => {}
                None if name.starts_with(b"End") => {
                    return Err(format!(
                        "line {line}: ${} closes no open section",
                        String::from_utf8_lossy(name)
                    ));
                }
                None => open = Some((name, line)),
            }
        }
        pos = end + 1;
    }
    if let Some((sec, start)) = open {
        return Err(format!(
            "section ${} opened at line {start} has no $End{} (the file ends at line {line}: truncated?)",
            String::from_utf8_lossy(sec),
            String::from_utf8_lossy(sec)
        ));
    }
    Ok(())
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
    let lines: Vec<&str> = lines.collect();
    if lines.len() != n {
        return Err(format!(
            "$PhysicalNames announces {n} names but holds {} lines",
            lines.len()
        ));
    }
    let mut groups = Vec::with_capacity(n);
    for line in lines {
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
