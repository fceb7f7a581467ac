//! The C API of the compensation core: what a C firmware (a vendor SDK, an RTOS application, a
//! soft core with a C toolchain) or a host C program links to run tcomp's models without Rust.
//!
//! Why a crate of its own: the core is `no_std`, allocation-free and never panics on data, which
//! is exactly what a C firmware needs, but its API is generic Rust (const generics, borrowed
//! models, `Result`s). This crate is the door: plain C types, integer error codes, storage the
//! caller provides, and nothing else. It holds no logic of its own — every function decodes,
//! checks, steps or names through the core's own [`tcomp_core::Model`], [`tcomp_core::Channel`],
//! [`tcomp_core::image::Image`] and [`tcomp_core::frame::status`], so a fix in the core reaches C,
//! Python, the CLI and the Rust firmware at once.
//!
//! The header `include/tcomp.h` is generated from this crate by cbindgen (`cbindgen.toml`) and
//! committed; `tests/header.rs` regenerates it and fails when the committed one differs.
//!
//! # Rules every entry point keeps
//! * **No allocation.** A channel lives in a [`TcompChannel`] the caller provides (a `static`, a
//!   stack variable, a member of the caller's own struct): [`TCOMP_CHANNEL_SIZE`] bytes aligned to
//!   [`TCOMP_CHANNEL_ALIGN`].
//! * **No panic crosses the boundary.** On the host each entry point runs under
//!   `catch_unwind` and a panic (a bug) comes back as [`TCOMP_ERR_PANIC`] (the channel is then
//!   refused until it is initialised again); on a bare-metal target the panic handler calls the
//!   application's `tcomp_panic_hook` and stops (see `panic.rs`). `tests/no_panic.rs` drives every
//!   entry point with arbitrary bytes and arguments and asserts that no path panics.
//! * **Errors are integers** (`TCOMP_OK` = 0, `TCOMP_ERR_*` < 0), named by [`tcomp_error_name`];
//!   the detail of a load's failure (the core's own message, e.g. which field of a blob is
//!   inconsistent) by [`tcomp_channel_describe`].
//! * **Never a NaN with status OK**: a step that cannot run (bad arguments) still writes the raw
//!   value with [`TCOMP_STATUS_INPUT_FAULT`] when it has somewhere to write it.
//!
//! Capacities are the reference firmware's ([`tcomp_core::FLIGHT_CENTERS`] and its siblings):
//! the blobs `tcomp fit` marks as fitting the firmware load here, bigger ones are refused with
//! [`TCOMP_ERR_BLOB_CAPACITY`].
#![no_std]

// The host build catches panics at the boundary; a bare-metal build has no unwinding.
#[cfg(not(target_os = "none"))]
extern crate std;

mod api;
mod channel;
mod error;
mod guard;
mod out;
mod panic;
mod query;
mod status;
mod step;

pub use api::*;
pub use channel::{TCOMP_CHANNEL_ALIGN, TCOMP_CHANNEL_SIZE, TcompChannel};
pub use error::*;
pub use query::*;
pub use status::*;
pub use step::*;
