//! Every operator of the feature language against its analytic result.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use tcomp_core::{ProgramBuilder, ProgramState, StepError};

type B<'a> = ProgramBuilder<'a, 48, 8>;

/// Runs one feature over a stream of (inputs, dt) and returns its values.
fn run(signals: &[&'static str], feature: &'static str, samples: &[(&[f32], f32)]) -> Vec<f32> {
    let mut b = B::new();
    for s in signals {
        b.line(s).unwrap();
    }
    b.feature(feature).unwrap();
    let p = b.finish().unwrap();
    let mut st = ProgramState::<48>::new();
    let mut out = [0.0f32; 8];
    samples
        .iter()
        .map(|(x, dt)| {
            st.step(&p, x, *dt).unwrap();
            st.features(&p, &mut out).unwrap();
            out[0]
        })
        .collect()
}

#[test]
fn arithmetic_mean_sq_abs_clamp() {
    let v = run(
        &[],
        "mean(a, b, c) * 2 - sq(a) / 4 + abs(b) + clamp(c, -1, 0.5)",
        &[(&[2.0, -3.0, 7.0], 1.0)],
    );
    let expect = (2.0 - 3.0 + 7.0) / 3.0 * 2.0 - 4.0 / 4.0 + 3.0 + 0.5;
    assert!((v[0] - expect).abs() < 1e-6, "{} vs {expect}", v[0]);
    let v = run(&[], "-a * -b", &[(&[2.0, 3.0], 1.0)]);
    assert_eq!(v[0], 6.0);
    let v = run(&[], "a - b - c", &[(&[10.0, 3.0, 2.0], 1.0)]);
    assert_eq!(v[0], 5.0, "subtraction is left-associative");
}

#[test]
fn lag_step_response_is_the_exponential() {
    let tau = 40.0f32;
    let dt = 0.5f32;
    let mut samples: Vec<(&[f32], f32)> = vec![(&[0.0], dt)];
    samples.extend(std::iter::repeat_n((&[1.0f32][..], dt), 400));
    let v = run(&[], "lag(x, 40)", &samples);
    assert_eq!(v[0], 0.0);
    for (k, y) in v.iter().enumerate().skip(1) {
        let exact = 1.0 - (-(k as f64) * dt as f64 / tau as f64).exp();
        assert!(
            (*y as f64 - exact).abs() < 2e-6,
            "sample {k}: {y} vs {exact}"
        );
    }
}

#[test]
fn rate_of_a_ramp_is_exact_in_units_per_minute_at_any_sample_rate() {
    for &(dt, window) in &[(1.0f32, 60.0f32), (0.005, 60.0), (0.01, 20.0)] {
        let slope_per_s = 3.0 / 60.0; // 3 °C/min
        let n = (12.0 * window / dt) as usize; // 12 windows: the start-up transient is gone
        let xs: Vec<[f32; 1]> = (0..n)
            .map(|i| [20.0 + slope_per_s * i as f32 * dt])
            .collect();
        let samples: Vec<(&[f32], f32)> = xs.iter().map(|x| (&x[..], dt)).collect();
        let feature: &'static str = if window == 60.0 {
            "rate(x)"
        } else {
            "rate(x, 20)"
        };
        let v = run(&[], feature, &samples);
        assert_eq!(v[0], 0.0, "rate starts at zero");
        let last = *v.last().unwrap();
        // Lags are stored in difference form; at 200 Hz the steady-state rounding of the same update
        // repeated leaves 1.5e-4 relative (measured), far below any thermometer noise.
        assert!(
            (last - 3.0).abs() < 1e-3,
            "dt {dt}: rate {last} vs 3 °C/min"
        );
    }
}

#[test]
fn rate_of_a_constant_is_zero() {
    let samples: Vec<(&[f32], f32)> = vec![(&[5.0f32][..], 1.0); 50];
    assert!(run(&[], "rate(x)", &samples).iter().all(|v| *v == 0.0));
}

#[test]
fn hysteresis_holds_its_state() {
    let xs = [0.0f32, 0.02, 0.2, 0.0, -0.04, -0.3, -0.01, 0.04, 0.06];
    let expect = [0.0f32, 0.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, 1.0];
    let rows: Vec<[f32; 1]> = xs.iter().map(|x| [*x]).collect();
    let samples: Vec<(&[f32], f32)> = rows.iter().map(|x| (&x[..], 1.0)).collect();
    assert_eq!(run(&[], "hyst(x, 0.05)", &samples), expect);
}

#[test]
fn named_signals_are_shared_and_reused() {
    let mut b = B::new();
    b.line("T = mean(ta, tc, ts)").unwrap();
    b.line("G = ta - ts").unwrap();
    b.feature("T").unwrap();
    b.feature("T * G").unwrap();
    let p = b.finish().unwrap();
    assert_eq!(p.inputs.as_slice(), &["ta", "tc", "ts"]);
    assert_eq!(p.signals.len(), 2);
    let mut st = ProgramState::<48>::new();
    st.step(&p, &[3.0, 6.0, 0.0], 1.0).unwrap();
    let mut out = [0.0; 8];
    st.features(&p, &mut out).unwrap();
    assert_eq!(out[0], 3.0);
    assert_eq!(out[1], 9.0);
}

#[test]
fn constants_fold_without_touching_signals() {
    let mut b = B::new();
    b.line("K = 5").unwrap();
    b.feature("K * 2").unwrap();
    b.feature("-2 * 3 + x").unwrap();
    let p = b.finish().unwrap();
    let mut st = ProgramState::<48>::new();
    st.step(&p, &[1.0], 1.0).unwrap();
    let mut out = [0.0; 8];
    st.features(&p, &mut out).unwrap();
    assert_eq!(&out[..2], &[10.0, -5.0]);
}

#[test]
fn bad_samples_leave_the_state_untouched() {
    let mut b = B::new();
    b.feature("lag(x, 10)").unwrap();
    let p = b.finish().unwrap();
    let mut st = ProgramState::<48>::new();
    st.step(&p, &[1.0], 1.0).unwrap();
    let before = st.clone();
    assert_eq!(
        st.step(&p, &[f32::NAN], 1.0),
        Err(StepError::NonFiniteInput { index: 0 })
    );
    assert_eq!(st.step(&p, &[2.0], 0.0), Err(StepError::BadTimeStep));
    assert_eq!(
        st.step(&p, &[], 1.0),
        Err(StepError::MissingInput { index: 0 })
    );
    assert_eq!(format!("{st:?}"), format!("{before:?}"));
}

#[test]
fn division_by_zero_is_reported_not_propagated_into_filters() {
    let mut b = B::new();
    b.feature("x / y").unwrap();
    b.feature("lag(x / y, 10)").unwrap();
    let p = b.finish().unwrap();
    let mut st = ProgramState::<48>::new();
    let mut out = [0.0; 8];
    st.step(&p, &[1.0, 1.0], 1.0).unwrap();
    st.step(&p, &[1.0, 0.0], 1.0).unwrap();
    assert_eq!(
        st.features(&p, &mut out),
        Err(StepError::NonFiniteFeature { feature: 0 })
    );
    st.step(&p, &[1.0, 1.0], 1.0).unwrap();
    st.features(&p, &mut out).unwrap();
    assert_eq!(out[1], 1.0, "the lag held through the bad value");
}
