//! A thermometer read only when its converter has a new conversion (its DRDY line is low).
//!
//! Why: an ADS1220 at 20 SPS converts every 50 ms while the loop samples every 5 ms. Reading the
//! converter on every loop period spends nine SPI transactions in ten re-reading the same
//! conversion, and a read that races the end of a conversion can return it half updated. Watching
//! DRDY, the loop reads each conversion exactly once, as soon as it is ready, and holds the last
//! value in between (the temperature's own time constants are minutes; the feature program's
//! rates see each conversion once). A DRDY line that cannot be read costs nothing but the saving:
//! the converter is read as before. Until the first good read there is nothing to hold, so the
//! converter is read whatever DRDY says.

use crate::error::ErrorType;
use crate::thermometer::Thermometer;
use embedded_hal::digital::InputPin;

/// `T` read only when `drdy` is low (new data), else its last good value.
pub struct OnReady<T, P> {
    inner: T,
    drdy: P,
    last: Option<f32>,
}

impl<T, P> OnReady<T, P> {
    /// Wraps a thermometer and its converter's active-low data-ready line.
    pub const fn new(inner: T, drdy: P) -> Self {
        Self {
            inner,
            drdy,
            last: None,
        }
    }

    /// The wrapped thermometer (e.g. to configure it).
    pub fn inner_mut(&mut self) -> &mut T {
        &mut self.inner
    }

    /// The thermometer and the DRDY line back.
    pub fn release(self) -> (T, P) {
        (self.inner, self.drdy)
    }
}

impl<T: ErrorType, P> ErrorType for OnReady<T, P> {
    type Error = T::Error;
}

impl<T: Thermometer, P: InputPin> Thermometer for OnReady<T, P> {
    fn read_celsius(&mut self) -> Result<f32, Self::Error> {
        if let (Ok(false), Some(v)) = (self.drdy.is_low(), self.last) {
            return Ok(v);
        }
        match self.inner.read_celsius() {
            Ok(v) => {
                self.last = Some(v);
                Ok(v)
            }
            Err(e) => {
                // A failed read forgets the held value: the next period reads the converter again.
                self.last = None;
                Err(e)
            }
        }
    }
}
