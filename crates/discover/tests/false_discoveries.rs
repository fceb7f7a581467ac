//! The rate of "missing effect" verdicts on runs where nothing is missing: the model is given the
//! truth's own features, so any effect the diagnosis names is invented. Three negative controls,
//! each over many seeds (simulated training and verification runs of the presets):
//!
//! - `plain`: the QMA and RLG presets with their true features;
//! - `distractors`: the IFOG preset with two auxiliary columns that follow the temperature (a board
//!   thermometer lagging the coil by 15 min, a fan duty proportional to it) and act on nothing;
//! - `drift`: the QMA preset with a slow non-thermal drift added to the output (a random walk,
//!   Gauss–Markov with a 3-hour correlation time, stationary from the first sample, 3× the noise
//!   floor) that no input explains;
//! - `drift_lagging`: the same drift, and a case thermometer `t_case_c` that follows the chamber
//!   through a 20-minute lag and acts on nothing;
//! - `idle_input`: the RLG preset with an auxiliary input `heater_v` that wanders on its own (a
//!   Gauss–Markov wander of 1-hour correlation time) and acts on nothing.
//!
//! `drift_lagging` and `idle_input` were added after the rest of the design was fixed: their
//! first run is their measurement.
//!
//! `cargo test --release -p tcomp-discover --test false_discoveries -- --nocapture` runs 20 seeds
//! of each control from 9000 (the set run once, to report, after the placebo leg was designed;
//! `SEEDS` and `FIRST` in the environment choose others — 500 is where it was developed)
//! prints each run's verdict and the rate per control: the share of "missing effect" verdicts (a
//! "cannot tell" names its candidates without claiming one, and counts apart).
//! and asserts the bound: at most 5 % "missing effect" verdicts per control. `NO_COMPOSE=1`
//! diagnoses with the listed effects alone (`tcomp diagnose --no-compose`), `CONTROL=drift` runs
//! one control alone (`plain` alternates QMA and RLG by the seed's place in the set, so run it from
//! the set's first seed), and `LEGS=1` prints how each run's five leading candidates stood on each
//! leg of the criterion.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use rayon::prelude::*;
use tcomp_demo::{Simulated, simulated};
use tcomp_discover::{DiagnoseOptions, Verdict, diagnose};
use tcomp_sim::{EffectKind, SensorKind, presets};
use tcomp_train::{Dataset, FitOptions};

fn signals(sim: &Simulated) -> Vec<String> {
    sim.train_truth
        .true_features
        .signals
        .iter()
        .map(|(k, v)| format!("{k} = {v}"))
        .collect()
}

/// `data` with `f(data)` columns appended.
fn with_columns(data: &Dataset, add: &[(&str, Vec<f64>)]) -> Dataset {
    let mut names = data.names().to_vec();
    let mut cols: Vec<Vec<f64>> = names
        .iter()
        .map(|n| data.column(n).unwrap().to_vec())
        .collect();
    for (n, c) in add {
        names.push((*n).to_string());
        cols.push(c.clone());
    }
    Dataset::from_columns(data.file(), names, cols)
}

/// A first-order lag of `x` with time constant `tau` samples.
fn lag(x: &[f64], tau: f64) -> Vec<f64> {
    let a = (-1.0 / tau).exp();
    let mut l = x.first().copied().unwrap_or(0.0);
    x.iter()
        .map(|v| {
            l = a * l + (1.0 - a) * v;
            l
        })
        .collect()
}

/// A stationary Gauss–Markov drift of correlation time `tau` samples and std `sd`, from a seeded
/// xorshift: its first value is drawn from the stationary distribution, so the drift has no
/// built-in transient (a drift started at 0 grows its variance over the first `tau`, a shape
/// every seed shares and a warm-up term can claim).
fn drift(n: usize, tau: f64, sd: f64, seed: u64) -> Vec<f64> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut normal = move || {
        let mut u = 0.0;
        for _ in 0..12 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            u += (s >> 11) as f64 / (1u64 << 53) as f64;
        }
        u - 6.0
    };
    let a = (-1.0 / tau).exp();
    let q = sd * (1.0 - a * a).sqrt();
    let mut v = sd * normal();
    (0..n)
        .map(|_| {
            v = a * v + q * normal();
            v
        })
        .collect()
}

/// The true-feature model's fit options of `sim`.
fn true_fit(sim: &Simulated) -> FitOptions {
    let truth = &sim.train_truth;
    let feats: Vec<&str> = truth
        .true_features
        .features
        .iter()
        .map(String::as_str)
        .collect();
    let mut o = FitOptions::new(&truth.columns.target, &feats);
    o.spec.signals = signals(sim);
    o.reference = Some(truth.columns.reference.clone());
    o
}

/// Diagnoses the true-feature model of `sim`; returns the verdict and its text.
fn verdict(sim: &Simulated) -> (Verdict, String) {
    let a = analysed(sim, &true_fit(sim));
    if std::env::var_os("LEGS").is_some() {
        for c in a.diagnosis.candidates.iter().take(5) {
            println!("{}", legs(c));
        }
    }
    (a.diagnosis.verdict, a.diagnosis.verdict_text)
}

/// The diagnosis of the model `o` fits on `sim`'s training run, its verification run beside.
fn analysed(sim: &Simulated, o: &FitOptions) -> tcomp_discover::Analysis {
    let fitted = tcomp_train::fit(&sim.train, o).unwrap();
    let bytes = fitted.model.to_bytes().unwrap();
    let model = tcomp_train::blob_io::decode("m.tcm".as_ref(), &bytes).unwrap();
    let opts = DiagnoseOptions {
        compose: env("NO_COMPOSE", 0) != 1,
        ..DiagnoseOptions::default()
    };
    diagnose(&model, &sim.train, Some(&sim.verify), &opts).unwrap()
}

/// The verification figure a diagnosis reports for a candidate is what the user's own fit with it
/// gets there (`tcomp fit`, the trainer's defaults), not the joint refit the training run's blocks
/// judge it with. On this run the two differ: the joint refit with `rate(t_qma_c − t_case_c)` was
/// 80 % worse there, the user's fit (the additive structure) 2 % better. The run is a negative
/// control of the fresh set 40000–, where that candidate was named (see BENCHMARKS.md). The
/// figure is reported for the candidates the verdict names, and for no other.
#[test]
fn the_verification_figure_is_the_users_fit() {
    let sim = control_run("drift_lagging", 40000, 0);
    let o = true_fit(&sim);
    let a = analysed(&sim, &o);
    let mut checked = 0;
    for c in a.diagnosis.candidates.iter().take(5) {
        let Some(v) = c
            .confirmation
            .as_ref()
            .and_then(|k| k.verification.as_ref())
        else {
            continue;
        };
        let mut with = o.clone();
        with.spec.features = c.candidate().applied_to(&o.spec.features);
        let fitted = tcomp_train::fit(&sim.train, &with).unwrap();
        let user = tcomp_demo::evaluate(&fitted, &sim.verify)
            .unwrap()
            .binned
            .residual_std;
        assert!(
            (v.residual_std_after - user).abs() <= 1e-9 * user,
            "{}: the diagnosis reports {} on the verification run, the user's fit gets {user}",
            c.expression,
            v.residual_std_after
        );
        checked += 1;
    }
    assert!(
        checked > 0,
        "no candidate was refitted with the verification run"
    );
    // The run is reported for the candidates the verdict names, and for those alone: each named
    // candidate's instruction is in the sentence, with its verification figure.
    for c in &a.diagnosis.candidates {
        let has = c
            .confirmation
            .as_ref()
            .is_some_and(|k| k.verification.is_some());
        let named = a
            .diagnosis
            .verdict_text
            .contains(&tcomp_discover::verdict::instruction(c));
        assert_eq!(has, named, "{}: {}", c.expression, a.diagnosis.verdict_text);
    }
}

/// How `c` stood on each leg: what it failed, and its placebo statistics (the first stage's
/// against the threshold and its own best placebo; the second stage's, when it ran).
fn legs(c: &tcomp_discover::score::Scored) -> String {
    let best = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let placebo = c.placebo.as_ref().map_or("not tested".to_string(), |p| {
        let second = p.refit.as_ref().map_or(String::new(), |r| {
            format!(
                "; refits {:.1} % against {:.1} % (own best {:.1} %)",
                r.improvement_pct,
                r.threshold_pct,
                best(&r.placebos_pct)
            )
        });
        format!(
            "ρ {} statistic {:.1} against {:.1} (own best {:.1}){second}",
            p.rho,
            p.statistic,
            p.threshold,
            best(&p.placebos)
        )
    });
    format!(
        "    {}: passes {}, Δ log evidence {:.1}, held-out {:.1} %, placebos: {placebo}; fails: {}",
        c.expression,
        c.passes,
        c.delta_log_evidence,
        c.improvement_pct,
        c.fails.join("; ")
    )
}

/// A number from the environment variable `name`, else `default`.
fn env(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// The simulated runs of `control` for `seed` (the `s`-th of the set).
fn control_run(control: &str, seed: u64, s: u64) -> Simulated {
    match control {
        "plain" => {
            let name = if s.is_multiple_of(2) { "qma" } else { "rlg" };
            simulated(&presets::preset(name).unwrap().with_seed(seed)).unwrap()
        }
        "distractors" => {
            let p = presets::with_effects(SensorKind::Ifog, &[EffectKind::Poly, EffectKind::Rate])
                .unwrap()
                .with_seed(seed);
            let mut sim = simulated(&p).unwrap();
            for (d, k) in [(&mut sim.train, 1.0), (&mut sim.verify, 2.0)] {
                let coil = d.column("t_coil_c").unwrap().to_vec();
                let board: Vec<f64> = lag(&coil, 900.0)
                    .iter()
                    .enumerate()
                    .map(|(i, v)| 0.9 * v + 3.0 + 0.02 * (i as f64 * 0.37 + k).sin())
                    .collect();
                let fan: Vec<f64> = coil.iter().map(|v| 0.02 * v + 0.1).collect();
                *d = with_columns(d, &[("t_board_c", board), ("fan_duty", fan)]);
            }
            sim
        }
        "idle_input" => {
            let mut sim = simulated(&presets::preset("rlg").unwrap().with_seed(seed)).unwrap();
            for (d, k) in [(&mut sim.train, 1u64), (&mut sim.verify, 2u64)] {
                let w = drift(d.len(), 3600.0, 0.3, seed * 11 + k);
                let heater: Vec<f64> = w.iter().map(|v| 12.0 + v).collect();
                *d = with_columns(d, &[("heater_v", heater)]);
            }
            sim
        }
        _ => {
            let mut sim = simulated(&presets::preset("qma").unwrap().with_seed(seed)).unwrap();
            if control == "drift_lagging" {
                for d in [&mut sim.train, &mut sim.verify] {
                    let air = d.column("t_chamber_c").unwrap().to_vec();
                    *d = with_columns(d, &[("t_case_c", lag(&air, 1200.0))]);
                }
            }
            let floor = sim.verify_truth.noise.std_100s;
            let target = sim.train_truth.columns.target.clone();
            for (d, k) in [(&mut sim.train, 1u64), (&mut sim.verify, 2u64)] {
                let n = d.len();
                let w = drift(n, 10_800.0, 3.0 * floor, seed * 7 + k);
                let names = d.names().to_vec();
                let cols: Vec<Vec<f64>> = names
                    .iter()
                    .map(|c| {
                        let v = d.column(c).unwrap();
                        if *c == target {
                            v.iter().zip(&w).map(|(a, b)| a + b).collect()
                        } else {
                            v.to_vec()
                        }
                    })
                    .collect();
                *d = Dataset::from_columns(d.file(), names, cols);
            }
            sim
        }
    }
}

#[test]
fn negative_controls_rarely_name_an_effect() {
    let seeds = env("SEEDS", 20);
    let first = env("FIRST", 9000);
    let only = std::env::var("CONTROL").ok();
    let all = [
        "plain",
        "distractors",
        "drift",
        "drift_lagging",
        "idle_input",
    ];
    let controls: Vec<&str> = all
        .iter()
        .copied()
        .filter(|c| only.as_deref().is_none_or(|o| o == *c))
        .collect();
    // The runs are independent: two at a time fill the cores that one diagnosis leaves idle in
    // its serial parts (the same verdicts, printed in the same order).
    let runs: Vec<(&str, u64)> = controls
        .iter()
        .flat_map(|&c| (0..seeds).map(move |s| (c, s)))
        .collect();
    let verdicts: Vec<(Verdict, String)> = runs
        .par_iter()
        .map(|&(control, s)| verdict(&control_run(control, first + s, s)))
        .collect();
    let mut rates = Vec::new();
    for (k, control) in controls.iter().enumerate() {
        let (mut missing, mut cannot) = (0, 0);
        for s in 0..seeds {
            let Some((v, text)) = verdicts.get(k * seeds as usize + s as usize) else {
                continue;
            };
            match v {
                Verdict::MissingEffect => missing += 1,
                Verdict::CannotTell => cannot += 1,
                Verdict::None => {}
            }
            println!("{control:<12} seed {}: {v:?} — {text}", first + s);
        }
        let rate = missing as f64 / seeds as f64;
        println!(
            "{control:<12} missing-effect verdicts {missing}/{seeds} ({:.0} %), cannot tell {cannot}",
            100.0 * rate
        );
        rates.push((control, missing));
    }
    println!(
        "FALSE-DISCOVERIES seeds={seeds} {}",
        rates
            .iter()
            .map(|(c, m)| format!("{c}={m}"))
            .collect::<Vec<_>>()
            .join(" ")
    );
    for (control, missing) in &rates {
        assert!(
            *missing as f64 <= 0.05 * seeds as f64,
            "{control}: {missing}/{seeds} missing-effect verdicts where nothing is missing (bound 5 %)"
        );
    }
}
