//! The boot report: what the unit runs, sent over the same serial link as the data frames.
//!
//! A user who plugs a terminal into a running unit must be able to see which calibration it runs
//! without resetting it, so the firmware sends this frame at boot and then every
//! [`BOOT_REPORT_PERIOD_S`] seconds. It shares the data frames' sync word and CRC but has its own
//! version byte ([`BOOT_VERSION`]), so a decoder that only knows data frames skips it like any
//! other non-frame bytes, and data frames' bytes are unchanged.
//!
//! # Layout (little-endian)
//!
//! ```text
//! offset    size  field
//! 0         2     sync word 0xEB 0x90
//! 2         1     kind and version: 0x83 (boot report, version 3)
//! 3         1     channel count K (0..=8)
//! 4         4     sequence number of the next data frame (the report does not consume one)
//! 8         8     the unit's serial
//! 16        8     the image's unit serial (0 without a version-2 image)
//! 24        8     the image's board-description hash (0 without one)
//! 32        4     the image's whole-image CRC (0 without one)
//! 36        2     image format version (0: no image)
//! 38        1     image state (see [`image_state`]: 0 ok, 1 no image, 2 made for another unit,
//!                 3 invalid, 4 its channel table refused by this board, 5 unsigned, 6 signed
//!                 by a key the unit does not hold, 7 its signature does not verify)
//! 39        1     flags: bit 0 the boot followed a watchdog reset; bit 1 a development build
//!                 that runs unsigned images ([`DEVELOPMENT`])
//! 40        8     the signer's key id, u64 (`sign::KeyId::as_u64`: the same 16 hex digits; 0: unsigned
//!                 or none)
//! 48        1     the last update since boot (see [`update_state`]: 0 none, 1 committed, runs
//!                 from the next reset, 2 refused, 3 failed)
//! 49        1     its reason: the update protocol's `Reason` code (0 when committed or none)
//! 50        4     the stack's peak use since boot, bytes, as the board measures it (its paint;
//!                 0 until the first measurement)
//! 54        4     the sample task's worst cost since boot (entry to the watchdog feed) on the
//!                 board's cost counter: core cycles on the STM32F407 (the DWT counter, 840,000
//!                 a 200 Hz period at 168 MHz), instructions under QEMU
//! 58        3·K   per channel: channel id u16, model state u8 (0 loaded, else the reason, see
//!                 the firmware's `LoadError::code`)
//! 58 + 3K   4     CRC-32 of bytes 2 .. 58 + 3K
//! ```
//!
//! The report repeats every [`BOOT_REPORT_PERIOD_S`], so it is also the unit's status frame: the
//! stack peak and the worst sample task are read off a running unit over the same link, without
//! a debugger (the budgets they are held to: BENCHMARKS.md, "Firmware").
//!
//! Version 1 (0x81) had no key id and no update outcome (header 40 bytes); version 2 (0x82) no
//! stack peak and worst cost (header 50 bytes); neither is read.
//! A refused update shows in every report until the next reset, so a user who looks at the unit
//! after a refused `tcomp flash` sees why, and that it still runs its old image.

use super::{MAX_CHANNELS, SYNC, le_u32, le_u64};
use crate::crc::crc32;

/// The version byte of a boot report (the data frames' is 1).
pub const BOOT_VERSION: u8 = 0x83;
/// How often the firmware repeats the report, seconds. Ten seconds: a user attaching a terminal
/// sees it within the time it takes to look at the screen, and at 200 Hz it costs one 64-byte
/// frame per 2,000 data frames (0.04 % of the link).
pub const BOOT_REPORT_PERIOD_S: u32 = 10;
/// Bytes before the channels.
pub const BOOT_HEADER_LEN: usize = 58;
/// Flag bit: the boot followed a watchdog reset.
pub const WATCHDOG: u8 = 1;
/// Flag bit: a development build, which runs unsigned images (chosen at build time; every
/// report of such a unit says so).
pub const DEVELOPMENT: u8 = 2;
/// Bytes per channel.
pub const BOOT_CHANNEL_LEN: usize = 3;

/// Length of a boot report of `channels` channels.
pub const fn boot_len(channels: usize) -> usize {
    BOOT_HEADER_LEN + BOOT_CHANNEL_LEN * channels + super::CRC_LEN
}

/// The image state of a boot report.
pub mod image_state {
    /// The image was read and its table accepted.
    pub const OK: u8 = 0;
    /// No image (erased or empty region).
    pub const NONE: u8 = 1;
    /// The image was made for another unit.
    pub const OTHER_UNIT: u8 = 2;
    /// The image is corrupt or unreadable.
    pub const INVALID: u8 = 3;
    /// The image's channel table does not fit this board.
    pub const TABLE: u8 = 4;
    /// The image is not signed (and this build runs signed images only).
    pub const UNSIGNED: u8 = 5;
    /// The image is signed by a key the unit does not hold.
    pub const UNKNOWN_KEY: u8 = 6;
    /// The image's signature does not verify.
    pub const BAD_SIGNATURE: u8 = 7;
    /// Every state with its name (what `tcomp frames` prints).
    pub const NAMES: [(u8, &str); 8] = [
        (OK, "ok"),
        (NONE, "no image"),
        (OTHER_UNIT, "made for another unit"),
        (INVALID, "invalid"),
        (TABLE, "channel table refused by the board"),
        (UNSIGNED, "not signed"),
        (UNKNOWN_KEY, "signed by a key the unit does not hold"),
        (BAD_SIGNATURE, "signature does not verify"),
    ];

    /// The name of `state` (`"unknown"` for a code this build does not know).
    pub fn name(state: u8) -> &'static str {
        NAMES
            .iter()
            .find(|(c, _)| *c == state)
            .map_or("unknown", |(_, n)| n)
    }
}

/// The last update since boot, as a boot report carries it.
pub mod update_state {
    /// No update since boot.
    pub const NONE: u8 = 0;
    /// An image was committed: it runs from the next reset.
    pub const COMMITTED: u8 = 1;
    /// The unit refused the image before committing it (the reason byte says why).
    pub const REFUSED: u8 = 2;
    /// The update failed on the unit's side (flash error, CRC after writing).
    pub const FAILED: u8 = 3;
    /// Every state with its name.
    pub const NAMES: [(u8, &str); 4] = [
        (NONE, "none"),
        (COMMITTED, "committed"),
        (REFUSED, "refused"),
        (FAILED, "failed"),
    ];

    /// The name of `state`.
    pub fn name(state: u8) -> &'static str {
        NAMES
            .iter()
            .find(|(c, _)| *c == state)
            .map_or("unknown", |(_, n)| n)
    }
}

/// One channel's line of a boot report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ChannelState {
    /// Channel id.
    pub id: u16,
    /// 0: model loaded; otherwise why not.
    pub state: u8,
}

/// A boot report's content.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BootReport {
    /// The next data frame's sequence number.
    pub sequence: u32,
    /// The unit's serial.
    pub unit_serial: u64,
    /// The image's unit serial.
    pub image_serial: u64,
    /// The image's board hash.
    pub board_hash: u64,
    /// The image's whole-image CRC.
    pub image_crc: u32,
    /// The image's format version (0: none).
    pub image_version: u16,
    /// [`image_state`].
    pub image_state: u8,
    /// [`WATCHDOG`], [`DEVELOPMENT`].
    pub flags: u8,
    /// The signer's key id (`sign::KeyId::as_u64`; 0: unsigned or no image).
    pub signer: u64,
    /// [`update_state`] of the last update since boot.
    pub update: u8,
    /// Its reason (the update protocol's `Reason` code).
    pub update_reason: u8,
    /// The stack's peak use since boot, bytes (0: not measured yet).
    pub stack_peak: u32,
    /// The sample task's worst cost since boot, on the board's cost counter (STM32F407: core
    /// cycles; QEMU: instructions).
    pub worst_task: u32,
    channels: [ChannelState; MAX_CHANNELS],
    count: u8,
}

impl BootReport {
    /// A report with every field zero and no channel lines (the `Default`, usable in a `static`).
    pub const EMPTY: Self = Self {
        sequence: 0,
        unit_serial: 0,
        image_serial: 0,
        board_hash: 0,
        image_crc: 0,
        image_version: 0,
        image_state: 0,
        flags: 0,
        signer: 0,
        update: 0,
        update_reason: 0,
        stack_peak: 0,
        worst_task: 0,
        channels: [ChannelState { id: 0, state: 0 }; MAX_CHANNELS],
        count: 0,
    };

    /// Sets the channel lines (the first [`MAX_CHANNELS`] of `channels`).
    pub fn set_channels(&mut self, channels: &[ChannelState]) {
        self.count = 0;
        for (slot, c) in self.channels.iter_mut().zip(channels) {
            *slot = *c;
            self.count += 1;
        }
    }

    /// The channel lines.
    pub fn channels(&self) -> &[ChannelState] {
        self.channels.get(..usize::from(self.count)).unwrap_or(&[])
    }

    /// Writes the report into the start of `out`; returns its length, or `None` when `out` is
    /// too short.
    pub fn encode(&self, out: &mut [u8]) -> Option<usize> {
        let k = usize::from(self.count);
        let len = boot_len(k);
        let out = out.get_mut(..len)?;
        let mut w = super::Writer { buf: out, at: 0 };
        w.put(&SYNC);
        w.put(&[BOOT_VERSION, self.count]);
        w.put(&self.sequence.to_le_bytes());
        w.put(&self.unit_serial.to_le_bytes());
        w.put(&self.image_serial.to_le_bytes());
        w.put(&self.board_hash.to_le_bytes());
        w.put(&self.image_crc.to_le_bytes());
        w.put(&self.image_version.to_le_bytes());
        w.put(&[self.image_state, self.flags]);
        w.put(&self.signer.to_le_bytes());
        w.put(&[self.update, self.update_reason]);
        w.put(&self.stack_peak.to_le_bytes());
        w.put(&self.worst_task.to_le_bytes());
        for c in self.channels() {
            w.put(&c.id.to_le_bytes());
            w.put(&[c.state]);
        }
        let crc = crc32(w.buf.get(SYNC.len()..w.at)?);
        w.put(&crc.to_le_bytes());
        Some(len)
    }

    /// Reads a report whose sync word, version, channel count, length and CRC the decoder's
    /// framer checked.
    pub(super) fn parse(bytes: &[u8]) -> Option<Self> {
        let k = usize::from(*bytes.get(3)?);
        if bytes.get(2) != Some(&BOOT_VERSION) || k > MAX_CHANNELS {
            return None;
        }
        let mut r = Self {
            sequence: le_u32(bytes, 4)?,
            unit_serial: le_u64(bytes, 8)?,
            image_serial: le_u64(bytes, 16)?,
            board_hash: le_u64(bytes, 24)?,
            image_crc: le_u32(bytes, 32)?,
            image_version: u16::from_le_bytes([*bytes.get(36)?, *bytes.get(37)?]),
            image_state: *bytes.get(38)?,
            flags: *bytes.get(39)?,
            signer: le_u64(bytes, 40)?,
            update: *bytes.get(48)?,
            update_reason: *bytes.get(49)?,
            stack_peak: le_u32(bytes, 50)?,
            worst_task: le_u32(bytes, 54)?,
            ..Self::default()
        };
        for (i, c) in r.channels.iter_mut().enumerate().take(k) {
            let at = BOOT_HEADER_LEN + BOOT_CHANNEL_LEN * i;
            *c = ChannelState {
                id: u16::from_le_bytes([*bytes.get(at)?, *bytes.get(at + 1)?]),
                state: *bytes.get(at + 2)?,
            };
        }
        r.count = u8::try_from(k).ok()?;
        Some(r)
    }
}
