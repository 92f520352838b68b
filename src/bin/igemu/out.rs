//! Standard output: every report line of the command line goes through [`outln!`] and
//! [`out!`], which return a write error as [`Error::Io`] on [`STDOUT`] instead of panicking
//! as `println!` does. `main` ends quietly with exit 0 on a closed pipe ([`is_broken_pipe`],
//! `igemu render --json | head -c 10`) and exits 2 on any other write error.

use igemu::error::Error;
use std::io::{self, Write};

/// The name standard output goes by in an [`Error::Io`].
pub const STDOUT: &str = "<stdout>";

/// Writes formatted text to stdout (`print!`), returning from the calling function with
/// the error when the write fails.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::out::write(format_args!($($arg)*), false)?
    };
}

/// Writes a formatted line to stdout (`println!`), returning from the calling function with
/// the error when the write fails.
macro_rules! outln {
    () => {
        $crate::out::write(format_args!(""), true)?
    };
    ($($arg:tt)*) => {
        $crate::out::write(format_args!($($arg)*), true)?
    };
}

pub(crate) use {out, outln};

fn stdout_error(source: io::Error) -> Error {
    Error::Io {
        path: STDOUT.into(),
        source,
    }
}

/// Writes `args` (and a newline) to stdout.
pub fn write(args: std::fmt::Arguments, newline: bool) -> Result<(), Error> {
    let mut o = io::stdout().lock();
    o.write_fmt(args)
        .and_then(|()| if newline { o.write_all(b"\n") } else { Ok(()) })
        .map_err(stdout_error)
}

/// Flushes stdout (the last buffered bytes fail here when the reader is gone).
pub fn flush() -> Result<(), Error> {
    io::stdout().lock().flush().map_err(stdout_error)
}

/// Whether `e` is a write to stdout whose reader has closed the pipe.
pub fn is_broken_pipe(e: &Error) -> bool {
    matches!(e, Error::Io { path, source } if path == STDOUT && source.kind() == io::ErrorKind::BrokenPipe)
}
