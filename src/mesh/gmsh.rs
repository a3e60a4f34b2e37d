//! Meshing a `.geo` with gmsh through its C API (gmsh-sys, linked to Debian's libgmsh 4.8).
//!
//! Every function called here was checked against `/usr/include/gmshc.h` of gmsh 4.8.4: the
//! crate binds the 4.4.1 API, whose signatures for these calls are unchanged.

use std::ffi::{CStr, CString};
use std::os::raw::{c_char, c_int};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// gmsh keeps global state: one model at a time per process.
static GMSH: Mutex<()> = Mutex::new(());

#[derive(Debug, thiserror::Error)]
pub enum GmshError {
    #[error("{path}: no such .geo file")]
    NotFound { path: PathBuf },
    #[error("gmsh failed on {path}: {msg}")]
    Failed { path: PathBuf, msg: String },
    #[error(
        "{path}: the geometry defines no physical groups; tag solids, medium and boundaries with Physical Surface/Volume/Curve(\"name\")"
    )]
    NoPhysicalGroups { path: PathBuf },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Options of `tmc mesh`.
#[derive(Clone, Debug, Default)]
pub struct MeshOptions {
    /// Element order (1 or 2).
    pub order: u8,
    /// Serendipity (incomplete) second-order elements: quad8/hex20 instead of quad9/hex27.
    pub incomplete: bool,
    /// `.geo` parameters set before parsing (`-setnumber NAME VALUE`).
    pub set_numbers: Vec<(String, f64)>,
    /// Print gmsh's own log.
    pub verbose: bool,
}

/// Summary of a meshing run.
#[derive(Clone, Debug)]
pub struct MeshReport {
    pub dim: i32,
    pub output: PathBuf,
    pub warnings: Vec<String>,
}

/// Mesh `geo` and write MSH 4.1 to `out` (written to a temporary file and renamed, so a failed
/// run leaves no half-written mesh).
pub fn mesh_geo(geo: &Path, out: &Path, opts: &MeshOptions) -> Result<MeshReport, GmshError> {
    if !geo.is_file() {
        return Err(GmshError::NotFound {
            path: geo.to_owned(),
        });
    }
    let _guard = GMSH.lock().unwrap_or_else(|e| e.into_inner());
    // .geo parameters: not gmsh's `-setnumber`, whose values stay in a process-wide table that
    // every later `open` re-applies (so a parameter set for one mesh would leak into the
    // next); instead a wrapper defines them before including the file, and `DefineConstant`
    // keeps an existing definition.
    let wrapper = ParamWrapper::new(geo, &opts.set_numbers).map_err(|source| GmshError::Write {
        path: std::env::temp_dir(),
        source,
    })?;
    let open_path = wrapper.path.as_deref().unwrap_or(geo);
    let session = Session::start()?;
    let fail = |msg: String| GmshError::Failed {
        path: geo.to_owned(),
        msg,
    };
    let run = || -> Result<MeshReport, GmshError> {
        session.set_number("General.Terminal", if opts.verbose { 1.0 } else { 0.0 });
        session
            .call(|e| unsafe { gmsh_sys::gmshLoggerStart(e) })
            .map_err(&fail)?;
        let cgeo = cstring(&open_path.to_string_lossy());
        let opened = session.call(|e| unsafe { gmsh_sys::gmshOpen(cgeo.as_ptr(), e) });
        let errors = session.errors();
        if opened.is_err() || !errors.is_empty() {
            return Err(fail(if errors.is_empty() {
                "could not open the file".into()
            } else {
                errors.join("; ")
            }));
        }
        let dim = session
            .call(|e| unsafe { gmsh_sys::gmshModelGetDimension(e) })
            .map_err(&fail)?;
        if dim < 2 {
            return Err(fail(format!(
                "the geometry has dimension {dim}; tmc needs 2D surfaces or 3D volumes"
            )));
        }
        if session.physical_group_count()? == 0 {
            return Err(GmshError::NoPhysicalGroups {
                path: geo.to_owned(),
            });
        }
        session.set_number("Mesh.MshFileVersion", 4.1);
        session.set_number("Mesh.Binary", 0.0);
        session.set_number("Mesh.SaveAll", 0.0);
        if opts.order == 2 {
            session.set_number(
                "Mesh.SecondOrderIncomplete",
                if opts.incomplete { 1.0 } else { 0.0 },
            );
        }
        let generated = session.call(|e| unsafe { gmsh_sys::gmshModelMeshGenerate(dim, e) });
        let errors = session.errors();
        if generated.is_err() || !errors.is_empty() {
            return Err(fail(format!("meshing failed: {}", errors.join("; "))));
        }
        if opts.order == 2 {
            session
                .call(|e| unsafe { gmsh_sys::gmshModelMeshSetOrder(2, e) })
                .map_err(|m| fail(format!("second-order meshing failed: {m}")))?;
        }
        // gmsh picks the format from the extension: the temporary name must end in .msh
        let tmp = out.with_extension("part.msh");
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| GmshError::Write {
                path: dir.to_owned(),
                source,
            })?;
        }
        let ctmp = cstring(&tmp.to_string_lossy());
        let written = session.call(|e| unsafe { gmsh_sys::gmshWrite(ctmp.as_ptr(), e) });
        if written.is_err() || !tmp.is_file() {
            let _ = std::fs::remove_file(&tmp);
            return Err(fail(format!("could not write {}", out.display())));
        }
        std::fs::rename(&tmp, out).map_err(|source| GmshError::Write {
            path: out.to_owned(),
            source,
        })?;
        Ok(MeshReport {
            dim,
            output: out.to_owned(),
            warnings: session.warnings(),
        })
    };
    run()
}

/// A temporary `.geo` that sets parameters and includes the user's file; removed on drop.
struct ParamWrapper {
    path: Option<PathBuf>,
}

impl ParamWrapper {
    fn new(geo: &Path, params: &[(String, f64)]) -> std::io::Result<ParamWrapper> {
        if params.is_empty() {
            return Ok(ParamWrapper { path: None });
        }
        static COUNT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let k = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let path = std::env::temp_dir().join(format!(
            "tmc-{}-{k}-{}",
            std::process::id(),
            geo.file_name()
                .map(|f| f.to_string_lossy())
                .unwrap_or_default()
        ));
        let abs = std::fs::canonicalize(geo)?;
        let mut text = String::new();
        for (name, value) in params {
            text.push_str(&format!("{name} = {value:?};\n"));
        }
        text.push_str(&format!("Include \"{}\";\n", abs.display()));
        std::fs::write(&path, text)?;
        Ok(ParamWrapper { path: Some(path) })
    }
}

impl Drop for ParamWrapper {
    fn drop(&mut self) {
        if let Some(p) = &self.path {
            let _ = std::fs::remove_file(p);
        }
    }
}

fn cstring(s: &str) -> CString {
    CString::new(s.replace('\0', "")).expect("no interior NUL")
}

/// An initialised gmsh session, finalised on drop.
struct Session {
    log: std::cell::RefCell<Vec<String>>,
}

impl Session {
    fn start() -> Result<Session, GmshError> {
        let args = [cstring("tmc")];
        let mut argv: Vec<*mut c_char> = args.iter().map(|a| a.as_ptr() as *mut c_char).collect();
        let mut ierr: c_int = 0;
        unsafe { gmsh_sys::gmshInitialize(argv.len() as c_int, argv.as_mut_ptr(), 0, &mut ierr) };
        if ierr != 0 {
            return Err(GmshError::Failed {
                path: PathBuf::new(),
                msg: "gmsh could not be initialised".into(),
            });
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
        unsafe { gmsh_sys::gmshOptionSetNumber(c.as_ptr(), value, &mut ierr) };
    }

    /// Drain gmsh's logger into our buffer.
    fn drain(&self) {
        let mut log: *mut *mut c_char = std::ptr::null_mut();
        let mut n: usize = 0;
        let mut ierr: c_int = 0;
        unsafe { gmsh_sys::gmshLoggerGet(&mut log, &mut n, &mut ierr) };
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
                    gmsh_sys::gmshFree(p as *mut _);
                }
            }
        }
        unsafe { gmsh_sys::gmshFree(log as *mut _) };
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

    fn physical_group_count(&self) -> Result<usize, GmshError> {
        let mut tags: *mut c_int = std::ptr::null_mut();
        let mut n: usize = 0;
        let mut ierr: c_int = 0;
        unsafe { gmsh_sys::gmshModelGetPhysicalGroups(&mut tags, &mut n, -1, &mut ierr) };
        if !tags.is_null() {
            unsafe { gmsh_sys::gmshFree(tags as *mut _) };
        }
        Ok(n / 2)
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        let mut ierr: c_int = 0;
        unsafe {
            gmsh_sys::gmshLoggerStop(&mut ierr);
            gmsh_sys::gmshFinalize(&mut ierr);
        }
    }
}
