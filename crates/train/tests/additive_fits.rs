//! Fits given the **true** features, on simulated chamber runs whose physics is additive or
//! one-dimensional but not a cubic: a thermal bias plus a supply-voltage term, plus a supply
//! voltage acting through a first-order lag beside an auxiliary column with no effect, a smooth
//! knee and a sharp step in the bias–temperature curve, and two thermal groups (a bias in T and a
//! saturating term in a thermometer gradient). Each case is trained on the training profile and
//! measured once on the verification profile: the std of 100 s bin means of the residual over the
//! drawn noise floor, beside the limit that least squares on the exact form reaches (the exact
//! expressions as linear features, no Gaussians), and the default fit given those expressions as
//! its features.
//!
//! The added terms are computed here from the recorded columns with the core's own filters in f64,
//! at 40× the verification run's noise floor, so a model that misses them cannot hide.
//!
//! `cargo test --release -p tcomp-train --test additive_fits -- --nocapture` prints the table
//! (`SHOW=1`: every structure each fit compared; `SEEDS=N`, `SEED_BASE=K`: other seeds; `CASE=knee`:
//! that case alone).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_core::eval::Lag;
use tcomp_sim::{EffectKind, SensorKind};
use tcomp_train::{Dataset, FitOptions, Method, Roles, blob_io, fit};

/// One run's columns, by name.
struct Run {
    names: Vec<String>,
    cols: Vec<Vec<f64>>,
}

impl Run {
    fn col(&self, name: &str) -> &[f64] {
        let i = self.names.iter().position(|n| n == name).unwrap();
        &self.cols[i]
    }
    fn add_to(&mut self, name: &str, term: &[f64]) {
        let i = self.names.iter().position(|n| n == name).unwrap();
        for (v, t) in self.cols[i].iter_mut().zip(term) {
            *v += t;
        }
    }
    fn push(&mut self, name: &str, v: Vec<f64>) {
        self.names.push(name.into());
        self.cols.push(v);
    }
    fn dataset(&self, file: &str) -> Dataset {
        Dataset::from_columns(file, self.names.clone(), self.cols.clone())
    }
}

/// A term added to the bias, from a run's columns, and its exact expression in the language.
type Term = Box<dyn Fn(&Run) -> Vec<f64>>;

struct Case {
    name: &'static str,
    sensor: SensorKind,
    effects: &'static [EffectKind],
    /// Added terms with their exact expressions, each scaled to `amplitude` × the noise floor
    /// (peak to peak over the training run).
    added: Vec<(Term, &'static str, f64)>,
    /// Features given besides the truth's (exact added expressions or columns).
    extra_features: Vec<&'static str>,
    /// Replace the truth's features with these.
    only: Option<Vec<&'static str>>,
    seed: u64,
}

struct Pair {
    train: Dataset,
    verify: Dataset,
    floor: f64,
    target: String,
    reference: String,
    signals: Vec<String>,
    features: Vec<String>,
    physics: Vec<String>,
}

/// A slow random walk (Gauss–Markov, τ = 1,500 s) from a seeded xorshift: an auxiliary column that
/// moves like a supply voltage but acts on nothing.
fn distractor(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut v = 0.0;
    let a = (-1.0f64 / 1500.0).exp();
    (0..n)
        .map(|_| {
            let mut u = 0.0;
            for _ in 0..4 {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                u += (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            }
            v = a * v + 0.02 * u;
            12.0 + v
        })
        .collect()
}

fn build(c: &Case) -> Pair {
    let p = tcomp_sim::presets::with_effects(c.sensor, c.effects)
        .unwrap()
        .with_seed(c.seed);
    let (tt, truth) = tcomp_sim::simulate(&p.train).unwrap();
    let (vt, vtruth) = tcomp_sim::simulate(&p.verify).unwrap();
    let floor = vtruth.noise.std_100s;
    let mut train = Run {
        names: tt.names,
        cols: tt.columns,
    };
    let mut verify = Run {
        names: vt.names,
        cols: vt.columns,
    };
    let target = truth.columns.target.clone();
    for (term, _, amplitude) in &c.added {
        let amplitude = &std::env::var("AMP")
            .ok()
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(*amplitude);
        let on_train = term(&train);
        let (lo, hi) = on_train
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
        let k = amplitude * floor / (hi - lo).max(1e-300);
        let scaled = |v: Vec<f64>| v.into_iter().map(|x| k * x).collect::<Vec<_>>();
        let on_verify = term(&verify);
        train.add_to(&target, &scaled(on_train));
        verify.add_to(&target, &scaled(on_verify));
    }
    if c.extra_features.contains(&"aux2") {
        let n = train.cols[0].len();
        train.push("aux2", distractor(n, 3 + c.seed));
        let n = verify.cols[0].len();
        verify.push("aux2", distractor(n, 4 + c.seed));
    }
    let mut physics: Vec<String> = Vec::new();
    for x in truth.effects.iter().flat_map(|e| &e.expressions) {
        if !physics.contains(x) {
            physics.push(x.clone());
        }
    }
    physics.extend(c.added.iter().map(|(_, e, _)| e.to_string()));
    let mut features: Vec<String> = match &c.only {
        Some(f) => f.iter().map(|s| s.to_string()).collect(),
        None => truth.true_features.features.clone(),
    };
    for f in &c.extra_features {
        if !features.iter().any(|g| g == f) {
            features.push(f.to_string());
        }
    }
    Pair {
        train: train.dataset(&format!("{}-train", c.name)),
        verify: verify.dataset(&format!("{}-verify", c.name)),
        floor,
        target,
        reference: truth.columns.reference.clone(),
        signals: truth
            .true_features
            .signals
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect(),
        features,
        physics,
    }
}

/// Trains on the training run and returns the verification figure (× floor) and the fit's
/// structure line. `additive`: offer `bayes` the additive structure (the default).
fn held_out(
    p: &Pair,
    features: &[String],
    centers: Option<usize>,
    additive: bool,
) -> (f64, String) {
    let mut o = FitOptions::new(&p.target, &[]);
    o.spec.signals = p.signals.clone();
    o.spec.features = features.to_vec();
    o.reference = Some(p.reference.clone());
    o.method = Method::Bayes;
    o.centers = centers;
    o.settings.bayes.additive = Some(additive);
    if centers == Some(0) {
        o.settings.bayes.cubic = Some(false);
    }
    let f = fit(&p.train, &o).unwrap();
    if std::env::var("SHOW").is_ok() && additive {
        for (n, e) in f.summary.details.structure.iter().flat_map(|s| &s.compared) {
            println!("      {e:>9.1}  {n}");
        }
    }
    let bytes = f.model.to_bytes().unwrap();
    let m = blob_io::decode(std::path::Path::new("mem"), &bytes).unwrap();
    let r = tcomp_train::evaluate(&m, &p.verify, &Roles::of_model(&m), 100.0, None, None).unwrap();
    let structure = f.summary.details.structure.as_ref().map_or_else(
        || format!("{} centers", f.summary.centers),
        |s| s.chosen.clone(),
    );
    (r.binned.residual_std / p.floor, structure)
}

fn lag(x: &[f64], time: &[f64], tau: f64) -> Vec<f64> {
    let mut l = Lag::<f64>::new(tau);
    let mut prev = time[0];
    x.iter()
        .zip(time)
        .map(|(v, t)| {
            let dt = t - prev;
            prev = *t;
            l.step(*v, dt)
        })
        .collect()
}

fn cases() -> Vec<Case> {
    use EffectKind::*;
    let clamp = |x: f64| x.clamp(-1.0, 1.0);
    vec![
        Case {
            name: "supply",
            sensor: SensorKind::Qma,
            effects: &[Poly, Rate, SupplyVoltage],
            added: vec![],
            extra_features: vec![],
            only: None,
            seed: 21,
        },
        Case {
            name: "lagged-aux",
            sensor: SensorKind::Qma,
            effects: &[Poly, Rate],
            added: vec![(
                Box::new(|r: &Run| lag(r.col("supply_v"), r.col("time_s"), 240.0)),
                "lag(supply_v, 240)",
                40.0,
            )],
            extra_features: vec!["lag(supply_v, 240)", "aux2"],
            only: None,
            seed: 22,
        },
        Case {
            name: "knee",
            sensor: SensorKind::Qma,
            effects: &[Poly],
            added: vec![(
                Box::new(move |r: &Run| {
                    r.col("t_qma_c")
                        .iter()
                        .map(|t| clamp((t - 5.0) / 8.0))
                        .collect()
                }),
                "clamp((t_qma_c - 5) / 8, -1, 1)",
                40.0,
            )],
            extra_features: vec![],
            only: Some(vec!["t_qma_c"]),
            seed: 23,
        },
        Case {
            name: "step",
            sensor: SensorKind::Qma,
            effects: &[Poly],
            added: vec![(
                Box::new(move |r: &Run| {
                    r.col("t_qma_c")
                        .iter()
                        .map(|t| clamp((t - 10.0) / 0.5))
                        .collect()
                }),
                "clamp((t_qma_c - 10) / 0.5, -1, 1)",
                40.0,
            )],
            extra_features: vec![],
            only: Some(vec!["t_qma_c"]),
            seed: 24,
        },
        Case {
            name: "two-groups",
            sensor: SensorKind::Rlg,
            effects: &[Poly, Rate, Gradient],
            added: vec![(
                Box::new(move |r: &Run| {
                    r.col("t_anode_c")
                        .iter()
                        .zip(r.col("t_shell_c"))
                        .map(|(a, s)| clamp((a - s - 1.0) / 1.5))
                        .collect()
                }),
                "clamp((t_anode_c - t_shell_c - 1) / 1.5, -1, 1)",
                40.0,
            )],
            extra_features: vec!["t_anode_c - t_shell_c"],
            only: None,
            seed: 25,
        },
    ]
}

/// One case at one seed: the default fit, the fit without the additive structure (the joint
/// model of before), least squares on the exact form, and the default fit given the exact form's
/// expressions as its features (what a user who knows the physics types; reported, not asserted:
/// on `SEEDS=20 SEED_BASE=5000` it is 1.14, 1.08, 1.07, 1.00 and 1.01 of the limit on average,
/// worst 1.57, 23 of 100 rows over 1.1× — a joint pick of Gaussians over the five expressions
/// keeps its place within the Occam margin of the additive model; see BENCHMARKS.md).
struct Row {
    fit: f64,
    joint: f64,
    limit: f64,
    exact: f64,
}

/// Every case over `SEEDS` seeds (3 unless the environment says; `SEED_BASE` shifts them: the
/// seeds below 1000 are the ones the method was developed on), printed as a table.
fn table() -> Vec<(&'static str, Vec<Row>)> {
    let seeds: u64 = std::env::var("SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let shift: u64 = std::env::var("SEED_BASE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    let mut out = Vec::new();
    println!("case        seed  fit    joint  LS limit  exact  structure chosen");
    for mut c in cases() {
        if std::env::var("CASE").is_ok_and(|n| n != c.name) {
            continue;
        }
        let base = c.seed + shift;
        let mut rows = Vec::new();
        for s in 0..seeds {
            c.seed = base + 100 * s;
            let p = build(&c);
            let (fit_ratio, structure) = held_out(&p, &p.features, None, true);
            let (joint, _) = held_out(&p, &p.features, None, false);
            let (limit, _) = held_out(&p, &p.physics, Some(0), false);
            let (exact, _) = held_out(&p, &p.physics, None, true);
            println!(
                "{:<11} {:>4}  {fit_ratio:.2}x  {joint:.2}x  {limit:.2}x     {exact:.2}x  {structure}",
                c.name, c.seed
            );
            rows.push(Row {
                fit: fit_ratio,
                joint,
                limit,
                exact,
            });
        }
        let mean = |f: fn(&Row) -> f64| rows.iter().map(f).sum::<f64>() / rows.len() as f64;
        println!(
            "{:<11} mean  {:.2}x  {:.2}x  {:.2}x     {:.2}x",
            c.name,
            mean(|r| r.fit),
            mean(|r| r.joint),
            mean(|r| r.limit),
            mean(|r| r.exact)
        );
        out.push((c.name, rows));
    }
    out
}

fn mean(rows: &[Row], f: fn(&Row) -> f64) -> f64 {
    rows.iter().map(f).sum::<f64>() / rows.len() as f64
}

/// Where the physics adds a nonlinear term in a second group of features (a saturating thermometer
/// gradient beside the thermal bias), the additive structure generalises where one RBF over all
/// features does not; and every case, the sharp step included, stays within 1.5× of what least
/// squares on the exact form reaches.
///
/// Measured on the seeds the method was developed on (21…225, this test's default), mean over
/// three (fit / joint model / limit): supply 1.08× / 3.27× / 1.10×, lagged input 1.02× / 1.09× /
/// 0.98×, knee 1.13× / 1.38× / 1.13×, step 1.08× / 2.02× / 1.09×, two groups 1.18× / 2.68× / 1.06×.
/// Before each step refitted terms moved off the grid (`bayes::additive`, "Off the grid"): knee
/// 1.17×, step 1.07×, two groups 1.32×; on `SEEDS=20 SEED_BASE=11000`, run once after that
/// design was fixed, fit over limit before → after: supply 0.96 → 0.96, lagged 1.00 → 1.00, knee
/// 1.06 → 1.01, step 0.97 → 0.97, two groups 1.18 → **1.07**; rows within the target 24 →
/// 33 of 40, the worst row 1.72 → 1.73 of its limit (a two-groups seed that took Gaussians).
/// Before the dictionary had saturating ramps: knee 1.39×, two groups 1.37×. On `SEEDS=20
/// SEED_BASE=9000`, run once after the ramps' design was fixed, fit over limit before → after:
/// supply 0.98 → 0.98, lagged 0.96 → 0.96, knee 1.14 → 1.05, step 1.04 → 1.02, two groups 1.42 →
/// **1.54** (one seed 1.28× → 3.35×, a ramp over the rate of T); rows within the target
/// 18 → 23 of 45. Before each term paid for its choice among the dictionary's (`bayes::additive`, "Which of
/// M"): 1.08×, 1.06×, 1.21×, 1.05×, 1.16×; before the additive model had steps and powers: 1.19×,
/// 1.41×, 1.24×, 4.02×, 1.20×. Three seeds are few: on 20 fresh ones (`SEEDS=20
/// SEED_BASE=5000`, where the charge was developed) the fit over the limit went 1.07 → 1.01,
/// 1.08 → 0.98, 1.14 → 1.12, 1.02 → 1.02 and 1.80 → 1.46 with it.
///
/// Held-out seeds, each set run once after the design it judged was fixed: `SEED_BASE=1000` (the
/// design before the "seen once" rule): supply 1.28×, lagged 1.05×, knee 1.10×, step 1.22×, two
/// groups **4.72×** (limit 1.04×) — a narrow Gaussian over T at the hottest hold, the rule's reason;
/// `SEED_BASE=2000` (the design before the charge): supply 1.21× (limit 1.22×), lagged 1.22×
/// (1.18×), knee 1.24× (1.13×), step 1.15× (1.10×), two groups **1.68×** (1.02×); the design
/// before steps and powers on the same seeds: 1.32×, 1.31×, 1.37×, 4.09×, 1.30×. `SEEDS=20
/// SEED_BASE=4000` (the design as it is): supply 1.17× (limit 1.19×), lagged 1.13× (1.13×), knee
/// 1.22× (1.09×), step 1.12× (1.11×), two groups 1.35× (1.03×), worst single seed 2.46× its limit;
/// the design before the charge on the same seeds: 1.22×, 1.21×, 1.20×, 1.12×, 1.74×, worst
/// 3.51×.
#[test]
fn additive_physics_is_fitted_near_the_least_squares_limit() {
    for (name, rows) in table() {
        let (fit, joint, limit) = (
            mean(&rows, |r| r.fit),
            mean(&rows, |r| r.joint),
            mean(&rows, |r| r.limit),
        );
        if name == "two-groups" {
            assert!(fit < 0.8 * joint, "{name}: {fit:.2}x vs joint {joint:.2}x");
        }
        assert!(fit <= 1.5 * limit, "{name}: {fit:.2}x vs limit {limit:.2}x");
    }
}

/// The target, literally: within 1.1× of the floor wherever least squares on the exact
/// form reaches 1.05×. Not met on the development seeds: 6 of the 7 such rows pass; two groups
/// 1.17× at 1.04× (the true ramp found, at half-width 0.58 of the gradient's std against the
/// truth's 0.58). On `SEEDS=20 SEED_BASE=4000` 20 of the 49 such rows pass (19 before the charge
/// for a term's choice); on `SEED_BASE=9000` 23 of 45 (18 before ramps); on `SEED_BASE=11000`
/// 33 of 40 (24 before the terms moved off the grid).
#[test]
#[ignore = "issue 25's target not met: two groups 1.17x at 1.04x"]
fn true_features_reach_the_floor_wherever_least_squares_does() {
    for (name, rows) in table() {
        for r in rows {
            if r.limit <= 1.05 {
                assert!(
                    r.fit <= 1.1,
                    "{name}: {:.2}x (limit {:.2}x)",
                    r.fit,
                    r.limit
                );
            }
        }
    }
}

/// `--feature 'linear:EXPR'` keeps a feature out of every Gaussian, joint or additive, and the mark
/// does not reach the blob; `additive:EXPR` keeps it out of the joint Gaussians.
#[test]
fn pins_hold_a_feature_to_its_term() {
    let c = cases().into_iter().find(|c| c.name == "supply").unwrap();
    let p = build(&c);
    let fit_with = |features: &[&str], additive: bool| {
        let mut o = FitOptions::new(&p.target, &[]);
        o.spec.signals = p.signals.clone();
        o.spec.features = features.iter().map(|s| s.to_string()).collect();
        o.reference = Some(p.reference.clone());
        o.settings.bayes.additive = Some(additive);
        fit(&p.train, &o).unwrap()
    };
    let pinned = ["t_qma_c", "rate(t_qma_c)", "linear:supply_v"];
    for additive in [true, false] {
        let f = fit_with(&pinned, additive);
        assert_eq!(f.model.spec.features[2], "supply_v");
        let ls = &f.summary.details.length_scales;
        assert_eq!(ls.get(2), Some(&64.0), "{ls:?}");
        let bytes = f.model.to_bytes().unwrap();
        let m = blob_io::decode(std::path::Path::new("mem"), &bytes).unwrap();
        assert!(
            (0..m.rbf.centers.len())
                .all(|j| !m.rbf.spans(j, 2) || m.rbf.masks.is_empty() && ls[2] == 64.0)
        );
        assert!(m.rbf.linear.0[2] != 0.0, "the linear term keeps it");
    }
    let f = fit_with(&["additive:t_qma_c", "rate(t_qma_c)", "supply_v"], false);
    assert_eq!(f.summary.details.length_scales.first(), Some(&64.0));
    let mut o = FitOptions::new(&p.target, &[]);
    o.spec.features = vec!["lineer:t_qma_c".into()];
    let err = fit(&p.train, &o).unwrap_err().to_string();
    assert!(err.contains("lineer:t_qma_c"), "{err}");
}
