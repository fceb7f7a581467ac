//! The compensator's statuses and its behaviour on faults.
#![allow(clippy::unwrap_used, missing_docs)]

use tcomp_core::testing::{example_model, example_sample};
use tcomp_core::{Channel, Model, Status};

type M = Model<'static, 32, 4, 24>;

fn model() -> M {
    example_model::<32, 4, 24>(32, 11)
}

#[test]
fn compensates_and_matches_program_plus_rbf() {
    let m = model();
    let mut ch = Channel::<24, 4>::new(0.01);
    for n in 0..500 {
        let (temps, raw) = example_sample(n, 0.01);
        let out = ch.step(Some(&m), &temps, raw);
        assert_eq!(out.status, Status::OK, "sample {n}");
        let expect = m.rbf.eval(ch.features());
        assert_eq!(out.correction, expect);
        assert_eq!(out.compensated, raw - expect);
    }
}

#[test]
fn no_model_passes_raw_through() {
    let mut ch = Channel::<24, 4>::new(0.01);
    let out = ch.step::<32>(None, &[1.0, 2.0, 3.0], 5.0);
    assert_eq!((out.compensated, out.status), (5.0, Status::NO_MODEL));
}

#[test]
fn nan_input_holds_last_good_features_and_keeps_the_clock() {
    let m = model();
    let mut a = Channel::<24, 4>::new(1.0);
    let mut b = Channel::<24, 4>::new(1.0);
    let mut held = [0.0; 4];
    for n in 0..200u32 {
        let (temps, raw) = example_sample(n, 1.0);
        let oa = a.step(Some(&m), &temps, raw);
        // Channel b loses samples 100..110 to a NaN thermometer, then reads a 11 s step at once.
        if (100..110).contains(&n) {
            let ob = b.step(Some(&m), &[f32::NAN, temps[1], temps[2]], raw);
            assert!(ob.status.contains(Status::INPUT_FAULT));
            assert_eq!(b.features(), &held);
            assert!(ob.compensated.is_finite());
        } else {
            let ob = b.step(Some(&m), &temps, raw);
            held = *b.features();
            if n < 100 {
                assert_eq!(oa, ob);
            } else {
                assert!(ob.status.is_ok());
            }
        }
    }
    // After the gap the lag states caught up on the skipped 10 s: features agree closely again.
    let diff = (a.features()[0] - b.features()[0]).abs();
    assert!(diff < 1e-3, "mean temperature differs by {diff}");
}

#[test]
fn out_of_range_is_clamped_and_flagged() {
    let m = model();
    let mut ch = Channel::<24, 4>::new(1.0);
    // T = 90 °C against a trained −40…60 °C (span 100): Gaussians see 60, the linear term 90.
    let out = ch.step(Some(&m), &[90.0, 90.0, 90.0], 0.0);
    assert!(out.status.contains(Status::OUT_OF_RANGE));
    let raw_features = *ch.features();
    let mut clamped = raw_features;
    clamped[0] = 60.0;
    assert_eq!(out.correction, m.rbf.eval_split(&clamped, &raw_features));
    assert_ne!(
        out.correction,
        m.rbf.eval(&clamped),
        "the linear term extrapolates"
    );
    // Far beyond, the linear term stops one span out: 500 °C is treated as 160 °C.
    let mut ch = Channel::<24, 4>::new(1.0);
    let out = ch.step(Some(&m), &[500.0, 500.0, 500.0], 0.0);
    let mut lin = *ch.features();
    lin[0] = 160.0;
    assert_eq!(out.correction, m.rbf.eval_split(&clamped, &lin));
    // In range, the split evaluation is the plain one, bit for bit.
    let x = [12.0f32, 0.3, 0.1, -0.2];
    assert_eq!(m.rbf.eval_split(&x, &x).to_bits(), m.rbf.eval(&x).to_bits());
}

#[test]
fn fault_before_any_good_sample_passes_raw() {
    let m = model();
    let mut ch = Channel::<24, 4>::new(1.0);
    let out = ch.step(Some(&m), &[f32::INFINITY, 0.0, 0.0], 3.0);
    assert_eq!((out.compensated, out.correction), (3.0, 0.0));
    assert!(out.status.contains(Status::INPUT_FAULT));
    assert_eq!(
        format!("{}", Status::INPUT_FAULT.with(Status::OUT_OF_RANGE)),
        "out-of-range+input-fault"
    );
}

#[test]
fn model_interval_refreshes_on_its_phase_and_holds_in_between() {
    let m = model();
    let mut every = Channel::<24, 4>::new(0.005);
    let mut sparse = Channel::<24, 4>::new(0.005).with_model_interval(4, 1);
    let mut last_fresh = None;
    for n in 0..400u32 {
        let (temps, raw) = example_sample(n, 0.005);
        let a = every.step(Some(&m), &temps, raw);
        let b = sparse.step(Some(&m), &temps, raw);
        assert_eq!(a.status, b.status);
        assert_eq!(
            every.features(),
            sparse.features(),
            "the program runs every sample"
        );
        if n == 0 || n % 4 == 1 {
            assert_eq!(
                a.correction.to_bits(),
                b.correction.to_bits(),
                "sample {n} is a refresh"
            );
            last_fresh = Some(a.correction);
        } else {
            assert_eq!(
                Some(b.correction),
                last_fresh,
                "sample {n} holds the last refresh"
            );
        }
        // Held for at most 15 ms of a 3 °C/min ramp: far below any sensor noise.
        assert!((a.correction - b.correction).abs() < 1e-4, "sample {n}");
    }
    sparse.reset();
    let (temps, raw) = example_sample(0, 0.005);
    let b = sparse.step(Some(&m), &temps, raw);
    assert_eq!(
        b.correction,
        m.rbf.eval(sparse.features()),
        "reset keeps the interval, starts fresh"
    );
}

#[test]
fn a_non_finite_correction_is_a_model_fault_and_raw_passes() {
    // Built directly (decoding would refuse it): every weight 3e38, so the sum overflows to ±inf.
    let mut m = model();
    for c in m.rbf.centers.iter_mut() {
        c.w = 3.0e38;
    }
    let mut ch = Channel::<24, 4>::new(0.01);
    let (temps, raw) = example_sample(0, 0.01);
    let out = ch.step(Some(&m), &temps, raw);
    assert!(!m.rbf.eval(ch.features()).is_finite(), "the sum overflows");
    assert_eq!(out.status, Status::MODEL_FAULT);
    assert_eq!((out.compensated, out.correction), (raw, 0.0));
    assert_eq!(format!("{}", out.status), "model-fault");
    // A NaN raw value is the input's fault, not the model's.
    let out = ch.step(Some(&m), &temps, f32::NAN);
    assert!(out.status.contains(Status::INPUT_FAULT));
    assert!(!out.status.contains(Status::MODEL_FAULT));
}

#[test]
fn an_overflowing_difference_is_a_model_fault() {
    // A finite correction, a finite raw value, but raw − correction overflows.
    let mut m = model();
    m.rbf.bias = -3.0e38;
    m.rbf.linear = tcomp_core::point::Point([0.0; 4]);
    for c in m.rbf.centers.iter_mut() {
        c.w = 0.0;
    }
    let mut ch = Channel::<24, 4>::new(0.01);
    let (temps, _) = example_sample(0, 0.01);
    let out = ch.step(Some(&m), &temps, 3.0e38);
    assert_eq!(out.status, Status::MODEL_FAULT);
    assert_eq!(out.compensated, 3.0e38);
    // The same model with an ordinary raw value is fine.
    let out = ch.step(Some(&m), &temps, 1.0);
    assert_eq!(out.status, Status::OK);
    assert_eq!(out.compensated, 1.0 + 3.0e38);
}
