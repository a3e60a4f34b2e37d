//! Files written under a temporary name and moved into place: a failure (a full disk, a
//! crash of what writes them) never leaves a partial file under the final name.

use std::path::{Path, PathBuf};

/// A folder name of its own under the system's temporary folder for one task of this process,
/// `tmc-<what>-<pid>-<n>`: two runs in one process (a program using the library, the tests)
/// never share one. Not created.
pub fn scratch_dir(what: &str) -> PathBuf {
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    std::env::temp_dir().join(format!("tmc-{what}-{}-{n}", std::process::id()))
}

/// A file under a temporary name, removed when dropped unless it was moved into place.
#[derive(Debug)]
pub struct TempFile(Option<PathBuf>);

impl TempFile {
    /// The temporary name `path` takes.
    pub fn new(path: PathBuf) -> TempFile {
        TempFile(Some(path))
    }

    pub fn path(&self) -> &Path {
        self.0.as_deref().expect("not yet moved")
    }

    /// Force the file's content to the disk (what the writer did not sync itself).
    pub fn sync(&self) -> std::io::Result<()> {
        std::fs::File::open(self.path())?.sync_all()
    }

    /// Move the file to `to` (one rename: atomic on one file system).
    pub fn commit(mut self, to: &Path) -> std::io::Result<()> {
        std::fs::rename(self.path(), to)?;
        self.0 = None;
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if let Some(p) = &self.0 {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// FNV-1a, 64 bits: a fingerprint of bytes fed in pieces (a mesh, a file as it grows), to tell
/// whether two are the same; not a defence against a forger.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Fnv {
        Fnv(0xcbf29ce484222325)
    }
}

impl Fnv {
    pub fn eat(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x100000001b3);
        }
    }

    /// Feed a number by its little-endian bytes.
    pub fn eat_u64(&mut self, v: u64) {
        self.eat(&v.to_le_bytes());
    }
}
