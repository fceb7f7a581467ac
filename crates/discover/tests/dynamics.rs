//! The residual's dynamics read from the data (`tcomp_discover::dynamics`): a QMA whose bias
//! responds to its thermometer through two thermal paths of very different time constants
//! (15 min and 2.5 h), hidden from a model given the rest of the truth. The lag bank must report
//! two time constants, separated (a factor of 3 at least), the faster within a factor of two of
//! its truth; the slower is printed beside its truth (measured 4100 s for 9000 s: a 2.5-hour path
//! on a 6-hour run is half absorbed by the model's own terms in T). The diagnosis is printed.
//!
//! `cargo test --release -p tcomp-discover --test dynamics -- --nocapture`
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use tcomp_demo::{fit_features, simulated};
use tcomp_discover::score::{ScoreOptions, prepare};
use tcomp_discover::{DiagnoseOptions, diagnose, dynamics, model_info};
use tcomp_train::Dataset;

/// A first-order lag of `x` (time constant `tau` s) over rows `dt` s apart.
fn lag(x: &[f64], tau: f64, dt: f64) -> Vec<f64> {
    let a = (-dt / tau).exp();
    let mut l = x.first().copied().unwrap_or(0.0);
    x.iter()
        .map(|v| {
            l = a * l + (1.0 - a) * v;
            l
        })
        .collect()
}

/// `data` with `add` added to its column `target`.
fn plus(data: &Dataset, target: &str, add: &[f64]) -> Dataset {
    let names = data.names().to_vec();
    let cols = names
        .iter()
        .map(|n| {
            let c = data.column(n).unwrap();
            if n == target {
                c.iter().zip(add).map(|(a, b)| a + b).collect()
            } else {
                c.to_vec()
            }
        })
        .collect();
    Dataset::from_columns(data.file(), names, cols)
}

#[test]
fn two_thermal_paths_come_out_as_two() {
    let truth_taus = [900.0, 9000.0];
    // A QMA whose only modelled effect is its bias polynomial in T: the model is given T, and the
    // two paths' departures from the thermometer are what it lacks.
    let preset = tcomp_sim::presets::with_effects(
        tcomp_sim::SensorKind::Qma,
        &[tcomp_sim::EffectKind::Poly],
    )
    .unwrap()
    .with_seed(21);
    let mut sim = simulated(&preset).unwrap();
    let t_col = "t_qma_c";
    let target = sim.train_truth.columns.target.clone();
    let floor = sim.verify_truth.noise.std_100s;
    for d in [&mut sim.train, &mut sim.verify] {
        let time = d.column("time_s").unwrap().to_vec();
        let dt = time.get(1).zip(time.first()).map_or(1.0, |(b, a)| b - a);
        let t = d.column(t_col).unwrap().to_vec();
        // Each path's bias follows its own lag of the temperature; scaled so that each path's
        // departure from the thermometer is a few times the noise floor on a ramp.
        let mut effect = vec![0.0; t.len()];
        for tau in truth_taus {
            let l = lag(&t, tau, dt);
            let dev: Vec<f64> = l.iter().zip(&t).map(|(a, b)| a - b).collect();
            let sd = (dev.iter().map(|v| v * v).sum::<f64>() / dev.len() as f64).sqrt();
            for (e, v) in effect.iter_mut().zip(&dev) {
                *e += 6.0 * floor * v / sd.max(1e-12);
            }
        }
        *d = plus(d, &target, &effect);
    }
    let truth = &sim.train_truth;
    let signals: Vec<String> = truth
        .true_features
        .signals
        .iter()
        .map(|(k, v)| format!("{k} = {v}"))
        .collect();
    let base = truth.true_features.features.clone();
    let fitted = fit_features(&sim.train, truth, &signals, &base).unwrap();
    let bytes = fitted.model.to_bytes().unwrap();
    let model = tcomp_train::blob_io::decode("m.tcm".as_ref(), &bytes).unwrap();
    let info = model_info(&model);
    let p = prepare(
        &info.spec,
        &info.roles,
        &sim.train,
        None,
        &ScoreOptions::default(),
    )
    .unwrap();
    let found = dynamics::time_constants(&p, t_col);
    let a = diagnose(
        &model,
        &sim.train,
        Some(&sim.verify),
        &DiagnoseOptions::default(),
    )
    .unwrap();
    println!(
        "truth τ {truth_taus:?}; the bank reads {found:?}\nverdict {:?}: {}",
        a.diagnosis.verdict, a.diagnosis.verdict_text
    );
    for c in a.diagnosis.candidates.iter().take(6) {
        println!("  {:<60} {}", c.effect, c.fails.join("; "));
    }
    assert_eq!(found.len(), 2, "{found:?}");
    assert!(found[1] / found[0] >= 3.0, "{found:?}");
    let fast = found[0] / truth_taus[0];
    assert!(
        (0.5..2.0).contains(&fast),
        "{found:?} against {truth_taus:?}"
    );
}
