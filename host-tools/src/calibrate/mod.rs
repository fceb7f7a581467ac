//! `tcomp calibrate SPEC.toml`: a whole IMU (or a folder of units) in one command.
//!
//! Why a module of its own below `cmd/`: the command is a composition of the others — fit (the
//! trainer), eval (the core's evaluator over the held-out rows), diagnose, report, image — and
//! its parts each have one job: [`spec`] reads the file, [`channel`] runs one channel,
//! [`ship`] chooses what ships, [`unit`] runs a unit's channels in parallel and builds its image,
//! [`summary`] is `summary.json`, [`fleet`] runs many units and names the outliers, [`collect`] reads back the units
//! calibrated one by one by batch jobs. It takes plain settings ([`channel::Settings`],
//! [`fleet::FleetOptions`]), never the command's clap arguments: `cmd/calibrate.rs` converts them.

pub mod channel;
pub mod collect;
pub mod fleet;
pub mod ship;
pub mod spec;
pub mod summary;
pub mod table;
pub mod unit;
