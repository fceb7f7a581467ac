//! The replay board: [`Thermometer`]s and [`PulseCounter`]s that play back a recorded test vector,
//! so the very application code of [`crate::app`] runs on it, on the host and under QEMU alike.
//!
//! The vector is written by `cargo xtask qemu` from a simulator run at 200 Hz (see
//! `firmware/replay/*.toml`) with faults injected, together with the outputs the host computed for it.
//! Under QEMU it is loaded into the board's 16 MiB `mps.ram` at `0x2100_0000` (test data, not
//! firmware: it is not linked and not counted in the flash budget). Little-endian layout:
//!
//! ```text
//! offset  size  field
//! 0       4     magic b"TCRV"
//! 4       2     version (2)
//! 6       2     configuration: 0 = IMU6 (3 RLG + 3 QMA), 1 = IFOG1
//! 8       4     samples S
//! 12      2     thermometers T
//! 14      2     counters P
//! 16      2     channels K
//! 18      2     flags: bit 0 [`HOLD_FOR_UPDATE`]
//! 20      4     timestamp latched with the counter registers before the first sample (u32)
//! 24      4·P   counter registers before the first sample (u32)
//! …       S × (8 + 4T + 4P)   per sample: fault mask u32 (bit i: thermometer i bus error,
//!                             bit 16+j: counter j bus error, bit 22+j: counter j flags the
//!                             interval, bits 28–31: the board's injections [`STALL`],
//!                             [`TIME_GLITCH`], [`HANG`], [`MISS`]), the timestamp the counter
//!                             block latched at the sample's timer edge (u32 ticks of
//!                             [`TICK_HZ`]: the nominal periods plus the jitter the vector
//!                             carries), T temperatures (f32 °C, may be NaN), P counter registers
//!                             (u32, free-running, wrapping)
//! …       S × K × 8           expected output per sample and channel: compensated f32 bits (u32),
//!                             status (u32)
//! ```
//!
//! The counters are read as the counter block is, one latched snapshot per sample ([`Board::snapshot`],
//! a [`CounterSnapshot`]), which returns the interval between the latched timestamps, so the loop
//! divides by the time the vector's counts really cover. A vector's timestamps do not wrap (10,000
//! samples are 1.25 · 10⁹ ticks of 2³²).
//!
//! A replayed NaN temperature is returned as `Ok(NaN)` on purpose, although the [`Thermometer`]
//! contract promises finite values: it tests the loop's defence against a driver that breaks it.

use crate::app::{MAX_COUNTERS, MAX_THERMOMETERS, Record};
use tcomp_hal::{
    CounterSnapshot, ErrorKind, ErrorType, Interval, PulseCounter, Thermometer, wrapping_delta,
};

/// The four bytes a vector starts with.
pub const MAGIC: [u8; 4] = *b"TCRV";
/// The vector format version.
pub const VERSION: u16 = 2;
/// Bytes before the initial timestamp and counter values.
pub const HEADER_LEN: usize = 20;
/// Header flag: a model update is sent while this vector plays. After the last sample the board
/// keeps its loop running (on the last record's inputs, frames not compared) until the update has
/// committed, so the run never ends in the middle of an update however slowly the host sends it.
pub const HOLD_FOR_UPDATE: u16 = 1;
/// Fault-mask bit: the sample task of this sample takes longer than a period (the next sample is
/// late and flagged [`crate::app::status::OVERRUN`]).
pub const STALL: u32 = 1 << 28;
/// Fault-mask bit: this sample's latched timestamp is off by half a period (a glitch of the time
/// base, flagged [`crate::app::status::TIME_JUMP`]).
pub const TIME_GLITCH: u32 = 1 << 29;
/// Fault-mask bit: the loop hangs in this sample; the watchdog resets the board, which resumes with
/// the next sample and flags [`crate::app::status::WATCHDOG_RESET`] on its first frame.
pub const HANG: u32 = 1 << 30;
/// Fault-mask bit: this sample's task overruns past the next timer edge (as a board whose sample
/// interrupt was held off for more than a period): that edge is never served, its vector record
/// is skipped (the counter block latched over it), and the sample after covers two periods, late
/// and flagged [`crate::app::status::OVERRUN`].
pub const MISS: u32 = 1 << 31;
/// All the board-level injections.
pub const BOARD_FAULTS: u32 = STALL | TIME_GLITCH | HANG | MISS;
/// First fault-mask bit of the counters' flagged intervals (counter `j`: this bit shifted by `j`).
pub const COUNTER_FLAG_SHIFT: u32 = 22;
/// Timestamp ticks per loop period of the replayed time base (25 MHz, the board clock).
pub const TICKS_PER_PERIOD: u64 = 125_000;
/// Tick rate of the replayed time base.
pub const TICK_HZ: u32 = 25_000_000;

/// The replay board's unit serial: a fixed test identity (QEMU has no OTP area), which the QEMU
/// run's images are made for (`tcomp image --serial`).
pub const UNIT_SERIAL: u64 = 0x7C0_0001;

/// Configuration code of [`crate::app::IMU6`].
pub const CONFIG_IMU6: u16 = 0;
/// Configuration code of [`crate::app::IFOG1`].
pub const CONFIG_IFOG1: u16 = 1;

/// The board hash of configuration `code`'s description (`wiring::NAME_HASH`): what the replay's
/// boot compares an image's board hash with.
pub fn board_hash(code: u16) -> Option<u64> {
    match code {
        CONFIG_IMU6 => Some(crate::wiring::IMU6_RLG_QMA_HASH),
        CONFIG_IFOG1 => Some(crate::wiring::IFOG1_HASH),
        _ => None,
    }
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    b.get(at..at + 2)
        .map_or(0, |s| u16::from_le_bytes([s[0], s[1]]))
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    b.get(at..at + 4)
        .map_or(0, |s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
}

/// Why a vector is unusable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum VectorError {
    /// No magic or another version.
    BadHeader,
    /// More thermometers or counters than the board has.
    TooWide,
    /// Shorter than its header says.
    Truncated,
}

/// A validated test vector.
#[derive(Clone, Copy, Debug)]
pub struct Vector<'a> {
    bytes: &'a [u8],
    /// Configuration code.
    pub config: u16,
    /// Samples.
    pub samples: usize,
    /// Thermometers per sample.
    pub thermometers: usize,
    /// Counters per sample.
    pub counters: usize,
    /// Channels per expected record.
    pub channels: usize,
    /// Header flags ([`HOLD_FOR_UPDATE`]).
    pub flags: u16,
}

impl<'a> Vector<'a> {
    /// Checks the header and the length.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, VectorError> {
        if bytes.get(..4) != Some(&MAGIC[..]) || u16_at(bytes, 4) != VERSION {
            return Err(VectorError::BadHeader);
        }
        let v = Self {
            bytes,
            config: u16_at(bytes, 6),
            samples: u32_at(bytes, 8) as usize,
            thermometers: usize::from(u16_at(bytes, 12)),
            counters: usize::from(u16_at(bytes, 14)),
            channels: usize::from(u16_at(bytes, 16)),
            flags: u16_at(bytes, 18),
        };
        if v.thermometers > MAX_THERMOMETERS || v.counters > MAX_COUNTERS {
            return Err(VectorError::TooWide);
        }
        if bytes.len() < v.total_len() {
            return Err(VectorError::Truncated);
        }
        Ok(v)
    }

    /// Bytes of one input record.
    pub fn record_len(&self) -> usize {
        8 + 4 * self.thermometers + 4 * self.counters
    }

    fn inputs_at(&self) -> usize {
        HEADER_LEN + 4 + 4 * self.counters
    }

    fn expected_at(&self) -> usize {
        self.inputs_at() + self.samples * self.record_len()
    }

    /// The vector's full length in bytes.
    pub fn total_len(&self) -> usize {
        self.expected_at() + self.samples * self.channels * 8
    }

    /// The host's output for `sample`, `channel`.
    pub fn expected(&self, sample: usize, channel: usize) -> Record {
        let at = self.expected_at() + (sample * self.channels + channel) * 8;
        Record {
            compensated: f32::from_bits(u32_at(self.bytes, at)),
            status: u32_at(self.bytes, at + 4) as u16,
            ..Record::default()
        }
    }

    /// The board-level injections of sample `n` ([`BOARD_FAULTS`]).
    pub fn board_faults(&self, n: usize) -> u32 {
        u32_at(self.bytes, self.inputs_at() + n * self.record_len()) & BOARD_FAULTS
    }

    /// The timestamp the counter block latched at sample `n`'s timer edge (ticks of [`TICK_HZ`]):
    /// the vector's, half a period late where [`TIME_GLITCH`] is injected.
    pub fn timestamp(&self, n: usize) -> u64 {
        let t = u64::from(u32_at(
            self.bytes,
            self.inputs_at() + n * self.record_len() + 4,
        ));
        if self.board_faults(n) & TIME_GLITCH != 0 {
            t + TICKS_PER_PERIOD / 2
        } else {
            t
        }
    }

    /// A board as a fresh boot finds it before sample `n`: the counters' last latch is sample
    /// `n − 1`'s (the one before the first sample for `n = 0`).
    pub fn board_at(&self, n: usize) -> Board {
        let mut b = self.board();
        if let Some(prev) = n.checked_sub(1) {
            self.load(prev, &mut b);
            let latched = b.block.timestamp;
            for c in b.block.counters.iter_mut() {
                c.last = c.register;
                c.last_ts = latched;
                c.fault = false;
                c.flagged = false;
            }
        }
        b
    }

    /// A board positioned before the first sample.
    pub fn board(&self) -> Board {
        let mut b = Board {
            thermometers: [ReplayThermometer::default(); MAX_THERMOMETERS],
            n_thermometers: self.thermometers,
            block: ReplayBlock {
                counters: [ReplayCounter::default(); MAX_COUNTERS],
                n: self.counters,
                timestamp: u64::from(u32_at(self.bytes, HEADER_LEN)),
            },
        };
        let latched = b.block.timestamp;
        for (j, c) in b.block.counters.iter_mut().take(self.counters).enumerate() {
            let r = u32_at(self.bytes, HEADER_LEN + 4 + 4 * j);
            *c = ReplayCounter {
                register: r,
                last: r,
                last_ts: latched,
                fault: false,
                flagged: false,
            };
        }
        b
    }

    /// Loads sample `n` into the board's sensors (what the front ends would latch at the tick).
    pub fn load(&self, n: usize, board: &mut Board) {
        let at = self.inputs_at() + n * self.record_len();
        let faults = u32_at(self.bytes, at);
        board.block.timestamp = self.timestamp(n);
        let at = at + 4;
        for (i, t) in board
            .thermometers
            .iter_mut()
            .take(self.thermometers)
            .enumerate()
        {
            *t = ReplayThermometer {
                value: f32::from_bits(u32_at(self.bytes, at + 4 + 4 * i)),
                fault: faults & (1 << i) != 0,
            };
        }
        let counters_at = at + 4 + 4 * self.thermometers;
        for (j, c) in board
            .block
            .counters
            .iter_mut()
            .take(self.counters)
            .enumerate()
        {
            c.register = u32_at(self.bytes, counters_at + 4 * j);
            c.fault = faults & (1 << (16 + j)) != 0;
            c.flagged = faults & (1 << (COUNTER_FLAG_SHIFT as usize + j)) != 0;
        }
    }
}

/// One replayed thermometer: the latched reading of the current sample.
#[derive(Clone, Copy, Debug, Default)]
pub struct ReplayThermometer {
    value: f32,
    fault: bool,
}

impl ErrorType for ReplayThermometer {
    type Error = ErrorKind;
}

impl Thermometer for ReplayThermometer {
    fn read_celsius(&mut self) -> Result<f32, ErrorKind> {
        if self.fault {
            Err(ErrorKind::Bus)
        } else {
            Ok(self.value)
        }
    }
}

/// One replayed 32-bit free-running counter register.
#[derive(Clone, Copy, Debug, Default)]
pub struct ReplayCounter {
    register: u32,
    last: u32,
    /// The timestamp latched with `last`.
    last_ts: u64,
    fault: bool,
    flagged: bool,
}

impl ErrorType for ReplayCounter {
    type Error = ErrorKind;
}

impl PulseCounter for ReplayCounter {
    fn read_delta(&mut self) -> Result<i32, ErrorKind> {
        if self.fault {
            // The register keeps counting; the next good read returns everything since `last`.
            return Err(ErrorKind::Bus);
        }
        if self.flagged {
            // The block flagged the interval (pulses lost): consumed, the next one starts clean.
            self.last = self.register;
            return Err(ErrorKind::Fault);
        }
        let delta = wrapping_delta(self.last, self.register, 32);
        self.last = self.register;
        Ok(delta)
    }
}

/// The replayed sensors of a configuration.
#[derive(Clone, Debug)]
pub struct Board {
    thermometers: [ReplayThermometer; MAX_THERMOMETERS],
    n_thermometers: usize,
    block: ReplayBlock,
}

/// The replayed counters as one latched snapshot (what the counter block gives a loop).
#[derive(Clone, Debug)]
pub struct ReplayBlock {
    counters: [ReplayCounter; MAX_COUNTERS],
    n: usize,
    /// The timestamp latched at the current sample's timer edge.
    timestamp: u64,
}

/// Every counter read at the same latched timestamp. A counter that fails on the bus is not
/// consumed (on the real block a bus error fails every channel; here one counter can, as a
/// separate front end would). The interval returned is the one since the counters consumed now
/// were last consumed, if that was at one instant for all of them (as [`tcomp_hal::pulse_counter`]
/// decides for the block); otherwise `None`, and the loop uses the nominal periods.
impl CounterSnapshot for ReplayBlock {
    fn read_snapshot(&mut self, out: &mut [Interval]) -> Option<f32> {
        let mut since: Option<u64> = None;
        let mut same = true;
        let counters = self.counters.get_mut(..self.n).unwrap_or(&mut []);
        for (c, o) in counters.iter_mut().zip(out.iter_mut()) {
            let last = c.last_ts;
            *o = Interval::from_result(c.read_delta());
            if !matches!(o, Interval::Unread(_)) {
                c.last_ts = self.timestamp;
                same &= since.is_none_or(|s| s == last);
                since = Some(last);
            }
        }
        let ticks = self.timestamp.wrapping_sub(since.filter(|_| same)?);
        Some(ticks as f32 / TICK_HZ as f32)
    }
}

impl Board {
    /// The thermometers and counters, as the loop reads them.
    pub fn sensors(&mut self) -> (&mut [ReplayThermometer], &mut [ReplayCounter]) {
        let t = self
            .thermometers
            .get_mut(..self.n_thermometers)
            .unwrap_or(&mut []);
        let c = self
            .block
            .counters
            .get_mut(..self.block.n)
            .unwrap_or(&mut []);
        (t, c)
    }

    /// The thermometers, and the counters as one latched snapshot, as the loop reads them.
    pub fn snapshot(&mut self) -> (&mut [ReplayThermometer], &mut ReplayBlock) {
        let t = self
            .thermometers
            .get_mut(..self.n_thermometers)
            .unwrap_or(&mut []);
        (t, &mut self.block)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// One counter, no thermometer, one channel: registers 100, 150, 230 from 0, latched at 0 and
    /// then one period apart (the first 100 ticks late); sample 1's interval flagged and its
    /// timestamp glitched.
    fn vector() -> Vec<u8> {
        let mut b = Vec::new();
        b.extend_from_slice(&MAGIC);
        b.extend_from_slice(&VERSION.to_le_bytes());
        b.extend_from_slice(&CONFIG_IFOG1.to_le_bytes());
        b.extend_from_slice(&3u32.to_le_bytes());
        for v in [0u16, 1, 1, 0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&0u32.to_le_bytes());
        b.extend_from_slice(&0u32.to_le_bytes());
        let t = TICKS_PER_PERIOD as u32;
        for (mask, ts, reg) in [
            (0u32, t + 100, 100u32),
            ((1 << COUNTER_FLAG_SHIFT) | TIME_GLITCH, 2 * t, 150),
            (0, 3 * t, 230),
        ] {
            b.extend_from_slice(&mask.to_le_bytes());
            b.extend_from_slice(&ts.to_le_bytes());
            b.extend_from_slice(&reg.to_le_bytes());
        }
        b.resize(b.len() + 3 * 8, 0);
        b
    }

    #[test]
    fn a_flagged_interval_is_consumed_and_a_fresh_board_latches_the_previous_sample() {
        let bytes = vector();
        let v = Vector::parse(&bytes).unwrap();
        let mut board = v.board();
        let mut deltas = Vec::new();
        for n in 0..3 {
            v.load(n, &mut board);
            deltas.push(board.sensors().1[0].read_delta());
        }
        assert_eq!(deltas, [Ok(100), Err(ErrorKind::Fault), Ok(80)]);
        let mut fresh = v.board_at(2);
        v.load(2, &mut fresh);
        assert_eq!(fresh.sensors().1[0].read_delta(), Ok(80));
        let mut first = v.board_at(0);
        v.load(0, &mut first);
        assert_eq!(first.sensors().1[0].read_delta(), Ok(100));
    }

    #[test]
    fn timestamps_are_periods_and_a_glitch_is_half_a_period_late() {
        let bytes = vector();
        let v = Vector::parse(&bytes).unwrap();
        let t: Vec<u64> = (0..3).map(|n| v.timestamp(n)).collect();
        let p = TICKS_PER_PERIOD;
        assert_eq!(t, [p + 100, 2 * p + p / 2, 3 * p]);
        assert_eq!(v.board_faults(1), TIME_GLITCH);
        assert_eq!(v.board_faults(0), 0);
    }

    #[test]
    fn the_snapshot_returns_the_latched_interval() {
        let bytes = vector();
        let v = Vector::parse(&bytes).unwrap();
        let mut board = v.board();
        let hz = TICK_HZ as f32;
        let p = TICKS_PER_PERIOD as f32;
        let mut got = Vec::new();
        for n in 0..3 {
            v.load(n, &mut board);
            let mut out = [Interval::Unread(ErrorKind::NotReady); 1];
            let latched = board.snapshot().1.read_snapshot(&mut out);
            got.push((out[0], latched));
        }
        assert_eq!(
            got,
            [
                (Interval::Counted(100), Some((p + 100.0) / hz)),
                (
                    Interval::Flagged(ErrorKind::Fault),
                    Some((1.5 * p - 100.0) / hz)
                ),
                (Interval::Counted(80), Some(0.5 * p / hz)),
            ]
        );
    }

    #[test]
    fn a_skipped_record_is_covered_by_the_next_snapshot() {
        let bytes = vector();
        let v = Vector::parse(&bytes).unwrap();
        let mut board = v.board();
        v.load(0, &mut board);
        let mut out = [Interval::Unread(ErrorKind::NotReady); 1];
        board.snapshot().1.read_snapshot(&mut out);
        // Record 1 is never served: record 2 covers both periods, counts and time.
        v.load(2, &mut board);
        let latched = board.snapshot().1.read_snapshot(&mut out);
        assert_eq!(out[0], Interval::Counted(130));
        let ticks = (3 * TICKS_PER_PERIOD - TICKS_PER_PERIOD - 100) as f32;
        assert_eq!(latched, Some(ticks / TICK_HZ as f32));
    }
}
