//! Hostile inputs: every mutation of a valid mesh or case file must end in an `Err` with a
//! message or in a valid result, never in a panic.

mod common;

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
                    std::fs::write(format!("/tmp/fz/{}-{k}.msh", name.replace(' ', "_")), &m).ok();
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
