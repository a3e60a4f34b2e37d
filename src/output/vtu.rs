//! ParaView files: one `.vtu` (VTK XML unstructured grid) per step and the `.pvd` collection.

use super::{OutputError, werr, write_atomic};
use crate::kernel::CellFields;
use crate::mesh::Mesh;
use std::path::Path;
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataSet, Piece, UnstructuredGridPiece,
    Version, VertexNumbers, Vtk,
};

fn vtk_cell_type(id: u8) -> CellType {
    match id {
        3 => CellType::Line,
        5 => CellType::Triangle,
        9 => CellType::Quad,
        10 => CellType::Tetra,
        12 => CellType::Hexahedron,
        21 => CellType::QuadraticEdge,
        22 => CellType::QuadraticTriangle,
        23 => CellType::QuadraticQuad,
        28 => CellType::BiquadraticQuad,
        24 => CellType::QuadraticTetra,
        25 => CellType::QuadraticHexahedron,
        29 => CellType::TriquadraticHexahedron,
        _ => CellType::Vertex,
    }
}

/// Nodal and cell data of one step.
pub struct StepFields<'a> {
    /// Displacement per node (zeros without mechanics).
    pub u: &'a [[f64; 3]],
    /// Temperature per node, if simulated.
    pub theta: Option<&'a [f64]>,
    /// Regularization fields per node (`np` components, zero off the medium), if any.
    pub p: Option<(&'a [f64], usize)>,
    /// Cell data in mesh block order.
    pub cells: &'a [CellFields],
    /// Region index and kind (0 solid, 1 medium) per cell.
    pub region: &'a [i32],
    pub kind: &'a [i32],
}

/// Write one step's `.vtu`.
pub fn write_vtu(path: &Path, mesh: &Mesh, f: &StepFields) -> Result<(), OutputError> {
    let points: Vec<f64> = mesh.coords.iter().flat_map(|x| x.iter().copied()).collect();
    let mut connectivity = Vec::new();
    let mut offsets = Vec::new();
    let mut types = Vec::new();
    for b in &mesh.cells {
        for c in 0..b.n_cells() {
            let cell = b.cell(c);
            match b.kind.vtk_order() {
                Some(order) => connectivity.extend(order.iter().map(|&i| cell[i] as u64)),
                None => connectivity.extend(cell.iter().map(|&n| n as u64)),
            }
            offsets.push(connectivity.len() as u64);
            types.push(vtk_cell_type(b.kind.vtk_id()));
        }
    }
    let u: Vec<f64> = f.u.iter().flat_map(|v| v.iter().copied()).collect();
    let pos: Vec<f64> = mesh
        .coords
        .iter()
        .zip(f.u)
        .flat_map(|(x, u)| [x[0] + u[0], x[1] + u[1], x[2] + u[2]])
        .collect();
    let mut point = vec![
        Attribute::vectors("u").with_data(u),
        Attribute::vectors("position").with_data(pos),
    ];
    if let Some(t) = f.theta {
        point.push(Attribute::scalars("theta", 1).with_data(t.to_vec()));
    }
    if let Some((p, np)) = f.p {
        point.push(Attribute::scalars("p", np as u32).with_data(p.to_vec()));
    }
    let c = f.cells;
    let sigma: Vec<f64> = c
        .iter()
        .flat_map(|c| c.sigma.iter().flatten().copied().collect::<Vec<_>>())
        .collect();
    let pressure: Vec<f64> = c
        .iter()
        .map(|c| -(c.sigma[0][0] + c.sigma[1][1] + c.sigma[2][2]) / 3.0)
        .collect();
    let mut cell = vec![
        Attribute::scalars("region", 1).with_data(f.region.to_vec()),
        Attribute::scalars("region_kind", 1).with_data(f.kind.to_vec()),
        Attribute::scalars("J", 1).with_data(c.iter().map(|c| c.J).collect::<Vec<_>>()),
        Attribute::tensors("sigma").with_data(sigma),
        Attribute::scalars("pressure", 1).with_data(pressure),
    ];
    if f.theta.is_some() {
        cell.push(
            Attribute::vectors("q").with_data(c.iter().flat_map(|c| c.q).collect::<Vec<_>>()),
        );
        cell.push(Attribute::scalars("k", 1).with_data(c.iter().map(|c| c.k).collect::<Vec<_>>()));
    }
    let vtk = Vtk {
        version: Version::XML { major: 1, minor: 0 },
        title: String::new(),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::UnstructuredGrid {
            meta: None,
            pieces: vec![Piece::Inline(Box::new(UnstructuredGridPiece {
                points: points.into(),
                cells: Cells {
                    cell_verts: VertexNumbers::XML {
                        connectivity,
                        offsets,
                    },
                    types,
                },
                data: Attributes { point, cell },
            }))],
        },
    };
    // into memory, then through the checked write (vtkio's own file export drops write
    // errors: a full disk left a truncated file under the final name)
    let mut bytes = Vec::new();
    vtk.write_xml(&mut bytes).map_err(|e| werr(path, e))?;
    write_atomic(path, &bytes)
}

/// Write the `.pvd` collection of (λ, file name) pairs.
pub fn write_pvd(path: &Path, steps: &[(f64, String)]) -> Result<(), OutputError> {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n",
    );
    for (t, file) in steps {
        s.push_str(&format!(
            "    <DataSet timestep=\"{t}\" part=\"0\" file=\"{file}\"/>\n"
        ));
    }
    s.push_str("  </Collection>\n</VTKFile>\n");
    write_atomic(path, s.as_bytes())
}
