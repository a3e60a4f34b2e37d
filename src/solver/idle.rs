//! What the thread pool's other threads do while a linear solve runs on one of them.

use std::sync::atomic::{AtomicBool, Ordering};

/// What the pool's other threads do while a linear solve runs: most of a factorisation or
/// triangular solve is on one thread.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IdleThreads {
    /// Stay on their cores: run whatever parallel work the solve hands out and spin in
    /// between (as OpenMP's active wait policy does). On a virtual machine a core left idle for
    /// the length of a solve halts, and the next assembly waits for it to come back: measured
    /// 10–16 ms against 8.3–9.5 ms for one assembly (H1 16×16, 2 threads,
    /// `benches/assembly.rs`).
    #[default]
    Spin,
    /// Sleep until the next parallel work (frees the cores for other processes).
    Sleep,
}

impl IdleThreads {
    /// The environment variable that chooses: `spin` (the default) or `sleep`.
    pub const VAR: &'static str = "TMC_IDLE_THREADS";

    /// From [`IdleThreads::VAR`]; unset means [`IdleThreads::Spin`].
    pub fn from_env() -> Result<IdleThreads, String> {
        match std::env::var(Self::VAR) {
            Err(std::env::VarError::NotPresent) => Ok(IdleThreads::Spin),
            Ok(v) if v == "spin" => Ok(IdleThreads::Spin),
            Ok(v) if v == "sleep" => Ok(IdleThreads::Sleep),
            Ok(v) => Err(format!(
                "{} = \"{v}\": expected \"spin\" or \"sleep\"",
                Self::VAR
            )),
            Err(e) => Err(format!("{}: {e}", Self::VAR)),
        }
    }

    /// Run `f` (a linear solve) with the pool's other threads doing what `self` says.
    pub fn run<R: Send>(self, f: impl FnOnce() -> R + Send) -> R {
        let threads = rayon::current_num_threads();
        if self == IdleThreads::Sleep || threads < 2 {
            return f();
        }
        let done = AtomicBool::new(false);
        rayon::scope(|s| {
            for _ in 1..threads {
                s.spawn(|s| spin(s, &done));
            }
            let r = f();
            done.store(true, Ordering::Release);
            r
        })
    }
}

/// How long one spinner runs before it hands its thread back to the pool's scheduler.
const SPIN_SLICE: std::time::Duration = std::time::Duration::from_micros(200);

/// Spin until `done`, running the pool's other jobs meanwhile. rayon's thieves take a
/// worker's oldest job first, so the spinners (spawned before the solve starts) are claimed
/// before any of the solve's own parallel work can be stolen, and none should end up on top of
/// a frame the solve waits for. Should one still (several solves in one pool, another
/// scheduler), it returns within [`SPIN_SLICE`], spawning its successor, and that frame resumes.
fn spin<'s>(s: &rayon::Scope<'s>, done: &'s AtomicBool) {
    let start = std::time::Instant::now();
    while !done.load(Ordering::Acquire) {
        if start.elapsed() > SPIN_SLICE {
            s.spawn(move |s| spin(s, done));
            return;
        }
        if rayon::yield_now() != Some(rayon::Yield::Executed) {
            std::hint::spin_loop();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::IdleThreads;
    use rayon::prelude::*;

    /// Σ lo..hi by recursive halving with `rayon::join`, slowly enough that halves get stolen.
    fn sum(lo: u64, hi: u64) -> u64 {
        if hi - lo <= 4 {
            std::thread::sleep(std::time::Duration::from_micros(20));
            return (lo..hi).sum();
        }
        let mid = (lo + hi) / 2;
        let (a, b) = rayon::join(|| sum(lo, mid), || sum(mid, hi));
        a + b
    }

    #[test]
    fn spinning_threads_never_hold_up_the_solves_beside_them() {
        // solves started from several pool threads at once, each with parallel work of its own:
        // spinners land on top of waiting joins, of their own solve and of the others
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        let n = 256;
        pool.install(|| {
            (0..8).into_par_iter().for_each(|_| {
                for idle in [IdleThreads::Spin, IdleThreads::Sleep] {
                    for _ in 0..5 {
                        assert_eq!(idle.run(|| sum(0, n)), n * (n - 1) / 2);
                    }
                }
            })
        });
    }
}
