//! The streaming evaluator's memory does not grow with the log's length: the peak of heap bytes
//! held while evaluating a generated 200,000-row 100 Hz log is that of a 20,000-row one (give or
//! take the per-bin summaries), while the in-memory path's grows tenfold. Measured with a counting
//! global allocator (bytes held, not wall-clock).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use peakmem_alloc::{INSTRUMENTED_SYSTEM, PeakMemAlloc, PeakMemAllocTrait};
use std::alloc::System;
use std::io::Cursor;
use tcomp_sim::{presets, simulate};
use tcomp_train::{
    Dataset, FitOptions, Method, Roles, StreamOptions, blob_io, eval_stream_reader, fit,
};

#[global_allocator]
static GLOBAL: &PeakMemAlloc<System> = &INSTRUMENTED_SYSTEM;

/// A 100 Hz RLG-like log of `rows` rows with the simulator's column names, its temperatures
/// ramping and holding.
fn log(rows: usize) -> Vec<u8> {
    let mut out = b"time_s,t_anode_c,t_cathode_c,t_shell_c,gyro_dph,ref_dph\n".to_vec();
    for i in 0..rows {
        let t = i as f64 * 0.01;
        let temp = 20.0 + 10.0 * (t / 900.0).sin();
        let noise = ((i * 7919) % 1000) as f64 * 1e-4;
        let gyro = 10.0 + 0.01 * temp + noise;
        out.extend_from_slice(
            format!(
                "{t:.4},{:.4},{:.4},{temp:.4},{gyro:.6},10.0\n",
                temp + 0.3,
                temp + 0.1
            )
            .as_bytes(),
        );
    }
    out
}

fn peak<T>(f: impl FnOnce() -> T) -> (T, usize) {
    GLOBAL.reset_peak_memory();
    let v = f();
    (v, GLOBAL.get_peak_memory())
}

#[test]
fn streaming_memory_does_not_grow_with_the_length() {
    let p = presets::preset("rlg").unwrap();
    let (tt, truth) = simulate(&p.train).unwrap();
    let train = Dataset::from_columns("train", tt.names, tt.columns);
    let mut o = FitOptions::new(&truth.columns.target, &[]);
    o.spec.signals = vec!["T=mean(t_anode_c, t_cathode_c, t_shell_c)".into()];
    o.spec.features = [
        "T",
        "rate(T)",
        "t_anode_c - t_shell_c",
        "t_cathode_c - t_shell_c",
    ]
    .map(String::from)
    .to_vec();
    o.reference = Some(truth.columns.reference.clone());
    o.method = Method::Bayes;
    let blob = fit(&train, &o).unwrap().model.to_bytes().unwrap();
    let model = blob_io::decode(std::path::Path::new("m.tcm"), &blob).unwrap();
    let opts = StreamOptions {
        roles: Roles::of_model(&model),
        bin_s: 50.0,
        ..StreamOptions::default()
    };
    let (short, long) = (log(20_000), log(200_000));
    let stream = |bytes: &[u8]| {
        peak(|| eval_stream_reader("log.csv", Cursor::new(bytes), false, &model, &opts).unwrap())
    };
    let (rs, ps) = stream(&short);
    let (rl, pl) = stream(&long);
    assert_eq!((rs.samples, rl.samples), (20_000, 200_000));
    assert!(
        tcomp_train::long_log::streamed_only(Cursor::new(&long), false, &model, &opts).is_some(),
        "the long log is streamed, not loaded"
    );
    println!("peak heap while streaming: 20,000 rows {ps} B, 200,000 rows {pl} B");
    // What may grow is the per-bin summaries (O(bins), not O(rows)): 1,800 s more is 36 × 50 s
    // and 30 × 60 s bins of 136 B each, in vectors that double their capacity (~16 kB here).
    assert!(pl <= ps + 64 * 1024, "{ps} B → {pl} B");
    assert!(pl < 1 << 20, "{pl} B");
    // The in-memory path on the same logs: its peak grows with the rows, so the check above
    // could see growth.
    let load = |bytes: &[u8]| {
        peak(|| {
            let d = Dataset::from_reader("log.csv", bytes).unwrap();
            tcomp_train::evaluate(&model, &d, &opts.roles, 50.0, None, None).unwrap()
        })
    };
    let ((_, ms), (_, ml)) = (load(&short), load(&long));
    println!("peak heap in memory: 20,000 rows {ms} B, 200,000 rows {ml} B");
    assert!(
        ml > 5 * ms && ml > 20 * pl,
        "{ms} B → {ml} B (streaming {pl} B)"
    );
}
