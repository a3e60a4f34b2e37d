//! Files written under a temporary name and moved into place: a failure (a full disk, a
//! crash of what writes them) never leaves a partial file under the final name.

use std::path::{Path, PathBuf};

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
