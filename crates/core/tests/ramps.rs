//! Saturating ramps (center kind [`KIND_RAMP`], blob format 5): a ramp evaluates to
//! `w·clamp(a·z + b, −1, 1)` — straight between its corners, exactly its levels beyond them — a
//! model with one is stamped format 5 and round-trips through both decoders while a model with
//! steps only keeps format 4, a format-4 stamp on a ramp is refused, and the plausibility bound
//! covers ramps.
#![allow(clippy::unwrap_used, missing_docs)]

mod trailing_support;

use tcomp_core::blob::{KINDS_SINCE, RAMPS_SINCE};
use tcomp_core::point::Point;
use tcomp_core::rbf::{KIND_GAUSSIAN, KIND_RAMP, KIND_STEP};
use tcomp_core::testing::example_model;
use tcomp_core::{BlobError, Center, HOST_CENTERS, HOST_FEATURES, HOST_NODES, HostModel, Rbf};

type R = Rbf<8, 2>;

/// `0.4 + 0.2·z0 − 0.1·z1 + 0.9·clamp((z0 − 0.2)/0.8) − 0.35·clamp((z1 − 0.1)/0.3)`.
fn model() -> R {
    let mut r = R {
        n_features: 2,
        offset: Point([20.0, 28.0]),
        scale: Point([0.1, 2.0]),
        linear: Point([0.2, -0.1]),
        bias: 0.4,
        ..Rbf::default()
    };
    for (a, b, w) in [
        ([1.25, 0.0], -0.25, 0.9),
        ([0.0, 3.333_333], -0.333_333, -0.35),
    ] {
        r.centers
            .push(Center::power_from_natural(&a, b, w))
            .unwrap();
    }
    r.masks.extend([0b01, 0b10]);
    r.kinds.extend([KIND_RAMP, KIND_RAMP]);
    r.validate().unwrap();
    r
}

fn exact(x: [f64; 2]) -> f64 {
    let z = [(x[0] - 20.0) * 0.1, (x[1] - 28.0) * 2.0];
    0.4 + 0.2 * z[0] - 0.1 * z[1] + 0.9 * (1.25 * z[0] - 0.25).clamp(-1.0, 1.0)
        - 0.35 * (3.333_333 * z[1] - 0.333_333).clamp(-1.0, 1.0)
}

#[test]
fn a_ramp_is_straight_between_its_corners_and_level_beyond() {
    let r = model();
    for t in [-60.0f32, 13.0, 14.0, 18.0, 22.0, 29.9, 30.0, 45.0, 200.0] {
        for v in [20.0f32, 27.8, 28.0, 28.1, 28.2, 40.0] {
            let want = exact([f64::from(t), f64::from(v)]);
            let got = f64::from(r.eval(&[t, v]));
            assert!(
                (got - want).abs() < 1e-5 * want.abs().max(1.0),
                "({t}, {v}): {got} vs {want}"
            );
        }
    }
    // Alone, beyond its corners a ramp is exactly its two levels, and between them a line.
    let mut one = model();
    one.centers.truncate(1);
    one.masks.truncate(1);
    one.kinds.truncate(1);
    one.linear = Point([0.0; 2]);
    one.bias = 0.0;
    assert_eq!(one.eval(&[-1.0e6, 0.0]), -0.9f32);
    assert_eq!(one.eval(&[1.0e6, 0.0]), 0.9f32);
    assert_eq!(one.eval(&[11.0, 0.0]), -0.9f32);
    assert_eq!(one.eval(&[31.0, 0.0]), 0.9f32);
    let (a, b) = (one.eval(&[18.0, 0.0]), one.eval(&[24.0, 0.0]));
    assert!(((b - a) / 6.0 - 0.9 * 0.125).abs() < 1e-6, "{a} {b}");
    // The kind's rules: a ramp's g must be 0.
    let mut bad = model();
    bad.centers[0].g = 1.0;
    assert!(bad.validate().is_err());
}

/// A host model with a ramp, a step and Gaussians over its features.
fn host_ramps(with_ramp: bool) -> HostModel<'static> {
    let mut m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(6, 7);
    let all = (1u8 << m.n_features()) - 1;
    for j in 0..m.rbf.centers.len() {
        let (c, gamma, w) = m.rbf.centers[j].to_natural();
        let mut a = vec![0.0; HOST_FEATURES];
        a[0] = 1.0 / f64::from(gamma).sqrt();
        let b = -a[0] * f64::from(c.0[0]);
        let (center, kind, mask) = match j % 3 {
            0 if with_ramp => (Center::power_from_natural(&a, b, w.into()), KIND_RAMP, 1),
            1 => (Center::step_from_natural(&a, b, w.into()), KIND_STEP, 1),
            _ => (m.rbf.centers[j], KIND_GAUSSIAN, all),
        };
        m.rbf.centers[j] = center;
        m.rbf.kinds.push(kind).unwrap();
        m.rbf.masks.push(mask).unwrap();
    }
    m.version = HostModel::version_for(&m.program, &m.rbf);
    m
}

#[test]
fn ramps_round_trip_as_format_5_and_steps_alone_keep_format_4() {
    let m = host_ramps(true);
    assert_eq!(m.version, RAMPS_SINCE);
    trailing_support::round_trips_and_refuses_bad_trailing_fields(&m);
    assert_eq!(host_ramps(false).version, KINDS_SINCE);
    // A ramp stamped format 4 (which a format-4 reader would refuse as an unknown kind) is
    // refused by the writer.
    let mut old = m.clone();
    old.version = KINDS_SINCE;
    assert!(matches!(
        old.encode(&mut vec![0u8; 8192]),
        Err(BlobError::Inconsistent(_))
    ));
}

#[test]
fn the_plausibility_bound_covers_ramps() {
    let m = host_ramps(true);
    let b = m.bound().unwrap();
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
    // A ramp whose argument can overflow is refused.
    let mut huge = m.clone();
    let j = huge.rbf.kinds.iter().position(|k| *k == KIND_RAMP).unwrap();
    huge.rbf.centers[j].q.0[0] = 3.0e38;
    assert!(matches!(huge.validate(), Err(BlobError::Implausible(_))));
}
