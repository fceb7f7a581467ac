//! Logistic steps and powers (center kinds, blob format 4): a step evaluates to `w·S(a·z + b)` and
//! holds its level on both sides, a square and a cube to `w·(a·z + b)²` and `w·(a·z + b)³`, a model whose kinds are all Gaussian gives the masked model's bits, the
//! kinds round-trip through the blob (both decoders) while a model without steps keeps format 3,
//! every rule of the kinds' validation holds, and the plausibility bound covers a step.
#![allow(clippy::unwrap_used, missing_docs)]

mod trailing_support;

use tcomp_core::blob::{KINDS_SINCE, MASKS_SINCE};
use tcomp_core::point::Point;
use tcomp_core::rbf::{KIND_CUBE, KIND_GAUSSIAN, KIND_LAST, KIND_SQUARE, KIND_STEP, RbfError};
use tcomp_core::testing::example_model;
use tcomp_core::{BlobError, Center, HOST_CENTERS, HOST_FEATURES, HOST_NODES, HostModel, Rbf};

type R = Rbf<8, 2>;

/// A Gaussian over feature 0, a sharp and a wide step over feature 0 and a step over feature 1.
fn model() -> R {
    let mut r = R {
        n_features: 2,
        offset: Point([20.0, 28.0]),
        scale: Point([0.1, 2.0]),
        linear: Point([0.2, -0.1]),
        bias: 0.4,
        ..Rbf::default()
    };
    r.centers
        .push(Center::from_natural(&[0.3, 0.0], 0.7, 1.1))
        .unwrap();
    // S((z0 + 0.5)/0.05), S((z0 − 0.2)/0.8), S((z1 − 0.1)/0.3).
    for (a, b, w) in [
        ([20.0, 0.0], 10.0, -0.6),
        ([1.25, 0.0], -0.25, 0.9),
        ([0.0, -3.333_333], 0.333_333, 0.35),
    ] {
        r.centers.push(Center::step_from_natural(&a, b, w)).unwrap();
    }
    r.masks.extend([0b01, 0b01, 0b01, 0b10]);
    r.kinds
        .extend([KIND_GAUSSIAN, KIND_STEP, KIND_STEP, KIND_STEP]);
    r.validate().unwrap();
    r
}

fn logistic(u: f64) -> f64 {
    1.0 / (1.0 + (-u).exp())
}

fn exact(x: [f64; 2]) -> f64 {
    let z = [(x[0] - 20.0) * 0.1, (x[1] - 28.0) * 2.0];
    0.4 + 0.2 * z[0] - 0.1 * z[1] + 1.1 * (-0.7 * (z[0] - 0.3).powi(2)).exp()
        - 0.6 * logistic(20.0 * z[0] + 10.0)
        + 0.9 * logistic(1.25 * z[0] - 0.25)
        + 0.35 * logistic(-3.333_333 * z[1] + 0.333_333)
}

#[test]
fn a_step_is_a_logistic_that_holds_its_level() {
    let r = model();
    for t in [-60.0f32, -10.0, 14.0, 15.0, 16.0, 20.0, 27.5, 45.0, 200.0] {
        for v in [20.0f32, 27.9, 28.0, 28.3, 40.0] {
            let want = exact([f64::from(t), f64::from(v)]);
            let got = f64::from(r.eval(&[t, v]));
            assert!(
                (got - want).abs() < 2e-5 * want.abs().max(1.0),
                "({t}, {v}): {got} vs {want}"
            );
        }
    }
    // Far past a step both sides are its exact levels: the exponential is flushed to zero.
    let mut one = model();
    one.centers.truncate(2);
    one.masks.truncate(2);
    one.kinds.truncate(2);
    one.centers.remove(0);
    one.masks.remove(0);
    one.kinds.remove(0);
    one.linear = Point([0.0; 2]);
    one.bias = 0.0;
    assert_eq!(one.eval(&[-1.0e6, 0.0]), 0.0);
    assert_eq!(one.eval(&[1.0e6, 0.0]), -0.6f32);
    // At its center the step is half way.
    let mid = one.eval(&[15.0, 0.0]);
    assert!((mid + 0.3).abs() < 1e-5, "{mid}");
}

#[test]
fn powers_are_the_polynomial_of_their_feature() {
    let mut r = model();
    r.centers.clear();
    r.masks.clear();
    r.kinds.clear();
    // 0.3·(z0 − 0.5)² − 0.05·(2·z0)³ over feature 0 only.
    r.centers
        .push(Center::power_from_natural(&[1.0, 0.0], -0.5, 0.3))
        .unwrap();
    r.centers
        .push(Center::power_from_natural(&[2.0, 0.0], 0.0, -0.05))
        .unwrap();
    r.masks.extend([0b01, 0b01]);
    r.kinds.extend([KIND_SQUARE, KIND_CUBE]);
    r.validate().unwrap();
    for t in [-30.0f32, 0.0, 20.0, 27.0, 60.0] {
        for v in [26.0f32, 28.0, 31.0] {
            let z0 = (f64::from(t) - 20.0) * 0.1;
            let z1 = (f64::from(v) - 28.0) * 2.0;
            let want =
                0.4 + 0.2 * z0 - 0.1 * z1 + 0.3 * (z0 - 0.5).powi(2) - 0.05 * (2.0 * z0).powi(3);
            let got = f64::from(r.eval(&[t, v]));
            assert!(
                (got - want).abs() < 1e-5 * want.abs().max(1.0),
                "{got} vs {want}"
            );
        }
    }
    // A power's g must be 0 too.
    let mut bad = r.clone();
    bad.centers[1].g = 1.0;
    assert!(bad.validate().is_err());
}

#[test]
fn gaussian_kinds_give_the_masked_bits() {
    let mut masked = model();
    masked.centers.truncate(1);
    masked.masks.truncate(1);
    masked.kinds.clear();
    let mut kinded = masked.clone();
    kinded.kinds.push(KIND_GAUSSIAN).unwrap();
    kinded.validate().unwrap();
    for x in [[20.0f32, 28.0], [12.5, 27.0], [31.0, 29.5]] {
        assert_eq!(masked.eval(&x).to_bits(), kinded.eval(&x).to_bits());
        assert_eq!(
            masked.eval_split(&x, &[0.0, 30.0]).to_bits(),
            kinded.eval_split(&x, &[0.0, 30.0]).to_bits()
        );
    }
}

#[test]
fn kind_rules_are_enforced() {
    let bad = |f: &dyn Fn(&mut R)| {
        let mut r = model();
        f(&mut r);
        r.validate()
    };
    let incon = |e: Result<(), RbfError>, what: &str| matches!(e, Err(RbfError::Inconsistent(m)) if m.starts_with(what));
    assert!(incon(
        bad(&|r| {
            r.kinds.pop();
        }),
        "rbf.kinds"
    ));
    assert!(incon(bad(&|r| r.masks.clear()), "rbf.kinds"));
    assert!(incon(bad(&|r| r.kinds[1] = KIND_LAST + 1), "rbf.kinds"));
    // A step must have g = 0, a Gaussian g > 0 and p ≥ 0 (a step's p may be negative).
    assert!(incon(bad(&|r| r.centers[1].g = 1.0), "rbf.centers"));
    assert!(incon(bad(&|r| r.kinds[1] = KIND_GAUSSIAN), "rbf.centers"));
    assert!(matches!(
        bad(&|r| r.centers[2].w = f32::NAN),
        Err(RbfError::NonFinite(_))
    ));
}

/// A host model with half its centers turned into steps over feature 0, and one into a cube.
fn host_steps() -> HostModel<'static> {
    let mut m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(6, 7);
    for j in 0..m.rbf.centers.len() {
        let (c, gamma, w) = m.rbf.centers[j].to_natural();
        if j == 1 {
            let mut a = vec![0.0; HOST_FEATURES];
            a[1] = 0.5;
            m.rbf.centers[j] = Center::power_from_natural(&a, 0.1, w.into());
            m.rbf.kinds.push(KIND_CUBE).unwrap();
            m.rbf.masks.push(0b10).unwrap();
        } else if j % 2 == 0 {
            let mut a = vec![0.0; HOST_FEATURES];
            a[0] = 1.0 / f64::from(gamma).sqrt();
            m.rbf.centers[j] = Center::step_from_natural(&a, -a[0] * f64::from(c.0[0]), w.into());
            m.rbf.kinds.push(KIND_STEP).unwrap();
            m.rbf.masks.push(1).unwrap();
        } else {
            let all = (1u8 << m.n_features()) - 1;
            m.rbf.kinds.push(KIND_GAUSSIAN).unwrap();
            m.rbf.masks.push(all).unwrap();
        }
    }
    m.version = HostModel::version_for(&m.program, &m.rbf);
    m
}

#[test]
fn kinds_round_trip_through_both_decoders_as_format_4() {
    let m = host_steps();
    assert_eq!(m.version, KINDS_SINCE);
    trailing_support::round_trips_and_refuses_bad_trailing_fields(&m);
    // Steps on a format-3 model are refused rather than silently dropped.
    let mut old = m.clone();
    old.version = MASKS_SINCE;
    assert!(matches!(
        old.encode(&mut vec![0u8; 8192]),
        Err(BlobError::Inconsistent(_))
    ));
}

#[test]
fn the_plausibility_bound_covers_steps() {
    let m = host_steps();
    let b = m.bound().unwrap();
    // Every evaluation in the range box stays under the bound.
    let nf = m.n_features();
    for i in 0..2000u32 {
        let mut x = [0.0f32; HOST_FEATURES];
        for (k, xk) in x.iter_mut().enumerate().take(nf) {
            let r = m.ranges[k];
            let t = ((i * 7919 + 31 * k as u32) % 1000) as f32 / 999.0;
            *xk = r.lo + t * (r.hi - r.lo);
        }
        assert!(m.rbf.eval(&x).abs() <= b.correction);
    }
    // A step whose exponent can overflow is refused, and a cube that can.
    let mut huge = m.clone();
    let j = huge.rbf.kinds.iter().position(|k| *k == KIND_STEP).unwrap();
    huge.rbf.centers[j].q.0[0] = 3.0e38;
    assert!(matches!(huge.validate(), Err(BlobError::Implausible(_))));
    let mut cube = m.clone();
    cube.rbf.centers[1].q.0[1] = 1.0e14;
    assert!(matches!(cube.validate(), Err(BlobError::Implausible(_))));
}
