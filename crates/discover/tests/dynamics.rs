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

/// The scenario: a QMA whose only modelled effect is its bias polynomial in T, plus two thermal
/// paths of time constants `taus`; the model given the rest of the truth. Returns the runs, the
/// model's signals and features and the noise floor.
fn two_paths(taus: [f64; 2]) -> (tcomp_demo::Simulated, Vec<String>, Vec<String>, f64) {
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
        for tau in taus {
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
    (sim, signals, base, floor)
}

#[test]
fn two_thermal_paths_come_out_as_two() {
    let truth_taus = [900.0, 9000.0];
    let t_col = "t_qma_c";
    let (sim, signals, base, _) = two_paths(truth_taus);
    let truth = &sim.train_truth;
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

/// The same two paths found over rounds: whatever each round names, every added parameter is
/// re-estimated together after it, and the final model's verification residual is printed beside
/// the model with the true pair.
#[test]
fn two_thermal_paths_over_rounds() {
    let truth_taus = [900.0, 9000.0];
    let (sim, signals, base, floor) = two_paths(truth_taus);
    let truth = &sim.train_truth;
    let fitted = fit_features(&sim.train, truth, &signals, &base).unwrap();
    let bytes = fitted.model.to_bytes().unwrap();
    let model = tcomp_train::blob_io::decode("m.tcm".as_ref(), &bytes).unwrap();
    let r = tcomp_discover::rounds::diagnose_rounds(
        &model,
        &sim.train,
        Some(&sim.verify),
        &DiagnoseOptions::default(),
        3,
    )
    .unwrap();
    let ratio = |features: &[String]| {
        let f = fit_features(&sim.train, truth, &signals, features).unwrap();
        tcomp_demo::evaluate(&f, &sim.verify)
            .unwrap()
            .binned
            .residual_std
            / floor
    };
    for (a, x) in r.analyses.iter().zip(0..) {
        println!("round {}: {}", x + 1, a.diagnosis.verdict_text);
    }
    for x in &r.applied {
        println!(
            "round {} added {:?}; re-estimated {:?}",
            x.round, x.expressions, x.reestimated
        );
    }
    let mut with_truth = base.clone();
    with_truth.extend(truth_taus.iter().map(|t| format!("lag(t_qma_c, {t})")));
    let (after, limit) = (ratio(&r.final_features), ratio(&with_truth));
    println!(
        "stopped: {}\nfinal {:?}: {after:.2}× the floor; with the true pair {limit:.2}×",
        r.stopped, r.final_features
    );
    // The rounds name a thermal path, and what they end with is better on the verification run
    // than the model they started from.
    assert!(!r.applied.is_empty(), "{}", r.stopped);
    assert!(after < ratio(&base), "{after:.2}×");
}
