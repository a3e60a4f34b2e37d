//! Files written under a temporary name and moved into place: a failure (a full disk, a
//! crash of what writes them) never leaves a partial file under the final name.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

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

/// What this process is writing: the temporary files it has created and not yet moved into
/// place or removed, and, while a step's records are made ([`placing`]), the files they have
/// put in place under names that were free. Created, moved and removed under this lock, so
/// that [`halt`] can stop every later write and clear what is half done.
struct Writes {
    parts: Vec<PathBuf>,
    placed: Option<Vec<PathBuf>>,
    /// The files other processes write for the same records (the other ranks' parts of a
    /// step), taken back with this process's own.
    elsewhere: Vec<PathBuf>,
}

static WRITES: Mutex<Writes> = Mutex::new(Writes {
    parts: Vec::new(),
    placed: None,
    elsewhere: Vec::new(),
});

/// How long [`halt`] leaves the other processes that write for the same records to halt too
/// (they are stopped by the same signal at the same moment) before it takes their files back.
const OTHERS_HALT: std::time::Duration = std::time::Duration::from_millis(200);

fn writes() -> MutexGuard<'static, Writes> {
    WRITES.lock().unwrap_or_else(|e| e.into_inner())
}

impl TempFile {
    /// The temporary name `path` takes (the caller creates the file).
    pub fn new(path: PathBuf) -> TempFile {
        TempFile(Some(path))
    }

    /// Create the file `path`, a temporary name, known to [`halt`] until it is moved into
    /// place or dropped.
    pub fn create(path: PathBuf) -> std::io::Result<(TempFile, File)> {
        let mut w = writes();
        let file = File::create(&path)?;
        w.parts.push(path.clone());
        Ok((TempFile(Some(path)), file))
    }

    pub fn path(&self) -> &Path {
        self.0.as_deref().expect("not yet moved")
    }

    /// Force the file's content to the disk (what the writer did not sync itself).
    pub fn sync(&self) -> std::io::Result<()> {
        File::open(self.path())?.sync_all()
    }

    /// Move the file to `to` (one rename: atomic on one file system).
    pub fn commit(mut self, to: &Path) -> std::io::Result<()> {
        let mut w = writes();
        let new = !to.exists();
        if let Err(e) = std::fs::rename(self.path(), to) {
            drop(w);
            return Err(e);
        }
        let p = self.0.take().expect("not yet moved");
        w.parts.retain(|q| *q != p);
        if let (true, Some(placed)) = (new, &mut w.placed) {
            placed.push(to.to_owned());
        }
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if let Some(p) = self.0.take() {
            let mut w = writes();
            let _ = std::fs::remove_file(&p);
            w.parts.retain(|q| *q != p);
        }
    }
}

/// Write `bytes` to `path` atomically: under a temporary name `path.part`, synced, then
/// renamed; a failure leaves no file under `path` and no temporary one.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    stage(path, bytes)?.commit()
}

/// A file written in full under its temporary name and synced, waiting to be moved into
/// place: what replaces a file at the moment chosen, however long the writing took.
#[derive(Debug)]
pub struct Staged {
    tmp: TempFile,
    to: PathBuf,
}

/// `bytes` written and synced under `path.part`, to be moved to `path` by [`Staged::commit`]
/// (removed if dropped first).
pub fn stage(path: &Path, bytes: &[u8]) -> std::io::Result<Staged> {
    let (tmp, mut f) = TempFile::create(part_name(path))?;
    f.write_all(bytes).and_then(|_| f.sync_data())?;
    Ok(Staged {
        tmp,
        to: path.to_owned(),
    })
}

impl Staged {
    /// Where it goes.
    pub fn path(&self) -> &Path {
        &self.to
    }

    /// Move it into place.
    pub fn commit(self) -> std::io::Result<()> {
        self.tmp.commit(&self.to)
    }
}

/// `path` with `.part` after its name.
fn part_name(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".part");
    path.with_file_name(name)
}

/// Note, until [`placed`], the files put in place under names that were free: what a step's
/// records add, which [`halt`] removes should the process be stopped before they are done.
pub fn placing() {
    let mut w = writes();
    w.placed = Some(Vec::new());
    w.elsewhere.clear();
}

/// While [`placing`]: `paths` are written by other processes for the same records (the
/// other ranks' parts of a step), to be taken back with this process's own.
pub fn placing_elsewhere(paths: impl IntoIterator<Item = PathBuf>) {
    let mut w = writes();
    if w.placed.is_some() {
        w.elsewhere.extend(paths);
    }
}

/// A step's records are done: its files stay, whatever happens next.
pub fn placed() {
    let mut w = writes();
    w.placed = None;
    w.elsewhere.clear();
}

/// This process writes nothing more: every later temporary file or move waits for ever (the
/// process is about to end) and the temporary files under way are removed. With `take_back`,
/// the files a step's records had put in place go too (see [`placing`]), and, once the other
/// processes have had [`OTHERS_HALT`] to stop writing, those they wrote for the same records:
/// what is left is what the last finished records left. The returned [`Halted`] still
/// writes, for the one who halted.
pub fn halt(take_back: bool) -> Halted {
    let mut w = writes();
    let placed = w.placed.take().unwrap_or_default();
    for p in w.parts.drain(..) {
        let _ = std::fs::remove_file(p);
    }
    if take_back {
        for p in placed {
            let _ = std::fs::remove_file(p);
        }
        if !w.elsewhere.is_empty() {
            std::thread::sleep(OTHERS_HALT);
            for p in w.elsewhere.drain(..) {
                let _ = std::fs::remove_file(p);
            }
        }
    }
    // never unlocked: nothing of this process writes after this
    std::mem::forget(w);
    Halted(())
}

/// The right to write after [`halt`].
pub struct Halted(());

impl Halted {
    /// As [`write_atomic`], for the one who halted.
    pub fn write_atomic(&self, path: &Path, bytes: &[u8]) -> std::io::Result<()> {
        let tmp = part_name(path);
        let written = File::create(&tmp)
            .and_then(|mut f| f.write_all(bytes).and_then(|_| f.sync_data()))
            .and_then(|_| std::fs::rename(&tmp, path));
        if written.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        written
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
