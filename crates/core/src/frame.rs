//! The output frame: what the firmware sends over its serial link once per sample, and the one
//! decoder the host reads it with.
//!
//! A serial link loses bytes (a receiver overrun, a cable unplugged mid-frame) and a host may start
//! listening in the middle of a frame, so every frame starts with a sync word, carries a sequence
//! number (a gap says how many frames were lost) and ends with a CRC (a corrupt frame is dropped,
//! never half-used). The decoder is the core's sync-word [`Framer`] (shared with the update
//! protocol's frames): after any garbage or a failed CRC it searches for the next sync word from
//! the byte after the one it had taken for a frame start, so one corrupt frame costs at most that
//! frame. This module only says how long a frame is and what its bytes mean.
//!
//! # Layout (little-endian)
//!
//! ```text
//! offset    size  field
//! 0         2     sync word 0xEB 0x90 (the IRIG-106 PCM frame sync, sent in this byte order)
//! 2         1     format version (1)
//! 3         1     channel count K (1..=8)
//! 4         4     sequence number u32, +1 per frame sent, wrapping
//! 8         8     timestamp u64: ticks of the sample timer since boot (missed periods included)
//! 16        4     tick rate u32, Hz: the timestamp's unit (time = timestamp / tick rate seconds)
//! 20        10·K  per channel: value f64 (°/h or µg), status word u16 (see [`status`])
//! 20 + 10K  4     CRC-32 (the core's [`crc32`](crate::crc), ISO-HDLC) of bytes 2 .. 20 + 10K
//! ```
//!
//! A six-channel frame is 84 bytes: at 200 Hz, 16.8 kB/s, a fifth of a 921,600-baud UART.
//!
//! # Why CRC-32
//! It is the project's one checksum implementation (blobs and images use it), its Hamming distance of
//! 4 over frames of this length catches every 1–3 bit error and every burst up to 32 bits, and
//! computing it bitwise over 82 bytes is a few thousand cycles, well under 1 % of a 200 Hz period at
//! 168 MHz. A CRC-16 would save two bytes per frame and need a second implementation.
//!
//! # Why the value is an f64
//! The loop computes `raw − correction` in f32, whose resolution at high rates is coarser than the
//! sensor's: at 360,000 °/h one f32 step is 0.031 °/h, while an RLG's pulse count over a period is
//! exact. The firmware therefore forms the sent value in f64 from the exact count
//! (`counts · per_pulse / interval − correction`). Its error, with ε = 2⁻⁵³:
//!
//! * the raw rate, one multiplication and one division of exactly represented operands:
//!   ≤ 2ε·|raw| — 2.2·10⁻¹⁶ relative, 8·10⁻¹¹ °/h at 360,000 °/h;
//! * the subtraction: ≤ ε·|value|;
//! * the correction is the model's f32 output: its rounding (≤ 2⁻²⁴·|correction|, 6·10⁻⁶ °/h for a
//!   100 °/h correction) belongs to the model, not to the transport, and is far below sensor noise.
//!
//! So the frame keeps the sensor's resolution at any rate. Fixed point would need a range and a step
//! chosen per sensor; two f32 (raw, correction) would lose the raw's resolution before it is sent.
//!
//! NaN values are sent as the canonical quiet NaN `0x7FF8_0000_0000_0000` (the f64 widening of the
//! f32 `0x7FC0_0000`), whatever NaN the arithmetic produced, so host and ARM frames are bit-identical.

use crate::crc::crc32;
use crate::framer::{Framer, Framing};

mod boot;
pub use boot::{
    BOOT_CHANNEL_LEN, BOOT_HEADER_LEN, BOOT_REPORT_PERIOD_S, BOOT_VERSION, BootReport,
    ChannelState, DEVELOPMENT, WATCHDOG, boot_len, image_state, update_state,
};

/// The two bytes every frame starts with.
pub const SYNC: [u8; 2] = [0xEB, 0x90];
/// The frame format version.
pub const VERSION: u8 = 1;
/// Most channels in one frame.
pub const MAX_CHANNELS: usize = 8;
/// Bytes before the channels.
pub const HEADER_LEN: usize = 20;
/// Bytes per channel: value f64, status u16.
pub const CHANNEL_LEN: usize = 10;
/// Bytes of the CRC.
pub const CRC_LEN: usize = 4;
/// Length of the longest frame.
pub const MAX_FRAME_LEN: usize = frame_len(MAX_CHANNELS);
/// The canonical NaN every NaN value is sent as.
pub const CANONICAL_NAN_BITS: u64 = 0x7FF8_0000_0000_0000;

/// Length of a frame of `channels` channels.
pub const fn frame_len(channels: usize) -> usize {
    HEADER_LEN + CHANNEL_LEN * channels + CRC_LEN
}

/// The bits of the output status word, and their names (one table for the firmware and the host).
pub mod status {
    use crate::compensator::Status;

    /// Model present, inputs good and in range.
    pub const OK: u16 = 0;
    /// No valid model: raw passed through (core bit).
    pub const NO_MODEL: u16 = Status::NO_MODEL.0 as u16;
    /// A feature outside its trained range, clamped (core bit).
    pub const OUT_OF_RANGE: u16 = Status::OUT_OF_RANGE.0 as u16;
    /// A NaN/infinite input or raw value: last good features held (core bit).
    pub const INPUT_FAULT: u16 = Status::INPUT_FAULT.0 as u16;
    /// A thermometer or counter read of this channel returned an error, or the counter flagged the
    /// interval (loop bit).
    pub const SENSOR_ERROR: u16 = 8;
    /// A thermometer of this channel has returned identical readings for too long (loop bit).
    pub const STUCK: u16 = 16;
    /// The model's correction was not finite: raw passed through (core bit).
    pub const MODEL_FAULT: u16 = Status::MODEL_FAULT.0 as u16;
    /// A thermometer of this channel moved faster than the instrument's thermal time constant
    /// allows: the reading is refused like a failed one (loop bit).
    pub const TEMP_JUMP: u16 = 1 << 6;
    /// The sample's latched timestamp is not one period (plus any missed periods) after the last
    /// one: the time base jumped (loop bit, on every channel of the frame).
    pub const TIME_JUMP: u16 = 1 << 7;
    /// The sample task overran its period: this sample was late (board bit, on every channel of the
    /// frame). Board bits are taken from bit 15 down, the core's and the loop's from bit 0 up.
    pub const OVERRUN: u16 = 1 << 15;
    /// The board booted after a watchdog reset: set on the first frame after that boot (board bit).
    pub const WATCHDOG_RESET: u16 = 1 << 14;
    /// The first frame after a boot (board bit): the feature filters start from nothing, and its
    /// counts cover the interval since the counters were last read, not one known period.
    pub const FIRST_SAMPLE: u16 = 1 << 13;
    /// Every named bit with its name, lowest bit first.
    pub const NAMES: [(u16, &str); 11] = [
        (NO_MODEL, "no-model"),
        (OUT_OF_RANGE, "out-of-range"),
        (INPUT_FAULT, "input-fault"),
        (SENSOR_ERROR, "sensor-error"),
        (STUCK, "stuck"),
        (MODEL_FAULT, "model-fault"),
        (TEMP_JUMP, "temperature-jump"),
        (TIME_JUMP, "time-jump"),
        (FIRST_SAMPLE, "first-sample"),
        (WATCHDOG_RESET, "watchdog-reset"),
        (OVERRUN, "overrun"),
    ];

    /// Calls `f` with the name of every set bit, lowest first; a bit without a name is `"bit<n>"`
    /// passed as its index (`Err(n)`), so no information is dropped.
    pub fn for_each_name(word: u16, mut f: impl FnMut(Result<&'static str, u32>)) {
        for bit in 0..16u32 {
            let mask = 1u16 << bit;
            if word & mask == 0 {
                continue;
            }
            match NAMES.iter().find(|(m, _)| *m == mask) {
                Some((_, name)) => f(Ok(name)),
                None => f(Err(bit)),
            }
        }
    }
}

/// Why a frame cannot be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FrameError {
    /// No channel, or more than [`MAX_CHANNELS`].
    ChannelCount,
    /// The output buffer is shorter than [`frame_len`].
    BufferTooSmall,
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::ChannelCount => write!(f, "a frame has 1 to {MAX_CHANNELS} channels"),
            Self::BufferTooSmall => f.write_str("output buffer too small for the frame"),
        }
    }
}

impl core::error::Error for FrameError {}

/// One channel's output in a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ChannelOutput {
    /// Compensated rate (°/h) or acceleration (µg).
    pub value: f64,
    /// Status word ([`status`]).
    pub status: u16,
}

/// One frame's content.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Sequence number.
    pub sequence: u32,
    /// Sample-timer ticks since boot.
    pub timestamp: u64,
    /// Tick rate of the timestamp, Hz.
    pub tick_hz: u32,
    channels: [ChannelOutput; MAX_CHANNELS],
    count: u8,
}

impl Frame {
    /// A frame of the first [`MAX_CHANNELS`] of `channels`.
    pub fn new(sequence: u32, timestamp: u64, tick_hz: u32, channels: &[ChannelOutput]) -> Self {
        let mut all = [ChannelOutput::default(); MAX_CHANNELS];
        let mut count = 0u8;
        for (slot, c) in all.iter_mut().zip(channels) {
            *slot = *c;
            count += 1;
        }
        Self {
            sequence,
            timestamp,
            tick_hz,
            channels: all,
            count,
        }
    }

    /// The channels.
    pub fn channels(&self) -> &[ChannelOutput] {
        self.channels.get(..usize::from(self.count)).unwrap_or(&[])
    }

    /// The timestamp in seconds (NaN without a tick rate).
    pub fn time_s(&self) -> f64 {
        if self.tick_hz == 0 {
            f64::NAN
        } else {
            self.timestamp as f64 / f64::from(self.tick_hz)
        }
    }

    /// Length of this frame on the wire.
    pub fn len(&self) -> usize {
        frame_len(usize::from(self.count))
    }

    /// True for a frame without channels (which cannot be encoded).
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Writes the frame into the start of `out`; returns its length.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, FrameError> {
        let k = usize::from(self.count);
        if k == 0 || k > MAX_CHANNELS {
            return Err(FrameError::ChannelCount);
        }
        let len = frame_len(k);
        let out = out.get_mut(..len).ok_or(FrameError::BufferTooSmall)?;
        let mut w = Writer { buf: out, at: 0 };
        w.put(&SYNC);
        w.put(&[VERSION, self.count]);
        w.put(&self.sequence.to_le_bytes());
        w.put(&self.timestamp.to_le_bytes());
        w.put(&self.tick_hz.to_le_bytes());
        for c in self.channels() {
            let bits = if c.value.is_nan() {
                CANONICAL_NAN_BITS
            } else {
                c.value.to_bits()
            };
            w.put(&bits.to_le_bytes());
            w.put(&c.status.to_le_bytes());
        }
        let crc = crc32(w.buf.get(SYNC.len()..w.at).unwrap_or(&[]));
        w.put(&crc.to_le_bytes());
        Ok(len)
    }

    /// Reads a frame whose sync word, version, channel count, length and CRC the framer checked.
    fn parse(bytes: &[u8]) -> Option<Self> {
        let k = usize::from(*bytes.get(3)?);
        let mut channels = [ChannelOutput::default(); MAX_CHANNELS];
        for (i, c) in channels.iter_mut().enumerate().take(k) {
            let at = HEADER_LEN + CHANNEL_LEN * i;
            *c = ChannelOutput {
                value: f64::from_bits(le_u64(bytes, at)?),
                status: u16::from_le_bytes([*bytes.get(at + 8)?, *bytes.get(at + 9)?]),
            };
        }
        Some(Self {
            sequence: le_u32(bytes, 4)?,
            timestamp: le_u64(bytes, 8)?,
            tick_hz: le_u32(bytes, 16)?,
            channels,
            count: u8::try_from(k).ok()?,
        })
    }
}

struct Writer<'a> {
    buf: &'a mut [u8],
    at: usize,
}

impl Writer<'_> {
    fn put(&mut self, bytes: &[u8]) {
        if let Some(dst) = self.buf.get_mut(self.at..self.at + bytes.len()) {
            dst.copy_from_slice(bytes);
        }
        self.at += bytes.len();
    }
}

fn le_u32(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

fn le_u64(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// What the decoder has seen so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Frames decoded.
    pub frames: u64,
    /// Frames missing by sequence gaps between decoded frames.
    pub lost: u64,
    /// Candidate frames (sync and a valid header) whose CRC failed.
    pub corrupt: u64,
    /// Bytes dropped while searching for a sync word (garbage, and the bytes of corrupt frames).
    pub skipped: u64,
    /// Sequence jumps backwards (or forwards by more than 2³¹): the sender restarted.
    pub restarts: u64,
}

/// The output link's framing: data frames and boot reports share the sync word and are told apart
/// by their version byte, which with the channel count gives the length.
#[derive(Clone, Copy, Debug, Default)]
struct Output;

impl Framing for Output {
    const SYNC: &'static [u8] = &SYNC;
    /// Sync word, version, channel count.
    const HEADER_LEN: usize = 4;

    fn frame_len(header: &[u8]) -> Option<usize> {
        let k = usize::from(*header.get(3)?);
        match *header.get(2)? {
            BOOT_VERSION if k <= MAX_CHANNELS => Some(boot_len(k)),
            VERSION if (1..=MAX_CHANNELS).contains(&k) => Some(frame_len(k)),
            _ => None,
        }
    }
}

/// Streaming decoder: feed it bytes as they arrive, in any chunks.
#[derive(Clone, Debug)]
pub struct Decoder {
    framer: Framer<Output, MAX_FRAME_LEN>,
    next_sequence: Option<u32>,
    frames: u64,
    lost: u64,
    restarts: u64,
    boot_reports: u64,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

/// One decoded item of the stream: a data frame or a boot report ([`BootReport`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Item {
    /// A data frame.
    Data(Frame),
    /// A boot report.
    Boot(BootReport),
}

/// The item of a frame the framer checked ([`Output::frame_len`] and the CRC): cannot fail.
fn parse(bytes: &[u8]) -> Option<Item> {
    if bytes.get(2) == Some(&BOOT_VERSION) {
        BootReport::parse(bytes).map(Item::Boot)
    } else {
        Frame::parse(bytes).map(Item::Data)
    }
}

impl Decoder {
    /// A decoder that has seen nothing.
    pub const fn new() -> Self {
        Self {
            framer: Framer::new(),
            next_sequence: None,
            frames: 0,
            lost: 0,
            restarts: 0,
            boot_reports: 0,
        }
    }

    /// Boot reports decoded so far (not counted in [`Stats`], which describes the data frames).
    pub const fn boot_reports(&self) -> u64 {
        self.boot_reports
    }

    /// Feeds `bytes`, calling `on_item` for every good data frame and boot report completed by
    /// them, in order.
    pub fn feed_items(&mut self, bytes: &[u8], mut on_item: impl FnMut(Item)) {
        for &b in bytes {
            let mut item = self.push_item(b);
            while let Some(i) = item {
                on_item(i);
                item = self.poll_item();
            }
        }
    }

    /// Counters so far.
    pub const fn stats(&self) -> Stats {
        Stats {
            frames: self.frames,
            lost: self.lost,
            corrupt: self.framer.corrupt(),
            skipped: self.framer.skipped(),
            restarts: self.restarts,
        }
    }

    /// Feeds `bytes`, calling `on_frame` for every good frame completed by them, in order.
    pub fn feed(&mut self, bytes: &[u8], mut on_frame: impl FnMut(Frame)) {
        for &b in bytes {
            if let Some(f) = self.push(b) {
                on_frame(f);
                while let Some(f) = self.poll() {
                    on_frame(f);
                }
            }
        }
    }

    /// Feeds one byte; returns a frame if one is complete. If it returns a frame, call
    /// [`poll`](Self::poll) until `None` before the next byte (a resynchronisation can leave a
    /// second complete frame in the buffer); [`feed`](Self::feed) does both.
    pub fn push(&mut self, byte: u8) -> Option<Frame> {
        match self.push_item(byte)? {
            Item::Data(f) => Some(f),
            Item::Boot(_) => self.poll(),
        }
    }

    /// Looks for a complete data frame in the bytes already fed (boot reports on the way are
    /// counted and dropped; [`Decoder::feed_items`] hands them out).
    pub fn poll(&mut self) -> Option<Frame> {
        loop {
            match self.poll_item()? {
                Item::Data(f) => return Some(f),
                Item::Boot(_) => {}
            }
        }
    }

    /// Feeds one byte; returns the data frame or boot report it completes, counted.
    fn push_item(&mut self, byte: u8) -> Option<Item> {
        let item = self.framer.push(byte).and_then(parse)?;
        Some(self.counted(item))
    }

    /// Looks for a complete data frame or boot report in the bytes already fed, counted.
    fn poll_item(&mut self) -> Option<Item> {
        let item = self.framer.poll().and_then(parse)?;
        Some(self.counted(item))
    }

    fn counted(&mut self, item: Item) -> Item {
        match item {
            Item::Data(f) => self.count(f.sequence),
            Item::Boot(_) => self.boot_reports += 1,
        }
        item
    }

    fn count(&mut self, sequence: u32) {
        self.frames += 1;
        if let Some(expected) = self.next_sequence {
            let gap = sequence.wrapping_sub(expected);
            if gap <= i32::MAX as u32 {
                self.lost += u64::from(gap);
            } else {
                self.restarts += 1;
            }
        }
        self.next_sequence = Some(sequence.wrapping_add(1));
    }
}
