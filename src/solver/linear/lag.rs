//! When a factor may be kept across tangents: its price in GMRES iterations, its budget,
//! and the solve that refactorises where the budget runs out.

use super::gmres::gmres;
use super::static_lu::{Real, StaticLu};
use super::submatrix::SubMatrix;
use super::{GMRES_MAX, GMRES_RESTART, GMRES_TOL, GMRES_USABLE, LinearError};
use std::cell::Cell;
use std::time::Instant;

/// GMRES iterations a lagged LU factor may take at most to solve with a newer tangent before
/// it is refactored (each iteration: a product with the matrix and a solve with the factor).
/// Measured on sphere-drag (a factor of 2.3 M entries): 4, 8, 12 and 24 iterations took
/// 27.2, 26.0, 25.5 and 27.9 s.
pub(super) const LAG_MAX_ITS: usize = 12;

/// How many times faster, per floating-point operation, a factorisation runs (dense blocks of
/// supernodes) than a GMRES iteration with its factor (sparse products and triangular solves,
/// bound by memory): the factor's price in iterations is its operations over an iteration's,
/// divided by this. Measured on this machine: lagging pays from about 12 iterations' price
/// (sphere-drag, 155 iterations' operations: best at 8–12) and not at 10 (friction-heating:
/// never lagging took 0.64 s against 0.71 s with up to 12 iterations).
pub(super) const FACTOR_SPEEDUP: f64 = 12.0;

/// The GMRES iterations worth one factorisation of `lu` for the block `sub`, at most
/// [`LAG_MAX_ITS`]: a lagged factor that needs more costs more than refactoring would have
/// (0: a factor this cheap is never lagged).
pub(super) fn lag_budget<T: Real>(lu: &StaticLu<T>, sub: &SubMatrix) -> usize {
    let (n, nnz) = (sub.pattern.nrows(), sub.values.len());
    budget_of(factor_price(lu.flops(), 2.0 * lu.entries() as f64, n, nnz))
}

/// The GMRES iterations on a matrix of `n` rows and `nnz` entries worth a factorisation of
/// `factor_flops` operations, when applying the factor takes `apply_flops` (not capped:
/// [`budget_of`] caps a lag's budget). Both as on one thread: the price must not change with
/// the threads ([`super::block::block_lag_price`]).
pub(super) fn factor_price(factor_flops: f64, apply_flops: f64, n: usize, nnz: usize) -> f64 {
    // the factor's solves, a product with A, and the orthogonalisation of a restart's dozen
    // vectors
    let iteration = apply_flops + 2.0 * nnz as f64 + 30.0 * n as f64;
    factor_flops / iteration / FACTOR_SPEEDUP
}

/// A lag's budget for a factor worth `price` iterations: at most [`LAG_MAX_ITS`].
pub(super) fn budget_of(price: f64) -> usize {
    (price.floor() as usize).min(LAG_MAX_ITS)
}

/// Whether a factor that may be kept across tangents is of the current one, its budget
/// ([`lag_budget`], [`block_lag_price`]) and the factorisations so far.
pub(super) struct Lag {
    /// GMRES iterations a factor of an older tangent may take (0: never kept).
    pub(super) budget: usize,
    pub(super) factored: bool,
    /// The factor is of the current values.
    pub(super) current: bool,
    pub(super) count: usize,
    /// A factorisation is worth more iterations than a lag may take ([`LAG_MAX_ITS`]): the
    /// factor is kept through Newton's damped iterations too (solved there to
    /// [`Lag::tol`]), a solve with an older factor gives up as soon as it falls behind
    /// ([`gmres`]'s `give_up`), and the new factor's solve goes on from its iterate.
    pub(super) dear: bool,
    /// Relative residual a solve with an older factor must reach: [`GMRES_TOL`], or
    /// [`DAMPED_TOL`] for a dear factor through damped iterations.
    pub(super) tol: f64,
    /// Seconds in the factorisations and the factor's applications so far, and when the
    /// factorisation under way began.
    pub(super) parts: SolveParts,
    started: Option<Instant>,
}

/// Where a solver's seconds went: its numeric factorisations, and the applications of its
/// factors (a direct solve's triangular solves, GMRES's preconditioner); the rest of a Krylov
/// solve is its products with the matrix and its orthogonalisation.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolveParts {
    pub factorising: f64,
    pub applying: f64,
}

impl std::ops::Sub for SolveParts {
    type Output = SolveParts;
    fn sub(self, o: SolveParts) -> SolveParts {
        SolveParts {
            factorising: self.factorising - o.factorising,
            applying: self.applying - o.applying,
        }
    }
}

impl std::ops::AddAssign for SolveParts {
    fn add_assign(&mut self, o: SolveParts) {
        self.factorising += o.factorising;
        self.applying += o.applying;
    }
}

impl Lag {
    pub(super) fn new(budget: usize) -> Lag {
        Lag {
            budget,
            factored: false,
            current: false,
            count: 0,
            dear: false,
            tol: GMRES_TOL,
            parts: SolveParts::default(),
            started: None,
        }
    }

    /// The lag of a factor worth `price` GMRES iterations.
    pub(super) fn priced(price: f64) -> Lag {
        Lag {
            dear: price >= LAG_MAX_ITS as f64,
            ..Lag::new(budget_of(price))
        }
    }

    /// A new tangent arrived: whether it must be factorised at once (the first, where no
    /// lag is worth it, or where it is not `near` the factor held).
    pub(super) fn next_tangent(&mut self, near: bool) -> bool {
        self.current = false;
        !self.factored || self.budget == 0 || !near
    }

    /// Around a factorisation: `factoring` before, `factored_now` after it succeeded.
    pub(super) fn factoring(&mut self) {
        self.factored = false;
        self.started = Some(Instant::now());
    }

    pub(super) fn factored_now(&mut self) {
        self.factored = true;
        self.current = true;
        self.count += 1;
        if let Some(t) = self.started.take() {
            self.parts.factorising += t.elapsed().as_secs_f64();
        }
    }
}

/// A solver whose factor may be of an older tangent than the matrix it solves with.
pub(super) trait Lagged {
    /// Whether the factor is of the current matrix, and the budget of an older one.
    fn lag(&self) -> &Lag;
    /// The same, to add a solve's seconds to.
    fn lag_mut(&mut self) -> &mut Lag;
    /// y = A x with the current matrix.
    fn mul(&self, x: &[f64], y: &mut [f64]);
    /// z = M⁻¹ r with the factor held.
    fn precondition(&self, r: &[f64], z: &mut [f64]);
    /// Factorise the current matrix.
    fn refactor(&mut self) -> Result<(), LinearError>;
}

/// b → A⁻¹ b by GMRES with the factor held: within the lag's budget where the factor is of an
/// older tangent, refactorised and solved again where that budget runs out (from zero, or
/// for a dear factor from where the older one left it). The Krylov iterations of both
/// attempts.
pub(super) fn solve_lagged(l: &mut impl Lagged, b: &mut [f64]) -> Result<usize, LinearError> {
    let rhs = b.to_vec();
    b.fill(0.0);
    let mut spent = 0;
    loop {
        let lag = l.lag();
        let (tol, budget, give_up) = if lag.current {
            (GMRES_TOL, GMRES_MAX, false)
        } else {
            (lag.tol, lag.budget, lag.dear)
        };
        let this = &*l;
        let applying = Cell::new(0.0);
        let out = gmres(
            &|x: &[f64], y: &mut [f64]| this.mul(x, y),
            &|r: &[f64], z: &mut [f64]| {
                let t = Instant::now();
                this.precondition(r, z);
                applying.set(applying.get() + t.elapsed().as_secs_f64());
            },
            &rhs,
            b,
            tol,
            GMRES_RESTART.min(budget),
            budget,
            give_up,
        );
        l.lag_mut().parts.applying += applying.get();
        match out {
            Ok(its) => return Ok(spent + its),
            Err((its, residual)) if l.lag().current && residual <= GMRES_USABLE => {
                return Ok(spent + its);
            }
            Err((iterations, residual)) if l.lag().current => {
                return Err(LinearError::Krylov {
                    iterations: spent + iterations,
                    residual,
                });
            }
            Err((its, _)) => {
                spent += its;
                if !l.lag().dear {
                    b.fill(0.0);
                }
                l.refactor()?;
            }
        }
    }
}
