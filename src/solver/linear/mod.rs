//! Sparse linear solvers behind one small interface: symbolic analysis once per pattern,
//! numeric factorisation per Newton iteration, then solves.
//!
//! - [`LinearKind::Ldlt`]: faer's sparse LDLᵀ of the whole system (symmetric tangents:
//!   mechanics alone, conduction alone), ordered by METIS nested dissection of the node graph.
//! - [`LinearKind::BlockGmres`]: the coupled tangent
//!   `[[K_mm, K_mθ], [K_θm, K_θθ]]` (m = u with p) is solved by GMRES, right-preconditioned with
//!   the block lower-triangular factor `[[K_mm, 0], [K_θm, K_θθ]]`, whose diagonal blocks are
//!   symmetric and factorised by LDLᵀ in single precision (half the memory traffic of double,
//!   twice the SIMD width; GMRES keeps the residual in double and reaches the same 1e-10).
//!   Without thermal expansion (K_mθ = 0) the preconditioner is the exact inverse up to that
//!   rounding, and GMRES stops after two or three iterations. Where Newton says the tangent
//!   is near the last ([`Factorization::set_near`]: its quadratic tail, or a step's start),
//!   the blocks' last factors precondition the new tangent while GMRES converges within the
//!   iterations a factorisation is worth ([`block_lag_price`]; none for a small system).
//!   Where a factorisation is worth more than a lag may take (a dear factor, [`Lag::dear`]:
//!   Table 2's 147k row, not its 20.5k row, at any thread count), the factors are kept
//!   through Newton's damped iterations too, whose updates are solved to [`DAMPED_TOL`] only.
//! - [`LinearKind::Lu`]: friction's unsymmetric mechanics, alone or as the first part of a
//!   one-way split. The friction tangent has the symmetric pattern of the frictionless one, so
//!   it is factorised without pivoting in the same nested-dissection order ([`StaticLu`]:
//!   twice LDLᵀ's entries), by faer's partially pivoted LU (fill bounded by AᵀA's pattern)
//!   only where a pivot vanishes in that order. A factor is kept across Newton iterations
//!   while it preconditions the newer tangents within the GMRES iterations a factorisation
//!   is worth (none for a small factor), or the tangent is refactorised. A factor of more
//!   than `SINGLE_LU_ENTRIES` is held in single precision (a pivot it refuses: the same
//!   factor in double first). In the block preconditioner above, friction's mechanics block
//!   is factorised the same way in single precision, at every factorisation.

mod block;
mod gmres;
mod lag;
mod ldlt;
mod lu;
mod ordering;
pub mod static_lu;
mod submatrix;
#[cfg(test)]
mod tests;
mod tree;

use crate::dofs::{Pattern, Structure};
use block::BlockTriangular;
use faer::Par;
pub use gmres::gmres;
pub use lag::SolveParts;
use ldlt::{Precision, SymFactor};
use lu::{LaggedLu, SINGLE_LU_ENTRIES};
use ordering::nodes_of;
use submatrix::SubMatrix;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LinearKind {
    Lu,
    Ldlt,
    BlockGmres,
    /// PETSc's KSP, chosen by its options (`[solver] engine = "petsc"`, or several ranks).
    Petsc,
}

/// What a factor's elimination tree predicts on some number of threads: the numeric
/// factorisation's speed-up (its multiply-adds on the critical path against all of them) and a
/// solve's (the factor's entries it reads, likewise). Bounds: memory bandwidth, the tasks'
/// start and the threads' waits only lower them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Speedup {
    pub factor: f64,
    pub solve: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum LinearError {
    #[error("symbolic analysis failed: {0}")]
    Symbolic(String),
    #[error("factorisation failed (singular or indefinite tangent): {0}")]
    Factor(String),
    #[error("GMRES did not converge in {iterations} iterations (relative residual {residual:.1e})")]
    Krylov { iterations: usize, residual: f64 },
    /// The distributed engine failed, or was asked for without being built in.
    #[error("{0}")]
    Engine(String),
    /// The distributed engine's iterative solver did not converge.
    #[error("{0}")]
    Diverged(String),
}

impl LinearError {
    /// Whether a smaller load step may succeed where this failed: not when the set-up or the
    /// engine itself failed, whatever the matrix.
    pub fn recoverable(&self) -> bool {
        !matches!(self, LinearError::Symbolic(_) | LinearError::Engine(_))
    }
}

/// One system's solver as an engine makes it: a numeric factorisation (or a preconditioner's
/// set-up) per tangent, then solves. [`LinearSolver`] holds one and counts its Krylov
/// iterations; an engine is a way of making them (`super::engine`).
pub trait Factorization: Send {
    /// Take the matrix with the analysed pattern and these `values` (the whole system's; on
    /// several ranks, this rank's part).
    fn factor(&mut self, values: &[f64]) -> Result<(), LinearError>;
    /// b → A⁻¹ b in place with the last factorisation; the Krylov iterations it took (0 for
    /// a direct solve).
    fn solve(&mut self, b: &mut [f64]) -> Result<usize, LinearError>;
    /// Entries of the factor(s) as the symbolic analysis laid them out, before any numeric
    /// work; `None` where the engine lays its factor out when it factorises.
    fn entries(&self) -> Option<usize> {
        None
    }
    /// Bytes of those entries' values, in the precision each factor is held in.
    fn factor_bytes(&self) -> Option<usize> {
        None
    }
    /// The engine's own words for its solver and preconditioner, where it has them.
    fn describe(&self) -> Option<String> {
        None
    }
    /// The speed-ups on `threads` threads its elimination tree predicts, where the engine
    /// works over the tree.
    fn predicted_speedup(&self, _threads: f64) -> Option<Speedup> {
        None
    }
    /// The engine, as `summary.json` names it.
    fn engine(&self) -> &'static str {
        "faer"
    }
    /// Whether the next tangent is near the last (Newton's residual is small, or a step
    /// starts from a converged state): an engine that may keep an older factor as the
    /// preconditioner of a newer tangent does so only then.
    fn set_near(&mut self, _near: bool) {}
    /// Numeric factorisations so far, where the engine may keep a factor across calls of
    /// [`Factorization::factor`] (`None`: each call is one).
    fn factorisations(&self) -> Option<usize> {
        None
    }
    /// Seconds in its factorisations and preconditioner applications so far, where the
    /// engine times them apart.
    fn parts(&self) -> Option<SolveParts> {
        None
    }
}

/// Relative residual at which GMRES stops, and its iteration budget.
const GMRES_TOL: f64 = 1e-10;
/// Relative residual at which a solve with a factor kept through Newton's damped iterations
/// stops (a [`Lag::dear`] factor, of a tangent that is not near it). Those updates are
/// halved while their residual grows and corrected by the next iteration: on Table 2's 147k
/// row, where a factorisation costs 24 GMRES iterations, three digits take 83 Newton
/// iterations where ten took 81, and 33 factorisations where they took 59 (the gap the same
/// to 5.5e-13); two digits reject a step.
const DAMPED_TOL: f64 = 1e-3;
/// Relative residual below which a solve with a fresh factor that stagnated short of
/// [`GMRES_TOL`] within [`GMRES_MAX`] iterations is still used as Newton's update. Newton
/// checks the nonlinear residual it leads to anyway, and an update solved to η shrinks that
/// residual by about η at worst (inexact Newton). Where a nearly singular mechanics block
/// amplifies the coupling the block-triangular preconditioner leaves out (a prescribed
/// patch's corner on a fine mesh), restarted GMRES stalls between 1e-10 and 1e-7.
const GMRES_USABLE: f64 = 1e-6;
const GMRES_RESTART: usize = 60;
const GMRES_MAX: usize = 300;
/// Factors with more entries than this are computed and applied with all threads.
const PARALLEL_FACTOR_NNZ: usize = 30_000_000;

/// faer's parallelism for a dense product or factorisation: every thread of the pool, but no
/// more than the CPUs this process may use. faer's threads meet at barriers they spin on; more
/// of them than CPUs take their time slices from the ones with work (16 threads on 2 CPUs
/// made a run six times slower).
pub(super) fn dense_par() -> Par {
    match rayon::current_num_threads().min(crate::threads::usable_cpus()) {
        0 | 1 => Par::Seq,
        n => Par::rayon(n),
    }
}

/// A sparse direct solver for a fixed pattern.
pub struct LinearSolver {
    pub kind: LinearKind,
    backend: Box<dyn Factorization>,
    /// Krylov iterations of the last solve and since the last `take_krylov` (0 for direct).
    pub krylov_last: usize,
    krylov_count: usize,
    /// Calls of `factor`, and the factorisations already counted by `take_factorisations`.
    factor_calls: usize,
    factorisations_taken: usize,
    parts_taken: SolveParts,
}

impl LinearSolver {
    /// Entries of the factor(s) as the symbolic analysis laid them out, before any numeric
    /// work (an LU that falls back to partial pivoting has other fill); `None` on PETSc, which
    /// lays its factor out when it factorises.
    pub fn factor_entries(&self) -> Option<usize> {
        self.backend.entries()
    }

    /// The speed-ups on `threads` threads its elimination tree predicts
    /// ([`Factorization::predicted_speedup`]).
    pub fn predicted_speedup(&self, threads: f64) -> Option<Speedup> {
        self.backend.predicted_speedup(threads)
    }

    /// Bytes of the factor(s)' values, each in its precision (single where
    /// [`LinearSolver::factor_entries`] counts a single-precision factor); `None` on PETSc.
    pub fn factor_bytes(&self) -> Option<usize> {
        self.backend.factor_bytes()
    }

    /// Symbolic analysis of the pattern (once per mesh).
    pub fn new(kind: LinearKind, p: &Pattern, s: &Structure) -> Result<LinearSolver, LinearError> {
        let all: Vec<usize> = (0..p.n).collect();
        match kind {
            LinearKind::Lu => Self::block_lu(p, s, &all),
            LinearKind::Ldlt => Self::block_ldlt(p, s, &all),
            LinearKind::BlockGmres => Self::block_gmres(p, s, false),
            LinearKind::Petsc => Err(LinearError::Engine(
                "the PETSc engine sets up its solvers itself (solver::engine::Petsc)".into(),
            )),
        }
    }

    /// LDLᵀ of the symmetric sub-block of equations `eqs` (increasing): `factor` takes the
    /// whole system's values, `solve` vectors of `eqs.len()`.
    pub fn block_ldlt(
        p: &Pattern,
        s: &Structure,
        eqs: &[usize],
    ) -> Result<LinearSolver, LinearError> {
        let sub = SubMatrix::new(p, eqs, eqs);
        let nodes = nodes_of(s, eqs);
        let backend = SymFactor::new(sub, &nodes, Precision::Double)?;
        Ok(Self::with(LinearKind::Ldlt, Box::new(backend)))
    }

    /// GMRES with the block-triangular preconditioner, its mechanics block factorised by LU
    /// where it is `unsymmetric` (friction), by LDLᵀ otherwise.
    pub fn block_gmres(
        p: &Pattern,
        s: &Structure,
        unsymmetric: bool,
    ) -> Result<LinearSolver, LinearError> {
        let backend = BlockTriangular::new(p, s, unsymmetric)?;
        Ok(Self::with(LinearKind::BlockGmres, Box::new(backend)))
    }

    /// LU of the (unsymmetric) sub-block of equations `eqs` (increasing): `factor` takes the
    /// whole system's values, `solve` vectors of `eqs.len()`.
    pub fn block_lu(
        p: &Pattern,
        s: &Structure,
        eqs: &[usize],
    ) -> Result<LinearSolver, LinearError> {
        let sub = SubMatrix::new(p, eqs, eqs);
        let lu: LaggedLu<f64> = LaggedLu::new(sub, &nodes_of(s, eqs));
        let backend: Box<dyn Factorization> = if lu.staticlu.entries() > SINGLE_LU_ENTRIES {
            Box::new(lu.in_precision::<f32>())
        } else {
            Box::new(lu)
        };
        Ok(Self::with(LinearKind::Lu, backend))
    }

    /// The engine's own words for its solver and preconditioner (PETSc's `ksp_type/pc_type`),
    /// where it has them.
    pub fn engine_solver(&self) -> Option<String> {
        self.backend.describe()
    }

    /// The engine, as `summary.json` names it.
    pub fn engine(&self) -> &'static str {
        self.backend.engine()
    }

    /// The engine and its method, in words (what `tmc check` says a solve will use).
    pub fn method(&self) -> String {
        let how = self.backend.describe().unwrap_or_else(|| {
            match self.kind {
                LinearKind::Ldlt => "LDLᵀ in nested-dissection order",
                LinearKind::Lu => "LU without row exchanges in nested-dissection order (single precision above 10⁶ entries), with GMRES",
                LinearKind::BlockGmres => {
                    "GMRES preconditioned by the block-triangular factor (LDLᵀ or LU blocks in single precision)"
                }
                LinearKind::Petsc => "KSP",
            }
            .to_string()
        });
        format!("{} {how}", self.engine())
    }

    /// A solver of the `kind` an engine made.
    pub fn with(kind: LinearKind, backend: Box<dyn Factorization>) -> LinearSolver {
        LinearSolver {
            kind,
            backend,
            krylov_last: 0,
            krylov_count: 0,
            factor_calls: 0,
            factorisations_taken: 0,
            parts_taken: SolveParts::default(),
        }
    }

    /// Numeric factorisation of the matrix with this pattern and `values`.
    pub fn factor(&mut self, values: &[f64]) -> Result<(), LinearError> {
        self.factor_calls += 1;
        self.backend.factor(values)
    }

    /// Numeric factorisations since the last call (fewer than the calls of `factor` where
    /// the engine kept an older factor).
    pub fn take_factorisations(&mut self) -> usize {
        let total = self.backend.factorisations().unwrap_or(self.factor_calls);
        total - std::mem::replace(&mut self.factorisations_taken, total)
    }

    /// Seconds in factorisations and preconditioner applications since the last call, where
    /// the engine times them apart.
    pub fn take_parts(&mut self) -> Option<SolveParts> {
        let total = self.backend.parts()?;
        Some(total - std::mem::replace(&mut self.parts_taken, total))
    }

    /// Whether the tangents factorised next are near the last ([`Factorization::set_near`]).
    pub fn set_near(&mut self, near: bool) {
        self.backend.set_near(near);
    }

    /// Solve A x = b in place (b → x) with the last factorisation.
    pub fn solve(&mut self, b: &mut [f64]) -> Result<(), LinearError> {
        self.krylov_last = 0;
        let its = self.backend.solve(b)?;
        self.krylov_last = its;
        self.krylov_count += its;
        Ok(())
    }

    /// Krylov iterations since the last call.
    pub fn take_krylov(&mut self) -> usize {
        std::mem::take(&mut self.krylov_count)
    }
}
