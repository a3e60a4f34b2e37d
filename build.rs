//! With the `petsc` feature: link PETSc (found by pkg-config) and check that its build matches
//! the declarations in `src/parallel/ffi.rs`: real double-precision scalars and 32-bit
//! `PetscInt` (Debian's `petsc-dev`), or 64-bit indices, which set the `petsc_int64` cfg.
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
    for flag in pc("--libs").split_whitespace() {
        if let Some(dir) = flag.strip_prefix("-L") {
            println!("cargo::rustc-link-search=native={dir}");
            println!("cargo::rustc-link-arg=-Wl,-rpath,{dir}");
        } else if let Some(lib) = flag.strip_prefix("-l") {
            println!("cargo::rustc-link-lib={lib}");
        }
    }
}
