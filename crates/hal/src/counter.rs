//! The pulse counter trait, and the wrap-around-safe difference it relies on.
//!
//! Ring laser gyros and quartz accelerometers with current-to-frequency converters output *pulses*:
//! each one is a fixed increment of angle or of velocity, on an "up" line for one sign and a "down"
//! line for the other. Counter hardware accumulates them in a free-running N-bit up/down register
//! that wraps around; what the loop needs is the *signed number of pulses since its previous read*.
//! That number is the difference of two successive register values taken modulo 2^N and reinterpreted
//! as a signed N-bit value ([`wrapping_delta`]), which is exact as long as fewer than 2^(N−1) pulses
//! arrive between reads (for a 32-bit counter and a 200 Hz loop: 4·10¹¹ pulses/s, never reached).

use crate::error::ErrorType;

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
    /// The first call after initialisation returns the pulses since initialisation. Pulses are never
    /// lost across a failed call: after a bus error the next successful call returns everything since
    /// the last successful one.
    fn read_delta(&mut self) -> Result<i32, Self::Error>;
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
