//! Up/down pulse-counter block in an FPGA/CPLD, for RLG and QMA pulse outputs.
//!
//! Why a counter block rather than MCU timers: an IMU has six or more pulse channels (three RLGs, three
//! QMAs with I/F converters), each an *up* and a *down* pulse line; the navigation solution wants all
//! of them sampled **at the same instant**, and a few MHz of RLG pulses must not depend on the MCU
//! servicing anything. A small block of logic counts every channel in hardware and copies all of them
//! into snapshot registers on one command; the MCU reads the snapshot at leisure.
//!
//! # Register map (defined here; the HDL implements this)
//!
//! SPI mode 0 (CPOL = 0, CPHA = 0), MSB first, 8-bit command bytes, registers 32 bits big-endian.
//! Within one chip-select frame the device takes command bytes until a READ; after a READ it shifts
//! out registers `addr, addr + 1, …` (auto-increment, 4 bytes each) for as long as the frame lasts,
//! ignoring what the controller sends.
//!
//! | command  | byte          | effect                                                                  |
//! |----------|---------------|-------------------------------------------------------------------------|
//! | LATCH    | `0x01`        | on the 8th SCLK edge, copy every live counter, the timestamp and the status event flags into the snapshot registers, on one clock edge of the counter clock; then clear the event flags |
//! | READ     | `0x80 \| addr` | shift out registers from `addr` (7-bit) upwards                         |
//!
//! Other command bytes are ignored. One frame `[LATCH, READ | STATUS]` + 4·(2 + N) bytes therefore
//! takes and reads a complete, coherent snapshot — one SPI transaction per loop sample.
//!
//! | addr        | name       | content                                                                 |
//! |-------------|------------|-------------------------------------------------------------------------|
//! | `0x00`      | ID         | `0x5544_4301`: ASCII "UDC" and register-map version 1                  |
//! | `0x01`      | INFO       | \[7:0\] number of channels (1…8) · \[15:8\] counter width in bits (32) · \[31:16\] timestamp clock in kHz |
//! | `0x02`      | STATUS     | snapshot of the event flags since the previous LATCH: \[7:0\] LOST\[ch\] pulses lost (up and down edges in one counter-clock cycle, or input faster than the synchroniser) · \[15:8\] FAULT\[ch\] the instrument's fault/valid line was asserted (RLG path-length control or dither out of lock, QMA rebalance loop saturated) · \[30:16\] reserved, 0 · \[31\] CLOCK_FAULT counter reference clock missing or PLL unlocked |
//! | `0x03`      | TIMESTAMP  | snapshot of a free-running counter of the timestamp clock                |
//! | `0x04 + ch` | COUNT\[ch\]| snapshot of channel `ch`'s free-running up/down counter: +1 per up pulse, −1 per down pulse, wrapping modulo 2³² |
//!
//! # What the driver does with it
//! The counters are never reset: the driver keeps, per channel, the count and timestamp it last
//! *consumed*, and the delta is the wrapping difference ([`wrapping_delta`]) — exact across the
//! 2³² wrap in both directions. Event flags are accumulated per channel until that channel is
//! consumed, so reading channels one at a time (the [`PulseCounter`] handles of
//! [`CounterBlock::channel`]) loses neither pulses nor faults; [`CounterBlock::sample`] (and the
//! [`CounterSnapshot`] impl over it) consumes all channels of one snapshot at once and is what a
//! fixed-rate loop should call.
//!
//! An interval with a flag set is still *consumed* (its pulses are returned, marked invalid), so the
//! next interval starts clean; an interval whose read failed on the bus is not, so the next
//! successful read covers it. The loop must tell the two apart (dividing the next interval's pulses by
//! two periods after a flagged one would halve the rate): [`CounterSnapshot::read_snapshot`] says it
//! with [`Interval::Flagged`] / [`Interval::Unread`], and a [`PulseCounter`] handle's error kinds say
//! the same ([`ErrorKind::Overflow`] and [`ErrorKind::Fault`] consumed, [`ErrorKind::Bus`] not; see
//! [`Interval::from_result`]). The snapshot also returns the interval's length from the timestamp
//! latched on the same edge as the counts, so the loop divides by the time that really elapsed
//! rather than the nominal period.

use core::fmt;

use embedded_hal::spi::{Operation, SpiDevice};

use crate::counter::{CounterSnapshot, Interval, PulseCounter, wrapping_delta};
use crate::error::{self, ErrorKind, ErrorType};

/// Command bytes.
pub mod cmd {
    /// Snapshot all counters, the timestamp and the event flags.
    pub const LATCH: u8 = 0x01;
    /// Read registers from `READ | addr` upwards.
    pub const READ: u8 = 0x80;
}

/// Register addresses.
pub mod reg {
    /// Identification, [`ID_VALUE`](super::ID_VALUE).
    pub const ID: u8 = 0x00;
    /// Channel count, counter width, timestamp clock.
    pub const INFO: u8 = 0x01;
    /// Event flags of the snapshot.
    pub const STATUS: u8 = 0x02;
    /// Timestamp of the snapshot.
    pub const TIMESTAMP: u8 = 0x03;
    /// Count of channel 0; channel `ch` is at `COUNT0 + ch`.
    pub const COUNT0: u8 = 0x04;
}

/// STATUS register bits.
pub mod status {
    /// LOST\[ch\] is bit `LOST_SHIFT + ch`.
    pub const LOST_SHIFT: u32 = 0;
    /// FAULT\[ch\] is bit `FAULT_SHIFT + ch`.
    pub const FAULT_SHIFT: u32 = 8;
    /// Counter reference clock missing or PLL unlocked.
    pub const CLOCK_FAULT: u32 = 1 << 31;
}

/// Content of the ID register: "UDC", version 1.
pub const ID_VALUE: u32 = 0x5544_4301;
/// Most channels one block has.
pub const MAX_CHANNELS: usize = 8;
/// Counter width this driver supports.
pub const COUNTER_BITS: u8 = 32;

/// Bytes of the largest snapshot read: STATUS, TIMESTAMP and [`MAX_CHANNELS`] counts.
const SNAPSHOT_BYTES_MAX: usize = 4 * (2 + MAX_CHANNELS);

/// Decoded INFO register.
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Info {
    /// Number of channels the block has.
    pub channels: u8,
    /// Width of the counters in bits.
    pub counter_bits: u8,
    /// Frequency of the timestamp clock, kHz.
    pub timestamp_khz: u16,
}

impl Info {
    /// Decode the register.
    pub const fn from_register(value: u32) -> Self {
        let [khz_hi, khz_lo, bits, channels] = value.to_be_bytes();
        Self {
            channels,
            counter_bits: bits,
            timestamp_khz: u16::from_be_bytes([khz_hi, khz_lo]),
        }
    }

    /// Encode the register (for simulators and tests).
    pub const fn to_register(&self) -> u32 {
        let [khz_hi, khz_lo] = self.timestamp_khz.to_be_bytes();
        u32::from_be_bytes([khz_hi, khz_lo, self.counter_bits, self.channels])
    }

    /// Timestamp clock, Hz.
    pub const fn timestamp_hz(&self) -> u32 {
        self.timestamp_khz as u32 * 1000
    }
}

/// Event flags of one channel over one consumed interval.
#[derive(Debug, Copy, Clone, Eq, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelFlags {
    /// Pulses were lost (LOST).
    pub pulses_lost: bool,
    /// The instrument signalled a fault (FAULT).
    pub sensor_fault: bool,
    /// The counter's clock failed (CLOCK_FAULT).
    pub clock_fault: bool,
}

impl ChannelFlags {
    fn from_status(status: u32, channel: usize) -> Self {
        let bit = |shift: u32| {
            u32::try_from(channel)
                .ok()
                .and_then(|c| status.checked_shr(shift + c))
                .is_some_and(|s| s & 1 == 1)
        };
        Self {
            pulses_lost: bit(status::LOST_SHIFT),
            sensor_fault: bit(status::FAULT_SHIFT),
            clock_fault: status & status::CLOCK_FAULT != 0,
        }
    }

    fn merge(&mut self, other: Self) {
        self.pulses_lost |= other.pulses_lost;
        self.sensor_fault |= other.sensor_fault;
        self.clock_fault |= other.clock_fault;
    }

    /// `Ok` if no flag is set; otherwise the most serious, as an [`ErrorKind`]: a clock or sensor
    /// fault is [`ErrorKind::Fault`], lost pulses [`ErrorKind::Overflow`].
    pub const fn check(&self) -> Result<(), ErrorKind> {
        if self.clock_fault || self.sensor_fault {
            Err(ErrorKind::Fault)
        } else if self.pulses_lost {
            Err(ErrorKind::Overflow)
        } else {
            Ok(())
        }
    }
}

/// One channel's share of a snapshot.
#[derive(Debug, Copy, Clone, Eq, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelReading {
    /// Pulses since the channel was last consumed (up positive).
    pub delta: i32,
    /// Timestamp-clock ticks over the same interval.
    pub ticks: u32,
    /// Events over the same interval.
    pub flags: ChannelFlags,
}

impl ChannelReading {
    /// The delta if no flag is set, else the flag's [`ErrorKind`].
    pub const fn valid_delta(&self) -> Result<i32, ErrorKind> {
        match self.flags.check() {
            Ok(()) => Ok(self.delta),
            Err(e) => Err(e),
        }
    }
}

/// All channels of one snapshot.
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
pub struct Sample<const N: usize> {
    /// Per channel.
    pub channels: [ChannelReading; N],
    /// Timestamp clock (Hz), to turn `ticks` into seconds.
    pub timestamp_hz: u32,
}

impl<const N: usize> Sample<N> {
    /// Channel `ch`, if it exists.
    pub fn channel(&self, ch: usize) -> Option<&ChannelReading> {
        self.channels.get(ch)
    }

    /// Length of channel `ch`'s interval, seconds (`None` for a missing channel).
    pub fn interval_s(&self, ch: usize) -> Option<f32> {
        let reading = self.channels.get(ch)?;
        if self.timestamp_hz == 0 {
            return None;
        }
        Some(reading.ticks as f32 / self.timestamp_hz as f32)
    }
}

/// Counter-block driver error.
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
pub enum Error<E> {
    /// The SPI transfer failed.
    Spi(E),
    /// The ID register did not read [`ID_VALUE`].
    WrongId {
        /// What it read.
        id: u32,
    },
    /// INFO shows fewer channels than the driver was built for, another counter width, or no
    /// timestamp clock.
    Unsupported {
        /// The INFO register.
        info: u32,
    },
    /// Read before a successful [`CounterBlock::init`].
    NotInitialised,
    /// No such channel.
    NoSuchChannel,
    /// Pulses were lost on the channel during the interval.
    PulsesLost,
    /// The instrument signalled a fault during the interval.
    SensorFault,
    /// The counter clock failed during the interval.
    ClockFault,
}

impl<E> Error<E> {
    fn from_flags(flags: ChannelFlags) -> Option<Self> {
        if flags.clock_fault {
            Some(Self::ClockFault)
        } else if flags.sensor_fault {
            Some(Self::SensorFault)
        } else if flags.pulses_lost {
            Some(Self::PulsesLost)
        } else {
            None
        }
    }
}

impl<E: fmt::Debug> error::Error for Error<E> {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::Spi(_) => ErrorKind::Bus,
            Self::WrongId { .. } | Self::Unsupported { .. } => ErrorKind::WrongDevice,
            Self::NotInitialised => ErrorKind::NotReady,
            Self::NoSuchChannel => ErrorKind::InvalidConfig,
            Self::PulsesLost => ErrorKind::Overflow,
            Self::SensorFault | Self::ClockFault => ErrorKind::Fault,
        }
    }
}

impl<E: fmt::Debug> fmt::Display for Error<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Spi(e) => write!(f, "counter block: SPI error {e:?}"),
            Self::WrongId { id } => {
                write!(f, "counter block: ID {id:#010x}, expected {ID_VALUE:#010x}")
            }
            Self::Unsupported { info } => write!(f, "counter block: unsupported INFO {info:#010x}"),
            Self::NotInitialised => f.write_str("counter block: not initialised"),
            Self::NoSuchChannel => f.write_str("counter block: no such channel"),
            Self::PulsesLost => f.write_str("counter block: pulses lost"),
            Self::SensorFault => f.write_str("counter block: instrument fault"),
            Self::ClockFault => f.write_str("counter block: counter clock fault"),
        }
    }
}

impl<E: fmt::Debug> core::error::Error for Error<E> {}

/// A raw snapshot: status, timestamp, counts.
struct Snapshot<const N: usize> {
    status: u32,
    timestamp: u32,
    counts: [u32; N],
}

/// Word `index` (big-endian u32) of `buf`, if there.
fn be32(buf: &[u8], index: usize) -> Option<u32> {
    let start = index.checked_mul(4)?;
    let bytes: [u8; 4] = buf.get(start..start.checked_add(4)?)?.try_into().ok()?;
    Some(u32::from_be_bytes(bytes))
}

/// Driver for a counter block with `N` channels used (1…[`MAX_CHANNELS`]).
#[derive(Debug)]
pub struct CounterBlock<SPI, const N: usize> {
    spi: SPI,
    consumed: [u32; N],
    consumed_ts: [u32; N],
    pending: [ChannelFlags; N],
    timestamp_hz: u32,
    ready: bool,
}

impl<SPI: SpiDevice, const N: usize> CounterBlock<SPI, N> {
    /// Wrap the device; no bus traffic until [`init`](Self::init).
    pub const fn new(spi: SPI) -> Self {
        const { assert!(N > 0 && N <= MAX_CHANNELS, "1..=8 channels") };
        Self {
            spi,
            consumed: [0; N],
            consumed_ts: [0; N],
            pending: [ChannelFlags {
                pulses_lost: false,
                sensor_fault: false,
                clock_fault: false,
            }; N],
            timestamp_hz: 0,
            ready: false,
        }
    }

    /// Give the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }

    /// Check ID and INFO, then take a baseline snapshot (its counts and flags are discarded, so the
    /// first reading covers the time since `init`).
    pub fn init(&mut self) -> Result<Info, Error<SPI::Error>> {
        self.ready = false;
        let mut buf = [0u8; 8];
        self.spi
            .transaction(&mut [
                Operation::Write(&[cmd::READ | reg::ID]),
                Operation::Read(&mut buf),
            ])
            .map_err(Error::Spi)?;
        // `be32` cannot fail on these fixed-size buffers; the `?` keeps the code free of panics.
        let id = be32(&buf, 0).ok_or(Error::NoSuchChannel)?;
        let raw_info = be32(&buf, 1).ok_or(Error::NoSuchChannel)?;
        if id != ID_VALUE {
            return Err(Error::WrongId { id });
        }
        let info = Info::from_register(raw_info);
        if usize::from(info.channels) < N
            || usize::from(info.channels) > MAX_CHANNELS
            || info.counter_bits != COUNTER_BITS
            || info.timestamp_khz == 0
        {
            return Err(Error::Unsupported { info: raw_info });
        }
        let snap = self.latch()?;
        self.consumed = snap.counts;
        self.consumed_ts = [snap.timestamp; N];
        self.pending = [ChannelFlags::default(); N];
        self.timestamp_hz = info.timestamp_hz();
        self.ready = true;
        Ok(info)
    }

    /// Latch and read a snapshot; accumulate its flags into every channel's pending flags.
    fn latch(&mut self) -> Result<Snapshot<N>, Error<SPI::Error>> {
        let mut buf = [0u8; SNAPSHOT_BYTES_MAX];
        let len = 4 * (2 + N);
        let data = buf.get_mut(..len).ok_or(Error::NoSuchChannel)?;
        self.spi
            .transaction(&mut [
                Operation::Write(&[cmd::LATCH, cmd::READ | reg::STATUS]),
                Operation::Read(data),
            ])
            .map_err(Error::Spi)?;
        let status = be32(&buf, 0).ok_or(Error::NoSuchChannel)?;
        let timestamp = be32(&buf, 1).ok_or(Error::NoSuchChannel)?;
        let mut counts = [0u32; N];
        for (i, count) in counts.iter_mut().enumerate() {
            *count = be32(&buf, 2 + i).ok_or(Error::NoSuchChannel)?;
        }
        for (i, pending) in self.pending.iter_mut().enumerate() {
            pending.merge(ChannelFlags::from_status(status, i));
        }
        Ok(Snapshot {
            status,
            timestamp,
            counts,
        })
    }

    /// Take one snapshot and consume every channel: what a fixed-rate loop calls once per sample.
    ///
    /// `Err` only for the bus or a missing `init`; per-channel faults are in each
    /// [`ChannelReading::flags`] (see [`ChannelReading::valid_delta`]), so one faulty instrument
    /// does not hide the others.
    pub fn sample(&mut self) -> Result<Sample<N>, Error<SPI::Error>> {
        if !self.ready {
            return Err(Error::NotInitialised);
        }
        let snap = self.latch()?;
        let mut channels = [ChannelReading::default(); N];
        let iter = channels
            .iter_mut()
            .zip(snap.counts.iter())
            .zip(self.consumed.iter_mut())
            .zip(self.consumed_ts.iter_mut())
            .zip(self.pending.iter_mut());
        for ((((reading, &now), consumed), consumed_ts), pending) in iter {
            *reading = ChannelReading {
                delta: wrapping_delta(*consumed, now, u32::from(COUNTER_BITS)),
                ticks: snap.timestamp.wrapping_sub(*consumed_ts),
                flags: *pending,
            };
            *consumed = now;
            *consumed_ts = snap.timestamp;
            *pending = ChannelFlags::default();
        }
        Ok(Sample {
            channels,
            timestamp_hz: self.timestamp_hz,
        })
    }

    /// Take one snapshot and consume channel `ch` only; the other channels keep accumulating.
    pub fn read_channel(&mut self, ch: usize) -> Result<ChannelReading, Error<SPI::Error>> {
        if !self.ready {
            return Err(Error::NotInitialised);
        }
        if ch >= N {
            return Err(Error::NoSuchChannel);
        }
        let snap = self.latch()?;
        let now = *snap.counts.get(ch).ok_or(Error::NoSuchChannel)?;
        let consumed = self.consumed.get_mut(ch).ok_or(Error::NoSuchChannel)?;
        let consumed_ts = self.consumed_ts.get_mut(ch).ok_or(Error::NoSuchChannel)?;
        let pending = self.pending.get_mut(ch).ok_or(Error::NoSuchChannel)?;
        let reading = ChannelReading {
            delta: wrapping_delta(*consumed, now, u32::from(COUNTER_BITS)),
            ticks: snap.timestamp.wrapping_sub(*consumed_ts),
            flags: *pending,
        };
        *consumed = now;
        *consumed_ts = snap.timestamp;
        *pending = ChannelFlags::default();
        Ok(reading)
    }

    /// A [`PulseCounter`] for channel `ch` (`None` if `ch ≥ N`).
    pub fn channel(&mut self, ch: usize) -> Option<Channel<'_, SPI, N>> {
        (ch < N).then_some(Channel {
            block: self,
            index: ch,
        })
    }

    /// Timestamp clock (Hz) read from INFO at `init` (0 before).
    pub const fn timestamp_hz(&self) -> u32 {
        self.timestamp_hz
    }

    /// Raw STATUS of a fresh snapshot, for diagnostics. The snapshot's flags are accumulated as by
    /// any other read, its counts are not consumed.
    pub fn read_status(&mut self) -> Result<u32, Error<SPI::Error>> {
        self.latch().map(|s| s.status)
    }
}

/// One channel of a [`CounterBlock`], as a [`PulseCounter`].
///
/// Each `read_delta` takes a full snapshot of the block; prefer [`CounterBlock::sample`] when all
/// channels are read at the same rate.
#[derive(Debug)]
pub struct Channel<'a, SPI, const N: usize> {
    block: &'a mut CounterBlock<SPI, N>,
    index: usize,
}

impl<SPI: SpiDevice, const N: usize> ErrorType for Channel<'_, SPI, N> {
    type Error = Error<SPI::Error>;
}

impl<SPI: SpiDevice, const N: usize> PulseCounter for Channel<'_, SPI, N> {
    fn read_delta(&mut self) -> Result<i32, Self::Error> {
        let reading = self.block.read_channel(self.index)?;
        match Error::from_flags(reading.flags) {
            Some(e) => Err(e),
            None => Ok(reading.delta),
        }
    }
}

/// The block as one latched snapshot per call: what a fixed-rate loop reads.
impl<SPI: SpiDevice, const N: usize> CounterSnapshot for CounterBlock<SPI, N> {
    fn read_snapshot(&mut self, out: &mut [Interval]) -> Option<f32> {
        match self.sample() {
            Ok(sample) => {
                for (o, reading) in out.iter_mut().zip(sample.channels.iter()) {
                    *o = match reading.flags.check() {
                        Ok(()) => Interval::Counted(reading.delta),
                        Err(kind) => Interval::Flagged(kind),
                    };
                }
                // One interval for the snapshot only if every channel was last consumed at the
                // same instant (always so when the block is read by snapshots only).
                let first = sample.channels.first()?.ticks;
                if sample.channels.iter().all(|r| r.ticks == first) {
                    sample.interval_s(0)
                } else {
                    None
                }
            }
            Err(e) => {
                let kind = error::Error::kind(&e);
                for o in out.iter_mut().take(N) {
                    *o = Interval::Unread(kind);
                }
                None
            }
        }
    }
}

impl<SPI: SpiDevice> ErrorType for CounterBlock<SPI, 1> {
    type Error = Error<SPI::Error>;
}

/// A single-channel block is itself a [`PulseCounter`].
impl<SPI: SpiDevice> PulseCounter for CounterBlock<SPI, 1> {
    fn read_delta(&mut self) -> Result<i32, Self::Error> {
        let reading = self.read_channel(0)?;
        match Error::from_flags(reading.flags) {
            Some(e) => Err(e),
            None => Ok(reading.delta),
        }
    }
}
