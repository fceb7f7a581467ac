//! The compensation loop on an STM32F407 IMU board: the firmware library's application (an RTIC 2
//! app, `tcomp_firmware::application!`) bound to this board's interrupts, with this board's setup
//! and drivers (`board.rs`, `setup.rs`, `flash.rs`). The tasks, their priorities, the frame queue,
//! the update task and the watchdog policy are the library's, the same the QEMU board runs in CI:
//!
//! * `receive` — DMA2 stream 2's half/full-transfer interrupt, priority 4: the received bytes are
//!   already in the ring (the DMA moved them); it counts the half rings for the ring's reader;
//! * `sample` — TIM2's update, priority 3: one loop period (`application::sample`);
//! * `drain` — USART1 (TXE), priority 2: the frame queue into the transmitter;
//! * `update` — UART5's line (unused by the board, pended), priority 1: the update protocol over
//!   the ring, writing the inactive slot through `flash.rs`.
//!
//! Logs go out with defmt over RTT (read by `probe-rs run`; without a probe they cost a buffer
//! write). A panic or HardFault is recorded in no-init RAM and resets the chip ([`fault`]); the
//! next boot reports it.
#![no_std]
#![no_main]

mod board;
mod fault;
mod flash;
mod setup;

include!(concat!(env!("OUT_DIR"), "/board_config.rs"));

use defmt_rtt as _;

tcomp_firmware::application! {
    device: stm32f4xx_hal::pac,
    board: crate::board,
    sample: TIM2,
    drain: USART1,
    receive: DMA2_STREAM2,
    update: UART5,
}

/// Start of the STM32F4's one-time-programmable area (RM0090 §3.8: 512 bytes in 16 blocks of
/// 32 bytes, and a lock byte per block at 0x1FFF_7A00). Block 0's first 8 bytes hold the unit
/// serial, programmed once at manufacturing and then locked: unlike the factory's 96-bit device
/// id (0x1FFF_7A10), it is the number on the unit's label, which `tcomp image --serial` takes; and
/// OTP survives every firmware and image update, so an image cannot be moved to another unit by
/// reflashing it.
const OTP_SERIAL: usize = 0x1FFF_7800;

/// The unit's serial (little-endian u64 at [`OTP_SERIAL`]); all ones on a unit whose OTP was never
/// programmed, which no image names, so such a unit runs every channel with `NO_MODEL` and its
/// boot report says "image made for another unit".
pub fn unit_serial() -> u64 {
    let mut b = [0u8; 8];
    for (i, byte) in b.iter_mut().enumerate() {
        // SAFETY: the OTP area is always mapped and readable on the STM32F405/407; reading it has
        // no side effect.
        *byte = unsafe { core::ptr::read_volatile((OTP_SERIAL + i) as *const u8) };
    }
    u64::from_le_bytes(b)
}

/// OTP blocks 1–4 (`0x1FFF_7820`, 128 bytes): the Ed25519 public keys this unit trusts, one per
/// 32-byte block, programmed at the factory after the serial (see README.md, "Signed images").
/// Outside the model slots and the firmware's sectors: no image or firmware update touches it.
/// An unprogrammed block (all 0xFF) or a revoked one (all 0x00) holds no key.
const OTP_KEYS: usize = 0x1FFF_7820;
/// Bytes of the key store: four keys, for rotation.
const OTP_KEYS_LEN: usize = 4 * 32;

/// The key store in OTP.
pub fn otp_keys() -> &'static [u8] {
    // SAFETY: the OTP area is always mapped and readable on the STM32F405/407, and nothing in
    // the firmware programs it; 128 bytes from block 1 lie inside its 512 bytes.
    unsafe { core::slice::from_raw_parts(OTP_KEYS as *const u8, OTP_KEYS_LEN) }
}

/// The unit's trust: its serial and its keys (`tcomp_firmware::trust`).
pub fn trust() -> tcomp_firmware::trust::Trust<'static> {
    tcomp_firmware::trust::Trust::new(unit_serial(), otp_keys())
}
