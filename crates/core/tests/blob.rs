//! Blob encoding: round trip, and rejection of every corruption without panicking.
#![allow(clippy::unwrap_used, missing_docs)]

use proptest::prelude::*;
use tcomp_core::blob::{FORMAT_VERSION, MAGIC};
use tcomp_core::testing::example_model;
use tcomp_core::{BlobError, HOST_CENTERS, HOST_FEATURES, HOST_NODES, HostModel, Model};

/// Rewrites the trailing CRC of `blob` so that it matches the content again.
fn reseal(blob: &mut [u8]) {
    let n = blob.len() - 4;
    let crc = tcomp_core::blob::crc32(&blob[..n]);
    blob[n..].copy_from_slice(&crc.to_le_bytes());
}

fn encoded(n_centers: usize, seed: u32) -> Vec<u8> {
    let m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(n_centers, seed);
    let mut buf = vec![0u8; 8192];
    let n = m.encode(&mut buf).unwrap();
    buf.truncate(n);
    buf
}

#[test]
fn reasons_are_specific() {
    let good = encoded(8, 1);
    assert_eq!(HostModel::decode(&[]).unwrap_err(), BlobError::Truncated);
    assert_eq!(
        HostModel::decode(b"NOPE....").unwrap_err(),
        BlobError::BadMagic
    );
    // An intact blob of another format version (valid CRC) is refused by its number…
    let mut v2 = good.clone();
    v2[4] = FORMAT_VERSION as u8 + 1;
    reseal(&mut v2);
    assert_eq!(
        HostModel::decode(&v2).unwrap_err(),
        BlobError::UnsupportedVersion(FORMAT_VERSION + 1)
    );
    // …while a version byte changed by corruption (CRC no longer matches) is corruption.
    let mut hit = good.clone();
    hit[4] = FORMAT_VERSION as u8 + 1;
    assert_eq!(HostModel::decode(&hit).unwrap_err(), BlobError::Checksum);
    let mut flipped = good.clone();
    let mid = flipped.len() / 2;
    flipped[mid] ^= 0x10;
    assert_eq!(
        HostModel::decode(&flipped).unwrap_err(),
        BlobError::Checksum
    );
    assert_eq!(&good[..4], &MAGIC);
}

#[test]
fn capacity_is_checked_by_the_smaller_firmware_type() {
    let blob = encoded(40, 2);
    assert!(HostModel::decode(&blob).is_ok());
    assert_eq!(
        Model::<'_, 32, 8, 48>::decode(&blob).unwrap_err(),
        BlobError::CapacityExceeded
    );
    // The wire format does not depend on F: a 4-feature model written by the host build (F = 8)
    // reads into the firmware's F = 4 type with the same numbers, and back.
    let host = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(32, 3);
    let mut buf = [0u8; 4096];
    let n = host.encode(&mut buf).unwrap();
    let fw = Model::<'_, 32, 4, 24>::decode(&buf[..n]).unwrap();
    let x4 = [12.0f32, 0.5, -0.3, 0.2];
    let x8 = [12.0f32, 0.5, -0.3, 0.2, 0.0, 0.0, 0.0, 0.0];
    assert_eq!(fw.rbf.eval(&x4).to_bits(), host.rbf.eval(&x8).to_bits());
    let mut buf2 = [0u8; 4096];
    let n2 = fw.encode(&mut buf2).unwrap();
    assert_eq!(
        &buf[..n],
        &buf2[..n2],
        "re-encoding with F = 4 gives the same bytes"
    );
    // A program with more features than the firmware holds is refused, not truncated.
    let mut wide = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(4, 3);
    wide.rbf.offset.0[6] = 1.0;
    let mut buf3 = [0u8; 4096];
    if let Ok(n3) = wide.encode(&mut buf3) {
        assert!(Model::<'_, 32, 4, 24>::decode(&buf3[..n3]).is_err());
    }
}

#[test]
fn non_finite_numbers_are_refused_on_encode_and_named() {
    let mut m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(8, 4);
    m.rbf.centers[3].w = f32::NAN;
    let mut buf = vec![0u8; 8192];
    assert_eq!(
        m.encode(&mut buf).unwrap_err(),
        BlobError::NonFinite("rbf.centers.w")
    );
    let mut m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(8, 4);
    m.rbf.centers[0].g = -1.0;
    assert!(matches!(
        m.encode(&mut buf).unwrap_err(),
        BlobError::Inconsistent(_)
    ));
}

#[test]
fn every_single_byte_corruption_is_rejected() {
    let good = encoded(16, 5);
    for i in 0..good.len() {
        for delta in [1u8, 0x80, 0xFF] {
            let mut bad = good.clone();
            bad[i] ^= delta;
            assert!(
                HostModel::decode(&bad).is_err(),
                "byte {i} ^ {delta:#x} accepted"
            );
        }
    }
    for len in 0..good.len() {
        assert!(
            HostModel::decode(&good[..len]).is_err(),
            "prefix of {len} accepted"
        );
    }
}

proptest! {
    #[test]
    fn encode_decode_is_identity(n in 1usize..=64, seed in 1u32..u32::MAX) {
        let m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(n, seed);
        let mut buf = vec![0u8; 8192];
        let len = m.encode(&mut buf).unwrap();
        prop_assert_eq!(HostModel::decode(&buf[..len]).unwrap(), m);
    }

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let _ = HostModel::decode(&bytes);
        let mut with_magic = MAGIC.to_vec();
        with_magic.push(FORMAT_VERSION as u8);
        with_magic.extend_from_slice(&bytes);
        prop_assert!(HostModel::decode(&with_magic).is_err());
    }

    #[test]
    fn mutated_blobs_are_rejected(seed in 1u32..1000, edits in proptest::collection::vec((any::<usize>(), 1u8..=255), 1..6)) {
        let good = encoded(12, seed);
        let mut bad = good.clone();
        for (pos, x) in edits {
            let i = pos % bad.len();
            bad[i] ^= x;
        }
        prop_assume!(bad != good);
        prop_assert!(HostModel::decode(&bad).is_err());
    }
}

#[test]
fn crc32_is_the_standard_iso_hdlc() {
    // The check value of CRC-32/ISO-HDLC (zip, PNG) for "123456789".
    assert_eq!(tcomp_core::blob::crc32(b"123456789"), 0xCBF4_3926);
    assert_eq!(tcomp_core::blob::crc32(b""), 0);
}

/// Postcard length of `v` (the wire format is the concatenation of the fields).
fn wire_len<T: serde::Serialize>(v: &T) -> usize {
    let mut buf = vec![0u8; 8192];
    postcard::to_slice(v, &mut buf).unwrap().len()
}

#[test]
fn unknown_enum_tags_are_malformed_and_named_not_capacity() {
    let m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(8, 21);
    let good = encoded(8, 21);
    // The sensor kind is the first field after magic and version: tag 0 (RLG) of 6 variants.
    assert_eq!(good[5], 0);
    for tag in [6u8, 0x7F] {
        let mut bad = good.clone();
        bad[5] = tag;
        reseal(&mut bad);
        let e = HostModel::decode(&bad).unwrap_err();
        assert_eq!(e, BlobError::UnknownTag("meta.sensor"), "tag {tag}");
        assert_eq!(
            e.to_string(),
            "malformed blob content: unknown enum tag in meta.sensor"
        );
    }
    // The first operation's tag: after magic, version, meta, inputs, signals and the node count.
    let at = 5 + wire_len(&m.meta) + wire_len(&m.program.inputs) + wire_len(&m.program.signals) + 1;
    assert_eq!(good[at], 0, "the first node reads an input (tag 0)");
    for tag in [14u8, 0x7F] {
        let mut bad = good.clone();
        bad[at] = tag;
        reseal(&mut bad);
        let e = HostModel::decode(&bad).unwrap_err();
        assert_eq!(e, BlobError::UnknownTag("program.nodes"), "tag {tag}");
        assert_eq!(
            e.to_string(),
            "malformed blob content: unknown enum tag in program.nodes"
        );
    }
    // The last valid tags still decode as far as the structure goes (the values may then be refused).
    let mut last = good.clone();
    last[5] = 5;
    reseal(&mut last);
    assert_eq!(
        HostModel::decode(&last).unwrap().meta.sensor,
        tcomp_core::SensorKind::Other
    );
}

#[test]
fn every_reason_has_its_message() {
    let cases = [
        (BlobError::Truncated, "truncated blob"),
        (BlobError::BadMagic, "not a tcomp model blob (bad magic)"),
        (
            BlobError::UnsupportedVersion(7),
            "unsupported blob format version 7 (this build reads 5)",
        ),
        (
            BlobError::Checksum,
            "checksum mismatch: the blob is corrupt",
        ),
        (
            BlobError::CapacityExceeded,
            "a size in the blob exceeds this build's capacity",
        ),
    ];
    for (e, msg) in cases {
        assert_eq!(e.to_string(), msg);
    }
    let good = encoded(4, 9);
    let mut v9 = good.clone();
    v9[4] = 9;
    reseal(&mut v9);
    assert_eq!(
        HostModel::decode(&v9).unwrap_err().to_string(),
        "unsupported blob format version 9 (this build reads 5)"
    );
    v9[4] = 1;
    assert_eq!(
        HostModel::decode(&v9).unwrap_err().to_string(),
        "checksum mismatch: the blob is corrupt"
    );
}

#[test]
fn serde_of_the_guarded_enums_round_trips_every_variant() {
    use tcomp_core::{Op, SensorKind};
    let kinds = [
        SensorKind::Rlg,
        SensorKind::Qma,
        SensorKind::Ifog,
        SensorKind::MemsGyro,
        SensorKind::MemsAccel,
        SensorKind::Other,
    ];
    for (i, k) in kinds.iter().enumerate() {
        let mut buf = [0u8; 16];
        let bytes = postcard::to_slice(k, &mut buf).unwrap();
        assert_eq!(bytes, &[i as u8], "tag of {k:?}");
        assert_eq!(postcard::from_bytes::<SensorKind>(bytes).unwrap(), *k);
    }
    let ops = [
        Op::Input(1),
        Op::Const(2.5),
        Op::Add(0, 1),
        Op::Sub(0, 1),
        Op::Mul(0, 1),
        Op::Div(0, 1),
        Op::Neg(2),
        Op::Sq(2),
        Op::Abs(2),
        Op::Clamp {
            x: 1,
            lo: -1.0,
            hi: 1.0,
        },
        Op::Rate {
            x: 1,
            slot: 0,
            window_s: 60.0,
        },
        Op::Lag {
            x: 1,
            slot: 1,
            tau_s: 30.0,
        },
        Op::Hyst {
            x: 1,
            slot: 2,
            threshold: 0.05,
        },
        Op::Warmup {
            slot: 3,
            tau_s: 600.0,
        },
    ];
    for (i, op) in ops.iter().enumerate() {
        let mut buf = [0u8; 32];
        let bytes = postcard::to_slice(op, &mut buf).unwrap();
        assert_eq!(bytes[0], i as u8, "tag of {op:?}");
        assert_eq!(postcard::from_bytes::<Op>(bytes).unwrap(), *op);
    }
    // An unknown tag on its own gives postcard's marker, never the capacity error.
    assert_eq!(
        postcard::from_bytes::<Op>(&[14, 0]).unwrap_err(),
        postcard::Error::WontImplement
    );
}

/// `decode_into` (in place, for a firmware's static) must be `decode`: the same model, the same
/// error, also over a slot that held another model, and an emptied slot on error.
#[test]
fn decode_into_is_decode_in_place() {
    let other = encoded(30, 9);
    let check = |bytes: &[u8]| {
        let mut slot: Option<HostModel<'_>> = None;
        HostModel::decode_into(&other, &mut slot).unwrap();
        let into = HostModel::decode_into(bytes, &mut slot).map(|()| slot.clone().unwrap());
        assert_eq!(into, HostModel::decode(bytes));
        if into.is_err() {
            assert!(slot.is_none());
        }
        // The smaller firmware type refuses the same blobs for the same reasons.
        let mut small: Option<Model<'_, 32, 4, 24>> = None;
        let small_into =
            Model::<32, 4, 24>::decode_into(bytes, &mut small).map(|()| small.unwrap());
        assert_eq!(small_into, Model::<32, 4, 24>::decode(bytes));
    };
    let good = encoded(16, 5);
    check(&good);
    check(&encoded(40, 2));
    check(&encoded(1, 3));
    for i in (0..good.len()).step_by(3) {
        let mut bad = good.clone();
        bad[i] ^= 0x80;
        check(&bad);
        check(&good[..i]);
    }
}
