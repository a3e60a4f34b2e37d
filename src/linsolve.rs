//! Sparse linear solvers behind one small interface: symbolic analysis once per pattern,
//! numeric factorisation per Newton iteration, then solves.
//!
//! - [`LinearKind::Ldlt`]: faer's sparse LDLᵀ (symmetric tangents: mechanics alone, conduction
//!   alone), fill-reducing AMD ordering.
//! - [`LinearKind::Lu`]: faer's sparse LU with partial pivoting (unsymmetric coupled tangents).
//!   It fills in far more than LDLᵀ in 3D (see SOLVERS.md); use it for small systems.

use crate::assembly::Pattern;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::cholesky::{
    LdltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LinearKind {
    Lu,
    Ldlt,
}

#[derive(Debug, thiserror::Error)]
pub enum LinearError {
    #[error("symbolic analysis failed: {0}")]
    Symbolic(String),
    #[error("factorisation failed (singular or indefinite tangent): {0}")]
    Factor(String),
}

enum Backend {
    Lu {
        symbolic: SymbolicLu<usize>,
        numeric: Option<Lu<usize, f64>>,
    },
    Ldlt {
        symbolic: SymbolicCholesky<usize>,
        l_values: Vec<f64>,
        factored: bool,
    },
}

/// A sparse direct solver for a fixed pattern.
pub struct LinearSolver {
    pub kind: LinearKind,
    pattern: SymbolicSparseColMat<usize>,
    backend: Backend,
    par: Par,
}

impl LinearSolver {
    /// Symbolic analysis of the pattern (once per mesh).
    pub fn new(kind: LinearKind, p: &Pattern) -> Result<LinearSolver, LinearError> {
        let pattern =
            SymbolicSparseColMat::new_checked(p.n, p.n, p.col_ptr.clone(), None, p.row_idx.clone());
        let backend = match kind {
            LinearKind::Lu => Backend::Lu {
                symbolic: SymbolicLu::try_new(pattern.as_ref())
                    .map_err(|e| LinearError::Symbolic(format!("{e:?}")))?,
                numeric: None,
            },
            LinearKind::Ldlt => {
                let symbolic = factorize_symbolic_cholesky(
                    pattern.as_ref(),
                    Side::Lower,
                    SymmetricOrdering::Amd,
                    Default::default(),
                )
                .map_err(|e| LinearError::Symbolic(format!("{e:?}")))?;
                Backend::Ldlt {
                    l_values: vec![0.0; symbolic.len_val()],
                    symbolic,
                    factored: false,
                }
            }
        };
        Ok(LinearSolver {
            kind,
            pattern,
            backend,
            par: Par::rayon(0),
        })
    }

    /// Numeric factorisation of the matrix with this pattern and `values`.
    pub fn factor(&mut self, values: &[f64]) -> Result<(), LinearError> {
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        match &mut self.backend {
            Backend::Lu { symbolic, numeric } => {
                *numeric = None;
                let lu = Lu::try_new_with_symbolic(symbolic.clone(), a)
                    .map_err(|e| LinearError::Factor(format!("{e:?}")))?;
                *numeric = Some(lu);
            }
            Backend::Ldlt {
                symbolic,
                l_values,
                factored,
            } => {
                *factored = false;
                let mut mem = MemBuffer::new(
                    symbolic.factorize_numeric_ldlt_scratch::<f64>(self.par, Default::default()),
                );
                symbolic
                    .factorize_numeric_ldlt(
                        l_values,
                        a,
                        Side::Lower,
                        Default::default(),
                        self.par,
                        MemStack::new(&mut mem),
                        Default::default(),
                    )
                    .map_err(|e| LinearError::Factor(format!("{e:?}")))?;
                *factored = true;
            }
        }
        Ok(())
    }

    /// Solve A x = b in place (b → x) with the last factorisation.
    pub fn solve(&self, b: &mut [f64]) {
        let n = b.len();
        let rhs = MatMut::from_column_major_slice_mut(b, n, 1);
        match &self.backend {
            Backend::Lu { numeric, .. } => {
                numeric
                    .as_ref()
                    .expect("factored before solve")
                    .solve_in_place(rhs);
            }
            Backend::Ldlt {
                symbolic,
                l_values,
                factored,
            } => {
                assert!(*factored, "factored before solve");
                let mut mem = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, self.par));
                LdltRef::new(symbolic, l_values).solve_in_place_with_conj(
                    Conj::No,
                    rhs,
                    self.par,
                    MemStack::new(&mut mem),
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1D Laplacian plus a small unsymmetric perturbation for LU.
    fn system(n: usize, unsym: f64) -> (Pattern, Vec<f64>) {
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut vals = Vec::new();
        for j in 0..n {
            for i in j.saturating_sub(1)..(j + 2).min(n) {
                row_idx.push(i);
                vals.push(if i == j {
                    2.0
                } else if i < j {
                    -1.0 + unsym
                } else {
                    -1.0
                });
            }
            col_ptr.push(row_idx.len());
        }
        (
            Pattern {
                n,
                col_ptr,
                row_idx,
            },
            vals,
        )
    }

    fn residual(p: &Pattern, v: &[f64], x: &[f64], b: &[f64]) -> f64 {
        let mut r = b.to_vec();
        for j in 0..p.n {
            for k in p.col_ptr[j]..p.col_ptr[j + 1] {
                r[p.row_idx[k]] -= v[k] * x[j];
            }
        }
        r.iter().map(|v| v.abs()).fold(0.0, f64::max)
    }

    #[test]
    fn both_solvers_solve_and_refactor() {
        for (kind, unsym) in [(LinearKind::Ldlt, 0.0), (LinearKind::Lu, 0.3)] {
            let (p, mut v) = system(50, unsym);
            let mut s = LinearSolver::new(kind, &p).unwrap();
            for round in 0..2 {
                if round == 1 {
                    v.iter_mut().for_each(|a| *a *= 1.7); // same pattern, new values
                }
                s.factor(&v).unwrap();
                let b: Vec<f64> = (0..50).map(|i| (i as f64).sin()).collect();
                let mut x = b.clone();
                s.solve(&mut x);
                assert!(residual(&p, &v, &x, &b) < 1e-12, "{kind:?}");
            }
        }
    }
}
