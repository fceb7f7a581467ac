//! The compensation core: everything that must behave the same on the host trainer and on the IMU.
//!
//! `no_std`, no allocation (except the optional `alloc` feature's [`expr`]), no `unsafe`. Four
//! parts, each in its own module:
//!
//! * [`program`] — feature programs: a small expression language over named input columns
//!   (`T = mean(t_anode_c, t_shell_c)`, `rate(T)`, `T * rate(T)`, `lag(T, 2400)`, …), defined once
//!   in the operator table of [`lang`], compiled by [`compile`] (errors and lexical rules in
//!   [`syntax`]) into a fixed-capacity list of operations, and [`stream`] runs it sample by sample
//!   with bounded state, each operation evaluated by its function in [`eval`]. The trainer computes
//!   its training features by running exactly this code over the CSV; programs, compiler and
//!   evaluator are generic over the number type ([`Real`]: f32 on the board, f64 for the
//!   simulator's truths). With the `alloc` feature, [`expr`] builds expressions as syntax trees and
//!   prints them as text the compiler reads.
//! * [`rbf`] — the Gaussian RBF evaluator with per-feature normalisation, per-center widths, an optional
//!   linear term, and the fast exponential of [`fastexp`].
//! * [`blob`] — the model blob: one serde type, postcard-encoded, with magic, version and CRC-32;
//!   decoding any byte string yields a `Result`, never a panic; [`bound`] refuses a model whose
//!   evaluation could be non-finite or implausibly large anywhere in its range box.
//! * [`compensator`] — the immutable model apart from the per-channel streaming state:
//!   `step(inputs, raw) → (compensated, status)`.
//!
//! [`frame`] is the output frame the firmware sends per sample and the host decodes.
//! [`framer`] is the one sync-word frame decoder, under both the output frames and the update
//! protocol's.
//! [`slots`] keeps the model image in two flash slots (A/B) with a commit marker written last, and
//! [`update`] is the framed protocol and the unit's receiver that replace an image over the serial
//! link through them.
//!
//! Capacities are const generics (`C` centers, `F` features, `N` program nodes), so the firmware sizes
//! its models for its channels and the host uses the large defaults.
#![no_std]

#[cfg(feature = "alloc")]
extern crate alloc;

pub mod blob;
pub mod bound;
pub mod compensator;
pub mod compile;
pub mod crc;
pub mod eval;
#[cfg(feature = "alloc")]
pub mod expr;
pub mod fastexp;
pub mod frame;
pub mod framer;
pub mod image;
pub mod lang;
pub mod point;
pub mod program;
pub mod rbf;
mod real;
pub mod slots;
pub mod stream;
pub mod syntax;
mod tag;
pub mod testing;
pub mod update;
pub mod vocab;

pub use blob::{BlobError, ColumnRoles, FeatureRange, Meta, Model, ResidualLevel, SensorKind};
pub use compensator::{Channel, Output, Status};
pub use compile::ProgramBuilder;
pub use program::{Op, Program, ProgramError};
pub use rbf::{Center, Rbf};
pub use real::Real;
pub use stream::{ProgramState, StepError};
pub use syntax::{ParseError, ParseErrorKind};
pub use vocab::EffectKind;

/// Host-side default capacity: centers per model.
pub const HOST_CENTERS: usize = 64;
/// Host-side default capacity: features per model.
pub const HOST_FEATURES: usize = 8;
/// Host-side default capacity: operations per feature program.
pub const HOST_NODES: usize = 48;
/// A model at the host-side capacities: what the trainer writes and every host tool decodes.
pub type HostModel<'a> = Model<'a, HOST_CENTERS, HOST_FEATURES, HOST_NODES>;
/// The reference firmware's capacity (`firmware/src/app.rs` takes these): centers per model.
pub const FLIGHT_CENTERS: usize = 32;
/// The reference firmware's capacity: features per model.
pub const FLIGHT_FEATURES: usize = 4;
/// The reference firmware's capacity: operations per feature program.
pub const FLIGHT_NODES: usize = 16;
/// Named input columns a program may read.
pub const MAX_INPUTS: usize = 8;
/// Named signals (`NAME = expr`) a program may define.
pub const MAX_SIGNALS: usize = 8;
/// Stateful operations (`rate`, `lag`, `hyst`) in one program.
pub const MAX_STATEFUL: usize = 8;
