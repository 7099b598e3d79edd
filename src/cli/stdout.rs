//! The command line's standard output. A line that cannot be written never
//! panics, as `println!` does: a closed pipe stops the printing quietly
//! (where SIGPIPE is ignored: `render --out` ignores it so its frame is
//! still written), and any other error (a full disk) is kept and reported
//! by `finish` once the command is done. Standard error's lines (`say_err!`)
//! are dropped where they cannot be written.

use lacuna::{Error, Result};
use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

static STOPPED: AtomicBool = AtomicBool::new(false);
static FAILED: Mutex<Option<std::io::Error>> = Mutex::new(None);

/// `println!` for the command line (`say!`).
macro_rules! say {
    () => {
        $crate::cli::stdout::write(format_args!(""), true)
    };
    ($($t:tt)*) => {
        $crate::cli::stdout::write(format_args!($($t)*), true)
    };
}

/// `eprintln!` for the command line: a line standard error cannot take
/// (a closed pipe, where SIGPIPE is ignored) is dropped, not a panic.
macro_rules! say_err {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($t)*);
    }};
}

/// `print!` for the command line.
macro_rules! say_text {
    ($($t:tt)*) => {
        $crate::cli::stdout::write(format_args!($($t)*), false)
    };
}

/// Writes `args` (and a newline) unless an earlier write failed.
pub fn write(args: std::fmt::Arguments, newline: bool) {
    if STOPPED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    let written = out.write_fmt(args).and_then(|()| match newline {
        true => out.write_all(b"\n"),
        false => Ok(()),
    });
    if let Err(e) = written {
        stop(e);
    }
}

fn stop(e: std::io::Error) {
    STOPPED.store(true, Ordering::Relaxed);
    if e.kind() != std::io::ErrorKind::BrokenPipe {
        FAILED.lock().unwrap_or_else(|p| p.into_inner()).get_or_insert(e);
    }
}

/// Restores SIGPIPE's default (Rust's runtime ignores it): output to a
/// closed pipe ends the process quietly, as it does other Unix tools.
pub fn end_at_a_closed_pipe() {
    #[cfg(unix)]
    sigpipe(libc::SIG_DFL);
}

/// Ignores SIGPIPE from here on: a closed pipe then stops the printing, not
/// the process, so a command whose product is a file still writes it.
pub fn outlive_a_closed_pipe() {
    #[cfg(unix)]
    sigpipe(libc::SIG_IGN);
}

#[cfg(unix)]
fn sigpipe(disposition: libc::sighandler_t) {
    // SAFETY: sets a default or ignoring disposition; no handler runs Rust
    // code.
    unsafe {
        libc::signal(libc::SIGPIPE, disposition);
    }
}

/// After the command: flushes, and an error naming standard output unless
/// everything was written (a closed pipe excepted).
pub fn finish() -> Result<()> {
    if !STOPPED.load(Ordering::Relaxed) {
        if let Err(e) = std::io::stdout().lock().flush() {
            stop(e);
        }
    }
    match FAILED.lock().unwrap_or_else(|p| p.into_inner()).take() {
        Some(e) => Err(Error::io("standard output", e)),
        None => Ok(()),
    }
}
