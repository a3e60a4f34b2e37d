//! LU of an unsymmetric block (friction's mechanics), kept across tangents while it
//! preconditions them within its budget.

use super::lag::{Lag, Lagged, lag_budget, solve_lagged};
use super::ordering::{Nodes, fill_reducing};
use super::static_lu::{Real, StaticLu};
use super::submatrix::SubMatrix;
use super::{Factorization, LinearError};
use faer::MatMut;
use faer::linalg::solvers::Solve;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};

/// An LU factor (of a whole system or of a part, not of a preconditioner's block) with more
/// entries than this is held in single precision: above it the factorisations and the
/// triangular solves stream the factor from memory, and halving it pays for the extra GMRES
/// products its rounding costs. Measured on the friction scenes (wall time, single against
/// double): 28 k and 167 k entries (2D) 1.08×, 440 k (3D) 1.03×, 2.3 M (3D) 0.91×.
pub(super) const SINGLE_LU_ENTRIES: usize = 1_000_000;

impl<T: Real> Lagged for LaggedLu<T> {
    fn lag(&self) -> &Lag {
        &self.lag
    }
    fn lag_mut(&mut self) -> &mut Lag {
        &mut self.lag
    }
    fn mul(&self, x: &[f64], y: &mut [f64]) {
        self.sub.mul(x, y)
    }
    fn precondition(&self, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
        self.apply(z)
    }
    fn refactor(&mut self) -> Result<(), LinearError> {
        LaggedLu::refactor(self)
    }
}

/// LU of an unsymmetric block, refactored only when its last factor no longer preconditions
/// the current tangent well: between Newton iterations a tangent moves little, so GMRES with
/// the last factor as its preconditioner reaches [`GMRES_TOL`] in a few products, each far
/// cheaper than a factorisation. A factor that needs more iterations than it is worth
/// ([`lag_budget`]) is refactored with the current values.
///
/// The factor is [`StaticLu`]: no pivoting, in the nested-dissection order of the symmetric
/// pattern, so its entries are twice LDLᵀ's. Where a pivot vanishes in that order (in single
/// precision: the same factor in double first), faer's LU with partial pivoting (fill bounded
/// by the pattern of AᵀA) takes over for that factor.
/// Every solve runs GMRES with the factor (one or two products with a fresh one), so a factor
/// whose static pivots lost digits still gives the solution to [`GMRES_TOL`].
pub(super) struct LaggedLu<T: Real> {
    /// The block's pattern and the current tangent's values; whether the factor is theirs.
    pub(super) sub: SubMatrix,
    pub(super) staticlu: StaticLu<T>,
    /// The same layout in double, made when a single-precision factorisation first refuses a
    /// pivot.
    pub(super) double: Option<StaticLu<f64>>,
    /// faer's symbolic analysis for the pivoted LU, made when a factorisation first needs it.
    pub(super) symbolic: Option<SymbolicLu<usize>>,
    /// The factor the last factorisation left.
    pub(super) held: Held,
    /// Budget ([`lag_budget`]) and state of the factor held.
    pub(super) lag: Lag,
}

/// Which factor of a [`LaggedLu`] holds the last factorisation.
pub(super) enum Held {
    /// Its static-pivot factor, in its precision.
    Static,
    /// The static-pivot factor in double (single precision refused a pivot).
    Double,
    /// faer's partially pivoted LU (a pivot vanished in the static order).
    Pivoted(Box<Lu<usize, f64>>),
}

impl<T: Real> LaggedLu<T> {
    /// Bytes of the factor's values, in `T`.
    pub(super) fn bytes(&self) -> usize {
        self.staticlu.entries() * std::mem::size_of::<T>()
    }

    /// `nodes`: the mesh node of each of the block's equations, and how to order them (the
    /// elimination order keeps a node's unknowns together).
    pub(super) fn new(sub: SubMatrix, nodes: &Nodes) -> LaggedLu<T> {
        let (fwd, _) = fill_reducing(&sub.pattern, nodes);
        let staticlu = StaticLu::<T>::new(&sub.pattern, &fwd);
        LaggedLu {
            lag: Lag::new(lag_budget(&staticlu, &sub)),
            staticlu,
            sub,
            double: None,
            symbolic: None,
            held: Held::Static,
        }
    }

    /// The same block and layout, its factor held in precision `U`.
    pub(super) fn in_precision<U: Real>(self) -> LaggedLu<U> {
        LaggedLu {
            lag: Lag::new(self.lag.budget),
            staticlu: self.staticlu.in_precision(),
            sub: self.sub,
            double: None,
            symbolic: self.symbolic,
            held: Held::Static,
        }
    }

    pub(super) fn refactor(&mut self) -> Result<(), LinearError> {
        self.lag.factoring();
        self.held = self.factor_held()?;
        self.lag.factored_now();
        Ok(())
    }

    /// Factorise the current values: without pivoting in `T`, then (for single precision)
    /// in double, then with partial pivoting.
    pub(super) fn factor_held(&mut self) -> Result<Held, LinearError> {
        let values = &self.sub.values;
        if self.staticlu.factor(values).is_ok() {
            return Ok(Held::Static);
        }
        if T::EPS > f64::EPSILON {
            let staticlu = &self.staticlu;
            let double = self.double.get_or_insert_with(|| staticlu.in_precision());
            if double.factor(values).is_ok() {
                return Ok(Held::Double);
            }
        }
        let pattern = self.sub.pattern.as_ref();
        let symbolic = match &mut self.symbolic {
            Some(s) => s,
            none => none.insert(
                SymbolicLu::try_new(pattern)
                    .map_err(|e| LinearError::Symbolic(format!("{e:?}")))?,
            ),
        };
        let a = SparseColMatRef::new(pattern, values);
        let lu = Lu::try_new_with_symbolic(symbolic.clone(), a)
            .map_err(|e| LinearError::Factor(format!("{e:?}")))?;
        Ok(Held::Pivoted(Box::new(lu)))
    }

    /// b → A⁻¹ b with the factor held, of the current values or of earlier ones.
    pub(super) fn apply(&self, b: &mut [f64]) {
        let n = b.len();
        match &self.held {
            Held::Static => self.staticlu.solve(b),
            Held::Double => self.double.as_ref().expect("factored in double").solve(b),
            Held::Pivoted(lu) => lu.solve_in_place(MatMut::from_column_major_slice_mut(b, n, 1)),
        }
    }
}

impl<T: Real> Factorization for LaggedLu<T> {
    /// Take the whole system's `values` as the current tangent; factorised at once the first
    /// time and wherever no lag is worth it, otherwise only when the last factor no longer
    /// solves with it.
    fn factor(&mut self, values: &[f64]) -> Result<(), LinearError> {
        self.sub.update(values);
        if self.lag.next_tangent(true) {
            self.refactor()?;
        }
        Ok(())
    }

    /// b → A⁻¹ b; the Krylov iterations it took.
    fn solve(&mut self, b: &mut [f64]) -> Result<usize, LinearError> {
        solve_lagged(self, b)
    }

    fn factorisations(&self) -> Option<usize> {
        Some(self.lag.count)
    }

    fn parts(&self) -> Option<super::SolveParts> {
        Some(self.lag.parts)
    }

    fn entries(&self) -> Option<usize> {
        Some(self.staticlu.entries())
    }

    fn factor_bytes(&self) -> Option<usize> {
        Some(self.bytes())
    }
}
