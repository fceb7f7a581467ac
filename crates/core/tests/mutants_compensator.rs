//! The compensator's clamping at the edges of the trained range and its bookkeeping of skipped time,
//! on small hand-made models whose output is known in closed form.
//! Written to kill what `cargo mutants` found untested in `compensator.rs`.
#![allow(clippy::unwrap_used, missing_docs)]

use heapless::Vec as HVec;
use tcomp_core::blob::{ColumnRoles, Meta, ResidualLevel, SensorKind};
use tcomp_core::point::Point;
use tcomp_core::{Center, Channel, FeatureRange, Model, ProgramBuilder, ProgramState, Rbf, Status};

const N: usize = 8;
const F: usize = 2;
type M = Model<'static, 4, F, N>;

fn meta() -> Meta<'static> {
    Meta {
        sensor: SensorKind::Other,
        axis: "x",
        unit: "u",
        method: "hand-made",
        columns: ColumnRoles {
            time: "t",
            target: "y",
            reference: "",
            reference_value: Some(0.0),
        },
        trained_on: "tests/mutants_compensator.rs",
        train_samples: 0,
    }
}

/// The model `f(x) = 0.5·x + exp(−x²/2)` on the one feature `x`, trained on `[-1, 1]`.
fn one_feature_model() -> M {
    let mut b = ProgramBuilder::<'static, N, F>::new();
    b.feature("x").unwrap();
    let program = b.finish().unwrap();
    let mut rbf = Rbf::<4, F> {
        n_features: 1,
        offset: Point([0.0; F]),
        scale: Point([1.0, 0.0]),
        linear: Point([0.5, 0.0]),
        ..Rbf::default()
    };
    rbf.centers
        .push(Center::from_natural(&[0.0], 0.5, 1.0))
        .unwrap();
    let mut ranges = HVec::new();
    ranges.push(FeatureRange { lo: -1.0, hi: 1.0 }).unwrap();
    let residual = ResidualLevel {
        std: 0.0,
        binned_std: 0.0,
        bin_s: 1.0,
    };
    let m = Model::new(meta(), program, ranges, rbf, residual);
    m.validate().unwrap();
    m
}

fn f(x_gauss: f64, x_linear: f64) -> f64 {
    0.5 * x_linear + (-x_gauss * x_gauss / 2.0).exp()
}

#[test]
fn the_edges_of_the_range_are_inside_it_and_beyond_them_is_clamped() {
    let m = one_feature_model();
    // (input, what the Gaussians see, what the linear term sees, flagged). Range −1…1, span 2: the
    // linear term follows to −3 and 3.
    let cases = [
        (-1.0f32, -1.0, -1.0, false),
        (1.0, 1.0, 1.0, false),
        (0.25, 0.25, 0.25, false),
        (-2.0, -1.0, -2.0, true),
        (2.5, 1.0, 2.5, true),
        (-3.0, -1.0, -3.0, true),
        (3.0, 1.0, 3.0, true),
        (-5.0, -1.0, -3.0, true),
        (40.0, 1.0, 3.0, true),
    ];
    for (x, g, l, flagged) in cases {
        let mut ch = Channel::<N, F>::new(1.0);
        let out = ch.step(Some(&m), &[x], 10.0);
        assert_eq!(
            out.status.contains(Status::OUT_OF_RANGE),
            flagged,
            "x = {x}: {}",
            out.status
        );
        assert!(!out.status.contains(Status::INPUT_FAULT));
        let exact = f(g, l);
        assert!(
            (out.correction as f64 - exact).abs() < 1e-5,
            "x = {x}: {} vs {exact}",
            out.correction
        );
        assert_eq!(out.compensated, 10.0 - out.correction);
        assert_eq!(ch.features()[0], x, "the features are kept unclamped");
    }
}

/// Features `x / y` and `lag(x, 10)`: a zero `y` spoils a feature without stopping the program.
fn division_and_lag_model() -> M {
    let mut b = ProgramBuilder::<'static, N, F>::new();
    b.feature("x / y").unwrap();
    b.feature("lag(x, 10)").unwrap();
    let program = b.finish().unwrap();
    let rbf = Rbf::<4, F> {
        n_features: 2,
        scale: Point([1.0, 1.0]),
        linear: Point([0.0, 1.0]),
        ..Rbf::default()
    };
    let mut ranges = HVec::new();
    for _ in 0..2 {
        ranges.push(FeatureRange { lo: -1e6, hi: 1e6 }).unwrap();
    }
    let residual = ResidualLevel {
        std: 0.0,
        binned_std: 0.0,
        bin_s: 1.0,
    };
    let m = Model::new(meta(), program, ranges, rbf, residual);
    m.validate().unwrap();
    m
}

#[test]
fn a_spoilt_feature_does_not_stop_the_clock() {
    // The program advances on the sample whose feature is infinite, so no time is carried: the lag
    // afterwards is that of a state stepped every second.
    let m = division_and_lag_model();
    let mut ch = Channel::<N, F>::new(1.0);
    let mut reference = ProgramState::<N>::new();
    for n in 0..30u32 {
        let x = n as f32;
        let y = if n == 12 { 0.0 } else { 1.0 };
        let out = ch.step(Some(&m), &[x, y], 0.0);
        reference.step(&m.program, &[x, y], 1.0).unwrap();
        assert_eq!(out.status.contains(Status::INPUT_FAULT), n == 12, "{n}");
        if n != 12 {
            let mut expect = [0.0f32; F];
            reference.features(&m.program, &mut expect).unwrap();
            assert_eq!(ch.features(), &expect, "sample {n}");
        }
    }
}

#[test]
fn time_skipped_by_bad_inputs_is_carried_into_the_next_good_step() {
    let m = division_and_lag_model();
    let mut ch = Channel::<N, F>::new(1.0);
    let mut reference = ProgramState::<N>::new();
    let mut expect = [0.0f32; F];
    for n in 0..40u32 {
        let x = n as f32;
        let out = ch.step(
            Some(&m),
            &[if (10..15).contains(&n) { f32::NAN } else { x }, 1.0],
            0.0,
        );
        match n {
            10..15 => assert!(out.status.contains(Status::INPUT_FAULT)),
            // The first good sample after the gap is 6 s after the last good one.
            15 => reference.step(&m.program, &[x, 1.0], 6.0).unwrap(),
            _ => reference.step(&m.program, &[x, 1.0], 1.0).unwrap(),
        }
        if !(10..15).contains(&n) {
            reference.features(&m.program, &mut expect).unwrap();
            assert_eq!(ch.features(), &expect, "sample {n}");
            assert!(out.status.is_ok(), "sample {n}: {}", out.status);
        }
    }
}
