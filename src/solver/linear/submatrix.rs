//! A sub-block of the system matrix, and its products.
//!
//! The product y −= A x runs on every thread for a large block: its columns are cut into
//! pieces of about [`PIECE_ENTRIES`] entries, each piece's product is summed apart into the
//! band of rows it touches, and the pieces are then subtracted from y, rows in parallel, in
//! the pieces' order. The cut depends on the matrix alone, never on the thread count, so the
//! product is the same to the last bit on any number of threads; a block of at most two
//! pieces' entries is one piece, the product as summed column by column on one thread.

use crate::dofs::Pattern;
use faer::sparse::SymbolicSparseColMat;
use rayon::prelude::*;
use std::ops::Range;

/// The entries of a piece of a block's product (a task of about a tenth of a millisecond).
const PIECE_ENTRIES: usize = 1 << 16;

/// The rows of y a task of the pieces' sum covers.
const ROW_BAND: usize = 1 << 12;

/// A sub-block of the system matrix, `rows × cols` of the free equations, with the slot of
/// the full matrix each of its entries copies.
pub(super) struct SubMatrix {
    pub(super) pattern: SymbolicSparseColMat<usize>,
    pub(super) values: Vec<f64>,
    pub(super) source: Vec<usize>,
    /// The pieces of the product: their columns, and the rows their entries lie in.
    pieces: Vec<Piece>,
}

/// Consecutive columns of a block and the band of rows their entries lie in.
struct Piece {
    cols: Range<usize>,
    rows: Range<usize>,
}

/// The block's columns cut into pieces of about [`PIECE_ENTRIES`] entries (one piece where
/// the block has fewer than two pieces' worth).
fn pieces(pattern: &SymbolicSparseColMat<usize>) -> Vec<Piece> {
    let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
    let ncols = cp.len() - 1;
    let nnz = cp[ncols];
    if nnz < 2 * PIECE_ENTRIES {
        return vec![Piece {
            cols: 0..ncols,
            rows: 0..pattern.nrows(),
        }];
    }
    let mut out = Vec::new();
    let mut start = 0;
    while start < ncols {
        let mut end = start + 1;
        while end < ncols && cp[end] - cp[start] < PIECE_ENTRIES {
            end += 1;
        }
        let rows = &ri[cp[start]..cp[end]];
        let lo = rows.iter().copied().min().unwrap_or(0);
        let hi = rows.iter().copied().max().map_or(lo, |r| r + 1);
        out.push(Piece {
            cols: start..end,
            rows: lo..hi,
        });
        start = end;
    }
    out
}

impl SubMatrix {
    /// The sub-block of rows `rows` and columns `cols` (increasing global equation numbers).
    pub(super) fn new(p: &Pattern, rows: &[usize], cols: &[usize]) -> SubMatrix {
        let mut local = vec![usize::MAX; p.n];
        for (l, &g) in rows.iter().enumerate() {
            local[g] = l;
        }
        let mut col_ptr = Vec::with_capacity(cols.len() + 1);
        // at most the columns' entries (all of them for the whole system)
        let most = cols.iter().map(|&c| p.col_ptr[c + 1] - p.col_ptr[c]).sum();
        let mut row_idx = Vec::with_capacity(most);
        let mut source = Vec::with_capacity(most);
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
        let pattern =
            SymbolicSparseColMat::new_checked(rows.len(), cols.len(), col_ptr, None, row_idx);
        SubMatrix {
            pieces: pieces(&pattern),
            pattern,
            values: vec![0.0; source.len()],
            source,
        }
    }

    /// Take the block's values from the whole system's `values`.
    pub(super) fn update(&mut self, full: &[f64]) {
        self.values
            .par_chunks_mut(PIECE_ENTRIES)
            .zip(self.source.par_chunks(PIECE_ENTRIES))
            .for_each(|(v, s)| v.iter_mut().zip(s).for_each(|(v, &k)| *v = full[k]));
    }

    /// y = A x.
    pub(super) fn mul(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        self.mul_sub(x, y);
        y.iter_mut().for_each(|v| *v = -*v);
    }

    /// y −= A x: on one thread column by column for a block of one piece; otherwise each
    /// piece's A x summed apart, then subtracted in the pieces' order (see the module).
    pub(super) fn mul_sub(&self, x: &[f64], y: &mut [f64]) {
        if let [whole] = &self.pieces[..] {
            return self.piece_mul_sub(whole, x, y);
        }
        let sums: Vec<Vec<f64>> = self
            .pieces
            .par_iter()
            .map(|piece| {
                let mut band = vec![0.0; piece.rows.len()];
                self.piece_mul_sub(piece, x, &mut band);
                band
            })
            .collect();
        y.par_chunks_mut(ROW_BAND).enumerate().for_each(|(b, ys)| {
            let r0 = b * ROW_BAND;
            let r1 = r0 + ys.len();
            for (piece, band) in self.pieces.iter().zip(&sums) {
                let (lo, hi) = (piece.rows.start.max(r0), piece.rows.end.min(r1));
                for r in lo..hi {
                    ys[r - r0] += band[r - piece.rows.start];
                }
            }
        });
    }

    /// y −= A x over the columns of `piece`, y holding the piece's rows from their first.
    fn piece_mul_sub(&self, piece: &Piece, x: &[f64], y: &mut [f64]) {
        let (cp, ri) = (self.pattern.col_ptr(), self.pattern.row_idx());
        let r0 = piece.rows.start;
        for j in piece.cols.clone() {
            let xj = x[j];
            if xj != 0.0 {
                for k in cp[j]..cp[j + 1] {
                    y[ri[k] - r0] -= self.values[k] * xj;
                }
            }
        }
    }
}
