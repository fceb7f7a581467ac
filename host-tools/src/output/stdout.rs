//! Standard output that never panics: `tcomp diagnose … | head` must not crash.
//!
//! Why: `println!` panics when the reader of a pipe has gone away (`EPIPE`), and with
//! `RUST_BACKTRACE=1` the user gets a stack trace for having piped into `head`. Command output goes
//! through [`write`] instead (the `outln!`/`out!` macros of the `output` module): the first write error
//! is kept and later output dropped, the command finishes its work (a `fit` still writes its blob),
//! and `main` asks [`finish`] how standard output fared.

use std::io::Write as _;
use std::sync::OnceLock;

static FAILURE: OnceLock<std::io::Error> = OnceLock::new();

/// Writes `args` to standard output, or nothing once a write has failed.
pub fn write(args: std::fmt::Arguments<'_>) {
    if FAILURE.get().is_some() {
        return;
    }
    if let Err(e) = std::io::stdout().lock().write_fmt(args) {
        let _ = FAILURE.set(e);
    }
}

/// Flushes standard output; the first error any write met, if one did.
pub fn finish() -> Result<(), &'static std::io::Error> {
    if FAILURE.get().is_none()
        && let Err(e) = std::io::stdout().lock().flush()
    {
        let _ = FAILURE.set(e);
    }
    FAILURE.get().map_or(Ok(()), Err)
}
