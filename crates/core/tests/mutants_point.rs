//! `Point`: construction, the finiteness check every blob read relies on, and the wire rules the
//! module doc promises (trailing zeros dropped, more than `F` values refused with a useful message).
//! Written to kill what `cargo mutants` found untested in `point.rs`.
#![allow(clippy::unwrap_used, missing_docs)]

use serde::Deserialize;
use serde::de::value::{Error as ValueError, SeqDeserializer};
use tcomp_core::point::Point;

fn from_values<const F: usize>(values: &[f32]) -> Result<Point<F>, ValueError> {
    let de = SeqDeserializer::<_, ValueError>::new(values.iter().copied());
    Point::<F>::deserialize(de)
}

#[test]
fn from_slice_copies_the_prefix_and_zero_fills() {
    assert_eq!(
        Point::<4>::from_slice(&[1.5, -2.0]).0,
        [1.5, -2.0, 0.0, 0.0]
    );
    assert_eq!(
        Point::<2>::from_slice(&[3.0, 4.0, 5.0]).0,
        [3.0, 4.0],
        "values past F are dropped"
    );
    assert_eq!(Point::<3>::from_slice(&[]).0, [0.0; 3]);
}

#[test]
fn is_finite_sees_every_entry() {
    assert!(Point::<3>::from_slice(&[1.0, -1e30, 0.0]).is_finite());
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        for k in 0..3 {
            let mut p = Point::<3>::from_slice(&[1.0, 2.0, 3.0]);
            p.0[k] = bad;
            assert!(!p.is_finite(), "{bad} at {k}");
        }
    }
}

#[test]
fn trailing_zeros_are_dropped_on_the_wire_and_read_back() {
    let p = Point::<6>::from_slice(&[0.0, 2.5, 0.0, -1.0]);
    let mut buf = [0u8; 64];
    let bytes = postcard::to_slice(&p, &mut buf).unwrap();
    // Length prefix 4 (up to the last non-zero entry), then four little-endian f32s.
    assert_eq!(bytes.len(), 1 + 4 * 4);
    assert_eq!(bytes[0], 4);
    let back: Point<6> = postcard::from_bytes(bytes).unwrap();
    assert_eq!(back, p);
    let zero = Point::<6>::default();
    let bytes = postcard::to_slice(&zero, &mut buf).unwrap();
    assert_eq!(bytes, &[0u8], "an all-zero point is an empty sequence");
}

#[test]
fn reading_fewer_values_zero_fills_and_more_than_f_is_refused_with_the_count() {
    let p = from_values::<4>(&[1.0, 2.0]).unwrap();
    assert_eq!(p.0, [1.0, 2.0, 0.0, 0.0]);
    let p = from_values::<4>(&[1.0, 2.0, 3.0, 4.0]).unwrap();
    assert_eq!(p.0, [1.0, 2.0, 3.0, 4.0]);
    let e = from_values::<4>(&[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap_err();
    // serde's own wording around our count (the 5th value) and our expectation.
    assert_eq!(
        e.to_string(),
        "invalid length 5, expected at most 4 f32 values"
    );
}
