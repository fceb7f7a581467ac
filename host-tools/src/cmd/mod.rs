//! One module per subcommand.

pub mod compare;
pub mod demo;
pub mod diagnose;
pub mod eval;
pub mod fit;
pub mod frames;
pub mod image;
pub mod inspect;
mod progress;
pub mod report;
pub mod simulate;
