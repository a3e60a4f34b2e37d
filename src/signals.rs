//! Sets of signals, for blocking them on a thread: the driver takes SIGINT and SIGTERM on a
//! thread of its own and blocks them everywhere else, and the mesh partitioner keeps SIGTERM
//! out of METIS while it works.

/// `signals` as a set.
pub fn set(signals: &[libc::c_int]) -> libc::sigset_t {
    // SAFETY: an empty set filled with valid signal numbers
    unsafe {
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        for &s in signals {
            libc::sigaddset(&mut set, s);
        }
        set
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_set_holds_the_signals_it_is_given_and_no_other() {
        let s = super::set(&[libc::SIGINT, libc::SIGTERM]);
        // SAFETY: asking a valid set about valid signals
        let member = |n| unsafe { libc::sigismember(&s, n) };
        assert_eq!([libc::SIGINT, libc::SIGTERM].map(member), [1, 1]);
        assert_eq!(
            [libc::SIGABRT, libc::SIGHUP, libc::SIGUSR1].map(member),
            [0, 0, 0]
        );
    }
}
