//! Benchmark of `diagnose`: target ≤ 2 s on a 22,000-row file on 2 cores (issue 24; it was ≤ 5 s
//! for ≥ 20 candidate fits before the placebo test).
//!
//! Run with `cargo bench -p tcomp-discover --bench diagnose`. A plain timing binary (no criterion):
//! one diagnosis is seconds long, so a handful of repetitions gives a stable figure. It simulates
//! the `rlg` preset's 6.1 h training run at 1 s (21,961 rows, five thermometer-like columns and a
//! supply voltage), fits (T, dT/dt) without the gradients, and times the diagnosis with held-out
//! blocks and with the verification run.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::time::Instant;
use tcomp_demo::{fit_features, simulated};
use tcomp_discover::{DiagnoseOptions, diagnose};

fn main() {
    let preset = tcomp_sim::presets::preset("rlg").expect("preset");
    let sim = simulated(&preset).expect("simulate");
    let signals = vec!["T = mean(t_anode_c, t_cathode_c, t_shell_c)".to_string()];
    let feats = vec!["T".to_string(), "rate(T)".to_string()];
    let fitted = fit_features(&sim.train, &sim.train_truth, &signals, &feats).expect("fit");
    let bytes = fitted.model.to_bytes().expect("encode");
    let model = tcomp_train::blob_io::decode("bench.tcm".as_ref(), &bytes).expect("decode");
    println!(
        "rows: train {}, verify {}; threads: {}",
        sim.train.len(),
        sim.verify.len(),
        rayon::current_num_threads()
    );
    for (name, verify) in [("blocks", None), ("verify", Some(&sim.verify))] {
        let mut times = Vec::new();
        let mut fits = 0;
        let mut verdict = String::new();
        for _ in 0..3 {
            let t = Instant::now();
            let a = diagnose(&model, &sim.train, verify, &DiagnoseOptions::default()).unwrap();
            times.push(t.elapsed().as_secs_f64());
            fits = a.diagnosis.fits;
            verdict = a.diagnosis.verdict_text.clone();
        }
        times.sort_by(f64::total_cmp);
        println!(
            "diagnose ({name}): {fits} candidate fits, median {:.2} s (min {:.2}, max {:.2}) — target ≤ 2 s on 2 cores\n  {verdict}",
            times[1], times[0], times[2]
        );
    }
}
