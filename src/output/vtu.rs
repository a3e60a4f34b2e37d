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
use crate::post::FrictionCell;
use base64::Engine;
use base64::engine::general_purpose::STANDARD as BASE64;
use rayon::prelude::*;
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
    /// Scenes with friction: each cell's slip state and slip-plane normal (`None` off the
    /// friction regions, written as zeros).
    pub friction: Option<&'a [Option<FrictionCell>]>,
    /// Scenes where solids meet the medium: the contact pressure and shear traction per node
    /// (zero off the faces where they meet).
    pub contact: Option<(&'a [f64], &'a [[f64; 3]])>,
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

/// The cells a `.vtu` holds: all of the mesh, or one rank's part of it (a piece of a
/// `.pvtu`), with the nodes they use.
pub struct Piece {
    /// Cells, as indices in mesh block order (the order of `StepFields::cells`).
    pub cells: Vec<usize>,
    /// The nodes of those cells, increasing: the piece's points.
    pub nodes: Vec<usize>,
    /// Whether this is a part: then each point also carries its mesh node number (`node`),
    /// by which the parts of a state are put together.
    pub part: bool,
}

impl Piece {
    /// The whole mesh.
    pub fn whole(mesh: &Mesh) -> Piece {
        Piece {
            cells: (0..mesh.cells.iter().map(|b| b.n_cells()).sum()).collect(),
            nodes: (0..mesh.coords.len()).collect(),
            part: false,
        }
    }

    /// The cells whose flag in `mine` (mesh block order) is set, and their nodes.
    pub fn part(mesh: &Mesh, mine: &[bool]) -> Piece {
        let mut used = vec![false; mesh.coords.len()];
        let mut cells = Vec::new();
        let all = mesh
            .cells
            .iter()
            .flat_map(|b| (0..b.n_cells()).map(move |c| b.cell(c)));
        for (i, (nodes, &m)) in all.zip(mine).enumerate() {
            if m {
                cells.push(i);
                nodes.iter().for_each(|&n| used[n] = true);
            }
        }
        Piece {
            cells,
            nodes: (0..used.len()).filter(|&n| used[n]).collect(),
            part: true,
        }
    }
}

/// The point and cell data arrays of the nodes and cells of `piece`: what `write_vtu` writes
/// and, from an empty part, what `pvtu_text` declares.
fn data_arrays(mesh: &Mesh, f: &StepFields, piece: &Piece) -> (Vec<Array>, Vec<Array>) {
    let (pn, pc) = (&piece.nodes, &piece.cells);
    let ns = &f.nodal.sigma;
    let position = pn.iter().flat_map(|&n| {
        let (x, u) = (mesh.coords[n], f.u[n]);
        [x[0] + u[0], x[1] + u[1], x[2] + u[2]]
    });
    let mut point = vec![
        f64s("u", 3, pn.iter().flat_map(|&n| f.u[n])),
        f64s("position", 3, position),
    ];
    if let Some(t) = f.theta {
        point.push(f64s("theta", 1, pn.iter().map(|&n| t[n])));
    }
    if let Some((p, np)) = f.p {
        point.push(f64s(
            "p",
            np,
            pn.iter()
                .flat_map(|&n| p[n * np..(n + 1) * np].iter().copied()),
        ));
    }
    point.push(f64s("sigma", 9, pn.iter().flat_map(|&n| matrix(&ns[n]))));
    point.push(f64s("von_mises", 1, pn.iter().map(|&n| von_mises(&ns[n]))));
    point.push(f64s(
        "sigma_principal",
        3,
        pn.iter().flat_map(|&n| principal(&ns[n])),
    ));
    if f.theta.is_some() {
        point.push(f64s("q", 3, pn.iter().flat_map(|&n| f.nodal.q[n])));
    }
    if let Some((pressure, shear)) = f.contact {
        point.push(f64s("contact_pressure", 1, pn.iter().map(|&n| pressure[n])));
        point.push(f64s("contact_shear", 3, pn.iter().flat_map(|&n| shear[n])));
    }
    if piece.part {
        point.push(i64s("node", pn.iter().map(|&n| n as i64)));
    }

    let c: Vec<&CellFields> = pc.iter().map(|&i| &f.cells[i]).collect();
    let pick = |v: &[i32]| -> Vec<i32> { pc.iter().map(|&i| v[i]).collect() };
    let mut cell = vec![
        i32s("region", &pick(f.region)),
        i32s("region_kind", &pick(f.kind)),
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
    if let Some(friction) = f.friction {
        let fc: Vec<FrictionCell> = pc
            .iter()
            .map(|&i| friction[i].unwrap_or_default())
            .collect();
        cell.push(f64s("slip", 3, fc.iter().flat_map(|c| c.state.slip)));
        cell.push(f64s(
            "slip_increment",
            3,
            fc.iter().flat_map(|c| c.state.increment),
        ));
        cell.push(f64s("slipping", 1, fc.iter().map(|c| c.state.slipping)));
        cell.push(f64s("slip_normal", 3, fc.iter().flat_map(|c| c.normal)));
    }

    (point, cell)
}

/// Write one step's `.vtu` of the cells of `piece`, its data compressed at zlib level
/// `zlib_level` (0: uncompressed).
pub fn write_vtu(
    path: &Path,
    mesh: &Mesh,
    f: &StepFields,
    piece: &Piece,
    zlib_level: u32,
) -> Result<(), OutputError> {
    let (pn, pc) = (&piece.nodes, &piece.cells);
    let mut local = vec![usize::MAX; if piece.part { mesh.coords.len() } else { 0 }];
    if piece.part {
        pn.iter().enumerate().for_each(|(l, &n)| local[n] = l);
    }
    let at = |n: usize| if piece.part { local[n] } else { n } as i64;
    let points = f64s("Points", 3, pn.iter().flat_map(|&n| mesh.coords[n]));
    let (mut connectivity, mut offsets, mut types) = (Vec::new(), Vec::new(), Vec::new());
    let mut wanted = pc.iter().peekable();
    let mut index = 0;
    for b in &mesh.cells {
        for c in 0..b.n_cells() {
            if wanted.next_if_eq(&&index).is_some() {
                let cell = b.cell(c);
                match b.kind.vtk_order() {
                    Some(order) => connectivity.extend(order.iter().map(|&i| at(cell[i]))),
                    None => connectivity.extend(cell.iter().map(|&n| at(n))),
                }
                offsets.push(connectivity.len() as i64);
                types.push(b.kind.vtk_id());
            }
            index += 1;
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

    let (point, cell) = data_arrays(mesh, f, piece);

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
        pn.len(),
        pc.len()
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

/// An array's type, name and components as XML attributes.
fn attributes(a: &Array) -> String {
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
    format!(" type=\"{}\"{name}{components}", a.ty)
}

/// One `<DataArray>` element with its data encoded.
fn data_array(a: &Array, zlib_level: u32) -> String {
    let mut s = format!("<DataArray{} format=\"binary\">\n", attributes(a));
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
            .map(|b| deflate(b, zlib_level))
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

/// `bytes` deflated into a zlib stream at `level`. The compressor is kept per thread and
/// reset between blocks: a new one zeroes its tables (hundreds of kB) for every block, which
/// cost more than compressing a small scene's arrays.
fn deflate(bytes: &[u8], level: u32) -> Vec<u8> {
    thread_local! {
        static KEPT: std::cell::RefCell<Option<(u32, flate2::Compress)>> =
            const { std::cell::RefCell::new(None) };
    }
    KEPT.with_borrow_mut(|kept| {
        if kept.as_ref().is_none_or(|(l, _)| *l != level) {
            *kept = Some((
                level,
                flate2::Compress::new(flate2::Compression::new(level), true),
            ));
        }
        let (_, z) = kept.as_mut().expect("a compressor was just made");
        z.reset();
        // a stream never exceeds its input by more than a few bytes per 16 kB block
        let mut out = Vec::with_capacity(bytes.len() + bytes.len() / 1000 + 64);
        loop {
            let read = z.total_in() as usize;
            let status = z
                .compress_vec(&bytes[read..], &mut out, flate2::FlushCompress::Finish)
                .expect("deflating into memory");
            if status == flate2::Status::StreamEnd {
                return out;
            }
            out.reserve(out.capacity().max(64));
        }
    })
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The text of the `.pvtu` that puts the parts `pieces` (file names, beside it) of one step
/// together, declaring the arrays [`write_vtu`] writes for `fields` of a part.
pub fn pvtu_text(mesh: &Mesh, f: &StepFields, pieces: &[String]) -> String {
    let declare = |a: &Array| format!("<PDataArray{}/>\n", attributes(a));
    let none = Piece {
        cells: Vec::new(),
        nodes: Vec::new(),
        part: true,
    };
    let (point, cell) = data_arrays(mesh, f, &none);
    let points = f64s("Points", 3, std::iter::empty());
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<PUnstructuredGrid GhostLevel=\"0\">\n",
    );
    for (tag, arrays) in [("PPointData", &point), ("PCellData", &cell)] {
        s.push_str(&format!("<{tag}>\n"));
        arrays.iter().for_each(|a| s.push_str(&declare(a)));
        s.push_str(&format!("</{tag}>\n"));
    }
    s.push_str(&format!("<PPoints>\n{}</PPoints>\n", declare(&points)));
    for p in pieces {
        s.push_str(&format!("<Piece Source=\"{}\"/>\n", xml_escape(p)));
    }
    s.push_str("</PUnstructuredGrid>\n</VTKFile>\n");
    s
}

/// The (time, file name) pairs a `.pvd` of [`write_pvd`] lists; the error says what is wrong.
pub fn read_pvd(path: &Path) -> Result<Vec<(f64, String)>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read it ({e})"))?;
    let quoted = |line: &str, key: &str| -> Option<String> {
        let start = line.find(&format!("{key}=\""))? + key.len() + 2;
        let len = line[start..].find('"')?;
        Some(line[start..start + len].to_string())
    };
    let mut steps = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if !line.trim_start().starts_with("<DataSet") {
            continue;
        }
        let time = quoted(line, "timestep").and_then(|t| t.parse::<f64>().ok());
        match (time, quoted(line, "file")) {
            (Some(t), Some(f)) => steps.push((t, f)),
            _ => return Err(format!("line {} is not a data set of tmc's", i + 1)),
        }
    }
    if !text.trim_end().ends_with("</VTKFile>") {
        return Err("it ends before its last line".into());
    }
    Ok(steps)
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
