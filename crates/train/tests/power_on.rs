//! `warmup(τ)` on the host: its clock starts at the first row read, or at `--power-on` (a time on
//! the time column, not after the first row); a warm-up hidden in a simulated run is fitted by it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_sim::{EffectKind, SensorKind, presets, simulate};
use tcomp_train::features::{FeatureSpec, compute_from, time_on_s};
use tcomp_train::{Dataset, FitOptions, Method, Roles, TrainError, blob_io, fit};

#[test]
fn the_clock_starts_at_the_first_row_or_at_power_on() {
    let time: Vec<f64> = (0..100).map(|i| 1000.0 + 10.0 * i as f64).collect();
    assert_eq!(time_on_s(&time, None).unwrap(), 0.0);
    assert_eq!(time_on_s(&time, Some(400.0)).unwrap(), 600.0);
    let e = time_on_s(&time, Some(1000.5)).unwrap_err();
    assert!(matches!(e, TrainError::PowerOnAfterStart { .. }));
    assert!(e.to_string().contains("--power-on 1000.5"), "{e}");
    let d = Dataset::from_columns(
        "t",
        vec!["time_s".into(), "x".into()],
        vec![time.clone(), vec![1.0; 100]],
    );
    let spec = FeatureSpec {
        signals: vec![],
        features: vec!["warmup(1200)".into()],
    };
    let p = spec.program().unwrap();
    let at = |t_on: f64| compute_from(&p, &d, &time, &[0], t_on).unwrap();
    let (a, b) = (at(0.0), at(600.0));
    assert!((f64::from(a[0][0]) - 1.0).abs() < 1e-6);
    assert!((f64::from(b[0][0]) - (-0.5f64).exp()).abs() < 1e-6);
    assert!((f64::from(b[99][0]) - (-(600.0 + 990.0) / 1200.0f64).exp()).abs() < 1e-6);
}

#[test]
fn a_hidden_warm_up_is_fitted_by_warmup() {
    let p =
        presets::with_effects(SensorKind::Qma, &[EffectKind::Poly, EffectKind::Warmup]).unwrap();
    let (tt, truth) = simulate(&p.train).unwrap();
    let (vt, vtruth) = simulate(&p.verify).unwrap();
    assert!(
        truth
            .true_features
            .features
            .contains(&"warmup(1200)".to_string())
    );
    let train = Dataset::from_columns("train", tt.names, tt.columns);
    let verify = Dataset::from_columns("verify", vt.names, vt.columns);
    let fit_with = |features: &[String]| {
        let mut o = FitOptions::new(&truth.columns.target, &[]);
        o.spec.features = features.to_vec();
        o.reference = Some(truth.columns.reference.clone());
        o.method = Method::Bayes;
        let f = fit(&train, &o).unwrap();
        let bytes = f.model.to_bytes().unwrap();
        let uses = features.iter().any(|f| f.contains("warmup"));
        assert_eq!(bytes[4], if uses { 2 } else { 1 }, "blob version");
        let m = blob_io::decode(std::path::Path::new("mem"), &bytes).unwrap();
        let r =
            tcomp_train::evaluate(&m, &verify, &Roles::of_model(&m), 100.0, None, None).unwrap();
        r.binned.residual_std / vtruth.noise.std_100s
    };
    let mut physics: Vec<String> = Vec::new();
    for x in truth.effects.iter().flat_map(|e| e.expressions.iter()) {
        physics.push(x.clone());
    }
    let with = fit_with(&physics);
    physics.retain(|f| !f.contains("warmup"));
    let without = fit_with(&physics);
    println!(
        "QMA poly + warm-up, exact physics: {with:.2} × the noise floor; without warmup(1200): \
         {without:.2} ×"
    );
    assert!(with <= 1.2, "{with:.2}");
    assert!(with < 0.8 * without, "{with:.2} vs {without:.2}");
}
