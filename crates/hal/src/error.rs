//! Error kinds shared by every driver, in embedded-hal's shape.
//!
//! Each driver has its own error type that keeps the details (the bus error, the code that was read,
//! the bytes that did not verify); generic code such as the firmware's status word only needs to know
//! *what kind* of failure it was, so every error type implements [`Error::kind`]. This is exactly how
//! `embedded_hal::digital::Error` and `embedded_hal::spi::Error` work, so a reader who knows one knows
//! the other.

use core::fmt;

/// What went wrong, independent of the driver that saw it.
///
/// `#[non_exhaustive]`: match with a `_` arm, new kinds may be added.
#[derive(Debug, Copy, Clone, Eq, PartialEq, Ord, PartialOrd, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ErrorKind {
    /// The bus transfer itself failed (SPI/I²C error reported by the HAL).
    Bus,
    /// No new data is available yet, or the device did not answer in time.
    NotReady,
    /// The reading is valid as a number but outside the range the sensor model covers
    /// (e.g. an RTD resistance outside −200…850 °C).
    OutOfRange,
    /// The sensor looks disconnected (e.g. an ADC at full scale with a broken RTD).
    OpenCircuit,
    /// The sensor looks shorted (e.g. an RTD reading zero or negative resistance).
    ShortCircuit,
    /// Pulses were lost: the input was faster than the counter can follow.
    Overflow,
    /// The device reported a fault (a status bit: missing clock, sensor fault line).
    Fault,
    /// The device did not identify as expected: wrong ID register, or a configuration that does not
    /// read back as written (no device, wrong device, or a broken MISO line).
    WrongDevice,
    /// The driver was asked for a configuration the part does not support.
    InvalidConfig,
    /// Anything else.
    Other,
}

impl ErrorKind {
    /// A short, stable, human-readable description.
    pub const fn as_str(self) -> &'static str {
        match self {
            Self::Bus => "bus transfer failed",
            Self::NotReady => "no new data",
            Self::OutOfRange => "reading out of the sensor's range",
            Self::OpenCircuit => "sensor open circuit",
            Self::ShortCircuit => "sensor short circuit",
            Self::Overflow => "pulses lost",
            Self::Fault => "device reported a fault",
            Self::WrongDevice => "device did not identify or verify",
            Self::InvalidConfig => "unsupported configuration",
            Self::Other => "other error",
        }
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl core::error::Error for ErrorKind {}

/// A driver error that can say what kind of failure it is.
pub trait Error: fmt::Debug {
    /// Convert the error to a generic [`ErrorKind`].
    fn kind(&self) -> ErrorKind;
}

impl Error for ErrorKind {
    #[inline]
    fn kind(&self) -> ErrorKind {
        *self
    }
}

impl Error for core::convert::Infallible {
    fn kind(&self) -> ErrorKind {
        match *self {}
    }
}

/// The error type of a sensor channel ([`Thermometer`](crate::Thermometer),
/// [`PulseCounter`](crate::PulseCounter)).
pub trait ErrorType {
    /// Error type.
    type Error: Error;
}

impl<T: ErrorType + ?Sized> ErrorType for &mut T {
    type Error = T::Error;
}
