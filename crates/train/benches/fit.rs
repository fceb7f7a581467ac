//! Fit time of the trainer on the reference case: the `rlg` preset's 6.1-hour training run
//! at 1 Hz (21,961 rows; T = mean of three thermometers, rate(T) and two gradients), `bayes` with 32
//! centers, on one thread (run with `RAYON_NUM_THREADS=1`, as BENCHMARKS.md does).
//!
//! `fit_22k_bayes_32c` is everything `tcomp fit` does after the CSV is read: the core's feature
//! program over every row, binning, the evidence search, the blob, and the training figures through
//! the decoded blob. `bayes_search_32c` is the evidence search alone on the binned rows (the part the
//! scikit-learn comparison in `scripts/sklearn_compare.py` times on its side). `load_csv_22k` is the
//! CSV read that `tcomp fit` adds on top.
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use tcomp_train::bayes::{self, BayesOptions};
use tcomp_train::{Dataset, fit};

#[path = "support/rlg_case.rs"]
mod rlg_case;

fn benches(c: &mut Criterion) {
    let p = tcomp_sim::presets::preset("rlg").unwrap().with_seed(1);
    let (tt, _) = tcomp_sim::simulate(&p.train).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("train.csv");
    let mut w = csv::Writer::from_path(&csv).unwrap();
    w.write_record(&tt.names).unwrap();
    for i in 0..tt.columns.first().map_or(0, Vec::len) {
        w.write_record(tt.columns.iter().map(|c| format!("{:.6}", c[i])))
            .unwrap();
    }
    w.flush().unwrap();
    let data = Dataset::load(&csv).unwrap();
    let opts = rlg_case::options();
    let binned = tcomp_train::train::training_rows(&data, &opts).unwrap();

    let mut g = c.benchmark_group("trainer");
    g.sample_size(20);
    g.bench_function("load_csv_22k", |b| {
        b.iter(|| Dataset::load(black_box(&csv)).unwrap())
    });
    g.bench_function("fit_22k_bayes_32c", |b| {
        b.iter(|| fit(black_box(&data), &opts).unwrap())
    });
    let bo = BayesOptions {
        centers: Some(32),
        ..BayesOptions::default()
    };
    g.bench_function("bayes_search_32c", |b| {
        b.iter(|| bayes::fit(black_box(&binned.0), &binned.1, &bo).unwrap())
    });
    g.finish();
}

criterion_group!(trainer, benches);
criterion_main!(trainer);
