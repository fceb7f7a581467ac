//! The truth of a finished run: what was simulated, the effects as expressions with their
//! contributions, and the noise actually drawn.

use std::collections::BTreeMap;

use crate::effects::{Context, EffectTruth};
use crate::noise::NoiseSpec;
use crate::scenario::Scenario;
use crate::sensor::SensorExt;
use crate::truth::{Columns, NoiseTruth, ProfileTruth, TrueFeatures, Truth};

use super::{Drawn, Effects, Grid, uses_ident};

/// The truth of the run of `sc` that produced `columns`.
pub(super) fn truth(
    sc: &Scenario,
    ctx: &Context<'_>,
    grid: Grid,
    columns: Vec<String>,
    effects: Effects,
    drawn: Drawn,
    reference: f64,
) -> Truth {
    let (effect_truth, bias) = effects.finish();
    let true_features = true_features(&effect_truth, ctx);
    Truth {
        scenario: sc.name.clone(),
        description: sc.description.clone(),
        sensor: sc.sensor,
        unit: ctx.unit.to_string(),
        seed: sc.seed,
        rate_hz: sc.rate_hz,
        step_s: grid.h,
        rows: grid.rows,
        reference_value: reference,
        columns: Columns {
            time: "time_s".into(),
            target: sc.sensor.output_column().into(),
            reference: sc.sensor.reference_column().into(),
            thermometers: sc.thermometers.iter().map(|t| t.name.clone()).collect(),
            chamber: "t_chamber_c".into(),
            inputs: vec!["supply_v".into()],
            all: columns,
        },
        profile: ProfileTruth {
            start_c: sc.profile.start_c,
            duration_s: sc.profile.duration_s(),
            segments: sc.profile.resolved(),
        },
        thermal: sc.thermometers.clone(),
        effects: effect_truth,
        signals: true_features.signals.clone(),
        true_features,
        bias_std: bias.run.std(),
        bias_p2p: bias.p2p(),
        noise: noise_truth(sc, grid.h, drawn),
        operators: crate::truth::operator_definitions(),
        dropouts: sc.dropouts.clone(),
        notes: vec![
            "error = target - reference = sum of effects + noise".into(),
            "each effect = offset + sum(coefficients[i] * expressions[i]), evaluated over this file's columns with the operators listed, dt = step_s; exact up to float rounding".into(),
            "effects are driven by the recorded (noisy, quantised, averaged) thermometer columns, not by the internal temperatures".into(),
            "internal temperatures: first-order lag of chamber air (tau_s) plus self-heating self_heating_c * (1 - exp(-t/self_heating_tau_s)) after power-on at t = 0".into(),
        ],
    }
}

/// The features a model needs (each once, in the effects' order) and the signals they use.
fn true_features(effects: &[EffectTruth], ctx: &Context<'_>) -> TrueFeatures {
    let mut features: Vec<String> = Vec::new();
    for f in effects.iter().flat_map(|e| e.features.iter()) {
        if !features.contains(f) {
            features.push(f.clone());
        }
    }
    let all_exprs: Vec<&String> = effects
        .iter()
        .flat_map(|e| e.expressions.iter().chain(e.features.iter()))
        .collect();
    let signals: BTreeMap<String, String> = ctx
        .signals()
        .into_iter()
        .filter(|(name, _)| all_exprs.iter().any(|e| uses_ident(e, name)))
        .collect();
    TrueFeatures { signals, features }
}

/// The noise drawn over the run, beside what the specification expects.
fn noise_truth(sc: &Scenario, h: f64, drawn: Drawn) -> NoiseTruth {
    let noise = sc.noise;
    let (std_100s, bins_100s) = drawn.bin100.finish();
    let (std_1000s, bins_1000s) = drawn.bin1000.finish();
    NoiseTruth {
        white_std_raw: drawn.white.std(),
        std_raw: drawn.total.std(),
        std_100s,
        std_1000s,
        bins_100s,
        bins_1000s,
        mean: drawn.total.mean(),
        bias_instability_std: drawn.gm.std(),
        quantisation_std: drawn.quant.std(),
        expected_white_std_raw: noise.white_std(h),
        expected_quantisation_std: noise.quantisation_std(h),
        spec: noise,
        spec_customary: customary(sc.sensor.is_accelerometer(), &noise),
    }
}

/// The noise specification in the units a data sheet uses.
fn customary(accelerometer: bool, noise: &NoiseSpec) -> BTreeMap<String, f64> {
    let mut c = BTreeMap::new();
    if accelerometer {
        c.insert("vrw_ug_per_sqrt_hz".into(), noise.white_density);
        c.insert("bias_instability_ug".into(), noise.bias_instability);
        c.insert("pulse_weight_ug_s".into(), noise.pulse_weight);
    } else {
        c.insert("arw_deg_per_sqrt_h".into(), noise.white_density / 60.0);
        c.insert("bias_instability_dph".into(), noise.bias_instability);
        c.insert("pulse_weight_arcsec".into(), noise.pulse_weight);
    }
    c.insert("correlation_s".into(), noise.correlation_s);
    c
}
