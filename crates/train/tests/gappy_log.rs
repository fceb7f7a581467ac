//! A gappy log (issue 15): a QMA sampled at 2 Hz whose bias follows a lag of 40 minutes, the
//! logger dropping out six times for five minutes in each run. When every gap reset the rate and
//! lag state, no feature could carry the lag across (measured here with the reset put back:
//! 57.6× the noise floor). Stepping over each gap as one long ordinary step (a `--gap` above every
//! dropout) assumes the input jumped at the gap's start: 1.89×. With the filters carried across
//! by the core's linear bridge: 1.08×.
//!
//! Figures are printed (`cargo test -p tcomp-train --test gappy_log -- --nocapture`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_sim::dropout::RandomDropouts;
use tcomp_sim::{EffectKind, Scenario, SensorKind, Truth, presets, simulate};
use tcomp_train::{Dataset, FitOptions, Method, Roles, blob_io, fit};

fn gappy(sc: Scenario, seed: u64) -> Scenario {
    let sc = sc.with_rate(2.0, 0.5);
    let holes = RandomDropouts {
        count: 6,
        length_s: 300.0,
        seed,
    }
    .resolve(sc.profile.duration_s())
    .unwrap();
    sc.with_dropouts(holes)
}

/// Every expression of every effect: the true feature set (as `sim_accuracy`'s exact physics).
fn physics(truth: &Truth) -> Vec<String> {
    let mut all: Vec<String> = Vec::new();
    for x in truth.effects.iter().flat_map(|e| e.expressions.iter()) {
        if !all.contains(x) {
            all.push(x.clone());
        }
    }
    all
}

/// Held-out residual (100 s bins) over the noise floor, with `gap_s` as `--gap`; and the fit's
/// summary's gap counts.
fn ratio(gap_s: Option<f64>) -> (f64, usize, usize, Vec<String>) {
    let kinds = [
        EffectKind::Poly,
        EffectKind::Rate,
        EffectKind::LaggedElement,
    ];
    let p = presets::with_effects(SensorKind::Qma, &kinds).unwrap();
    let (tt, truth) = simulate(&gappy(p.train, 11)).unwrap();
    let (vt, vtruth) = simulate(&gappy(p.verify, 12)).unwrap();
    assert_eq!(truth.dropouts.len(), 6);
    let train = Dataset::from_columns("qma-gappy-train", tt.names, tt.columns);
    let verify = Dataset::from_columns("qma-gappy-verify", vt.names, vt.columns);
    let mut o = FitOptions::new(&truth.columns.target, &[]);
    o.spec.features = physics(&truth);
    o.reference = Some(truth.columns.reference.clone());
    o.method = Method::Bayes;
    o.gap_s = gap_s;
    let f = fit(&train, &o).unwrap();
    let bytes = f.model.to_bytes().unwrap();
    let m = blob_io::decode(std::path::Path::new("mem"), &bytes).unwrap();
    let r = tcomp_train::evaluate(&m, &verify, &Roles::of_model(&m), 100.0, None, gap_s).unwrap();
    let floor = vtruth.noise.std_100s;
    let ratio = r.binned.residual_std / floor;
    println!(
        "qma 2 Hz, 6 × 300 s dropouts, --gap {gap_s:?}, features {:?}: verify 100 s raw {:.4e} \
         residual {:.4e} floor {floor:.4e} ratio {ratio:.2}",
        o.spec.features, r.binned.raw_std, r.binned.residual_std
    );
    (
        ratio,
        f.summary.train.gaps,
        f.summary.train.gaps_restarted,
        f.summary.warnings,
    )
}

#[test]
fn a_gappy_2_hz_qma_with_a_long_lag_reaches_the_noise_floor() {
    let (carried, gaps, restarted, warnings) = ratio(None);
    // The dropouts are gaps (the default threshold is 10 steps); none is long enough to restart.
    assert_eq!((gaps, restarted), (6, 0), "{warnings:?}");
    assert!(
        warnings.iter().any(|w| w.contains("carried")),
        "{warnings:?}"
    );
    assert!(carried <= 1.25, "{carried:.2} × the noise floor");
    // The same run with no step counted as a gap: each dropout is one long ordinary step.
    let (one_step, gaps, _, _) = ratio(Some(1e6));
    assert_eq!(gaps, 0);
    assert!(
        carried < 0.8 * one_step,
        "carried {carried:.2} vs one long step {one_step:.2}"
    );
}
