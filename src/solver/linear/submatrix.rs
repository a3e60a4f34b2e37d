//! A square sub-block of the system matrix, and its products.

use crate::dofs::Pattern;
use faer::sparse::SymbolicSparseColMat;

/// A square sub-block of the system matrix, `rows × cols` of the free equations, with the slot
/// of the full matrix each of its entries copies.
pub(super) struct SubMatrix {
    pub(super) pattern: SymbolicSparseColMat<usize>,
    pub(super) values: Vec<f64>,
    pub(super) source: Vec<usize>,
}

impl SubMatrix {
    /// The sub-block of rows `rows` and columns `cols` (increasing global equation numbers).
    pub(super) fn new(p: &Pattern, rows: &[usize], cols: &[usize]) -> SubMatrix {
        let mut local = vec![usize::MAX; p.n];
        for (l, &g) in rows.iter().enumerate() {
            local[g] = l;
        }
        let mut col_ptr = Vec::with_capacity(cols.len() + 1);
        let mut row_idx = Vec::new();
        let mut source = Vec::new();
        col_ptr.push(0);
        for &c in cols {
            for k in p.col_ptr[c]..p.col_ptr[c + 1] {
                let l = local[p.row_idx[k]];
                if l != usize::MAX {
                    row_idx.push(l);
                    source.push(k);
                }
            }
            col_ptr.push(row_idx.len());
        }
        SubMatrix {
            pattern: SymbolicSparseColMat::new_checked(
                rows.len(),
                cols.len(),
                col_ptr,
                None,
                row_idx,
            ),
            values: vec![0.0; source.len()],
            source,
        }
    }

    pub(super) fn update(&mut self, full: &[f64]) {
        for (v, &k) in self.values.iter_mut().zip(&self.source) {
            *v = full[k];
        }
    }

    /// y = A x.
    pub(super) fn mul(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        self.mul_sub(x, y);
        y.iter_mut().for_each(|v| *v = -*v);
    }

    /// y −= A x.
    pub(super) fn mul_sub(&self, x: &[f64], y: &mut [f64]) {
        let (cp, ri) = (self.pattern.col_ptr(), self.pattern.row_idx());
        for (j, &xj) in x.iter().enumerate() {
            if xj != 0.0 {
                for k in cp[j]..cp[j + 1] {
                    y[ri[k]] -= self.values[k] * xj;
                }
            }
        }
    }
}
