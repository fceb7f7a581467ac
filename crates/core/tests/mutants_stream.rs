//! The streaming filters against an f64 transcription of their documented definitions (the table in
//! `program.rs`) on an irregular clock, the boundaries of `clamp` and `hyst`, the healing of a
//! filter whose first value was not finite, and the state's small accessors.
//! Written to kill what `cargo mutants` found untested in `stream.rs`.
#![allow(clippy::unwrap_used, missing_docs)]

use tcomp_core::{Program, ProgramBuilder, ProgramState, StepError};

type P = Program<'static, 48, 8>;

fn compile(lines: &[&'static str]) -> P {
    let mut b = ProgramBuilder::<'static, 48, 8>::new();
    for l in lines {
        b.line(l).unwrap();
    }
    b.finish().unwrap()
}

/// `lag(a, τ)` exactly as documented: `L[0] = a[0]`, `L[n] = L[n−1] + c·(a[n] − L[n−1])`,
/// `c = 1 − e^(−Δt/τ)`.
struct Lag {
    tau: f64,
    l: Option<f64>,
}

impl Lag {
    fn new(tau: f64) -> Self {
        Self { tau, l: None }
    }
    fn step(&mut self, a: f64, dt: f64) -> f64 {
        let l = match self.l {
            None => a,
            Some(l) => l + (1.0 - (-dt / self.tau).exp()) * (a - l),
        };
        self.l = Some(l);
        l
    }
}

/// `rate(a, w)` as documented: lags `L1` of `a` and `L2` of `L1` with `τ = w/2`, and
/// `60·(L1 − L2)·(e^(Δt/τ) − 1)/Δt`; 0 on the first sample.
struct Rate {
    l1: Lag,
    l2: Lag,
    first: bool,
}

impl Rate {
    fn new(window: f64) -> Self {
        Self {
            l1: Lag::new(window / 2.0),
            l2: Lag::new(window / 2.0),
            first: true,
        }
    }
    fn step(&mut self, a: f64, dt: f64) -> f64 {
        let l1 = self.l1.step(a, dt);
        let l2 = self.l2.step(l1, dt);
        if std::mem::take(&mut self.first) {
            return 0.0;
        }
        60.0 * (l1 - l2) * ((dt / self.l1.tau).exp() - 1.0) / dt
    }
}

#[test]
fn lags_and_rates_follow_their_definitions_on_an_irregular_clock() {
    let p = compile(&["lag(x, 7)", "rate(x, 20)", "rate(x)", "lag(lag(x, 3), 30)"]);
    let mut st = ProgramState::<48>::new();
    let (mut lag7, mut rate20, mut rate60) = (Lag::new(7.0), Rate::new(20.0), Rate::new(60.0));
    let (mut inner, mut outer) = (Lag::new(3.0), Lag::new(30.0));
    let steps = [0.5f32, 0.5, 1.0, 0.25, 2.0, 0.75];
    let mut t = 0.0f64;
    let mut out = [0.0f32; 8];
    for n in 0..400usize {
        let dt = steps[n % steps.len()];
        if n > 0 {
            t += dt as f64;
        }
        // A slow swing, a step at 60 s and a ramp from 150 s: every filter sees a transient.
        let x = 20.0
            + 3.0 * (0.05 * t).sin()
            + if t > 60.0 { 0.5 } else { 0.0 }
            + (t - 150.0).max(0.0) * 0.02;
        let xf = x as f32;
        st.step(&p, &[xf], dt).unwrap();
        st.features(&p, &mut out).unwrap();
        let x = xf as f64;
        let dt = dt as f64;
        let expect = [
            lag7.step(x, dt),
            rate20.step(x, dt),
            rate60.step(x, dt),
            outer.step(inner.step(x, dt), dt),
        ];
        for (k, (got, want)) in out.iter().zip(expect).enumerate() {
            assert!(
                (*got as f64 - want).abs() < 2e-4,
                "sample {n}, feature {k}: {got} vs {want}"
            );
        }
    }
}

#[test]
fn clamp_limits_on_both_sides() {
    let p = compile(&["clamp(x, -1, 2)"]);
    let mut st = ProgramState::<48>::new();
    let mut out = [0.0f32; 8];
    for (x, want) in [
        (-5.0f32, -1.0f32),
        (-1.0, -1.0),
        (0.5, 0.5),
        (2.0, 2.0),
        (7.0, 2.0),
    ] {
        st.step(&p, &[x], 1.0).unwrap();
        st.features(&p, &mut out).unwrap();
        assert_eq!(out[0], want, "clamp({x})");
    }
}

#[test]
fn hysteresis_holds_at_exactly_its_threshold() {
    let p = compile(&["hyst(x, 0.25)"]);
    let mut st = ProgramState::<48>::new();
    let mut out = [0.0f32; 8];
    let xs = [0.25f32, 0.3, 0.25, -0.25, -0.2, -0.3, -0.25, 0.25, 0.0];
    let want = [0.0f32, 1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, -1.0];
    for (x, w) in xs.iter().zip(want) {
        st.step(&p, &[*x], 1.0).unwrap();
        st.features(&p, &mut out).unwrap();
        assert_eq!(out[0], w, "hyst({x})");
    }
}

#[test]
fn a_filter_whose_first_value_is_not_finite_restarts_on_the_next() {
    let p = compile(&["x / y", "rate(x / y)", "lag(x / y, 5)"]);
    let mut st = ProgramState::<48>::new();
    let mut out = [0.0f32; 8];
    st.step(&p, &[1.0, 0.0], 1.0).unwrap();
    assert_eq!(
        st.features(&p, &mut out),
        Err(StepError::NonFiniteFeature { feature: 0 })
    );
    // The next finite value starts both filters afresh, as a first sample would.
    st.step(&p, &[3.0, 1.0], 1.0).unwrap();
    st.features(&p, &mut out).unwrap();
    assert_eq!(&out[..3], &[3.0, 0.0, 3.0]);
    st.step(&p, &[3.0, 1.0], 1.0).unwrap();
    st.features(&p, &mut out).unwrap();
    assert_eq!(&out[..3], &[3.0, 0.0, 3.0]);
}

#[test]
fn a_rate_holds_through_a_non_finite_operand() {
    let p = compile(&["rate(x / y, 10)"]);
    let node = p.features[0] as usize;
    let mut st = ProgramState::<48>::new();
    let mut held = 0.0;
    for n in 0..30 {
        let x = n as f32 * 0.5;
        let y = if n == 20 { 0.0 } else { 1.0 };
        st.step(&p, &[x, y], 1.0).unwrap();
        let v = st.value(node);
        assert!(v.is_finite(), "sample {n}");
        if n == 20 {
            assert_eq!(v, held, "the rate is held, not poisoned");
        }
        held = v;
    }
    // A ramp of 0.5 per sample, one sample lost: well on its way back to 30 per minute.
    assert!((held - 30.0).abs() < 3.0, "{held}");
}

#[test]
fn state_accessors_and_reset() {
    let p = compile(&["T = a + b", "T", "lag(T, 10)"]);
    let mut st = ProgramState::<48>::default();
    assert!(!st.started());
    st.step(&p, &[1.0, 2.0], 1.0).unwrap();
    assert!(st.started());
    // Nodes: a, b, T = a + b, lag.
    assert_eq!(
        [st.value(0), st.value(1), st.value(2), st.value(3)],
        [1.0, 2.0, 3.0, 3.0]
    );
    assert!(st.value(48).is_nan() && st.value(1000).is_nan());
    st.step(&p, &[11.0, 2.0], 1.0).unwrap();
    assert!(st.value(3) > 3.0 && st.value(3) < 13.0);
    st.reset();
    assert!(!st.started());
    // After a reset the next sample is a first sample: the lag starts at its input.
    st.step(&p, &[20.0, 2.0], 1.0).unwrap();
    assert_eq!(st.value(3), 22.0);
}

#[test]
fn the_time_step_must_be_positive_and_finite() {
    let p = compile(&["lag(x, 10)"]);
    let mut st = ProgramState::<48>::new();
    // The first sample's step is ignored.
    st.step(&p, &[1.0], f32::NAN).unwrap();
    for dt in [0.0f32, -1.0, f32::NAN, f32::INFINITY] {
        assert_eq!(st.step(&p, &[1.0], dt), Err(StepError::BadTimeStep), "{dt}");
    }
    st.step(&p, &[1.0], 1e-6).unwrap();
}

#[test]
fn every_step_error_names_its_place() {
    for (e, words) in [
        (StepError::MissingInput { index: 3 }, "input 3"),
        (StepError::NonFiniteInput { index: 4 }, "input 4"),
        (StepError::BadTimeStep, "time step"),
        (StepError::NonFiniteFeature { feature: 5 }, "feature 5"),
    ] {
        assert!(e.to_string().contains(words), "{e:?}: {e}");
    }
}
