//! The gmsh C API calls tmc makes, declared against `/usr/include/gmshc.h` (gmsh 4.8.4, Debian's
//! `libgmsh-dev`); only those, so that each is used. The library is opened on first use
//! ([`load`]): a `tmc` that meshes nothing never loads gmsh and OpenCASCADE.
#![allow(non_snake_case)]

use std::os::raw::{c_char, c_double, c_int, c_void};

crate::dynamic_api! {
    "gmsh" from ["libgmsh.so", "libgmsh.so.4.8"];
    fn gmshInitialize(argc: c_int, argv: *mut *mut c_char, readConfigFiles: c_int, ierr: *mut c_int);
    fn gmshFinalize(ierr: *mut c_int);
    fn gmshFree(p: *mut c_void);
    fn gmshLoggerStart(ierr: *mut c_int);
    fn gmshLoggerGet(log: *mut *mut *mut c_char, log_n: *mut usize, ierr: *mut c_int);
    fn gmshLoggerStop(ierr: *mut c_int);
    fn gmshOpen(fileName: *const c_char, ierr: *mut c_int);
    fn gmshOptionSetNumber(name: *const c_char, value: c_double, ierr: *mut c_int);
    fn gmshModelGetDimension(ierr: *mut c_int) -> c_int;
    fn gmshModelGetEntities(dimTags: *mut *mut c_int, dimTags_n: *mut usize, dim: c_int, ierr: *mut c_int);
    fn gmshModelGetPhysicalGroups(dimTags: *mut *mut c_int, dimTags_n: *mut usize, dim: c_int, ierr: *mut c_int);
    fn gmshModelGetPhysicalGroupsForEntity(
        dim: c_int,
        tag: c_int,
        physicalTags: *mut *mut c_int,
        physicalTags_n: *mut usize,
        ierr: *mut c_int,
    );
    fn gmshModelMeshGenerate(dim: c_int, ierr: *mut c_int);
    fn gmshModelMeshSetOrder(order: c_int, ierr: *mut c_int);
    fn gmshWrite(fileName: *const c_char, ierr: *mut c_int);
}
