//! Each simulated effect hidden in turn from the starting model: the diagnosis must rank it first
//! and say so, and adding the named feature must bring the held-out residual (100 s bins) within
//! 1.2× the noise floor. With nothing hidden the verdict must be "none".
//!
//! Runs: 1 s rows of the RLG/QMA chamber profiles (train ≈ 6.1 h, verify ≈ 5.7 h), fitted on 30 s
//! bins by the trainer, scored on 60 s bins.
//!
//! `SEED_OFFSET=k` runs every case on fresh runs, its seed moved by `k`: a held-out measurement
//! (the assertions were set on the listed seeds).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod support;
use support::seed_offset;
use tcomp_demo::{evaluate, fit_features, simulated};
use tcomp_discover::{DiagnoseOptions, Verdict, diagnose};
use tcomp_sim::{EffectKind, SensorKind, presets};

struct Outcome {
    verdict: Verdict,
    top: Option<(EffectKind, Vec<String>)>,
    text: String,
    after_over_floor: f64,
}

fn case(sensor: SensorKind, effects: &[EffectKind], hidden: Option<EffectKind>) -> Outcome {
    let preset = presets::with_effects(sensor, effects)
        .unwrap()
        .with_seed(11 + seed_offset());
    case_preset(preset, hidden)
}

/// `case` with the demo's training profile (three ramps: cool, heat, cool at 0.5 °C/min over
/// −10…40 °C) instead of the preset's two-ramp one (one heating, one cooling). The diagnosis
/// chooses on the training run alone; a heating/cooling hysteresis shows only between the two
/// directions, and with one ramp of each, holding either out leaves no example of its direction
/// in the fit — so a training run for hysteresis needs more than one ramp per direction, as a
/// chamber profile for it would have.
fn case_multi_ramp(
    sensor: SensorKind,
    effects: &[EffectKind],
    hidden: Option<EffectKind>,
) -> Outcome {
    let mut preset = presets::with_effects(sensor, effects)
        .unwrap()
        .with_seed(11 + seed_offset());
    preset.train.profile = tcomp_demo::demo_preset(11).unwrap().train.profile;
    case_preset(preset, hidden)
}

fn case_preset(preset: tcomp_sim::Preset, hidden: Option<EffectKind>) -> Outcome {
    let sim = simulated(&preset).unwrap();
    let truth = &sim.train_truth;
    let signals: Vec<String> = truth
        .true_features
        .signals
        .iter()
        .map(|(k, v)| format!("{k} = {v}"))
        .collect();
    let hidden_feats: Vec<String> = hidden
        .and_then(|h| truth.effects.iter().find(|e| e.kind() == Some(h)))
        .map(|e| e.features.clone())
        .unwrap_or_default();
    let base: Vec<String> = truth
        .true_features
        .features
        .iter()
        .filter(|f| !hidden_feats.contains(f))
        .cloned()
        .collect();
    let fitted = fit_features(&sim.train, truth, &signals, &base).unwrap();
    let bytes = fitted.model.to_bytes().unwrap();
    let model = tcomp_train::blob_io::decode("m.tcm".as_ref(), &bytes).unwrap();
    let a = diagnose(
        &model,
        &sim.train,
        Some(&sim.verify),
        &DiagnoseOptions::default(),
    )
    .unwrap();
    let d = &a.diagnosis;
    let floor = sim.verify_truth.noise.std_100s;
    let mut text = format!(
        "hidden {:?}: base {:?}; verdict {:?}: {}\n  base held-out {:.4e}, floor est {:.4e}, true floor {:.4e}, {} fits in {:.2} s\n",
        hidden.map(|h| h.name()),
        base,
        d.verdict,
        d.verdict_text,
        d.base.heldout_residual_std,
        d.base.noise_floor_estimate,
        floor,
        d.fits,
        d.elapsed_s
    );
    for c in d.candidates.iter().take(5) {
        text += &format!(
            "  {:<60} dlnE {:+9.1} after {:.4e} ({:+.1} %) {}\n",
            c.effect,
            c.delta_log_evidence,
            c.residual_std_after,
            c.improvement_pct,
            c.fails.join("; ")
        );
    }
    if std::env::var("SHOW_PROFILE").is_ok() {
        for c in d.candidates.iter().take(4) {
            if let Some(e) = &c.estimate {
                text += &format!(
                    "  {} profile: {:?}\n",
                    c.effect,
                    e.profile
                        .iter()
                        .map(|p| format!("{:.0}:{:.1}", p[0], p[1]))
                        .collect::<Vec<_>>()
                );
            }
        }
    }
    let top = d
        .candidates
        .first()
        .map(|c| (c.kind, c.expressions.clone()));
    let mut after_over_floor = f64::NAN;
    if let (Verdict::MissingEffect, Some((_, exprs))) = (d.verdict, &top) {
        let mut feats = base.clone();
        feats.extend(exprs.iter().cloned());
        let refit = fit_features(&sim.train, truth, &signals, &feats).unwrap();
        let ev = evaluate(&refit, &sim.verify).unwrap();
        after_over_floor = ev.binned.residual_std / floor;
        text += &format!(
            "  after adding {exprs:?}: held-out {:.4e} = {:.2}× floor\n",
            ev.binned.residual_std, after_over_floor
        );
        // The verification figure the diagnosis reports is the user's own fit's: the one just
        // made, with the trainer's defaults.
        let reported = d
            .candidates
            .first()
            .and_then(|c| c.confirmation.as_ref())
            .and_then(|k| k.verification.as_ref())
            .map(|v| v.residual_std_after);
        let user = ev.binned.residual_std;
        assert!(
            reported.is_some_and(|r| (r - user).abs() <= 1e-9 * user.abs().max(1e-300)),
            "the diagnosis reports {reported:?} on the verification run, the user's fit gets {user}\n{text}"
        );
    }
    println!("{text}");
    Outcome {
        verdict: d.verdict,
        top,
        text,
        after_over_floor,
    }
}

/// Issue 5's target for the refit with the named effect: within 1.2× the noise floor.
const AFTER_TARGET: f64 = 1.2;

fn check_found(o: &Outcome, kind: EffectKind) {
    check_found_within(o, kind, AFTER_TARGET);
}

fn check_found_within(o: &Outcome, kind: EffectKind, bound: f64) {
    assert_eq!(o.verdict, Verdict::MissingEffect, "{}", o.text);
    assert_eq!(o.top.as_ref().map(|t| t.0), Some(kind), "{}", o.text);
    assert!(o.after_over_floor <= bound, "{}", o.text);
}

use EffectKind::*;

#[test]
fn hidden_rate() {
    let o = case(SensorKind::Ifog, &[Poly, Rate], Some(Rate));
    check_found(&o, EffectKind::Rate);
}

#[test]
fn hidden_shupe() {
    let p = tcomp_demo::demo_preset(11).unwrap();
    let o = case_preset(p, Some(Shupe));
    check_found(&o, EffectKind::Shupe);
}

#[test]
fn hidden_gradient() {
    let o = case(SensorKind::Rlg, &[Poly, Rate, Gradient], Some(Gradient));
    check_found(&o, EffectKind::Gradient);
}

#[test]
fn hidden_lagged_element() {
    let o = case(
        SensorKind::Ifog,
        &[Poly, Rate, LaggedElement],
        Some(LaggedElement),
    );
    // The scoring (base Gaussians held fixed) ranks τ = 20 min first; the confirmation's refits
    // re-choose τ by their log evidence among 10, 20 and 40 min and find the true 40 min.
    // Measured 1.05× the noise floor after (1.26× with τ = 20 min).
    check_found(&o, EffectKind::LaggedElement);
    let exprs = o.top.as_ref().map(|t| t.1.clone()).unwrap_or_default();
    assert_eq!(exprs, vec!["lag(t_coil_c, 2400)".to_string()], "{}", o.text);
}

#[test]
fn hidden_hysteresis() {
    let o = case_multi_ramp(
        SensorKind::Ifog,
        &[Poly, Rate, Hysteresis],
        Some(Hysteresis),
    );
    check_found(&o, EffectKind::Hysteresis);
}

#[test]
fn hidden_supply_voltage() {
    let o = case(
        SensorKind::Ifog,
        &[Poly, Rate, SupplyVoltage],
        Some(SupplyVoltage),
    );
    check_found(&o, EffectKind::NonThermal);
}

#[test]
fn nothing_hidden_gives_none() {
    let o = case(SensorKind::Ifog, &[Poly, Rate, Shupe], None);
    assert_eq!(o.verdict, Verdict::None, "{}", o.text);
}

#[test]
fn nothing_hidden_rlg_gives_none() {
    let o = case(SensorKind::Rlg, &[Poly, Rate, Gradient], None);
    assert_eq!(o.verdict, Verdict::None, "{}", o.text);
}
