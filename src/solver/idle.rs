//! What the thread pool's other threads do while a linear solve runs on one of them.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// What the pool's other threads do while a linear solve runs: between the parallel parts of
/// a factorisation or a solve (the elimination tree's subtrees, a wide front's products), and
/// through GMRES's sequential steps, they have nothing to do.
///
/// Why spin at all: on a virtual machine a core left idle halts, and the next parallel work
/// waits for it to come back (one assembly, H1 16×16 on 2 threads, `benches/assembly.rs`:
/// 10–16 ms after an idle solve against 8.3–9.5 ms with the core kept busy). Why not spin
/// through everything: a long solve then burns a whole core for nothing, on a machine the user
/// may share. The default spins only while work keeps coming, as OpenMP runtimes do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IdleThreads {
    /// Run whatever parallel work the solve hands out and spin in between, until the solve has
    /// handed out none for this long; then sleep until the next parallel work.
    SpinFor(Duration),
    /// Spin through every solve, however long.
    Spin,
    /// Sleep until the next parallel work (frees the cores for other processes at once).
    Sleep,
    /// No pool around the solve: it runs on the calling thread, as a library that must be
    /// called from there needs (PETSc, whose MPI may allow the main thread only).
    CallingThread,
}

impl Default for IdleThreads {
    fn default() -> IdleThreads {
        IdleThreads::SpinFor(IdleThreads::DEFAULT_SPIN)
    }
}

impl IdleThreads {
    /// The environment variable `tmc solve --idle-threads` falls back to.
    pub const VAR: &'static str = "TMC_IDLE_THREADS";

    /// The default's bound on spinning without work.
    pub const DEFAULT_SPIN: Duration = Duration::from_millis(DEFAULT_SPIN_MS);

    /// `spin`, `sleep`, or a number of milliseconds to spin for without work (`50`, `50ms`).
    pub fn parse(v: &str) -> Result<IdleThreads, String> {
        let v = v.trim();
        match v {
            "spin" => return Ok(IdleThreads::Spin),
            "sleep" => return Ok(IdleThreads::Sleep),
            _ => {}
        }
        match v.strip_suffix("ms").unwrap_or(v).trim().parse::<u64>() {
            Ok(ms) => Ok(IdleThreads::SpinFor(Duration::from_millis(ms))),
            Err(_) => Err(format!(
                "\"{v}\" (given here or in {}): expected \"spin\", \"sleep\" or the \
                 milliseconds to spin without work (default {DEFAULT_SPIN_MS})",
                Self::VAR
            )),
        }
    }

    /// Run `f` (a linear solve) on one of the pool's threads (but for
    /// [`IdleThreads::CallingThread`]), its other threads doing what `self` says. On the
    /// pool, the solve's many small parallel parts (GMRES's vector operations, a solve's
    /// bands) are handed to the other threads directly; from outside it each would wake a
    /// pool thread and wait for it.
    pub fn run<R: Send>(self, f: impl FnOnce() -> R + Send) -> R {
        self.run_counting(f, &AtomicUsize::new(0))
    }

    /// [`IdleThreads::run`], counting in `gave_up` the spinners that stopped for want of work.
    fn run_counting<R: Send>(self, f: impl FnOnce() -> R + Send, gave_up: &AtomicUsize) -> R {
        let spinners = spinners(rayon::current_num_threads(), crate::threads::usable_cpus());
        let bound = match self {
            IdleThreads::CallingThread => return f(),
            IdleThreads::Sleep => return rayon::scope(|_| f()),
            IdleThreads::SpinFor(d) if d.is_zero() => return rayon::scope(|_| f()),
            _ if spinners == 0 => return rayon::scope(|_| f()),
            IdleThreads::SpinFor(d) => Some(d),
            IdleThreads::Spin => None,
        };
        let done = AtomicBool::new(false);
        rayon::scope(|s| {
            for _ in 0..spinners {
                let idle = Idle {
                    done: &done,
                    gave_up,
                    bound,
                    since: Instant::now(),
                };
                s.spawn(move |s| spin(s, idle));
            }
            let r = f();
            done.store(true, Ordering::Release);
            r
        })
    }
}

impl std::fmt::Display for IdleThreads {
    /// As [`IdleThreads::parse`] reads it.
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            IdleThreads::SpinFor(d) => write!(f, "{}", d.as_millis()),
            IdleThreads::Spin => f.write_str("spin"),
            IdleThreads::Sleep | IdleThreads::CallingThread => f.write_str("sleep"),
        }
    }
}

/// How many of a pool's `threads` spin beside the solve's own, on `cpus` usable CPUs: one per
/// CPU left. A spinner beyond the CPUs would take its time slices from a thread with work (on
/// 2 CPUs, 16 threads spinning made a solve twenty times slower).
fn spinners(threads: usize, cpus: usize) -> usize {
    threads.min(cpus).saturating_sub(1)
}

/// Milliseconds the default spins without work: the length of a few assemblies, so a solve
/// that hands out work or ends within them finds its cores awake, and one that runs longer
/// (where a core's wake-up is small beside it) does not keep them.
pub const DEFAULT_SPIN_MS: u64 = 50;

/// One spinner's state, handed on to its successors.
#[derive(Clone, Copy)]
struct Idle<'s> {
    done: &'s AtomicBool,
    /// Spinners that stopped because no work came within the bound.
    gave_up: &'s AtomicUsize,
    /// How long to spin without work; `None`: until `done`.
    bound: Option<Duration>,
    /// When this thread last ran work (or started spinning).
    since: Instant,
}

/// How long one spinner runs before it hands its thread back to the pool's scheduler.
const SPIN_SLICE: Duration = Duration::from_micros(200);

/// Spin until `done` (or until idle for longer than the bound), running the pool's other jobs
/// meanwhile. rayon's thieves take a worker's oldest job first, so the spinners (spawned before
/// the solve starts) are claimed before any of the solve's own parallel work can be stolen, and
/// none should end up on top of a frame the solve waits for. Should one still (several solves
/// in one pool, another scheduler), it returns within [`SPIN_SLICE`], spawning its successor,
/// and that frame resumes.
fn spin<'s>(s: &rayon::Scope<'s>, mut idle: Idle<'s>) {
    let start = Instant::now();
    while !idle.done.load(Ordering::Acquire) {
        let now = Instant::now();
        if idle.bound.is_some_and(|b| now - idle.since > b) {
            idle.gave_up.fetch_add(1, Ordering::Relaxed);
            return; // the thread goes back to the pool, which sleeps it until work comes
        }
        if now - start > SPIN_SLICE {
            s.spawn(move |s| spin(s, idle));
            return;
        }
        if rayon::yield_now() == Some(rayon::Yield::Executed) {
            idle.since = Instant::now();
        } else {
            std::hint::spin_loop();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{IdleThreads, spinners};

    #[test]
    fn no_more_threads_spin_than_there_are_cpus_beside_the_solve() {
        assert_eq!(spinners(2, 2), 1);
        assert_eq!(spinners(16, 2), 1);
        assert_eq!(spinners(16, 16), 15);
        assert_eq!(spinners(4, 16), 3);
        assert_eq!(spinners(1, 8), 0);
        assert_eq!(spinners(8, 1), 0);
    }
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use std::time::{Duration, Instant};

    /// CPU seconds this thread has used.
    fn thread_cpu() -> f64 {
        let mut t = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: clock_gettime writes one timespec, which `t` is
        let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
        assert_eq!(rc, 0);
        t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64
    }

    /// A pool of two threads, and the CPU seconds its thread other than the caller uses while
    /// `job` runs on the caller.
    fn other_cpu(job: impl FnOnce() + Send) -> f64 {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let cpu = || pool.broadcast(|_| thread_cpu());
        pool.install(|| {
            let caller = rayon::current_thread_index().unwrap();
            let before = cpu();
            job();
            let after = cpu();
            (0..2)
                .filter(|&i| i != caller)
                .map(|i| after[i] - before[i])
                .sum()
        })
    }

    /// A solve that hands out no work for 200 ms.
    fn idle_solve() {
        std::thread::sleep(Duration::from_millis(200));
    }

    #[test]
    fn the_default_stops_spinning_when_a_solve_hands_out_no_work() {
        // the measure itself: 60 ms of CPU burnt on the other thread (the caller sleeps
        // outside rayon, so the job it spawned can only run there) read as at least that
        let burnt = other_cpu(|| {
            let done = AtomicBool::new(false);
            rayon::scope(|s| {
                s.spawn(|_| {
                    let start = thread_cpu();
                    while thread_cpu() - start < 0.06 {
                        std::hint::spin_loop();
                    }
                    done.store(true, Ordering::Release);
                });
                while !done.load(Ordering::Acquire) {
                    std::thread::sleep(Duration::from_millis(1));
                }
            });
        });
        let default = other_cpu(|| IdleThreads::default().run(idle_solve));
        let sleep = other_cpu(|| IdleThreads::Sleep.run(idle_solve));
        // upper bounds: a loaded machine can only take CPU away from the spinner
        assert!(default < 0.08, "default: {default} s of CPU");
        assert!(sleep < 0.01, "sleep: {sleep} s of CPU");
        assert!(burnt >= 0.06, "burnt: {burnt} s of CPU");
    }

    #[test]
    fn spinning_stops_after_the_bound_without_work_and_never_under_spin() {
        // what the policies decide, counted rather than timed (a loaded machine changes how
        // much CPU a spinner gets, not whether it stops)
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        pool.install(|| {
            let gave_up = AtomicUsize::new(0);
            IdleThreads::Spin.run_counting(idle_solve, &gave_up);
            assert_eq!(gave_up.load(Ordering::Relaxed), 0, "spin gave up");
            // the default's spinner gives up once 50 ms have passed without work: the solve
            // waits for that (or 10 s), and must not have seen it sooner
            let gave_up = AtomicUsize::new(0);
            let start = Instant::now();
            let waited = IdleThreads::default().run_counting(
                || {
                    while gave_up.load(Ordering::Relaxed) == 0
                        && start.elapsed() < Duration::from_secs(10)
                    {
                        std::thread::sleep(Duration::from_millis(1));
                    }
                    start.elapsed()
                },
                &gave_up,
            );
            assert_eq!(gave_up.load(Ordering::Relaxed), 1, "after {waited:?}");
            assert!(waited >= IdleThreads::DEFAULT_SPIN, "{waited:?}");
        });
    }

    #[test]
    fn policies_parse_from_their_names_and_milliseconds() {
        assert_eq!(IdleThreads::parse("spin"), Ok(IdleThreads::Spin));
        assert_eq!(IdleThreads::parse("sleep"), Ok(IdleThreads::Sleep));
        let ms = |n| Ok(IdleThreads::SpinFor(Duration::from_millis(n)));
        assert_eq!(IdleThreads::parse("20"), ms(20));
        assert_eq!(IdleThreads::parse("20ms"), ms(20));
        assert_eq!(IdleThreads::parse("0"), ms(0));
        let e = IdleThreads::parse("nap").unwrap_err();
        assert!(e.contains("\"nap\"") && e.contains("spin"), "{e}");
        assert!(IdleThreads::parse("-5").is_err());
        for p in [
            IdleThreads::default(),
            IdleThreads::Spin,
            IdleThreads::Sleep,
        ] {
            assert_eq!(IdleThreads::parse(&p.to_string()), Ok(p));
        }
    }

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
                for idle in [
                    IdleThreads::Spin,
                    IdleThreads::Sleep,
                    IdleThreads::default(),
                    IdleThreads::SpinFor(Duration::from_micros(50)),
                ] {
                    for _ in 0..5 {
                        assert_eq!(idle.run(|| sum(0, n)), n * (n - 1) / 2);
                    }
                }
            })
        });
    }
}
