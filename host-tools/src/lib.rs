//! The `tcomp` command line's modules as a library, for the Python binding (`python/`), which
//! runs `tcomp calibrate` as a function and must hold no logic of its own.
//!
//! Why this file and nothing more: `calibrate` composes the other commands (fit, eval, diagnose,
//! report, image) and writes through their helpers, all of which live in this crate. Moving it
//! below the commands into a library crate of its own is the structural issue's work; until then
//! the binary's modules are compiled as this library and `main.rs` is only the argument parser
//! and dispatcher, so the Python function and `tcomp calibrate` run one implementation.
//! The modules were written as the binary's internals: their public items are documented where
//! a reader of the command needs it, not as a library's API, hence the lint below.
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
