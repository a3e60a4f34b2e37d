//! The fill-reducing ordering: METIS nested dissection of the mesh nodes' graph, or faer's
//! approximate minimum degree of it (where the run asks for it, or where METIS fails).

use crate::dofs::{Ordering, Structure};
use faer::sparse::SymbolicSparseColMat;

/// The equations of a block as its ordering sees them: each one's mesh node, and how the
/// run orders them ([`Structure::ordering`]).
pub(super) struct Nodes {
    pub node: Vec<u32>,
    pub ordering: Ordering,
}

/// The mesh node of each of the equations `eqs`, and the structure's ordering, for
/// [`fill_reducing`].
pub(super) fn nodes_of(s: &Structure, eqs: &[usize]) -> Nodes {
    Nodes {
        node: eqs.iter().map(|&e| s.node[e]).collect(),
        ordering: s.ordering,
    }
}

/// The fill-reducing ordering of a symmetric pattern whose equations stand at `nodes`, as
/// they ask: (forward, inverse) with `forward[new] = old`, a node's unknowns together.
pub(super) fn fill_reducing(
    p: &SymbolicSparseColMat<usize>,
    nodes: &Nodes,
) -> (Vec<usize>, Vec<usize>) {
    ordered(p, &nodes.node, nodes.ordering, None)
}

/// Graphs of at least this many mesh nodes are cut by the best of [`SEPARATOR_TRIES`]
/// separators at every level of the nested dissection (METIS_OPTION_NSEPS) instead of the
/// first. On Table 2's H1 block-plate-3d: at 64×64 (278 850 nodes, 1.1M unknowns) 5.5 % fewer
/// factor entries (2 280 M against 2 414 M) and 10–13 % less solver time over a factorisation
/// and 100 GMRES iterations with it, for 16–20 s more of METIS once per run; at 32×32 (37 026
/// nodes) 0.9 % fewer entries, not worth its time.
pub(super) const SEPARATOR_TRIES_FROM: usize = 100_000;
pub(super) const SEPARATOR_TRIES: i32 = 5;

/// Fill-reducing ordering of a symmetric pattern: METIS nested dissection of the graph whose
/// vertices are mesh nodes (all unknowns of a node stay together), expanded to equations.
/// Returns (forward, inverse) with `forward[new] = old`.
#[cfg(test)]
pub(super) fn nested_dissection(
    p: &SymbolicSparseColMat<usize>,
    node: &[u32],
) -> (Vec<usize>, Vec<usize>) {
    nested_dissection_trying(p, node, None)
}

/// [`nested_dissection`], with `tries` separators per level if given (else as many as the
/// graph's size calls for).
#[cfg(test)]
pub(super) fn nested_dissection_trying(
    p: &SymbolicSparseColMat<usize>,
    node: &[u32],
    tries: Option<i32>,
) -> (Vec<usize>, Vec<usize>) {
    ordered(p, node, Ordering::NestedDissection, tries)
}

/// The mesh nodes' graph of `p` ordered as `how` says (nested dissection with `tries`
/// separators per level if given), expanded to equations.
fn ordered(
    p: &SymbolicSparseColMat<usize>,
    node: &[u32],
    how: Ordering,
    tries: Option<i32>,
) -> (Vec<usize>, Vec<usize>) {
    let n = p.nrows();
    // compact node ids, in the order of their first equation
    let mut id = vec![u32::MAX; node.iter().map(|&v| v as usize + 1).max().unwrap_or(0)];
    let mut nv = 0;
    let vertex: Vec<usize> = node
        .iter()
        .map(|&v| {
            if id[v as usize] == u32::MAX {
                id[v as usize] = nv as u32;
                nv += 1;
            }
            id[v as usize] as usize
        })
        .collect();
    // each vertex's equations, then its neighbours through their columns: sorted, once each
    let mut eq_at = vec![0usize; nv + 1];
    for &v in &vertex {
        eq_at[v + 1] += 1;
    }
    for v in 0..nv {
        eq_at[v + 1] += eq_at[v];
    }
    let mut eqs = vec![0usize; n];
    let mut next = eq_at.clone();
    for (e, &v) in vertex.iter().enumerate() {
        eqs[next[v]] = e;
        next[v] += 1;
    }
    let (cp, ri) = (p.col_ptr(), p.row_idx());
    let mut seen = vec![usize::MAX; nv];
    let mut xadj = Vec::with_capacity(nv + 1);
    let mut adjncy: Vec<i32> = Vec::with_capacity(cp[n] / 2);
    xadj.push(0i32);
    for b in 0..nv {
        let start = adjncy.len();
        for &j in &eqs[eq_at[b]..eq_at[b + 1]] {
            for &i in &ri[cp[j]..cp[j + 1]] {
                let a = vertex[i];
                if a != b && seen[a] != b {
                    seen[a] = b;
                    adjncy.push(a as i32);
                }
            }
        }
        adjncy[start..].sort_unstable();
        xadj.push(adjncy.len() as i32);
    }
    let order: Vec<usize> = match how {
        _ if nv <= 1 || adjncy.is_empty() => (0..nv).collect(),
        Ordering::MinimumDegree => minimum_degree(&xadj, &adjncy),
        Ordering::NestedDissection => {
            let separators = tries.unwrap_or(if nv >= SEPARATOR_TRIES_FROM {
                SEPARATOR_TRIES
            } else {
                1
            });
            metis_nested_dissection(&mut xadj, &mut adjncy, separators)
        }
    };
    // equations of each vertex, in their original order
    let fwd: Vec<usize> = (order.iter())
        .flat_map(|&v| eqs[eq_at[v]..eq_at[v + 1]].iter().copied())
        .collect();
    let mut inv = vec![0; n];
    for (new, &old) in fwd.iter().enumerate() {
        inv[old] = new;
    }
    (fwd, inv)
}

/// METIS's nested dissection of the graph `xadj`/`adjncy` (CSR, sorted, without self loops, at
/// least two vertices and an edge), `separators` tried per level: `order[new] = old`. Where
/// METIS fails for itself (short of memory, say), the minimum degree: the natural order would
/// fill a 3D factor without bound, the minimum degree fills it about as little as METIS.
fn metis_nested_dissection(xadj: &mut [i32], adjncy: &mut [i32], separators: i32) -> Vec<usize> {
    let nv = xadj.len() - 1;
    let mut nvtxs = nv as i32;
    let mut perm = vec![0i32; nv];
    let mut iperm = vec![0i32; nv];
    let mut options = [-1i32; metis_sys::METIS_NOPTIONS as usize];
    // SAFETY: METIS reads xadj/adjncy (a valid CSR graph without self loops) and writes
    // nv entries of perm and iperm; options is set to defaults (−1) before the call.
    let status = crate::mesh::partition::metis(|| unsafe {
        metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
        options[metis_sys::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
        options[metis_sys::moptions_et_METIS_OPTION_NSEPS as usize] = separators;
        metis_sys::METIS_NodeND(
            &mut nvtxs,
            xadj.as_mut_ptr(),
            adjncy.as_mut_ptr(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    });
    if status == metis_sys::rstatus_et_METIS_OK {
        perm.iter().map(|&v| v as usize).collect()
    } else {
        minimum_degree(xadj, adjncy)
    }
}

/// faer's approximate minimum degree ordering of the graph `xadj`/`adjncy` (CSR, sorted,
/// without self loops): `order[new] = old`. The natural order where even that fails.
fn minimum_degree(xadj: &[i32], adjncy: &[i32]) -> Vec<usize> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::sparse::linalg::amd;
    let nv = xadj.len() - 1;
    let graph = SymbolicSparseColMat::new_checked(
        nv,
        nv,
        xadj.iter().map(|&k| k as usize).collect(),
        None,
        adjncy.iter().map(|&v| v as usize).collect(),
    );
    let (mut perm, mut inv) = (vec![0usize; nv], vec![0usize; nv]);
    let mut mem = MemBuffer::new(amd::order_scratch::<usize>(nv, adjncy.len()));
    match amd::order(
        &mut perm,
        &mut inv,
        graph.as_ref(),
        amd::Control::default(),
        MemStack::new(&mut mem),
    ) {
        Ok(_) => perm,
        Err(_) => (0..nv).collect(),
    }
}
