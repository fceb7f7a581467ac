//! No path through the C API panics, whatever the caller passes: arbitrary bytes as blobs and
//! images (and valid ones with bytes flipped, which reach deeper), then arbitrary sequences of
//! calls with arbitrary floats, lengths, indices and buffer sizes on the loaded channel.
//!
//! Why this test: on the host a panic would be caught and returned as `TCOMP_ERR_PANIC`; on a
//! bare-metal target it stops the firmware in `tcomp_panic_hook`. Neither may happen on data, so
//! every call here must return anything but `TCOMP_ERR_PANIC`, and every step must keep the
//! output promise (a finite raw value never leaves as NaN with status 0).
#![allow(unsafe_code, clippy::unwrap_used, missing_docs)]
// Every unsafe call below passes pointers to live Rust buffers with their true lengths (or NULL
// on purpose): the C API's contract, kept by construction.
#![allow(clippy::undocumented_unsafe_blocks)]

mod common;

use common::{Storage, example_blob, image};
use proptest::prelude::*;
use std::ptr::null;
use tcomp_ffi::*;

/// Cases per property: the core's decoders are fuzzed with 100,000 cases each in its own tests;
/// here the boundary around them, 10,000 cases per property (about 10 s of CPU).
const CASES: u32 = 10_000;

/// One call on a channel.
#[derive(Clone, Debug)]
enum Call {
    Step {
        inputs: Vec<f32>,
        raw: f32,
    },
    StepDt {
        inputs: Vec<f32>,
        dt: f32,
        gap: bool,
        raw: f32,
    },
    Skip(f32),
    Reset,
    TimeOn(f32),
    InputName {
        index: usize,
        buf: usize,
    },
    Describe {
        buf: usize,
    },
    Wiring,
    Status {
        word: u16,
        buf: usize,
    },
}

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -100.0f32..100.0,
        1 => any::<f32>(),
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(0.0f32),
        1 => Just(1e-30f32),
    ]
}

fn call() -> impl Strategy<Value = Call> {
    prop_oneof![
        6 => (prop::collection::vec(any_f32(), 0..6), any_f32())
            .prop_map(|(inputs, raw)| Call::Step { inputs, raw }),
        4 => (prop::collection::vec(any_f32(), 0..6), any_f32(), any::<bool>(), any_f32())
            .prop_map(|(inputs, dt, gap, raw)| Call::StepDt { inputs, dt, gap, raw }),
        1 => any_f32().prop_map(Call::Skip),
        1 => Just(Call::Reset),
        1 => any_f32().prop_map(Call::TimeOn),
        1 => (0usize..12, 0usize..40).prop_map(|(index, buf)| Call::InputName { index, buf }),
        1 => (0usize..200).prop_map(|buf| Call::Describe { buf }),
        1 => Just(Call::Wiring),
        1 => (any::<u16>(), 0usize..200).prop_map(|(word, buf)| Call::Status { word, buf }),
    ]
}

/// Runs `calls` on the channel at `s`, asserting no call panicked and every output kept its
/// promise.
fn run(s: &mut Storage, calls: &[Call]) {
    for c in calls {
        let rc = match c {
            Call::Step { inputs, raw } | Call::StepDt { inputs, raw, .. } => {
                let mut out = TcompOutput::default();
                let rc = match c {
                    Call::StepDt { dt, gap, .. } => unsafe {
                        tcomp_step_dt(
                            s.ptr(),
                            inputs.as_ptr(),
                            inputs.len(),
                            *dt,
                            *gap,
                            *raw,
                            &mut out,
                        )
                    },
                    _ => unsafe {
                        tcomp_step(s.ptr(), inputs.as_ptr(), inputs.len(), *raw, &mut out)
                    },
                };
                if raw.is_finite() && out.status == 0 {
                    assert!(out.compensated.is_finite(), "{c:?} gave {out:?}");
                }
                if out.status & TCOMP_STATUS_NO_MODEL != 0 || rc != TCOMP_OK {
                    assert_eq!(
                        out.compensated.to_bits(),
                        raw.to_bits(),
                        "{c:?} gave {out:?}"
                    );
                }
                rc
            }
            Call::Skip(x) => unsafe { tcomp_skip(s.ptr(), *x) },
            Call::Reset => unsafe { tcomp_reset(s.ptr()) },
            Call::TimeOn(x) => unsafe { tcomp_set_time_on(s.ptr(), *x) },
            Call::InputName { index, buf } => {
                let mut b = vec![0u8; *buf];
                unsafe { tcomp_channel_input_name(s.ptr(), *index, b.as_mut_ptr().cast(), *buf) }
            }
            Call::Describe { buf } => {
                let mut b = vec![0u8; *buf];
                let n = unsafe { tcomp_channel_describe(s.ptr(), b.as_mut_ptr().cast(), *buf) };
                if *buf > 0 {
                    assert!(b.contains(&0), "not NUL-terminated");
                }
                n
            }
            Call::Wiring => {
                let mut w = TcompWiring::default();
                unsafe { tcomp_channel_wiring(s.ptr(), &mut w) }
            }
            Call::Status { word, buf } => {
                let mut b = vec![0u8; *buf];
                unsafe { tcomp_status_describe(*word, b.as_mut_ptr().cast(), *buf) }
            }
        };
        assert_ne!(rc, TCOMP_ERR_PANIC, "{c:?} panicked");
    }
}

/// A valid blob with up to four bytes replaced (the CRC usually catches it; a case that fixes
/// nothing up is still a valid path).
fn mutated(base: Vec<u8>) -> impl Strategy<Value = Vec<u8>> {
    let n = base.len();
    prop::collection::vec((0..n, any::<u8>()), 0..4).prop_map(move |edits| {
        let mut b = base.clone();
        for (i, v) in edits {
            b[i] = v;
        }
        b
    })
}

fn blob_bytes() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        prop::collection::vec(any::<u8>(), 0..2048),
        mutated(example_blob(9)),
        // A valid blob cut short or with bytes appended.
        (0usize..1200).prop_map(|n| {
            let b = example_blob(9);
            b[..n.min(b.len())].to_vec()
        }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: CASES, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn no_blob_and_no_call_sequence_panics(
        bytes in blob_bytes(),
        period in any_f32(),
        calls in prop::collection::vec(call(), 0..24),
    ) {
        let mut why = [0u8; 64];
        let rc = unsafe { tcomp_validate_blob(bytes.as_ptr(), bytes.len(), why.as_mut_ptr().cast(), why.len()) };
        prop_assert_ne!(rc, TCOMP_ERR_PANIC);
        let mut s = Storage::new();
        let rc = unsafe { tcomp_load_blob(s.ptr(), bytes.as_ptr(), bytes.len(), period) };
        prop_assert_ne!(rc, TCOMP_ERR_PANIC);
        // Also on a channel that did load (the mutations mostly fail the CRC).
        let good = example_blob(9);
        run(&mut s, &calls);
        let rc = unsafe { tcomp_load_blob(s.ptr(), good.as_ptr(), good.len(), 0.005) };
        prop_assert_eq!(rc, TCOMP_OK);
        run(&mut s, &calls);
    }

    #[test]
    fn no_image_panics(
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..4),
        garbage in prop::collection::vec(any::<u8>(), 0..512),
        id in 0u16..12,
        serial in prop::option::of(any::<u64>()),
        use_garbage in any::<bool>(),
        calls in prop::collection::vec(call(), 0..8),
    ) {
        let blob = example_blob(5);
        let (mut img, hash) = image(7, &blob);
        for (i, v) in edits {
            let at = i.index(img.len());
            img[at] = v;
        }
        let bytes = if use_garbage { garbage } else { img };
        let mut s = Storage::new();
        let rc = unsafe {
            tcomp_load_image(
                s.ptr(),
                bytes.as_ptr(),
                bytes.len(),
                id,
                serial.as_ref().map_or(null(), |v| v),
                &hash,
                0.005,
            )
        };
        prop_assert_ne!(rc, TCOMP_ERR_PANIC);
        run(&mut s, &calls);
    }
}
