//! Symmetric LDLᵀ of a sub-block, in double or single precision, on faer's supernodal
//! factorisation.

use super::ordering::{Nodes, fill_reducing};
use super::static_lu::Real;
use super::submatrix::SubMatrix;
use super::tree::TreeLdlt;
use super::{Factorization, LinearError, PARALLEL_FACTOR_NNZ, SolveParts};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::perm::PermRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Par, Side};

impl Factorization for SymFactor {
    fn factor(&mut self, values: &[f64]) -> Result<(), LinearError> {
        let t = std::time::Instant::now();
        SymFactor::factor(self, values)?;
        self.parts.factorising += t.elapsed().as_secs_f64();
        Ok(())
    }

    fn solve(&mut self, b: &mut [f64]) -> Result<usize, LinearError> {
        let t = std::time::Instant::now();
        SymFactor::solve(self, b);
        self.parts.applying += t.elapsed().as_secs_f64();
        Ok(0)
    }

    fn parts(&self) -> Option<SolveParts> {
        Some(self.parts)
    }

    fn entries(&self) -> Option<usize> {
        Some(self.symbolic.len_val())
    }

    fn factor_bytes(&self) -> Option<usize> {
        Some(self.bytes())
    }

    fn predicted_speedup(&self, threads: f64) -> Option<super::Speedup> {
        self.tree.as_ref().map(|t| t.speedups(threads))
    }
}

/// The precision of an LDLᵀ factor: double for direct solves, single where the factor only
/// preconditions GMRES (which keeps the residual in double): half the memory traffic and
/// twice the SIMD width, for a few more Krylov iterations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Precision {
    Double,
    Single,
}

/// Symmetric LDLᵀ of a square sub-block, ordered by nested dissection of its node graph. The
/// factor and the scratch of factorisation and solve are allocated once.
pub(super) struct SymFactor {
    pub(super) sub: SubMatrix,
    pub(super) symbolic: SymbolicCholesky<usize>,
    /// The numeric factorisation over the elimination tree (`None`: a simplicial analysis).
    pub(super) tree: Option<TreeLdlt>,
    pub(super) precision: Precision,
    pub(super) par: Par,
    /// Seconds in its factorisations and solves as a whole system's solver.
    pub(super) parts: SolveParts,
    pub(super) l64: Vec<f64>,
    pub(super) l32: Vec<f32>,
    pub(super) a32: Vec<f32>,
    pub(super) factor_mem: MemBuffer,
    /// Solve scratch and, in single precision, the right-hand side in f32.
    pub(super) solve_mem: std::cell::RefCell<(MemBuffer, Vec<f32>)>,
    /// The tree solve's permuted unknowns, in either precision.
    pub(super) x: std::cell::RefCell<(Vec<f64>, Vec<f32>)>,
    pub(super) factored: bool,
}

impl SymFactor {
    /// `nodes`: the mesh node of each of the sub-block's equations, and how to order them.
    pub(super) fn new(
        sub: SubMatrix,
        nodes: &Nodes,
        precision: Precision,
    ) -> Result<SymFactor, LinearError> {
        let n = sub.pattern.nrows();
        let (fwd, inv) = fill_reducing(&sub.pattern, nodes);
        let perm = PermRef::new_checked(&fwd, &inv, n);
        let symbolic = factorize_symbolic_cholesky(
            sub.pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Custom(perm),
            // supernodal at every size: faer's own choice, simplicial below 40 flops per
            // entry of L (2D meshes up to some 10⁴ unknowns), factors column by column with
            // no dense kernel and 1.4 to 3.7 times slower (docs/notes/2026-12-03-supernodal-
            // at-every-size.md); and the tree's threads work only on a supernodal analysis
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| LinearError::Symbolic(format!("{e:?}")))?;
        // threads pay only for large dense fronts: below this, their synchronisation costs
        // more than it saves (measured on 2 cores, 15k 3D unknowns: 24.6 s → 17.1 s sequential)
        let par = if symbolic.len_val() > PARALLEL_FACTOR_NNZ {
            super::dense_par()
        } else {
            Par::Seq
        };
        let single = precision == Precision::Single;
        let tree = TreeLdlt::new(&symbolic, &sub.pattern);
        // faer's scratch, where faer factors and solves
        let (factor_mem, solve_mem) = if tree.is_some() {
            (StackReq::EMPTY, StackReq::EMPTY)
        } else if single {
            (
                symbolic.factorize_numeric_ldlt_scratch::<f32>(par, Default::default()),
                symbolic.solve_in_place_scratch::<f32>(1, par),
            )
        } else {
            (
                symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
                symbolic.solve_in_place_scratch::<f64>(1, par),
            )
        };
        let len = symbolic.len_val();
        Ok(SymFactor {
            tree,
            parts: SolveParts::default(),
            l64: if single { Vec::new() } else { vec![0.0; len] },
            l32: if single { vec![0.0; len] } else { Vec::new() },
            a32: if single {
                vec![0.0; sub.values.len()]
            } else {
                Vec::new()
            },
            factor_mem: MemBuffer::new(factor_mem),
            solve_mem: std::cell::RefCell::new((
                MemBuffer::new(solve_mem),
                vec![0.0; if single { n } else { 0 }],
            )),
            x: Default::default(),
            symbolic,
            precision,
            par,
            sub,
            factored: false,
        })
    }

    /// Bytes of the factor's values, in its precision.
    pub(super) fn bytes(&self) -> usize {
        self.symbolic.len_val()
            * match self.precision {
                Precision::Double => std::mem::size_of::<f64>(),
                Precision::Single => std::mem::size_of::<f32>(),
            }
    }

    /// Numeric factorisation of the block of the whole system's `values`.
    pub(super) fn factor(&mut self, values: &[f64]) -> Result<(), LinearError> {
        self.sub.update(values);
        self.factor_current()
    }

    /// Numeric factorisation of the block's values as last taken.
    pub(super) fn factor_current(&mut self) -> Result<(), LinearError> {
        self.factored = false;
        if self.precision == Precision::Single {
            for (s, d) in self.sub.values.iter().zip(self.a32.iter_mut()) {
                *d = *s as f32;
            }
        }
        let mem = &mut self.factor_mem;
        let (tree, symbolic, pattern) = (self.tree.as_ref(), &self.symbolic, &self.sub.pattern);
        match self.precision {
            Precision::Double => numeric(
                tree,
                symbolic,
                pattern,
                &mut self.l64,
                &self.sub.values,
                self.par,
                mem,
            )?,
            Precision::Single => numeric(
                tree,
                symbolic,
                pattern,
                &mut self.l32,
                &self.a32,
                self.par,
                mem,
            )?,
        }
        self.factored = true;
        Ok(())
    }

    /// Floating-point operations of one numeric factorisation: per supernode of width w with
    /// r rows below it, the LDLᵀ of its diagonal block (w³/3), its panel (r w²) and the
    /// symmetric update of the rows below (r² w).
    pub(super) fn flops(&self) -> f64 {
        use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(sn) => {
                let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
                let rows = sn.col_ptr_for_row_idx();
                (0..sn.n_supernodes())
                    .map(|s| {
                        let w = (end[s] - begin[s]) as f64;
                        let r = (rows[s + 1] - rows[s]) as f64;
                        w * w * w / 3.0 + r * w * w + r * r * w
                    })
                    .sum()
            }
            SymbolicCholeskyRaw::Simplicial(sp) => {
                let cp = sp.col_ptr();
                (0..sp.nrows())
                    .map(|j| {
                        let c = (cp[j + 1] - cp[j]) as f64;
                        c * c
                    })
                    .sum()
            }
        }
    }

    /// Floating-point operations of one solve with the factor (L forward and back).
    pub(super) fn apply_flops(&self) -> f64 {
        4.0 * self.symbolic.len_val() as f64
    }

    pub(super) fn solve(&self, b: &mut [f64]) {
        assert!(self.factored, "factored before solve");
        let mut guard = self.solve_mem.borrow_mut();
        let (mem, b32) = &mut *guard;
        let stack = MemStack::new(mem);
        let mut x = self.x.borrow_mut();
        let (x64, x32) = &mut *x;
        match self.precision {
            Precision::Double => self.solve_in(&self.l64, b, x64, stack),
            Precision::Single => {
                for (d, s) in b32.iter_mut().zip(b.iter()) {
                    *d = *s as f32;
                }
                self.solve_in(&self.l32, b32, x32, stack);
                for (d, s) in b.iter_mut().zip(b32.iter()) {
                    *d = *s as f64;
                }
            }
        }
    }

    /// b ← (L D Lᵀ)⁻¹ b with the factor `l` in its precision: over the tree, or faer's solve.
    fn solve_in<T: Real + Send + Sync>(
        &self,
        l: &[T],
        b: &mut [T],
        x: &mut Vec<T>,
        stack: &mut MemStack,
    ) {
        match &self.tree {
            Some(tree) => tree.solve(l, b, x),
            None => ldlt_solve(&self.symbolic, l, b, self.par, stack),
        }
    }
}

/// Numeric LDLᵀ of `values` into `l`, in the precision T: over the tree where there is one,
/// else faer's (with its scratch `mem`).
fn numeric<T: Real + Send + Sync>(
    tree: Option<&TreeLdlt>,
    symbolic: &SymbolicCholesky<usize>,
    pattern: &SymbolicSparseColMat<usize>,
    l: &mut [T],
    values: &[T],
    par: Par,
    mem: &mut MemBuffer,
) -> Result<(), LinearError> {
    match tree {
        Some(tree) => tree
            .factor(l, values)
            .map_err(|e| LinearError::Factor(format!("ZeroPivot {{ index: {e} }}"))),
        None => ldlt_numeric(symbolic, l, pattern, values, par, MemStack::new(mem)),
    }
}

/// Numeric LDLᵀ of `values` (on `pattern`, lower triangle used) into `l`, in the precision T.
pub(super) fn ldlt_numeric<T: ComplexField>(
    symbolic: &SymbolicCholesky<usize>,
    l: &mut [T],
    pattern: &SymbolicSparseColMat<usize>,
    values: &[T],
    par: Par,
    stack: &mut MemStack,
) -> Result<(), LinearError> {
    let a = SparseColMatRef::new(pattern.as_ref(), values);
    symbolic
        .factorize_numeric_ldlt(
            l,
            a,
            Side::Lower,
            Default::default(),
            par,
            stack,
            Default::default(),
        )
        .map(|_| ())
        .map_err(|e| LinearError::Factor(format!("{e:?}")))
}

/// b ← (L D Lᵀ)⁻¹ b with the factor `l`, in the precision T.
pub(super) fn ldlt_solve<T: ComplexField>(
    symbolic: &SymbolicCholesky<usize>,
    l: &[T],
    b: &mut [T],
    par: Par,
    stack: &mut MemStack,
) {
    let n = b.len();
    LdltRef::new(symbolic, l).solve_in_place_with_conj(
        Conj::No,
        MatMut::from_column_major_slice_mut(b, n, 1),
        par,
        stack,
    );
}
