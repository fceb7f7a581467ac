//! What the commands write and show: standard output that never panics ([`stdout`], through the
//! `outln!`/`out!` macros below), strings from files made safe to print ([`printable`]), the
//! shared JSON vocabulary of `--json` ([`json`]), output files that never overwrite an input nor
//! stay half-written ([`files`]), and the progress display on stderr ([`progress`]).
//!
//! Why a module of its own below `cmd/`: the commands use these, and so do the parts of the crate
//! the commands are built on (`calibrate/` stages its outputs and writes the JSON vocabulary,
//! `render/` names changes as `json` does). Helpers never import a command, so they cannot live
//! among the commands.

/// `println!` for command output, through [`stdout::write`]: never panics on a closed pipe.
macro_rules! outln {
    () => {
        $crate::output::stdout::write(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::output::stdout::write(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` for command output, through [`stdout::write`].
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::output::stdout::write(format_args!($($arg)*))
    };
}

pub mod files;
pub mod json;
pub mod printable;
pub mod progress;
pub mod stdout;
