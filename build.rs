//! With the `petsc` feature: find PETSc's library (by pkg-config), for tmc to open when a run
//! starts it, and check that its build matches the declarations in `src/parallel/ffi.rs`: real
//! double-precision scalars and 32-bit `PetscInt` (Debian's `petsc-dev`), or 64-bit indices,
//! which set the `petsc_int64` cfg.
use std::process::Command;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(petsc_int64)");
    println!("cargo::rerun-if-changed=build.rs");
    if std::env::var_os("CARGO_FEATURE_PETSC").is_none() {
        return;
    }
    println!("cargo::rerun-if-env-changed=PKG_CONFIG_PATH");
    let pc = |arg: &str| -> String {
        let out = Command::new("pkg-config")
            .args([arg, "petsc"])
            .output()
            .unwrap_or_else(|e| panic!("the petsc feature needs pkg-config: {e}"));
        if !out.status.success() {
            panic!(
                "the petsc feature needs PETSc: `pkg-config {arg} petsc` failed ({}); \
                 install Debian's petsc-dev and libopenmpi-dev (make deps)",
                String::from_utf8_lossy(&out.stderr).trim()
            );
        }
        String::from_utf8(out.stdout).expect("pkg-config prints UTF-8")
    };
    let include = pc("--variable=includedir");
    let conf_path = format!("{}/petscconf.h", include.trim());
    let conf = std::fs::read_to_string(&conf_path)
        .unwrap_or_else(|e| panic!("cannot read {conf_path}: {e}"));
    let defined = |name: &str| {
        conf.lines()
            .any(|l| l.split_whitespace().take(2).eq(["#define", name]))
    };
    assert!(
        defined("PETSC_USE_REAL_DOUBLE") && !defined("PETSC_USE_COMPLEX"),
        "{conf_path}: tmc needs PETSc built with real double-precision scalars"
    );
    if defined("PETSC_USE_64BIT_INDICES") {
        println!("cargo::rustc-cfg=petsc_int64");
    }
    // PETSc is opened when a run first starts it (src/dynamic.rs), not linked: its hundred
    // libraries would cost every start of tmc their symbol lookups
    let mut dirs = Vec::new();
    let mut library = None;
    for flag in pc("--libs").split_whitespace() {
        if let Some(dir) = flag.strip_prefix("-L") {
            dirs.push(std::path::PathBuf::from(dir));
        } else if let Some(lib) = flag.strip_prefix("-l")
            && lib.starts_with("petsc")
            && library.is_none()
        {
            library = Some(format!("lib{lib}.so"));
        }
    }
    let library = library.expect("`pkg-config --libs petsc` names PETSc's library (-lpetsc…)");
    let path = dirs
        .iter()
        .map(|d| d.join(&library))
        .find(|p| p.exists())
        .unwrap_or_else(|| panic!("{library} is in none of pkg-config's folders {dirs:?}"));
    println!("cargo::rustc-env=TMC_PETSC_LIBRARY={}", path.display());
}
