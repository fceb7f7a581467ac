//! `OnReady`: the converter is read once per conversion, when DRDY is low, and held in between.
#![allow(clippy::unwrap_used, missing_docs)]

use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as Pin};
use tcomp_hal::{ErrorKind, ErrorType, OnReady, Thermometer};

/// A thermometer that returns its queued readings in turn and counts its reads.
struct Queue {
    readings: Vec<Result<f32, ErrorKind>>,
    reads: usize,
}

impl ErrorType for Queue {
    type Error = ErrorKind;
}

impl Thermometer for Queue {
    fn read_celsius(&mut self) -> Result<f32, ErrorKind> {
        self.reads += 1;
        self.readings.remove(0)
    }
}

#[test]
fn reads_each_conversion_once_and_holds_it_in_between() {
    let drdy = PinMock::new(&[
        Pin::get(State::High), // nothing held yet: read anyway
        Pin::get(State::High), // no new conversion: held
        Pin::get(State::High),
        Pin::get(State::Low), // new conversion: read
        Pin::get(State::High),
    ]);
    let th = Queue {
        readings: vec![Ok(21.0), Ok(21.5)],
        reads: 0,
    };
    let mut t = OnReady::new(th, drdy);
    let got: Vec<_> = (0..5).map(|_| t.read_celsius()).collect();
    assert_eq!(got, [Ok(21.0), Ok(21.0), Ok(21.0), Ok(21.5), Ok(21.5)]);
    let (th, mut drdy) = t.release();
    assert_eq!(th.reads, 2);
    drdy.done();
}

#[test]
fn a_failed_read_is_not_held_and_the_next_period_reads_again() {
    let drdy = PinMock::new(&[
        Pin::get(State::Low),
        Pin::get(State::High), // nothing good held: read although DRDY is high
        Pin::get(State::High),
    ]);
    let th = Queue {
        readings: vec![Err(ErrorKind::Bus), Ok(22.0)],
        reads: 0,
    };
    let mut t = OnReady::new(th, drdy);
    assert_eq!(t.read_celsius(), Err(ErrorKind::Bus));
    assert_eq!(t.read_celsius(), Ok(22.0));
    assert_eq!(t.read_celsius(), Ok(22.0));
    let (th, mut drdy) = t.release();
    assert_eq!(th.reads, 2);
    drdy.done();
}
