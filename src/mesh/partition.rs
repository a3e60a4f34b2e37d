//! The mesh cut into one part per rank for a distributed run: METIS k-way on the cells' dual
//! graph (cells are neighbours when they share a side), all cell blocks together. Each node
//! belongs to the lowest rank among its cells, each boundary facet to its first node's rank.
//! Computed from the mesh alone, so every rank computes the same parts.

use super::Mesh;
pub use crate::parallel::Partition;

/// METIS keeps process-wide statics (its random generator and memory core): concurrent calls
/// race, giving results that depend on other threads, or crash. Every call holds this.
static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// No METIS call runs while the guard this returns lives. A fork holds it: METIS draws from
/// the C library's `rand`, under that library's lock, and a child forked while another thread
/// held it inherits it taken; a meshing child so forked in the test binary hung for good in
/// gmsh's first `srandom`.
pub(crate) fn metis_held() -> std::sync::MutexGuard<'static, ()> {
    METIS.lock().unwrap_or_else(|e| e.into_inner())
}

/// Make a METIS call, `call`, returning its status: one call at a time, and none lets a
/// SIGTERM in or changes its handler. While it works METIS puts its own handler on SIGTERM (and
/// SIGABRT), one that jumps back to the call's start from wherever the signal lands, and puts
/// the one it found back at its end as a handler that runs once. A SIGTERM from outside
/// (`mpirun` passing on a Ctrl-C, a user's `kill`) that landed in `malloc` left its lock
/// taken, and the call hung at its next allocation; one that landed elsewhere ended the call
/// with `METIS_ERROR`, never reaching the run's handler. So SIGTERM is blocked on this thread
/// while METIS works, and reaches the handler in place once it is done (the `tmc` binary takes
/// it on a thread of its own, `driver::take_signals`, and blocks it everywhere else); the
/// handlers are put back as they were. SIGABRT, with which METIS ends a call that runs out of
/// memory, is left to it.
pub(crate) fn metis(call: impl FnOnce() -> i32) -> i32 {
    let _one_at_a_time = metis_held();
    let signals = [libc::SIGTERM, libc::SIGABRT];
    // SAFETY: reading the dispositions of two signals, blocking one on this thread, and
    // setting both back as they were
    unsafe {
        let mut was: [libc::sigaction; 2] = std::mem::zeroed();
        for (s, w) in signals.iter().zip(&mut was) {
            libc::sigaction(*s, std::ptr::null(), w);
        }
        let term = crate::signals::set(&[libc::SIGTERM]);
        let mut mask: libc::sigset_t = std::mem::zeroed();
        libc::pthread_sigmask(libc::SIG_BLOCK, &term, &mut mask);
        let status = call();
        for (s, w) in signals.iter().zip(&was) {
            // the handler METIS put back, as it was; one changed since by another thread stays
            let mut now: libc::sigaction = std::mem::zeroed();
            libc::sigaction(*s, std::ptr::null(), &mut now);
            if now.sa_sigaction == w.sa_sigaction {
                libc::sigaction(*s, w, std::ptr::null_mut());
            }
        }
        libc::pthread_sigmask(libc::SIG_SETMASK, &mask, std::ptr::null_mut());
        status
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PartitionError {
    #[error("{ranks} ranks for a mesh of {cells} cells: run on at most {cells} ranks")]
    TooManyRanks { ranks: usize, cells: usize },
    #[error("METIS could not partition the mesh into {parts} parts (status {status})")]
    Metis { parts: usize, status: i32 },
}

/// Everything on one rank.
pub fn whole(mesh: &Mesh) -> Partition {
    Partition {
        parts: 1,
        cell_rank: mesh.cells.iter().map(|b| vec![0; b.n_cells()]).collect(),
        facet_rank: mesh.facets.iter().map(|b| vec![0; b.n_cells()]).collect(),
        node_rank: vec![0; mesh.coords.len()],
    }
}

/// `parts` parts of about equal cell counts, with few cell sides between them.
pub fn cut(mesh: &Mesh, parts: usize) -> Result<Partition, PartitionError> {
    let cells: usize = mesh.cells.iter().map(|b| b.n_cells()).sum();
    if parts > cells {
        return Err(PartitionError::TooManyRanks {
            ranks: parts,
            cells,
        });
    }
    if parts == 1 {
        return Ok(whole(mesh));
    }
    let mut eptr = vec![0i32];
    let mut eind = Vec::new();
    for b in &mesh.cells {
        for c in 0..b.n_cells() {
            eind.extend(b.cell(c).iter().map(|&n| n as i32));
            eptr.push(eind.len() as i32);
        }
    }
    let mut epart = vec![0i32; cells];
    let mut npart = vec![0i32; mesh.coords.len()];
    let (mut ne, mut nn) = (cells as i32, mesh.coords.len() as i32);
    // neighbours share a side: an edge (2 nodes) in 2D, a face (at least 3) in 3D
    let mut ncommon = mesh.dim as i32;
    let mut nparts = parts as i32;
    let mut objval = 0i32;
    let mut options = [-1i32; metis_sys::METIS_NOPTIONS as usize];
    let status = metis(|| {
        // SAFETY: eptr/eind describe `cells` cells over `nn` nodes; METIS writes `cells`
        // entries of epart and `nn` of npart; options are METIS's defaults.
        unsafe {
            metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
            options[metis_sys::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
            metis_sys::METIS_PartMeshDual(
                &mut ne,
                &mut nn,
                eptr.as_mut_ptr(),
                eind.as_mut_ptr(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                &mut ncommon,
                &mut nparts,
                std::ptr::null_mut(),
                options.as_mut_ptr(),
                &mut objval,
                epart.as_mut_ptr(),
                npart.as_mut_ptr(),
            )
        }
    });
    if status != metis_sys::rstatus_et_METIS_OK {
        return Err(PartitionError::Metis { parts, status });
    }
    let mut cell_rank = Vec::new();
    let mut node_rank = vec![u32::MAX; mesh.coords.len()];
    let mut next = epart.iter();
    for b in &mesh.cells {
        let ranks: Vec<u32> = next.by_ref().take(b.n_cells()).map(|&r| r as u32).collect();
        for (c, &r) in ranks.iter().enumerate() {
            for &n in b.cell(c) {
                node_rank[n] = node_rank[n].min(r);
            }
        }
        cell_rank.push(ranks);
    }
    // nodes of no cell (none in a checked mesh) stay on rank 0
    for r in &mut node_rank {
        if *r == u32::MAX {
            *r = 0;
        }
    }
    let facet_rank = mesh
        .facets
        .iter()
        .map(|b| (0..b.n_cells()).map(|f| node_rank[b.cell(f)[0]]).collect())
        .collect();
    Ok(Partition {
        parts,
        cell_rank,
        facet_rank,
        node_rank,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Block, CellKind};

    /// A row of `n` unit squares.
    fn strip(n: usize) -> Mesh {
        let mut coords = Vec::new();
        for i in 0..=n {
            coords.push([i as f64, 0.0, 0.0]);
            coords.push([i as f64, 1.0, 0.0]);
        }
        let conn = (0..n)
            .flat_map(|i| [2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1])
            .collect();
        let cells = vec![Block {
            kind: CellKind::Quad4,
            groups: vec![],
            conn,
        }];
        Mesh::of_cells(2, coords, cells)
    }

    #[test]
    fn a_strip_is_cut_into_balanced_connected_parts() {
        let mesh = strip(40);
        let p = cut(&mesh, 2).unwrap();
        assert_eq!(p.cells_per_rank(), vec![20, 20]);
        // one cut: along the strip the rank changes once
        let r = &p.cell_rank[0];
        assert_eq!(r.windows(2).filter(|w| w[0] != w[1]).count(), 1);
        // a node is on the lowest rank of its cells: the cut's two nodes on rank r[cut]
        for (c, &rc) in r.iter().enumerate() {
            for &n in mesh.cells[0].cell(c) {
                assert!(p.node_rank[n] <= rc);
            }
        }
        assert_eq!(
            cut(&mesh, 41),
            Err(PartitionError::TooManyRanks {
                ranks: 41,
                cells: 40
            })
        );
        assert_eq!(cut(&mesh, 1).unwrap(), whole(&mesh));
    }

    mod signals {
        use super::super::{metis, metis_held};
        use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering::SeqCst};
        use std::time::{Duration, Instant};

        /// SIGTERMs handled, and of them those handled while METIS worked.
        static HANDLED: AtomicUsize = AtomicUsize::new(0);
        static HANDLED_INSIDE: AtomicUsize = AtomicUsize::new(0);
        /// The worker's calls, and the one it is inside (0: none).
        static CALLS: AtomicUsize = AtomicUsize::new(0);
        static INSIDE: AtomicUsize = AtomicUsize::new(0);
        /// The worker may stop.
        static DONE: AtomicBool = AtomicBool::new(false);

        extern "C" fn counted(_: libc::c_int) {
            HANDLED.fetch_add(1, SeqCst);
            if INSIDE.load(SeqCst) != 0 {
                HANDLED_INSIDE.fetch_add(1, SeqCst);
            }
        }

        fn arm(handler: libc::sighandler_t) -> libc::sighandler_t {
            // SAFETY: setting a disposition; the handler only counts (atomic adds)
            unsafe { libc::signal(libc::SIGTERM, handler) }
        }

        fn counting() -> libc::sighandler_t {
            counted as extern "C" fn(libc::c_int) as libc::sighandler_t
        }

        /// METIS nested dissection of a k × k grid (tens of milliseconds at k = 200); for the
        /// worker that signals are sent to (`spot`), the call it is inside is marked.
        fn order(k: usize, spot: bool) -> (i32, Vec<i32>) {
            let (mut xadj, mut adjncy) = (vec![0i32], Vec::new());
            for v in 0..k * k {
                let (x, y) = (v % k, v / k);
                let near = [(x > 0, v.wrapping_sub(1)), (x + 1 < k, v + 1)];
                let far = [(y > 0, v.wrapping_sub(k)), (y + 1 < k, v + k)];
                adjncy.extend(near.iter().chain(&far).filter(|n| n.0).map(|n| n.1 as i32));
                xadj.push(adjncy.len() as i32);
            }
            let mut nv = (k * k) as i32;
            let (mut perm, mut iperm) = (vec![0i32; k * k], vec![0i32; k * k]);
            let status = metis(|| {
                let call = CALLS.fetch_add(1, SeqCst) + 1;
                INSIDE.store(if spot { call } else { 0 }, SeqCst);
                // SAFETY: a valid CSR graph of nv vertices; METIS writes nv entries of each
                // of perm and iperm
                let status = unsafe {
                    metis_sys::METIS_NodeND(
                        &mut nv,
                        xadj.as_mut_ptr(),
                        adjncy.as_mut_ptr(),
                        std::ptr::null_mut(),
                        std::ptr::null_mut(),
                        perm.as_mut_ptr(),
                        iperm.as_mut_ptr(),
                    )
                };
                INSIDE.store(0, SeqCst);
                status
            });
            (status, perm)
        }

        /// Wait up to ten seconds for `until`.
        fn wait(until: impl Fn() -> bool) {
            let start = Instant::now();
            while !until() && start.elapsed() < Duration::from_secs(10) {
                std::thread::yield_now();
            }
        }

        #[test]
        fn a_sigterm_that_comes_while_metis_works_reaches_the_run_after_it_and_the_result_stands() {
            let k = 200;
            let (status, alone) = order(k, false);
            assert_eq!(status, metis_sys::rstatus_et_METIS_OK);
            // put in place, and back, under METIS's lock: a METIS call on another thread puts
            // back at its end the handler it found at its start
            let under_lock = |h| {
                let _one_at_a_time = metis_held();
                arm(h)
            };
            let before = under_lock(counting());
            let worker = std::thread::spawn(move || {
                let mut runs = vec![order(k, true)];
                while !DONE.load(SeqCst) {
                    runs.push(order(k, true));
                }
                runs
            });
            let id = {
                use std::os::unix::thread::JoinHandleExt;
                worker.as_pthread_t()
            };
            let sends = 4;
            let mut during = 0;
            for sent in 1..=sends {
                wait(|| INSIDE.load(SeqCst) != 0);
                let call = INSIDE.load(SeqCst);
                std::thread::sleep(Duration::from_millis(2));
                // SAFETY: the worker thread is alive: it works until DONE
                unsafe { libc::pthread_kill(id, libc::SIGTERM) };
                // still inside the call it was in before the signal was sent
                during += usize::from(call != 0 && INSIDE.load(SeqCst) == call);
                wait(|| HANDLED.load(SeqCst) >= sent);
            }
            DONE.store(true, SeqCst);
            let runs: Vec<(i32, Vec<i32>)> = worker.join().unwrap();
            under_lock(before);
            assert_eq!(HANDLED.load(SeqCst), sends, "a SIGTERM was lost");
            assert!(during >= 1, "no SIGTERM came while METIS worked");
            assert_eq!(HANDLED_INSIDE.load(SeqCst), 0, "a SIGTERM came into METIS");
            for (status, perm) in runs {
                assert_eq!(status, metis_sys::rstatus_et_METIS_OK);
                assert!(perm == alone, "an interrupted ordering differs");
            }
        }
    }
}
