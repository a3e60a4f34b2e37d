//! Work done in a forked child, so that a crash or an `exit` inside a library (gmsh) ends only
//! that child and is reported: one request after another by a child forked once and kept
//! ([`Served`]), which pays the fork, and the first touch of the memory the work allocates,
//! once rather than per request (a remade 3D medium is meshed every step or two).

use serde::Serialize;
use serde::de::DeserializeOwned;
use std::io::{Read, Write};
use std::os::fd::FromRawFd;
use std::os::raw::c_int;

/// How a child process ended without an answer.
#[derive(Debug)]
pub enum Isolation {
    /// It exited (gmsh's `Exit`) before answering.
    Ended(String),
    /// A signal ended it.
    Crashed(String),
    Os(std::io::Error),
}

/// A pipe: (read end, write end), closed in any program this process or a child executes
/// (MPI's daemon, started after a meshing child, must not hold that child's pipe open).
fn pipe() -> Result<(c_int, c_int), Isolation> {
    let mut fds = [0 as c_int; 2];
    if unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) } != 0 {
        return Err(Isolation::Os(std::io::Error::last_os_error()));
    }
    Ok((fds[0], fds[1]))
}

/// Fork; in the child (0) close the fds of `parent`, in this process those of `child`. No
/// METIS call runs in another thread meanwhile (see [`super::partition::metis_held`]).
fn fork(parent: &[c_int], child: &[c_int]) -> Result<libc::pid_t, Isolation> {
    let metis = super::partition::metis_held();
    let pid = unsafe { libc::fork() };
    drop(metis);
    if pid < 0 {
        let e = std::io::Error::last_os_error();
        for fd in parent.iter().chain(child) {
            unsafe { libc::close(*fd) };
        }
        return Err(Isolation::Os(e));
    }
    let close = if pid == 0 { parent } else { child };
    for fd in close {
        unsafe { libc::close(*fd) };
    }
    Ok(pid)
}

/// Wait for the child `pid` to end: how it ended, as the reason it gave no answer.
fn reaped(pid: libc::pid_t) -> Isolation {
    let mut status: c_int = 0;
    while unsafe { libc::waitpid(pid, &mut status, 0) } < 0 {
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Isolation::Os(e);
        }
    }
    if libc::WIFSIGNALED(status) {
        let name = match libc::WTERMSIG(status) {
            libc::SIGSEGV => "segmentation fault".to_string(),
            libc::SIGABRT => "aborted".to_string(),
            libc::SIGFPE => "floating-point exception".to_string(),
            libc::SIGKILL => "killed, perhaps out of memory".to_string(),
            libc::SIGBUS => "bus error".to_string(),
            s => format!("signal {s}"),
        };
        return Isolation::Crashed(name);
    }
    Isolation::Ended(if libc::WIFEXITED(status) {
        format!("exit status {}", libc::WEXITSTATUS(status))
    } else {
        format!("wait status {status}")
    })
}

/// `value` as JSON to the pipe written as `file`, its length first (8 bytes, little-endian);
/// false if the pipe broke.
fn send<T: Serialize>(file: &mut std::fs::File, value: &T) -> bool {
    let body = serde_json::to_vec(value).unwrap_or_default();
    file.write_all(&(body.len() as u64).to_le_bytes())
        .and_then(|_| file.write_all(&body))
        .is_ok()
}

/// The next value [`send`] wrote to the pipe read as `file`; `None` at its end.
fn receive<T: DeserializeOwned>(file: &mut std::fs::File) -> Option<T> {
    let mut length = [0u8; 8];
    file.read_exact(&mut length).ok()?;
    let mut body = vec![0u8; u64::from_le_bytes(length) as usize];
    file.read_exact(&mut body).ok()?;
    serde_json::from_slice(&body).ok()
}

/// A child forked once that answers requests with `work`, one after another, until the pipe
/// to it closes (when this value is dropped, or the process ends). The child does nothing but
/// the work and its answers, and `_exit`s, so it runs no destructor or handler of this
/// process; it is killed when the thread that made it ends. A request it dies or exits on is
/// reported (how it ended), and the child is gone: the next request needs a new one. The child
/// closes every file it inherited but its two pipes, so that a child made later does not hold
/// another's pipe open. In the `tmc` binary it keeps SIGINT and SIGTERM blocked, as every
/// thread of its parent has them: a Ctrl-C that a terminal sends the whole group stops the
/// run, and the child finishes the request at hand.
pub struct Served {
    pid: libc::pid_t,
    to: Option<std::fs::File>,
    from: std::fs::File,
}

impl Served {
    /// Fork the child that answers requests `Q` with `work(q)`.
    pub fn start<Q: DeserializeOwned, A: Serialize>(work: fn(Q) -> A) -> Result<Served, Isolation> {
        let (request_read, request_write) = pipe()?;
        let (answer_read, answer_write) = match pipe() {
            Ok(p) => p,
            Err(e) => {
                unsafe {
                    libc::close(request_read);
                    libc::close(request_write);
                }
                return Err(e);
            }
        };
        let parent = unsafe { libc::getpid() };
        let pid = fork(&[request_write, answer_read], &[request_read, answer_write])?;
        if pid == 0 {
            // killed when the thread that made it ends, however it ends: a process ended by a
            // signal (a Ctrl-C to `tmc mesh`) runs no drop, and its child would go on meshing
            if unsafe { libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) } != 0
                || unsafe { libc::getppid() } != parent
            {
                unsafe { libc::_exit(0) };
            }
            close_all_but(&[0, 1, 2, request_read, answer_write]);
            let mut requests = unsafe { std::fs::File::from_raw_fd(request_read) };
            let mut answers = unsafe { std::fs::File::from_raw_fd(answer_write) };
            while let Some(request) = receive::<Q>(&mut requests) {
                let answer =
                    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(request)));
                if !answer.is_ok_and(|a| send(&mut answers, &a)) {
                    break;
                }
            }
            unsafe { libc::_exit(0) };
        }
        Ok(Served {
            pid,
            to: Some(unsafe { std::fs::File::from_raw_fd(request_write) }),
            from: unsafe { std::fs::File::from_raw_fd(answer_read) },
        })
    }

    /// The child's answer to `request`; where it gave none, how it ended (the child is then
    /// reaped, and this value spent: asked again, it answers that the child had ended).
    pub fn ask<Q: Serialize, A: DeserializeOwned>(&mut self, request: &Q) -> Result<A, Isolation> {
        let Some(to) = self.to.as_mut() else {
            return Err(Isolation::Ended(
                "it had ended at an earlier request".into(),
            ));
        };
        if send(to, request)
            && let Some(answer) = receive(&mut self.from)
        {
            return Ok(answer);
        }
        self.to = None;
        let how = reaped(self.pid);
        self.pid = 0;
        Err(how)
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        // the pipe's end tells the child to exit; it waits for a request, idle, so it is also
        // ended outright, lest a process that inherited the pipe keep it from ever seeing the end
        self.to = None;
        if self.pid > 0 {
            unsafe { libc::kill(self.pid, libc::SIGKILL) };
            reaped(self.pid);
        }
    }
}

/// Close every file descriptor of this process but `keep`.
fn close_all_but(keep: &[c_int]) {
    let mut keep: Vec<c_int> = keep.to_vec();
    keep.sort_unstable();
    let mut from: c_int = 0;
    for &k in &keep {
        if k > from {
            unsafe { libc::close_range(from as u32, (k - 1) as u32, 0) };
        }
        from = k + 1;
    }
    unsafe { libc::close_range(from as u32, u32::MAX, 0) };
}

#[cfg(test)]
mod tests {
    use super::*;

    fn work(q: i64) -> i64 {
        match q {
            -1 => unsafe { libc::abort() },
            -2 => std::process::exit(4),
            q => q * q,
        }
    }

    #[test]
    fn a_served_child_answers_one_request_after_another_and_its_end_is_reported() {
        let mut a = Served::start(work).unwrap();
        let mut b = Served::start(work).unwrap();
        for q in 1..5i64 {
            assert_eq!(a.ask::<i64, i64>(&q).unwrap(), q * q);
            assert_eq!(b.ask::<i64, i64>(&(q + 10)).unwrap(), (q + 10) * (q + 10));
        }
        // b was forked after a: closing a's pipe ends a, though b's fork saw it open
        drop(a);
        let crashed = b.ask::<i64, i64>(&-1);
        assert!(
            matches!(&crashed, Err(Isolation::Crashed(s)) if s == "aborted"),
            "{crashed:?}"
        );
        let spent = b.ask::<i64, i64>(&2);
        assert!(
            matches!(&spent, Err(Isolation::Ended(s)) if s == "it had ended at an earlier request"),
            "{spent:?}"
        );
        let mut c = Served::start(work).unwrap();
        let ended = c.ask::<i64, i64>(&-2);
        assert!(
            matches!(&ended, Err(Isolation::Ended(s)) if s == "exit status 4"),
            "{ended:?}"
        );
    }

    #[test]
    fn a_served_child_ends_with_the_thread_that_made_it_though_never_dropped() {
        // as a process ended by a signal leaves it: its pipe never closed, the child would wait
        // for a request for ever
        let pid = std::thread::spawn(|| {
            let mut served = Served::start(work).unwrap();
            assert_eq!(served.ask::<i64, i64>(&3).unwrap(), 9);
            let pid = served.pid;
            std::mem::forget(served);
            pid
        })
        .join()
        .unwrap();
        let start = std::time::Instant::now();
        let mut status: c_int = 0;
        while unsafe { libc::waitpid(pid, &mut status, libc::WNOHANG) } == 0 {
            assert!(
                start.elapsed() < std::time::Duration::from_secs(10),
                "the child outlived its thread"
            );
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        assert!(libc::WIFSIGNALED(status) && libc::WTERMSIG(status) == libc::SIGKILL);
    }
}
