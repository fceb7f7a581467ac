//! Physics checks of the simulator: lags, self-heating, ramp rates, noise levels, seeds.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::BTreeMap;

use tcomp_sim::{
    EffectKind, NoiseSpec, Profile, Scenario, Segment, SensorKind, effects, presets, simulate,
    simulate_to_writer, truth,
};

/// An IFOG scenario with noiseless, unquantised thermometers and the given profile.
fn quiet_ifog(profile: Profile) -> Scenario {
    let mut sc = Scenario::new(SensorKind::Ifog, profile);
    for t in &mut sc.thermometers {
        t.noise_c = 0.0;
        t.lsb_c = 0.0;
        t.self_heating_c = 0.0;
    }
    sc
}

#[test]
fn recorded_thermometer_lags_a_ramp_by_rate_times_tau() {
    let tau = 600.0;
    let mut sc = quiet_ifog(Profile::new(
        0.0,
        vec![Segment::ramp(100.0, 1.0), Segment::hold_h(0.1)],
    ));
    sc.thermometers[0].tau_s = tau;
    let (table, _) = simulate(&sc).unwrap();
    let t = table.column("time_s").unwrap();
    let air = table.column("t_chamber_c").unwrap();
    let coil = table.column("t_coil_c").unwrap();
    // After 10 τ on the ramp, the coil is rate·τ = (1/60 °C/s)·600 s = 10 °C behind the air.
    let i = t.iter().position(|&x| x >= 6000.0).unwrap();
    let behind = air[i] - coil[i];
    assert!((behind - tau / 60.0).abs() < 1e-3, "behind = {behind}");
}

#[test]
fn recorded_thermometer_follows_a_step_exponentially() {
    // A very fast ramp (a near step) from 0 to 10 °C, then a hold.
    let tau = 900.0;
    let mut sc = quiet_ifog(Profile::new(
        0.0,
        vec![Segment::ramp(10.0, 600.0), Segment::hold_h(2.0)],
    ));
    sc.thermometers[0].tau_s = tau;
    let (table, _) = simulate(&sc).unwrap();
    let coil = table.column("t_coil_c").unwrap();
    // The step is complete at t = 1 s; one τ later the response is 63.2 % (within the 1 s step).
    let y = coil[1 + tau as usize];
    assert!((y - 6.3212).abs() < 0.02, "y(τ) = {y}");
    let y3 = coil[1 + 3 * tau as usize];
    assert!((y3 - 9.5021).abs() < 0.02, "y(3τ) = {y3}");
}

#[test]
fn self_heating_settles_to_its_final_value_with_its_time_constant() {
    let mut sc = quiet_ifog(Profile::new(25.0, vec![Segment::hold_h(4.0)]));
    sc.thermometers[0].self_heating_c = 2.0;
    sc.thermometers[0].self_heating_tau_s = 1200.0;
    let (table, _) = simulate(&sc).unwrap();
    let coil = table.column("t_coil_c").unwrap();
    let at_tau = coil[1200] - 25.0;
    assert!(
        (at_tau - 2.0 * 0.632_12).abs() < 1e-3,
        "rise at τ = {at_tau}"
    );
    let end = coil[coil.len() - 1] - 25.0;
    assert!((end - 2.0).abs() < 2e-3, "final rise = {end}");
}

#[test]
fn chamber_ramp_has_its_rate() {
    let p = presets::rlg_qma_train_profile();
    let sc = Scenario::new(SensorKind::Qma, p);
    let (table, truth) = simulate(&sc).unwrap();
    let rate =
        truth::evaluate(&table, &BTreeMap::new(), "rate(t_chamber_c)", truth.step_s).unwrap();
    // Heating ramp 5400..6000 s at +3 °C/min; after 5 windows the estimate is exact.
    assert!((rate[5990] - 3.0).abs() < 0.01, "{}", rate[5990]);
    // Cooling ramp from 13200 s at −3 °C/min.
    assert!((rate[14500] + 3.0).abs() < 0.01, "{}", rate[14500]);
    // Hold.
    assert!(rate[12000].abs() < 1e-6);
}

fn noise_only(sensor: SensorKind, noise: NoiseSpec, hours: f64) -> Scenario {
    let mut sc = Scenario::new(sensor, Profile::new(20.0, vec![Segment::hold_h(hours)]));
    sc.noise = noise;
    sc
}

#[test]
fn drawn_white_noise_matches_the_specification() {
    // IFOG ARW 0.005 °/√h → 0.3 °/h at 1 s; 21,600 samples → std known to ~0.5 %.
    let sc = noise_only(
        SensorKind::Ifog,
        NoiseSpec::gyro(0.005, 0.0, 600.0, 0.0),
        6.0,
    );
    let (table, truth) = simulate(&sc).unwrap();
    let n = &truth.noise;
    assert!((n.expected_white_std_raw - 0.3).abs() < 1e-12);
    assert!(
        (n.white_std_raw / 0.3 - 1.0).abs() < 0.03,
        "{}",
        n.white_std_raw
    );
    assert!((n.std_raw / 0.3 - 1.0).abs() < 0.03, "{}", n.std_raw);
    // White noise averages as 1/√N over 100 s bins (216 bins → ~5 % uncertainty).
    assert!((n.std_100s / 0.03 - 1.0).abs() < 0.25, "{}", n.std_100s);
    // And the file agrees with the truth: error = output − reference.
    let out = table.column("gyro_dph").unwrap();
    let r = table.column("ref_dph").unwrap();
    let e: Vec<f64> = out.iter().zip(r).map(|(a, b)| a - b).collect();
    let mean = e.iter().sum::<f64>() / e.len() as f64;
    let std = (e.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / e.len() as f64).sqrt();
    assert!((std - n.std_raw).abs() < 1e-9, "{std} vs {}", n.std_raw);
}

#[test]
fn averaging_100_hz_to_1_s_keeps_the_noise_density() {
    // VRW 10 µg/√Hz: 100 µg per sample at 100 Hz, 10 µg on 1 s averages.
    let sc = noise_only(
        SensorKind::Qma,
        NoiseSpec::accel(10.0, 0.0, 600.0, 0.0),
        1.0,
    )
    .with_rate(100.0, 1.0);
    let (table, truth) = simulate(&sc).unwrap();
    assert_eq!(table.rows(), 3600);
    let w = truth.noise.white_std_raw;
    assert!((w / 10.0 - 1.0).abs() < 0.06, "{w}");
}

#[test]
fn bias_instability_matches_the_specification() {
    // Short correlation time so that 6 h holds ~700 independent stretches.
    let sc = noise_only(SensorKind::Ifog, NoiseSpec::gyro(0.0, 0.01, 30.0, 0.0), 6.0);
    let (_, truth) = simulate(&sc).unwrap();
    let n = &truth.noise;
    assert!(
        (n.bias_instability_std / 0.01 - 1.0).abs() < 0.2,
        "{}",
        n.bias_instability_std
    );
    assert!((n.std_raw / 0.01 - 1.0).abs() < 0.2, "{}", n.std_raw);
}

#[test]
fn pulse_quantisation_matches_the_specification() {
    // 0.5″ pulses at 1 s: std 0.5·√(1/6) = 0.204 °/h, when white noise (0.3 °/h = 0.6 pulse)
    // randomises the phase. (Without noise the phase rotates deterministically and the std
    // depends on the fractional pulse rate: that is physics, not a bug.)
    let sc = noise_only(
        SensorKind::Rlg,
        NoiseSpec::gyro(0.005, 0.0, 600.0, 0.5),
        6.0,
    );
    let (_, truth) = simulate(&sc).unwrap();
    let n = &truth.noise;
    assert!((n.expected_quantisation_std - 0.2041).abs() < 1e-3);
    assert!(
        (n.quantisation_std / n.expected_quantisation_std - 1.0).abs() < 0.05,
        "{}",
        n.quantisation_std
    );
    let expect_total = (0.3f64.powi(2) + n.expected_quantisation_std.powi(2)).sqrt();
    assert!(
        (n.std_raw / expect_total - 1.0).abs() < 0.05,
        "{}",
        n.std_raw
    );
}

#[test]
fn same_seed_same_bytes_different_seed_different_bytes() {
    let p = presets::preset("rlg").unwrap();
    let short = |sc: &Scenario, seed: u64| {
        let mut sc = sc.clone().with_seed(seed);
        sc.profile = Profile::new(20.0, vec![Segment::hold_h(0.2), Segment::ramp(30.0, 3.0)]);
        let mut buf = Vec::new();
        simulate_to_writer(&sc, &mut buf).unwrap();
        buf
    };
    let a = short(&p.train, 5);
    let b = short(&p.train, 5);
    let c = short(&p.train, 6);
    assert!(!a.is_empty());
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn with_effects_builds_every_subset() {
    let all: Vec<EffectKind> = effects::SIMULATED.to_vec();
    let p = presets::with_effects(SensorKind::Rlg, &all).unwrap();
    assert_eq!(p.train.effects.len(), all.len());
    assert!(
        all.len() >= 11,
        "the eight effects and the three gradient ones"
    );
    let hidden = p.clone().map(|s| s.without_effect(EffectKind::Shupe));
    assert_eq!(hidden.train.effects.len(), all.len() - 1);
    assert!(
        hidden
            .verify
            .effects
            .iter()
            .all(|e| e.kind() != EffectKind::Shupe)
    );
    let err = presets::with_effects(SensorKind::Qma, &[EffectKind::Gradient]).unwrap_err();
    assert!(err.to_string().starts_with("effects[0].name"), "{err}");
}
