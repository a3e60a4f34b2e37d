//! Meshes of `.geo` files kept for the next run that asks for the same one: a study's
//! variants, a solve run again, a check before a solve. gmsh is then neither opened (its 140
//! libraries take about 0.08 s of each `tmc` that meshes) nor run. A mesh is kept under a key
//! made of everything its cells follow from: the `.geo` (its place and its bytes), the
//! parameters and element order asked, the gmsh library (its place, size and time) and this
//! tmc's version. A `.geo` that reads other files or its surroundings (`Include`, `Merge`,
//! `GetEnv`, …) or writes files (`Save`, `Print`, `Printf`) is meshed every time.
//!
//! The folder is `TMC_MESH_CACHE` (`off`: none), else `$XDG_CACHE_HOME/tmc/meshes`, else
//! `$HOME/.cache/tmc/meshes`. An entry is two files, `KEY.msh` and `KEY.json` (gmsh's dimension
//! and warnings), each written under a name of its own and renamed into place, the `.json`
//! last; one that cannot be read is a miss, and removed. The folder keeps the [`ENTRIES`] last
//! used.

use crate::files::TempFile;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

/// How many meshes the folder keeps (the least recently used go first).
pub const ENTRIES: usize = 200;

/// Meshes larger than this (bytes of `.msh`) are not kept.
pub const LARGEST: u64 = 256 << 20;

/// Words of a `.geo` that make its mesh depend on more than its own text and parameters, or
/// its meshing do more than mesh (`Print` stands for `Printf` too: any text that holds one is
/// meshed every time).
const NOT_KEPT: [&str; 11] = [
    "Include",
    "Merge",
    "ShapeFromFile",
    "GetEnv",
    "GetString",
    "GetValue",
    "SystemCall",
    "OnelabRun",
    "Save",
    "Print",
    "Plugin",
];

/// Where the mesh of one `.geo` with its options is kept: the folder and the key.
#[derive(Clone, Debug, PartialEq)]
pub struct Kept {
    dir: PathBuf,
    key: String,
}

/// What is kept beside a mesh: what gmsh said of it.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Entry {
    pub dim: i32,
    pub warnings: Vec<String>,
}

impl Kept {
    /// Where the mesh of `geo` meshed with `options` (everything else asked of the mesher) is
    /// kept, `None` where there is no folder or it is not to be kept ([`key`]).
    pub fn of(geo: &Path, options: &impl Hash) -> Option<Kept> {
        let dir = folder()?;
        Some(Kept {
            dir,
            key: key(geo, options)?,
        })
    }

    /// Whether a mesh is kept under this key.
    pub fn held(&self) -> bool {
        self.path("json").is_file() && self.path("msh").is_file()
    }

    fn path(&self, ext: &str) -> PathBuf {
        self.dir.join(format!("{}.{ext}", self.key))
    }

    /// The kept mesh copied to `to` (a file of the caller's) and what gmsh said of it, if
    /// there is one; an entry that cannot be read is removed.
    pub fn fetch(&self, to: &Path) -> Option<Entry> {
        let json = std::fs::read(self.path("json")).ok()?;
        let entry = serde_json::from_slice(&json).ok();
        if entry.is_none() || std::fs::copy(self.path("msh"), to).is_err() {
            self.forget();
            return None;
        }
        // last used now, for the folder's pruning
        if let Ok(f) = std::fs::File::options()
            .append(true)
            .open(self.path("json"))
        {
            let _ = f.set_modified(std::time::SystemTime::now());
        }
        entry
    }

    /// The entry removed (a kept mesh the reader refused).
    pub fn forget(&self) {
        let _ = std::fs::remove_file(self.path("json"));
        let _ = std::fs::remove_file(self.path("msh"));
    }

    /// Keep the mesh `msh` with `entry`; nothing is said where the folder cannot take it.
    pub fn keep(&self, msh: &Path, entry: &Entry) {
        if std::fs::metadata(msh).map_or(true, |m| m.len() > LARGEST) {
            return;
        }
        let _ = self.try_keep(msh, entry);
        prune(&self.dir);
    }

    fn try_keep(&self, msh: &Path, entry: &Entry) -> std::io::Result<()> {
        use std::io::Write;
        std::fs::create_dir_all(&self.dir)?;
        // under names of this call's own (another process or thread may keep the same mesh),
        // removed if the copy fails or the process halts before they are in place
        let own = |ext: &str| {
            let unique = crate::files::scratch_dir("kept");
            let name = unique.file_name().unwrap_or_default().to_string_lossy();
            (self.dir).join(format!(".{}.{name}.{ext}", self.key))
        };
        let (m, mut f) = TempFile::create(own("msh"))?;
        std::io::copy(&mut std::fs::File::open(msh)?, &mut f)?;
        m.commit(&self.path("msh"))?;
        let (j, mut f) = TempFile::create(own("json"))?;
        f.write_all(&serde_json::to_vec(entry).map_err(std::io::Error::other)?)?;
        j.commit(&self.path("json"))
    }
}

/// The cache's folder, if any.
fn folder() -> Option<PathBuf> {
    let non_empty = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty());
    if let Some(dir) = non_empty("TMC_MESH_CACHE") {
        return (dir != "off").then(|| PathBuf::from(dir));
    }
    let base = (non_empty("XDG_CACHE_HOME").map(PathBuf::from))
        .or_else(|| non_empty("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("tmc").join("meshes"))
}

/// The gmsh library the loader would open, by where it is, its size and its time: a gmsh
/// installed anew makes every key new.
fn gmsh_library() -> Option<(PathBuf, u64, std::time::SystemTime)> {
    let arch = format!("/usr/lib/{}-linux-gnu", std::env::consts::ARCH);
    let dirs = std::env::var("LD_LIBRARY_PATH").unwrap_or_default();
    let dirs = (dirs.split(':').filter(|d| !d.is_empty()))
        .map(PathBuf::from)
        .chain(["/usr/local/lib", &arch, "/usr/lib", "/lib"].map(PathBuf::from));
    for dir in dirs {
        for name in ["libgmsh.so", "libgmsh.so.4.8"] {
            let path = dir.join(name);
            if let Ok(m) = std::fs::metadata(&path) {
                let real = std::fs::canonicalize(&path).unwrap_or(path);
                return Some((real, m.len(), m.modified().ok()?));
            }
        }
    }
    None
}

/// Only the [`ENTRIES`] last used entries of `dir` kept.
fn prune(dir: &Path) {
    let Ok(read) = std::fs::read_dir(dir) else {
        return;
    };
    let mut used: Vec<(std::time::SystemTime, PathBuf)> = read
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .filter_map(|p| Some((std::fs::metadata(&p).ok()?.modified().ok()?, p)))
        .collect();
    if used.len() <= ENTRIES {
        return;
    }
    used.sort();
    for (_, json) in &used[..used.len() - ENTRIES] {
        let _ = std::fs::remove_file(json);
        let _ = std::fs::remove_file(json.with_extension("msh"));
    }
}

/// The key of the mesh of `geo` with `options` (32 hexadecimal digits), `None` where it is
/// not to be kept: a `.geo` that reads or writes other files, or a gmsh library not found to
/// tell its version by.
fn key(geo: &Path, options: &impl Hash) -> Option<String> {
    let text = std::fs::read(geo).ok()?;
    let words = String::from_utf8_lossy(&text);
    if NOT_KEPT.iter().any(|w| words.contains(w)) {
        return None;
    }
    let mut all = Bytes::default();
    "tmc mesh cache 1".hash(&mut all);
    env!("CARGO_PKG_VERSION").hash(&mut all);
    gmsh_library()?.hash(&mut all);
    std::fs::canonicalize(geo).ok()?.hash(&mut all);
    text.hash(&mut all);
    options.hash(&mut all);
    // 128 bits: std's hasher over the bytes twice, seeded apart
    let half = |seed: u8| {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        (seed, &all.0).hash(&mut h);
        h.finish()
    };
    Some(format!("{:016x}{:016x}", half(0), half(1)))
}

/// The bytes a value hashes as, collected.
#[derive(Default)]
struct Bytes(Vec<u8>);

impl Hasher for Bytes {
    fn write(&mut self, bytes: &[u8]) {
        self.0.extend_from_slice(bytes);
    }
    fn finish(&self) -> u64 {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An element order and a parameter `n`'s value, as the mesher is asked.
    fn opts(n: f64) -> (u8, u64) {
        (1, n.to_bits())
    }

    #[test]
    fn a_key_follows_the_file_its_parameters_and_its_order() {
        let dir = crate::files::scratch_dir("cache-key");
        std::fs::create_dir_all(&dir).unwrap();
        let geo = dir.join("a.geo");
        std::fs::write(&geo, "DefineConstant[ n = 2 ];\nPoint(1) = {0, 0, 0};\n").unwrap();
        let key = |opts: &(u8, u64)| key(&geo, opts);
        let a = key(&opts(2.0));
        assert!(a.is_some(), "a .geo of its own alone, with gmsh installed");
        assert_eq!(a, key(&opts(2.0)));
        assert_ne!(a, key(&opts(3.0)));
        assert_ne!(a, key(&(2, 2f64.to_bits())));
        std::fs::write(&geo, "DefineConstant[ n = 2 ];\nPoint(1) = {0, 0, 1};\n").unwrap();
        assert_ne!(a, key(&opts(2.0)), "another text");
        std::fs::write(&geo, "Include \"b.geo\";\n").unwrap();
        assert_eq!(key(&opts(2.0)), None, "a file that reads another");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_entry_is_fetched_as_kept_and_a_spoilt_one_is_forgotten() {
        let dir = crate::files::scratch_dir("cache-entry");
        let kept = Kept {
            dir: dir.join("cache"),
            key: "k".into(),
        };
        std::fs::create_dir_all(&dir).unwrap();
        let (msh, to) = (dir.join("m.msh"), dir.join("to.msh"));
        assert!(kept.fetch(&to).is_none(), "nothing kept yet");
        std::fs::write(&msh, "$MeshFormat\n").unwrap();
        let said = Entry {
            dim: 2,
            warnings: vec!["a warning".into()],
        };
        kept.keep(&msh, &said);
        let entry = kept.fetch(&to).expect("kept");
        assert_eq!((entry.dim, entry.warnings), (2, said.warnings.clone()));
        assert_eq!(std::fs::read(&to).unwrap(), b"$MeshFormat\n");
        // no file of its own left behind
        let names: Vec<String> = std::fs::read_dir(dir.join("cache"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
        std::fs::write(kept.path("json"), "not json").unwrap();
        assert!(kept.fetch(&to).is_none());
        assert!(!kept.path("msh").exists(), "a spoilt entry is removed");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_folder_keeps_the_entries_last_used() {
        let dir = crate::files::scratch_dir("cache-prune");
        std::fs::create_dir_all(&dir).unwrap();
        let t0 = std::time::SystemTime::now() - std::time::Duration::from_secs(10_000);
        for k in 0..ENTRIES + 3 {
            for ext in ["json", "msh"] {
                let p = dir.join(format!("{k}.{ext}"));
                std::fs::write(&p, "{}").unwrap();
                let f = std::fs::File::options().append(true).open(&p).unwrap();
                f.set_modified(t0 + std::time::Duration::from_secs(k as u64))
                    .unwrap();
            }
        }
        prune(&dir);
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2 * ENTRIES);
        for k in 0..3 {
            assert!(!dir.join(format!("{k}.json")).exists(), "the oldest go");
        }
        assert!(dir.join(format!("{}.msh", ENTRIES + 2)).exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
