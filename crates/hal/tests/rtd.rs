//! Callendar–Van Dusen and Steinhart–Hart conversions.
#![allow(clippy::unwrap_used, clippy::panic, missing_docs)] // tests: a failed unwrap is a failed test

use proptest::prelude::*;
use tcomp_hal::ErrorKind;
use tcomp_hal::rtd::Rtd;
use tcomp_hal::thermistor::SteinhartHart;

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn pt100_matches_iec60751_table() {
    // IEC 60751 table values (Ω) for a PT100.
    let table = [
        (-200.0, 18.5201),
        (-100.0, 60.2558),
        (-40.0, 84.2707),
        (0.0, 100.0),
        (25.0, 109.7347),
        (100.0, 138.5055),
        (500.0, 280.9775),
        (850.0, 390.4811),
    ];
    for (t, r) in table {
        let got = Rtd::PT100.resistance(t).unwrap();
        assert!(close(got, r, 2e-4), "R({t}) = {got}, table {r}");
        let back = Rtd::PT100.temperature(r).unwrap();
        assert!(close(back, t, 1e-3), "T({r}) = {back}, table {t}");
    }
}

#[test]
fn pt1000_is_ten_pt100s() {
    for t in [-150.0, -1.0, 0.5, 420.0] {
        let r100 = Rtd::PT100.resistance(t).unwrap();
        let r1000 = Rtd::PT1000.resistance(t).unwrap();
        assert!(close(r1000, 10.0 * r100, 1e-3 * r100));
    }
}

#[test]
fn out_of_range_both_ways() {
    let pt = Rtd::PT100;
    assert_eq!(pt.resistance(-200.1), Err(ErrorKind::OutOfRange));
    assert_eq!(pt.resistance(850.1), Err(ErrorKind::OutOfRange));
    assert_eq!(pt.resistance(f32::NAN), Err(ErrorKind::OutOfRange));
    assert_eq!(pt.temperature(18.0), Err(ErrorKind::OutOfRange)); // below −200 °C
    assert_eq!(pt.temperature(391.0), Err(ErrorKind::OutOfRange)); // above 850 °C
    assert_eq!(pt.temperature(f32::NAN), Err(ErrorKind::OutOfRange));
    assert_eq!(pt.temperature(f32::INFINITY), Err(ErrorKind::OutOfRange));
    assert_eq!(pt.temperature(-5.0), Err(ErrorKind::OutOfRange));
    // The end points themselves are inside.
    assert!(close(pt.temperature(pt.r_min()).unwrap(), -200.0, 1e-3));
    assert!(close(pt.temperature(pt.r_max()).unwrap(), 850.0, 1e-3));
}

#[test]
fn dense_round_trip_sweep() {
    // Every 0.01 °C from −200 to 850 °C, both sensors: a deterministic complement to the property.
    let mut worst = 0.0f32;
    for rtd in [Rtd::PT100, Rtd::PT1000] {
        for i in 0..=105_000 {
            let t = -200.0 + i as f32 * 0.01;
            let t = t.min(850.0);
            let back = rtd.temperature(rtd.resistance(t).unwrap()).unwrap();
            worst = worst.max((back - t).abs());
        }
    }
    eprintln!("worst CVD round-trip error: {worst} °C");
    assert!(worst < 1e-3, "worst round-trip error {worst} °C");
}

proptest! {
    #[test]
    fn cvd_round_trip_within_1_mk(t in -200.0f32..=850.0, pt1000 in any::<bool>()) {
        let rtd = if pt1000 { Rtd::PT1000 } else { Rtd::PT100 };
        let r = rtd.resistance(t).unwrap();
        let back = rtd.temperature(r).unwrap();
        prop_assert!((back - t).abs() < 1e-3, "{} → {} Ω → {}", t, r, back);
    }

    #[test]
    fn cvd_inverse_never_panics_and_stays_in_range(r in proptest::num::f32::ANY) {
        if let Ok(t) = Rtd::PT100.temperature(r) {
            prop_assert!((-200.0..=850.0).contains(&t));
        }
    }
}

#[test]
fn steinhart_hart_10k_ntc() {
    let ntc = SteinhartHart::EXAMPLE_10K;
    // 1/T = a + b·ln R + c·ln³R at R = 9876.6 Ω: ln R = 9.19793, so
    // 1/T = 1.00925e-3 + 2.18764e-3 + 1.57126e-4 = 3.35402e-3 /K → T = 298.15 K = 25.00 °C.
    let r25 = ntc.resistance(25.0).unwrap();
    assert!((r25 - 9876.6).abs() < 2.0, "R(25 °C) = {r25}");
    for t in [-40.0, -10.0, 0.0, 25.0, 60.0, 125.0] {
        let back = ntc.temperature(ntc.resistance(t).unwrap()).unwrap();
        assert!(close(back, t, 5e-3), "{t} → {back}");
    }
    assert_eq!(ntc.temperature(0.0), Err(ErrorKind::OutOfRange));
    assert_eq!(ntc.temperature(50.0), Err(ErrorKind::OutOfRange)); // ≈ 200 °C
    assert_eq!(ntc.resistance(130.0), Err(ErrorKind::OutOfRange));
}
