//! The PETSc calls tmc makes, declared by hand against the installed headers (PETSc 3.18,
//! `petscsys.h`, `petscvec.h`, `petscmat.h`, `petscksp.h`, `petscpc.h`,
//! `petscoptions.h`, `petscerror.h`); only those, so that each is used. `build.rs` checks the
//! scalar and index sizes assumed here and finds the library, which is opened when a run first
//! starts PETSc ([`load`]), not with tmc.
#![allow(non_camel_case_types)]

use mpi::ffi::MPI_Comm;
use std::os::raw::{c_char, c_int, c_void};

#[cfg(not(petsc_int64))]
pub type PetscInt = i32;
#[cfg(petsc_int64)]
pub type PetscInt = i64;
pub type PetscScalar = f64;
pub type PetscReal = f64;
pub type PetscErrorCode = c_int;
/// `PetscBool` is a C enum: `PETSC_FALSE` = 0, `PETSC_TRUE` = 1.
pub type PetscBool = c_int;
pub const PETSC_FALSE: PetscBool = 0;
pub const PETSC_TRUE: PetscBool = 1;

pub type Mat = *mut c_void;
pub type Vec = *mut c_void;
pub type KSP = *mut c_void;
pub type PC = *mut c_void;
pub type VecScatter = *mut c_void;
pub type PetscOptions = *mut c_void;
pub type IS = *mut c_void;
pub type MatNullSpace = *mut c_void;
pub type PetscObject = *mut c_void;

/// `InsertMode`.
pub const INSERT_VALUES: c_int = 1;
pub const ADD_VALUES: c_int = 2;
/// `MatAssemblyType`.
pub const MAT_FINAL_ASSEMBLY: c_int = 0;
/// `ScatterMode`.
pub const SCATTER_FORWARD: c_int = 0;
/// `MatOption`.
pub const MAT_SYMMETRIC: c_int = 1;
pub const MAT_SYMMETRY_ETERNAL: c_int = 10;
pub const MAT_NEW_NONZERO_ALLOCATION_ERR: c_int = 19;
/// `PETSC_DEFAULT` for tolerances and iteration counts.
pub const PETSC_DEFAULT: c_int = -2;
/// `PETSC_DETERMINE` for a global size PETSc sums from the local ones.
pub const PETSC_DETERMINE: PetscInt = -1;
/// `PetscCopyMode`.
pub const PETSC_COPY_VALUES: c_int = 0;

pub type ErrorHandler = unsafe extern "C" fn(
    MPI_Comm,
    c_int,
    *const c_char,
    *const c_char,
    PetscErrorCode,
    c_int,
    *const c_char,
    *mut c_void,
) -> PetscErrorCode;

crate::dynamic_api! {
    "PETSc" from [env!("TMC_PETSC_LIBRARY")];
    fn PetscInitializeNoArguments() -> PetscErrorCode;
    fn PetscFinalize() -> PetscErrorCode;
    fn PetscErrorMessage(
        code: c_int,
        text: *mut *const c_char,
        specific: *mut *mut c_char,
    ) -> PetscErrorCode;
    fn PetscPushErrorHandler(handler: ErrorHandler, ctx: *mut c_void) -> PetscErrorCode;

    fn PetscOptionsInsertString(options: PetscOptions, s: *const c_char) -> PetscErrorCode;
    fn PetscLogDefaultBegin() -> PetscErrorCode;
    fn PetscOptionsLeftGet(
        options: PetscOptions,
        n: *mut PetscInt,
        names: *mut *mut *mut c_char,
        values: *mut *mut *mut c_char,
    ) -> PetscErrorCode;
    fn PetscOptionsLeftRestore(
        options: PetscOptions,
        n: *mut PetscInt,
        names: *mut *mut *mut c_char,
        values: *mut *mut *mut c_char,
    ) -> PetscErrorCode;

    fn MatCreate(comm: MPI_Comm, m: *mut Mat) -> PetscErrorCode;
    fn MatSetSizes(
        m: Mat,
        rl: PetscInt,
        cl: PetscInt,
        r: PetscInt,
        c: PetscInt,
    ) -> PetscErrorCode;
    fn MatSetType(m: Mat, t: *const c_char) -> PetscErrorCode;
    fn MatSeqAIJSetPreallocation(m: Mat, nz: PetscInt, nnz: *const PetscInt) -> PetscErrorCode;
    fn MatMPIAIJSetPreallocation(
        m: Mat,
        d_nz: PetscInt,
        d_nnz: *const PetscInt,
        o_nz: PetscInt,
        o_nnz: *const PetscInt,
    ) -> PetscErrorCode;
    fn MatSetOption(m: Mat, op: c_int, flg: PetscBool) -> PetscErrorCode;
    fn MatSetValues(
        m: Mat,
        nr: PetscInt,
        rows: *const PetscInt,
        nc: PetscInt,
        cols: *const PetscInt,
        v: *const PetscScalar,
        mode: c_int,
    ) -> PetscErrorCode;
    fn MatZeroEntries(m: Mat) -> PetscErrorCode;
    fn MatAssemblyBegin(m: Mat, t: c_int) -> PetscErrorCode;
    fn MatAssemblyEnd(m: Mat, t: c_int) -> PetscErrorCode;
    fn MatCreateVecs(m: Mat, right: *mut Vec, left: *mut Vec) -> PetscErrorCode;
    fn MatDestroy(m: *mut Mat) -> PetscErrorCode;

    fn VecGetArray(v: Vec, a: *mut *mut PetscScalar) -> PetscErrorCode;
    fn VecRestoreArray(v: Vec, a: *mut *mut PetscScalar) -> PetscErrorCode;
    fn VecGetArrayRead(v: Vec, a: *mut *const PetscScalar) -> PetscErrorCode;
    fn VecRestoreArrayRead(v: Vec, a: *mut *const PetscScalar) -> PetscErrorCode;
    fn VecScatterCreateToAll(v: Vec, ctx: *mut VecScatter, all: *mut Vec) -> PetscErrorCode;
    fn VecScatterBegin(
        ctx: VecScatter,
        x: Vec,
        y: Vec,
        mode: c_int,
        smode: c_int,
    ) -> PetscErrorCode;
    fn VecScatterEnd(
        ctx: VecScatter,
        x: Vec,
        y: Vec,
        mode: c_int,
        smode: c_int,
    ) -> PetscErrorCode;
    fn VecScatterDestroy(ctx: *mut VecScatter) -> PetscErrorCode;
    fn VecDestroy(v: *mut Vec) -> PetscErrorCode;

    fn KSPCreate(comm: MPI_Comm, ksp: *mut KSP) -> PetscErrorCode;
    fn KSPSetOperators(ksp: KSP, a: Mat, p: Mat) -> PetscErrorCode;
    fn KSPSetType(ksp: KSP, t: *const c_char) -> PetscErrorCode;
    fn KSPGetType(ksp: KSP, t: *mut *const c_char) -> PetscErrorCode;
    fn KSPSetTolerances(
        ksp: KSP,
        rtol: PetscReal,
        abstol: PetscReal,
        dtol: PetscReal,
        maxits: PetscInt,
    ) -> PetscErrorCode;
    fn KSPSetFromOptions(ksp: KSP) -> PetscErrorCode;
    fn KSPSolve(ksp: KSP, b: Vec, x: Vec) -> PetscErrorCode;
    fn KSPGetIterationNumber(ksp: KSP, its: *mut PetscInt) -> PetscErrorCode;
    fn KSPGetConvergedReason(ksp: KSP, reason: *mut c_int) -> PetscErrorCode;
    fn KSPGetPC(ksp: KSP, pc: *mut PC) -> PetscErrorCode;
    fn KSPDestroy(ksp: *mut KSP) -> PetscErrorCode;
    fn PCSetType(pc: PC, t: *const c_char) -> PetscErrorCode;
    fn PCGetType(pc: PC, t: *mut *const c_char) -> PetscErrorCode;
    fn PCFactorSetMatSolverType(pc: PC, t: *const c_char) -> PetscErrorCode;
    fn PCFieldSplitSetIS(pc: PC, name: *const c_char, is: IS) -> PetscErrorCode;
    fn KSPSetReusePreconditioner(ksp: KSP, flag: PetscBool) -> PetscErrorCode;

    fn ISCreateGeneral(
        comm: MPI_Comm,
        n: PetscInt,
        idx: *const PetscInt,
        mode: c_int,
        is: *mut IS,
    ) -> PetscErrorCode;
    fn ISDestroy(is: *mut IS) -> PetscErrorCode;
    fn VecCreateMPI(comm: MPI_Comm, n: PetscInt, nn: PetscInt, v: *mut Vec) -> PetscErrorCode;
    fn MatNullSpaceCreate(
        comm: MPI_Comm,
        has_cnst: PetscBool,
        n: PetscInt,
        vecs: *const Vec,
        sp: *mut MatNullSpace,
    ) -> PetscErrorCode;
    fn MatNullSpaceDestroy(sp: *mut MatNullSpace) -> PetscErrorCode;
    fn MatSetNearNullSpace(m: Mat, sp: MatNullSpace) -> PetscErrorCode;
    fn PetscObjectCompose(
        obj: PetscObject,
        name: *const c_char,
        other: PetscObject,
    ) -> PetscErrorCode;
    fn PetscOptionsHasName(
        options: PetscOptions,
        prefix: *const c_char,
        name: *const c_char,
        set: *mut PetscBool,
    ) -> PetscErrorCode;
    fn PetscOptionsSetValue(
        options: PetscOptions,
        name: *const c_char,
        value: *const c_char,
    ) -> PetscErrorCode;
}

/// PETSc's names of KSPConvergedReason (`KSPConvergedReasons`), indexed by the reason itself
/// (PETSc shifts the pointer so that negative reasons index it too): `reasons[-3]` is
/// "DIVERGED_ITS". PETSc is loaded by then.
pub fn KSPConvergedReasons() -> *const *const c_char {
    let api = load().expect("PETSc is loaded before its first call");
    let table = api
        .library
        .symbol("PETSc", "KSPConvergedReasons")
        .expect("PETSc 3.18 exports KSPConvergedReasons");
    // SAFETY: the symbol is a `const char *const *` variable
    unsafe { *(table.as_ptr() as *const *const *const c_char) }
}
