//! The mesh cut into one part per rank for a distributed run: METIS k-way on the cells' dual
//! graph (cells are neighbours when they share a side), all cell blocks together. Each node
//! belongs to the lowest rank among its cells, each boundary facet to its first node's rank.
//! Computed from the mesh alone, so every rank computes the same parts.

use super::Mesh;
pub use crate::parallel::Partition;

/// METIS keeps process-wide statics (its random generator and memory core): concurrent calls
/// race, giving results that depend on other threads, or crash. Every call holds this.
static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Make a METIS call, `call`, returning its status: one call at a time, and none loses a
/// SIGTERM or changes its handler. While it works METIS puts its own handler on SIGTERM (and
/// SIGABRT), puts the one it found back at its end as a handler that runs once, and a SIGTERM
/// that comes meanwhile (`mpirun` passing on a Ctrl-C, a user's `kill`) ends the call with
/// `METIS_ERROR`, never reaching the run's handler: the run would fail as if METIS could not
/// cut its mesh, or go on with its ordering lost and its stop forgotten. So the handlers are
/// put back as they were after each call, and a call that ends with `METIS_ERROR` is made
/// once more: METIS's own errors come again from the same input (it is deterministic), so if
/// that one succeeds, the first ended on a signal, which is raised again for the run's handler
/// and the second call's result is kept.
pub(crate) fn metis(mut call: impl FnMut() -> i32) -> i32 {
    let _one_at_a_time = METIS.lock().unwrap_or_else(|e| e.into_inner());
    let kept = |call: &mut dyn FnMut() -> i32| {
        let signals = [libc::SIGTERM, libc::SIGABRT];
        // SAFETY: reading the dispositions of two signals, and setting them back as they were
        let mut was: [libc::sigaction; 2] = unsafe { std::mem::zeroed() };
        for (s, w) in signals.iter().zip(&mut was) {
            unsafe { libc::sigaction(*s, std::ptr::null(), w) };
        }
        let status = call();
        for (s, w) in signals.iter().zip(&was) {
            // the handler METIS put back, as it was; one the handler itself changed since
            // (the run's, on a signal, to the default) stays
            let mut now: libc::sigaction = unsafe { std::mem::zeroed() };
            unsafe { libc::sigaction(*s, std::ptr::null(), &mut now) };
            if now.sa_sigaction == w.sa_sigaction {
                unsafe { libc::sigaction(*s, w, std::ptr::null_mut()) };
            }
        }
        status
    };
    let status = kept(&mut call);
    if status != metis_sys::rstatus_et_METIS_ERROR {
        return status;
    }
    let again = kept(&mut call);
    if again == metis_sys::rstatus_et_METIS_OK {
        // SAFETY: METIS left its handler by a long jump, which would keep SIGTERM blocked on
        // this thread were it installed to be blocked while it runs: unblocked, and raised
        // here, the signal runs the handler in place now, the run's (or the default, which
        // ends the process as the SIGTERM would have).
        unsafe {
            let mut term: libc::sigset_t = std::mem::zeroed();
            libc::sigemptyset(&mut term);
            libc::sigaddset(&mut term, libc::SIGTERM);
            libc::pthread_sigmask(libc::SIG_UNBLOCK, &term, std::ptr::null_mut());
            libc::raise(libc::SIGTERM);
        }
    }
    again
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
        use super::super::{METIS, metis};
        use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering::SeqCst};

        static HANDLED: AtomicUsize = AtomicUsize::new(0);
        /// Signals sent, or about to be: the last one is handled before its target call lets
        /// go of the lock, so that none reaches a thread while another's METIS traps it.
        static SENT: AtomicUsize = AtomicUsize::new(0);
        /// The worker's calls: the one it is inside (0: none), and the one the next signal is
        /// for (0: none).
        static CALLS: AtomicUsize = AtomicUsize::new(0);
        static INSIDE: AtomicUsize = AtomicUsize::new(0);
        static TARGET: AtomicUsize = AtomicUsize::new(0);
        /// A signal ended a METIS call (METIS caught it).
        static CAUGHT: AtomicBool = AtomicBool::new(false);
        /// The worker may stop.
        static DONE: AtomicBool = AtomicBool::new(false);

        extern "C" fn counted(_: libc::c_int) {
            HANDLED.fetch_add(1, SeqCst);
        }

        fn arm(handler: libc::sighandler_t) -> libc::sighandler_t {
            // SAFETY: setting a disposition; the handler only counts (an atomic add)
            unsafe { libc::signal(libc::SIGTERM, handler) }
        }

        fn counting() -> libc::sighandler_t {
            counted as extern "C" fn(libc::c_int) as libc::sighandler_t
        }

        /// METIS nested dissection of a k × k grid (tens of milliseconds at k = 200), as
        /// call after call of a worker that signals are sent to (`spot`).
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
                let caught = status == metis_sys::rstatus_et_METIS_ERROR;
                CAUGHT.fetch_or(caught, SeqCst);
                if !caught && TARGET.load(SeqCst) == call {
                    // a signal sent late comes after METIS put back the handler as one that
                    // runs once, and `metis` leaves the default that it then falls to (the
                    // run's handler sets that itself): armed again for the next send
                    arm(counting());
                }
                // the signal for this call, if METIS did not catch it, is handled before the
                // lock is let go
                while !caught
                    && TARGET.load(SeqCst) == call
                    && HANDLED.load(SeqCst) < SENT.load(SeqCst)
                {
                    std::hint::spin_loop();
                }
                status
            });
            (status, perm)
        }

        #[test]
        fn a_sigterm_that_comes_while_metis_works_reaches_the_run_and_the_result_stands() {
            let k = 200;
            let (status, alone) = order(k, false);
            assert_eq!(status, metis_sys::rstatus_et_METIS_OK);
            // put in place, and back, under METIS's lock: a METIS call on another thread puts
            // back at its end the handler it found at its start
            let under_lock = |h| {
                let _one_at_a_time = METIS.lock().unwrap_or_else(|e| e.into_inner());
                arm(h)
            };
            let before = under_lock(counting());
            let sends = 4;
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
            let mut caught = 0;
            for sent in 1..=sends {
                SENT.store(sent, SeqCst);
                // a call to send it to, held by Dekker's handshake with the worker's spin:
                // the target named, then the worker seen still inside it
                loop {
                    let call = INSIDE.load(SeqCst);
                    if call != 0 {
                        TARGET.store(call, SeqCst);
                        if INSIDE.load(SeqCst) == call {
                            break;
                        }
                        TARGET.store(0, SeqCst);
                    }
                    std::hint::spin_loop();
                }
                std::thread::sleep(std::time::Duration::from_millis(2));
                // SAFETY: the worker thread is alive: it spins until the signal is handled
                unsafe { libc::pthread_kill(id, libc::SIGTERM) };
                let waited = std::time::Instant::now();
                while HANDLED.load(SeqCst) < sent && waited.elapsed().as_secs() < 10 {
                    std::thread::yield_now();
                }
                caught += usize::from(CAUGHT.swap(false, SeqCst));
                TARGET.store(0, SeqCst);
            }
            DONE.store(true, SeqCst);
            let runs: Vec<(i32, Vec<i32>)> = worker.join().unwrap();
            under_lock(before);
            assert_eq!(HANDLED.load(SeqCst), sends, "a SIGTERM was lost");
            assert!(caught >= 1, "no SIGTERM came while METIS worked");
            for (status, perm) in runs {
                assert_eq!(status, metis_sys::rstatus_et_METIS_OK);
                assert!(perm == alone, "an interrupted ordering differs");
            }
        }
    }
}
