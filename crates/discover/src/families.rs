//! The hypotheses with a parameter: how a candidate is built at any value of its parameter (a
//! lag's τ, a rate window, a hysteresis threshold, a warm-up's τ), the grid scoring starts from,
//! and the range [`crate::param`] searches on a continuous scale.
//!
//! Why a template rather than a list of members: the parameter is estimated, not picked from a
//! grid (a doubling grid cannot get a lag's τ closer than a factor of √2, and the held-out residual
//! can change several-fold over that), so the family must be able to build its member at any
//! value the optimiser asks for. Every expression is built as a tree ([`tcomp_core::expr`]) and
//! printed by its one printer.

use crate::hypothesis::{Candidate, EffectKind, Searched, num};
use crate::user_program;
use serde::Serialize;
use tcomp_core::expr::{self, Expr};

/// A hypothesis: candidates differing only in a searched parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Family {
    /// Members scored (one for a plain candidate; the grid of a searched parameter).
    pub members: Vec<Candidate>,
    /// How the parameter is searched beyond the grid (none for a plain candidate).
    pub search: Option<Search>,
    /// How the member was read off the data, when it was rather than built by a template: what
    /// each of its placebos searches the same way ([`crate::placebo`]).
    pub searched: Searched,
}

/// A family's parameter as [`crate::param`] searches it: the template that builds a member, and
/// the range of the search (log scale).
#[derive(Clone, Debug, PartialEq)]
pub struct Search {
    /// Builds the member at a value.
    pub template: Template,
    /// Lowest value searched.
    pub lo: f64,
    /// Highest value searched.
    pub hi: f64,
}

/// How the members of a family are built from the parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Template {
    /// `lag(x, τ)` added beside the model's features: an element lagging its thermometer `x`.
    Lag {
        /// The lagged temperature.
        of: String,
    },
    /// Every use of the temperature `name` in the model's `features` replaced by `lag(name, τ)`:
    /// the element sees the lagged temperature *instead of* the thermometer's.
    LagReplacing {
        /// The temperature replaced.
        name: String,
        /// The model's features.
        features: Vec<String>,
    },
    /// `lag(a - b, τ)`: a thermal gradient that reaches the element late.
    GradientLag {
        /// Warmer side.
        a: String,
        /// Reference side.
        b: String,
    },
    /// `rate(x, w)` added; or, with `existing`, replacing the model's own rate of `x`.
    Rate {
        /// The temperature.
        of: String,
        /// The model's rate of `x` and its window, when it has one.
        existing: Option<(String, f64)>,
    },
    /// `hyst(rate(x), h)`.
    Hyst {
        /// The temperature.
        of: String,
    },
    /// `warmup(τ)`: e^(−t_on/τ), the transient after power-on.
    Warmup,
}

/// What the searched parameter is (for reports).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ParamKind {
    /// A time constant τ (s).
    TimeConstant,
    /// A rate window (s).
    Window,
    /// A hysteresis threshold (temperature units per minute).
    Threshold,
}

/// `τ ≈ 40 min` (or seconds under ten minutes).
fn minutes(tau_s: f64) -> String {
    if tau_s >= 600.0 {
        format!("τ ≈ {} min", num((tau_s / 60.0).round()))
    } else {
        format!("τ ≈ {} s", num(tau_s.round()))
    }
}

/// The effect kind of the core's vocabulary called `name`, or `fallback` while the vocabulary
/// lacks it (the simulator's newer effects add their names there).
pub fn kind_named(name: &str, fallback: EffectKind) -> EffectKind {
    EffectKind::from_name(name).unwrap_or(fallback)
}

impl Template {
    /// What the parameter is.
    pub fn param_kind(&self) -> ParamKind {
        match self {
            Template::Rate { .. } => ParamKind::Window,
            Template::Hyst { .. } => ParamKind::Threshold,
            _ => ParamKind::TimeConstant,
        }
    }

    /// The value to take when the training run cannot tell the values apart and it is among
    /// them: the language's default rate window (`rate(T)`, the simplest expression the data do not
    /// reject). Other parameters have no conventional value.
    pub fn default_value(&self) -> Option<f64> {
        match self {
            Template::Rate { existing: None, .. } => {
                Some(f64::from(tcomp_core::lang::DEFAULT_RATE_WINDOW_S))
            }
            _ => None,
        }
    }

    /// Which temperature profile would tell the parameter's values apart, when the training run
    /// cannot.
    pub fn resolving_profile(&self) -> &'static str {
        match self {
            Template::Lag { .. } | Template::LagReplacing { .. } | Template::GradientLag { .. } => {
                "a fast temperature step followed by a long hold (the element's settling after the \
                 step shows τ directly)"
            }
            Template::Warmup => {
                "a record from power-on at constant temperature, several τ long, repeated after a \
                 cold start"
            }
            Template::Rate { .. } => {
                "ramps at several different rates, and ramps that reverse (the window's delay \
                 shows at each reversal)"
            }
            Template::Hyst { .. } => "slow ramps that reverse at several rates",
        }
    }

    /// The member at `p`.
    pub fn member(&self, p: f64) -> Candidate {
        let added = |kind, effect, e: Expr| Candidate::added(kind, effect, vec![e.to_string()], p);
        match self {
            Template::Lag { of } => added(
                EffectKind::LaggedElement,
                format!("sensing element lags its thermometer {of}, {}", minutes(p)),
                expr::lag(expr::name(of), p),
            ),
            Template::LagReplacing { name, features } => {
                let by = expr::lag(expr::name(name), p);
                let replaces: Vec<String> = features
                    .iter()
                    .filter(|f| user_program::uses(f, name))
                    .cloned()
                    .collect();
                Candidate {
                    kind: EffectKind::LaggedElement,
                    effect: format!(
                        "sensing element sees {by} instead of {name} (every use replaced), {}",
                        minutes(p)
                    ),
                    expressions: replaces
                        .iter()
                        .map(|f| user_program::replace(f, name, &by))
                        .collect(),
                    parameter: Some(p),
                    replaces,
                    refines: None,
                }
            }
            Template::GradientLag { a, b } => added(
                kind_named("gradient_lag", EffectKind::Gradient),
                format!(
                    "thermal gradient {a}−{b} reaching the element late, {}",
                    minutes(p)
                ),
                expr::lag(expr::name(a) - expr::name(b), p),
            ),
            Template::Rate { of, existing } => {
                let e = expr::rate_window(expr::name(of), p);
                match existing {
                    None => added(
                        EffectKind::Rate,
                        format!("rate of temperature d{of}/dt (window {} s)", num(p)),
                        e,
                    ),
                    Some((feature, w0)) => Candidate {
                        kind: EffectKind::Rate,
                        effect: format!(
                            "a {} window of the existing rate {feature} ({} s instead of {} s)",
                            if p > *w0 { "longer" } else { "shorter" },
                            num(p),
                            num(*w0)
                        ),
                        expressions: vec![e.to_string()],
                        parameter: Some(p),
                        replaces: vec![feature.clone()],
                        refines: Some(feature.clone()),
                    },
                }
            }
            Template::Hyst { of } => added(
                EffectKind::Hysteresis,
                format!(
                    "heating/cooling hysteresis of {of} (switches at ±{} per min)",
                    num(p)
                ),
                expr::hyst(expr::rate(expr::name(of)), p),
            ),
            Template::Warmup => added(
                EffectKind::Warmup,
                format!("warm-up transient after power-on, {}", minutes(p)),
                Expr::call("warmup", [Expr::num(p)]),
            ),
        }
    }

    /// The family: its members on `grid`, searched over `[lo, hi]`.
    pub fn family(self, grid: &[f64], lo: f64, hi: f64) -> Family {
        Family {
            members: grid.iter().map(|&p| self.member(p)).collect(),
            searched: Searched::No,
            search: Some(Search {
                template: self,
                lo,
                hi,
            }),
        }
    }
}

/// Whether the core's language has the function `name` (`warmup` arrives with a newer core; until
/// then its family is left out, so this crate builds and diagnoses with either).
pub fn language_has(name: &str) -> bool {
    tcomp_core::lang::function(name).is_some()
}

/// The model's rate of `x` among `features` and its window: `rate(x)` or `rate(x, w)`.
pub fn existing_rate(x: &str, features: &[String]) -> Option<(String, f64)> {
    let norm = |e: &str| e.split_whitespace().collect::<String>();
    let plain = norm(&expr::rate(expr::name(x)).to_string());
    let open = plain.strip_suffix(')').unwrap_or(&plain).to_string() + ",";
    features.iter().find_map(|f| {
        let n = norm(f);
        if n == plain {
            return Some((
                f.clone(),
                f64::from(tcomp_core::lang::DEFAULT_RATE_WINDOW_S),
            ));
        }
        let w: f64 = n.strip_prefix(&open)?.strip_suffix(')')?.parse().ok()?;
        Some((f.clone(), w))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lag_replacing_its_thermometer_rewrites_every_use() {
        let t = Template::LagReplacing {
            name: "T".into(),
            features: vec!["T".into(), "rate(T)".into(), "t_a - t_s".into()],
        };
        let m = t.member(1800.0);
        assert_eq!(m.replaces, vec!["T".to_string(), "rate(T)".to_string()]);
        assert_eq!(
            m.expressions,
            vec!["lag(T, 1800)".to_string(), "rate(lag(T, 1800))".to_string()]
        );
        assert_eq!(
            m.applied_to(&["T".into(), "rate(T)".into(), "t_a - t_s".into()]),
            vec![
                "lag(T, 1800)".to_string(),
                "rate(lag(T, 1800))".to_string(),
                "t_a - t_s".to_string()
            ]
        );
        assert!(m.effect.contains("τ ≈ 30 min"), "{}", m.effect);
    }

    #[test]
    fn the_existing_rate_is_found_with_its_window() {
        let f = vec!["temp_imu_C".to_string(), "rate(temp_imu_C)".to_string()];
        assert_eq!(
            existing_rate("temp_imu_C", &f),
            Some(("rate(temp_imu_C)".to_string(), 60.0))
        );
        let f = vec!["rate( T , 240 )".to_string()];
        assert_eq!(existing_rate("T", &f).map(|e| e.1), Some(240.0));
        assert_eq!(existing_rate("T2", &f), None);
        let m = Template::Rate {
            of: "temp_imu_C".into(),
            existing: Some(("rate(temp_imu_C)".into(), 60.0)),
        }
        .member(240.0);
        assert!(m.effect.starts_with("a longer window of the existing rate"));
        assert_eq!(m.refines.as_deref(), Some("rate(temp_imu_C)"));
    }
}
