//! The thermometer channel trait.
//!
//! The compensation model's inputs are temperatures in °C, whatever the sensor (an RTD on a delta-sigma
//! ADC, a thermistor, a replayed test vector). One trait object per physical thermometer keeps the
//! firmware loop independent of how the temperature was measured.

use crate::error::ErrorType;

/// One temperature channel.
///
/// A board that replays recorded data implements it directly, using [`ErrorKind`](crate::ErrorKind)
/// as its error type:
///
/// ```
/// use tcomp_hal::{ErrorKind, ErrorType, Thermometer};
///
/// struct Replay<'a> {
///     samples: &'a [f32],
///     next: usize,
/// }
/// impl ErrorType for Replay<'_> {
///     type Error = ErrorKind;
/// }
/// impl Thermometer for Replay<'_> {
///     fn read_celsius(&mut self) -> Result<f32, ErrorKind> {
///         let t = *self.samples.get(self.next).ok_or(ErrorKind::NotReady)?;
///         self.next += 1;
///         if t.is_nan() { Err(ErrorKind::Bus) } else { Ok(t) } // a NaN marks an injected bus error
///     }
/// }
///
/// let mut th = Replay { samples: &[21.5, f32::NAN], next: 0 };
/// assert_eq!(th.read_celsius(), Ok(21.5));
/// assert_eq!(th.read_celsius(), Err(ErrorKind::Bus));
/// assert_eq!(th.read_celsius(), Err(ErrorKind::NotReady));
/// ```
pub trait Thermometer: ErrorType {
    /// Read the temperature in °C.
    ///
    /// A returned value is always finite; anything the driver cannot stand behind (open sensor, reading
    /// out of the sensor model's range, bus error) is an error whose [`kind`](crate::Error::kind) says
    /// which.
    fn read_celsius(&mut self) -> Result<f32, Self::Error>;
}

impl<T: Thermometer + ?Sized> Thermometer for &mut T {
    #[inline]
    fn read_celsius(&mut self) -> Result<f32, Self::Error> {
        T::read_celsius(self)
    }
}
