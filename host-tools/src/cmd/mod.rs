//! One module per subcommand.

pub mod autopilot;
pub mod calibrate;
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
pub mod keygen;
pub mod report;
pub mod simulate;
mod simulate_units;
