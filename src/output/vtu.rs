//! ParaView files: one `.vtu` (VTK XML unstructured grid) per step and the `.pvd` collection.
//!
//! The `.vtu` is written here rather than through vtkio's model: VTK's connectivity type
//! (`Int64`) and field data are not in that model, and its compressor takes values one by one
//! (three times the write time of the uncompressed file, measured by `make bench`). The format
//! is VTK's "binary" inline data: per array a header of `UInt64`s, then the data, each
//! base64-encoded; compressed arrays are cut into blocks of [`BLOCK`] bytes, each deflated
//! (zlib), the header listing the blocks' sizes.

use super::nodal::{NodalFields, principal, von_mises};
use super::{OutputError, write_atomic};
use crate::kernel::CellFields;
use crate::mesh::Mesh;
use base64::Engine;
use base64::engine::general_purpose::STANDARD as BASE64;
use rayon::prelude::*;
use std::io::Write;
use std::path::Path;

/// zlib level of the data (0: uncompressed). `make bench` (output) measures the levels.
pub const ZLIB_LEVEL: u32 = 1;

/// Uncompressed size of a compressed block (VTK's default).
const BLOCK: usize = 1 << 15;

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
    /// Cauchy stress and heat flux at the nodes.
    pub nodal: &'a NodalFields,
    /// Region index and kind (0 solid, 1 medium) per cell.
    pub region: &'a [i32],
    pub kind: &'a [i32],
    /// Region names, indexed by `region`: written as field data.
    pub region_names: &'a [String],
}

/// One data array: name, VTK type, components and its little-endian bytes.
struct Array {
    name: &'static str,
    ty: &'static str,
    components: usize,
    bytes: Vec<u8>,
}

fn f64s(name: &'static str, components: usize, v: impl Iterator<Item = f64>) -> Array {
    Array {
        name,
        ty: "Float64",
        components,
        bytes: v.flat_map(f64::to_le_bytes).collect(),
    }
}

fn i64s(name: &'static str, v: impl Iterator<Item = i64>) -> Array {
    Array {
        name,
        ty: "Int64",
        components: 1,
        bytes: v.flat_map(i64::to_le_bytes).collect(),
    }
}

fn i32s(name: &'static str, v: &[i32]) -> Array {
    Array {
        name,
        ty: "Int32",
        components: 1,
        bytes: v.iter().flat_map(|x| x.to_le_bytes()).collect(),
    }
}

fn matrix(m: &[[f64; 3]; 3]) -> impl Iterator<Item = f64> + '_ {
    m.iter().flatten().copied()
}

/// Write one step's `.vtu`, its data compressed at zlib level `zlib_level` (0: uncompressed).
pub fn write_vtu(
    path: &Path,
    mesh: &Mesh,
    f: &StepFields,
    zlib_level: u32,
) -> Result<(), OutputError> {
    let points = f64s("Points", 3, mesh.coords.iter().flatten().copied());
    let (mut connectivity, mut offsets, mut types) = (Vec::new(), Vec::new(), Vec::new());
    for b in &mesh.cells {
        for c in 0..b.n_cells() {
            let cell = b.cell(c);
            match b.kind.vtk_order() {
                Some(order) => connectivity.extend(order.iter().map(|&i| cell[i] as i64)),
                None => connectivity.extend(cell.iter().map(|&n| n as i64)),
            }
            offsets.push(connectivity.len() as i64);
            types.push(b.kind.vtk_id());
        }
    }
    let cells = vec![
        i64s("connectivity", connectivity.into_iter()),
        i64s("offsets", offsets.into_iter()),
        Array {
            name: "types",
            ty: "UInt8",
            components: 1,
            bytes: types,
        },
    ];

    let ns = &f.nodal.sigma;
    let position = mesh
        .coords
        .iter()
        .zip(f.u)
        .flat_map(|(x, u)| [x[0] + u[0], x[1] + u[1], x[2] + u[2]]);
    let mut point = vec![
        f64s("u", 3, f.u.iter().flatten().copied()),
        f64s("position", 3, position),
    ];
    if let Some(t) = f.theta {
        point.push(f64s("theta", 1, t.iter().copied()));
    }
    if let Some((p, np)) = f.p {
        point.push(f64s("p", np, p.iter().copied()));
    }
    point.push(f64s("sigma", 9, ns.iter().flat_map(matrix)));
    point.push(f64s("von_mises", 1, ns.iter().map(von_mises)));
    point.push(f64s("sigma_principal", 3, ns.iter().flat_map(principal)));
    if f.theta.is_some() {
        point.push(f64s("q", 3, f.nodal.q.iter().flatten().copied()));
    }

    let c = f.cells;
    let mut cell = vec![
        i32s("region", f.region),
        i32s("region_kind", f.kind),
        f64s("J", 1, c.iter().map(|c| c.J)),
        f64s("sigma", 9, c.iter().flat_map(|c| matrix(&c.sigma))),
        f64s(
            "pressure",
            1,
            c.iter()
                .map(|c| -(c.sigma[0][0] + c.sigma[1][1] + c.sigma[2][2]) / 3.0),
        ),
        f64s("von_mises", 1, c.iter().map(|c| von_mises(&c.sigma))),
    ];
    if f.theta.is_some() {
        cell.push(f64s("q", 3, c.iter().flat_map(|c| c.q)));
        cell.push(f64s("k", 1, c.iter().map(|c| c.k)));
    }

    // the arrays are encoded in parallel; the document is put together in order
    let sections = [&[points][..], &cells, &point, &cell];
    let encoded: Vec<Vec<String>> = sections
        .par_iter()
        .map(|arrays| {
            arrays
                .par_iter()
                .map(|a| data_array(a, zlib_level))
                .collect()
        })
        .collect();
    let mut xml =
        String::with_capacity(encoded.iter().flatten().map(String::len).sum::<usize>() + 4096);
    xml.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\"");
    if zlib_level > 0 {
        xml.push_str(" compressor=\"vtkZLibDataCompressor\"");
    }
    xml.push_str(">\n<UnstructuredGrid>\n<FieldData>\n");
    // one Int32 array per region, named by it and holding its index: meshio reads that as
    // `field_data`; a `String` array it cannot read
    for (i, name) in f.region_names.iter().enumerate() {
        xml.push_str(&format!(
            "<DataArray type=\"Int32\" Name=\"{}\" NumberOfTuples=\"1\" format=\"ascii\">{i}</DataArray>\n",
            xml_escape(name)
        ));
    }
    xml.push_str(&format!(
        "</FieldData>\n<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
        mesh.coords.len(),
        f.region.len()
    ));
    for (tag, arrays) in ["Points", "Cells", "PointData", "CellData"]
        .iter()
        .zip(&encoded)
    {
        xml.push_str(&format!("<{tag}>\n"));
        for a in arrays {
            xml.push_str(a);
        }
        xml.push_str(&format!("</{tag}>\n"));
    }
    xml.push_str("</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    write_atomic(path, xml.as_bytes())
}

/// One `<DataArray>` element with its data encoded.
fn data_array(a: &Array, zlib_level: u32) -> String {
    let name = if a.name == "Points" {
        String::new()
    } else {
        format!(" Name=\"{}\"", a.name)
    };
    // one component is VTK's default, and meshio then reads a flat array
    let components = match a.components {
        1 => String::new(),
        n => format!(" NumberOfComponents=\"{n}\""),
    };
    let mut s = format!(
        "<DataArray type=\"{}\"{name}{components} format=\"binary\">\n",
        a.ty
    );
    let header: Vec<u64>;
    let mut data = Vec::new();
    if zlib_level == 0 {
        header = vec![a.bytes.len() as u64];
        data.extend_from_slice(&a.bytes);
    } else {
        // full blocks, then a partial last one whose size the header gives (0: none)
        let blocks: Vec<Vec<u8>> = a
            .bytes
            .chunks(BLOCK)
            .map(|b| {
                let mut z = flate2::write::ZlibEncoder::new(
                    Vec::new(),
                    flate2::Compression::new(zlib_level),
                );
                z.write_all(b)
                    .and_then(|_| z.finish())
                    .expect("deflating into memory")
            })
            .collect();
        let mut h = vec![
            blocks.len() as u64,
            BLOCK as u64,
            (a.bytes.len() % BLOCK) as u64,
        ];
        h.extend(blocks.iter().map(|b| b.len() as u64));
        header = h;
        for b in blocks {
            data.extend(b);
        }
    }
    // header and data are encoded separately, as VTK does
    let header: Vec<u8> = header.iter().flat_map(|x| x.to_le_bytes()).collect();
    BASE64.encode_string(header, &mut s);
    BASE64.encode_string(data, &mut s);
    s.push_str("\n</DataArray>\n");
    s
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
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
