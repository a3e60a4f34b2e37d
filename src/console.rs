//! What tmc prints on the terminal: lines on stdout ([`say!`](crate::say)) and stderr
//! ([`note!`](crate::note)). A closed pipe (`tmc check CASE | head`) silences them instead of
//! ending the run: a solve goes on to write all its results, and its exit code is the solve's.

/// A line on stdout, dropped when stdout is closed.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// A line on stderr, dropped when stderr is closed.
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}
