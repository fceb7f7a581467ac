//! One module per subcommand.

mod check;
pub mod compare;
pub mod demo;
pub mod diagnose;
pub mod eval;
pub mod fit;
pub mod image;
pub mod inspect;
mod output;
mod printable;
mod progress;
pub mod report;
pub mod simulate;
