//! Host timings of the per-sample path: RBF evaluation (32 centers × 4 features), a feature-program
//! step, a whole compensator step, and blob decoding. Instruction counts on the target come from
//! the QEMU run (`cargo xtask qemu`), not from here.
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use tcomp_core::testing::{example_model, example_sample};
use tcomp_core::{Channel, Model, ProgramState};

fn benches(c: &mut Criterion) {
    let model = example_model::<32, 4, 24>(32, 11);
    let x = [25.0f32, 1.0, 0.3, -0.2];
    c.bench_function("rbf_eval_32x4", |b| {
        b.iter(|| model.rbf.eval(black_box(&x)))
    });

    let mut state = ProgramState::<24>::new();
    let mut n = 0u32;
    c.bench_function("program_step_rlg", |b| {
        b.iter(|| {
            let (t, _) = example_sample(n, 0.005);
            n = n.wrapping_add(1);
            state.step(&model.program, black_box(&t), 0.005).unwrap();
        })
    });

    let mut ch = Channel::<24, 4>::new(0.005);
    c.bench_function("channel_step_32x4", |b| {
        b.iter(|| {
            let (t, raw) = example_sample(n, 0.005);
            n = n.wrapping_add(1);
            ch.step(Some(&model), black_box(&t), raw)
        })
    });

    let mut buf = [0u8; 4096];
    let len = model.encode(&mut buf).unwrap();
    c.bench_function("blob_decode_32x4", |b| {
        b.iter(|| Model::<'_, 32, 4, 24>::decode(black_box(&buf[..len])).unwrap())
    });
}

criterion_group!(core_benches, benches);
criterion_main!(core_benches);
