//! One module per subcommand.

pub mod eval;
pub mod fit;
pub mod image;
pub mod inspect;
mod progress;
pub mod simulate;
