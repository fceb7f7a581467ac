//! The truth file is exact: every effect's expressions, evaluated over the file's own columns with
//! the core's operator definitions, reproduce the bias up to the noise drawn.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::BTreeMap;

use tcomp_sim::profile::SegmentKind;
use tcomp_sim::{
    EffectKind, Preset, Scenario, SensorKind, Table, Truth, effects, presets, simulate,
    truth as truth_file, write_preset,
};

fn std(v: &[f64]) -> f64 {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
}

/// error − Σ effects, from the expressions alone.
fn residual(table: &Table, truth: &Truth) -> Vec<f64> {
    let out = table.column(&truth.columns.target).unwrap();
    let reference = table.column(&truth.columns.reference).unwrap();
    let mut r: Vec<f64> = out.iter().zip(reference).map(|(a, b)| a - b).collect();
    for e in &truth.effects {
        assert_eq!(e.expressions.len(), e.coefficients.len());
        for (x, c) in e.expressions.iter().zip(&e.coefficients) {
            let v = truth_file::evaluate(table, &truth.signals, x, truth.step_s)
                .unwrap_or_else(|err| panic!("{}: {err}", e.name));
            for (ri, vi) in r.iter_mut().zip(&v) {
                *ri -= c * vi;
            }
        }
        for ri in r.iter_mut() {
            *ri -= e.offset;
        }
    }
    r
}

fn check_exact(sc: &Scenario) {
    let (table, truth) = simulate(sc).unwrap();
    let r = residual(&table, &truth);
    let s = std(&r);
    assert!(
        (s - truth.noise.std_raw).abs() < 1e-6 * truth.noise.std_raw.max(1e-9),
        "{}: residual std {s} vs drawn noise {}",
        sc.name,
        truth.noise.std_raw
    );
    // Effects are well above the noise floor over 100 s.
    assert!(
        truth.bias_std > 3.0 * truth.noise.std_100s,
        "{}: bias {} vs floor {}",
        sc.name,
        truth.bias_std,
        truth.noise.std_100s
    );
    // true_features parse and use only the file's columns (and declared signals).
    for f in &truth.true_features.features {
        truth_file::evaluate(&table, &truth.true_features.signals, f, truth.step_s)
            .unwrap_or_else(|e| panic!("{}: {e}", sc.name));
    }
    assert!(!truth.true_features.features.is_empty());
}

#[test]
fn every_effect_is_exactly_its_expressions_on_every_sensor() {
    for sensor in [SensorKind::Rlg, SensorKind::Qma, SensorKind::Ifog] {
        let kinds: Vec<EffectKind> = effects::SIMULATED
            .iter()
            .copied()
            .filter(|&k| effects::applies_to(k, sensor))
            .collect();
        let p = presets::with_effects(sensor, &kinds).unwrap();
        check_exact(&p.train);
    }
}

#[test]
fn each_effect_alone_is_exact_and_named() {
    for &kind in effects::SIMULATED {
        let p = presets::with_effects(SensorKind::Rlg, &[kind]).unwrap();
        let (table, truth) = simulate(&p.verify).unwrap();
        assert_eq!(truth.effects.len(), 1);
        assert_eq!(truth.effects[0].name, kind.name());
        let r = residual(&table, &truth);
        assert!(
            (std(&r) - truth.noise.std_raw).abs() < 1e-6 * truth.noise.std_raw,
            "{}",
            kind.name()
        );
        assert!(
            truth.effects[0].contribution_std > 2.0 * truth.noise.std_100s,
            "{} is buried in noise: {} vs {}",
            kind.name(),
            truth.effects[0].contribution_std,
            truth.noise.std_100s
        );
    }
}

#[test]
fn presets_are_exact_and_use_the_convention() {
    for info in presets::list() {
        let p = presets::preset(info.name).unwrap();
        check_exact(&p.train);
        let (_, truth) = simulate(&p.verify).unwrap();
        let cols = &truth.columns.all;
        assert_eq!(cols[0], "time_s");
        assert!(cols.contains(&"t_chamber_c".to_string()));
        assert!(cols.contains(&"supply_v".to_string()));
        match p.train.sensor {
            SensorKind::Rlg => {
                for c in [
                    "t_anode_c",
                    "t_cathode_c",
                    "t_shell_c",
                    "gyro_dph",
                    "ref_dph",
                ] {
                    assert!(cols.contains(&c.to_string()), "{c}");
                }
                assert_eq!(
                    truth.signals.get("T").map(String::as_str),
                    Some("mean(t_anode_c, t_cathode_c, t_shell_c)")
                );
            }
            SensorKind::Qma => {
                for c in ["t_qma_c", "accel_ug", "ref_ug"] {
                    assert!(cols.contains(&c.to_string()), "{c}");
                }
            }
            SensorKind::Ifog => {
                for c in ["t_coil_c", "gyro_dph", "ref_dph"] {
                    assert!(cols.contains(&c.to_string()), "{c}");
                }
            }
            other => panic!("preset {} of a sensor not simulated: {other:?}", info.name),
        }
    }
    let shupe = presets::preset("ifog-shupe").unwrap();
    let (_, truth) = simulate(&shupe.train).unwrap();
    assert!(
        truth
            .true_features
            .features
            .contains(&"t_coil_c * rate(t_coil_c)".to_string()),
        "{:?}",
        truth.true_features.features
    );
    assert!(presets::preset("nope").is_err());
}

fn shape(p: &tcomp_sim::Profile) -> Vec<(SegmentKind, f64, f64, f64)> {
    p.resolved()
        .iter()
        .map(|s| (s.kind, s.end_s - s.start_s, s.to_c, s.rate_c_per_min))
        .collect()
}

#[test]
fn seed_profiles_have_the_published_shapes() {
    use SegmentKind::*;
    let close = |a: &[(SegmentKind, f64, f64, f64)], b: &[(SegmentKind, f64, f64, f64)]| {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            assert_eq!(x.0, y.0);
            assert!(
                (x.1 - y.1).abs() < 1e-9 && x.2 == y.2 && x.3 == y.3,
                "{x:?} vs {y:?}"
            );
        }
    };
    let train = presets::rlg_qma_train_profile();
    assert_eq!(train.start_c, 20.0);
    close(
        &shape(&train),
        &[
            (Hold, 5400.0, 20.0, 0.0),
            (Heat, 600.0, 50.0, 3.0),
            (Hold, 7200.0, 50.0, 0.0),
            (Cool, 1600.0, -30.0, -3.0),
            (Hold, 7200.0, -30.0, 0.0),
        ],
    );
    close(
        &shape(&presets::rlg_qma_verify_profile()),
        &[
            (Hold, 3600.0, 20.0, 0.0),
            (Cool, 3000.0, -30.0, -1.0),
            (Hold, 3600.0, -30.0, 0.0),
            (Heat, 1800.0, 30.0, 2.0),
            (Hold, 3600.0, 30.0, 0.0),
            (Cool, 1200.0, -30.0, -3.0),
            (Hold, 3600.0, -30.0, 0.0),
        ],
    );
    let ifog = presets::ifog_train_profile();
    assert_eq!(ifog.start_c, 10.0);
    close(
        &shape(&ifog),
        &[
            (Hold, 3600.0, 10.0, 0.0),
            (Heat, 3600.0, 40.0, 0.5),
            (Hold, 7200.0, 40.0, 0.0),
        ],
    );
    let (lo, hi) = presets::ifog_verify_profile().range_c();
    assert_eq!((lo, hi), (-10.0, 40.0));
    // Training is about 22,000 rows at 1 s.
    let p = presets::preset("rlg").unwrap();
    assert_eq!(p.train.rows(), 22_000);
}

#[test]
fn random_profiles_are_seeded_and_within_limits() {
    let a = presets::random_profile(3).unwrap();
    let b = presets::random_profile(3).unwrap();
    let c = presets::random_profile(4).unwrap();
    assert_eq!(a, b);
    assert_ne!(a, c);
    for s in a.resolved() {
        assert!(s.to_c >= -30.0 && s.to_c <= 50.0, "{s:?}");
        assert!(s.rate_c_per_min.abs() <= 3.0, "{s:?}");
    }
    assert!(a.duration_s() >= 6.0 * 3600.0);
    assert!(a.validate("profile").is_ok());
}

#[test]
fn write_preset_writes_train_verify_and_truth() {
    let dir = std::env::temp_dir().join(format!("tcomp-sim-write-{}", std::process::id()));
    let mut p: Preset = presets::preset("qma").unwrap().with_seed(9);
    // Keep the test fast: short profiles.
    p.train.profile = tcomp_sim::Profile::new(20.0, vec![tcomp_sim::Segment::hold_h(0.5)]);
    p.verify.profile = tcomp_sim::Profile::new(20.0, vec![tcomp_sim::Segment::ramp(30.0, 1.0)]);
    let t = write_preset(&p, &dir, true).unwrap();
    assert_eq!(
        t.files.get("train").map(String::as_str),
        Some("train.csv.gz")
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    for key in [
        "sensor",
        "columns",
        "effects",
        "true_features",
        "train",
        "verify",
    ] {
        assert!(json.get(key).is_some(), "{key}");
    }
    for key in ["profile", "noise", "effects", "columns", "true_features"] {
        assert!(json["train"].get(key).is_some(), "train.{key}");
    }
    for key in ["white_std_raw", "std_raw", "std_100s", "std_1000s", "spec"] {
        assert!(json["verify"]["noise"].get(key).is_some(), "noise.{key}");
    }
    let e = &json["effects"][0];
    for key in ["name", "coefficient", "unit", "expressions", "description"] {
        assert!(e.get(key).is_some(), "effects[0].{key}");
    }
    // The gzip file decodes to header + rows.
    let gz = std::fs::File::open(dir.join("train.csv.gz")).unwrap();
    let mut text = String::new();
    std::io::Read::read_to_string(&mut flate2::read::GzDecoder::new(gz), &mut text).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("time_s,t_chamber_c,t_qma_c,supply_v,accel_ug,ref_ug")
    );
    assert_eq!(lines.count(), 1800);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn expressions_with_unknown_columns_are_rejected() {
    let p = presets::preset("ifog").unwrap();
    let mut sc = p.train.clone();
    sc.profile = tcomp_sim::Profile::new(20.0, vec![tcomp_sim::Segment::hold_h(0.1)]);
    let (table, _) = simulate(&sc).unwrap();
    let err = truth_file::evaluate(&table, &BTreeMap::new(), "rate(t_anode_c)", 1.0).unwrap_err();
    assert!(err.to_string().contains("t_anode_c"), "{err}");
    assert!(truth_file::evaluate(&table, &BTreeMap::new(), "lag(t_coil_c, 60", 1.0).is_err());
}

/// The gradient effects and the warm-up are written in the language the discovery searches:
/// the expressions a model needs, each exact over the file (checked for every effect above).
#[test]
fn the_new_effects_are_written_as_the_features_a_model_needs() {
    let cases = [
        (EffectKind::GradientRate, "rate(t_anode_c - t_shell_c)"),
        (EffectKind::GradientLag, "lag(t_anode_c - t_shell_c, 1800)"),
        (
            EffectKind::TempGradientProduct,
            "T * (t_anode_c - t_shell_c)",
        ),
        (EffectKind::Warmup, "warmup(1200)"),
    ];
    for (kind, expr) in cases {
        let p = presets::with_effects(SensorKind::Rlg, &[kind]).unwrap();
        let (table, truth) = simulate(&p.train).unwrap();
        assert_eq!(truth.effects[0].expressions, vec![expr.to_string()]);
        assert_eq!(truth.true_features.features, vec![expr.to_string()]);
        let r = residual(&table, &truth);
        assert!(
            (std(&r) - truth.noise.std_raw).abs() < 1e-6 * truth.noise.std_raw,
            "{expr}"
        );
    }
    for kind in [
        EffectKind::GradientRate,
        EffectKind::GradientLag,
        EffectKind::TempGradientProduct,
    ] {
        assert!(!effects::applies_to(kind, SensorKind::Qma), "{kind:?}");
    }
}
