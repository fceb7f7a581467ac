//! The error kinds and the trait shape.
#![allow(clippy::unwrap_used, clippy::panic, missing_docs)] // tests: a failed unwrap is a failed test

use tcomp_hal::{Error, ErrorKind};

#[test]
fn kind_of_a_kind_is_itself_and_displays() {
    for k in [
        ErrorKind::Bus,
        ErrorKind::NotReady,
        ErrorKind::OutOfRange,
        ErrorKind::OpenCircuit,
        ErrorKind::ShortCircuit,
        ErrorKind::Overflow,
        ErrorKind::Fault,
        ErrorKind::WrongDevice,
        ErrorKind::InvalidConfig,
        ErrorKind::Other,
    ] {
        assert_eq!(k.kind(), k);
        assert!(!k.to_string().is_empty());
    }
    assert_eq!(ErrorKind::OpenCircuit.to_string(), "sensor open circuit");
}

#[test]
fn driver_errors_display_their_details() {
    let e: tcomp_hal::ads1220::Error<()> = tcomp_hal::ads1220::Error::ConfigMismatch {
        written: [4, 4, 0x56, 0x80],
        read: [0xff; 4],
    };
    assert_eq!(
        e.to_string(),
        "ADS1220: wrote registers [04, 04, 56, 80], read back [ff, ff, ff, ff]"
    );
    let e: tcomp_hal::pulse_counter::Error<()> =
        tcomp_hal::pulse_counter::Error::WrongId { id: 0xdead_beef };
    assert_eq!(
        e.to_string(),
        "counter block: ID 0xdeadbeef, expected 0x55444301"
    );
}
