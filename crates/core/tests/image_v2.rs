//! The version-2 calibration image: what the writer writes reads back field for field, the board
//! hash depends on the table and nothing else, every corruption is refused, a blob is bound to its
//! row, and the reader survives any bytes (100,000 cases per property).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use proptest::prelude::*;
use tcomp_core::SensorKind;
use tcomp_core::image::{
    ChannelRow, Entry, Image, ImageError, ImageSpec, Input, MAX_ROW_INPUTS, Mismatch, Provenance,
    Source, ThermKind, Thermometer, seal,
};

const PT1000: ThermKind = ThermKind::Rtd {
    r0: 1000.0,
    a: 3.9083e-3,
    b: -5.775e-7,
};

fn therms() -> Vec<Thermometer<'static>> {
    vec![
        Thermometer {
            name: "x-anode",
            adc: 0,
            input: 0,
            kind: PT1000,
        },
        Thermometer {
            name: "x-shell",
            adc: 0,
            input: 1,
            kind: ThermKind::Ntc {
                r0: 10_000.0,
                beta: 3435.0,
                t0_k: 298.15,
            },
        },
        Thermometer {
            name: "imu",
            adc: 1,
            input: 0,
            kind: ThermKind::Digital {
                scale: 1.0 / 256.0,
                offset_c: 25.0,
            },
        },
    ]
}

fn inputs(list: &[(&'static str, u8)]) -> ([Input<'static>; MAX_ROW_INPUTS], u8) {
    let mut a = [Input::default(); MAX_ROW_INPUTS];
    for (d, &(name, thermometer)) in a.iter_mut().zip(list) {
        *d = Input { name, thermometer };
    }
    (a, list.len() as u8)
}

fn rows() -> Vec<ChannelRow<'static>> {
    let (rlg_in, rlg_n) = inputs(&[("t_anode_c", 0), ("t_shell_c", 1)]);
    let (mems_in, mems_n) = inputs(&[("temp_imu_C", 2)]);
    vec![
        ChannelRow {
            id: 0,
            name: "rlg-x",
            sensor: SensorKind::Rlg,
            axis: "x",
            unit: "deg/h",
            source: Source::Counter(0),
            scale: 1.0e-5,
            inputs: rlg_in,
            n_inputs: rlg_n,
        },
        ChannelRow {
            id: 7,
            name: "gyro-z",
            sensor: SensorKind::MemsGyro,
            axis: "z",
            unit: "rad/s",
            source: Source::Sample(2),
            scale: 1.0e-3,
            inputs: mems_in,
            n_inputs: mems_n,
        },
    ]
}

fn blob(len: usize, seed: u8) -> Vec<u8> {
    (0..len)
        .map(|i| (i as u8).wrapping_mul(31) ^ seed)
        .collect()
}

fn prov(data: &'static str) -> Provenance<'static> {
    Provenance {
        data,
        data_hash: 0x0123_4567_89ab_cdef,
        window: [0.0, 3130.0],
        method: "bayes",
    }
}

fn write(spec: &ImageSpec<'_>) -> Vec<u8> {
    let len = spec.image_len().unwrap();
    let mut buf = vec![0xA5; len + 9];
    assert_eq!(spec.write(&mut buf).unwrap(), len);
    assert!(
        buf[len..].iter().all(|&b| b == 0xA5),
        "bytes past the image"
    );
    buf.truncate(len);
    buf
}

fn with<R>(entries: &[Entry<'_>], f: impl FnOnce(ImageSpec<'_>) -> R) -> R {
    let t = therms();
    let r = rows();
    f(ImageSpec {
        serial: 4242,
        created: 1_763_900_000,
        tool: "0.1.0+abc1234",
        thermometers: &t,
        channels: &r,
        entries,
    })
}

fn sample_image() -> (Vec<u8>, Vec<u8>, Vec<u8>) {
    let (a, b) = (blob(37, 1), blob(40, 2));
    let entries = [
        Entry {
            channel: 7,
            blob: &a,
            provenance: prov("mems.csv"),
        },
        Entry {
            channel: 0,
            blob: &b,
            provenance: prov("rlg/train.csv"),
        },
    ];
    let image = with(&entries, |s| write(&s));
    (image, a, b)
}

#[test]
fn round_trip_reads_every_field() {
    let (image, a, b) = sample_image();
    assert_eq!(image.len() % 4, 0);
    let p = Image::parse(&image).unwrap();
    assert_eq!(p.version(), 2);
    assert_eq!(p.byte_len(), image.len());
    let h = p.header().unwrap();
    assert_eq!(
        (h.serial, h.created, h.tool),
        (4242, 1_763_900_000, "0.1.0+abc1234")
    );
    let expected_hash = with(&[], |s| s.board_hash());
    assert_eq!(h.board_hash, expected_hash);
    assert_eq!(p.n_thermometers(), 3);
    for (i, t) in therms().iter().enumerate() {
        assert_eq!(p.thermometer(i).as_ref(), Some(t));
    }
    assert_eq!(p.n_channels(), 2);
    for (i, r) in rows().iter().enumerate() {
        assert_eq!(p.channel(i).as_ref(), Some(r));
        assert_eq!(p.channel_by_id(r.id).as_ref(), Some(r));
    }
    assert_eq!(p.channel(2), None);
    assert_eq!(p.blob(7).unwrap(), &a[..]);
    assert_eq!(p.blob(0).unwrap(), &b[..]);
    assert_eq!(p.blob(1), Err(ImageError::Missing));
    assert_eq!(p.provenance(1), Some(prov("rlg/train.csv")));
    assert_eq!(p.entry_crc(0), Some(tcomp_core::blob::crc32(&a)));
    assert_eq!(p.check_unit(4242), Ok(()));
    assert_eq!(p.check_unit(4243), Err(ImageError::OtherUnit));
    // Reproducible: the same description gives the same bytes.
    assert_eq!(sample_image().0, image);
    // The whole region (erased flash after the image) reads the same.
    let mut region = image.clone();
    region.resize(image.len() + 100, 0xFF);
    assert_eq!(Image::parse(&region).unwrap().blob(7).unwrap(), &a[..]);
}

#[test]
fn board_hash_follows_the_table_only() {
    let base = with(&[], |s| s.board_hash());
    let t = therms();
    let mut r = rows();
    let spec = |r: &[ChannelRow<'_>], t: &[Thermometer<'_>]| {
        tcomp_core::image::board_hash(t.iter().copied(), r.iter().copied())
    };
    assert_eq!(spec(&r, &t), base);
    r[1].scale = 2.0e-3;
    assert_ne!(spec(&r, &t), base);
    let mut r = rows();
    r[0].inputs[0].thermometer = 1;
    assert_ne!(spec(&r, &t), base);
    let mut t2 = therms();
    t2[0].input = 5;
    assert_ne!(spec(&rows(), &t2), base);
    // Moving a character between two adjacent strings changes it too.
    let mut r = rows();
    r[0].name = "rlg-";
    r[0].axis = "xx";
    assert_ne!(spec(&r, &t), base);
}

#[test]
fn writer_refuses_what_the_reader_would() {
    let a = blob(8, 1);
    let on = |channel| Entry {
        channel,
        blob: &a,
        provenance: prov("d.csv"),
    };
    with(&[on(99)], |s| {
        assert_eq!(s.image_len(), Err(ImageError::UnknownChannel(99)))
    });
    with(&[on(7), on(7)], |s| {
        assert_eq!(s.image_len(), Err(ImageError::DuplicateId(7)))
    });
    let t = therms();
    let mut r = rows();
    r[1].id = 0;
    let spec = ImageSpec {
        serial: 1,
        created: 0,
        tool: "t",
        thermometers: &t,
        channels: &r,
        entries: &[],
    };
    assert_eq!(spec.image_len(), Err(ImageError::DuplicateId(0)));
    let mut r = rows();
    r[0].inputs[1].thermometer = 3;
    let spec = ImageSpec {
        channels: &r,
        ..spec
    };
    assert_eq!(spec.image_len(), Err(ImageError::BadRow));
    let r = rows();
    let long = ImageSpec {
        channels: &r,
        tool: "0123456789abcdefg",
        ..spec
    };
    assert_eq!(long.image_len(), Err(ImageError::TooLarge));
    let ok = ImageSpec { tool: "t", ..long };
    let needed = ok.image_len().unwrap();
    for short in [0, 10, needed - 1] {
        assert_eq!(
            ok.write(&mut vec![0; short]),
            Err(ImageError::BufferTooSmall { needed })
        );
    }
}

#[test]
fn every_corruption_is_refused() {
    let (image, _, _) = sample_image();
    // Any single flipped bit past the magic and version: the CRC (or the header checks) refuse it.
    for at in 6..image.len() {
        for bit in [0x01u8, 0x80] {
            let mut bad = image.clone();
            bad[at] ^= bit;
            assert!(Image::parse(&bad).is_err(), "bit {bit:#x} of byte {at}");
        }
    }
    // Cut anywhere: refused.
    for len in 0..image.len() {
        assert!(Image::parse(&image[..len]).is_err(), "cut at {len}");
    }
    // A table change re-sealed with a valid CRC: the board hash no longer matches.
    let p = Image::parse(&image).unwrap();
    let scale_at = 64 + 20 * p.n_thermometers() + 8;
    let mut bad = image.clone();
    bad[scale_at] ^= 1;
    seal(&mut bad).unwrap();
    assert_eq!(Image::parse(&bad).unwrap_err(), ImageError::BoardHash);
    // An entry pointed at another channel (re-sealed): still readable, but the blob is not the one
    // the row accepts; `accepts` is what refuses it (see below). Pointing at a channel not in the
    // table is refused by the reader.
    let entry0 = 64 + 20 * 3 + 56 * 2;
    let mut bad = image.clone();
    bad[entry0..entry0 + 2].copy_from_slice(&9u16.to_le_bytes());
    seal(&mut bad).unwrap();
    assert_eq!(
        Image::parse(&bad).unwrap_err(),
        ImageError::UnknownChannel(9)
    );
    bad[entry0..entry0 + 2].copy_from_slice(&0u16.to_le_bytes());
    seal(&mut bad).unwrap();
    assert_eq!(Image::parse(&bad).unwrap_err(), ImageError::DuplicateId(0));
}

#[test]
fn a_blob_is_bound_to_its_row() {
    let model = tcomp_core::testing::example_model::<32, 4, 16>(4, 1);
    let rlg = rows()[0];
    let mems = rows()[1];
    let inputs = ["t_anode_c", "t_shell_c"];
    let mut meta = model.meta;
    meta.sensor = SensorKind::Rlg;
    meta.axis = "x";
    meta.unit = "deg/h";
    assert_eq!(rlg.accepts(&meta, inputs), Ok(()));
    assert_eq!(
        mems.accepts(&meta, inputs),
        Err(Mismatch::Sensor(SensorKind::Rlg))
    );
    assert_eq!(
        rlg.accepts(&meta, ["t_anode_c", "t_cathode_c"]),
        Err(Mismatch::Input("t_cathode_c"))
    );
    let mut m = meta;
    m.unit = "ug";
    assert_eq!(rlg.accepts(&m, inputs), Err(Mismatch::Unit));
    let mut m = meta;
    m.axis = "y";
    assert_eq!(rlg.accepts(&m, inputs), Err(Mismatch::Axis));
}

// ---- Fuzzing --------------------------------------------------------------------------------

const FUZZ_CASES: u32 = 100_000;

/// Whatever the reader accepts is self-consistent and every borrowed slice lies inside the input.
fn check_reader(bytes: &[u8]) -> Result<(), TestCaseError> {
    let Ok(p) = Image::parse(bytes) else {
        return Ok(());
    };
    let region = bytes.as_ptr_range();
    let inside = |s: &[u8]| {
        let r = s.as_ptr_range();
        s.is_empty() || (region.start <= r.start && r.end <= region.end)
    };
    prop_assert!(p.byte_len() <= bytes.len());
    for i in 0..p.n_channels() {
        let row = p.channel(i);
        prop_assert!(row.is_some());
        let row = row.unwrap();
        prop_assert!(inside(row.name.as_bytes()) && inside(row.unit.as_bytes()));
        for input in row.inputs() {
            prop_assert!(usize::from(input.thermometer) < p.n_thermometers());
        }
    }
    for i in 0..p.len() {
        let (id, blob) = p.entry(i).unwrap();
        prop_assert!(inside(blob));
        prop_assert!(p.channel_by_id(id).is_some());
        prop_assert!(p.provenance(i).is_some());
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(FUZZ_CASES))]

    /// A valid image with up to four bytes overwritten, re-sealed most of the time so the change
    /// reaches the row checks behind the CRC.
    #[test]
    fn fuzz_structured_images(
        edits in proptest::collection::vec((0usize..400, any::<u8>()), 1..4),
        cut in prop::option::weighted(0.1, 0usize..400),
        reseal in prop::bool::weighted(0.9),
    ) {
        let (mut image, _, _) = sample_image();
        for &(at, v) in &edits {
            if let Some(b) = image.get_mut(at) {
                *b = v;
            }
        }
        if let Some(len) = cut {
            image.truncate(len);
        }
        if reseal {
            let _ = seal(&mut image);
        }
        check_reader(&image)?;
    }

    /// Random bytes, half of them behind a valid magic, version and header length, sealed.
    #[test]
    fn fuzz_raw_bytes(mut bytes in proptest::collection::vec(any::<u8>(), 0..400), framed in any::<bool>()) {
        if framed && bytes.len() >= 64 {
            let len = (bytes.len() as u32).to_le_bytes();
            bytes[..4].copy_from_slice(b"TCMI");
            bytes[4..6].copy_from_slice(&2u16.to_le_bytes());
            bytes[6..8].copy_from_slice(&64u16.to_le_bytes());
            bytes[8..12].copy_from_slice(&len);
            let _ = seal(&mut bytes);
        }
        check_reader(&bytes)?;
    }
}
