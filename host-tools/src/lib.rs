//! The `tcomp` command line's modules as a library, for the Python binding (`python/`), which
//! runs `tcomp calibrate` as a function and must hold no logic of its own.
//!
//! Commands on top, helpers below: [`cmd`] holds one module per subcommand (its clap arguments and
//! its `run`); what they are built from lives beside it and never imports it — [`calibrate`] (a
//! whole unit or fleet, composed of the trainer, the evaluator, the diagnosis and the image),
//! [`image`] (building and signing a unit's calibration image), [`render`] (tables, diagnosis
//! text, the HTML report), [`demo`] (the demo's narrative), [`output`] (standard output, safe
//! printing, the `--json` vocabulary, output files, progress) and [`args`] (the arguments several
//! commands share). `host-tools/tests/layering.rs` fails when a module outside `cmd/` names it.
//!
//! Why this file and nothing more: moving the library side into a library crate of its own is the
//! structural issue's work; until then the binary's modules are compiled as this library and
//! `main.rs` is only the argument parser and dispatcher, so the Python function and `tcomp
//! calibrate` run one implementation. The modules were written as the binary's internals: their
//! public items are documented where a reader of the command needs it, not as a library's API,
//! hence the lint below.
#![allow(missing_docs)]

// First, so that its `outln!`/`out!` macros are in scope in the modules declared after it.
#[macro_use]
pub mod output;

pub mod args;
pub mod calibrate;
pub mod cmd;
pub mod demo;
pub mod image;
pub mod render;
