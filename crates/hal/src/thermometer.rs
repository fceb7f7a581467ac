//! The thermometer channel trait.
//!
//! The compensation model's inputs are temperatures in °C, whatever the sensor (an RTD on a delta-sigma
//! ADC, a thermistor, a replayed test vector). One trait object per physical thermometer keeps the
//! firmware loop independent of how the temperature was measured.

use crate::error::ErrorType;

/// One temperature channel.
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
