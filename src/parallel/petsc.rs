//! The engine: MPI, then PETSc, started once per process ([`start`]) and ended before it exits
//! ([`finish`]); PETSc's objects as owned values that destroy themselves; PETSc's errors as
//! [`PetscError`] values (PETSc's own handler, which prints a traceback, is replaced by one
//! that keeps PETSc's words for the error where it was raised, for the error tmc reports).

use super::Ranks;
use super::ffi::{self, PetscInt};
use mpi::collective::{CommunicatorCollectives, Root, SystemOperation};
use mpi::topology::{Communicator, SimpleCommunicator};
use mpi::traits::AsRaw;
use std::ffi::{CStr, CString};
use std::sync::Mutex;

/// The engine while it runs: started by [`start_mpi`], ended by [`finish`].
static ENGINE: Mutex<Option<Engine>> = Mutex::new(None);

struct Engine {
    /// MPI's universe (dropping it ends MPI).
    universe: mpi::environment::Universe,
    /// Whether PETSc is up.
    petsc: bool,
    /// A copy of the world's communicator for [`all_failed`] alone, so that its barrier can
    /// never be matched with another collective call of tmc's or PETSc's.
    failures: SimpleCommunicator,
}

// SAFETY: the communicator is made, used and freed on the thread that started MPI (tmc's
// main thread, the only one that calls MPI); the lock only moves the handle's ownership.
unsafe impl Send for Engine {}

/// A PETSc call that failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("PETSc: {call} failed: {message} (error {code})")]
pub struct PetscError {
    pub call: &'static str,
    pub code: i32,
    pub message: String,
}

/// The message and function of the error PETSc raised last (where it was first raised, not
/// the calls it went back through), taken by the next [`check`]; tmc calls PETSc from one
/// thread.
static RAISED: Mutex<Option<(String, String)>> = Mutex::new(None);

/// PETSc's error handler while tmc runs: keeps where the error was raised and PETSc's words
/// for it, prints nothing, and returns the code (as PETSc's `PetscReturnErrorHandler`).
unsafe extern "C" fn keep_error(
    _comm: mpi::ffi::MPI_Comm,
    _line: std::os::raw::c_int,
    fun: *const std::os::raw::c_char,
    _file: *const std::os::raw::c_char,
    n: ffi::PetscErrorCode,
    p: std::os::raw::c_int,
    mess: *const std::os::raw::c_char,
    _ctx: *mut std::os::raw::c_void,
) -> ffi::PetscErrorCode {
    // p = PETSC_ERROR_INITIAL (0) where the error is raised, PETSC_ERROR_REPEAT on the way back
    if p == 0 {
        let text = |s: *const std::os::raw::c_char| {
            if s.is_null() {
                String::new()
            } else {
                // SAFETY: PETSc passes NUL-terminated strings that live through the call
                unsafe { CStr::from_ptr(s) }
                    .to_string_lossy()
                    .trim()
                    .to_owned()
            }
        };
        if let Ok(mut raised) = RAISED.lock() {
            *raised = Some((text(mess), text(fun)));
        }
    }
    n
}

/// `Ok` for PETSc's 0, else the error: PETSc's text for `code` and, where PETSc said more
/// where it raised it, those words and the function that raised it.
pub fn check(call: &'static str, code: ffi::PetscErrorCode) -> Result<(), PetscError> {
    let raised = RAISED.lock().ok().and_then(|mut r| r.take());
    if code == 0 {
        return Ok(());
    }
    let mut text: *const std::os::raw::c_char = std::ptr::null();
    let generic = unsafe {
        if ffi::PetscErrorMessage(code, &mut text, std::ptr::null_mut()) == 0 && !text.is_null() {
            Some(CStr::from_ptr(text).to_string_lossy().into_owned())
        } else {
            None
        }
    };
    let message = match (generic, raised) {
        (Some(g), Some((m, f))) if !m.is_empty() => format!("{g}: {m} (in {f})"),
        (None, Some((m, f))) if !m.is_empty() => format!("{m} (in {f})"),
        (Some(g), _) => g,
        (None, _) => "PETSc gave no text for this code".into(),
    };
    Err(PetscError {
        call,
        code,
        message,
    })
}

/// PETSc's name of a KSPConvergedReason ("DIVERGED_ITS" for −3), or the number where PETSc
/// has no name for it.
pub fn reason_name(reason: i32) -> String {
    // KSP_DIVERGED_PC_FAILED (−11) … KSP_CONVERGED_ATOL_NORMAL (9) in PETSc 3.18
    if (-11..=9).contains(&reason) && reason != -1 {
        // SAFETY: PETSc's table holds a name (or NULL) for every reason in that range
        let name = unsafe { *ffi::KSPConvergedReasons().offset(reason as isize) };
        if !name.is_null() {
            return unsafe { CStr::from_ptr(name) }
                .to_string_lossy()
                .into_owned();
        }
    }
    format!("reason {reason}")
}

/// Start MPI if it is not running yet (idempotent): the ranks of the world.
pub fn start_mpi() -> Ranks {
    let mut engine = ENGINE.lock().expect("engine lock");
    if engine.is_none() {
        let universe = mpi::initialize().expect("MPI starts once per process");
        *engine = Some(Engine {
            universe,
            petsc: false,
            // (collective: every rank starts MPI here)
            failures: SimpleCommunicator::world().duplicate(),
        });
    }
    drop(engine);
    world().expect("MPI is running")
}

/// Start MPI and PETSc if they are not running yet (idempotent). PETSc reads the
/// `PETSC_OPTIONS` environment variable here.
pub fn start() -> Result<Ranks, PetscError> {
    let ranks = start_mpi();
    let mut engine = ENGINE.lock().expect("engine lock");
    let Engine { petsc, .. } = engine.as_mut().expect("MPI is running");
    if !*petsc {
        ffi::load().map_err(|e| PetscError {
            call: "loading PETSc",
            code: -1,
            message: format!("{e}; rebuild tmc (make build) if PETSc was upgraded or removed"),
        })?;
        unsafe {
            check("PetscInitialize", ffi::PetscInitializeNoArguments())?;
            check(
                "PetscPushErrorHandler",
                ffi::PetscPushErrorHandler(keep_error, std::ptr::null_mut()),
            )?;
        }
        *petsc = true;
    }
    Ok(ranks)
}

/// Called by a rank whose run failed: whether every rank's run failed too, as far as can be
/// told within `wait`. A failure the ranks share (a step they all cut to nothing, an option
/// PETSc refused) brings them all here; one that struck a rank alone (a PETSc call that
/// failed in its part) leaves the others waiting in a collective call for it, and they never
/// come: that rank must then end the run ([`abort`]) or it would hang.
pub fn all_failed(wait: std::time::Duration) -> bool {
    let engine = ENGINE.lock().expect("engine lock");
    let Some(Engine { failures, .. }) = engine.as_ref() else {
        return true;
    };
    let start = std::time::Instant::now();
    let mut request = failures.immediate_barrier();
    loop {
        match request.test() {
            Ok(_) => return true,
            Err(pending) => request = pending,
        }
        if start.elapsed() > wait {
            // never to complete; the process ends next (dropping it would abort at once)
            std::mem::forget(request);
            return false;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// End every rank of the run at once, with exit status `code` (MPI_Abort): what a rank does
/// when it failed alone and the others wait for it.
pub fn abort(code: i32) -> ! {
    SimpleCommunicator::world().abort(code)
}

/// End PETSc, then MPI, if they were started. PETSc's objects must be gone by then.
pub fn finish() {
    let mut engine = ENGINE.lock().expect("engine lock");
    if let Some(Engine {
        universe,
        petsc,
        failures,
    }) = engine.take()
    {
        drop(failures);
        if petsc {
            unsafe { ffi::PetscFinalize() };
        }
        drop(universe);
    }
}

/// The world's ranks while MPI runs.
pub fn world() -> Option<Ranks> {
    let engine = ENGINE.lock().expect("engine lock");
    engine.as_ref()?;
    let w = SimpleCommunicator::world();
    Some(Ranks {
        rank: w.rank() as usize,
        size: w.size() as usize,
    })
}

pub(super) enum Reduce {
    Sum,
    Min,
}

/// `v` reduced over the world, on every rank.
pub(super) fn all_reduce(v: &mut [f64], op: Reduce) {
    let w = SimpleCommunicator::world();
    let send = v.to_vec();
    match op {
        Reduce::Sum => w.all_reduce_into(&send[..], v, SystemOperation::sum()),
        Reduce::Min => w.all_reduce_into(&send[..], v, SystemOperation::min()),
    }
}

/// `bytes` of `root` on every rank.
pub(super) fn broadcast(root: usize, bytes: &mut Vec<u8>) {
    let w = SimpleCommunicator::world();
    let p = w.process_at_rank(root as i32);
    let mut len = [bytes.len() as u64];
    p.broadcast_into(&mut len[..]);
    bytes.resize(len[0] as usize, 0);
    // nothing to send: Open MPI refuses the empty buffer's dangling pointer (MPI_ERR_ARG)
    if !bytes.is_empty() {
        p.broadcast_into(&mut bytes[..]);
    }
}

fn comm() -> mpi::ffi::MPI_Comm {
    SimpleCommunicator::world().as_raw()
}

fn cstring(s: &str) -> CString {
    CString::new(s).expect("no NUL in PETSc names")
}

/// Add `options` (PETSc's command-line syntax) to PETSc's options. `-log_view`, which PETSc
/// reads when it starts (before the case's options are known), starts its logging here, and
/// PETSc prints the log when it ends.
pub fn insert_options(options: &str) -> Result<(), PetscError> {
    let s = cstring(options);
    check("PetscOptionsInsertString", unsafe {
        ffi::PetscOptionsInsertString(std::ptr::null_mut(), s.as_ptr())
    })?;
    // (asking marks the option used)
    if has_option("-log_view")? {
        check("PetscLogDefaultBegin", unsafe {
            ffi::PetscLogDefaultBegin()
        })?;
    }
    Ok(())
}

/// Whether PETSc's options hold `name` (with its dash); asking marks it used.
fn has_option(name: &str) -> Result<bool, PetscError> {
    let key = cstring(name);
    let mut set: ffi::PetscBool = ffi::PETSC_FALSE;
    check("PetscOptionsHasName", unsafe {
        ffi::PetscOptionsHasName(
            std::ptr::null_mut(),
            std::ptr::null(),
            key.as_ptr(),
            &mut set,
        )
    })?;
    Ok(set != ffi::PETSC_FALSE)
}

/// Options tmc set as defaults ([`default_option`]): not the user's, so never reported unused.
static DEFAULTS: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Set option `-name value` unless the user's options (or an earlier default) set it.
pub fn default_option(name: &str, value: &str) -> Result<(), PetscError> {
    let key = format!("-{name}");
    if !has_option(&key)? {
        let (key, v) = (cstring(&key), cstring(value));
        check("PetscOptionsSetValue", unsafe {
            ffi::PetscOptionsSetValue(std::ptr::null_mut(), key.as_ptr(), v.as_ptr())
        })?;
        DEFAULTS
            .lock()
            .expect("defaults lock")
            .push(name.to_string());
    }
    Ok(())
}

/// The options given that no PETSc object has read so far, as `-name value` (tmc's own
/// defaults left out: they may be for a solver the user's options replaced).
pub fn unused_options() -> Vec<String> {
    let mut n: PetscInt = 0;
    let mut names: *mut *mut std::os::raw::c_char = std::ptr::null_mut();
    let mut values: *mut *mut std::os::raw::c_char = std::ptr::null_mut();
    let mut out = Vec::new();
    unsafe {
        if ffi::PetscOptionsLeftGet(std::ptr::null_mut(), &mut n, &mut names, &mut values) != 0 {
            return out;
        }
        let defaults = DEFAULTS.lock().expect("defaults lock");
        for i in 0..n as usize {
            let name = CStr::from_ptr(*names.add(i)).to_string_lossy();
            if defaults.iter().any(|d| *d == name) {
                continue;
            }
            let value = *values.add(i);
            out.push(if value.is_null() {
                format!("-{name}")
            } else {
                format!("-{name} {}", CStr::from_ptr(value).to_string_lossy())
            });
        }
        ffi::PetscOptionsLeftRestore(std::ptr::null_mut(), &mut n, &mut names, &mut values);
    }
    out
}

/// A parallel AIJ matrix with `local` rows (and columns) on this rank.
pub struct Matrix(pub(crate) ffi::Mat);

impl Matrix {
    /// Rows `local` of `global` here, preallocated with `diag[i]` entries of row i in this
    /// rank's columns and `off[i]` in the others'. Inserting outside the preallocation is an
    /// error, not a silent slow-down.
    pub fn aij(
        global: usize,
        local: usize,
        diag: &[PetscInt],
        off: &[PetscInt],
        symmetric: bool,
    ) -> Result<Matrix, PetscError> {
        let mut m: ffi::Mat = std::ptr::null_mut();
        unsafe {
            check("MatCreate", ffi::MatCreate(comm(), &mut m))?;
            let me = Matrix(m);
            let (l, g) = (local as PetscInt, global as PetscInt);
            check("MatSetSizes", ffi::MatSetSizes(m, l, l, g, g))?;
            check("MatSetType", ffi::MatSetType(m, cstring("aij").as_ptr()))?;
            check(
                "MatSeqAIJSetPreallocation",
                ffi::MatSeqAIJSetPreallocation(m, 0, diag.as_ptr()),
            )?;
            check(
                "MatMPIAIJSetPreallocation",
                ffi::MatMPIAIJSetPreallocation(m, 0, diag.as_ptr(), 0, off.as_ptr()),
            )?;
            check(
                "MatSetOption",
                ffi::MatSetOption(m, ffi::MAT_NEW_NONZERO_ALLOCATION_ERR, ffi::PETSC_TRUE),
            )?;
            if symmetric {
                for op in [ffi::MAT_SYMMETRIC, ffi::MAT_SYMMETRY_ETERNAL] {
                    check("MatSetOption", ffi::MatSetOption(m, op, ffi::PETSC_TRUE))?;
                }
            }
            Ok(me)
        }
    }

    pub fn zero(&mut self) -> Result<(), PetscError> {
        check("MatZeroEntries", unsafe { ffi::MatZeroEntries(self.0) })
    }

    /// Add `values` at rows `rows` of column `col` (global numbers; rows of other ranks go to
    /// them at [`Matrix::assemble`]).
    pub fn add_column(
        &mut self,
        rows: &[PetscInt],
        col: PetscInt,
        values: &[f64],
    ) -> Result<(), PetscError> {
        check("MatSetValues", unsafe {
            ffi::MatSetValues(
                self.0,
                rows.len() as PetscInt,
                rows.as_ptr(),
                1,
                &col,
                values.as_ptr(),
                ffi::ADD_VALUES,
            )
        })
    }

    /// Exchange the entries added for other ranks' rows and finish the matrix (collective).
    pub fn assemble(&mut self) -> Result<(), PetscError> {
        unsafe {
            check(
                "MatAssemblyBegin",
                ffi::MatAssemblyBegin(self.0, ffi::MAT_FINAL_ASSEMBLY),
            )?;
            check(
                "MatAssemblyEnd",
                ffi::MatAssemblyEnd(self.0, ffi::MAT_FINAL_ASSEMBLY),
            )
        }
    }

    /// The near-kernel an algebraic multigrid of this matrix keeps on its coarse levels.
    pub fn set_near_kernel(&mut self, k: &NearKernel) -> Result<(), PetscError> {
        check("MatSetNearNullSpace", unsafe {
            ffi::MatSetNearNullSpace(self.0, k.0)
        })
    }

    /// A vector laid out like the matrix's rows.
    pub fn vector(&self) -> Result<Vector, PetscError> {
        let mut v: ffi::Vec = std::ptr::null_mut();
        check("MatCreateVecs", unsafe {
            ffi::MatCreateVecs(self.0, std::ptr::null_mut(), &mut v)
        })?;
        Ok(Vector(v))
    }
}

impl Drop for Matrix {
    fn drop(&mut self) {
        unsafe { ffi::MatDestroy(&mut self.0) };
    }
}

/// This rank's rows of one block of a field split (PETSc's IS).
pub struct IndexSet(ffi::IS);

impl IndexSet {
    /// The global rows `rows`, all of this rank (collective).
    pub fn new(rows: &[PetscInt]) -> Result<IndexSet, PetscError> {
        let mut is: ffi::IS = std::ptr::null_mut();
        check("ISCreateGeneral", unsafe {
            ffi::ISCreateGeneral(
                comm(),
                rows.len() as PetscInt,
                rows.as_ptr(),
                ffi::PETSC_COPY_VALUES,
                &mut is,
            )
        })?;
        Ok(IndexSet(is))
    }

    /// Give the block these rows select the near-kernel `k`: PETSc's field split hands it to
    /// the block's matrix, where an algebraic multigrid finds it.
    pub fn set_near_kernel(&self, k: &NearKernel) -> Result<(), PetscError> {
        let name = cstring("nearnullspace");
        check("PetscObjectCompose", unsafe {
            ffi::PetscObjectCompose(self.0, name.as_ptr(), k.0)
        })
    }
}

impl Drop for IndexSet {
    fn drop(&mut self) {
        unsafe { ffi::ISDestroy(&mut self.0) };
    }
}

/// The modes a matrix maps to nearly zero (PETSc's near null space; for elasticity the rigid
/// motions), which a smoothed-aggregation multigrid must keep on its coarse levels.
pub struct NearKernel(ffi::MatNullSpace);

impl NearKernel {
    /// From `modes`, each this rank's `local` entries of one vector, orthonormal over all
    /// ranks (collective).
    pub fn new(local: usize, modes: &[Vec<f64>]) -> Result<NearKernel, PetscError> {
        let mut vecs = Vec::with_capacity(modes.len());
        for m in modes {
            let mut v: ffi::Vec = std::ptr::null_mut();
            check("VecCreateMPI", unsafe {
                ffi::VecCreateMPI(comm(), local as PetscInt, ffi::PETSC_DETERMINE, &mut v)
            })?;
            let mut v = Vector(v);
            v.with_local(|a| a.copy_from_slice(m), local);
            vecs.push(v);
        }
        let raw: Vec<ffi::Vec> = vecs.iter().map(|v| v.0).collect();
        let mut sp: ffi::MatNullSpace = std::ptr::null_mut();
        check("MatNullSpaceCreate", unsafe {
            ffi::MatNullSpaceCreate(
                comm(),
                ffi::PETSC_FALSE,
                raw.len() as PetscInt,
                raw.as_ptr(),
                &mut sp,
            )
        })?;
        // the null space holds its own references to the vectors
        Ok(NearKernel(sp))
    }
}

impl Drop for NearKernel {
    fn drop(&mut self) {
        unsafe { ffi::MatNullSpaceDestroy(&mut self.0) };
    }
}

/// A parallel vector.
pub struct Vector(pub(crate) ffi::Vec);

impl Vector {
    /// This rank's entries, to read and write.
    pub fn with_local<T>(&mut self, f: impl FnOnce(&mut [f64]) -> T, len: usize) -> T {
        let mut a: *mut f64 = std::ptr::null_mut();
        unsafe {
            ffi::VecGetArray(self.0, &mut a);
            let out = f(std::slice::from_raw_parts_mut(a, len));
            ffi::VecRestoreArray(self.0, &mut a);
            out
        }
    }
}

impl Drop for Vector {
    fn drop(&mut self) {
        unsafe { ffi::VecDestroy(&mut self.0) };
    }
}

/// A whole parallel vector copied to every rank.
pub struct ToAll {
    scatter: ffi::VecScatter,
    all: Vector,
}

impl ToAll {
    pub fn new(like: &Vector) -> Result<ToAll, PetscError> {
        let mut scatter: ffi::VecScatter = std::ptr::null_mut();
        let mut all: ffi::Vec = std::ptr::null_mut();
        check("VecScatterCreateToAll", unsafe {
            ffi::VecScatterCreateToAll(like.0, &mut scatter, &mut all)
        })?;
        Ok(ToAll {
            scatter,
            all: Vector(all),
        })
    }

    /// Every entry of `v`, in global order, handed to `f` (collective).
    pub fn gather<T>(
        &mut self,
        v: &Vector,
        global: usize,
        f: impl FnOnce(&[f64]) -> T,
    ) -> Result<T, PetscError> {
        unsafe {
            let mode = (ffi::INSERT_VALUES, ffi::SCATTER_FORWARD);
            check(
                "VecScatterBegin",
                ffi::VecScatterBegin(self.scatter, v.0, self.all.0, mode.0, mode.1),
            )?;
            check(
                "VecScatterEnd",
                ffi::VecScatterEnd(self.scatter, v.0, self.all.0, mode.0, mode.1),
            )?;
            let mut a: *const f64 = std::ptr::null();
            check("VecGetArrayRead", ffi::VecGetArrayRead(self.all.0, &mut a))?;
            let out = f(std::slice::from_raw_parts(a, global));
            ffi::VecRestoreArrayRead(self.all.0, &mut a);
            Ok(out)
        }
    }
}

impl Drop for ToAll {
    fn drop(&mut self) {
        unsafe { ffi::VecScatterDestroy(&mut self.scatter) };
    }
}

/// A Krylov solver with its preconditioner (PETSc's KSP and PC).
pub struct Krylov(pub(crate) ffi::KSP);

/// What a solve did: iterations, and PETSc's reason (negative: diverged).
#[derive(Clone, Copy, Debug)]
pub struct KrylovReport {
    pub iterations: usize,
    pub reason: i32,
}

impl Krylov {
    /// A solver of `a` with `ksp_type`/`pc_type` (and the factor package, if any) unless the
    /// options say otherwise, relative tolerance `rtol`. `splits` name the blocks of a field
    /// split, used if the preconditioner is one (`-fieldsplit_NAME_` options configure each).
    pub fn new(
        a: &Matrix,
        ksp_type: &str,
        pc_type: &str,
        factor_package: Option<&str>,
        rtol: f64,
        splits: &[(&str, &IndexSet)],
    ) -> Result<Krylov, PetscError> {
        let mut k: ffi::KSP = std::ptr::null_mut();
        unsafe {
            check("KSPCreate", ffi::KSPCreate(comm(), &mut k))?;
            let me = Krylov(k);
            check("KSPSetOperators", ffi::KSPSetOperators(k, a.0, a.0))?;
            check("KSPSetType", ffi::KSPSetType(k, cstring(ksp_type).as_ptr()))?;
            let mut pc: ffi::PC = std::ptr::null_mut();
            check("KSPGetPC", ffi::KSPGetPC(k, &mut pc))?;
            check("PCSetType", ffi::PCSetType(pc, cstring(pc_type).as_ptr()))?;
            if let Some(pkg) = factor_package {
                check(
                    "PCFactorSetMatSolverType",
                    ffi::PCFactorSetMatSolverType(pc, cstring(pkg).as_ptr()),
                )?;
            }
            check(
                "KSPSetTolerances",
                ffi::KSPSetTolerances(
                    k,
                    rtol,
                    ffi::PETSC_DEFAULT as f64,
                    ffi::PETSC_DEFAULT as f64,
                    1000,
                ),
            )?;
            check("KSPSetFromOptions", ffi::KSPSetFromOptions(k))?;
            if !splits.is_empty() {
                // a no-op unless the options made the preconditioner a field split; then the
                // blocks' solvers read their options
                for (name, is) in splits {
                    let name = cstring(name);
                    check(
                        "PCFieldSplitSetIS",
                        ffi::PCFieldSplitSetIS(pc, name.as_ptr(), is.0),
                    )?;
                }
                check("KSPSetFromOptions", ffi::KSPSetFromOptions(k))?;
            }
            Ok(me)
        }
    }

    /// Solve `a x = b` (collective).
    pub fn solve(&mut self, b: &Vector, x: &mut Vector) -> Result<KrylovReport, PetscError> {
        let (mut its, mut reason): (PetscInt, i32) = (0, 0);
        unsafe {
            check("KSPSolve", ffi::KSPSolve(self.0, b.0, x.0))?;
            check(
                "KSPGetIterationNumber",
                ffi::KSPGetIterationNumber(self.0, &mut its),
            )?;
            check(
                "KSPGetConvergedReason",
                ffi::KSPGetConvergedReason(self.0, &mut reason),
            )?;
        }
        Ok(KrylovReport {
            iterations: its as usize,
            reason,
        })
    }

    /// Keep the preconditioner built for an earlier matrix (`true`) or rebuild it for the
    /// current one at the next solve.
    pub fn reuse_preconditioner(&mut self, reuse: bool) -> Result<(), PetscError> {
        let flag = if reuse {
            ffi::PETSC_TRUE
        } else {
            ffi::PETSC_FALSE
        };
        check("KSPSetReusePreconditioner", unsafe {
            ffi::KSPSetReusePreconditioner(self.0, flag)
        })
    }

    /// The solver and preconditioner types in use, as `ksp_type/pc_type`.
    pub fn describe(&self) -> String {
        unsafe {
            let (mut kt, mut pt): (*const std::os::raw::c_char, *const std::os::raw::c_char) =
                (std::ptr::null(), std::ptr::null());
            let mut pc: ffi::PC = std::ptr::null_mut();
            ffi::KSPGetType(self.0, &mut kt);
            ffi::KSPGetPC(self.0, &mut pc);
            ffi::PCGetType(pc, &mut pt);
            let s = |p: *const std::os::raw::c_char| {
                if p.is_null() {
                    "?".to_string()
                } else {
                    CStr::from_ptr(p).to_string_lossy().into_owned()
                }
            };
            format!("{}/{}", s(kt), s(pt))
        }
    }
}

impl Drop for Krylov {
    fn drop(&mut self) {
        unsafe { ffi::KSPDestroy(&mut self.0) };
    }
}
