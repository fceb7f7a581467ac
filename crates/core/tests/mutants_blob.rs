//! The blob's checks one by one: each field that `validate` guards is refused when bad and accepted
//! when good, each failure maps to the reason a user is shown, and the encoder reports a short buffer.
//! Written to kill what `cargo mutants` found untested in `blob.rs`.
#![allow(clippy::unwrap_used, missing_docs)]

use tcomp_core::blob::{FORMAT_VERSION, MAGIC, crc32};
use tcomp_core::program::ProgramError;
use tcomp_core::testing::example_model;
use tcomp_core::{BlobError, FeatureRange, HOST_CENTERS, HOST_FEATURES, HOST_NODES, HostModel};

fn model() -> HostModel<'static> {
    example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(8, 9)
}

fn encoded(m: &HostModel<'_>) -> Vec<u8> {
    let mut buf = vec![0u8; 8192];
    let n = m.encode(&mut buf).unwrap();
    buf.truncate(n);
    buf
}

#[test]
fn a_structure_that_ends_early_under_a_matching_crc_is_truncated() {
    let good = encoded(&model());
    let body = &good[..good.len() - 4];
    // Every proper prefix of the body past the header, re-sealed with its own CRC: the checksum
    // passes, so only the structure can tell that it is cut short.
    for len in 5..body.len() {
        let mut cut = body[..len].to_vec();
        cut.extend_from_slice(&crc32(&cut).to_le_bytes());
        assert_eq!(
            HostModel::decode(&cut).unwrap_err(),
            BlobError::Truncated,
            "body cut at {len}"
        );
    }
}

#[test]
fn a_header_cut_inside_the_version_is_truncated() {
    assert_eq!(HostModel::decode(&MAGIC).unwrap_err(), BlobError::Truncated);
    // The CRC is checked before the version, so the version cases carry a valid CRC.
    let sealed = |tail: &[u8]| {
        let mut v = MAGIC.to_vec();
        v.extend_from_slice(tail);
        let crc = crc32(&v);
        v.extend_from_slice(&crc.to_le_bytes());
        v
    };
    // A varint continuation byte with nothing after it.
    assert_eq!(
        HostModel::decode(&sealed(&[0x80])).unwrap_err(),
        BlobError::Truncated
    );
    // A version varint longer than a u16 is malformed, not truncated.
    assert_eq!(
        HostModel::decode(&sealed(&[0xFF, 0xFF, 0xFF, 0x01])).unwrap_err(),
        BlobError::Malformed
    );
    // Without a CRC the same bytes are too short to be a blob.
    let mut v = MAGIC.to_vec();
    v.extend_from_slice(&[0xFF, 0xFF, 0xFF, 0x01]);
    assert_eq!(HostModel::decode(&v).unwrap_err(), BlobError::Truncated);
}

#[test]
fn a_short_output_buffer_is_reported() {
    let m = model();
    let n = encoded(&m).len();
    let mut exact = vec![0u8; n];
    assert_eq!(m.encode(&mut exact), Ok(n));
    // Room for the body but not the CRC, and not even for the body.
    for short in [n - 1, n - 4, n / 2, 3] {
        let mut buf = vec![0u8; short];
        assert_eq!(
            m.encode(&mut buf),
            Err(BlobError::BufferTooSmall),
            "buffer of {short} bytes"
        );
    }
}

#[test]
fn n_features_counts_the_program_features() {
    let m = model();
    assert_eq!(m.n_features(), 4);
    assert_eq!(m.n_features(), m.program.features.len());
    assert_eq!(m.n_features(), m.ranges.len());
}

#[test]
fn ranges_must_be_finite_and_ordered() {
    for (lo, hi) in [
        (f32::NAN, 1.0),
        (0.0, f32::INFINITY),
        (f32::NEG_INFINITY, 0.0),
        (0.0, f32::NAN),
    ] {
        let mut m = model();
        m.ranges[1] = FeatureRange { lo, hi };
        assert_eq!(
            m.validate(),
            Err(BlobError::NonFinite("ranges")),
            "{lo}..{hi}"
        );
    }
    let mut m = model();
    m.ranges[2] = FeatureRange { lo: 1.0, hi: -1.0 };
    assert_eq!(
        m.validate(),
        Err(BlobError::Inconsistent("ranges: lo > hi"))
    );
}

/// A feature that was constant in training has an empty range; the compensator then clamps it to
/// that one value. (If plausibility checks come to refuse degenerate ranges, this test goes.)
#[test]
fn a_degenerate_range_is_accepted() {
    let mut m = model();
    m.ranges[3] = FeatureRange { lo: 0.5, hi: 0.5 };
    assert_eq!(m.validate(), Ok(()));
}

#[test]
fn the_constant_reference_must_be_finite_when_present() {
    let mut m = model();
    m.meta.columns.reference_value = Some(0.0);
    assert_eq!(m.validate(), Ok(()));
    m.meta.columns.reference_value = Some(-15.2);
    assert_eq!(m.validate(), Ok(()));
    m.meta.columns.reference_value = Some(f32::NAN);
    assert_eq!(
        m.validate(),
        Err(BlobError::NonFinite("meta.columns.reference_value"))
    );
}

#[test]
fn every_residual_figure_must_be_finite() {
    for k in 0..3 {
        let mut m = model();
        let field = match k {
            0 => &mut m.residual.std,
            1 => &mut m.residual.binned_std,
            _ => &mut m.residual.bin_s,
        };
        *field = f32::INFINITY;
        assert_eq!(
            m.validate(),
            Err(BlobError::NonFinite("residual")),
            "field {k}"
        );
    }
}

#[test]
fn range_points_carry_the_ranges() {
    let m = model();
    let (lo, hi) = m.range_points();
    assert_eq!(&lo.0[..4], &[-40.0, -5.0, -3.0, -3.0]);
    assert_eq!(&hi.0[..4], &[60.0, 5.0, 3.0, 3.0]);
    assert_eq!(&lo.0[4..], &[0.0; 4], "slots past the features are zero");
    assert_eq!(&hi.0[4..], &[0.0; 4]);
}

#[test]
fn every_reason_reads_as_a_sentence_with_its_detail() {
    let cases: [(BlobError, &[&str]); 10] = [
        (BlobError::Truncated, &["truncated"]),
        (BlobError::BadMagic, &["magic"]),
        (
            BlobError::UnsupportedVersion(7),
            &["version 7", &FORMAT_VERSION.to_string()],
        ),
        (BlobError::Checksum, &["checksum"]),
        (BlobError::CapacityExceeded, &["capacity"]),
        (BlobError::Malformed, &["malformed"]),
        (
            BlobError::NonFinite("rbf.bias"),
            &["non-finite", "rbf.bias"],
        ),
        (
            BlobError::Inconsistent("ranges: lo > hi"),
            &["inconsistent", "ranges: lo > hi"],
        ),
        (
            BlobError::Program(ProgramError::NoFeatures),
            &["feature program", "no features"],
        ),
        (BlobError::BufferTooSmall, &["buffer"]),
    ];
    for (e, words) in cases {
        let text = e.to_string();
        for w in words {
            assert!(text.contains(w), "{e:?} reads {text:?}, lacks {w:?}");
        }
    }
}
