//! Candidate features: the physical effects a model may be missing, generated from the file's
//! columns and the model's signals, each with a name an engineer recognises and an expression ready
//! for `tcomp fit --feature`.
//!
//! Why generated, not hand-listed: on a user's own data nobody knows the answer in advance, so every
//! plausible mechanism is put to the same test. For each temperature (the model's signals and every
//! thermometer column): its rate, the Shupe-type product T·dT/dt, its square, a lag (a sensing
//! element that lags its thermometer) both added beside the model's features and *replacing* the
//! temperature in every one of them, and a heating/cooling hysteresis state; for every pair or
//! triple of thermometers, their differences (thermal gradients), a gradient's rate, its lag and
//! its product with the temperature; the warm-up after power-on (`warmup(τ)`, when the core's
//! language has it); and every other numeric column (supply voltage, other channels) as a
//! non-thermal input — each kind one line of the registry [`LISTED`]. A *family* is one hypothesis with a parameter (τ, threshold, rate window);
//! its grid members are scored individually and the family's evidence is marginalised over the
//! grid, so searching more values does not buy evidence; [`crate::param`] then estimates the
//! parameter of the leading families on a continuous scale ([`crate::families`] builds a member at
//! any value).
//!
//! Every expression is written with the names the user's program has (the model's signals as the
//! user defined them and the file's columns), never a signal the trainer added to the stored
//! program (see [`crate::user_program`]), so each one is accepted by `tcomp fit --feature` as printed.
//! A candidate that only re-states a feature the model has (its rate with another window) is
//! marked as a refinement of that feature ([`Candidate::refines`]), not a missing effect.

use crate::families::{Template, existing_rate, kind_named, language_has};
use crate::user_program;
use tcomp_core::expr::{self, Expr};
use tcomp_core::syntax::is_column_name;
use tcomp_train::Dataset;

pub use crate::families::{Family, Search};
pub use crate::hypothesis::{Candidate, EffectKind, Searched};

/// Lag time constants of the scoring grid (s); [`crate::param`] then searches `LAG_RANGE_S`.
pub const LAG_TAUS_S: [f64; 6] = [300.0, 600.0, 1200.0, 2400.0, 4800.0, 9600.0];
/// The range a lag's τ is searched over (s).
pub const LAG_RANGE_S: (f64, f64) = (120.0, 20_000.0);
/// Warm-up time constants of the scoring grid (s).
pub const WARMUP_TAUS_S: [f64; 5] = [150.0, 300.0, 600.0, 1200.0, 2400.0];
/// The range a warm-up's τ is searched over (s).
pub const WARMUP_RANGE_S: (f64, f64) = (60.0, 7200.0);
/// Hysteresis thresholds searched (temperature units per minute).
pub const HYST_THRESHOLDS: [f64; 4] = [0.02, 0.05, 0.1, 0.2];
/// The range a hysteresis threshold is searched over.
pub const HYST_RANGE: (f64, f64) = (0.01, 0.4);
/// Rate windows searched (s); 60 s is the core's default.
pub const RATE_WINDOWS_S: [f64; 2] = [60.0, 240.0];
/// The range a rate window is searched over (s).
pub const RATE_RANGE_S: (f64, f64) = (30.0, 1200.0);

/// What candidates are built from.
#[derive(Clone, Debug, Default)]
pub struct Sources {
    /// Temperatures: model signal names and thermometer columns.
    pub temperatures: Vec<String>,
    /// Thermometer columns (for gradients).
    pub thermometers: Vec<String>,
    /// Numeric non-temperature columns.
    pub inputs: Vec<String>,
    /// Chamber or ambient temperatures: not candidates, because a compensation that needs the
    /// chamber's air temperature cannot fly (and heat flow from the chamber is what a rate or a
    /// lag of the sensor's own thermometer describes).
    pub environment: Vec<String>,
    /// Other inertial outputs (gyro, accelerometer, magnetometer axes): not candidates, because in
    /// flight they carry the motion being measured, not only their own thermal drift.
    pub outputs: Vec<String>,
}

/// Whether a column reads as an inertial or magnetic output (`gyro*`, `acc*`, `mag*`).
pub fn is_sensor_output(name: &str) -> bool {
    let l = name.to_ascii_lowercase();
    ["gyro", "acc", "mag_", "ref_"]
        .iter()
        .any(|k| l.starts_with(k))
}

/// Whether a temperature column is the environment's (chamber, ambient, air, oven), not the sensor's.
pub fn is_environment(name: &str) -> bool {
    let l = name.to_ascii_lowercase();
    ["chamber", "ambient", "air", "oven"]
        .iter()
        .any(|k| l.contains(k))
}

/// Whether a column name reads as a temperature (`t_*`, `*temp*`, `*_c`, `*_degc`).
pub fn is_temperature(name: &str) -> bool {
    let l = name.to_ascii_lowercase();
    l.starts_with("t_") || l.contains("temp") || l.ends_with("_c") || l.ends_with("_degc")
}

/// Sorts the columns of `data` into temperatures and inputs, leaving out the roles (`exclude`),
/// columns that are not numeric, not finite or constant, and names the expression language cannot
/// spell. `signals` are the model's named signals (`NAME = EXPR`); they come first.
pub fn sources(data: &Dataset, exclude: &[&str], signals: &[String]) -> Sources {
    let mut s = Sources::default();
    for sig in signals {
        if let Some((name, _)) = sig.split_once('=') {
            s.temperatures.push(name.trim().to_string());
        }
    }
    for name in data.names() {
        if exclude.contains(&name.as_str()) || !is_column_name(name) {
            continue;
        }
        let Ok(col) = data.column(name) else { continue };
        let (lo, hi) = col
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(*v), h.max(*v))
            });
        if hi - lo <= 1e-12 * (1.0 + hi.abs()) {
            continue;
        }
        if is_sensor_output(name) {
            s.outputs.push(name.clone());
            continue;
        }
        if is_temperature(name) && is_environment(name) {
            s.environment.push(name.clone());
        } else if is_temperature(name) {
            s.temperatures.push(name.clone());
            s.thermometers.push(name.clone());
        } else {
            s.inputs.push(name.clone());
        }
    }
    s
}

fn single(kind: EffectKind, effect: String, exprs: Vec<Expr>) -> Family {
    Family {
        members: vec![Candidate {
            kind,
            effect,
            expressions: exprs.iter().map(Expr::to_string).collect(),
            parameter: None,
            replaces: Vec::new(),
            refines: None,
        }],
        search: None,
        searched: Searched::No,
    }
}

/// Every candidate family for these sources, minus expressions the model already has; `existing`
/// are the model's features (as the user wrote them: see [`crate::user_program::user_spec`]).
pub fn generate(src: &Sources, existing: &[String]) -> Vec<Family> {
    let norm = |e: &str| e.split_whitespace().collect::<String>();
    let have: Vec<String> = existing.iter().map(|e| norm(e)).collect();
    let mut out = Vec::new();
    for (_, generate) in LISTED {
        generate(src, existing, &mut out);
    }
    for f in &mut out {
        f.members.retain(|m| {
            m.expressions.iter().all(|e| !e.is_empty())
                && !m.expressions.iter().any(|e| have.contains(&norm(e)))
        });
    }
    out.retain(|f| !f.members.is_empty());
    out
}

/// A generator of listed families: from the run's sources and the model's features, appends its
/// families.
pub type Generator = fn(&Sources, &[String], &mut Vec<Family>);

/// The registry of listed families: one line per kind of mechanism, in the order they are
/// generated. A new kind is a function here and one line in this table; an effect the language
/// can compose needs neither ([`crate::compose`]).
pub const LISTED: &[(&str, Generator)] = &[
    ("temperature", |s, e, o| {
        for t in &s.temperatures {
            temperature_families(t, e, o);
        }
    }),
    ("gradients", |s, _, o| gradient_families(&s.thermometers, o)),
    ("gradient physics", |s, _, o| gradient_physics(s, o)),
    ("warm-up", |_, _, o| warmup_family(o)),
    ("inputs", |s, _, o| input_families(&s.inputs, o)),
];

/// The warm-up after power-on, when the core's language has it.
fn warmup_family(out: &mut Vec<Family>) {
    if language_has("warmup") {
        let (lo, hi) = WARMUP_RANGE_S;
        out.push(Template::Warmup.family(&WARMUP_TAUS_S, lo, hi));
    }
}

/// The effects of one temperature: rate (several windows; a refinement of the model's own rate
/// when it has one), Shupe-type product, lagged element (added beside the model's features, and
/// replacing the temperature in every one of them), heating/cooling hysteresis.
///
/// Not its square: curvature in a temperature is a shape of the bias–temperature curve, which the
/// model's own terms in temperature fit (its Gaussians, the additive structure's squares and
/// cubes, the cubic), not a missing signal — the same rule as the compositions'
/// ([`crate::compose`]). Measured: listed, it was named only where nothing was missing (fresh
/// negative controls 52000–: 2 of 100, each by a fit that extrapolated badly into the held-out
/// blocks and gained there, −65 % and −38 %, with the verification run unchanged) and beside a
/// hysteresis it did not belong to (a fresh run of `hidden_effects`).
fn temperature_families(t: &str, existing: &[String], out: &mut Vec<Family>) {
    let x = || expr::name(t);
    let (lo, hi) = RATE_RANGE_S;
    let rate = Template::Rate {
        of: t.to_string(),
        existing: existing_rate(t, existing),
    };
    let windows: Vec<f64> = RATE_WINDOWS_S
        .iter()
        .copied()
        .filter(|w| existing_rate(t, existing).is_none_or(|(_, w0)| *w != w0))
        .collect();
    out.push(rate.family(&windows, lo, hi));
    out.push(single(
        EffectKind::Shupe,
        format!("Shupe-type {t}·d{t}/dt"),
        vec![x() * expr::rate(x())],
    ));
    let (lo, hi) = LAG_RANGE_S;
    out.push(Template::Lag { of: t.to_string() }.family(&LAG_TAUS_S, lo, hi));
    if existing.iter().any(|f| user_program::uses(f, t)) {
        let replacing = Template::LagReplacing {
            name: t.to_string(),
            features: existing.to_vec(),
        };
        out.push(replacing.family(&LAG_TAUS_S, lo, hi));
    }
    let (lo, hi) = HYST_RANGE;
    out.push(Template::Hyst { of: t.to_string() }.family(&HYST_THRESHOLDS, lo, hi));
}

/// `a - b` of two columns.
fn difference(a: &str, b: &str) -> Expr {
    expr::name(a) - expr::name(b)
}

/// Gradients between thermometers: each pair, and two gradients against a common thermometer.
fn gradient_families(th: &[String], out: &mut Vec<Family>) {
    for (i, a) in th.iter().enumerate() {
        for b in th.iter().skip(i + 1) {
            out.push(single(
                EffectKind::Gradient,
                format!("thermal gradient {a}−{b}"),
                vec![difference(a, b)],
            ));
        }
    }
    // Two gradients against a common thermometer (the RLG's anode−shell and cathode−shell).
    for i in 0..th.len() {
        for j in i + 1..th.len() {
            for k in j + 1..th.len() {
                let (Some(a), Some(b), Some(r)) = (th.get(i), th.get(j), th.get(k)) else {
                    continue;
                };
                out.push(single(
                    EffectKind::Gradient,
                    format!("thermal gradients {a}−{r} and {b}−{r}"),
                    vec![difference(a, r), difference(b, r)],
                ));
            }
        }
    }
}

/// What a gradient does besides being there: its rate (a gradient that changes drives the bias,
/// as heat flows through the block), its lag (the gradient reaches the sensing element late),
/// and its product with the temperature (a gradient's effect that grows with temperature). The
/// temperature of the products is the model's own (its signals), else the first thermometer.
fn gradient_physics(src: &Sources, out: &mut Vec<Family>) {
    let th = &src.thermometers;
    let signals: Vec<&String> = src
        .temperatures
        .iter()
        .filter(|t| !th.contains(t))
        .collect();
    let temps: Vec<&String> = if signals.is_empty() {
        th.first().into_iter().collect()
    } else {
        signals
    };
    let (lo, hi) = LAG_RANGE_S;
    for (i, a) in th.iter().enumerate() {
        for b in th.iter().skip(i + 1) {
            out.push(single(
                kind_named("gradient_rate", EffectKind::Gradient),
                format!("rate of the thermal gradient d({a}−{b})/dt"),
                vec![expr::rate(difference(a, b))],
            ));
            let lagged = Template::GradientLag {
                a: a.clone(),
                b: b.clone(),
            };
            out.push(lagged.family(&LAG_TAUS_S, lo, hi));
            for t in &temps {
                if *t == a || *t == b {
                    continue;
                }
                out.push(single(
                    kind_named("temp_gradient_product", EffectKind::Gradient),
                    format!("temperature × thermal gradient {t}·({a}−{b})"),
                    vec![expr::name(t) * difference(a, b)],
                ));
            }
        }
    }
}

/// Non-thermal inputs (a supply voltage by its name).
fn input_families(inputs: &[String], out: &mut Vec<Family>) {
    for c in inputs {
        let effect = if c.to_ascii_lowercase().contains("supply") || c.ends_with("_v") {
            format!("supply-voltage sensitivity ({c})")
        } else {
            format!("non-thermal input {c}")
        };
        out.push(single(EffectKind::NonThermal, effect, vec![expr::name(c)]));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_registered_generator_lists_families() {
        let src = Sources {
            temperatures: vec!["t_a_c".into(), "t_b_c".into()],
            thermometers: vec!["t_a_c".into(), "t_b_c".into()],
            inputs: vec!["supply_v".into()],
            ..Sources::default()
        };
        let mut names = std::collections::HashSet::new();
        for (name, generate) in LISTED {
            assert!(names.insert(*name), "{name} registered twice");
            let mut out = Vec::new();
            generate(&src, &[], &mut out);
            assert!(!out.is_empty(), "{name} listed nothing");
        }
        let all: usize = generate(&src, &[]).len();
        assert!(all >= LISTED.len());
    }

    #[test]
    fn temperatures_and_inputs_are_told_apart() {
        for t in ["t_coil_c", "temp_imu_C", "t_anode_c", "board_degC"] {
            assert!(is_temperature(t), "{t}");
        }
        for n in ["supply_v", "gyro_dph", "chunk_id", "acc_x_m_s2"] {
            assert!(!is_temperature(n), "{n}");
        }
    }

    #[test]
    fn generated_names_and_expressions() {
        let src = Sources {
            temperatures: vec!["T".into(), "t_a".into(), "t_b".into(), "t_s".into()],
            thermometers: vec!["t_a".into(), "t_b".into(), "t_s".into()],
            inputs: vec!["supply_v".into()],
            environment: Vec::new(),
            outputs: Vec::new(),
        };
        let f = generate(&src, &["rate(T)".into(), "T".into()]);
        let all: Vec<&Candidate> = f.iter().flat_map(|f| &f.members).collect();
        assert!(!all.iter().any(|c| c.expressions == ["rate(T)"]));
        assert!(all.iter().any(|c| c.expressions == ["T * rate(T)"]));
        assert!(
            all.iter()
                .any(|c| c.expressions == ["lag(t_a, 2400)"] && c.effect.contains("τ ≈ 40 min"))
        );
        assert!(
            all.iter()
                .any(|c| c.expressions == ["t_a - t_s", "t_b - t_s"])
        );
        assert!(all.iter().any(|c| c.effect.contains("supply-voltage")));
        assert!(all.len() >= 20);
    }
}
