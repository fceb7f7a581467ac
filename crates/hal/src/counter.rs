//! The pulse counter trait, and the wrap-around-safe difference it relies on.
//!
//! Ring laser gyros and quartz accelerometers with current-to-frequency converters output *pulses*:
//! each one is a fixed increment of angle or of velocity, on an "up" line for one sign and a "down"
//! line for the other. Counter hardware accumulates them in a free-running N-bit up/down register
//! that wraps around; what the loop needs is the *signed number of pulses since its previous read*.
//! That number is the difference of two successive register values taken modulo 2^N and reinterpreted
//! as a signed N-bit value ([`wrapping_delta`]), which is exact as long as fewer than 2^(N−1) pulses
//! arrive between reads (for a 32-bit counter and a 200 Hz loop: 4·10¹¹ pulses/s, never reached).

use crate::error::{Error, ErrorKind, ErrorType};

/// One up/down pulse channel.
///
/// A replay board can keep the recorded raw register values and let [`wrapping_delta`] do the
/// rest, so recorded wrap-arounds are exercised exactly as on hardware:
///
/// ```
/// use tcomp_hal::{ErrorKind, ErrorType, PulseCounter, wrapping_delta};
///
/// struct Replay<'a> {
///     raw: &'a [u32],
///     next: usize,
///     last: u32,
/// }
/// impl ErrorType for Replay<'_> {
///     type Error = ErrorKind;
/// }
/// impl PulseCounter for Replay<'_> {
///     fn read_delta(&mut self) -> Result<i32, ErrorKind> {
///         let now = *self.raw.get(self.next).ok_or(ErrorKind::NotReady)?;
///         self.next += 1;
///         let delta = wrapping_delta(self.last, now, 32);
///         self.last = now;
///         Ok(delta)
///     }
/// }
///
/// let mut c = Replay { raw: &[0xFFFF_FFFE, 3], next: 0, last: 0xFFFF_FFF0 };
/// assert_eq!(c.read_delta(), Ok(14));
/// assert_eq!(c.read_delta(), Ok(5)); // across the 2³² wrap
/// ```
pub trait PulseCounter: ErrorType {
    /// Signed number of pulses since the previous call (up pulses positive, down pulses negative).
    ///
    /// The first call after initialisation returns the pulses since initialisation.
    ///
    /// What an error means for the interval depends on its [`kind`](crate::Error::kind) (see
    /// [`Interval::from_result`]): [`ErrorKind::Overflow`] and [`ErrorKind::Fault`] say the interval
    /// *was consumed* but its pulses are not valid (lost pulses, an instrument or clock fault), so the
    /// next call covers the next interval only; any other kind (a bus error, …) says nothing was
    /// consumed, the pulses are still in the counter and the next successful call returns everything
    /// since the last successful one.
    fn read_delta(&mut self) -> Result<i32, Self::Error>;
}

/// What one counter channel says about one loop period.
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Interval {
    /// Valid pulses since the channel was last consumed.
    Counted(i32),
    /// The interval was consumed but is not valid (pulses lost, instrument or clock fault): its
    /// pulses are gone, the next interval starts clean.
    Flagged(ErrorKind),
    /// The read failed before consuming anything (bus error, not ready): the pulses are still in
    /// the counter and the next successful read covers this interval too.
    Unread(ErrorKind),
}

impl Interval {
    /// Classifies a [`PulseCounter::read_delta`] result by its error kind.
    pub fn from_result<E: Error>(result: Result<i32, E>) -> Self {
        match result {
            Ok(delta) => Self::Counted(delta),
            Err(e) => match e.kind() {
                kind @ (ErrorKind::Overflow | ErrorKind::Fault) => Self::Flagged(kind),
                kind => Self::Unread(kind),
            },
        }
    }
}

/// A block of counter channels that are latched together: one call takes **one** snapshot of every
/// channel and consumes all of them, so a loop sees all its instruments at the same instant (reading
/// channel handles one by one would latch once per channel).
pub trait CounterSnapshot {
    /// Latches every channel once and writes channel `i`'s [`Interval`] into `out[i]`, for as many
    /// channels as both have; a failed bus read makes every one of them [`Interval::Unread`].
    ///
    /// Returns the length of the latched interval in seconds, measured by the block's own
    /// timestamp clock latched on the same edge as the counts: the time since the previous
    /// snapshot that consumed the channels (so it covers the periods of any unread snapshot in
    /// between, exactly as the counts do). `None` when the block cannot say (no timestamp, a failed
    /// read, channels consumed at different instants); the loop then divides by the nominal period.
    fn read_snapshot(&mut self, out: &mut [Interval]) -> Option<f32>;
}

impl<T: CounterSnapshot + ?Sized> CounterSnapshot for &mut T {
    #[inline]
    fn read_snapshot(&mut self, out: &mut [Interval]) -> Option<f32> {
        T::read_snapshot(self, out)
    }
}

impl<T: PulseCounter + ?Sized> PulseCounter for &mut T {
    #[inline]
    fn read_delta(&mut self) -> Result<i32, Self::Error> {
        T::read_delta(self)
    }
}

/// Signed difference `now − prev` of two readings of a free-running `bits`-bit up/down counter.
///
/// Only the low `bits` bits of `prev` and `now` are used. The result is the difference modulo
/// 2^`bits`, sign-extended: in `−2^(bits−1) ..= 2^(bits−1) − 1`. `bits` is clamped to `1..=32`
/// (a 16-bit MCU timer in encoder mode uses 16, the FPGA counter block 32).
///
/// ```
/// use tcomp_hal::wrapping_delta;
/// assert_eq!(wrapping_delta(0xFFFF_FFFE, 0x0000_0003, 32), 5); // wrapped upwards
/// assert_eq!(wrapping_delta(0x0003, 0xFFFE, 16), -5); // wrapped downwards
/// ```
#[inline]
pub const fn wrapping_delta(prev: u32, now: u32, bits: u32) -> i32 {
    let bits = if bits == 0 {
        1
    } else if bits > 32 {
        32
    } else {
        bits
    };
    let shift = 32 - bits;
    // Move the N-bit difference into the top bits, then an arithmetic shift sign-extends it.
    let diff = now.wrapping_sub(prev) << shift;
    (diff as i32) >> shift
}
