//! Additive models (per-center feature masks, blob format 3): the masked evaluation is the sum of
//! one-group models, a full mask gives the unmasked bits, the masks round-trip through the blob
//! (both decoders) and a blob without masks keeps its older version and bytes, and every rule of
//! the masks' validation and of the plausibility bound holds.
#![allow(clippy::unwrap_used, missing_docs)]

mod trailing_support;

use tcomp_core::blob::{FORMAT_VERSION, MASKS_SINCE};
use tcomp_core::point::Point;
use tcomp_core::rbf::RbfError;
use tcomp_core::testing::example_model;
use tcomp_core::{BlobError, Center, HOST_CENTERS, HOST_FEATURES, HOST_NODES, HostModel, Rbf};

type R = Rbf<8, 3>;

fn base() -> R {
    R {
        n_features: 3,
        offset: Point([20.0, 0.0, 5.0]),
        scale: Point([0.1, 2.0, 4.0]),
        linear: Point([0.2, -0.1, 0.05]),
        bias: 0.4,
        ..Rbf::default()
    }
}

/// A center over the features in `mask` at `c` (natural units; entries outside the mask unused).
fn center(mask: u8, c: [f64; 3], gamma: f64, w: f64) -> Center<3> {
    let masked: Vec<f64> = (0..3)
        .map(|k| if mask >> k & 1 == 1 { c[k] } else { 0.0 })
        .collect();
    Center::from_natural(&masked, gamma, w)
}

/// Thermal group {0, 1} (two centers) plus a one-dimensional group {2} (two centers).
fn additive() -> R {
    let mut r = base();
    for (m, c, g, w) in [
        (0b011, [0.3, -0.2, 0.0], 0.7, 1.1),
        (0b011, [-0.5, 0.4, 0.0], 1.3, -0.6),
        (0b100, [0.0, 0.0, 0.8], 0.9, 0.35),
        (0b100, [0.0, 0.0, -1.1], 2.0, -0.25),
    ] {
        r.centers.push(center(m, c, g, w)).unwrap();
        r.masks.push(m).unwrap();
    }
    r.validate().unwrap();
    r
}

fn exact(x: [f64; 3]) -> f64 {
    let z = [(x[0] - 20.0) * 0.1, x[1] * 2.0, (x[2] - 5.0) * 4.0];
    let g = |d2: f64, gamma: f64| (-gamma * d2).exp();
    0.4 + 0.2 * z[0] - 0.1 * z[1]
        + 0.05 * z[2]
        + 1.1 * g((z[0] - 0.3).powi(2) + (z[1] + 0.2).powi(2), 0.7)
        - 0.6 * g((z[0] + 0.5).powi(2) + (z[1] - 0.4).powi(2), 1.3)
        + 0.35 * g((z[2] - 0.8).powi(2), 0.9)
        - 0.25 * g((z[2] + 1.1).powi(2), 2.0)
}

const POINTS: [[f32; 3]; 5] = [
    [20.0, 0.0, 5.0],
    [25.0, -0.1, 5.2],
    [12.0, 0.3, 4.6],
    // The third input far outside anything the thermal group saw: its Gaussians do not fade.
    [23.0, -0.1, 9.0],
    [-10.0, 1.0, 0.0],
];

#[test]
fn masked_evaluation_is_the_sum_of_the_groups() {
    let r = additive();
    for x in POINTS {
        let want = exact(x.map(f64::from));
        let got = r.eval(&x) as f64;
        assert!(
            (got - want).abs() < 2e-5 * want.abs().max(1.0),
            "{x:?}: {got} vs {want}"
        );
    }
    // Far along the third input the thermal group's contribution is exactly what it is at its
    // nominal value: the masked distance does not see it.
    let mut thermal = additive();
    thermal.centers.truncate(2);
    thermal.masks.truncate(2);
    thermal.linear = Point([0.0; 3]);
    thermal.bias = 0.0;
    assert_eq!(
        thermal.eval(&[23.0, -0.1, 9.0]),
        thermal.eval(&[23.0, -0.1, 5.0])
    );
    assert!(thermal.eval(&[23.0, -0.1, 500.0]).abs() > 0.1);
}

#[test]
fn a_full_mask_gives_the_unmasked_bits() {
    let mut plain = base();
    for (c, g, w) in [([0.3, -0.2, 0.5], 0.7, 1.1), ([-0.5, 0.4, -0.9], 1.3, -0.6)] {
        plain.centers.push(center(0b111, c, g, w)).unwrap();
    }
    let mut masked = plain.clone();
    masked.masks.extend([0b111, 0b111]);
    masked.validate().unwrap();
    for x in POINTS {
        assert_eq!(plain.eval(&x).to_bits(), masked.eval(&x).to_bits(), "{x:?}");
        assert_eq!(
            plain.eval_split(&x, &[0.0, 0.1, 7.0]).to_bits(),
            masked.eval_split(&x, &[0.0, 0.1, 7.0]).to_bits()
        );
    }
}

#[test]
fn mask_rules_are_enforced() {
    let bad = |f: &dyn Fn(&mut R)| {
        let mut r = additive();
        f(&mut r);
        r.validate()
    };
    let incon = |e: Result<(), RbfError>| matches!(e, Err(RbfError::Inconsistent(m)) if m.starts_with("rbf.masks"));
    assert!(incon(bad(&|r| {
        r.masks.pop();
    })));
    assert!(incon(bad(&|r| r.masks[0] = 0)));
    // Bit 3 names a feature past n_features.
    assert!(incon(bad(&|r| r.masks[0] = 0b1001)));
    // A center with q ≠ 0 outside its mask.
    assert!(incon(bad(&|r| r.masks[0] = 0b001)));
}

fn host_additive() -> HostModel<'static> {
    let mut m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(6, 7);
    // Split the centers into a group over feature 0 and a group over features 1..4.
    let nf = m.n_features();
    for j in 0..m.rbf.centers.len() {
        let (c, gamma, w) = m.rbf.centers[j].to_natural();
        let mask: u8 = if j % 2 == 0 {
            0b0001
        } else {
            ((1u8 << nf) - 1) & !1
        };
        let cm: Vec<f64> = (0..HOST_FEATURES)
            .map(|k| {
                if mask >> k & 1 == 1 {
                    c.0[k] as f64
                } else {
                    0.0
                }
            })
            .collect();
        m.rbf.centers[j] = Center::from_natural(&cm, gamma as f64, w as f64);
        m.rbf.masks.push(mask).unwrap();
    }
    m.version = HostModel::version_for(&m.program, &m.rbf);
    m
}

#[test]
fn masks_round_trip_through_both_decoders_as_format_3() {
    let m = host_additive();
    assert_eq!(m.version, MASKS_SINCE);
    const { assert!(MASKS_SINCE <= FORMAT_VERSION) };
    trailing_support::round_trips_and_refuses_bad_trailing_fields(&m);
}

#[test]
fn a_model_without_masks_keeps_its_version_and_bytes() {
    let m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(6, 7);
    assert!(m.version < MASKS_SINCE);
    let mut buf = vec![0u8; 8192];
    let n = m.encode(&mut buf).unwrap();
    // The bytes are the derived layout and nothing more: postcard of the model plus the CRC.
    let mut plain = vec![0u8; 8192];
    let used = postcard::to_slice(&m, &mut plain).unwrap().len();
    assert_eq!(&buf[..n - 4], &plain[..used]);
    // Masks on a format-1 model are refused rather than silently dropped.
    let mut a = host_additive();
    a.version = 1;
    assert!(matches!(
        a.encode(&mut buf),
        Err(BlobError::Inconsistent(_))
    ));
}

#[test]
fn the_plausibility_bound_leaves_out_features_outside_a_mask() {
    // A one-dimensional group's center: its exponent's lower bound must not include the other
    // features' (non-negative) squares, so the bound stays a bound where those features are large.
    let m = host_additive();
    let b = m.bound().unwrap();
    let (lo, hi) = m.range_points();
    let mut worst = f32::INFINITY;
    let mut state = 1u32;
    for _ in 0..2000 {
        let mut x = [0.0f32; HOST_FEATURES];
        for (k, xk) in x.iter_mut().enumerate().take(m.n_features()) {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            let t = (state >> 8) as f32 / (1u32 << 24) as f32;
            *xk = lo.0[k] + t * (hi.0[k] - lo.0[k]);
        }
        let out = m.rbf.eval(&x);
        assert!(out.is_finite());
        worst = worst.min(-out.abs());
    }
    assert!(-worst <= b.correction, "{} > {}", -worst, b.correction);
}
