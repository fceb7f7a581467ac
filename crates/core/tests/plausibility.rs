//! Model plausibility: blobs whose numbers are all valid but whose evaluation would overflow, or
//! whose Gaussians exceed 1 by more than rounding, are refused on encode and on decode, named.
#![allow(clippy::unwrap_used, clippy::panic, missing_docs)]

mod fuzz_support;

use fuzz_support::{HostModel, seal};
use tcomp_core::bound::MAX_CORRECTION;
use tcomp_core::testing::{example_model, example_sample};
use tcomp_core::{BlobError, Center, Channel, HOST_CENTERS, HOST_FEATURES, HOST_NODES, Status};

fn model() -> HostModel<'static> {
    example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(12, 31)
}

/// Refused by `encode` and, written with a valid CRC anyway, by `decode`; returns the reason.
fn refused(m: &HostModel<'static>) -> &'static str {
    let mut buf = vec![0u8; 8192];
    let on_encode = m.encode(&mut buf).unwrap_err();
    let blob = seal(m, &[]).unwrap();
    let on_decode = HostModel::decode(&blob).unwrap_err();
    assert_eq!(on_encode, on_decode);
    match on_decode {
        BlobError::Implausible(why) => why,
        e => panic!("expected an implausible model, got {e:?}"),
    }
}

#[test]
fn the_reviewers_blobs_are_refused() {
    // One center with q = 3.2e38 and g = 1e-7: the exponent overflows, the fast exponential gives NaN.
    let mut m = model();
    m.rbf.centers[0].q.0[0] = 3.2e38;
    m.rbf.centers[0].g = 1.0e-7;
    let why = refused(&m);
    assert!(why.starts_with("rbf.centers"), "{why}");
    assert_eq!(
        BlobError::Implausible(why).to_string(),
        format!("implausible model: {why}")
    );
    // rbf.scale 3e38: the normalised features overflow.
    let mut m = model();
    m.rbf.scale.0[1] = 3.0e38;
    assert!(refused(&m).starts_with("rbf.scale"));
    // Every weight 3e38: the sum overflows.
    let mut m = model();
    for c in m.rbf.centers.iter_mut() {
        c.w = 3.0e38;
    }
    assert_eq!(
        refused(&m),
        "rbf: the correction can exceed 1e12 in the range box"
    );
    // A range of ±3e38: its span (and the linear term's widened box) overflows f32.
    let mut m = model();
    m.ranges[0].lo = -3.0e38;
    m.ranges[0].hi = 3.0e38;
    assert_eq!(refused(&m), "ranges: the widened range overflows f32");
}

#[test]
fn an_inconsistent_p_is_refused_but_rounding_is_not() {
    // A center away from the origin: u = g‖z − c‖² + (p − g‖c‖²), so p = 0 makes u as low as −g‖c‖².
    let c = [0.8f64, -0.6, 0.0, 0.0];
    let good = Center::<8>::from_natural(&c, 8.0, 0.3);
    let mut m = model();
    m.rbf.centers[0] = good;
    assert!(m.bound().is_ok());
    // p one f32 step low (rounding of a trained model) is fine; 2 eval units low as well.
    m.rbf.centers[0].p = f32::from_bits(good.p.to_bits() - 1);
    assert!(m.bound().is_ok());
    m.rbf.centers[0].p = good.p - 2.0;
    assert!(m.bound().is_ok());
    // 30 eval units low (a Gaussian of 2^(30/16) ≈ 3.7) or p = 0 is refused.
    for p in [good.p - 30.0, 0.0] {
        m.rbf.centers[0].p = p;
        let why = refused(&m);
        assert!(why.contains("p inconsistent"), "{why}");
    }
    let b = {
        m.rbf.centers[0].p = good.p - 2.0;
        m.bound().unwrap()
    };
    assert!(
        b.min_exponent < 0.0 && b.min_exponent > -2.5,
        "{}",
        b.min_exponent
    );
}

#[test]
fn the_correction_limit_is_on_the_bound() {
    let mut m = model();
    m.rbf.centers.clear();
    m.rbf.linear = tcomp_core::point::Point::default();
    m.rbf.bias = 0.9 * MAX_CORRECTION;
    let b = m.bound().unwrap();
    assert!(b.correction >= 0.9 * MAX_CORRECTION && b.correction < MAX_CORRECTION);
    assert_eq!(b.min_exponent, f32::INFINITY);
    m.rbf.bias = 1.1 * MAX_CORRECTION;
    refused(&m);
}

#[test]
fn example_models_pass_and_stay_within_their_bound() {
    for (n, seed) in [(1usize, 1u32), (8, 2), (32, 3), (64, 4)] {
        let m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(n, seed);
        let b = m.bound().unwrap();
        let mut ch = Channel::<48, 8>::new(1.0);
        let mut largest = 0.0f32;
        for k in 0..2000u32 {
            let (temps, raw) = example_sample(k * 7, 1.0);
            let out = ch.step(Some(&m), &temps, raw);
            assert!(!out.status.contains(Status::MODEL_FAULT));
            largest = largest.max(out.correction.abs());
        }
        assert!(largest <= b.correction, "{largest} > {b:?}");
        // Not a vacuous bound either: within a few times the largest value seen.
        assert!(b.correction < 50.0 * largest.max(0.1), "{b:?}");
    }
}
