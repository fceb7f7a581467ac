//! One module per subcommand, and nothing else: each holds its command's clap arguments and its
//! `run` (`inspect_image` and `simulate_units` are parts of `inspect` and `simulate`).
//!
//! Why nothing else: commands sit on top and helpers below. What several commands share (the
//! output helpers in [`crate::output`], the shared arguments in [`crate::args`], the image
//! building in [`crate::image`], the rendering in [`crate::render`], the calibration in
//! [`crate::calibrate`]) lives outside `cmd/`, and no module outside it imports from it except the
//! dispatchers (`main.rs`, `lib.rs`); `host-tools/tests/layering.rs` holds that rule.

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
