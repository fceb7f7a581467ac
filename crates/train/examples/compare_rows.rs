//! The tcomp side of `scripts/sklearn_compare.py`: hands scikit-learn exactly the numbers tcomp fits
//! on, and times tcomp in-process on the same machine and thread budget.
//!
//! `cargo run --release -p tcomp-train --example compare_rows -- SIM_DIR OUT_DIR [REPS]` reads the
//! simulated RLG run (`tcomp simulate --preset rlg --out SIM_DIR`), and writes into OUT_DIR:
//! `train_rows.csv` and `verify_rows.csv` (time, the four features computed by the core's feature
//! program for every sample, error = gyro − reference), `train_bins.csv` (the binned rows tcomp's
//! `bayes` fits on), and `tcomp.json`: the median wall time of `fit` over REPS repetitions (features
//! over every row, binning, the evidence search with 32 centers, the blob and the training
//! figures through it), of the part before the blob (features, binning, search), and the held-out
//! std of 100 s bin means of the residual on the verification run.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::path::Path;
use std::time::Instant;
use tcomp_train::dataset::stretch_starts;
use tcomp_train::{Dataset, FitOptions, Roles, blob_io, evaluate, features, fit};

#[path = "../benches/support/rlg_case.rs"]
mod rlg_case;

fn write_rows(data: &Dataset, opts: &FitOptions, path: &Path) {
    let program = opts.spec.program().unwrap();
    let time = data.time("time_s").unwrap();
    let rows = features::compute(&program, data, time, &stretch_starts(time, None)).unwrap();
    let gyro = data.column("gyro_dph").unwrap();
    let reference = data.column("ref_dph").unwrap();
    let mut w = csv::Writer::from_path(path).unwrap();
    w.write_record(["time_s", "f0", "f1", "f2", "f3", "error"])
        .unwrap();
    for (i, r) in rows.iter().enumerate() {
        let mut rec = vec![format!("{}", time[i])];
        rec.extend(r.iter().take(4).map(|v| format!("{v:e}")));
        rec.push(format!("{:e}", gyro[i] - reference[i]));
        w.write_record(&rec).unwrap();
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let sim = Path::new(&args[1]);
    let out = Path::new(&args[2]);
    let reps: usize = args.get(3).map_or(11, |s| s.parse().unwrap());
    std::fs::create_dir_all(out).unwrap();
    let train = Dataset::load(&sim.join("train.csv")).unwrap();
    let verify = Dataset::load(&sim.join("verify.csv")).unwrap();
    let opts = rlg_case::options();
    write_rows(&train, &opts, &out.join("train_rows.csv"));
    write_rows(&verify, &opts, &out.join("verify_rows.csv"));
    let (x, y) = tcomp_train::train::training_rows(&train, &opts).unwrap();
    let mut w = csv::Writer::from_path(out.join("train_bins.csv")).unwrap();
    w.write_record(["f0", "f1", "f2", "f3", "error"]).unwrap();
    for (r, v) in x.iter().zip(&y) {
        let mut rec: Vec<String> = r.iter().map(|a| format!("{a:e}")).collect();
        rec.push(format!("{v:e}"));
        w.write_record(&rec).unwrap();
    }
    w.flush().unwrap();

    let bo = tcomp_train::bayes::BayesOptions {
        centers: opts.centers,
        ..Default::default()
    };
    let (mut t_fit, mut t_search) = (Vec::new(), Vec::new());
    let mut fitted = None;
    for _ in 0..reps {
        let t = Instant::now();
        let (x, y) = tcomp_train::train::training_rows(&train, &opts).unwrap();
        let _ = tcomp_train::bayes::fit(&x, &y, &bo).unwrap();
        t_search.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        fitted = Some(fit(&train, &opts).unwrap());
        t_fit.push(t.elapsed().as_secs_f64());
    }
    let f = fitted.unwrap();
    let bytes = f.model.to_bytes().unwrap();
    let m = blob_io::decode(Path::new("compare.tcm"), &bytes).unwrap();
    let r = evaluate(&m, &verify, &Roles::of_model(&m), 100.0, None, None).unwrap();
    let json = serde_json::json!({
        "rows": train.len(),
        "bins": y.len(),
        "centers": f.summary.centers,
        "settings_evaluated": f.summary.details.settings_evaluated,
        "threads": rayon::current_num_threads(),
        "fit_s": median(t_fit),
        "features_bins_search_s": median(t_search),
        "held_out_100s_std": r.binned.residual_std,
        "reps": reps,
    });
    std::fs::write(out.join("tcomp.json"), json.to_string()).unwrap();
    println!("{json}");
}
