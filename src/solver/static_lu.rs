//! Sparse LU without pivoting of a matrix whose pattern is symmetric (values need not be):
//! friction's tangent has the pattern of the frictionless one, so it can be eliminated in the
//! fill-reducing order of its symmetric part (nested dissection), and L and Uᵀ then have the
//! pattern of the Cholesky factor: twice LDLᵀ's entries, far fewer than a partially pivoted
//! LU, whose fill is bounded by the pattern of AᵀA.
//!
//! Up-looking, one row at a time: for row k, the column U[0..k, k] solves L u = A[0..k, k]
//! and the row L[k, 0..k] solves Uᵀ lᵀ = A[k, 0..k]ᵀ, both over the row subtree of k in the
//! elimination tree (the nonzeros of row k of L), then U[k, k] = A[k, k] − L[k, 0..k] U[0..k, k].
//! The pivots are taken where the order puts them (static pivoting): a pivot that vanishes
//! against its row and column is reported, and the caller falls back to a pivoted LU.

use faer::sparse::SymbolicSparseColMat;
use std::ops::{Div, Mul, Sub, SubAssign};

/// The precision of a factor: f64, or f32 where it only preconditions a Krylov method that
/// keeps the residual in f64 (half the memory traffic).
pub trait Real:
    Copy
    + PartialEq
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + SubAssign
    + Default
{
    /// Machine epsilon.
    const EPS: f64;
    fn of(v: f64) -> Self;
    fn get(self) -> f64;
}

impl Real for f64 {
    const EPS: f64 = f64::EPSILON;
    fn of(v: f64) -> f64 {
        v
    }
    fn get(self) -> f64 {
        self
    }
}

impl Real for f32 {
    const EPS: f64 = f32::EPSILON as f64;
    fn of(v: f64) -> f32 {
        v as f32
    }
    fn get(self) -> f64 {
        self as f64
    }
}

/// A pivot smaller than this many rounding errors of the largest entry of its row and column
/// is refused: it would be mostly cancellation.
const PIVOT_EPS: f64 = 100.0;

#[derive(Debug, thiserror::Error)]
#[error("pivot {pivot:.3e} of equation {equation} is negligible against its row and column")]
pub struct SmallPivot {
    pub equation: usize,
    pub pivot: f64,
}

/// The factor's layout, computed once per pattern, and its values.
pub struct StaticLu<T: Real> {
    n: usize,
    /// `perm[new] = old`, `inv[old] = new`.
    perm: Vec<usize>,
    inv: Vec<usize>,
    /// The permuted matrix P A Pᵀ in CSC, with the slot of the original values of each entry
    /// and the slot of its mirror image (the pattern is symmetric).
    a_ptr: Vec<usize>,
    a_row: Vec<usize>,
    a_src: Vec<usize>,
    a_mirror: Vec<usize>,
    a_val: Vec<T>,
    /// Elimination tree of P A Pᵀ.
    parent: Vec<usize>,
    /// Column j of L and row j of U (strictly off the diagonal) share rows/columns
    /// `idx[ptr[j]..ptr[j + 1]]`, in increasing order.
    ptr: Vec<usize>,
    idx: Vec<usize>,
    l: Vec<T>,
    u: Vec<T>,
    diag: Vec<T>,
}

const NONE: usize = usize::MAX;

impl<T: Real> StaticLu<T> {
    /// The layout of the factor of a matrix with the symmetric `pattern` (both triangles),
    /// eliminated in the order `perm` (`perm[new] = old`).
    pub fn new(pattern: &SymbolicSparseColMat<usize>, perm: &[usize]) -> StaticLu<T> {
        let n = pattern.nrows();
        let mut inv = vec![0; n];
        for (new, &old) in perm.iter().enumerate() {
            inv[old] = new;
        }
        // P A Pᵀ column by column, rows sorted
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        let mut a_ptr = vec![0];
        let mut a_row = Vec::with_capacity(ri.len());
        let mut a_src = Vec::with_capacity(ri.len());
        let mut column: Vec<(usize, usize)> = Vec::new();
        for &old in perm {
            column.clear();
            column.extend((cp[old]..cp[old + 1]).map(|k| (inv[ri[k]], k)));
            column.sort_unstable();
            a_row.extend(column.iter().map(|c| c.0));
            a_src.extend(column.iter().map(|c| c.1));
            a_ptr.push(a_row.len());
        }
        let (ap, ar) = (&a_ptr, &a_row);
        let a_mirror = (0..n)
            .flat_map(|k| (ap[k]..ap[k + 1]).map(move |p| (ar[p], k)))
            .map(|(i, k)| {
                let (a, b) = (a_ptr[i], a_ptr[i + 1]);
                a + a_row[a..b].binary_search(&k).expect("symmetric pattern")
            })
            .collect();
        let parent = elimination_tree(n, &a_ptr, &a_row);
        // row k of L has its nonzeros at the row subtree of k: count them per column, then
        // fill the columns in increasing k (so each is sorted)
        let mut count = vec![0; n];
        let mut mark = vec![NONE; n];
        let mut reach = Vec::new();
        for k in 0..n {
            row_subtree(k, &a_ptr, &a_row, &parent, &mut mark, &mut reach);
            for &j in &reach {
                count[j] += 1;
            }
        }
        let mut ptr = vec![0; n + 1];
        for j in 0..n {
            ptr[j + 1] = ptr[j] + count[j];
        }
        let mut idx = vec![0; ptr[n]];
        let mut next = ptr[..n].to_vec();
        mark.fill(NONE);
        for k in 0..n {
            row_subtree(k, &a_ptr, &a_row, &parent, &mut mark, &mut reach);
            for &j in &reach {
                idx[next[j]] = k;
                next[j] += 1;
            }
        }
        let len = idx.len();
        StaticLu {
            n,
            perm: perm.to_vec(),
            inv,
            a_val: vec![T::default(); a_row.len()],
            a_ptr,
            a_row,
            a_src,
            a_mirror,
            parent,
            ptr,
            idx,
            l: vec![T::default(); len],
            u: vec![T::default(); len],
            diag: vec![T::default(); n],
        }
    }

    /// Entries of L and U, the diagonal counted once.
    pub fn entries(&self) -> usize {
        2 * self.idx.len() + self.n
    }

    /// Factorise the matrix of the pattern given to [`StaticLu::new`] with `values` (in its
    /// slots).
    pub fn factor(&mut self, values: &[f64]) -> Result<(), SmallPivot> {
        let n = self.n;
        for (v, &s) in self.a_val.iter_mut().zip(&self.a_src) {
            *v = T::of(values[s]);
        }
        // the largest entry of each row and column, for the pivot test
        let mut scale = vec![0.0f64; n];
        for j in 0..n {
            for k in self.a_ptr[j]..self.a_ptr[j + 1] {
                let a = values[self.a_src[k]].abs();
                scale[j] = scale[j].max(a);
                scale[self.a_row[k]] = scale[self.a_row[k]].max(a);
            }
        }
        // x: column k of A above the diagonal → U[.., k]; y: row k of A left of it → L[k, ..]
        let mut x = vec![T::default(); n];
        let mut y = vec![T::default(); n];
        let mut mark = vec![NONE; n];
        let mut reach = Vec::new();
        // next free slot of each column of L (row of U)
        let mut next = self.ptr[..n].to_vec();
        for k in 0..n {
            let mut d = T::default();
            // column k holds A[i, k]; the pattern is symmetric, so row k's entries A[k, i]
            // sit at the mirror slots: scatter both through the column of A
            for p in self.a_ptr[k]..self.a_ptr[k + 1] {
                let i = self.a_row[p];
                if i < k {
                    x[i] = self.a_val[p];
                    y[i] = self.a_val[self.a_mirror[p]];
                } else if i == k {
                    d = self.a_val[p];
                }
            }
            row_subtree(
                k,
                &self.a_ptr,
                &self.a_row,
                &self.parent,
                &mut mark,
                &mut reach,
            );
            // topological order: each j before the ancestors its column updates
            for &j in reach.iter().rev() {
                let ujk = x[j];
                let lkj = y[j] / self.diag[j];
                x[j] = T::default();
                y[j] = T::default();
                for q in self.ptr[j]..next[j] {
                    let i = self.idx[q];
                    x[i] -= self.l[q] * ujk;
                    y[i] -= self.u[q] * lkj;
                }
                d -= lkj * ujk;
                self.l[next[j]] = lkj;
                self.u[next[j]] = ujk;
                next[j] += 1;
            }
            let pivot = d.get();
            if !pivot.is_finite() || pivot.abs() <= PIVOT_EPS * T::EPS * scale[k] {
                return Err(SmallPivot {
                    equation: self.perm[k],
                    pivot,
                });
            }
            self.diag[k] = d;
        }
        Ok(())
    }

    /// b → A⁻¹ b.
    pub fn solve(&self, b: &mut [f64]) {
        let n = self.n;
        let mut z: Vec<T> = self.perm.iter().map(|&old| T::of(b[old])).collect();
        // L z = b: L unit lower, stored by columns
        for j in 0..n {
            let zj = z[j];
            if zj != T::default() {
                for q in self.ptr[j]..self.ptr[j + 1] {
                    z[self.idx[q]] -= self.l[q] * zj;
                }
            }
        }
        // U z = z: U stored by rows (row j: diag[j], then u at columns idx)
        for j in (0..n).rev() {
            let mut s = z[j];
            for q in self.ptr[j]..self.ptr[j + 1] {
                s -= self.u[q] * z[self.idx[q]];
            }
            z[j] = s / self.diag[j];
        }
        for (old, v) in b.iter_mut().enumerate() {
            *v = z[self.inv[old]].get();
        }
    }
}

/// Elimination tree of a matrix with symmetric pattern (CSC, both triangles), Liu's algorithm
/// with path compression.
fn elimination_tree(n: usize, ptr: &[usize], row: &[usize]) -> Vec<usize> {
    let mut parent = vec![NONE; n];
    let mut ancestor = vec![NONE; n];
    for k in 0..n {
        for &i0 in &row[ptr[k]..ptr[k + 1]] {
            let mut i = i0;
            while i != NONE && i < k {
                let next = ancestor[i];
                ancestor[i] = k;
                if next == NONE {
                    parent[i] = k;
                }
                i = next;
            }
        }
    }
    parent
}

/// The nonzeros of row k of L (columns j < k), into `reach` in reverse topological order
/// (each column after the descendants it depends on, when read backwards). `mark` holds, for
/// each node, the last row that visited it.
fn row_subtree(
    k: usize,
    ptr: &[usize],
    row: &[usize],
    parent: &[usize],
    mark: &mut [usize],
    reach: &mut Vec<usize>,
) {
    reach.clear();
    mark[k] = k;
    for &i0 in &row[ptr[k]..ptr[k + 1]] {
        if i0 >= k {
            continue;
        }
        // climb from i0 to the first node already visited in this row, then turn the path
        // so that, read backwards, the deepest comes first
        let start = reach.len();
        let mut i = i0;
        while mark[i] != k {
            reach.push(i);
            mark[i] = k;
            i = parent[i];
        }
        reach[start..].reverse();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A random unsymmetric matrix on the symmetric pattern of a 2D grid Laplacian (5-point),
    /// diagonally dominant.
    fn grid(m: usize, seed: u64) -> (SymbolicSparseColMat<usize>, Vec<f64>) {
        let n = m * m;
        let mut state = seed;
        let mut rand = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let (mut ptr, mut row, mut val) = (vec![0], Vec::new(), Vec::new());
        for j in 0..n {
            let (x, y) = (j % m, j / m);
            let mut rows = vec![j];
            if x > 0 {
                rows.push(j - 1);
            }
            if x + 1 < m {
                rows.push(j + 1);
            }
            if y > 0 {
                rows.push(j - m);
            }
            if y + 1 < m {
                rows.push(j + m);
            }
            rows.sort_unstable();
            for i in rows {
                row.push(i);
                val.push(if i == j { 4.5 } else { -1.0 + rand() });
            }
            ptr.push(row.len());
        }
        (SymbolicSparseColMat::new_checked(n, n, ptr, None, row), val)
    }

    fn mul(p: &SymbolicSparseColMat<usize>, v: &[f64], x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        for j in 0..x.len() {
            for k in p.col_ptr()[j]..p.col_ptr()[j + 1] {
                y[p.row_idx()[k]] += v[k] * x[j];
            }
        }
        y
    }

    /// The largest error of the solution of A x = b by the factor in precision T.
    fn error<T: Real>(
        p: &SymbolicSparseColMat<usize>,
        perm: &[usize],
        v: &[f64],
        b: &[f64],
        x: &[f64],
    ) -> f64 {
        let mut lu = StaticLu::<T>::new(p, perm);
        lu.factor(v).unwrap();
        let mut s = b.to_vec();
        lu.solve(&mut s);
        s.iter()
            .zip(x)
            .map(|(a, c)| (a - c).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn solves_unsymmetric_systems_in_any_order() {
        let (p, v) = grid(9, 7);
        let n = p.nrows();
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let b = mul(&p, &v, &x);
        let reversed: Vec<usize> = (0..n).rev().collect();
        let shuffled: Vec<usize> = (0..n).map(|i| (i * 17) % n).collect();
        for perm in [(0..n).collect::<Vec<_>>(), reversed, shuffled] {
            let err = error::<f64>(&p, &perm, &v, &b, &x);
            assert!(err < 1e-12, "error {err:e}");
            let err = error::<f32>(&p, &perm, &v, &b, &x);
            assert!(err < 1e-5, "error in single precision {err:e}");
            let lu = StaticLu::<f64>::new(&p, &perm);
            // fill: L has at least the lower pattern of A, no more than a dense lower triangle
            assert!(lu.entries() >= p.row_idx().len() && lu.entries() <= n * n);
        }
    }

    #[test]
    fn refuses_a_vanishing_pivot() {
        let (p, mut v) = grid(3, 1);
        // zero the first diagonal entry: the first pivot, in the natural order
        let first = p.col_ptr()[0];
        v[first] = 0.0;
        let mut lu = StaticLu::<f64>::new(&p, &(0..9).collect::<Vec<_>>());
        let e = lu.factor(&v).unwrap_err();
        assert_eq!(e.equation, 0);
    }
}
