//! Gaps in the samples: `lag` and `rate` carried across exactly for an input that moved linearly,
//! `hyst` holding, long gaps restarting the filters (and saying so), `warmup`'s clock counting on.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use proptest::prelude::*;
use tcomp_core::stream::{RESET_AFTER_TIME_CONSTANTS, gap_resets};
use tcomp_core::{Channel, Program, ProgramBuilder, ProgramState, Real};

/// A filter of a filter (`rate(lag(x, τ))`) is left out: its operand is not linear across the gap
/// even where `x` is, and the gap code assumes each filter's own operand is (see `eval`).
const FEATURES: &str = "lag(x, TAU)|rate(x, WIN)|lag(x, WIN) - x|hyst(rate(x), 0.2)";

fn program<S: Real>(tau: f64, window: f64) -> Program<'static, 16, 4, S> {
    let mut b = ProgramBuilder::<16, 4, S>::new();
    for f in FEATURES.split('|') {
        let text = f
            .replace("TAU", &tau.to_string())
            .replace("WIN", &window.to_string());
        b.feature(Box::leak(text.into_boxed_str())).unwrap();
    }
    b.finish().unwrap()
}

fn features<S: Real>(st: &ProgramState<16, S>, p: &Program<'_, 16, 4, S>) -> [S; 4] {
    let mut out = [S::ZERO; 4];
    st.features(p, &mut out).unwrap();
    out
}

/// A wandering history: a slow sine, a ramp and a wobble (not linear, so the state is not trivial).
fn history(n: usize, phase: f64) -> f64 {
    let t = n as f64;
    20.0 + 3.0 * (t / 170.0 + phase).sin() + 0.01 * t + 0.3 * (t / 13.0).cos()
}

/// Runs `before` samples, a gap of `k` steps (input linear across it), then `after` samples, once
/// sample by sample and once with the gap; returns both feature series after the gap.
fn both_runs<S: Real>(
    tau: f64,
    window: f64,
    before: usize,
    k: usize,
    slope: f64,
    phase: f64,
) -> (Vec<[S; 4]>, Vec<[S; 4]>) {
    let p = program::<S>(tau, window);
    let dt: f32 = 0.5;
    // Inputs on a 2⁻¹² grid, so that the ramp across the gap is exactly linear in f32 as in f64.
    let grid = |v: f64| (v * 4096.0).round() / 4096.0;
    let (base, slope) = (grid(history(before - 1, phase)), grid(slope));
    let x_at = |n: usize| {
        if n < before {
            grid(history(n, phase))
        } else {
            base + slope * (n + 1 - before) as f64
        }
    };
    let mut full = ProgramState::<16, S>::new();
    let mut gappy = ProgramState::<16, S>::new();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for n in 0..before {
        let x = [S::from_f32(x_at(n) as f32)];
        full.step(&p, &x, S::from_f32(dt)).unwrap();
        gappy.step(&p, &x, S::from_f32(dt)).unwrap();
    }
    // The gap: the sample-by-sample run sees the k − 1 samples the gappy one lost.
    let last = before + k - 1;
    for n in before..=last {
        full.step(&p, &[S::from_f32(x_at(n) as f32)], S::from_f32(dt))
            .unwrap();
    }
    let x = [S::from_f32(x_at(last) as f32)];
    gappy.step_gap(&p, &x, S::from_f32(k as f32 * dt)).unwrap();
    a.push(features(&full, &p));
    b.push(features(&gappy, &p));
    for n in last + 1..last + 50 {
        let x = [S::from_f32(x_at(n) as f32)];
        full.step(&p, &x, S::from_f32(dt)).unwrap();
        gappy.step(&p, &x, S::from_f32(dt)).unwrap();
        a.push(features(&full, &p));
        b.push(features(&gappy, &p));
    }
    (a, b)
}

/// Compares the three filter features (lag, rate, lag difference). Not the fourth, `hyst` of the
/// rate: a relay. The rate of an arbitrary history relaxing to the slope across the gap need not be
/// monotone, so the gap-free run can switch on a transient inside the gap that the sample after it
/// never sees (a proptest case found one); the relay after a gap acts on the carried rate, as
/// `hysteresis_keeps_its_state_across_a_gap` checks.
fn assert_close<S: Real + Into<f64>>(a: &[[S; 4]], b: &[[S; 4]], tol: f64, what: &str) {
    for (n, (ra, rb)) in a.iter().zip(b).enumerate() {
        for k in 0..3 {
            let (x, y): (f64, f64) = (ra[k].into(), rb[k].into());
            assert!(
                (x - y).abs() <= tol * (1.0 + x.abs()),
                "{what}: sample {n} after the gap, feature {k}: {x} vs {y}"
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Where the input was linear across the gap, the filters after it are the gap-free run's
    /// (see [`assert_close`] for the relay).
    #[test]
    fn a_gap_over_a_linear_input_is_the_gap_free_run(
        tau in 5.0f64..3000.0,
        window in 10.0f64..600.0,
        before in 20usize..400,
        k in 2usize..400,
        slope in -0.05f64..0.05,
        phase in 0.0f64..6.0,
    ) {
        prop_assume!(!gap_resets(&program::<f64>(tau, window), k as f64 * 0.5));
        let (a, b) = both_runs::<f64>(tau, window, before, k, slope, phase);
        assert_close(&a, &b, 1e-9, "f64");
        let (a, b) = both_runs::<f32>(tau, window, before, k, slope, phase);
        assert_close(&a, &b, 2e-4, "f32");
    }
}

/// Resetting at the gap, as before, is measurably wrong on the same input: the property above is
/// not met by any behaviour.
#[test]
fn restarting_at_the_gap_is_not_the_gap_free_run() {
    let p = program::<f64>(600.0, 120.0);
    let (a, _) = both_runs::<f64>(600.0, 120.0, 300, 200, 0.01, 1.0);
    let mut st = ProgramState::<16, f64>::new();
    st.step(&p, &[history(299, 1.0) + 0.01 * 200.0], 0.5)
        .unwrap();
    let restarted = features(&st, &p);
    assert!(
        (restarted[0] - a[0][0]).abs() > 0.5,
        "{restarted:?} {:?}",
        a[0]
    );
    assert!(
        (restarted[1] - a[0][1]).abs() > 0.3,
        "{restarted:?} {:?}",
        a[0]
    );
}

/// Off the nominal grid (a gap that is not a whole number of steps) the lag is the continuous
/// first-order system's exact response to a linear input, to O(δ/τ).
#[test]
fn a_gap_off_the_grid_is_the_continuous_response() {
    let mut b = ProgramBuilder::<4, 1, f64>::new();
    b.feature("lag(x, 100)").unwrap();
    let p = b.finish().unwrap();
    let mut st = ProgramState::<4, f64>::new();
    // Steady on a ramp of 0.02/s: the lag's error is s·τ (to O(δ/τ)).
    let mut x = 0.0;
    for _ in 0..5000 {
        x += 0.02 * 0.1;
        st.step(&p, &[x], 0.1).unwrap();
    }
    let e0 = x - st.value(p.features[0] as usize);
    let gap = 73.37;
    let x1 = x - 1.5; // the input turned and fell 1.5 over the gap
    st.step_gap(&p, &[x1], gap).unwrap();
    let s = (x1 - x) / gap;
    let d = (-gap / 100.0f64).exp();
    let want = x1 - (d * e0 + s * 100.0 * (1.0 - d));
    let got = st.value(p.features[0] as usize);
    assert!((got - want).abs() < 2e-3, "{got} vs {want}");
}

#[test]
fn long_gaps_restart_the_filters_and_are_told() {
    let p = program::<f32>(120.0, 60.0);
    assert_eq!(p.longest_time_constant(), 120.0);
    let limit = RESET_AFTER_TIME_CONSTANTS * 120.0;
    assert!(!gap_resets(&p, limit));
    assert!(gap_resets(&p, limit * 1.001));
    let mut st = ProgramState::<16>::new();
    for n in 0..400 {
        st.step(&p, &[history(n, 0.0) as f32], 1.0).unwrap();
    }
    st.step_gap(&p, &[31.0], limit * 2.0).unwrap();
    let f = features(&st, &p);
    assert_eq!(f[0], 31.0, "lag restarted at its input");
    assert_eq!(f[1], 0.0, "rate restarted at 0");
    assert_eq!(f[3], 0.0, "hyst restarted");
    // A program without lag or rate carries every gap.
    let mut b = ProgramBuilder::<4, 1>::new();
    b.feature("hyst(x, 1)").unwrap();
    assert!(!gap_resets(&b.finish().unwrap(), 1e9));
}

#[test]
fn hysteresis_keeps_its_state_across_a_gap() {
    let mut b = ProgramBuilder::<4, 1>::new();
    b.feature("hyst(x, 1)").unwrap();
    let p = b.finish().unwrap();
    let mut st = ProgramState::<4>::new();
    st.step(&p, &[2.0], 1.0).unwrap();
    st.step(&p, &[0.5], 1.0).unwrap();
    st.step_gap(&p, &[0.0], 100.0).unwrap();
    assert_eq!(st.value(p.features[0] as usize), 1.0);
}

/// The board's way: `Channel::skip` of the missed periods, then an ordinary step, is
/// `ProgramState::step_gap`; a step without a skip is an ordinary one.
#[test]
fn a_channel_skip_is_a_gap() {
    use tcomp_core::testing::{example_model, example_sample, rlg_program};
    let period = 0.005;
    let model = example_model::<16, 4, 16>(8, 3);
    let p = rlg_program::<16, 4>();
    let mut ch = Channel::<16, 4>::new(period);
    ch.prepare(&model);
    let mut st = ProgramState::<16>::new();
    st.prepare(&p, period);
    for n in 0..20_000 {
        let (x, raw) = example_sample(n, period);
        ch.step(Some(&model), &x, raw);
        st.step(&p, &x, period).unwrap();
    }
    let mut gap_free = Channel::<16, 4>::new(period);
    gap_free.prepare(&model);
    for n in 0..20_100 {
        let (x, raw) = example_sample(n, period);
        gap_free.step(Some(&model), &x, raw);
    }
    let mut carried = 0.0;
    for n in 20_003..20_100 {
        let (x, raw) = example_sample(n, period);
        if n == 20_003 {
            ch.skip(3.0 * period);
            st.step_gap(&p, &x, 4.0 * period).unwrap();
        } else {
            st.step(&p, &x, period).unwrap();
        }
        ch.step(Some(&model), &x, raw);
        assert_eq!(ch.features(), &features(&st, &p), "sample {n}");
        carried = ch.features()[1];
    }
    // The rate came through the gap without a restart transient.
    let want = gap_free.features()[1];
    assert!(
        (carried - want).abs() < 1e-3 * want.abs(),
        "{carried} vs {want}"
    );
}
