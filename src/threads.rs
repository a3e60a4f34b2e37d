//! The threads tmc computes with, decided once when it starts: `RAYON_NUM_THREADS` as tmc
//! reads it (spaces around the number ignored; unset or 0: the default), else one thread per
//! CPU this process may use — its CPU affinity and its cgroup's CPU quota, as
//! `std::thread::available_parallelism` reads them, not the cores the machine has — shared
//! among the ranks under `mpirun`. Rayon's pool is built with that count, so the library runs
//! what tmc understood (rayon alone would not read " 2 " and would fall back to every core).

use std::sync::OnceLock;

/// How many threads, and why that many (for `tmc check`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Threads {
    pub count: usize,
    pub why: String,
}

/// The CPUs this process may use (at least 1), read once: std reads the affinity and the
/// cgroup's files at each call, and the solvers ask at every linear solve.
pub fn usable_cpus() -> usize {
    static CPUS: OnceLock<usize> = OnceLock::new();
    *CPUS.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// The thread count for the value `env` of `RAYON_NUM_THREADS` (`None`: unset), on `cpus`
/// usable CPUs, over `ranks` ranks. An error says what to give instead.
pub fn choose(env: Option<&str>, cpus: usize, ranks: usize) -> Result<Threads, String> {
    let limit = 16 * cpus;
    let default = || {
        let count = (cpus / ranks.max(1)).max(1);
        let why = match ranks > 1 {
            true => format!("the {cpus} CPUs this process may use, shared by {ranks} ranks"),
            false => "one per CPU this process may use: its affinity and CPU quota".into(),
        };
        Threads { count, why }
    };
    let Some(v) = env else {
        return Ok(default());
    };
    match v.trim().parse::<usize>() {
        Ok(0) => Ok(default()),
        Ok(n) if n <= limit => Ok(Threads {
            count: n,
            why: "RAYON_NUM_THREADS".into(),
        }),
        _ => Err(format!(
            "RAYON_NUM_THREADS={v}: give a number of threads from 1 to {limit} (16 per core), \
             or 0 for one per core"
        )),
    }
}

static CHOSEN: OnceLock<Threads> = OnceLock::new();

/// The thread count for a run over `ranks` ranks, from this process's `RAYON_NUM_THREADS`
/// and usable CPUs.
pub fn decide(ranks: usize) -> Result<Threads, String> {
    let env = std::env::var("RAYON_NUM_THREADS").ok();
    choose(env.as_deref(), usable_cpus(), ranks)
}

/// Build rayon's global pool with the count `threads` ([`decide`]). Once per process.
pub fn start(threads: Threads) -> Result<&'static Threads, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.count)
        .build_global()
        .map_err(|e| e.to_string())?;
    Ok(CHOSEN.get_or_init(|| threads))
}

/// The count [`start`] decided, if it ran.
pub fn chosen() -> Option<&'static Threads> {
    CHOSEN.get()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_thread_count_is_read_as_a_user_means_it() {
        // unset or 0: one per usable CPU, shared by the ranks
        assert_eq!(choose(None, 6, 1).unwrap().count, 6);
        assert_eq!(choose(Some("0"), 6, 1).unwrap().count, 6);
        assert_eq!(choose(None, 6, 4).unwrap().count, 1);
        assert_eq!(choose(None, 16, 4).unwrap().count, 4);
        // spaces around the number are the number
        let t = choose(Some(" 2 "), 6, 1).unwrap();
        assert_eq!((t.count, t.why.as_str()), (2, "RAYON_NUM_THREADS"));
        // more threads than CPUs, within 16 per CPU
        assert_eq!(choose(Some("32"), 2, 1).unwrap().count, 32);
        for bad in ["33", "-1", "two", "", "1.5"] {
            let e = choose(Some(bad), 2, 1).unwrap_err();
            assert!(e.contains("from 1 to 32"), "{bad}: {e}");
        }
    }
}
