//! The apps' standard output and error, through [`print_stdout`] and
//! [`stdout_line!`](crate::stdout_line), [`print_stderr`] and [`stderr_line!`](crate::stderr_line).
//!
//! `println!` panics when its reader has gone (`meshsimplify info F | head -1`): Rust ignores
//! SIGPIPE, so the write fails with `BrokenPipe`. Here the process ends instead, as SIGPIPE
//! ends `cat`: no message, this process's temporary files removed, status 141 (128 + SIGPIPE,
//! what a shell reports for a process that signal ended). Any other write error (a full disk
//! behind `>`) ends it with one line on stderr and status 1. Resetting SIGPIPE to its default
//! action would need `unsafe`, which this workspace denies. Messages on stderr (progress, the
//! final error) are written where they can be and dropped where not: `eprintln!` would panic
//! once stderr's reader has gone, and there is nowhere left to report that.

use std::io::Write;

use super::atomic_write::remove_live_temporaries;

/// The exit status after the reader of standard output has gone.
pub const BROKEN_PIPE_STATUS: i32 = 128 + 13;

/// Writes `text` to standard output and flushes it; exits the process when that fails (module
/// documentation).
pub fn print_stdout(text: std::fmt::Arguments) {
    let mut out = std::io::stdout().lock();
    let Err(error) = out.write_fmt(text).and_then(|()| out.flush()) else {
        return;
    };
    remove_live_temporaries();
    if error.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(BROKEN_PIPE_STATUS);
    }
    // stderr may be gone too: nothing is left to report the failure on
    let _ = writeln!(std::io::stderr(), "writing to standard output: {error}");
    std::process::exit(1);
}

/// `println!` for the apps: one line on standard output through [`print_stdout`].
#[macro_export]
macro_rules! stdout_line {
    () => {
        $crate::print_stdout(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::print_stdout(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// Writes `text` to standard error, dropping it when that fails (module documentation).
pub fn print_stderr(text: std::fmt::Arguments) {
    let _ = std::io::stderr().lock().write_fmt(text);
}

/// `eprintln!` for the apps: one line on standard error through [`print_stderr`].
#[macro_export]
macro_rules! stderr_line {
    () => {
        $crate::print_stderr(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::print_stderr(format_args!("{}\n", format_args!($($arg)*)))
    };
}
