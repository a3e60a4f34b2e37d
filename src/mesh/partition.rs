//! The mesh cut into one part per rank for a distributed run: METIS k-way on the cells' dual
//! graph (cells are neighbours when they share a side), all cell blocks together. Each node
//! belongs to the lowest rank among its cells, each boundary facet to its first node's rank.
//! Computed from the mesh alone, so every rank computes the same parts.

use super::Mesh;
pub use crate::parallel::Partition;

/// METIS keeps process-wide statics (its random generator and memory core): concurrent calls
/// race, giving results that depend on other threads, or crash. Every call holds this.
pub(crate) static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PartitionError {
    #[error("{ranks} ranks for a mesh of {cells} cells: run on at most {cells} ranks")]
    TooManyRanks { ranks: usize, cells: usize },
    #[error("METIS could not partition the mesh into {parts} parts (status {status})")]
    Metis { parts: usize, status: i32 },
}

/// Everything on one rank.
pub fn whole(mesh: &Mesh) -> Partition {
    Partition {
        parts: 1,
        cell_rank: mesh.cells.iter().map(|b| vec![0; b.n_cells()]).collect(),
        facet_rank: mesh.facets.iter().map(|b| vec![0; b.n_cells()]).collect(),
        node_rank: vec![0; mesh.coords.len()],
    }
}

/// `parts` parts of about equal cell counts, with few cell sides between them.
pub fn cut(mesh: &Mesh, parts: usize) -> Result<Partition, PartitionError> {
    let cells: usize = mesh.cells.iter().map(|b| b.n_cells()).sum();
    if parts > cells {
        return Err(PartitionError::TooManyRanks {
            ranks: parts,
            cells,
        });
    }
    if parts == 1 {
        return Ok(whole(mesh));
    }
    let mut eptr = vec![0i32];
    let mut eind = Vec::new();
    for b in &mesh.cells {
        for c in 0..b.n_cells() {
            eind.extend(b.cell(c).iter().map(|&n| n as i32));
            eptr.push(eind.len() as i32);
        }
    }
    let mut epart = vec![0i32; cells];
    let mut npart = vec![0i32; mesh.coords.len()];
    let (mut ne, mut nn) = (cells as i32, mesh.coords.len() as i32);
    // neighbours share a side: an edge (2 nodes) in 2D, a face (at least 3) in 3D
    let mut ncommon = mesh.dim as i32;
    let mut nparts = parts as i32;
    let mut objval = 0i32;
    let mut options = [-1i32; metis_sys::METIS_NOPTIONS as usize];
    let status = {
        let _one_at_a_time = METIS.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: eptr/eind describe `cells` cells over `nn` nodes; METIS writes `cells`
        // entries of epart and `nn` of npart; options are METIS's defaults.
        unsafe {
            metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
            options[metis_sys::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
            metis_sys::METIS_PartMeshDual(
                &mut ne,
                &mut nn,
                eptr.as_mut_ptr(),
                eind.as_mut_ptr(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                &mut ncommon,
                &mut nparts,
                std::ptr::null_mut(),
                options.as_mut_ptr(),
                &mut objval,
                epart.as_mut_ptr(),
                npart.as_mut_ptr(),
            )
        }
    };
    if status != metis_sys::rstatus_et_METIS_OK {
        return Err(PartitionError::Metis { parts, status });
    }
    let mut cell_rank = Vec::new();
    let mut node_rank = vec![u32::MAX; mesh.coords.len()];
    let mut next = epart.iter();
    for b in &mesh.cells {
        let ranks: Vec<u32> = next.by_ref().take(b.n_cells()).map(|&r| r as u32).collect();
        for (c, &r) in ranks.iter().enumerate() {
            for &n in b.cell(c) {
                node_rank[n] = node_rank[n].min(r);
            }
        }
        cell_rank.push(ranks);
    }
    // nodes of no cell (none in a checked mesh) stay on rank 0
    for r in &mut node_rank {
        if *r == u32::MAX {
            *r = 0;
        }
    }
    let facet_rank = mesh
        .facets
        .iter()
        .map(|b| (0..b.n_cells()).map(|f| node_rank[b.cell(f)[0]]).collect())
        .collect();
    Ok(Partition {
        parts,
        cell_rank,
        facet_rank,
        node_rank,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Block, CellKind};

    /// A row of `n` unit squares.
    fn strip(n: usize) -> Mesh {
        let mut coords = Vec::new();
        for i in 0..=n {
            coords.push([i as f64, 0.0, 0.0]);
            coords.push([i as f64, 1.0, 0.0]);
        }
        let conn = (0..n)
            .flat_map(|i| [2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1])
            .collect();
        let cells = vec![Block {
            kind: CellKind::Quad4,
            groups: vec![],
            conn,
        }];
        Mesh::of_cells(2, coords, cells)
    }

    #[test]
    fn a_strip_is_cut_into_balanced_connected_parts() {
        let mesh = strip(40);
        let p = cut(&mesh, 2).unwrap();
        assert_eq!(p.cells_per_rank(), vec![20, 20]);
        // one cut: along the strip the rank changes once
        let r = &p.cell_rank[0];
        assert_eq!(r.windows(2).filter(|w| w[0] != w[1]).count(), 1);
        // a node is on the lowest rank of its cells: the cut's two nodes on rank r[cut]
        for (c, &rc) in r.iter().enumerate() {
            for &n in mesh.cells[0].cell(c) {
                assert!(p.node_rank[n] <= rc);
            }
        }
        assert_eq!(
            cut(&mesh, 41),
            Err(PartitionError::TooManyRanks {
                ranks: 41,
                cells: 40
            })
        );
        assert_eq!(cut(&mesh, 1).unwrap(), whole(&mesh));
    }
}
