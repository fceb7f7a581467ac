//! The C API does what the core does, bit for bit, and refuses what the core refuses with the
//! right code: every entry point called as a C caller calls it (raw pointers, caller storage).
#![allow(unsafe_code, clippy::unwrap_used, clippy::expect_used, missing_docs)]
// Every unsafe call below passes pointers to live Rust buffers with their true lengths (or NULL
// on purpose): the C API's contract, kept by construction.
#![allow(clippy::undocumented_unsafe_blocks)]

mod common;

use common::{Storage, example_blob, image, text, too_big_blob};
use std::ffi::CStr;
use std::ptr::{null, null_mut};
use tcomp_core::testing::example_sample;
use tcomp_core::{Channel, FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES, Model};
use tcomp_ffi::*;

const PERIOD: f32 = 0.005;

type M<'a> = Model<'a, FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES>;

fn describe(s: &mut Storage) -> String {
    let mut buf = [0u8; 200];
    let n = unsafe { tcomp_channel_describe(s.ptr(), buf.as_mut_ptr().cast(), buf.len()) };
    assert!(n >= 0);
    text(&buf)
}

fn step(s: &mut Storage, inputs: &[f32], raw: f32) -> (i32, TcompOutput) {
    let mut out = TcompOutput::default();
    let rc = unsafe { tcomp_step(s.ptr(), inputs.as_ptr(), inputs.len(), raw, &mut out) };
    (rc, out)
}

#[test]
fn version_and_capacities_describe_this_build() {
    let v = unsafe { CStr::from_ptr(tcomp_version()) };
    assert_eq!(v.to_str().unwrap(), env!("CARGO_PKG_VERSION"));
    let c = tcomp_capacities();
    assert_eq!(c.api_version, TCOMP_API_VERSION);
    assert_eq!(c.channel_size as usize, TCOMP_CHANNEL_SIZE);
    assert_eq!(c.channel_size as usize, size_of::<TcompChannel>());
    assert_eq!(c.channel_align as usize, align_of::<TcompChannel>());
    assert!(c.channel_used > 0 && c.channel_used <= c.channel_size);
    // The storage wastes less than the rounding it promises.
    assert!(c.channel_size - c.channel_used < 128, "{c:?}");
    assert_eq!(usize::from(c.max_centers), FLIGHT_CENTERS);
    assert_eq!(c.blob_format_newest, tcomp_core::blob::FORMAT_VERSION);
    assert_eq!(c.image_format, tcomp_core::image::VERSION_2);
}

/// A loaded channel's outputs are the core `Channel`'s, bit for bit, through ordinary samples,
/// a NaN thermometer, a NaN raw value, an out-of-range stretch, a gap and a reset.
#[test]
fn steps_are_the_cores_bit_for_bit() {
    let blob = example_blob(11);
    let model = M::decode(&blob).unwrap();
    let mut core = Channel::<FLIGHT_NODES, FLIGHT_FEATURES>::new(PERIOD);
    core.prepare(&model);
    let mut s = Storage::new();
    let rc = unsafe { tcomp_load_blob(s.ptr(), blob.as_ptr(), blob.len(), PERIOD) };
    assert_eq!(rc, TCOMP_OK);
    assert_eq!(unsafe { tcomp_channel_has_model(s.ptr()) }, 1);
    assert_eq!(unsafe { tcomp_channel_input_count(s.ptr()) }, 3);
    assert_eq!(describe(&mut s), "ok");
    let (mut flagged, mut out_of_range) = (0, 0);
    for n in 0..3000u32 {
        let (mut temps, mut raw) = example_sample(n, PERIOD);
        if n == 500 {
            temps[1] = f32::NAN;
        }
        if n == 700 {
            raw = f32::NAN;
        }
        if (1200..1300).contains(&n) {
            temps[0] += 80.0; // far above the trained range
        }
        let (rc, ours, theirs) = match n {
            // A gap of 2 s before sample 2000 (dt spans it), given as the host gives it.
            2000 => {
                let mut out = TcompOutput::default();
                let rc =
                    unsafe { tcomp_step_dt(s.ptr(), temps.as_ptr(), 3, 2.0, true, raw, &mut out) };
                core.mark_gap();
                (rc, out, core.step_dt(Some(&model), &temps, 2.0, raw))
            }
            // Missed periods announced by a firmware loop.
            2500 => {
                assert_eq!(unsafe { tcomp_skip(s.ptr(), 0.5) }, TCOMP_OK);
                core.skip(0.5);
                let (rc, out) = step(&mut s, &temps, raw);
                (rc, out, core.step(Some(&model), &temps, raw))
            }
            2800 => {
                assert_eq!(unsafe { tcomp_reset(s.ptr()) }, TCOMP_OK);
                core.reset();
                core.prepare(&model);
                let (rc, out) = step(&mut s, &temps, raw);
                (rc, out, core.step(Some(&model), &temps, raw))
            }
            _ => {
                let (rc, out) = step(&mut s, &temps, raw);
                (rc, out, core.step(Some(&model), &temps, raw))
            }
        };
        assert_eq!(rc, TCOMP_OK, "sample {n}");
        assert_eq!(
            ours.compensated.to_bits(),
            theirs.compensated.to_bits(),
            "sample {n}"
        );
        assert_eq!(ours.correction.to_bits(), theirs.correction.to_bits());
        assert_eq!(ours.status, u16::from(theirs.status.0), "sample {n}");
        flagged += usize::from(ours.status & TCOMP_STATUS_INPUT_FAULT != 0);
        out_of_range += usize::from(ours.status & TCOMP_STATUS_OUT_OF_RANGE != 0);
    }
    assert_eq!(flagged, 2, "the NaN thermometer and the NaN raw value");
    assert!(out_of_range >= 100, "{out_of_range}");
}

#[test]
fn a_refused_blob_leaves_a_channel_that_passes_raw_through_and_says_why() {
    let mut blob = example_blob(3);
    let mid = blob.len() / 2;
    blob[mid] ^= 0x10;
    let mut s = Storage::new();
    let rc = unsafe { tcomp_load_blob(s.ptr(), blob.as_ptr(), blob.len(), PERIOD) };
    assert_eq!(rc, TCOMP_ERR_BLOB_CHECKSUM);
    assert_eq!(
        describe(&mut s),
        "blob refused: checksum mismatch: the blob is corrupt"
    );
    assert_eq!(unsafe { tcomp_channel_has_model(s.ptr()) }, 0);
    let (rc, out) = step(&mut s, &[], 12.5);
    assert_eq!(rc, TCOMP_OK);
    assert_eq!(out.compensated, 12.5);
    assert_eq!(out.status, TCOMP_STATUS_NO_MODEL);

    let big = too_big_blob();
    let rc = unsafe { tcomp_load_blob(s.ptr(), big.as_ptr(), big.len(), PERIOD) };
    assert_eq!(rc, TCOMP_ERR_BLOB_CAPACITY);
    let cases: [(&[u8], i32); 3] = [
        (b"", TCOMP_ERR_BLOB_TRUNCATED),
        (b"XXXXXXXXXXXX", TCOMP_ERR_BLOB_MAGIC),
        (&blob[..blob.len() - 3], TCOMP_ERR_BLOB_CHECKSUM),
    ];
    for (bytes, code) in cases {
        let mut why = [0u8; 120];
        let rc = unsafe {
            tcomp_validate_blob(
                bytes.as_ptr(),
                bytes.len(),
                why.as_mut_ptr().cast(),
                why.len(),
            )
        };
        assert_eq!(rc, code, "{}", text(&why));
        assert!(!text(&why).is_empty() && text(&why) != "ok");
    }
    let good = example_blob(4);
    let rc = unsafe { tcomp_validate_blob(good.as_ptr(), good.len(), null_mut(), 0) };
    assert_eq!(rc, TCOMP_OK);
}

#[test]
fn bad_calls_are_refused_with_their_code_and_never_emit_an_unflagged_value() {
    let blob = example_blob(7);
    let mut s = Storage::new();
    // Never initialised: refused, and the output still carries the raw value, flagged.
    let (rc, out) = step(&mut s, &[1.0, 2.0, 3.0], 4.0);
    assert_eq!(rc, TCOMP_ERR_UNINITIALISED);
    assert_eq!(
        (out.compensated, out.status & TCOMP_STATUS_INPUT_FAULT),
        (4.0, 4)
    );
    assert_eq!(unsafe { tcomp_reset(s.ptr()) }, TCOMP_ERR_UNINITIALISED);
    assert_eq!(unsafe { tcomp_reset(null_mut()) }, TCOMP_ERR_NULL);
    // Misaligned storage.
    let mut raw = vec![0u64; TCOMP_CHANNEL_SIZE / 8 + 2];
    let misaligned = unsafe { raw.as_mut_ptr().cast::<u8>().add(4) }.cast::<TcompChannel>();
    assert_eq!(
        unsafe { tcomp_channel_init(misaligned, PERIOD) },
        TCOMP_ERR_ALIGNMENT
    );
    // Bad periods.
    for p in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert_eq!(
            unsafe { tcomp_channel_init(s.ptr(), p) },
            TCOMP_ERR_ARGUMENT
        );
    }
    assert_eq!(
        unsafe { tcomp_load_blob(s.ptr(), null(), 10, PERIOD) },
        TCOMP_ERR_NULL
    );
    // A loaded model with the wrong number of inputs: not stepped, raw out, flagged.
    assert_eq!(
        unsafe { tcomp_load_blob(s.ptr(), blob.as_ptr(), blob.len(), PERIOD) },
        TCOMP_OK
    );
    let (rc, out) = step(&mut s, &[20.0, 20.0], 5.0);
    assert_eq!(rc, TCOMP_ERR_INPUT_COUNT);
    assert_eq!(
        (out.compensated, out.status),
        (5.0, TCOMP_STATUS_INPUT_FAULT)
    );
    let mut out = TcompOutput::default();
    let rc = unsafe { tcomp_step(s.ptr(), null(), 3, 5.0, &mut out) };
    assert_eq!(rc, TCOMP_ERR_NULL);
    assert_ne!(out.status, 0);
    let rc = unsafe { tcomp_step(s.ptr(), [1.0f32; 3].as_ptr(), 3, 5.0, null_mut()) };
    assert_eq!(rc, TCOMP_ERR_NULL);
    assert_eq!(unsafe { tcomp_skip(s.ptr(), -1.0) }, TCOMP_ERR_ARGUMENT);
    assert_eq!(
        unsafe { tcomp_set_time_on(s.ptr(), f32::NAN) },
        TCOMP_ERR_ARGUMENT
    );
    // The first sample has no features yet if its inputs are bad: raw out, flagged.
    let (rc, out) = step(&mut s, &[f32::NAN, 20.0, 20.0], 5.0);
    assert_eq!(rc, TCOMP_OK);
    assert_eq!(out.compensated, 5.0);
    assert_ne!(out.status & TCOMP_STATUS_INPUT_FAULT, 0);
}

#[test]
fn input_names_are_the_models_in_its_order() {
    let blob = example_blob(1);
    let mut s = Storage::new();
    unsafe { tcomp_load_blob(s.ptr(), blob.as_ptr(), blob.len(), PERIOD) };
    let mut names = Vec::new();
    for i in 0..3 {
        let mut buf = [0u8; 32];
        let n = unsafe { tcomp_channel_input_name(s.ptr(), i, buf.as_mut_ptr().cast(), 32) };
        assert_eq!(n as usize, text(&buf).len());
        names.push(text(&buf));
    }
    assert_eq!(names, ["t_anode_c", "t_cathode_c", "t_shell_c"]);
    // Asking for the length only, and truncation.
    assert_eq!(
        unsafe { tcomp_channel_input_name(s.ptr(), 0, null_mut(), 0) },
        9
    );
    let mut small = [0xFFu8; 4];
    assert_eq!(
        unsafe { tcomp_channel_input_name(s.ptr(), 0, small.as_mut_ptr().cast(), 4) },
        9
    );
    assert_eq!(&small, b"t_a\0");
    assert_eq!(
        unsafe { tcomp_channel_input_name(s.ptr(), 3, small.as_mut_ptr().cast(), 4) },
        TCOMP_ERR_INDEX
    );
}

#[test]
fn an_image_channel_loads_with_its_wiring_and_the_checks_refuse_the_wrong_one() {
    let blob = example_blob(2);
    let (img, hash) = image(0x7C00_0001, &blob);
    let serial = 0x7C00_0001u64;
    let mut s = Storage::new();
    let rc =
        unsafe { tcomp_load_image(s.ptr(), img.as_ptr(), img.len(), 3, &serial, &hash, PERIOD) };
    assert_eq!(rc, TCOMP_OK, "{}", describe(&mut s));
    let mut w = TcompWiring::default();
    assert_eq!(unsafe { tcomp_channel_wiring(s.ptr(), &mut w) }, TCOMP_OK);
    assert_eq!((w.channel_id, w.source_kind, w.source_index), (3, 0, 4));
    assert_eq!(w.scale, 2.5e-5);
    // The model reads anode, cathode, shell; the row wires them to thermometers 1, 2, 3.
    assert_eq!(w.n_inputs, 3);
    assert_eq!(&w.thermometer[..3], &[1, 2, 3]);

    let other = 99u64;
    let cases = [
        (3, Some(&other), None, TCOMP_ERR_IMAGE_OTHER_UNIT),
        (3, None, Some(&other), TCOMP_ERR_IMAGE_BOARD_HASH),
        (9, None, None, TCOMP_ERR_IMAGE_WRONG_CHANNEL),
        (5, None, None, TCOMP_ERR_IMAGE_MISSING),
    ];
    for (id, unit, board, code) in cases {
        let rc = unsafe {
            tcomp_load_image(
                s.ptr(),
                img.as_ptr(),
                img.len(),
                id,
                unit.map_or(null(), |u| u),
                board.map_or(null(), |b| b),
                PERIOD,
            )
        };
        assert_eq!(rc, code, "channel {id}: {}", describe(&mut s));
        assert_eq!(unsafe { tcomp_channel_has_model(s.ptr()) }, 0);
        assert_eq!(
            unsafe { tcomp_channel_wiring(s.ptr(), &mut w) },
            TCOMP_ERR_INDEX
        );
    }
    let mut corrupt = img.clone();
    let last = corrupt.len() - 1;
    corrupt[last] ^= 1;
    let rc = unsafe {
        tcomp_load_image(
            s.ptr(),
            corrupt.as_ptr(),
            corrupt.len(),
            3,
            null(),
            null(),
            PERIOD,
        )
    };
    assert_eq!(rc, TCOMP_ERR_IMAGE_CHECKSUM);
    let erased = vec![0xFFu8; 4096];
    let rc = unsafe {
        tcomp_load_image(
            s.ptr(),
            erased.as_ptr(),
            erased.len(),
            3,
            null(),
            null(),
            PERIOD,
        )
    };
    assert_eq!(rc, TCOMP_ERR_IMAGE_NONE);
    assert_eq!(
        describe(&mut s),
        "image refused: no model image (erased or empty region)"
    );
}

#[test]
fn status_words_are_named_from_the_cores_table() {
    let name = |w: u16| {
        let mut buf = [0u8; 200];
        let n = unsafe { tcomp_status_describe(w, buf.as_mut_ptr().cast(), buf.len()) };
        assert_eq!(n as usize, text(&buf).len());
        text(&buf)
    };
    assert_eq!(name(0), "ok");
    assert_eq!(
        name(TCOMP_STATUS_NO_MODEL | TCOMP_STATUS_INPUT_FAULT),
        "no-model+input-fault"
    );
    assert_eq!(
        name(TCOMP_STATUS_MODEL_FAULT | (1 << 15)),
        "model-fault+overrun"
    );
    assert_eq!(name(1 << 12), "bit12");
    // The longest word fits the 160 bytes the header promises.
    assert!(name(u16::MAX).len() < 160, "{}", name(u16::MAX));
    assert_eq!(unsafe { tcomp_status_describe(3, null_mut(), 0) }, 21);
    assert_eq!(
        unsafe { tcomp_status_describe(3, null_mut(), 5) },
        TCOMP_ERR_NULL
    );
}

#[test]
fn metadata_is_the_blobs_borrowed_in_place() {
    let blob = example_blob(6);
    let mut s = Storage::new();
    let mut meta = std::mem::MaybeUninit::<TcompMeta>::zeroed();
    unsafe { tcomp_channel_init(s.ptr(), PERIOD) };
    assert_eq!(
        unsafe { tcomp_channel_meta(s.ptr(), meta.as_mut_ptr()) },
        TCOMP_ERR_INDEX
    );
    unsafe { tcomp_load_blob(s.ptr(), blob.as_ptr(), blob.len(), PERIOD) };
    assert_eq!(
        unsafe { tcomp_channel_meta(s.ptr(), meta.as_mut_ptr()) },
        TCOMP_OK
    );
    let meta = unsafe { meta.assume_init() };
    let str_of = |t: TcompStr| {
        let bytes = unsafe { std::slice::from_raw_parts(t.ptr.cast::<u8>(), t.len) };
        // Borrowed from the blob, not copied.
        let range = blob.as_ptr_range();
        assert!(t.len == 0 || range.contains(&bytes.as_ptr()));
        std::str::from_utf8(bytes).unwrap().to_string()
    };
    let model = M::decode(&blob).unwrap();
    assert_eq!(meta.sensor, 0);
    assert_eq!(str_of(meta.axis), model.meta.axis);
    assert_eq!(str_of(meta.unit), "deg/h");
    assert_eq!(str_of(meta.time_column), "time_s");
    assert_eq!(str_of(meta.target_column), "gyro_dph");
    assert_eq!(str_of(meta.reference_column), "ref_dph");
    assert!(meta.reference_value.is_nan());
    assert_eq!(usize::from(meta.n_centers), model.rbf.centers.len());
    assert_eq!((meta.n_features, meta.n_inputs), (4, 3));
    assert_eq!(meta.format_version, model.version);
}
