//! Counts → rate / acceleration, with the numbers worked by hand.
#![allow(clippy::unwrap_used, clippy::panic, missing_docs)] // tests: a failed unwrap is a failed test

use tcomp_hal::ErrorKind;
use tcomp_hal::scale::{ChannelScale, Unit};

fn close(a: f32, b: f32, rtol: f32) -> bool {
    (a - b).abs() <= rtol * b.abs().max(1e-30)
}

#[test]
fn rlg_rate_in_deg_per_hour() {
    let rlg = ChannelScale::rlg_arcsec_per_pulse(1.5);
    assert_eq!(rlg.unit(), Unit::DegPerHour);
    // 10 pulses × 1.5″ = 15″ in 1 s = 15″/s; 1″/s = (1/3600)° per (1/3600) h = 1 °/h → 15 °/h,
    // about the Earth's rate (15.04 °/h).
    assert!(close(rlg.rate(10, 1.0).unwrap(), 15.0, 1e-6));
    // 200 Hz loop: 3 pulses in 5 ms = 4.5″ / 0.005 s = 900 °/h; down pulses give the sign.
    assert!(close(rlg.rate(-3, 0.005).unwrap(), -900.0, 1e-6));
    assert!(close(rlg.increment(-3), -4.5, 1e-6));
}

#[test]
fn rlg_scale_from_geometry() {
    // Equilateral ring, side 0.1 m: L = 0.3 m, A = √3/4 · 0.01 = 4.330127e-3 m², λ = 632.8 nm.
    // One pulse = λL / 4A = 632.8e-9 · 0.3 / 0.01732051 = 1.096041e-5 rad
    //           = 1.096041e-5 · 206 264.8″ = 2.26074″.
    let rlg = ChannelScale::rlg_from_geometry(3f64.sqrt() / 4.0 * 0.01, 0.3, 632.8e-9);
    assert!(close(rlg.per_pulse(), 2.26074, 1e-5), "{}", rlg.per_pulse());
}

#[test]
fn qma_acceleration_in_micro_g() {
    // K1 = 1.25 mA/g, q = 312.5 nC/pulse: f = K1·a/q = 1.25e-3 / 312.5e-9 = 4000 Hz per g,
    // so SF = 1e6 µg / 4000 Hz = 250 µg/Hz (= 1e6 · q / K1 = 1e6 · 2.5e-4).
    let qma = ChannelScale::qma_from_converter(1.25e-3, 312.5e-9);
    assert_eq!(qma.unit(), Unit::MicroG);
    assert!(close(qma.per_pulse(), 250.0, 1e-6));
    // 1 g for 5 ms: 4000 Hz · 0.005 s = 20 pulses → 20 / 0.005 = 4000 Hz · 250 = 1e6 µg.
    assert!(close(qma.rate(20, 0.005).unwrap(), 1.0e6, 1e-6));
    // One pulse in 5 ms is the per-sample quantum: 200 Hz · 250 = 50 000 µg.
    assert!(close(qma.rate(1, 0.005).unwrap(), 5.0e4, 1e-6));
    // −0.5 g over 1 s: −2000 pulses → −500 000 µg.
    assert!(close(qma.rate(-2000, 1.0).unwrap(), -5.0e5, 1e-6));
    assert_eq!(ChannelScale::qma_ug_per_hz(250.0), qma);
}

#[test]
fn bad_interval_is_out_of_range() {
    let s = ChannelScale::rlg_arcsec_per_pulse(1.0);
    for dt in [0.0, -0.005, f32::NAN, f32::INFINITY] {
        assert_eq!(s.rate(1, dt), Err(ErrorKind::OutOfRange), "dt = {dt}");
    }
}

/// The general constructors are the device ones' numbers with the unit of what is measured.
#[test]
fn general_constructors_name_the_quantity_not_the_device() {
    assert_eq!(
        ChannelScale::gyro_arcsec_per_count(1.5),
        ChannelScale::rlg_arcsec_per_pulse(1.5)
    );
    assert_eq!(
        ChannelScale::accel_ug_s_per_count(50.0),
        ChannelScale::qma_ug_per_hz(50.0)
    );
    assert_eq!(ChannelScale::accel_ug_s_per_count(1.0).unit(), Unit::MicroG);
    assert_eq!(
        ChannelScale::gyro_arcsec_per_count(1.0).unit(),
        Unit::DegPerHour
    );
}
