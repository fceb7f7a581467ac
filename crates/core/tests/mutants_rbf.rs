//! The RBF evaluator on small hand-made models whose output is known in closed form, the stored
//! form's conversions, the cutoff at its exact boundary, and each rule of `Rbf::validate`.
//! Written to kill what `cargo mutants` found untested in `rbf.rs`.
#![allow(clippy::unwrap_used, missing_docs)]

use tcomp_core::fastexp::{EVAL_CUTOFF, EXP_CUTOFF, exp_neg};
use tcomp_core::point::Point;
use tcomp_core::rbf::RbfError;
use tcomp_core::{Center, Rbf};

/// Two features, offset (1, −2), scale (0.5, 2), linear (0.3, −0.1), bias 0.7, and two Gaussians:
/// at (0, 0) with γ = 0.5, w = 1.2 and at (1, −0.5) with γ = 2, w = −0.4.
fn model() -> Rbf<4, 3> {
    let mut r = Rbf::<4, 3> {
        n_features: 2,
        offset: Point([1.0, -2.0, 0.0]),
        scale: Point([0.5, 2.0, 0.0]),
        linear: Point([0.3, -0.1, 0.0]),
        bias: 0.7,
        ..Rbf::default()
    };
    r.centers
        .push(Center::from_natural(&[0.0, 0.0], 0.5, 1.2))
        .unwrap();
    r.centers
        .push(Center::from_natural(&[1.0, -0.5], 2.0, -0.4))
        .unwrap();
    r.validate().unwrap();
    r
}

/// The same model in f64, straight from its definition.
fn exact(xg: [f64; 2], xl: [f64; 2]) -> f64 {
    let z = |x: [f64; 2]| [(x[0] - 1.0) * 0.5, (x[1] + 2.0) * 2.0];
    let (zg, zl) = (z(xg), z(xl));
    let d2 = |c: [f64; 2]| (zg[0] - c[0]).powi(2) + (zg[1] - c[1]).powi(2);
    0.7 + 0.3 * zl[0] - 0.1 * zl[1] + 1.2 * (-0.5 * d2([0.0, 0.0])).exp()
        - 0.4 * (-2.0 * d2([1.0, -0.5])).exp()
}

const POINTS: [[f32; 2]; 6] = [
    [1.0, -2.0],
    [3.0, -2.25],
    [-0.5, -1.5],
    [2.0, -2.0],
    [9.0, 1.0],
    [-7.0, -4.0],
];

#[test]
fn normalise_subtracts_the_offset_then_scales() {
    let r = model();
    assert_eq!(r.normalise(&[3.0, -1.0, 5.0]), [1.0, 2.0, 0.0]);
    assert_eq!(r.normalise(&[1.0, -2.0, 0.0]), [0.0, 0.0, 0.0]);
}

#[test]
fn eval_is_the_closed_form() {
    let r = model();
    for x in POINTS {
        let xd = [x[0] as f64, x[1] as f64];
        let got = r.eval(&[x[0], x[1], 0.0]) as f64;
        assert!((got - exact(xd, xd)).abs() < 2e-6, "{x:?}: {got}");
    }
}

#[test]
fn eval_split_takes_the_gaussians_and_the_linear_term_at_their_own_points() {
    let r = model();
    for xg in POINTS {
        for xl in POINTS {
            let got = r.eval_split(&[xg[0], xg[1], 0.0], &[xl[0], xl[1], 0.0]) as f64;
            let want = exact([xg[0] as f64, xg[1] as f64], [xl[0] as f64, xl[1] as f64]);
            assert!(
                (got - want).abs() < 2e-6,
                "{xg:?} / {xl:?}: {got} vs {want}"
            );
        }
    }
}

#[test]
fn a_center_exactly_at_the_cutoff_contributes_nothing() {
    // u = p + g·‖z‖² + q·z = EVAL_CUTOFF at z = 0: skipped, as `exp_neg(EXP_CUTOFF)` is 0. A huge
    // weight makes the 2e-9 that it would otherwise add visible.
    let mut r = Rbf::<1, 1> {
        n_features: 1,
        scale: Point([1.0]),
        ..Rbf::default()
    };
    r.centers
        .push(Center {
            p: EVAL_CUTOFF,
            q: Point([0.0]),
            g: 1.0,
            w: 1e9,
        })
        .unwrap();
    r.validate().unwrap();
    assert_eq!(r.eval(&[0.0]), 0.0);
    assert_eq!(r.eval_split(&[0.0], &[0.0]), 0.0);
    // Half an eval unit inside the cutoff it counts: 1e9·e^(−20 + 0.5/23.083) ≈ 2.106.
    r.centers[0].p = EVAL_CUTOFF - 0.5;
    let inside = r.eval(&[0.0]);
    assert!((inside - 2.106).abs() < 0.005, "{inside}");
    assert_eq!(Rbf::<1, 1>::cutoff(), EXP_CUTOFF);
    assert_eq!(exp_neg(Rbf::<1, 1>::cutoff()), 0.0);
}

#[test]
fn unused_features_are_positive_zeros_in_the_stored_form() {
    let c = Center::<4>::from_natural(&[0.5, 0.0, -0.25, 0.0], 2.0, 1.0);
    assert_eq!(c.q.0[1].to_bits(), 0, "a zero coordinate is +0, not −0");
    assert_eq!(c.q.0[3].to_bits(), 0);
    assert!(c.q.0[0] < 0.0 && c.q.0[2] > 0.0);
    // p = g·‖c‖², g = γ·16·log2(e).
    let g = 2.0 * 16.0 * std::f64::consts::LOG2_E;
    assert!((c.g as f64 - g).abs() < 1e-5 * g);
    assert!((c.p as f64 - g * 0.3125).abs() < 1e-5 * g);
    assert!((c.q.0[0] as f64 + 2.0 * g * 0.5).abs() < 1e-5 * g);
}

#[test]
fn validate_checks_sizes() {
    let mut r = model();
    r.n_features = 3;
    r.validate().unwrap();
    r.n_features = 4;
    assert_eq!(r.validate(), Err(RbfError::Inconsistent("rbf.n_features")));
    r.n_features = 0;
    assert_eq!(r.validate(), Err(RbfError::Inconsistent("rbf.n_features")));
}

/// Makes one field of a valid model bad.
type Spoil = fn(&mut Rbf<4, 3>);

#[test]
fn validate_names_each_non_finite_field() {
    let cases: [(Spoil, &str); 7] = [
        (|r| r.offset.0[1] = f32::NAN, "rbf.offset"),
        (|r| r.scale.0[0] = f32::INFINITY, "rbf.scale"),
        (|r| r.linear.0[1] = f32::NAN, "rbf.linear"),
        (|r| r.bias = f32::NEG_INFINITY, "rbf.bias"),
        (|r| r.centers[1].p = f32::INFINITY, "rbf.centers"),
        (|r| r.centers[0].q.0[0] = f32::NAN, "rbf.centers"),
        (|r| r.centers[1].w = f32::NAN, "rbf.centers.w"),
    ];
    for (spoil, field) in cases {
        let mut r = model();
        spoil(&mut r);
        assert_eq!(r.validate(), Err(RbfError::NonFinite(field)), "{field}");
    }
    let mut r = model();
    r.centers[0].g = f32::INFINITY;
    assert_eq!(r.validate(), Err(RbfError::NonFinite("rbf.centers")));
}

#[test]
fn validate_wants_positive_widths_and_inert_unused_slots() {
    let inconsistent = |r: &Rbf<4, 3>| matches!(r.validate(), Err(RbfError::Inconsistent(_)));
    // A center at the origin has p = 0, which is fine.
    let mut r = model();
    assert_eq!(r.centers[0].p, 0.0);
    r.validate().unwrap();
    r.centers[0].g = 0.0;
    assert!(inconsistent(&r));
    let mut r = model();
    r.centers[1].g = -1.0;
    assert!(inconsistent(&r));
    let mut r = model();
    r.centers[1].p = -0.5;
    assert!(inconsistent(&r));
    // Entries past n_features must be zero in the scale, the linear term and every center.
    for k in 0..3 {
        let mut r = model();
        match k {
            0 => r.scale.0[2] = 1.0,
            1 => r.linear.0[2] = 1.0,
            _ => r.centers[1].q.0[2] = 1.0,
        }
        assert_eq!(
            r.validate(),
            Err(RbfError::Inconsistent(
                "rbf: entries past n_features must be zero"
            )),
            "slot kind {k}"
        );
    }
    // The offset of an unused slot is harmless (its scale is zero).
    let mut r = model();
    r.offset.0[2] = 5.0;
    r.validate().unwrap();
}
