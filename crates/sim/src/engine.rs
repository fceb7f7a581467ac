//! The simulation loop: chamber air → internal temperatures → recorded columns → bias → output.
//!
//! Why one streaming loop: every quantity is produced sample by sample at the internal rate,
//! averaged into output rows on the fly and handed to a [`RowSink`], so a run of any length needs
//! only the state of its filters. Order per output row:
//!
//! 1. At each internal sample: chamber air from the profile; each location's internal temperature
//!    (exact first-order lag of the air plus self-heating); thermometer reading (plus white noise,
//!    quantised to its LSB); supply voltage (slow Gauss–Markov wander plus noise); output white noise
//!    and Gauss–Markov bias instability. All are summed over the row.
//! 2. At the end of a row: the averages are rounded to the decimals written in the file; the bias
//!    effects are evaluated from those *recorded* values with the core's streaming operators at
//!    `dt = step_s` (so the truth expressions are exact over the file); the true output integral over
//!    the row (reference + bias + noise) feeds the pulse counter; the quantised, rounded output is
//!    written, and `output − reference − bias` is the noise actually drawn.

use std::collections::BTreeMap;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use crate::effects::{Context, EffectState, EffectTruth, RowInputs};
use crate::error::Result;
use crate::noise::{BinnedStd, GaussMarkov, PulseCounter, Running};
use crate::scenario::{Scenario, SensorKind};
use crate::thermal::{FohLag, SelfHeating, quantise};
use crate::truth::{Columns, NoiseTruth, ProfileTruth, TrueFeatures, Truth, operator_definitions};
use crate::writer::RowSink;

const TIME_DECIMALS: usize = 4;
const TEMP_DECIMALS: usize = 4;
const VOLT_DECIMALS: usize = 4;

/// Rounds to `d` decimals so that the value printed with `{:.d$}` parses back to the same f64.
fn round_dec(v: f64, d: usize) -> f64 {
    let p = 10f64.powi(d as i32);
    (v * p).round() / p
}

struct Extremes {
    run: Running,
    lo: f64,
    hi: f64,
}

impl Extremes {
    fn new() -> Self {
        Extremes {
            run: Running::default(),
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
        }
    }
    fn push(&mut self, x: f64) {
        self.run.push(x);
        self.lo = self.lo.min(x);
        self.hi = self.hi.max(x);
    }
    fn p2p(&self) -> f64 {
        if self.hi >= self.lo {
            self.hi - self.lo
        } else {
            0.0
        }
    }
}

/// Whether `expr` uses the identifier `name`.
pub(crate) fn uses_ident(expr: &str, name: &str) -> bool {
    expr.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .any(|tok| tok == name)
}

/// Runs `sc` into `sink`; returns the truth.
pub(crate) fn run<S: RowSink>(sc: &Scenario, sink: &mut S) -> Result<Truth> {
    sc.validate()?;
    let mut rng = ChaCha8Rng::seed_from_u64(sc.seed);
    let mut normal = move || -> f64 { rng.sample(StandardNormal) };

    let dt = 1.0 / sc.rate_hz;
    let k = sc.samples_per_row();
    let h = k as f64 * dt;
    let rows = sc.rows();
    let nt = sc.thermometers.len();
    let out_dec = sc.sensor.output_decimals();

    // Effects.
    let (names, unit) = sc.context();
    let ctx = Context {
        sensor: sc.sensor,
        therm_names: &names,
        unit,
    };
    let mut states: Vec<EffectState> = sc
        .effects
        .iter()
        .map(|e| e.state(&ctx, h))
        .collect::<Result<_>>()?;
    let mut effect_truth: Vec<EffectTruth> = sc.effects.iter().map(|e| e.truth(&ctx, h)).collect();
    let mut effect_stats: Vec<Extremes> = sc.effects.iter().map(|_| Extremes::new()).collect();
    let mut bias_stats = Extremes::new();

    // Physics state.
    let mut cursor = sc.profile.cursor();
    let air0 = cursor.at(0.0);
    let mut lags: Vec<FohLag> = sc
        .thermometers
        .iter()
        .map(|t| FohLag::new(t.tau_s, air0))
        .collect();
    let decays: Vec<f64> = sc
        .thermometers
        .iter()
        .map(|t| (-dt / t.tau_s).exp())
        .collect();
    let mut heat: Vec<SelfHeating> = sc
        .thermometers
        .iter()
        .map(|t| SelfHeating::new(t.self_heating_c, t.self_heating_tau_s, dt))
        .collect();
    let sup = sc.supply;
    let mut wander = GaussMarkov::new(sup.wander_v, sup.wander_tau_s, dt, sup.wander_v * normal());
    let noise = sc.noise;
    let white_sigma = noise.white_std(dt);
    let mut gm = GaussMarkov::new(
        noise.bias_instability,
        noise.correlation_s,
        dt,
        noise.bias_instability * normal(),
    );
    let phase = {
        let mut r2 = ChaCha8Rng::seed_from_u64(sc.seed ^ 0x5eed_9a15_e000_0001);
        r2.random_range(0.0..1.0)
    };
    let mut counter = PulseCounter::new(noise.pulse_weight, phase);
    let reference = round_dec(sc.reference, out_dec);

    // Header.
    let columns = sc.columns();
    let mut decimals = vec![TIME_DECIMALS, TEMP_DECIMALS];
    decimals.extend(std::iter::repeat_n(TEMP_DECIMALS, nt));
    decimals.extend([VOLT_DECIMALS, out_dec, out_dec]);
    sink.header(&columns, &decimals)?;

    // Statistics of the drawn noise.
    let mut st_white = Running::default();
    let mut st_gm = Running::default();
    let mut st_quant = Running::default();
    let mut st_total = Running::default();
    let mut bin100 = BinnedStd::new(100.0, h);
    let mut bin1000 = BinnedStd::new(1000.0, h);

    let mut air_prev = air0;
    let mut therm_sum = vec![0.0; nt];
    let mut therms = vec![0.0; nt];
    let mut row = vec![0.0; columns.len()];
    let mut n: u64 = 0;
    for _ in 0..rows {
        let (mut t_sum, mut air_sum, mut v_sum, mut w_sum, mut g_sum) = (0.0, 0.0, 0.0, 0.0, 0.0);
        therm_sum.iter_mut().for_each(|s| *s = 0.0);
        for _ in 0..k {
            let t = n as f64 * dt;
            let air = if n == 0 { air0 } else { cursor.at(t) };
            for i in 0..nt {
                let (Some(lag), Some(sh), Some(spec), Some(decay), Some(acc)) = (
                    lags.get_mut(i),
                    heat.get_mut(i),
                    sc.thermometers.get(i),
                    decays.get(i),
                    therm_sum.get_mut(i),
                ) else {
                    continue;
                };
                let (inside, rise) = if n == 0 {
                    (lag.value(), sh.value())
                } else {
                    (lag.step(air_prev, air, dt, *decay), sh.step())
                };
                let reading = quantise(inside + rise + spec.noise_c * normal(), spec.lsb_c);
                *acc += reading;
            }
            let v_w = if n == 0 {
                wander.value()
            } else {
                wander.step(normal())
            };
            v_sum += sup.nominal_v + v_w + sup.noise_v * normal();
            w_sum += white_sigma * normal();
            g_sum += if n == 0 {
                gm.value()
            } else {
                gm.step(normal())
            };
            t_sum += t;
            air_sum += air;
            air_prev = air;
            n += 1;
        }
        let kf = k as f64;
        let time = round_dec(t_sum / kf, TIME_DECIMALS);
        let chamber = round_dec(air_sum / kf, TEMP_DECIMALS);
        for (dst, s) in therms.iter_mut().zip(&therm_sum) {
            *dst = round_dec(s / kf, TEMP_DECIMALS);
        }
        let supply = round_dec(v_sum / kf, VOLT_DECIMALS);
        let inputs = RowInputs {
            time_s: time,
            therms: &therms,
            supply_v: supply,
        };
        let mut bias = 0.0;
        for (st, stats) in states.iter_mut().zip(effect_stats.iter_mut()) {
            let c = st.step(&inputs, h);
            stats.push(c);
            bias += c;
        }
        bias_stats.push(bias);
        let white = w_sum / kf;
        let gmv = g_sum / kf;
        let analog = reference + bias + white + gmv;
        let out = round_dec(counter.step(analog, h), out_dec);
        let drawn = out - reference - bias;
        st_white.push(white);
        st_gm.push(gmv);
        st_quant.push(out - analog);
        st_total.push(drawn);
        bin100.push(time, drawn);
        bin1000.push(time, drawn);

        let mut w = row.iter_mut();
        let mut put = |v: f64| {
            if let Some(slot) = w.next() {
                *slot = v;
            }
        };
        put(time);
        put(chamber);
        for &x in &therms {
            put(x);
        }
        put(supply);
        put(out);
        put(reference);
        sink.row(&row)?;
    }
    sink.finish()?;

    for (t, s) in effect_truth.iter_mut().zip(&effect_stats) {
        t.contribution_std = s.run.std();
        t.contribution_p2p = s.p2p();
    }
    let (std_100s, bins_100s) = bin100.finish();
    let (std_1000s, bins_1000s) = bin1000.finish();

    let mut features: Vec<String> = Vec::new();
    for f in effect_truth.iter().flat_map(|e| e.features.iter()) {
        if !features.contains(f) {
            features.push(f.clone());
        }
    }
    let all_exprs: Vec<&String> = effect_truth
        .iter()
        .flat_map(|e| e.expressions.iter().chain(e.features.iter()))
        .collect();
    let signals: BTreeMap<String, String> = ctx
        .signals()
        .into_iter()
        .filter(|(name, _)| all_exprs.iter().any(|e| uses_ident(e, name)))
        .collect();

    let mut customary = BTreeMap::new();
    match sc.sensor {
        SensorKind::Qma => {
            customary.insert("vrw_ug_per_sqrt_hz".into(), noise.white_density);
            customary.insert("bias_instability_ug".into(), noise.bias_instability);
            customary.insert("pulse_weight_ug_s".into(), noise.pulse_weight);
        }
        _ => {
            customary.insert("arw_deg_per_sqrt_h".into(), noise.white_density / 60.0);
            customary.insert("bias_instability_dph".into(), noise.bias_instability);
            customary.insert("pulse_weight_arcsec".into(), noise.pulse_weight);
        }
    }
    customary.insert("correlation_s".into(), noise.correlation_s);

    let therm_names: Vec<String> = sc.thermometers.iter().map(|t| t.name.clone()).collect();
    Ok(Truth {
        scenario: sc.name.clone(),
        description: sc.description.clone(),
        sensor: sc.sensor,
        unit: unit.to_string(),
        seed: sc.seed,
        rate_hz: sc.rate_hz,
        step_s: h,
        rows,
        reference_value: reference,
        columns: Columns {
            time: "time_s".into(),
            target: sc.sensor.output_column().into(),
            reference: sc.sensor.reference_column().into(),
            thermometers: therm_names,
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
        signals: signals.clone(),
        true_features: TrueFeatures { signals, features },
        bias_std: bias_stats.run.std(),
        bias_p2p: bias_stats.p2p(),
        noise: NoiseTruth {
            white_std_raw: st_white.std(),
            std_raw: st_total.std(),
            std_100s,
            std_1000s,
            bins_100s,
            bins_1000s,
            mean: st_total.mean(),
            bias_instability_std: st_gm.std(),
            quantisation_std: st_quant.std(),
            expected_white_std_raw: noise.white_std(h),
            expected_quantisation_std: noise.quantisation_std(h),
            spec: noise,
            spec_customary: customary,
        },
        operators: operator_definitions(),
        notes: vec![
            "error = target - reference = sum of effects + noise".into(),
            "each effect = offset + sum(coefficients[i] * expressions[i]), evaluated over this file's columns with the operators listed, dt = step_s; exact up to float rounding".into(),
            "effects are driven by the recorded (noisy, quantised, averaged) thermometer columns, not by the internal temperatures".into(),
            "internal temperatures: first-order lag of chamber air (tau_s) plus self-heating self_heating_c * (1 - exp(-t/self_heating_tau_s)) after power-on at t = 0".into(),
        ],
    })
}
