//! Shared libraries opened when a run first needs them, not when tmc starts.
//!
//! gmsh (with OpenCASCADE) and PETSc (with MUMPS, hypre, BLAS …) bring about 180 shared
//! libraries. Linked into the executable, the dynamic loader resolves their 100 000 symbols
//! before `main` on every start: 0.21 s for `tmc --version`, against 3 ms without them. Most
//! starts need neither (`tmc check`, `tmc solve` on one process with no remake, `tmc plot`), so
//! each library is opened on first use and kept open for the life of the process.
//! [`dynamic_api!`](crate::dynamic_api) declares a library's functions once and gives each a
//! wrapper with its C name and signature, so callers read as with `extern "C"` declarations.

use std::ffi::{CStr, CString, c_void};
use std::ptr::NonNull;

/// A shared library opened with `dlopen` and never closed.
pub struct Library {
    handle: NonNull<c_void>,
    /// The name it was opened by, for messages.
    pub name: String,
}

// SAFETY: a dlopen handle may be used from any thread; it is never closed.
unsafe impl Send for Library {}
unsafe impl Sync for Library {}

/// A library or one of its symbols that could not be loaded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("cannot load {what} ({name}): {reason}")]
pub struct LoadError {
    /// What the library is, in a user's words ("gmsh", "PETSc").
    pub what: &'static str,
    pub name: String,
    pub reason: String,
}

/// The last `dlerror` text, or `fallback`.
fn dl_error(fallback: &str) -> String {
    // SAFETY: dlerror returns NULL or a NUL-terminated string valid until the next dl call
    let e = unsafe { libc::dlerror() };
    if e.is_null() {
        fallback.to_owned()
    } else {
        unsafe { CStr::from_ptr(e) }.to_string_lossy().into_owned()
    }
}

impl Library {
    /// Open the first of `names` that loads (each a file name the loader searches for, or a
    /// path), its symbols visible to the libraries opened after it, as linking would make them.
    pub fn open(what: &'static str, names: &[&str]) -> Result<Library, LoadError> {
        let mut reasons = Vec::new();
        for name in names {
            let c = CString::new(*name).expect("library names hold no NUL");
            // SAFETY: a valid C string; the library's initialisers run here, once
            let handle = unsafe { libc::dlopen(c.as_ptr(), libc::RTLD_NOW | libc::RTLD_GLOBAL) };
            match NonNull::new(handle) {
                Some(handle) => {
                    return Ok(Library {
                        handle,
                        name: (*name).to_owned(),
                    });
                }
                None => reasons.push(dl_error("dlopen failed")),
            }
        }
        Err(LoadError {
            what,
            name: names.join(", "),
            reason: reasons.join("; "),
        })
    }

    /// The address of the symbol `name`.
    pub fn symbol(&self, what: &'static str, name: &str) -> Result<NonNull<c_void>, LoadError> {
        let c = CString::new(name).expect("symbol names hold no NUL");
        // SAFETY: a handle from dlopen, never closed; a valid C string
        let address = unsafe { libc::dlsym(self.handle.as_ptr(), c.as_ptr()) };
        NonNull::new(address).ok_or_else(|| LoadError {
            what,
            name: self.name.clone(),
            reason: format!("it has no symbol {name}: {}", dl_error("not found")),
        })
    }
}

/// Declare the C functions of a library opened on first use: a table of their addresses,
/// `load()` that opens the library and fills the table once (the error is kept and returned
/// again), and for each function an `unsafe fn` of the same name and signature that calls it
/// through the table. Call `load()` where a failure can be reported; a wrapper called before
/// a successful `load()` panics.
#[macro_export]
macro_rules! dynamic_api {
    (
        $what:literal from [$($path:expr),+ $(,)?];
        $( $(#[$meta:meta])* fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)?; )*
    ) => {
        /// The library's functions, found once; and the library, for other symbols.
        #[allow(non_snake_case)]
        pub struct Api {
            /// For symbols other than functions (PETSc's tables of names).
            #[allow(dead_code)]
            pub library: $crate::dynamic::Library,
            $( $name: unsafe extern "C" fn($($ty),*) $(-> $ret)?, )*
        }

        /// Open the library and find its functions, once per process.
        pub fn load() -> Result<&'static Api, &'static $crate::dynamic::LoadError> {
            static API: std::sync::OnceLock<Result<Api, $crate::dynamic::LoadError>> =
                std::sync::OnceLock::new();
            API.get_or_init(|| {
                let library = $crate::dynamic::Library::open($what, &[$($path),+])?;
                Ok(Api {
                    $( $name: {
                        let address = library.symbol($what, stringify!($name))?;
                        // SAFETY: the symbol is the function declared here, with the C
                        // signature of the library's header
                        unsafe {
                            std::mem::transmute::<
                                *mut std::ffi::c_void,
                                unsafe extern "C" fn($($ty),*) $(-> $ret)?,
                            >(address.as_ptr())
                        }
                    }, )*
                    library,
                })
            })
            .as_ref()
        }

        $(
            $(#[$meta])*
            #[allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]
            pub unsafe fn $name($($arg: $ty),*) $(-> $ret)? {
                let api = load().expect(concat!($what, " is loaded before its first call"));
                // SAFETY: the caller keeps the C function's contract
                unsafe { (api.$name)($($arg),*) }
            }
        )*
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    mod libm {
        crate::dynamic_api! {
            "the C maths library" from ["libm.so.6"];
            fn cos(x: f64) -> f64;
        }
    }
    #[allow(dead_code)]
    mod missing {
        crate::dynamic_api! {
            "a library no machine has" from ["libtmc-no-such-library.so", "libneither.so"];
            fn nothing();
        }
    }

    #[test]
    fn a_function_is_called_through_the_library_opened_on_first_use() {
        assert!(libm::load().is_ok());
        assert_eq!(unsafe { libm::cos(0.0) }, 1.0);
        assert_eq!(unsafe { libm::cos(std::f64::consts::PI) }, -1.0);
    }

    #[test]
    fn a_library_that_is_not_there_is_an_error_naming_it_and_each_name_tried() {
        let e = missing::load().err().expect("no such library");
        assert_eq!(e.what, "a library no machine has");
        assert_eq!(e.name, "libtmc-no-such-library.so, libneither.so");
        assert!(e.reason.contains("libtmc-no-such-library.so"), "{e}");
        assert!(e.reason.contains("libneither.so"), "{e}");
        // the error is kept: the second call answers the same
        assert_eq!(missing::load().err(), Some(e));
    }

    #[test]
    fn a_missing_symbol_is_an_error_naming_it() {
        let libm = Library::open("the C maths library", &["libm.so.6"]).unwrap();
        assert!(libm.symbol("libm", "cos").is_ok());
        let e = libm.symbol("libm", "tmc_no_such_function").unwrap_err();
        assert!(e.reason.contains("tmc_no_such_function"), "{e}");
    }
}
