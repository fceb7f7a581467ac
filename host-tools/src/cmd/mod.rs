//! One module per subcommand.

/// `println!` for command output, through [`stdout::write`]: never panics on a closed pipe.
macro_rules! outln {
    () => {
        $crate::cmd::stdout::write(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::cmd::stdout::write(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` for command output, through [`stdout::write`].
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::cmd::stdout::write(format_args!($($arg)*))
    };
}

pub mod autopilot;
pub mod calibrate;
mod check;
pub mod compare;
pub mod demo;
pub mod diagnose;
pub mod eval;
pub mod fit;
pub mod flash;
pub mod frames;
pub mod image;
pub mod inspect;
mod inspect_image;
pub mod json;
pub mod keygen;
pub mod output;
pub mod printable;
pub mod progress;
pub mod report;
pub mod run;
pub mod simulate;
mod simulate_units;
pub mod stdout;
