//! The stand-alone filters (`eval::{Lag, Rate, Hyst}`, which the simulator's effects use in f64)
//! are the feature program's operations: stepped over the same samples they give the same values,
//! bit for bit, in f64 and in f32.
#![allow(clippy::unwrap_used, missing_docs)]

use tcomp_core::eval::{Hyst, Lag, Rate};
use tcomp_core::{ProgramBuilder, ProgramState, Real};

/// A temperature-like stream with a changing step: ramps, a hold, a jump.
fn samples<S: Real>() -> Vec<(S, S)> {
    (0..3000)
        .map(|n| {
            let t = n as f32;
            let x = 20.0 + 0.05 * t - if n > 1500 { 0.08 * (t - 1500.0) } else { 0.0 };
            let dt = if n % 700 < 350 { 1.0 } else { 0.5 };
            (S::from_f32(x), S::from_f32(dt))
        })
        .collect()
}

fn program_values<S: Real>(feature: &'static str) -> Vec<S> {
    let mut b = ProgramBuilder::<8, 1, S>::new();
    b.feature(feature).unwrap();
    let p = b.finish().unwrap();
    let mut st = ProgramState::<8, S>::new();
    let node = p.features[0] as usize;
    samples::<S>()
        .into_iter()
        .map(|(x, dt)| {
            st.step(&p, &[x], dt).unwrap();
            st.value(node)
        })
        .collect()
}

fn check<S: Real>() {
    let mut lag = Lag::new(S::from_f32(120.0));
    let mut rate = Rate::new(S::from_f32(240.0));
    let mut hyst = Hyst::new(S::from_f32(1.0));
    let mut inner = Rate::new(S::from_f32(60.0));
    let (mut l, mut r, mut h) = (Vec::new(), Vec::new(), Vec::new());
    for (x, dt) in samples::<S>() {
        l.push(lag.step(x, dt));
        r.push(rate.step(x, dt));
        h.push(hyst.step(inner.step(x, dt)));
    }
    assert_eq!(l, program_values::<S>("lag(x, 120)"));
    assert_eq!(r, program_values::<S>("rate(x, 240)"));
    assert_eq!(h, program_values::<S>("hyst(rate(x), 1)"));
    assert!(
        h.contains(&S::ONE) && h.contains(&-S::ONE),
        "the hysteresis switched both ways"
    );
}

#[test]
fn filters_are_the_programs_operations_in_f64() {
    check::<f64>();
}

#[test]
fn filters_are_the_programs_operations_in_f32() {
    check::<f32>();
}

#[test]
fn f64_and_f32_programs_agree_to_f32_rounding() {
    let (a, b) = (
        program_values::<f64>("lag(x, 120) - x"),
        program_values::<f32>("lag(x, 120) - x"),
    );
    for (x, y) in a.iter().zip(&b) {
        assert!((x - f64::from(*y)).abs() < 1e-3, "{x} vs {y}");
    }
    assert_ne!(
        a.iter().map(|v| *v as f32).collect::<Vec<_>>(),
        b,
        "f64 is not f32"
    );
}
