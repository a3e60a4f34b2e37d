//! LDLᵀ's numeric factorisation and solves on faer's supernodal layout, worked over the
//! elimination tree on every thread.
//!
//! faer's supernodal LDLᵀ visits its supernodes one after another and gives threads only to
//! the dense products inside each: most of a 3D factor is many middling fronts, where that
//! leaves every thread but one idle. Here a supernode is left-looking as in faer (it gathers
//! the updates of every earlier supernode whose rows reach it, factors its diagonal block and
//! scales its panel), but supernodes in disjoint subtrees of the elimination tree run at the
//! same time: a subtree is a task once its work is worth one, its children's subtrees run
//! side by side before it, and the large fronts near the root, where the tree offers no
//! more tasks than threads, give their dense products every thread (faer's `Par`). The
//! factor is laid out exactly as faer's (the tests compare the two). What a supernode
//! computes does not depend on where or when it runs: the factor is the same at every thread
//! count.

use super::static_lu::{Real, children_of};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{
    LdltError, cholesky_in_place, cholesky_in_place_scratch,
};
use faer::sparse::SymbolicSparseColMat;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;
use std::sync::Mutex;

/// Subtrees with less work than this many multiply-adds run as one task on one thread.
const TASK_FLOPS: f64 = 2e6;
/// The most bands a wide supernode's gathering is split into (whatever the threads, so that
/// the factor is the same at every thread count).
const MAX_BANDS: f64 = 32.0;
/// Subtrees whose factor has fewer entries than this are solved as one task on one thread.
const TASK_ENTRIES: f64 = 2e5;
/// A supernode whose own work exceeds this many multiply-adds gives its dense products every
/// thread.
const WIDE_FLOPS: f64 = 3e7;
/// A solve applies a supernode's panel below its diagonal block in bands of about this many
/// entries, a task each, where the panel holds at least two bands (the supernodes near the
/// root, which the tree leaves to one thread). The bands follow from the panel's shape, not
/// the threads: the answer is the same at every thread count.
const SOLVE_BAND: usize = 1 << 16;
/// The columns of a wide diagonal block a solve works at a time (their triangle on one
/// thread, the rest of the block in bands).
const SOLVE_BLOCK: usize = 128;

/// The supernodes' elimination tree, the updates each supernode gathers, and where the
/// matrix's entries land in the factor: computed once per pattern.
pub(super) struct TreeLdlt {
    n: usize,
    /// `fwd[new] = old`: the fill-reducing order.
    fwd: Vec<usize>,
    /// Supernode s holds columns `begin[s]..begin[s + 1]` of the permuted matrix.
    begin: Vec<usize>,
    /// The rows below supernode s: `rows[rows_at[s]..rows_at[s] + n_rows[s]]`.
    rows_at: Vec<usize>,
    n_rows: Vec<usize>,
    rows: Vec<usize>,
    /// Supernode s's panel, column-major, in `l[val_at[s]..val_at[s + 1]]`.
    val_at: Vec<usize>,
    /// The entries of A that supernode s starts from: (slot in its panel, slot in A's values).
    a_at: Vec<usize>,
    a: Vec<(usize, usize)>,
    /// The supernodes whose rows reach supernode s, increasing: `upd[upd_at[s]..upd_at[s + 1]]`.
    upd_at: Vec<usize>,
    upd: Vec<usize>,
    /// The tree: children of s in `children[child_at[s]..child_at[s + 1]]`, and the roots.
    child_at: Vec<usize>,
    children: Vec<usize>,
    roots: Vec<usize>,
    /// Multiply-adds of a supernode alone (gathering its updates, factoring its diagonal
    /// block, scaling its panel), of its gathering, and of its subtree.
    work: Vec<f64>,
    gather: Vec<f64>,
    subtree_work: Vec<f64>,
    /// The factor's entries in each supernode's subtree: a solve's work.
    subtree_solve: Vec<f64>,
    /// Maps from a row to its place in a supernode's panel or pattern, one per task at work.
    maps: Mutex<Vec<Vec<usize>>>,
}

/// One task's scratch: the local row of each row of the supernode being worked, a product's
/// buffers, and the dense factorisation's stack.
struct Scratch<T> {
    /// A map of [`TreeLdlt::maps`].
    local: Vec<usize>,
    /// The panel's rows of the rows an update reaches.
    rows: Vec<usize>,
    product: Vec<T>,
    scaled: Vec<T>,
    stack: MemBuffer,
    stack_for: usize,
}

/// The factor's values, written by each supernode into its own panel while others read the
/// panels of supernodes already done.
struct Panels<T> {
    ptr: *mut T,
    len: usize,
}

// SAFETY: a panel is written only by the task working its supernode, and read only by the
// supernodes above it in the tree, which start after it has finished (rayon's join orders them).
unsafe impl<T: Send> Sync for Panels<T> {}

impl<T: Copy> Panels<T> {
    /// # Safety
    /// No other thread writes entry i meanwhile.
    unsafe fn read(&self, i: usize) -> T {
        assert!(i < self.len);
        unsafe { *self.ptr.add(i) }
    }

    /// # Safety
    /// No other thread writes `a..b` while the slice lives.
    unsafe fn get(&self, a: usize, b: usize) -> &[T] {
        assert!(a <= b && b <= self.len);
        unsafe { std::slice::from_raw_parts(self.ptr.add(a), b - a) }
    }

    /// # Safety
    /// No other thread reads or writes `a..b` while the slice lives.
    #[allow(clippy::mut_from_ref)]
    unsafe fn get_mut(&self, a: usize, b: usize) -> &mut [T] {
        assert!(a <= b && b <= self.len);
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(a), b - a) }
    }
}

impl TreeLdlt {
    /// The plan of `symbolic` (supernodal, from [`faer`]'s analysis of `pattern`, whose lower
    /// triangle is factorised); `None` for a simplicial analysis, which faer factors itself.
    pub(super) fn new(
        symbolic: &SymbolicCholesky<usize>,
        pattern: &SymbolicSparseColMat<usize>,
    ) -> Option<TreeLdlt> {
        let SymbolicCholeskyRaw::Supernodal(sn) = symbolic.raw() else {
            return None;
        };
        let n = symbolic.nrows();
        let ns = sn.n_supernodes();
        let begin = sn.supernode_begin().to_vec();
        let begin: Vec<usize> = begin.into_iter().chain([n]).collect();
        let rows_at = sn.col_ptr_for_row_idx().to_vec();
        let n_rows = sn.nnz_per_super().to_vec();
        let rows = sn.row_idx().to_vec();
        let val_at = sn.col_ptr_for_val().to_vec();
        let mut node_of = vec![0; n];
        for s in 0..ns {
            node_of[begin[s]..begin[s + 1]].fill(s);
        }
        let pattern_of = |s: usize| &rows[rows_at[s]..rows_at[s] + n_rows[s]];

        // A's lower triangle, permuted, into the panels: new index of old i is inv[i]
        let (fwd, inv): (Vec<usize>, Vec<usize>) = match symbolic.perm() {
            Some(p) => (p.arrays().0.to_vec(), p.arrays().1.to_vec()),
            None => ((0..n).collect(), (0..n).collect()),
        };
        // each supernode's entries counted, then laid out in one array (a supernode's in its
        // panel's order): a medium made again analyses a new pattern each time
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let lower = |c: usize| (col_ptr[c]..col_ptr[c + 1]).filter(move |&k| row_idx[k] >= c);
        let mut a_at = vec![0usize; ns + 1];
        for c in 0..n {
            for k in lower(c) {
                a_at[node_of[inv[row_idx[k]].min(inv[c])] + 1] += 1;
            }
        }
        for s in 0..ns {
            a_at[s + 1] += a_at[s];
        }
        let mut next = a_at.clone();
        let mut a = vec![(0usize, 0usize); a_at[ns]];
        for c in 0..n {
            for k in lower(c) {
                let r = row_idx[k];
                let (i, j) = (inv[r].max(inv[c]), inv[r].min(inv[c]));
                let s = node_of[j];
                let w = begin[s + 1] - begin[s];
                let li = if i < begin[s + 1] {
                    i - begin[s]
                } else {
                    w + pattern_of(s).partition_point(|&x| x < i)
                };
                a[next[s]] = ((j - begin[s]) * (w + n_rows[s]) + li, k);
                next[s] += 1;
            }
        }
        for s in 0..ns {
            a[a_at[s]..a_at[s + 1]].sort_unstable();
        }

        // who updates whom, and the tree (a supernode's parent holds its first row below it)
        let mut upd_of: Vec<Vec<usize>> = vec![Vec::new(); ns];
        for d in 0..ns {
            let mut last = usize::MAX;
            for &r in pattern_of(d) {
                let s = node_of[r];
                if s != last {
                    upd_of[s].push(d);
                    last = s;
                }
            }
        }
        let parent: Vec<usize> = (0..ns)
            .map(|d| pattern_of(d).first().map_or(usize::MAX, |&r| node_of[r]))
            .collect();
        let roots = (0..ns).filter(|&d| parent[d] == usize::MAX).collect();
        let (upd_at, upd) = flatten(upd_of);
        let (child_at, children) = children_of(&parent);
        // d's update of s: its rows from s's first column down, times its rows in s, times
        // its width
        let mut gather = vec![0.0; ns];
        for d in 0..ns {
            let dpat = pattern_of(d);
            let dw = (begin[d + 1] - begin[d]) as f64;
            let mut p0 = 0;
            while p0 < dpat.len() {
                let s = node_of[dpat[p0]];
                let nm = dpat[p0..].partition_point(|&r| r < begin[s + 1]);
                gather[s] += ((dpat.len() - p0) * nm) as f64 * dw;
                p0 += nm;
            }
        }
        let work: Vec<f64> = (0..ns)
            .map(|s| {
                let w = (begin[s + 1] - begin[s]) as f64;
                w * w * w / 3.0 + n_rows[s] as f64 * w * w + gather[s]
            })
            .collect();
        // children are numbered below their parent: one increasing sweep sums the subtrees
        let mut subtree_work = work.clone();
        let mut subtree_solve: Vec<f64> = (0..ns)
            .map(|s| (val_at[s + 1] - val_at[s]) as f64)
            .collect();
        for s in 0..ns {
            for &c in &children[child_at[s]..child_at[s + 1]] {
                subtree_work[s] += subtree_work[c];
                subtree_solve[s] += subtree_solve[c];
            }
        }
        Some(TreeLdlt {
            n,
            fwd,
            begin,
            rows_at,
            n_rows,
            rows,
            val_at,
            a_at,
            a,
            upd_at,
            upd,
            child_at,
            children,
            roots,
            work,
            gather,
            subtree_work,
            subtree_solve,
            maps: Mutex::new(Vec::new()),
        })
    }

    fn pattern(&self, s: usize) -> &[usize] {
        &self.rows[self.rows_at[s]..self.rows_at[s] + self.n_rows[s]]
    }

    fn children(&self, s: usize) -> &[usize] {
        &self.children[self.child_at[s]..self.child_at[s + 1]]
    }

    /// Numeric LDLᵀ of `values` (A's values on the analysed pattern) into `l`, laid out as
    /// faer's supernodal factor; the permuted equation of a zero pivot on failure.
    pub(super) fn factor<T: Real + Send + Sync>(
        &self,
        l: &mut [T],
        values: &[T],
    ) -> Result<(), usize> {
        assert_eq!(l.len(), *self.val_at.last().unwrap());
        let panels = Panels {
            ptr: l.as_mut_ptr(),
            len: l.len(),
        };
        let work = Work {
            plan: self,
            panels: &panels,
            values,
            pool: Mutex::new(Vec::new()),
            failed: Mutex::new(None),
        };
        self.roots.par_iter().for_each(|&s| work.subtree(s));
        for sc in work.pool.into_inner().unwrap() {
            self.give_map(sc.local);
        }
        match work.failed.into_inner().unwrap() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

impl TreeLdlt {
    /// b ← (L D Lᵀ)⁻¹ b with the factor `l` (from [`TreeLdlt::factor`]), `x` its scratch.
    /// Forward, subtrees side by side: a subtree's task writes the unknowns of its own
    /// supernodes and sums what it sends above itself apart, and its parent adds those sums
    /// in; backward from the roots, each supernode reading its finished ancestors. The
    /// tasks and the order of every sum are the tree's, so the answer is the same at every
    /// thread count.
    pub(super) fn solve<T: Real + Send + Sync>(&self, l: &[T], b: &mut [T], x: &mut Vec<T>) {
        x.clear();
        x.extend(self.fwd.iter().map(|&old| b[old]));
        let shared = Panels {
            ptr: x.as_mut_ptr(),
            len: x.len(),
        };
        let forward = |s: usize| {
            let sent = self.forward_tree(s, l, &shared);
            debug_assert!(sent.is_empty(), "a root sends nothing above itself");
        };
        self.roots.par_iter().for_each(|&s| forward(s));
        self.roots
            .par_iter()
            .for_each(|&s| self.backward_tree(s, l, &shared));
        for (&old, &v) in self.fwd.iter().zip(x.iter()) {
            b[old] = v;
        }
    }

    /// The supernodes of s's subtree, increasing (each after its descendants; faer does not
    /// number a subtree's supernodes together).
    fn subtree_nodes(&self, s: usize) -> Vec<usize> {
        let mut nodes = vec![s];
        let mut k = 0;
        while k < nodes.len() {
            nodes.extend_from_slice(self.children(nodes[k]));
            k += 1;
        }
        nodes.sort_unstable();
        nodes
    }

    /// A map of rows, from the pool or new (its entries are set before they are read).
    fn take_map(&self) -> Vec<usize> {
        let pooled = self.maps.lock().unwrap().pop();
        pooled.unwrap_or_else(|| vec![0; self.n])
    }

    fn give_map(&self, map: Vec<usize>) {
        self.maps.lock().unwrap().push(map);
    }

    /// Supernode s's columns `sb..se`, the rows below them, and its panel of `l` split into
    /// the diagonal block and the rows below.
    fn panel<'l, T: Real>(
        &self,
        s: usize,
        l: &'l [T],
    ) -> (usize, usize, &[usize], MatRef<'l, T>, MatRef<'l, T>) {
        let (sb, se) = (self.begin[s], self.begin[s + 1]);
        let pat = self.pattern(s);
        let ls = &l[self.val_at[s]..self.val_at[s + 1]];
        let (top, bot) =
            MatRef::from_column_major_slice(ls, se - sb + pat.len(), se - sb).split_at_row(se - sb);
        (sb, se, pat, top, bot)
    }

    /// L⁻¹ b on the unknowns of s's subtree; what it subtracts from the rows below s (s's
    /// pattern), returned in that pattern's order.
    fn forward_tree<T: Real + Send + Sync>(&self, s: usize, l: &[T], x: &Panels<T>) -> Vec<T> {
        let se = self.begin[s + 1];
        let pat = self.pattern(s);
        let mut sent = vec![T::of(0.0); pat.len()];
        let mut local = self.take_map();
        for (i, &r) in pat.iter().enumerate() {
            local[r] = i;
        }
        let mut tmp = Vec::new();
        let out = |r: usize, v: T, sent: &mut [T]| {
            if r < se {
                // SAFETY: a row above s's last column belongs to s's subtree, this task's
                unsafe { x.get_mut(r, r + 1)[0] -= v };
            } else {
                sent[local[r]] += v;
            }
        };
        if self.subtree_solve[s] < TASK_ENTRIES {
            for t in self.subtree_nodes(s) {
                self.forward_node(t, l, x, &mut tmp, |r, v| out(r, v, &mut sent));
            }
        } else {
            let from: Vec<Vec<T>> = self
                .children(s)
                .par_iter()
                .map(|&c| self.forward_tree(c, l, x))
                .collect();
            for (&c, got) in self.children(s).iter().zip(&from) {
                for (&r, &v) in self.pattern(c).iter().zip(got) {
                    out(r, v, &mut sent);
                }
            }
            self.forward_node(s, l, x, &mut tmp, |r, v| out(r, v, &mut sent));
        }
        self.give_map(local);
        sent
    }

    /// Supernode s's unknowns of L⁻¹ b (all that reach them already subtracted), and `out`
    /// told what they subtract from each row below.
    fn forward_node<T: Real + Send + Sync>(
        &self,
        s: usize,
        l: &[T],
        x: &Panels<T>,
        tmp: &mut Vec<T>,
        mut out: impl FnMut(usize, T),
    ) {
        let (sb, se, pat, top, bot) = self.panel(s, l);
        // SAFETY: only this task writes supernode s's unknowns
        let xs = unsafe { x.get_mut(sb, se) };
        lower_solve(top, xs);
        if pat.is_empty() {
            return;
        }
        grow(tmp, pat.len());
        let xm = MatRef::from_column_major_slice(xs, se - sb, 1);
        let product = |r0: usize, out: &mut [T]| {
            let len = out.len();
            faer::linalg::matmul::matmul(
                MatMut::from_column_major_slice_mut(out, len, 1),
                Accum::Replace,
                bot.subrows(r0, len),
                xm,
                T::of(1.0),
                Par::Seq,
            )
        };
        match band_of(pat.len(), se - sb) {
            None => product(0, &mut tmp[..pat.len()]),
            Some(rows) => tmp[..pat.len()]
                .par_chunks_mut(rows)
                .enumerate()
                .for_each(|(b, out)| product(b * rows, out)),
        }
        for (&r, &v) in pat.iter().zip(tmp.iter()) {
            out(r, v);
        }
    }

    fn backward_tree<T: Real + Send + Sync>(&self, s: usize, l: &[T], x: &Panels<T>) {
        let mut tmp = Vec::new();
        if self.subtree_solve[s] < TASK_ENTRIES {
            for t in self.subtree_nodes(s).into_iter().rev() {
                self.backward(t, l, x, &mut tmp);
            }
            return;
        }
        self.backward(s, l, x, &mut tmp);
        self.children(s)
            .par_iter()
            .for_each(|&c| self.backward_tree(c, l, x));
    }

    /// Supernode s's unknowns of L⁻ᵀ D⁻¹ y, from those of its ancestors (finished).
    fn backward<T: Real + Send + Sync>(&self, s: usize, l: &[T], x: &Panels<T>, tmp: &mut Vec<T>) {
        let (sb, se, pat, top, bot) = self.panel(s, l);
        grow(tmp, pat.len());
        for (t, &r) in tmp.iter_mut().zip(pat) {
            // SAFETY: r is an ancestor's unknown, finished
            *t = unsafe { x.read(r) };
        }
        // SAFETY: only this task writes supernode s's unknowns
        let xs = unsafe { x.get_mut(sb, se) };
        for (j, v) in xs.iter_mut().enumerate() {
            *v /= top[(j, j)];
        }
        if !pat.is_empty() {
            let y = MatRef::from_column_major_slice(&tmp[..pat.len()], pat.len(), 1);
            let product = |c0: usize, out: &mut [T]| {
                let len = out.len();
                faer::linalg::matmul::matmul(
                    MatMut::from_column_major_slice_mut(out, len, 1),
                    Accum::Add,
                    bot.subcols(c0, len).transpose(),
                    y,
                    T::of(-1.0),
                    Par::Seq,
                )
            };
            match band_of(se - sb, pat.len()) {
                None => product(0, xs),
                Some(cols) => xs
                    .par_chunks_mut(cols)
                    .enumerate()
                    .for_each(|(b, out)| product(b * cols, out)),
            }
        }
        upper_solve(top, xs);
    }
}

impl TreeLdlt {
    /// The numeric factorisation's speed-up on `p` threads as its elimination tree predicts
    /// it, counting multiply-adds only: the threads are mapped onto the subtrees in
    /// proportion to their work (as MUMPS maps its processes), a subtree given less than a
    /// thread shares one, a supernode gathers its updates in at most [`MAX_BANDS`] bands and
    /// factors its diagonal block and panel in pieces of at least [`WIDE_FLOPS`]` / 8`, and no
    /// forest finishes before its work over the threads.
    /// What it leaves out (memory traffic, the tasks' start, threads waiting for a parent)
    /// only lowers the speed-up, so this is a bound to measure against.
    pub(super) fn predicted_speedup(&self, p: f64) -> f64 {
        let total: f64 = self.work.iter().sum();
        // the gathering in its bands, the diagonal block and panel in pieces
        let own = |s: usize, ps: f64| {
            let (gather, dense) = (self.gather[s], self.work[s] - self.gather[s]);
            let bands = bands(gather) as f64;
            let pieces = (dense / (WIDE_FLOPS / 8.0)).max(1.0);
            gather / ps.min(bands).max(1.0) + dense / ps.min(pieces).max(1.0)
        };
        total / self.mapped_time(&self.roots, p, &self.subtree_work, 0.0, &own)
    }

    /// A solve's speed-up on `p` threads as the tree predicts it, counting the factor's
    /// entries read (a solve reads each once each way, and memory, not arithmetic, is what
    /// it waits on): the threads mapped onto the subtrees as in [`Self::predicted_speedup`],
    /// a subtree of fewer than [`TASK_ENTRIES`] entries one task, a supernode's diagonal
    /// block by blocks ([`lower_solve`]) and its panel below in its bands ([`SOLVE_BAND`]).
    /// It leaves out the memory's bandwidth, which all threads share: where they saturate
    /// it, the solves stop gaining, whatever the tree allows.
    pub(super) fn predicted_solve_speedup(&self, p: f64) -> f64 {
        let total: f64 = self.roots.iter().map(|&s| self.subtree_solve[s]).sum();
        let own = |s: usize, ps: f64| {
            let (w, below) = (self.begin[s + 1] - self.begin[s], self.n_rows[s]);
            let bands = band_of(below, w).map_or(1.0, |b| below.div_ceil(b) as f64);
            // the diagonal block: by blocks, their triangles one after another
            let (tri, square) = match blocked(w) {
                true => ((w * SOLVE_BLOCK / 2) as f64, (w * w / SOLVE_BAND) as f64),
                false => ((w * w) as f64, 1.0),
            };
            tri + ((w * w) as f64 - tri) / ps.min(square).max(1.0)
                + (w * below) as f64 / ps.min(bands).max(1.0)
        };
        total / self.mapped_time(&self.roots, p, &self.subtree_solve, TASK_ENTRIES, &own)
    }

    /// The time of the forest `trees` on `p` threads, `size[s]` the work of s's subtree: the
    /// threads mapped onto the subtrees in proportion to their work, a subtree of less than
    /// `task` run whole on one thread, `own(s, ps)` supernode s's own time on its `ps`
    /// threads, and no forest finished before its work over the threads.
    fn mapped_time(
        &self,
        trees: &[usize],
        p: f64,
        size: &[f64],
        task: f64,
        own: &dyn Fn(usize, f64) -> f64,
    ) -> f64 {
        let sum: f64 = trees.iter().map(|&s| size[s]).sum();
        if p <= 1.0 || sum == 0.0 {
            return sum;
        }
        let longest = trees
            .iter()
            .map(|&s| {
                if size[s] < task {
                    return size[s];
                }
                let ps = p * size[s] / sum;
                own(s, ps) + self.mapped_time(self.children(s), ps, size, task, own)
            })
            .fold(0.0, f64::max);
        longest.max(sum / p)
    }

    /// Both predictions on `p` threads.
    pub(super) fn speedups(&self, p: f64) -> super::Speedup {
        super::Speedup {
            factor: self.predicted_speedup(p),
            solve: self.predicted_solve_speedup(p),
        }
    }

    /// The supernodes whose panel below a solve applies in bands, and those whose diagonal
    /// block it works by blocks.
    #[cfg(test)]
    pub(super) fn banded(&self) -> (usize, usize) {
        let width = |s: usize| self.begin[s + 1] - self.begin[s];
        let ns = self.n_rows.len();
        (
            (0..ns)
                .filter(|&s| band_of(self.n_rows[s], width(s)).is_some())
                .count(),
            (0..ns).filter(|&s| blocked(width(s))).count(),
        )
    }
}

/// One numeric factorisation under way.
struct Work<'a, T> {
    plan: &'a TreeLdlt,
    panels: &'a Panels<T>,
    values: &'a [T],
    pool: Mutex<Vec<Scratch<T>>>,
    /// The first zero pivot met, by any task.
    failed: Mutex<Option<usize>>,
}

impl<T: Real + Send + Sync> Work<'_, T> {
    fn scratch(&self) -> Scratch<T> {
        self.pool.lock().unwrap().pop().unwrap_or_else(|| Scratch {
            local: self.plan.take_map(),
            rows: Vec::new(),
            product: Vec::new(),
            scaled: Vec::new(),
            stack: MemBuffer::new(faer::dyn_stack::StackReq::EMPTY),
            stack_for: 0,
        })
    }

    fn give_back(&self, s: Scratch<T>) {
        self.pool.lock().unwrap().push(s);
    }

    fn stop(&self) -> bool {
        self.failed.lock().unwrap().is_some()
    }

    /// Supernode s's subtree: small ones as one task, larger ones their children's subtrees
    /// side by side, then s.
    fn subtree(&self, s: usize) {
        let plan = self.plan;
        if plan.subtree_work[s] < TASK_FLOPS {
            return self.sequential(plan.subtree_nodes(s));
        }
        plan.children(s).par_iter().for_each(|&c| self.subtree(c));
        if self.stop() {
            return;
        }
        let par = if plan.work[s] > WIDE_FLOPS {
            super::dense_par()
        } else {
            Par::Seq
        };
        let mut sc = self.scratch();
        self.node(s, par, &mut sc);
        self.give_back(sc);
    }

    /// Small subtrees' supernodes, one after another on this thread.
    fn sequential(&self, nodes: impl IntoIterator<Item = usize>) {
        let mut sc = self.scratch();
        for s in nodes {
            if self.stop() {
                break;
            }
            self.node(s, Par::Seq, &mut sc);
        }
        self.give_back(sc);
    }

    /// Supernode s: A's entries, the updates of the supernodes below it, its diagonal block's
    /// LDLᵀ and its panel L_R = A_R L⁻ᵀ D⁻¹. A wide one gathers its updates on every thread,
    /// each a band of its columns.
    fn node(&self, s: usize, par: Par, sc: &mut Scratch<T>) {
        let plan = self.plan;
        let (sb, se) = (plan.begin[s], plan.begin[s + 1]);
        let w = se - sb;
        let pat = plan.pattern(s);
        let m = w + pat.len();
        // SAFETY: only this task writes supernode s's panel; the panels read below are of
        // supernodes in s's subtree, all finished
        let ls = unsafe { self.panels.get_mut(plan.val_at[s], plan.val_at[s + 1]) };
        let bands = match par {
            Par::Seq => 1,
            _ => bands(plan.gather[s]),
        };
        if bands == 1 {
            self.local_rows(s, sc);
            self.gather(s, 0, ls, sc);
        } else {
            // bands of equal work: column c gathers rows c..m
            let mut cuts = vec![0];
            let per = (m * (m + 1) - (m - w) * (m - w + 1)) as f64 / 2.0 / bands as f64;
            let mut acc = 0.0;
            for c in 0..w {
                acc += (m - c) as f64;
                if acc >= per * cuts.len() as f64 && c + 1 < w {
                    cuts.push(c + 1);
                }
            }
            cuts.push(w);
            let mut parts = Vec::new();
            let mut rest = &mut ls[..];
            for b in cuts.windows(2) {
                let (band, r) = rest.split_at_mut((b[1] - b[0]) * m);
                parts.push((b[0], band));
                rest = r;
            }
            parts.into_par_iter().for_each(|(c0, band)| {
                let mut sc = self.scratch();
                self.local_rows(s, &mut sc);
                self.gather(s, c0, band, &mut sc);
                self.give_back(sc);
            });
        }
        let mut lsm = MatMut::from_column_major_slice_mut(ls, m, w);
        let (mut top, mut bot) = lsm.as_mut().split_at_row_mut(w);
        if sc.stack_for < w {
            sc.stack = MemBuffer::new(cholesky_in_place_scratch::<T>(w, par, Default::default()));
            sc.stack_for = w;
        }
        let stack = MemStack::new(&mut sc.stack);
        if let Err(LdltError::ZeroPivot { index }) = cholesky_in_place(
            top.as_mut(),
            Default::default(),
            par,
            stack,
            Default::default(),
        ) {
            let mut f = self.failed.lock().unwrap();
            let e = f.get_or_insert(sb + index);
            *e = (*e).min(sb + index);
            return;
        }
        for j in 1..w {
            for i in 0..j {
                top[(i, j)] = T::of(0.0);
            }
        }
        faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(
            top.as_ref(),
            bot.as_mut().transpose_mut(),
            par,
        );
        for j in 0..w {
            let inv = T::of(1.0) / top[(j, j)];
            for i in 0..pat.len() {
                let v = bot[(i, j)] * inv;
                bot[(i, j)] = v;
            }
        }
    }

    /// `sc.local[r]`: the row of supernode s's panel that holds its row r below it.
    fn local_rows(&self, s: usize, sc: &mut Scratch<T>) {
        let w = self.plan.begin[s + 1] - self.plan.begin[s];
        for (i, &r) in self.plan.pattern(s).iter().enumerate() {
            sc.local[r] = w + i;
        }
    }

    /// Columns `c0..` of supernode s's panel (`band`, whole columns): A's entries less the
    /// updates of every supernode whose rows reach them.
    fn gather(&self, s: usize, c0: usize, band: &mut [T], sc: &mut Scratch<T>) {
        let plan = self.plan;
        let (sb, se) = (plan.begin[s], plan.begin[s + 1]);
        let m = se - sb + plan.n_rows[s];
        let c1 = c0 + band.len() / m;
        let (g0, g1) = (sb + c0, sb + c1);
        band.fill(T::of(0.0));
        let entries = &plan.a[plan.a_at[s]..plan.a_at[s + 1]];
        let from = entries.partition_point(|&(at, _)| at < c0 * m);
        for &(at, k) in &entries[from..] {
            if at >= c1 * m {
                break;
            }
            band[at - c0 * m] = self.values[k];
        }
        for &d in &plan.upd[plan.upd_at[s]..plan.upd_at[s + 1]] {
            let dw = plan.begin[d + 1] - plan.begin[d];
            let dpat = plan.pattern(d);
            let dm = dw + dpat.len();
            let p0 = dpat.partition_point(|&r| r < g0);
            let nm = dpat[p0..].partition_point(|&r| r < g1);
            if nm == 0 {
                continue;
            }
            let nr = dpat.len() - p0;
            // SAFETY: d is below s in the tree, finished before s started
            let ld = unsafe { self.panels.get(plan.val_at[d], plan.val_at[d + 1]) };
            let ld = MatRef::from_column_major_slice(ld, dm, dw);
            // product = L_{rows ≥ g0} · D · L_{rows in the band}ᵀ, nr × nm
            let below = ld.subrows(dw + p0, nr);
            let mid = ld.subrows(dw + p0, nm);
            grow(&mut sc.scaled, nm * dw);
            grow(&mut sc.product, nr * nm);
            for j in 0..dw {
                let dj = ld[(j, j)];
                for (i, v) in sc.scaled[j * nm..(j + 1) * nm].iter_mut().enumerate() {
                    *v = mid[(i, j)] * dj;
                }
            }
            let scaled = MatRef::from_column_major_slice(&sc.scaled[..nm * dw], nm, dw);
            let prod = &mut sc.product[..nr * nm];
            faer::linalg::matmul::matmul(
                MatMut::from_column_major_slice_mut(prod, nr, nm),
                Accum::Replace,
                below,
                scaled.transpose(),
                T::of(1.0),
                Par::Seq,
            );
            // the panel's row of each row of the product, then the product's lower part out
            let rows = &dpat[p0..];
            sc.rows.clear();
            sc.rows.extend(
                rows.iter()
                    .map(|&r| if r < se { r - sb } else { sc.local[r] }),
            );
            for j in 0..nm {
                let col = &mut band[(rows[j] - g0) * m..][..m];
                for (&li, &v) in sc.rows[j..].iter().zip(&prod[j * nr + j..(j + 1) * nr]) {
                    col[li] -= v;
                }
            }
        }
    }
}

/// The bands of columns a wide supernode gathers its updates in, side by side: a quarter of
/// [`WIDE_FLOPS`] each, at most [`MAX_BANDS`].
fn bands(gather: f64) -> usize {
    (gather / (WIDE_FLOPS / 4.0)).clamp(1.0, MAX_BANDS) as usize
}

/// `v` at least `len` long.
/// x ← L⁻¹ x, L the unit lower triangle of `top`. A diagonal block of at least two bands
/// ([`SOLVE_BAND`]) is worked [`SOLVE_BLOCK`] columns at a time: the block's triangle on one
/// thread, then its columns below it applied to the rows below in bands, a task each.
fn lower_solve<T: Real + Send + Sync>(top: MatRef<'_, T>, x: &mut [T]) {
    let w = x.len();
    if !blocked(w) {
        let xm = MatMut::from_column_major_slice_mut(x, w, 1);
        return faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(
            top,
            xm,
            Par::Seq,
        );
    }
    for c0 in (0..w).step_by(SOLVE_BLOCK) {
        let nb = SOLVE_BLOCK.min(w - c0);
        let (head, below) = x.split_at_mut(c0 + nb);
        let xb = MatMut::from_column_major_slice_mut(&mut head[c0..], nb, 1);
        faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(
            top.submatrix(c0, c0, nb, nb),
            xb,
            Par::Seq,
        );
        let xb = MatRef::from_column_major_slice(&head[c0..], nb, 1);
        let rows = SOLVE_BAND.div_ceil(nb);
        below.par_chunks_mut(rows).enumerate().for_each(|(b, out)| {
            let len = out.len();
            faer::linalg::matmul::matmul(
                MatMut::from_column_major_slice_mut(out, len, 1),
                Accum::Add,
                top.submatrix(c0 + nb + b * rows, c0, len, nb),
                xb,
                T::of(-1.0),
                Par::Seq,
            )
        });
    }
}

/// x ← L⁻ᵀ x, L the unit lower triangle of `top`, by blocks as in [`lower_solve`] from the
/// last: each block's triangle, then its rows of L applied to the unknowns before it, in
/// bands of those unknowns.
fn upper_solve<T: Real + Send + Sync>(top: MatRef<'_, T>, x: &mut [T]) {
    let w = x.len();
    if !blocked(w) {
        let xm = MatMut::from_column_major_slice_mut(x, w, 1);
        return faer::linalg::triangular_solve::solve_unit_upper_triangular_in_place(
            top.transpose(),
            xm,
            Par::Seq,
        );
    }
    let blocks = w.div_ceil(SOLVE_BLOCK);
    for k in (0..blocks).rev() {
        let c0 = k * SOLVE_BLOCK;
        let nb = SOLVE_BLOCK.min(w - c0);
        let (before, rest) = x.split_at_mut(c0);
        let xb = MatMut::from_column_major_slice_mut(&mut rest[..nb], nb, 1);
        faer::linalg::triangular_solve::solve_unit_upper_triangular_in_place(
            top.submatrix(c0, c0, nb, nb).transpose(),
            xb,
            Par::Seq,
        );
        let xb = MatRef::from_column_major_slice(&rest[..nb], nb, 1);
        let cols = SOLVE_BAND.div_ceil(nb);
        before
            .par_chunks_mut(cols)
            .enumerate()
            .for_each(|(b, out)| {
                let len = out.len();
                faer::linalg::matmul::matmul(
                    MatMut::from_column_major_slice_mut(out, len, 1),
                    Accum::Add,
                    top.submatrix(c0, b * cols, nb, len).transpose(),
                    xb,
                    T::of(-1.0),
                    Par::Seq,
                )
            });
    }
}

/// Whether a solve works a diagonal block `w` wide by blocks: where it holds two bands.
fn blocked(w: usize) -> bool {
    w * w >= 2 * SOLVE_BAND && w >= 2 * SOLVE_BLOCK
}

/// The lines of a band of a panel with `lines` lines of `length` entries each ([`SOLVE_BAND`]),
/// or `None` where the panel is a single band.
fn band_of(lines: usize, length: usize) -> Option<usize> {
    let band = SOLVE_BAND.div_ceil(length.max(1)).max(1);
    (lines >= 2 * band).then_some(band)
}

fn grow<T: Real>(v: &mut Vec<T>, len: usize) {
    if v.len() < len {
        v.resize(len, T::of(0.0));
    }
}

/// Lists as one array and where each starts.
fn flatten<X>(lists: Vec<Vec<X>>) -> (Vec<usize>, Vec<X>) {
    let mut at = Vec::with_capacity(lists.len() + 1);
    at.push(0);
    let mut all = Vec::new();
    for l in lists {
        all.extend(l);
        at.push(all.len());
    }
    (at, all)
}
