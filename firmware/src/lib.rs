//! The firmware: the compensation loop ([`app`]), the fault record kept across resets ([`fault`]),
//! the time-base check ([`timing`]), the boot report ([`boot`]), the channel tables generated from
//! the board descriptions ([`wiring`]),
//! the model-blob image in flash ([`image`]) and its two slots ([`slots`]), which images the unit
//! runs (made for it, signed by a provisioned key: [`trust`]), the update task that
//! rewrites them over the serial link ([`update`]), the replay board of the QEMU run ([`replay`]), and
//! board support for the binaries (semihosting exit codes, the SysTick instruction counter).
//!
//! Only the board support touches hardware and is compiled for the target alone
//! (`cfg(target_os = "none")`); the rest builds on the host, where `cargo xtask qemu` runs the very
//! same loop over the replay vector to produce the outputs the firmware must reproduce bit for bit.
//!
//! Under QEMU with `-icount shift=0` every guest instruction takes one nanosecond of virtual time and
//! SysTick runs from the 25 MHz board clock, so one SysTick tick is 40 instructions: counting ticks
//! counts instructions deterministically (QEMU does not emulate the DWT cycle counter). The replay
//! runs with `-icount shift=3` (8 ns per instruction): one tick is 5 instructions there.
#![no_std]

pub mod app;
pub mod boot;
pub mod fault;
pub mod image;
pub mod replay;
pub mod slots;
pub mod timing;
pub mod trust;
pub mod update;
pub mod wiring;

#[cfg(test)]
mod trust_tests;

#[cfg(target_os = "none")]
mod board;
#[cfg(target_os = "none")]
pub use board::*;

/// FNV-1a over the bits of a record, folded into `hash`: the running output hash both sides print.
pub fn fold_hash(hash: u32, record: &app::Record) -> u32 {
    let mut h = hash;
    for b in record
        .compensated
        .to_bits()
        .to_le_bytes()
        .into_iter()
        .chain(record.status.to_le_bytes())
    {
        h = (h ^ u32::from(b)).wrapping_mul(0x0100_0193);
    }
    h
}

/// FNV-1a offset basis: the hash before any record.
pub const HASH_START: u32 = 0x811C_9DC5;
