//! Smoke run under QEMU: decode an embedded blob, replay a few hundred samples through the
//! compensator, compare every output bit for bit with the host's, count instructions, and exit with
//! QEMU's status telling the verdict. A panic or HardFault also ends the run with a failure code.
#![no_std]
#![no_main]

use cortex_m_rt::{ExceptionFrame, entry, exception};
use cortex_m_semihosting::hprintln;
use tcomp_board_qemu::drivers::{InstructionCounter, exit};
use tcomp_core::{Channel, Model, Status};

/// The example RLG model, encoded by the build script with the host's `tcomp-core`.
static BLOB: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/smoke_model.tcm"));
/// The same model made additive (each center over one feature; blob format 3).
static ADDITIVE: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/smoke_additive.tcm"));
/// The same model with every kind of term: steps, ramps, Gaussians, a square and a cube (blob
/// format 5).
static KINDS: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/smoke_kinds.tcm"));
/// The host's output of [`KINDS`] at eight points on its range box's diagonal (f32 LE each).
static KINDS_EXPECTED: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/smoke_kinds_expected.bin"));
/// Per sample: anode, cathode, shell (°C), raw (deg/h), host-compensated (f32 LE), host status (u32 LE).
static VECTOR: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/smoke_vector.bin"));
const RECORD: usize = 24;
const PERIOD_S: f32 = 0.005;
/// Evaluations timed for the per-evaluation instruction figure.
const TIMED_EVALS: u32 = 1000;

fn f32_at(rec: &[u8], i: usize) -> f32 {
    let mut b = [0u8; 4];
    if let Some(s) = rec.get(i * 4..i * 4 + 4) {
        b.copy_from_slice(s);
    }
    f32::from_le_bytes(b)
}

#[entry]
fn main() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        exit(false)
    };
    let counter = InstructionCounter::new(cp.SYST);

    let model = match Model::<'_, 32, 4, 24>::decode(BLOB) {
        Ok(m) => m,
        Err(e) => {
            hprintln!("FAIL: blob rejected: {}", e);
            exit(false)
        }
    };
    hprintln!(
        "model: {} centers x {} features, blob {} bytes",
        model.rbf.centers.len(),
        model.n_features(),
        BLOB.len()
    );

    // A corrupted copy must be refused with a reason, not crash.
    let mut corrupt = [0u8; 2048];
    let n = BLOB.len().min(corrupt.len());
    corrupt[..n].copy_from_slice(&BLOB[..n]);
    corrupt[n / 2] ^= 0x40;
    let corrupt_rejected = Model::<'_, 32, 4, 24>::decode(&corrupt[..n]).is_err();

    let mut channel = Channel::<24, 4>::new(PERIOD_S);
    let (mut samples, mut mismatches, mut flagged) = (0u32, 0u32, 0u32);
    let mut first_mismatch = None;
    let (mut steps_instr, mut steps) = (0u64, 0u64);
    for rec in VECTOR.chunks_exact(RECORD) {
        let temps = [f32_at(rec, 0), f32_at(rec, 1), f32_at(rec, 2)];
        let raw = f32_at(rec, 3);
        let expected = f32_at(rec, 4).to_bits();
        let expected_status = f32_at(rec, 5).to_bits();
        let t0 = counter.now();
        let out = channel.step(Some(&model), &temps, raw);
        let t1 = counter.now();
        steps_instr += u64::from(counter.instructions_between(t0, t1));
        steps += 1;
        if out.compensated.to_bits() != expected || u32::from(out.status.0) != expected_status {
            mismatches += 1;
            first_mismatch.get_or_insert(samples);
        }
        if !out.status.is_ok() {
            flagged += 1;
        }
        samples += 1;
    }

    // Instructions per RBF evaluation (32 x 4), call and loop overhead included: eight feature
    // vectors around the last one, cycled so no evaluation can be hoisted out of the loop.
    let base = *channel.features();
    let points: [[f32; 4]; 8] = core::array::from_fn(|i| {
        let mut p = base;
        p[0] += i as f32 * 0.5;
        p[1] -= i as f32 * 0.1;
        p
    });
    let mut sink = 0.0f32;
    let per_eval = per_rbf_eval(&counter, &model, &points, &mut sink);
    // The same for the additive model (masked distances).
    let additive = match Model::<'_, 32, 4, 24>::decode(ADDITIVE) {
        Ok(m) => m,
        Err(e) => {
            hprintln!("FAIL: additive blob rejected: {}", e);
            exit(false)
        }
    };
    let per_additive = per_rbf_eval(&counter, &additive, &points, &mut sink);
    // The model with every kind: bit for bit with the host at the eight points, and its cost.
    let kinds = match Model::<'_, 32, 4, 24>::decode(KINDS) {
        Ok(m) => m,
        Err(e) => {
            hprintln!("FAIL: blob with every kind rejected: {}", e);
            exit(false)
        }
    };
    let kind_points: [[f32; 4]; 8] = core::array::from_fn(|i| {
        let mut x = [0.0f32; 4];
        for (k, r) in kinds.ranges.iter().enumerate().take(4) {
            x[k] = r.lo + (r.hi - r.lo) * i as f32 / 7.0;
        }
        x
    });
    let mut kinds_mismatches = 0u32;
    for (i, x) in kind_points.iter().enumerate() {
        if rbf_eval(&kinds, x).to_bits() != f32_at(KINDS_EXPECTED, i).to_bits() {
            kinds_mismatches += 1;
        }
    }
    let per_kinds = per_rbf_eval(&counter, &kinds, &kind_points, &mut sink);
    let per_step = steps_instr.checked_div(steps).unwrap_or(0);

    hprintln!(
        "samples={} mismatches={} flagged={} first_mismatch={:?}",
        samples,
        mismatches,
        flagged,
        first_mismatch
    );
    hprintln!(
        "corrupt_blob_rejected={} checksum_sink={}",
        corrupt_rejected,
        sink
    );
    hprintln!("kinds_mismatches={}", kinds_mismatches);
    hprintln!(
        "SMOKE-SUMMARY instructions_per_rbf_eval={} instructions_per_additive_rbf_eval={} instructions_per_kinds_rbf_eval={} instructions_per_channel_step={}",
        per_eval,
        per_additive,
        per_kinds,
        per_step
    );
    let ok = samples > 0
        && mismatches == 0
        && kinds_mismatches == 0
        && flagged >= 2
        && corrupt_rejected
        && sink.is_finite();
    let _ = Status::OK;
    hprintln!("{}", if ok { "SMOKE OK" } else { "SMOKE FAIL" });
    exit(ok)
}

/// Instructions per [`rbf_eval`] of `model`, averaged over [`TIMED_EVALS`] calls cycling through
/// `points`; each output is added to `sink` so that no call is optimised away.
fn per_rbf_eval(
    counter: &InstructionCounter,
    model: &Model<'_, 32, 4, 24>,
    points: &[[f32; 4]; 8],
    sink: &mut f32,
) -> u32 {
    let t0 = counter.now();
    for i in 0..TIMED_EVALS {
        let x = core::hint::black_box(&points[(i & 7) as usize]);
        *sink += rbf_eval(model, x);
    }
    let t1 = counter.now();
    counter.instructions_between(t0, t1) / TIMED_EVALS
}

/// One RBF evaluation in a function of its own, so the figure measures the evaluator as the
/// compensator calls it and not how the register allocator of this long `main` happens to treat
/// an inlined copy (which moved it by 5 % when unrelated code was added to `main`).
#[inline(never)]
fn rbf_eval(model: &Model<'_, 32, 4, 24>, x: &[f32; 4]) -> f32 {
    model.rbf.eval(x)
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    hprintln!("HardFault at pc={:#x}", frame.pc());
    exit(false)
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    exit(false)
}
