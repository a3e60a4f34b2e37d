//! Meshing a `.geo` with gmsh through its C API (`gmshc.rs`: Debian's libgmsh 4.8, opened on
//! first use).
//!
//! Every function called here is declared in `gmshc.rs` against `/usr/include/gmshc.h` of gmsh
//! 4.8.4.

use super::child::{Isolation, Served};
use super::gmshc;
use crate::dynamic::LoadError;
use crate::files::TempFile;
use std::ffi::{CStr, CString};
use std::os::raw::{c_char, c_int};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum GmshError {
    #[error("{path}: no such .geo file")]
    NotFound { path: PathBuf },
    #[error("{path} is a folder, not a .geo file")]
    NotAFile { path: PathBuf },
    #[error("{path} is {what}, not a .geo file: {hint}")]
    NotGeo {
        path: PathBuf,
        what: &'static str,
        hint: &'static str,
    },
    #[error("{0}; tmc meshes with gmsh's library: install Debian's libgmsh-dev (make deps)")]
    Library(LoadError),
    #[error("gmsh failed on {path}: {msg}")]
    Failed { path: PathBuf, msg: String },
    #[error(
        "{path}: the geometry defines no physical groups; tag solids, medium and boundaries with Physical Surface/Volume/Curve(\"name\")"
    )]
    NoPhysicalGroups { path: PathBuf },
    #[error("{path}: {msg}")]
    Parameter { path: PathBuf, msg: String },
    #[error(
        "gmsh ended the process while meshing {path} ({status}) and wrote no mesh; a .geo for tmc \
         must not end with `Exit;` (tmc meshes and saves the geometry itself: remove Exit, Mesh \
         and Save commands)"
    )]
    Ended { path: PathBuf, status: String },
    #[error(
        "gmsh crashed while meshing {path} ({signal}); try another meshing algorithm or \
         recombination option in the .geo, or a coarser or finer mesh"
    )]
    Crashed { path: PathBuf, signal: String },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "the mesh gmsh wrote for {path} cannot be read back (a full disk or a file size limit \
         truncates it): {msg}"
    )]
    Unreadable { path: PathBuf, msg: String },
    #[error("the mesh of {path} cannot be used: {msg}")]
    Unusable { path: PathBuf, msg: String },
}

/// Options of `tmc mesh`.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct MeshOptions {
    /// Element order (1 or 2).
    pub order: u8,
    /// Serendipity (incomplete) second-order elements: quad8/hex20 instead of quad9/hex27.
    pub incomplete: bool,
    /// `.geo` parameters set before parsing (`-setnumber NAME VALUE`); each must be a
    /// `DefineConstant` of the file.
    pub set_numbers: Vec<(String, f64)>,
    /// Print gmsh's own log.
    pub verbose: bool,
}

/// Summary of a meshing run, with the mesh as read back from the written file.
#[derive(Clone, Debug)]
pub struct MeshReport {
    pub dim: i32,
    pub output: PathBuf,
    /// gmsh's warnings, then the mesh reader's.
    pub warnings: Vec<String>,
    pub mesh: super::Mesh,
    /// Taken from the cache of meshes made before (`mesh/cache.rs`), not made now.
    pub cached: bool,
}

/// What the meshing process sends back.
#[derive(serde::Serialize, serde::Deserialize)]
enum Outcome {
    Meshed { dim: i32, warnings: Vec<String> },
    NoPhysicalGroups,
    Failed(String),
}

/// A case file or a mesh handed where a `.geo` belongs: gmsh would read it as geometry and
/// fail on its first line with a syntax error that does not say what went wrong.
fn not_geo(geo: &Path) -> Result<(), GmshError> {
    let ext = geo.extension().and_then(|e| e.to_str()).unwrap_or("");
    let (what, hint) = match ext.to_ascii_lowercase().as_str() {
        "toml" => (
            "a case file",
            "`tmc mesh` meshes a .geo; `tmc check` and `tmc solve` mesh a case's geometry themselves",
        ),
        "msh" => (
            "a mesh already",
            "a case can name it as its `mesh` directly; `tmc mesh` makes one from a .geo",
        ),
        _ => return Ok(()),
    };
    Err(GmshError::NotGeo {
        path: geo.to_owned(),
        what,
        hint,
    })
}

/// The `.geo` a file that exists, its parameters its own, and `out` a file whose folder can
/// be made.
fn paths_usable(geo: &Path, out: &Path, opts: &MeshOptions) -> Result<(), GmshError> {
    not_geo(geo)?;
    if geo.is_dir() {
        return Err(GmshError::NotAFile {
            path: geo.to_owned(),
        });
    }
    if !geo.is_file() {
        return Err(GmshError::NotFound {
            path: geo.to_owned(),
        });
    }
    check_parameters(geo, &opts.set_numbers)?;
    if out.is_dir() {
        return Err(GmshError::Write {
            path: out.to_owned(),
            source: std::io::Error::other("it is a folder; name the .msh file to write"),
        });
    }
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| GmshError::Write {
            path: dir.to_owned(),
            source,
        })?;
    }
    Ok(())
}

/// Where the cache of meshes keeps the mesh of `geo` with `opts` (`mesh/cache.rs`), `None`
/// where it keeps none: gmsh's log asked for (`verbose`), among the cache's own reasons.
pub fn kept(geo: &Path, opts: &MeshOptions) -> Option<super::cache::Kept> {
    let params: Vec<(&str, u64)> = (opts.set_numbers.iter())
        .map(|(name, value)| (name.as_str(), value.to_bits()))
        .collect();
    let asked = (opts.order, opts.incomplete, params);
    (!opts.verbose)
        .then(|| super::cache::Kept::of(geo, &asked))
        .flatten()
}

/// Set once this process has opened gmsh's library.
static OPENED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether this process has opened gmsh (its libraries are then in its memory).
pub fn opened() -> bool {
    OPENED.load(std::sync::atomic::Ordering::Relaxed)
}

/// Mesh `geo` and write MSH 4.1 to `out`.
///
/// gmsh runs in a child process, so that a `.geo` that calls `Exit` or a crash inside gmsh
/// ends only that process and is reported. The mesh is written to a temporary name, read back
/// (a truncated file, e.g. on a full disk, fails here), synced and renamed: `out` is either the
/// complete new mesh or untouched. A mesh made before of the same file and options is taken
/// from the cache instead (`mesh/cache.rs`: gmsh is then not opened), and a new one kept there.
pub fn mesh_geo(geo: &Path, out: &Path, opts: &MeshOptions) -> Result<MeshReport, GmshError> {
    paths_usable(geo, out, opts)?;
    let kept = kept(geo, opts);
    if let Some(report) = kept.as_ref().and_then(|k| from_cache(k, out)) {
        return Ok(report);
    }
    // opened here, in tmc, so that a meshing child, forked from it, finds gmsh loaded (and a
    // missing library is told before any child is made)
    gmshc::load().map_err(|e| GmshError::Library(e.clone()))?;
    OPENED.store(true, std::sync::atomic::Ordering::Relaxed);
    // .geo parameters: not gmsh's `-setnumber`, whose values stay in a process-wide table that
    // every later `open` re-applies; instead a wrapper defines them before including the file,
    // and `DefineConstant` keeps an existing definition.
    let wrapper = param_wrapper(geo, &opts.set_numbers).map_err(|source| GmshError::Write {
        path: std::env::temp_dir(),
        source,
    })?;
    let open_path = wrapper.as_ref().map_or(geo, TempFile::path);
    // gmsh picks the format from the extension: the temporary name must end in .msh
    let tmp = TempFile::new(out.with_extension("part.msh"));
    let outcome = meshed_in_child(open_path, tmp.path(), opts).map_err(|e| match e {
        Isolation::Ended(status) => GmshError::Ended {
            path: geo.to_owned(),
            status,
        },
        Isolation::Crashed(signal) => GmshError::Crashed {
            path: geo.to_owned(),
            signal,
        },
        Isolation::Os(source) => GmshError::Write {
            path: tmp.path().to_owned(),
            source,
        },
    })?;
    // messages about the wrapper are about the user's file
    let own = |m: String| match &wrapper {
        Some(w) => m.replace(&w.path().display().to_string(), &geo.display().to_string()),
        None => m,
    };
    let (dim, mut warnings): (i32, Vec<String>) = match outcome {
        Outcome::Meshed { dim, warnings } => (dim, warnings.into_iter().map(own).collect()),
        Outcome::NoPhysicalGroups => {
            return Err(GmshError::NoPhysicalGroups {
                path: geo.to_owned(),
            });
        }
        Outcome::Failed(msg) => {
            return Err(GmshError::Failed {
                path: geo.to_owned(),
                msg: own(msg),
            });
        }
    };
    let mut mesh = super::msh::read_msh(tmp.path()).map_err(|e| match e {
        super::msh::MshError::Invalid { msg, .. } => GmshError::Unusable {
            path: geo.to_owned(),
            // what gmsh warned about (e.g. surfaces in no group) is usually why
            msg: std::iter::once(msg)
                .chain(warnings.iter().cloned())
                .collect::<Vec<_>>()
                .join("; "),
        },
        super::msh::MshError::Parse { msg, .. } => GmshError::Unreadable {
            path: geo.to_owned(),
            msg,
        },
        other => GmshError::Unreadable {
            path: geo.to_owned(),
            msg: other.to_string(),
        },
    })?;
    mesh.source = out.to_owned();
    let entry = super::cache::Entry {
        dim,
        warnings: warnings.clone(),
    };
    warnings.extend(mesh.warnings.iter().cloned());
    let write = |source| GmshError::Write {
        path: out.to_owned(),
        source,
    };
    tmp.sync().map_err(write)?;
    tmp.commit(out).map_err(write)?;
    if let Some(k) = kept {
        k.keep(out, &entry);
    }
    Ok(MeshReport {
        dim,
        output: out.to_owned(),
        warnings,
        mesh,
        cached: false,
    })
}

/// The mesh kept in the cache under `kept`, copied to `out` and read, if there is one that
/// reads; `out` is left as it was otherwise.
fn from_cache(kept: &super::cache::Kept, out: &Path) -> Option<MeshReport> {
    let tmp = TempFile::new(out.with_extension("part.msh"));
    let entry = kept.fetch(tmp.path())?;
    let Ok(mut mesh) = super::msh::read_msh(tmp.path()) else {
        kept.forget();
        return None;
    };
    tmp.sync().ok()?;
    tmp.commit(out).ok()?;
    mesh.source = out.to_owned();
    let mut warnings = entry.warnings;
    warnings.extend(mesh.warnings.iter().cloned());
    Some(MeshReport {
        dim: entry.dim,
        output: out.to_owned(),
        warnings,
        mesh,
        cached: true,
    })
}

/// `ADDR_NO_RANDOMIZE` of <sys/personality.h>: a program started with it lays out its memory
/// the same way at every start.
pub(crate) const ADDR_NO_RANDOMIZE: libc::c_ulong = 0x0040000;

/// Mesh the 3D `geo` in first-order cells with the `gmsh` program, in a process of its own
/// started with the address space's randomisation off, and read the mesh it writes to `out`
/// (both in one folder). For gmsh's HXT, whose tetrahedra depend on where its objects lie in
/// memory: the same faces gave other cells in each run of tmc (each forks its meshing child
/// from its own randomised addresses), the same cells each time in processes started alike
/// (docs/notes/2026-12-05-the-suite-s-time-and-a-mesher-that-is-not-the-same-twice.md).
/// `None` where the program cannot be started; where the kernel keeps the randomisation, the
/// cells are HXT's as before.
pub(crate) fn mesh_geo_apart(geo: &Path, out: &Path) -> Option<Result<super::Mesh, String>> {
    use std::os::unix::process::CommandExt;
    let (dir, name, written) = (geo.parent()?, geo.file_name()?, out.file_name()?);
    let mut gmsh = std::process::Command::new("gmsh");
    // relative names, so that the process starts alike wherever the folder is
    gmsh.current_dir(dir)
        .arg(name)
        .args(["-3", "-nt", "1", "-format", "msh41", "-v", "1", "-o"])
        .arg(written)
        .stdin(std::process::Stdio::null());
    // SAFETY: between fork and exec only async-signal-safe calls, on the child itself: its
    // personality, and its end with the thread that started it (as the meshing child's)
    unsafe {
        gmsh.pre_exec(|| {
            libc::personality(ADDR_NO_RANDOMIZE);
            libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
            Ok(())
        });
    }
    let done = gmsh.output().ok()?;
    let said = |o: &[u8]| String::from_utf8_lossy(o).trim().to_owned();
    if !done.status.success() || !out.is_file() {
        let errors: Vec<String> = [said(&done.stderr), said(&done.stdout)]
            .into_iter()
            .filter(|e| !e.is_empty())
            .collect();
        return Some(Err(format!("meshing failed: {}", errors.join("; "))));
    }
    Some(super::msh::read_msh(out).map_err(|e| e.to_string()))
}

thread_local! {
    /// This thread's meshing child, forked at its first mesh and kept for the next.
    static MESHER: std::cell::RefCell<Option<Served>> = const { std::cell::RefCell::new(None) };
}

/// [`mesh_in_process`] in this thread's meshing child (started if there is none, or the last
/// one ended): a remade 3D medium is meshed every step or two, and a child kept pays the fork
/// of a large process, and the first touch of the memory gmsh allocates, once (measured: a
/// tetrahedral mesh 35 ms in a kept process against 63 ms forked each time). Each request
/// starts gmsh afresh and finalises it, as a child forked for it alone would.
fn meshed_in_child(open_path: &Path, tmp: &Path, opts: &MeshOptions) -> Result<Outcome, Isolation> {
    let request = (open_path.to_owned(), tmp.to_owned(), opts.clone());
    MESHER.with(|m| {
        let mut m = m.borrow_mut();
        let child = match m.as_mut() {
            Some(child) => child,
            None => m.insert(Served::start(serve)?),
        };
        let answer = child.ask(&request);
        if answer.is_err() {
            *m = None;
        }
        answer
    })
}

/// Whether this process (a meshing child) writes to its standard output or to /dev/null.
/// gmsh's 3D mesher (TetGen) prints to standard output whatever `General.Terminal` says: a
/// medium made again in 3D whose first try fails (its outer faces placed where they cross)
/// printed "Found two exactly self-intersecting facets" 129 times into a quiet run.
fn standard_output_shown(shown: bool) {
    static SAVED: std::sync::OnceLock<c_int> = std::sync::OnceLock::new();
    // SAFETY: dup and dup2 on this process's own descriptors; a failure leaves them as they are
    let saved = *SAVED.get_or_init(|| unsafe { libc::dup(1) });
    if saved < 0 {
        return;
    }
    let target = match shown {
        true => saved,
        false => {
            let null = CString::new("/dev/null").expect("no NUL");
            // SAFETY: a valid C string; the descriptor is closed below once duplicated
            unsafe { libc::open(null.as_ptr(), libc::O_WRONLY) }
        }
    };
    if target >= 0 {
        // SAFETY: both descriptors are open
        unsafe { libc::dup2(target, 1) };
        if !shown {
            // SAFETY: `target` was opened above and is not used again
            unsafe { libc::close(target) };
        }
    }
}

/// A meshing child's answer to one request.
fn serve((open_path, tmp, opts): (PathBuf, PathBuf, MeshOptions)) -> Outcome {
    mesh_in_process(&open_path, &tmp, &opts)
}

/// Mesh in this process (the child): open, generate, write `tmp`.
fn mesh_in_process(open_path: &Path, tmp: &Path, opts: &MeshOptions) -> Outcome {
    standard_output_shown(opts.verbose);
    let session = match Session::start() {
        Ok(s) => s,
        Err(e) => return Outcome::Failed(e),
    };
    let run = || -> Result<Outcome, String> {
        session.set_number("General.Terminal", if opts.verbose { 1.0 } else { 0.0 });
        session.call(|e| unsafe { gmshc::gmshLoggerStart(e) })?;
        let cgeo = cstring(&open_path.to_string_lossy());
        let opened = session.call(|e| unsafe { gmshc::gmshOpen(cgeo.as_ptr(), e) });
        let errors = session.errors();
        if opened.is_err() || !errors.is_empty() {
            return Err(if errors.is_empty() {
                "could not open the file".into()
            } else {
                errors.join("; ")
            });
        }
        let dim = session.call(|e| unsafe { gmshc::gmshModelGetDimension(e) })?;
        if dim < 2 {
            return Err(format!(
                "the geometry has dimension {dim}; tmc needs 2D surfaces or 3D volumes"
            ));
        }
        if session.physical_group_count() == 0 {
            return Ok(Outcome::NoPhysicalGroups);
        }
        let untagged = session.untagged_entities(dim);
        session.set_number("Mesh.MshFileVersion", 4.1);
        session.set_number("Mesh.Binary", 0.0);
        session.set_number("Mesh.SaveAll", 0.0);
        if opts.order == 2 {
            session.set_number(
                "Mesh.SecondOrderIncomplete",
                if opts.incomplete { 1.0 } else { 0.0 },
            );
        }
        let generated = session.call(|e| unsafe { gmshc::gmshModelMeshGenerate(dim, e) });
        let errors = session.errors();
        if generated.is_err() || !errors.is_empty() {
            return Err(format!("meshing failed: {}", errors.join("; ")));
        }
        if opts.order == 2 {
            session
                .call(|e| unsafe { gmshc::gmshModelMeshSetOrder(2, e) })
                .map_err(|m| format!("second-order meshing failed: {m}"))?;
        }
        let ctmp = cstring(&tmp.to_string_lossy());
        let written = session.call(|e| unsafe { gmshc::gmshWrite(ctmp.as_ptr(), e) });
        if written.is_err() || !tmp.is_file() {
            return Err(format!("could not write {}", tmp.display()));
        }
        let mut warnings = session.warnings();
        if !untagged.is_empty() {
            let kind = if dim == 2 { "surfaces" } else { "volumes" };
            warnings.push(format!(
                "{kind} {} belong to no physical group: gmsh leaves their cells out of the mesh \
                 (a forgotten Physical {}(\"medium\") leaves the bodies without the medium \
                 between them, and without contact)",
                untagged
                    .iter()
                    .map(|t| t.to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                if dim == 2 { "Surface" } else { "Volume" }
            ));
        }
        Ok(Outcome::Meshed { dim, warnings })
    };
    run().unwrap_or_else(Outcome::Failed)
}

/// Every parameter finite and declared by a `DefineConstant` of the `.geo` (or of a file it
/// includes): a misspelt name would otherwise be ignored and the default mesh used.
fn check_parameters(geo: &Path, params: &[(String, f64)]) -> Result<(), GmshError> {
    let err = |msg: String| GmshError::Parameter {
        path: geo.to_owned(),
        msg,
    };
    for (name, value) in params {
        if !value.is_finite() {
            return Err(err(format!(
                "parameter {name} = {value} is not a finite number"
            )));
        }
        if name.is_empty()
            || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            || name.starts_with(|c: char| c.is_ascii_digit())
        {
            return Err(err(format!("\"{name}\" is not a .geo parameter name")));
        }
    }
    if params.is_empty() {
        return Ok(());
    }
    let mut defined = Vec::new();
    super::geo_text::define_constants(geo, &mut defined, 0).map_err(|e| GmshError::Write {
        path: geo.to_owned(),
        source: e,
    })?;
    for (name, _) in params {
        if !defined.contains(name) {
            return Err(err(if defined.is_empty() {
                format!(
                    "no parameter \"{name}\": the file declares no DefineConstant[...], so it \
                     has no parameters to set"
                )
            } else {
                format!(
                    "no parameter \"{name}\"; its parameters (DefineConstant) are {}",
                    defined.join(", ")
                )
            }));
        }
    }
    Ok(())
}

/// A temporary `.geo` that sets parameters and includes the user's file (removed when
/// dropped); `None` without parameters.
fn param_wrapper(geo: &Path, params: &[(String, f64)]) -> std::io::Result<Option<TempFile>> {
    if params.is_empty() {
        return Ok(None);
    }
    static COUNT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let wrapper = TempFile::new(std::env::temp_dir().join(format!(
        "tmc-{}-{k}-{}",
        std::process::id(),
        geo.file_name()
            .map(|f| f.to_string_lossy())
            .unwrap_or_default()
    )));
    let abs = std::fs::canonicalize(geo)?;
    let mut text = String::new();
    for (name, value) in params {
        text.push_str(&format!("{name} = {value:?};\n"));
    }
    text.push_str(&format!("Include \"{}\";\n", abs.display()));
    std::fs::write(wrapper.path(), text)?;
    Ok(Some(wrapper))
}

fn cstring(s: &str) -> CString {
    CString::new(s.replace('\0', "")).expect("no interior NUL")
}

/// An initialised gmsh session, finalised on drop.
struct Session {
    log: std::cell::RefCell<Vec<String>>,
}

impl Session {
    fn start() -> Result<Session, String> {
        let args = [cstring("tmc")];
        let mut argv: Vec<*mut c_char> = args.iter().map(|a| a.as_ptr() as *mut c_char).collect();
        let mut ierr: c_int = 0;
        unsafe { gmshc::gmshInitialize(argv.len() as c_int, argv.as_mut_ptr(), 0, &mut ierr) };
        if ierr != 0 {
            return Err("gmsh could not be initialised".into());
        }
        Ok(Session {
            log: std::cell::RefCell::new(Vec::new()),
        })
    }

    fn call<T>(&self, f: impl FnOnce(*mut c_int) -> T) -> Result<T, String> {
        let mut ierr: c_int = 0;
        let v = f(&mut ierr);
        if ierr != 0 {
            let errs = self.errors();
            return Err(if errs.is_empty() {
                format!("gmsh error code {ierr}")
            } else {
                errs.join("; ")
            });
        }
        Ok(v)
    }

    fn set_number(&self, name: &str, value: f64) {
        let c = cstring(name);
        let mut ierr: c_int = 0;
        unsafe { gmshc::gmshOptionSetNumber(c.as_ptr(), value, &mut ierr) };
    }

    /// Drain gmsh's logger into our buffer.
    fn drain(&self) {
        let mut log: *mut *mut c_char = std::ptr::null_mut();
        let mut n: usize = 0;
        let mut ierr: c_int = 0;
        unsafe { gmshc::gmshLoggerGet(&mut log, &mut n, &mut ierr) };
        if ierr != 0 || log.is_null() {
            return;
        }
        let mut buf = self.log.borrow_mut();
        buf.clear();
        for i in 0..n {
            unsafe {
                let p = *log.add(i);
                if !p.is_null() {
                    buf.push(CStr::from_ptr(p).to_string_lossy().into_owned());
                    gmshc::gmshFree(p as *mut _);
                }
            }
        }
        unsafe { gmshc::gmshFree(log as *mut _) };
    }

    fn errors(&self) -> Vec<String> {
        self.drain();
        self.log
            .borrow()
            .iter()
            .filter(|l| l.starts_with("Error"))
            .map(|l| {
                l.trim_start_matches("Error")
                    .trim_start_matches(':')
                    .trim()
                    .to_string()
            })
            .collect()
    }

    fn warnings(&self) -> Vec<String> {
        self.drain();
        self.log
            .borrow()
            .iter()
            .filter(|l| l.starts_with("Warning"))
            .cloned()
            .collect()
    }

    /// Tags of the entities of dimension `dim` that belong to no physical group.
    fn untagged_entities(&self, dim: c_int) -> Vec<c_int> {
        let mut dim_tags: *mut c_int = std::ptr::null_mut();
        let mut n: usize = 0;
        let mut ierr: c_int = 0;
        unsafe { gmshc::gmshModelGetEntities(&mut dim_tags, &mut n, dim, &mut ierr) };
        if ierr != 0 || dim_tags.is_null() {
            return Vec::new();
        }
        let pairs: Vec<c_int> = unsafe { std::slice::from_raw_parts(dim_tags, n) }.to_vec();
        unsafe { gmshc::gmshFree(dim_tags as *mut _) };
        let mut out = Vec::new();
        for p in pairs.chunks_exact(2) {
            let mut tags: *mut c_int = std::ptr::null_mut();
            let mut m: usize = 0;
            unsafe {
                gmshc::gmshModelGetPhysicalGroupsForEntity(p[0], p[1], &mut tags, &mut m, &mut ierr)
            };
            if !tags.is_null() {
                unsafe { gmshc::gmshFree(tags as *mut _) };
            }
            if ierr == 0 && m == 0 {
                out.push(p[1]);
            }
        }
        out
    }

    fn physical_group_count(&self) -> usize {
        let mut tags: *mut c_int = std::ptr::null_mut();
        let mut n: usize = 0;
        let mut ierr: c_int = 0;
        unsafe { gmshc::gmshModelGetPhysicalGroups(&mut tags, &mut n, -1, &mut ierr) };
        if !tags.is_null() {
            unsafe { gmshc::gmshFree(tags as *mut _) };
        }
        n / 2
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        let mut ierr: c_int = 0;
        unsafe {
            gmshc::gmshLoggerStop(&mut ierr);
            gmshc::gmshFinalize(&mut ierr);
        }
    }
}
