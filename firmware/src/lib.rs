//! The firmware's application, once for every board: the compensation loop ([`app`]), the tasks
//! that run it on a board ([`application`]: an RTIC 2 app each board binary binds, with the frame
//! queue, the update task and the watchdog policy), the fault record kept across resets
//! ([`fault`]), the time-base check ([`timing`]), the boot report ([`boot`]), the channel tables
//! generated from the board descriptions ([`wiring`]), the model-blob image in flash ([`image`])
//! and its two slots ([`slots`]), which images the unit runs (made for it, signed by a provisioned
//! key: [`trust`]), the update task's protocol end ([`update`]), and the replay board
//! of the QEMU run ([`replay`]).
//!
//! Nothing here touches hardware: the board crates (`boards/qemu`, `boards/stm32f4`) own the
//! registers, and everything here builds and is tested on the host, where `cargo xtask qemu` runs
//! the very same loop over the replay vector to produce the outputs the QEMU board must reproduce
//! bit for bit.
#![no_std]

pub mod app;
pub mod application;
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
mod test_flash;
#[cfg(test)]
mod trust_tests;

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
