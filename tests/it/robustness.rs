//! Hostile inputs: every mutation of a valid mesh or case file must end in an `Err` with a
//! message or in a valid result, never in a panic.

use crate::common;

use common::{root, scratch};
use std::panic::{AssertUnwindSafe, catch_unwind};
use tmc::mesh::gmsh::{MeshOptions, mesh_geo};
use tmc::mesh::msh::read_msh_bytes;

/// A small reproducible generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Byte offsets of the starts of lines beginning with `$` (section boundaries).
fn section_starts(bytes: &[u8]) -> Vec<usize> {
    let mut v = vec![0];
    for i in 0..bytes.len() {
        if bytes[i] == b'$' && (i == 0 || bytes[i - 1] == b'\n') {
            v.push(i);
        }
    }
    v.push(bytes.len());
    v
}

/// Numbers that break counts, sizes and ids.
const HOSTILE: &[&str] = &[
    "0",
    "-1",
    "-2147483649",
    "2147483648",
    "4294967296",
    "100000000000000",
    "18446744073709551615",
    "18446744073709551616",
    "9223372036854775807",
    "1e308",
    "nan",
    "inf",
    "",
    "x",
];

/// Mutations of `bytes`: truncation at every section boundary and at random bytes, byte flips,
/// hostile numbers in place of numbers, swapped and dropped sections.
fn mutations(bytes: &[u8], rng: &mut Rng, n_random: usize) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let starts = section_starts(bytes);
    for &s in &starts {
        out.push(bytes[..s].to_vec());
        // inside the section's first lines too
        for k in [1usize, 10, 30] {
            out.push(bytes[..(s + k).min(bytes.len())].to_vec());
        }
    }
    // drop or swap whole sections
    for w in starts.windows(2) {
        let mut v = bytes[..w[0]].to_vec();
        v.extend_from_slice(&bytes[w[1]..]);
        out.push(v);
    }
    for w in starts.windows(3) {
        let mut v = bytes[..w[0]].to_vec();
        v.extend_from_slice(&bytes[w[1]..w[2]]);
        v.extend_from_slice(&bytes[w[0]..w[1]]);
        v.extend_from_slice(&bytes[w[2]..]);
        out.push(v);
    }
    // numbers: the positions of every whitespace-separated token
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if !bytes[i].is_ascii_whitespace() {
            let j = (i..bytes.len())
                .find(|&j| bytes[j].is_ascii_whitespace())
                .unwrap_or(bytes.len());
            tokens.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    for _ in 0..n_random {
        let mut v = bytes.to_vec();
        match rng.below(4) {
            0 => v.truncate(rng.below(bytes.len())),
            1 => {
                for _ in 0..1 + rng.below(4) {
                    let k = rng.below(v.len());
                    v[k] = rng.next() as u8;
                }
            }
            _ => {
                // the first tokens of each section hold its counts: favour them
                let (a, b) = if rng.below(2) == 0 {
                    let s = starts[rng.below(starts.len() - 1)];
                    let first = tokens.iter().position(|&(a, _)| a >= s).unwrap_or(0);
                    tokens[(first + 1 + rng.below(8)).min(tokens.len() - 1)]
                } else {
                    tokens[rng.below(tokens.len())]
                };
                let h = HOSTILE[rng.below(HOSTILE.len())].as_bytes();
                v.splice(a..b, h.iter().copied());
            }
        }
        out.push(v);
    }
    out
}

fn valid_meshes() -> Vec<(String, Vec<u8>)> {
    let dir = scratch("robust-msh");
    type Scene = (&'static str, &'static [(&'static str, f64)], u8);
    let scenes: &[Scene] = &[
        ("block.geo", &[("n", 3.0), ("m", 2.0), ("l", 1.0)], 1),
        ("block.geo", &[("n", 2.0), ("m", 1.0), ("l", 1.0)], 2),
        ("mixed2d.geo", &[("h", 0.6)], 1),
        ("box-tet.geo", &[("h", 0.6)], 1),
        ("bar3d.geo", &[("n", 2.0), ("m", 1.0)], 2),
    ];
    scenes
        .iter()
        .enumerate()
        .map(|(k, (geo, params, order))| {
            let msh = dir.join(format!("{k}.msh"));
            let opts = MeshOptions {
                order: *order,
                set_numbers: params.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
                ..Default::default()
            };
            mesh_geo(&root().join("geo").join(geo), &msh, &opts).unwrap();
            (format!("{geo} order {order}"), std::fs::read(&msh).unwrap())
        })
        .chain(binary_meshes(&dir))
        .collect()
}

/// Binary MSH 4.1 (what gmsh writes with `-bin`), through Debian's gmsh command.
fn binary_meshes(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    [
        ("block.geo", "-2", "n 3 m 2 l 1"),
        ("box-tet.geo", "-3", "h 0.7"),
    ]
    .iter()
    .map(|(geo, d, params)| {
        let out = dir.join(format!("{geo}.bin.msh"));
        let mut cmd = std::process::Command::new("gmsh");
        cmd.arg(root().join("geo").join(geo))
            .args([*d, "-bin", "-format", "msh41", "-o"])
            .arg(&out);
        let p: Vec<&str> = params.split(' ').collect();
        for kv in p.chunks(2) {
            cmd.args(["-setnumber", kv[0], kv[1]]);
        }
        let st = cmd.output().expect("gmsh (Debian package gmsh) runs");
        assert!(st.status.success(), "gmsh {geo}");
        (format!("{geo} binary"), std::fs::read(&out).unwrap())
    })
    .collect()
}

#[test]
fn mutated_meshes_never_panic() {
    let mut rng = Rng(0x5eed_0001);
    let mut tried = 0;
    let mut accepted = 0;
    let mut panics = Vec::new();
    let path = std::path::Path::new("fuzz.msh");
    for (name, bytes) in valid_meshes() {
        assert!(read_msh_bytes(path, &bytes).is_ok(), "{name} is valid");
        for (k, m) in mutations(&bytes, &mut rng, 600).into_iter().enumerate() {
            tried += 1;
            match catch_unwind(AssertUnwindSafe(|| read_msh_bytes(path, &m))) {
                Ok(Ok(_)) => accepted += 1,
                Ok(Err(e)) => assert!(!e.to_string().is_empty()),
                Err(p) => {
                    let msg = p
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_default();
                    let keep = scratch("robust-msh-panics");
                    std::fs::write(keep.join(format!("{}-{k}.msh", name.replace(' ', "_"))), &m)
                        .ok();
                    panics.push(format!("{name} mutation {k}: {msg}"));
                }
            }
        }
    }
    eprintln!("{tried} mutated meshes, {accepted} still valid");
    assert!(
        panics.is_empty(),
        "{} panics:\n{}",
        panics.len(),
        panics.join("\n")
    );
}

/// Mutations of a case file's text: lines dropped, doubled and swapped, values replaced by
/// hostile ones, truncations and byte flips.
fn case_mutations(text: &str, rng: &mut Rng, n: usize) -> Vec<String> {
    const VALUES: &[&str] = &[
        "nan",
        "inf",
        "-inf",
        "-1.0",
        "0",
        "0.0",
        "1e308",
        "-1e308",
        "1e-320",
        "9223372036854775807",
        "-9223372036854775808",
        "\"x\"",
        "\"\"",
        "[]",
        "{}",
        "[nan, 1.0]",
        "[1.0]",
        "[1.0, 2.0, 3.0, 4.0]",
        "true",
        "\"solid\"",
        "\"medium\"",
        "\"top\"",
    ];
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let mut l: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
        let k = rng.below(l.len());
        match rng.below(7) {
            0 => {
                l.remove(k);
            }
            1 => {
                let line = l[k].clone();
                l.insert(k, line);
            }
            2 => l.swap(k, rng.below(lines.len())),
            3 | 4 => {
                // a value: the right side of some `key = value`
                let with_value: Vec<usize> =
                    (0..l.len()).filter(|&i| l[i].contains(" = ")).collect();
                if let Some(&i) = with_value.get(rng.below(with_value.len())) {
                    let key = l[i].split(" = ").next().unwrap().to_string();
                    l[i] = format!("{key} = {}", VALUES[rng.below(VALUES.len())]);
                }
            }
            5 => {
                let joined = l.join("\n");
                let cut = rng.below(joined.len());
                let cut = (0..=cut)
                    .rev()
                    .find(|&c| joined.is_char_boundary(c))
                    .unwrap_or(0);
                l = vec![joined[..cut].to_string()];
            }
            _ => {
                let mut bytes = l.join("\n").into_bytes();
                let i = rng.below(bytes.len());
                const BYTES: &[u8] = b" =[]{}\",.#0123456789enaif-";
                bytes[i] = BYTES[rng.below(BYTES.len())];
                l = vec![String::from_utf8_lossy(&bytes).into_owned()];
            }
        }
        out.push(l.join("\n") + "\n");
    }
    out
}

#[test]
fn mutated_case_files_never_panic() {
    use tmc::case::Case;
    let dir = scratch("robust-case");
    // (case, its geometry, a small mesh, a longer time step for the solved mutations: the
    // same keys, fewer steps)
    type Scene = (
        &'static str,
        &'static str,
        &'static [(&'static str, f64)],
        Option<(&'static str, &'static str)>,
    );
    let block = &[("n", 4.0), ("m", 2.0), ("l", 1.0)];
    let scenes: &[Scene] = &[
        ("block", "block.geo", block, None),
        (
            "block-transient",
            "block.geo",
            block,
            Some(("dt = 0.1\n", "dt = 0.5\n")),
        ),
        (
            "slab-convection",
            "slab.geo",
            &[("n", 4.0), ("m", 2.0)],
            None,
        ),
        // friction with its heat under [time]
        (
            "friction-heating",
            "block.geo",
            block,
            Some(("dt = 0.025\n", "dt = 0.1\n")),
        ),
        ("plate-hole", "plate-hole.geo", &[("h", 0.3)], None),
        (
            "block-plate-3d",
            "block-plate-3d.geo",
            &[("n", 2.0), ("nb", 1.0), ("nm", 1.0), ("nq", 1.0)],
            None,
        ),
    ];
    let mut rng = Rng(0x5eed_0002);
    let (mut tried, mut built, mut solved) = (0, 0, 0);
    let mut panics = Vec::new();
    for (name, geo, params, longer_step) in scenes {
        let msh = dir.join(format!("{name}.msh"));
        let opts = MeshOptions {
            set_numbers: params.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
            order: 1,
            ..Default::default()
        };
        let mesh = mesh_geo(&root().join("geo").join(geo), &msh, &opts)
            .unwrap()
            .mesh;
        let mut text =
            std::fs::read_to_string(root().join("cases").join(format!("{name}.toml"))).unwrap();
        if let Some((from, to)) = longer_step {
            assert_eq!(text.matches(from).count(), 1, "{name}: {from}");
            text = text.replace(from, to);
        }
        let path = dir.join(format!("{name}.toml"));
        let through = |text: String| -> Result<(), String> {
            let case = Case::parse(&path, text).map_err(|e| e.to_string())?;
            tmc::model::validate::validate(&case, &mesh).map_err(|e| e.to_string())?;
            let model = tmc::model::build(&case, mesh.clone()).map_err(|e| e.to_string())?;
            tmc::output::probes::build(&case, &model.mesh).map_err(|e| e.to_string())?;
            Ok(())
        };
        assert_eq!(through(text.clone()), Ok(()), "{name} is valid");
        // a valid mutation, solved on the small mesh
        let solve_text = |m: &str| {
            let own: String = m
                .lines()
                .map(|l| {
                    if l.starts_with("mesh =") {
                        format!("mesh = \"{}\"", msh.display())
                    } else {
                        l.to_string()
                    }
                })
                .collect::<Vec<_>>()
                .join("\n");
            let case = dir.join(format!("{name}-solve.toml"));
            std::fs::write(&case, own).unwrap();
            let opts = common::quiet(Some(dir.join(format!("{name}-out"))));
            let _ = tmc::driver::run(&case, &opts);
        };
        for (k, m) in case_mutations(&text, &mut rng, 700).into_iter().enumerate() {
            tried += 1;
            match catch_unwind(AssertUnwindSafe(|| through(m.clone()))) {
                Ok(Ok(())) => {
                    built += 1;
                    // solve every fifth valid one to its end (or to an error)
                    if built % 5 == 0 {
                        solved += 1;
                        let solved_ok = catch_unwind(AssertUnwindSafe(|| solve_text(&m)));
                        if solved_ok.is_err() {
                            panics.push(format!("{name} mutation {k} (solving)"));
                        }
                    }
                }
                Ok(Err(e)) => {
                    assert!(
                        e.contains(&format!("{name}.toml")),
                        "{name} mutation {k}: the file is named: {e}"
                    )
                }
                Err(_) => {
                    std::fs::write(dir.join(format!("panic-{name}-{k}.toml")), &m).ok();
                    panics.push(format!("{name} mutation {k}"));
                }
            }
        }
    }
    eprintln!("{tried} mutated case files, {built} still valid, {solved} of those solved");
    assert!(
        panics.is_empty(),
        "{} panics:\n{}",
        panics.len(),
        panics.join("\n")
    );
}

#[test]
fn degenerate_cells_are_refused_and_coincident_nodes_reported() {
    use tmc::mesh::{Block, CellKind, Mesh, PhysicalGroup, check_geometry};
    let mesh = |coords: Vec<[f64; 3]>, conn: Vec<usize>| Mesh {
        dim: 2,
        coords,
        cells: vec![Block {
            kind: CellKind::Quad4,
            groups: vec![0],
            conn,
        }],
        facets: vec![],
        groups: vec![PhysicalGroup {
            name: "solid".into(),
            dim: 2,
            tag: 1,
        }],
        source: "test.msh".into(),
        warnings: vec![],
    };
    let square = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    assert_eq!(
        check_geometry(&mesh(square.clone(), vec![0, 1, 2, 3])),
        Ok(vec![])
    );
    // a corner moved onto its neighbour: the cell has a zero-area corner
    let mut collapsed = square.clone();
    collapsed[2] = collapsed[1];
    let e = check_geometry(&mesh(collapsed, vec![0, 1, 2, 3])).unwrap_err();
    assert!(
        e.contains("Q1") && e.contains("\"solid\"") && e.contains("degenerate"),
        "{e}"
    );
    // a non-finite coordinate is named with its node
    let mut bad = square.clone();
    bad[3][1] = f64::NAN;
    let e = check_geometry(&mesh(bad, vec![0, 1, 2, 3])).unwrap_err();
    assert!(e.contains("node 3") && e.contains("non-finite"), "{e}");
    // two cells side by side that do not share their edge: a crack
    let mut coords = square.clone();
    coords.extend([
        [1.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ]);
    let w = check_geometry(&mesh(coords, vec![0, 1, 2, 3, 4, 5, 6, 7])).unwrap();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].starts_with("2 nodes share their position"), "{w:?}");
}

#[test]
fn a_huge_count_in_a_mesh_file_is_an_error_not_an_allocation() {
    let (_, bytes) = valid_meshes().swap_remove(0);
    let text = String::from_utf8(bytes).unwrap();
    let (head, rest) = text.split_once("$PhysicalNames\n").unwrap();
    let (_, names) = rest.split_once('\n').unwrap();
    for count in ["100000000000000", "18446744073709551615"] {
        let m = format!("{head}$PhysicalNames\n{count}\n{names}");
        let e = read_msh_bytes(std::path::Path::new("huge.msh"), m.as_bytes()).unwrap_err();
        assert!(
            e.to_string().contains(&format!("announces {count} names")),
            "{e}"
        );
    }
}

#[test]
fn a_checkpoint_knows_its_mesh_s_boundary_groups() {
    // the same nodes and cells with a boundary group on other facets: a restart would go on
    // under other boundary conditions, so the mesh's fingerprint differs
    let dir = scratch("fingerprint-groups");
    std::fs::create_dir_all(&dir).unwrap();
    let opts = MeshOptions {
        set_numbers: vec![("n".into(), 4.0), ("m".into(), 2.0), ("l".into(), 1.0)],
        order: 1,
        ..Default::default()
    };
    let mesh = mesh_geo(&root().join("geo/block.geo"), &dir.join("m.msh"), &opts)
        .unwrap()
        .mesh;
    let fingerprint = tmc::driver::checkpoint::mesh_fingerprint;
    let mut moved = mesh.clone();
    let (top, bottom) = (moved.group("top").unwrap(), moved.group("bottom").unwrap());
    for b in &mut moved.facets {
        for g in &mut b.groups {
            if *g == top {
                *g = bottom;
            } else if *g == bottom {
                *g = top;
            }
        }
    }
    assert_eq!(fingerprint(&mesh), fingerprint(&mesh.clone()));
    assert_ne!(fingerprint(&mesh), fingerprint(&moved));
}
