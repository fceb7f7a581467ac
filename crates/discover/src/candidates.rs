//! Candidate features: the physical effects a model may be missing, generated from the file's
//! columns and the model's signals, each with a name an engineer recognises and an expression ready
//! for `tcomp fit --feature`.
//!
//! Why generated, not hand-listed: on a user's own data nobody knows the answer in advance, so every
//! plausible mechanism is put to the same test. For each temperature (the model's signals and every
//! thermometer column): its rate, the Shupe-type product T·dT/dt, its square, a lag with the time
//! constant searched over a grid (a sensing element that lags its thermometer), and a
//! heating/cooling hysteresis state with the threshold searched; for every pair or triple of
//! thermometers, their differences (thermal gradients); and every other numeric column (supply
//! voltage, other channels) as a non-thermal input. A *family* is one hypothesis with a searched
//! parameter (τ, threshold, rate window); its members are scored individually and the family's
//! evidence is marginalised over the grid, so searching more values does not buy evidence.

use serde::Serialize;
use tcomp_core::expr::{self, Expr};
use tcomp_core::parse::is_identifier;
use tcomp_train::Dataset;

/// Lag time constants searched (s).
pub const LAG_TAUS_S: [f64; 6] = [300.0, 600.0, 1200.0, 2400.0, 4800.0, 9600.0];
/// Hysteresis thresholds searched (temperature units per minute).
pub const HYST_THRESHOLDS: [f64; 4] = [0.02, 0.05, 0.1, 0.2];
/// Rate windows searched (s); 60 s is the core's default.
pub const RATE_WINDOWS_S: [f64; 2] = [60.0, 240.0];

/// The kind of physical effect a candidate stands for: the core's vocabulary, shared with the
/// simulator (which hides effects of these kinds).
pub use tcomp_core::EffectKind;

/// One candidate: the features to add.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Candidate {
    /// Effect kind.
    pub kind: EffectKind,
    /// Physical name, e.g. "Shupe-type T·dT/dt of t_coil_c".
    pub effect: String,
    /// Feature expressions to add (one, or two/three for gradient sets).
    pub expressions: Vec<String>,
    /// The searched parameter: τ (s) for lags, threshold for hysteresis, window (s) for rates.
    pub parameter: Option<f64>,
}

/// A hypothesis: candidates differing only in a searched parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Family {
    /// Members (one for a plain candidate).
    pub members: Vec<Candidate>,
}

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
        if exclude.contains(&name.as_str()) || !is_identifier(name) {
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

fn num(v: f64) -> String {
    let s = format!("{v}");
    s.strip_suffix(".0").map(str::to_string).unwrap_or(s)
}

fn single(kind: EffectKind, effect: String, expr: Expr, parameter: Option<f64>) -> Family {
    Family {
        members: vec![Candidate {
            kind,
            effect,
            expressions: vec![expr.to_string()],
            parameter,
        }],
    }
}

/// Every candidate family for these sources, minus expressions the model already has.
pub fn generate(src: &Sources, existing: &[String]) -> Vec<Family> {
    let norm = |e: &str| e.split_whitespace().collect::<String>();
    let have: Vec<String> = existing.iter().map(|e| norm(e)).collect();
    let mut out = Vec::new();
    for t in &src.temperatures {
        temperature_families(t, &mut out);
    }
    gradient_families(&src.thermometers, &mut out);
    input_families(&src.inputs, &mut out);
    for f in &mut out {
        f.members
            .retain(|m| !m.expressions.iter().any(|e| have.contains(&norm(e))));
    }
    out.retain(|f| !f.members.is_empty());
    out
}

/// The effects of one temperature: rate (several windows), Shupe-type product, curvature, lagged
/// element (several time constants), heating/cooling hysteresis (several thresholds).
fn temperature_families(t: &str, out: &mut Vec<Family>) {
    let x = || expr::name(t);
    out.push(Family {
        members: RATE_WINDOWS_S
            .iter()
            .map(|&w| Candidate {
                kind: EffectKind::Rate,
                effect: format!("rate of temperature d{t}/dt (window {} s)", num(w)),
                expressions: vec![expr::rate_window(x(), w).to_string()],
                parameter: Some(w),
            })
            .collect(),
    });
    out.push(single(
        EffectKind::Shupe,
        format!("Shupe-type {t}·d{t}/dt"),
        x() * expr::rate(x()),
        None,
    ));
    out.push(single(
        EffectKind::Square,
        format!("curvature in temperature {t}²"),
        expr::sq(x()),
        None,
    ));
    out.push(Family {
        members: LAG_TAUS_S
            .iter()
            .map(|&tau| Candidate {
                kind: EffectKind::LaggedElement,
                effect: format!(
                    "sensing element lags its thermometer {t}, τ ≈ {} min",
                    num((tau / 60.0).round())
                ),
                expressions: vec![expr::lag(x(), tau).to_string()],
                parameter: Some(tau),
            })
            .collect(),
    });
    out.push(Family {
        members: HYST_THRESHOLDS
            .iter()
            .map(|&h| Candidate {
                kind: EffectKind::Hysteresis,
                effect: format!(
                    "heating/cooling hysteresis of {t} (switches at ±{} per min)",
                    num(h)
                ),
                expressions: vec![expr::hyst(expr::rate(x()), h).to_string()],
                parameter: Some(h),
            })
            .collect(),
    });
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
                difference(a, b),
                None,
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
                out.push(Family {
                    members: vec![Candidate {
                        kind: EffectKind::Gradient,
                        effect: format!("thermal gradients {a}−{r} and {b}−{r}"),
                        expressions: vec![
                            difference(a, r).to_string(),
                            difference(b, r).to_string(),
                        ],
                        parameter: None,
                    }],
                });
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
        out.push(single(EffectKind::NonThermal, effect, expr::name(c), None));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
