//! The order cells are assembled in, and which of them may run at once: recursive coordinate
//! bisection into halves, with the cells a half shares nodes with the other run first (left)
//! or last (right).

use super::MIN_PART_CELLS;
use crate::mesh::centroid;
use std::sync::atomic::{AtomicBool, Ordering};

/// The order a block's cells are assembled in, and which of them may run at once.
#[derive(Debug)]
pub(super) enum Schedule {
    /// Cells run one after another.
    Cells(Vec<u32>),
    /// Two halves that run at once. `first`: the left half's cells sharing a node with the
    /// right half, run before the rest of the left; `last`: the right half's cells sharing a
    /// node with the left half, run after the rest of the right and after `first`.
    Split {
        first: Vec<u32>,
        left: Box<Schedule>,
        right: Box<Schedule>,
        last: Vec<u32>,
    },
}

impl Schedule {
    /// Split `cells` (`nodes` gives each one's mesh nodes) `depth` times by coordinate
    /// bisection of their centroids along the widest extent. `mark` (one entry per mesh node)
    /// is scratch.
    pub(super) fn build<'m>(
        nodes: &impl Fn(u32) -> &'m [usize],
        coords: &[[f64; 3]],
        mut cells: Vec<u32>,
        depth: usize,
        mark: &mut [u32],
        stamp: &mut u32,
    ) -> Schedule {
        if depth == 0 || cells.len() < 2 * MIN_PART_CELLS {
            cells.sort_unstable();
            return Schedule::Cells(cells);
        }
        let mut keyed: Vec<([f64; 3], u32)> = cells
            .iter()
            .map(|&c| (centroid(coords, nodes(c)), c))
            .collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for (m, _) in &keyed {
            for i in 0..3 {
                lo[i] = lo[i].min(m[i]);
                hi[i] = hi[i].max(m[i]);
            }
        }
        let axis = (0..3)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
            .unwrap_or(0);
        keyed.sort_by(|a, b| a.0[axis].total_cmp(&b.0[axis]).then(a.1.cmp(&b.1)));
        cells = keyed.into_iter().map(|(_, c)| c).collect();
        let right = cells.split_off(cells.len() / 2);
        let left = cells;
        // the cells of one half with a node in a cell of the other
        let mut shared_with = |of: &[u32], other: &[u32]| -> (Vec<u32>, Vec<u32>) {
            *stamp += 1;
            for &c in other {
                for &n in nodes(c) {
                    mark[n] = *stamp;
                }
            }
            let (mut shared, rest): (Vec<u32>, Vec<u32>) = of
                .iter()
                .partition(|&&c| nodes(c).iter().any(|&n| mark[n] == *stamp));
            shared.sort_unstable();
            (shared, rest)
        };
        let (first, left_rest) = shared_with(&left, &right);
        let (last, right_rest) = shared_with(&right, &left);
        Schedule::Split {
            first,
            left: Box::new(Schedule::build(
                nodes,
                coords,
                left_rest,
                depth - 1,
                mark,
                stamp,
            )),
            right: Box::new(Schedule::build(
                nodes,
                coords,
                right_rest,
                depth - 1,
                mark,
                stamp,
            )),
            last,
        }
    }

    /// All cells, in an order consistent with every order `run` may run them in: two cells
    /// sharing a node come in the order they run in.
    pub(super) fn order(&self, out: &mut Vec<u32>) {
        match self {
            Schedule::Cells(c) => out.extend(c),
            Schedule::Split {
                first,
                left,
                right,
                last,
            } => {
                // `first` runs before `left` and `last`; `last` after `right`; `left` shares no
                // node with `right` or `last`, nor `first` with `right`
                out.extend(first);
                left.order(out);
                right.order(out);
                out.extend(last);
            }
        }
    }

    /// Run `cells` on every part, halves at once; results combined in a fixed order.
    pub(super) fn run<T: Send, E: Send>(
        &self,
        cells: &(impl Fn(&[u32]) -> Result<T, E> + Sync),
        combine: &(impl Fn(T, T) -> T + Sync),
    ) -> Result<T, E> {
        match self {
            Schedule::Cells(c) => cells(c),
            Schedule::Split {
                first,
                left,
                right,
                last,
            } => {
                let first_done = AtomicBool::new(false);
                let (a, b) = rayon::join(
                    || {
                        // set even on failure, or the right half would wait forever
                        let a = cells(first);
                        first_done.store(true, Ordering::Release);
                        Ok(combine(a?, left.run(cells, combine)?))
                    },
                    || {
                        let b = right.run(cells, combine)?;
                        // `first` runs at once on the thread that called join (never waiting
                        // itself), so this wait ends; it is normally over before it starts
                        while !first_done.load(Ordering::Acquire) {
                            std::thread::yield_now();
                        }
                        Ok(combine(b, cells(last)?))
                    },
                );
                Ok(combine(a?, b?))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every cell once; the cells that may run at once (one half with its `first`, against
    /// the other half with its `last`, except `first` against `last`) share no node.
    fn check(s: &Schedule, nodes: &dyn Fn(u32) -> Vec<usize>, seen: &mut Vec<u32>) {
        let all = |s: &Schedule| {
            let mut v = Vec::new();
            check(s, nodes, &mut v);
            v
        };
        match s {
            Schedule::Cells(c) => seen.extend(c),
            Schedule::Split {
                first,
                left,
                right,
                last,
            } => {
                let (l, r) = (all(left), all(right));
                let node_set = |cells: &[&[u32]]| -> std::collections::HashSet<usize> {
                    cells
                        .iter()
                        .flat_map(|c| c.iter())
                        .flat_map(|&c| nodes(c))
                        .collect()
                };
                let a = node_set(&[first, &l]);
                assert!(
                    node_set(&[&r]).is_disjoint(&a),
                    "left and right share a node"
                );
                assert!(node_set(&[last]).is_disjoint(&node_set(&[&l])));
                // a real split: both halves have work that runs at once
                assert!(!l.is_empty() && !r.is_empty());
                seen.extend(first.iter().chain(&l).chain(&r).chain(last));
            }
        }
    }

    #[test]
    fn schedule_never_runs_cells_sharing_a_node_at_once() {
        // a 40 × 30 grid of quads, cells numbered in a scrambled order
        let (nx, ny) = (40usize, 30usize);
        let coords: Vec<[f64; 3]> = (0..(nx + 1) * (ny + 1))
            .map(|n| [(n % (nx + 1)) as f64, (n / (nx + 1)) as f64, 0.0])
            .collect();
        let n_cells = nx * ny;
        let conn: Vec<Vec<usize>> = (0..n_cells)
            .map(|c| (c * 7919) % n_cells)
            .map(|c| {
                let (i, j) = (c % nx, c / nx);
                let n0 = j * (nx + 1) + i;
                vec![n0, n0 + 1, n0 + nx + 2, n0 + nx + 1]
            })
            .collect();
        let nodes = |c: u32| -> &[usize] { &conn[c as usize] };
        for depth in 0..4 {
            let (mut mark, mut stamp) = (vec![0u32; coords.len()], 0);
            let cells = (0..n_cells as u32).collect();
            let s = Schedule::build(&nodes, &coords, cells, depth, &mut mark, &mut stamp);
            let mut seen = Vec::new();
            check(&s, &|c| nodes(c).to_vec(), &mut seen);
            seen.sort_unstable();
            assert_eq!(seen, (0..n_cells as u32).collect::<Vec<_>>());
            // the halves are cut across the grid's long side: few cells are shared
            if let Schedule::Split { first, last, .. } = &s {
                assert!(first.len() + last.len() <= 2 * ny, "{}", first.len());
            }
        }
    }
}
