//! Sparse LU without pivoting of a matrix whose pattern is symmetric (values need not be):
//! friction's tangent has the pattern of the frictionless one, so it can be eliminated in the
//! fill-reducing order of its symmetric part (nested dissection), and L and Uᵀ then have the
//! pattern of the Cholesky factor: twice LDLᵀ's entries, far fewer than a partially pivoted
//! LU, whose fill is bounded by the pattern of AᵀA.
//!
//! Supernodal and left-looking: columns of L whose patterns nest (a column, its parent in the
//! elimination tree, and so on, each one row shorter) form a supernode, held as a dense panel
//! [L_JJ \ U_JJ; L_RJ] with the rows R below it and, beside it, U_JR stored transposed. A
//! supernode gathers the updates of every earlier one whose rows reach it (dense products),
//! factors its diagonal block, and solves its two off-diagonal panels against it. The pivots
//! are taken where the order puts them (static pivoting): a pivot that vanishes against its
//! row and column is reported, and the caller falls back to a pivoted LU. In 3D the dense
//! products are most of the work; a row-by-row (up-looking) LU spent 3–5× longer there.

use faer::reborrow::{IntoConst, Reborrow, ReborrowMut};
use faer::sparse::SymbolicSparseColMat;
use faer::traits::ComplexField;
use faer::{Accum, MatMut, MatRef, Par};
use std::ops::{Div, DivAssign, Mul, Sub, SubAssign};
use std::sync::Arc;

/// The precision of a factor: f64, or f32 where it only preconditions a Krylov method that
/// keeps the residual in f64 (half the memory traffic).
pub trait Real:
    Copy
    + PartialEq
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + DivAssign
    + SubAssign
    + Default
    + ComplexField
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

/// Dense blocks below this many multiply-adds are worked on one thread: a second one costs
/// more to wake than it saves.
const PARALLEL_FLOPS: usize = 1 << 18;

/// Diagonal blocks up to this width are factored entry by entry; wider ones split in two.
const BLOCK: usize = 32;

#[derive(Debug, thiserror::Error)]
#[error("pivot {pivot:.3e} of equation {equation} is negligible against its row and column")]
pub struct SmallPivot {
    pub equation: usize,
    pub pivot: f64,
}

/// One supernode: columns `begin..end` of the permuted matrix, the rows below them, and
/// where its panels start in the factor's storage.
struct Supernode {
    begin: usize,
    end: usize,
    /// The rows of L below the supernode, `rows[rows_at..rows_at + n_rows]` of the factor.
    rows_at: usize,
    n_rows: usize,
    /// [L_JJ \ U_JJ; L_RJ], column-major, (width + n_rows) × width.
    l_at: usize,
    /// U_JRᵀ, column-major, n_rows × width.
    u_at: usize,
}

impl Supernode {
    fn width(&self) -> usize {
        self.end - self.begin
    }
}

/// Where a factor's entries go, computed once per pattern and shared by the factors of any
/// precision that follow it.
struct Layout {
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
    nodes: Vec<Supernode>,
    /// The supernode of each column.
    node_of: Vec<usize>,
    rows: Vec<usize>,
}

/// The factor's layout and its values.
pub struct StaticLu<T: Real> {
    layout: Arc<Layout>,
    l: Vec<T>,
    u: Vec<T>,
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
        // P A Pᵀ column by column, rows sorted: row i of it is A's column perm[i] (the pattern
        // is symmetric), so appending i to each of its columns, i in order, sorts every column
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        let a_mirrored = mirrors(cp, ri);
        let mut a_ptr = vec![0; n + 1];
        for (new, &old) in perm.iter().enumerate() {
            a_ptr[new + 1] = a_ptr[new] + (cp[old + 1] - cp[old]);
        }
        let mut next = a_ptr[..n].to_vec();
        let mut a_row = vec![0; ri.len()];
        let mut a_src = vec![0; ri.len()];
        for (i, &old) in perm.iter().enumerate() {
            for k in cp[old]..cp[old + 1] {
                // A's entry (ri[k], old) is P A Pᵀ's (j, i); its mirror is (i, j)
                let j = inv[ri[k]];
                a_row[next[j]] = i;
                a_src[next[j]] = a_mirrored[k];
                next[j] += 1;
            }
        }
        let a_mirror = mirrors(&a_ptr, &a_row);
        let parent = elimination_tree(n, &a_ptr, &a_row);
        let [bounds, rows_ptr, rows] = supernodes(&a_ptr, &a_row, &parent);
        let mut node_of = vec![0; n];
        let mut nodes = Vec::with_capacity(bounds.len() - 1);
        let (mut l_at, mut u_at) = (0, 0);
        for (s, (w, r)) in bounds.windows(2).zip(rows_ptr.windows(2)).enumerate() {
            let (begin, end) = (w[0], w[1]);
            let (width, n_rows) = (end - begin, r[1] - r[0]);
            node_of[begin..end].fill(s);
            nodes.push(Supernode {
                begin,
                end,
                rows_at: r[0],
                n_rows,
                l_at,
                u_at,
            });
            l_at += (width + n_rows) * width;
            u_at += n_rows * width;
        }
        StaticLu {
            layout: Arc::new(Layout {
                n,
                perm: perm.to_vec(),
                inv,
                a_ptr,
                a_row,
                a_src,
                a_mirror,
                node_of,
                rows,
                nodes,
            }),
            l: vec![T::default(); l_at],
            u: vec![T::default(); u_at],
        }
    }

    /// A factor of precision `U` with the same layout, shared (its values are computed by its
    /// first [`StaticLu::factor`]).
    pub fn in_precision<U: Real>(&self) -> StaticLu<U> {
        StaticLu {
            layout: Arc::clone(&self.layout),
            l: vec![U::default(); self.l.len()],
            u: vec![U::default(); self.u.len()],
        }
    }

    /// Entries of L and U, the diagonal counted once.
    pub fn entries(&self) -> usize {
        self.l.len() + self.u.len()
    }

    /// Floating-point operations of one factorisation: per supernode of width w with r rows
    /// below it, the LU of its diagonal block (2w³/3), the panels of L and U (r w² each) and
    /// the update of the rows below (2 r² w).
    pub fn flops(&self) -> f64 {
        self.layout
            .nodes
            .iter()
            .map(|s| {
                let (w, r) = (s.width() as f64, s.n_rows as f64);
                2.0 * w * w * w / 3.0 + 2.0 * r * w * w + 2.0 * r * r * w
            })
            .sum()
    }

    /// Factorise the matrix of the pattern given to [`StaticLu::new`] with `values` (in its
    /// slots).
    pub fn factor(&mut self, values: &[f64]) -> Result<(), SmallPivot> {
        let n = self.layout.n;
        // the largest entry of each row and column, for the pivot test
        let mut scale = vec![0.0f64; n];
        for j in 0..n {
            for k in self.layout.a_ptr[j]..self.layout.a_ptr[j + 1] {
                let a = values[self.layout.a_src[k]].abs();
                scale[j] = scale[j].max(a);
                scale[self.layout.a_row[k]] = scale[self.layout.a_row[k]].max(a);
            }
        }
        // local position of each row in the supernode being factored
        let mut pos = vec![NONE; n];
        // the earlier supernodes whose next rows fall in each supernode, and how far down
        // their rows each has been applied
        let mut waiting: Vec<Vec<usize>> = vec![Vec::new(); self.layout.nodes.len()];
        let mut cursor = vec![0; self.layout.nodes.len()];
        let (mut into_l, mut into_u): (Vec<T>, Vec<T>) = (Vec::new(), Vec::new());
        for s in 0..self.layout.nodes.len() {
            let sn = &self.layout.nodes[s];
            let (b, w, nr) = (sn.begin, sn.width(), sn.n_rows);
            let m = w + nr;
            let below = &self.layout.rows[sn.rows_at..sn.rows_at + nr];
            for t in 0..w {
                pos[b + t] = t;
            }
            for (r, &i) in below.iter().enumerate() {
                pos[i] = w + r;
            }
            let (l_at, u_at) = (sn.l_at, sn.u_at);
            // the supernode's columns and rows of A
            self.l[l_at..l_at + m * w].fill(T::default());
            self.u[u_at..u_at + nr * w].fill(T::default());
            for j in b..sn.end {
                for p in self.layout.a_ptr[j]..self.layout.a_ptr[j + 1] {
                    let i = self.layout.a_row[p];
                    if i < b {
                        continue;
                    }
                    let r = pos[i];
                    self.l[l_at + (j - b) * m + r] = T::of(values[self.layout.a_src[p]]);
                    if r >= w {
                        self.u[u_at + (j - b) * nr + r - w] =
                            T::of(values[self.layout.a_src[self.layout.a_mirror[p]]]);
                    }
                }
            }
            // the updates of the earlier supernodes that reach these columns
            for d in std::mem::take(&mut waiting[s]) {
                let dn = &self.layout.nodes[d];
                let (wd, nd) = (dn.width(), dn.n_rows);
                let drows = &self.layout.rows[dn.rows_at..dn.rows_at + nd];
                let c0 = cursor[d];
                let c1 = c0 + drows[c0..].partition_point(|&i| i < sn.end);
                let (k, k1, k2) = (nd - c0, c1 - c0, nd - c1);
                // L_d and U_dᵀ from row c0 down; rows c0..c1 fall in these columns
                let (l, u) = (&self.l, &self.u);
                let ld = MatRef::from_column_major_slice_with_stride(
                    &l[dn.l_at + wd + c0..],
                    k,
                    wd,
                    wd + nd,
                );
                let ud = MatRef::from_column_major_slice_with_stride(&u[dn.u_at + c0..], k, wd, nd);
                // into the L panel: rows c0.. of L times columns c0..c1 of U; into the U
                // panel: rows c1.. of Uᵀ times columns c0..c1 of Lᵀ
                into_l.clear();
                into_l.resize(k * k1, T::default());
                product(
                    MatMut::from_column_major_slice_mut(&mut into_l, k, k1),
                    ld,
                    ud.subrows(0, k1).transpose(),
                );
                into_u.clear();
                into_u.resize(k2 * k1, T::default());
                product(
                    MatMut::from_column_major_slice_mut(&mut into_u, k2, k1),
                    ud.subrows(k1, k2),
                    ld.subrows(0, k1).transpose(),
                );
                for (c, &j) in drows[c0..c1].iter().enumerate() {
                    let col = l_at + (j - b) * m;
                    for (r, &i) in drows[c0..].iter().enumerate() {
                        self.l[col + pos[i]] -= into_l[c * k + r];
                    }
                    let col = u_at + (j - b) * nr;
                    for (r, &i) in drows[c1..].iter().enumerate() {
                        self.u[col + pos[i] - w] -= into_u[c * k2 + r];
                    }
                }
                cursor[d] = c1;
                if c1 < nd {
                    waiting[self.layout.node_of[drows[c1]]].push(d);
                }
            }
            // the diagonal block, then the panels against it: L_RJ U_JJ = A_RJ and
            // U_JRᵀ L_JJᵀ = A_JRᵀ
            let (l, u) = (&mut self.l, &mut self.u);
            let panel = MatMut::from_column_major_slice_mut(&mut l[l_at..l_at + m * w], m, w);
            let (mut diag, lower) = panel.split_at_row_mut(w);
            dense_lu(diag.rb_mut(), &scale[b..b + w]).map_err(|(t, pivot)| SmallPivot {
                equation: self.layout.perm[b + t],
                pivot,
            })?;
            let diag = diag.into_const();
            let par = threads_for(nr * w * w);
            faer::linalg::triangular_solve::solve_lower_triangular_in_place(
                diag.transpose(),
                lower.transpose_mut(),
                par,
            );
            let upper = MatMut::from_column_major_slice_mut(&mut u[u_at..u_at + nr * w], nr, w);
            faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(
                diag,
                upper.transpose_mut(),
                par,
            );
            for &i in below {
                pos[i] = NONE;
            }
            if nr > 0 {
                waiting[self.layout.node_of[below[0]]].push(s);
            }
        }
        Ok(())
    }

    /// b → A⁻¹ b.
    pub fn solve(&self, b: &mut [f64]) {
        let mut z: Vec<T> = self.layout.perm.iter().map(|&old| T::of(b[old])).collect();
        // the rows below a supernode, gathered: L_RJ z_J, or z_R for U_JR z_R
        let widest = self
            .layout
            .nodes
            .iter()
            .map(|s| s.n_rows.max(s.width()))
            .max();
        let mut tmp = vec![T::default(); widest.unwrap_or(0)];
        // L z = b, supernode by supernode: z_J by the unit lower L_JJ, then z_R −= L_RJ z_J
        for sn in &self.layout.nodes {
            let (bg, w, nr) = (sn.begin, sn.width(), sn.n_rows);
            let m = w + nr;
            let l = &self.l[sn.l_at..sn.l_at + m * w];
            for t in 0..w {
                let zt = z[bg + t];
                for (zr, &lrt) in z[bg + t + 1..bg + w]
                    .iter_mut()
                    .zip(&l[t * m + t + 1..t * m + w])
                {
                    *zr -= lrt * zt;
                }
            }
            if nr > 0 {
                let panel = MatRef::from_column_major_slice_with_stride(&l[w..], nr, w, m);
                let zj = MatRef::from_column_major_slice(&z[bg..bg + w], w, 1);
                let out = MatMut::from_column_major_slice_mut(&mut tmp[..nr], nr, 1);
                faer::linalg::matmul::matmul(out, Accum::Replace, panel, zj, T::of(1.0), Par::Seq);
                for (&i, &v) in self.layout.rows[sn.rows_at..sn.rows_at + nr]
                    .iter()
                    .zip(&tmp)
                {
                    z[i] -= v;
                }
            }
        }
        // U z = z, backwards: z_J −= U_JR z_R, then z_J by the upper U_JJ
        for sn in self.layout.nodes.iter().rev() {
            let (bg, w, nr) = (sn.begin, sn.width(), sn.n_rows);
            let m = w + nr;
            let l = &self.l[sn.l_at..sn.l_at + m * w];
            if nr > 0 {
                let below = &self.layout.rows[sn.rows_at..sn.rows_at + nr];
                for (t, &i) in tmp.iter_mut().zip(below) {
                    *t = z[i];
                }
                let u = MatRef::from_column_major_slice(&self.u[sn.u_at..sn.u_at + nr * w], nr, w);
                let zr = MatRef::from_column_major_slice(&tmp[..nr], nr, 1);
                let zj = MatMut::from_column_major_slice_mut(&mut z[bg..bg + w], w, 1);
                faer::linalg::matmul::matmul(
                    zj,
                    Accum::Add,
                    u.transpose(),
                    zr,
                    T::of(-1.0),
                    Par::Seq,
                );
            }
            for t in (0..w).rev() {
                let zt = z[bg + t] / l[t * m + t];
                z[bg + t] = zt;
                for r in 0..t {
                    let v = z[bg + r] - l[t * m + r] * zt;
                    z[bg + r] = v;
                }
            }
        }
        for (old, v) in b.iter_mut().enumerate() {
            *v = z[self.layout.inv[old]].get();
        }
    }
}

/// Both threads for dense work of more than [`PARALLEL_FLOPS`] multiply-adds, one below.
fn threads_for(flops: usize) -> Par {
    if flops > PARALLEL_FLOPS {
        super::dense_par()
    } else {
        Par::Seq
    }
}

/// dst = lhs · rhs.
fn product<T: Real>(dst: MatMut<'_, T>, lhs: MatRef<'_, T>, rhs: MatRef<'_, T>) {
    let par = threads_for(lhs.nrows() * lhs.ncols() * rhs.ncols());
    faer::linalg::matmul::matmul(dst, Accum::Replace, lhs, rhs, T::of(1.0), par);
}

/// In place, A = L U with L unit lower and U upper, no row exchanges (the pivots where they
/// stand); `scale` the largest entry of each row and column of the sparse matrix, to judge the
/// pivots. A negligible pivot is returned with its position.
fn dense_lu<T: Real>(mut a: MatMut<'_, T>, scale: &[f64]) -> Result<(), (usize, f64)> {
    let w = a.nrows();
    let check = |t: usize, pivot: f64| {
        if !pivot.is_finite() || pivot.abs() <= PIVOT_EPS * T::EPS * scale[t] {
            Err((t, pivot))
        } else {
            Ok(())
        }
    };
    if w <= BLOCK {
        for t in 0..w {
            let pivot = a[(t, t)];
            check(t, pivot.get())?;
            for r in t + 1..w {
                let v = a[(r, t)] / pivot;
                a[(r, t)] = v;
            }
            for c in t + 1..w {
                let utc = a[(t, c)];
                if utc == T::default() {
                    continue;
                }
                for r in t + 1..w {
                    let v = a[(r, c)] - a[(r, t)] * utc;
                    a[(r, c)] = v;
                }
            }
        }
        return Ok(());
    }
    // [A11 A12; A21 A22]: A11 = L11 U11, U12 = L11⁻¹ A12, L21 = A21 U11⁻¹, then A22 − L21 U12
    let h = w / 2;
    let (mut a11, mut a12, mut a21, a22) = a.rb_mut().split_at_mut(h, h);
    dense_lu(a11.rb_mut(), &scale[..h])?;
    let a11 = a11.into_const();
    let par = threads_for(h * h * (w - h));
    faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(a11, a12.rb_mut(), par);
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        a11.transpose(),
        a21.rb_mut().transpose_mut(),
        par,
    );
    let mut a22 = a22;
    faer::linalg::matmul::matmul(
        a22.rb_mut(),
        Accum::Add,
        a21.rb(),
        a12.rb(),
        T::of(-1.0),
        par,
    );
    dense_lu(a22, &scale[h..]).map_err(|(t, p)| (t + h, p))
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

/// The children of each node of a forest whose nodes have the parents `parent` (`usize::MAX`
/// for a root), increasing, as `children[at[p]..at[p + 1]]`: `(at, children)`.
pub(super) fn children_of(parent: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let n = parent.len();
    let mut at = vec![0; n + 1];
    for &p in parent.iter().filter(|&&p| p != NONE) {
        at[p + 1] += 1;
    }
    for j in 0..n {
        at[j + 1] += at[j];
    }
    let mut children = vec![0; at[n]];
    let mut next = at[..n].to_vec();
    for (c, &p) in parent.iter().enumerate().filter(|(_, p)| **p != NONE) {
        children[next[p]] = c;
        next[p] += 1;
    }
    (at, children)
}

/// The supernodes of the factor of a matrix with a symmetric pattern (CSC `ptr`/`row`, both
/// triangles, rows sorted) and elimination tree `parent`, and the rows of L below each:
/// column j joins j − 1's supernode when it is j − 1's parent and its pattern is j − 1's less
/// j (then every column of a supernode has the last one's rows below it). Returns each
/// supernode's first column and then n, and the rows below each, increasing, as
/// `rows[rows_ptr[s]..rows_ptr[s + 1]]`.
///
/// A column's pattern is A's rows below it merged with its children's patterns less itself.
/// The open supernode's pattern is kept, its rows marked; a column that would join is only
/// checked against the marks, so the work is A's entries and each supernode's rows a few
/// times, where walking each row's subtree visits every entry of L.
fn supernodes(ptr: &[usize], row: &[usize], parent: &[usize]) -> [Vec<usize>; 3] {
    let n = parent.len();
    let (first, child) = children_of(parent);
    let (mut bounds, mut rows_ptr, mut rows) = (vec![0], vec![0], Vec::new());
    // the supernode whose last column each closed column is
    let mut closed_at = vec![NONE; n];
    // the open supernode's rows below its last column, `open[at..]`; `mark[k]` its number
    // for each of them, `seen[k]` the column whose pattern was gathered with k last
    let (mut open, mut at, mut opened) = (Vec::<usize>::new(), 0, 0);
    let (mut mark, mut seen) = (vec![NONE; n], vec![NONE; n]);
    for j in 0..n {
        let a_below = || {
            row[ptr[j]..ptr[j + 1]]
                .iter()
                .copied()
                .filter(move |&k| k > j)
        };
        let kids = &child[first[j]..first[j + 1]];
        let extends = j > 0 && parent[j - 1] == j;
        if extends {
            debug_assert_eq!(open.get(at), Some(&j));
            let inside = |k: usize| k == j || mark[k] == opened;
            let others = kids.iter().filter(|&&c| c != j - 1);
            let mut theirs = others.flat_map(|&c| below(&rows, &rows_ptr, closed_at[c]));
            if a_below().all(inside) && theirs.all(|&k| inside(k)) {
                at += 1;
                continue;
            }
        }
        if j > 0 {
            rows.extend_from_slice(&open[at..]);
            rows_ptr.push(rows.len());
            bounds.push(j);
            closed_at[j - 1] = bounds.len() - 2;
        }
        // column j's pattern: A's rows below it and its children's less j
        let mut pattern = Vec::new();
        let mut gather = |k: usize| {
            if k != j && seen[k] != j {
                seen[k] = j;
                pattern.push(k);
            }
        };
        if extends {
            open[at..].iter().for_each(|&k| gather(k));
        }
        a_below().for_each(&mut gather);
        for &c in kids.iter().filter(|&&c| !(extends && c == j - 1)) {
            below(&rows, &rows_ptr, closed_at[c])
                .iter()
                .for_each(|&k| gather(k));
        }
        pattern.sort_unstable();
        opened += 1;
        pattern.iter().for_each(|&k| mark[k] = opened);
        (open, at) = (pattern, 0);
    }
    if n > 0 {
        rows.extend_from_slice(&open[at..]);
        rows_ptr.push(rows.len());
        bounds.push(n);
    }
    [bounds, rows_ptr, rows]
}

/// The rows below supernode `s`.
fn below<'a>(rows: &'a [usize], rows_ptr: &[usize], s: usize) -> &'a [usize] {
    &rows[rows_ptr[s]..rows_ptr[s + 1]]
}

/// The slot of each entry's mirror image in a pattern that is symmetric, its rows sorted in
/// each column (CSC `ptr`/`row`): the entries of column i are met in the order of their rows
/// where its mirrors are met column by column.
fn mirrors(ptr: &[usize], row: &[usize]) -> Vec<usize> {
    let n = ptr.len() - 1;
    let mut next = ptr[..n].to_vec();
    let mut mirror = vec![0; row.len()];
    for k in 0..n {
        debug_assert!(row[ptr[k]..ptr[k + 1]].is_sorted(), "column {k} unsorted");
        for (p, &i) in mirror[ptr[k]..ptr[k + 1]]
            .iter_mut()
            .zip(&row[ptr[k]..ptr[k + 1]])
        {
            *p = next[i];
            next[i] += 1;
        }
    }
    // a pattern that is not symmetric leaves some column's entries unmet, or met out of place
    debug_assert!(
        (0..n).all(|i| next[i] == ptr[i + 1]),
        "pattern not symmetric"
    );
    debug_assert!((0..n).all(|k| (ptr[k]..ptr[k + 1]).all(|p| row[mirror[p]] == k)));
    mirror
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

    /// The nonzeros of row k of L (columns j < k), into `reach`. `mark` holds, for each node,
    /// the last row that visited it.
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
            // climb from i0 to the first node already visited in this row
            let mut i = i0;
            while mark[i] != k {
                reach.push(i);
                mark[i] = k;
                i = parent[i];
            }
        }
    }

    /// The supernodes and their rows as the layout found them before `supernodes`: each
    /// row's subtree walked twice, once to count each column's entries, once for the rows.
    fn by_walks(ptr: &[usize], row: &[usize], parent: &[usize]) -> [Vec<usize>; 3] {
        let n = parent.len();
        let (mut count, mut mark, mut reach) = (vec![0; n], vec![NONE; n], Vec::new());
        for k in 0..n {
            row_subtree(k, ptr, row, parent, &mut mark, &mut reach);
            reach.iter().for_each(|&j| count[j] += 1);
        }
        let mut bounds = vec![0];
        for j in 1..n {
            if !(parent[j - 1] == j && count[j - 1] == count[j] + 1) {
                bounds.push(j);
            }
        }
        bounds.push(n);
        let mut rows_ptr = vec![0];
        for w in bounds.windows(2) {
            rows_ptr.push(rows_ptr.last().unwrap() + count[w[1] - 1]);
        }
        let mut rows = vec![0; *rows_ptr.last().unwrap()];
        let mut next = rows_ptr.clone();
        mark.fill(NONE);
        for k in 0..n {
            row_subtree(k, ptr, row, parent, &mut mark, &mut reach);
            for &j in &reach {
                let s = bounds.partition_point(|&b| b <= j) - 1;
                if j + 1 == bounds[s + 1] {
                    rows[next[s]] = k;
                    next[s] += 1;
                }
            }
        }
        [bounds, rows_ptr, rows]
    }

    #[test]
    fn supernodes_and_their_rows_are_those_each_row_s_subtree_gives() {
        for (m, seed) in [(1, 1), (6, 2), (9, 7), (17, 5)] {
            let (p, _) = grid(m, seed);
            let n = p.nrows();
            let reversed: Vec<usize> = (0..n).rev().collect();
            let shuffled: Vec<usize> = (0..n).map(|i| (i * 7 + 3) % n).collect();
            for perm in [(0..n).collect::<Vec<_>>(), reversed, shuffled] {
                let lu = StaticLu::<f64>::new(&p, &perm);
                let l = &lu.layout;
                let parent = elimination_tree(n, &l.a_ptr, &l.a_row);
                let [bounds, rows_ptr, rows] = supernodes(&l.a_ptr, &l.a_row, &parent);
                assert_eq!(
                    [&bounds, &rows_ptr, &rows],
                    by_walks(&l.a_ptr, &l.a_row, &parent).each_ref()
                );
                assert!(
                    bounds.len() < n + 1 || n < 2,
                    "no column joined a supernode"
                );
            }
        }
    }

    #[test]
    fn each_entrys_mirror_is_the_entry_across_the_diagonal() {
        let (p, _) = grid(7, 3);
        let (ptr, row) = (p.col_ptr(), p.row_idx());
        let mirror = mirrors(ptr, row);
        let col_of = |k: usize| ptr.partition_point(|&q| q <= k) - 1;
        for k in 0..row.len() {
            let m = mirror[k];
            assert_eq!((row[m], col_of(m)), (col_of(k), row[k]), "entry {k}");
            assert_eq!(mirror[m], k);
        }
    }

    #[test]
    #[cfg(debug_assertions)]
    #[should_panic(expected = "pattern not symmetric")]
    fn a_pattern_that_is_not_symmetric_is_refused_in_a_debug_build() {
        // column 0 holds rows 0 and 1; column 1 holds row 1 only
        let _ = mirrors(&[0, 2, 3], &[0, 1, 1]);
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
    fn wide_supernodes_are_factored_in_blocks() {
        // natural order on a 70 × 70 grid: the band fills, and the last columns form one
        // dense supernode wider than a block, factored by halves
        let (p, v) = grid(70, 3);
        let n = p.nrows();
        let natural: Vec<usize> = (0..n).collect();
        let lu = StaticLu::<f64>::new(&p, &natural);
        let widest = lu.layout.nodes.iter().map(Supernode::width).max().unwrap();
        assert!(widest > 2 * BLOCK, "widest supernode {widest}");
        // no more than the band this order fills (columns of L reach at most 70 rows down)
        let band: usize = (0..n).map(|j| (n - 1 - j).min(70)).sum();
        assert!(lu.entries() <= 2 * band + n && lu.entries() > 2 * band);
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
        let b = mul(&p, &v, &x);
        assert!(error::<f64>(&p, &natural, &v, &b, &x) < 1e-11);
        assert!(error::<f32>(&p, &natural, &v, &b, &x) < 1e-4);
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
