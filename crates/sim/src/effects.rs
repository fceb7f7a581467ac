//! Named bias effects and their exact feature expressions.
//!
//! Why: tests and demos need a bias whose parts are known by name, so that a diagnosis can be checked
//! against "the effect that is really there". Each effect is evaluated from the *recorded* columns of
//! the output file, sample by sample with the core's streaming operators ([`crate::ops`]), so the
//! expressions written to the truth file reproduce the bias exactly (to float rounding): a perfect
//! model is limited only by the noise.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::ops::{Hyst, Lag, RATE_WINDOW_S, Rate};
use crate::scenario::SensorKind;

/// The names of the effects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    /// Polynomial in temperature.
    Poly,
    /// Rate of temperature.
    Rate,
    /// Thermometer gradients anode−shell and cathode−shell (RLG only).
    Gradient,
    /// Shupe-type product T·dT/dt.
    Shupe,
    /// A sensing element whose temperature lags its thermometer.
    LaggedElement,
    /// Heating/cooling hysteresis.
    Hysteresis,
    /// Warm-up transient after power-on.
    Warmup,
    /// Sensitivity to the supply voltage (a non-thermal input).
    SupplyVoltage,
}

impl EffectKind {
    /// Every effect, in a fixed order.
    pub const ALL: [EffectKind; 8] = [
        EffectKind::Poly,
        EffectKind::Rate,
        EffectKind::Gradient,
        EffectKind::Shupe,
        EffectKind::LaggedElement,
        EffectKind::Hysteresis,
        EffectKind::Warmup,
        EffectKind::SupplyVoltage,
    ];

    /// The name used in TOML and in the truth file.
    pub fn name(self) -> &'static str {
        match self {
            EffectKind::Poly => "poly",
            EffectKind::Rate => "rate",
            EffectKind::Gradient => "gradient",
            EffectKind::Shupe => "shupe",
            EffectKind::LaggedElement => "lagged_element",
            EffectKind::Hysteresis => "hysteresis",
            EffectKind::Warmup => "warmup",
            EffectKind::SupplyVoltage => "supply_voltage",
        }
    }

    /// The effect of this name, if any.
    pub fn from_name(name: &str) -> Option<EffectKind> {
        EffectKind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Comma-separated list of all names (for error messages).
    pub fn known() -> String {
        EffectKind::ALL.map(|k| k.name()).join(", ")
    }

    /// Whether the effect can be applied to this sensor.
    pub fn applies_to(self, sensor: SensorKind) -> bool {
        !(self == EffectKind::Gradient && sensor != SensorKind::Rlg)
    }
}

fn default_t0() -> f64 {
    20.0
}
fn default_input() -> String {
    "T".to_string()
}
fn default_window() -> f64 {
    RATE_WINDOW_S
}
fn default_nominal_v() -> f64 {
    28.0
}

/// One bias effect with its coefficients. `input` is `"T"` (the sensor's temperature: the mean of
/// its thermometers for the RLG, the only thermometer otherwise) or a thermometer column name.
/// Coefficients are in output units (°/h or µg) per unit of their feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "name", rename_all = "snake_case", deny_unknown_fields)]
pub enum Effect {
    /// `Σ c_k·(T − t0)^k`, k = 1..=len (at most 5 coefficients).
    Poly {
        /// Coefficients of (T − t0), (T − t0)², … in output units per °C^k.
        coefficients: Vec<f64>,
        /// Expansion point, °C.
        #[serde(default = "default_t0")]
        t0_c: f64,
        /// Temperature input.
        #[serde(default = "default_input")]
        input: String,
    },
    /// `c·rate(T, window)` with the rate in °C/min.
    Rate {
        /// Output units per °C/min.
        coefficient: f64,
        /// Window of the rate, s.
        #[serde(default = "default_window")]
        window_s: f64,
        /// Temperature input.
        #[serde(default = "default_input")]
        input: String,
    },
    /// `a·(t_anode_c − t_shell_c) + c·(t_cathode_c − t_shell_c)` (RLG only).
    Gradient {
        /// Output units per °C of anode−shell.
        anode_shell: f64,
        /// Output units per °C of cathode−shell.
        cathode_shell: f64,
    },
    /// `c·T·rate(T, window)` (Shupe-type product).
    Shupe {
        /// Output units per °C·°C/min.
        coefficient: f64,
        /// Window of the rate, s.
        #[serde(default = "default_window")]
        window_s: f64,
        /// Temperature input.
        #[serde(default = "default_input")]
        input: String,
    },
    /// `c·(lag(T, tau) − t0)`: a sensing element lagging its thermometer.
    LaggedElement {
        /// Output units per °C.
        coefficient: f64,
        /// Time constant of the element behind its thermometer, s.
        tau_s: f64,
        /// Reference temperature, °C.
        #[serde(default = "default_t0")]
        t0_c: f64,
        /// Temperature input.
        #[serde(default = "default_input")]
        input: String,
    },
    /// `c·hyst(rate(T, window), threshold)`: +c after heating, −c after cooling.
    Hysteresis {
        /// Half the heating/cooling difference, output units.
        coefficient: f64,
        /// Rate threshold, °C/min.
        #[serde(default = "default_threshold")]
        threshold_c_per_min: f64,
        /// Window of the rate, s.
        #[serde(default = "default_window")]
        window_s: f64,
        /// Temperature input.
        #[serde(default = "default_input")]
        input: String,
    },
    /// `c·exp(−(t − t_first)/tau)`: a warm-up transient, written exactly as
    /// `1 - (time_s - lag(time_s, tau)) / D` with `D = dt·e^(−dt/τ)/(1 − e^(−dt/τ))`.
    Warmup {
        /// Amplitude at power-on, output units.
        coefficient: f64,
        /// Decay time constant, s.
        tau_s: f64,
    },
    /// `c·(supply_v − nominal)`.
    SupplyVoltage {
        /// Output units per volt.
        coefficient: f64,
        /// Nominal supply, V.
        #[serde(default = "default_nominal_v")]
        nominal_v: f64,
    },
}

fn default_threshold() -> f64 {
    0.05
}

/// How an effect's input temperature is read from a row.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Input {
    Mean,
    Column(usize),
}

/// One output row's inputs (recorded, rounded values).
#[derive(Debug, Clone, Copy)]
pub(crate) struct RowInputs<'a> {
    pub time_s: f64,
    pub therms: &'a [f64],
    pub supply_v: f64,
}

impl RowInputs<'_> {
    fn read(&self, input: Input) -> f64 {
        match input {
            Input::Column(i) => self.therms.get(i).copied().unwrap_or(f64::NAN),
            Input::Mean => {
                let n = self.therms.len().max(1) as f64;
                self.therms.iter().sum::<f64>() / n
            }
        }
    }
}

/// Streaming state of one effect.
#[derive(Debug, Clone)]
pub(crate) enum EffectState {
    Poly(Input, f64, Vec<f64>),
    Rate(Input, f64, Rate),
    Gradient(usize, usize, usize, f64, f64),
    Shupe(Input, f64, Rate),
    Lagged(Input, f64, f64, Lag),
    Hyst(Input, f64, Rate, Hyst),
    Warmup(f64, f64, Lag),
    Supply(f64, f64),
}

impl EffectState {
    /// Contribution of this effect for one row of period `dt`.
    pub fn step(&mut self, row: &RowInputs<'_>, dt: f64) -> f64 {
        match self {
            EffectState::Poly(inp, t0, c) => {
                let x = row.read(*inp) - *t0;
                let mut p = 1.0;
                let mut sum = 0.0;
                for ck in c.iter() {
                    p *= x;
                    sum += ck * p;
                }
                sum
            }
            EffectState::Rate(inp, c, r) => *c * r.step(row.read(*inp), dt),
            EffectState::Gradient(a, c, s, ka, kc) => {
                let g = |i: usize| row.therms.get(i).copied().unwrap_or(f64::NAN);
                *ka * (g(*a) - g(*s)) + *kc * (g(*c) - g(*s))
            }
            EffectState::Shupe(inp, c, r) => {
                let t = row.read(*inp);
                *c * t * r.step(t, dt)
            }
            EffectState::Lagged(inp, c, t0, lag) => *c * (lag.step(row.read(*inp), dt) - *t0),
            EffectState::Hyst(inp, c, r, h) => *c * h.step(r.step(row.read(*inp), dt)),
            EffectState::Warmup(c, d, lag) => {
                let l = lag.step(row.time_s, dt);
                *c * (1.0 - (row.time_s - l) / *d)
            }
            EffectState::Supply(c, v0) => *c * (row.supply_v - *v0),
        }
    }
}

/// What the truth file says about one effect.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectTruth {
    /// Effect name (see [`EffectKind`]).
    pub name: String,
    /// The main coefficient (the first of `coefficients`).
    pub coefficient: f64,
    /// Unit of `coefficient`.
    pub unit: String,
    /// The effect equals `offset + Σ coefficients[i] · expressions[i]` over the file's columns.
    pub expressions: Vec<String>,
    /// One coefficient per expression.
    pub coefficients: Vec<f64>,
    /// Unit of each coefficient.
    pub coefficient_units: Vec<String>,
    /// Constant part of the effect, output units.
    pub offset: f64,
    /// The inputs a model needs to represent this effect (what to pass as `--feature`).
    pub features: Vec<String>,
    /// Physical meaning.
    pub description: String,
    /// Std of this effect's contribution over the run, output units (filled after the run).
    pub contribution_std: f64,
    /// Peak-to-peak of this effect's contribution over the run, output units (filled after the run).
    pub contribution_p2p: f64,
}

/// Resolves the names the effects refer to, for one sensor.
#[derive(Debug, Clone)]
pub(crate) struct Context<'a> {
    pub sensor: SensorKind,
    pub therm_names: &'a [String],
    pub unit: &'a str,
}

impl Context<'_> {
    fn input(&self, name: &str, field: &str) -> Result<Input> {
        if name == "T" {
            return Ok(if self.therm_names.len() == 1 {
                Input::Column(0)
            } else {
                Input::Mean
            });
        }
        self.therm_names
            .iter()
            .position(|n| n == name)
            .map(Input::Column)
            .ok_or_else(|| {
                Error::invalid(
                    field,
                    format!(
                        "unknown input \"{name}\" (use \"T\" or one of: {})",
                        self.therm_names.join(", ")
                    ),
                )
            })
    }

    /// Expression text of an input.
    fn input_expr(&self, name: &str) -> String {
        if name == "T" && self.therm_names.len() == 1 {
            self.therm_names.first().cloned().unwrap_or_default()
        } else {
            name.to_string()
        }
    }

    /// Named signals the expressions use (the RLG's `T`).
    pub fn signals(&self) -> Vec<(String, String)> {
        if self.therm_names.len() > 1 {
            vec![(
                "T".to_string(),
                format!("mean({})", self.therm_names.join(", ")),
            )]
        } else {
            Vec::new()
        }
    }
}

fn num(x: f64) -> String {
    format!("{x}")
}

/// `x - c` written without unary minus.
fn shifted(x: &str, c: f64) -> String {
    if c == 0.0 {
        x.to_string()
    } else if c > 0.0 {
        format!("{x} - {}", num(c))
    } else {
        format!("{x} + {}", num(-c))
    }
}

fn rate_expr(x: &str, window_s: f64) -> String {
    if window_s == RATE_WINDOW_S {
        format!("rate({x})")
    } else {
        format!("rate({x}, {})", num(window_s))
    }
}

/// The constant `D = dt·e^(−dt/τ)/(1 − e^(−dt/τ))` of the warm-up expression.
pub(crate) fn warmup_d(dt: f64, tau_s: f64) -> f64 {
    let e = (-dt / tau_s).exp();
    dt * e / (1.0 - e)
}

fn check_finite(v: f64, field: String) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Error::invalid(field, "must be finite"))
    }
}

fn check_pos(v: f64, field: String) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(field, format!("must be > 0, got {v}")))
    }
}

impl Effect {
    /// Which effect this is.
    pub fn kind(&self) -> EffectKind {
        match self {
            Effect::Poly { .. } => EffectKind::Poly,
            Effect::Rate { .. } => EffectKind::Rate,
            Effect::Gradient { .. } => EffectKind::Gradient,
            Effect::Shupe { .. } => EffectKind::Shupe,
            Effect::LaggedElement { .. } => EffectKind::LaggedElement,
            Effect::Hysteresis { .. } => EffectKind::Hysteresis,
            Effect::Warmup { .. } => EffectKind::Warmup,
            Effect::SupplyVoltage { .. } => EffectKind::SupplyVoltage,
        }
    }

    /// A realistic default of `kind` for `sensor`: well above the noise floor of that sensor.
    pub fn default_for(kind: EffectKind, sensor: SensorKind) -> Effect {
        // Scale: °/h for the gyros, µg for the QMA.
        let (poly, rate, shupe, lagc, hyst, warm, supply) = match sensor {
            SensorKind::Rlg => (vec![0.004, 5e-5, 1e-6], 0.15, 0.006, 0.005, 0.08, 0.5, 0.2),
            SensorKind::Qma => (vec![15.0, 0.2, 0.005], 60.0, 3.0, 8.0, 50.0, 200.0, 200.0),
            SensorKind::Ifog => (vec![0.01, 2e-4, 4e-6], 0.3, 0.02, 0.008, 0.1, 0.6, 0.3),
        };
        let input = default_input();
        match kind {
            EffectKind::Poly => Effect::Poly {
                coefficients: poly,
                t0_c: 20.0,
                input,
            },
            EffectKind::Rate => Effect::Rate {
                coefficient: rate,
                window_s: RATE_WINDOW_S,
                input,
            },
            EffectKind::Gradient => Effect::Gradient {
                anode_shell: 0.25,
                cathode_shell: -0.15,
            },
            EffectKind::Shupe => Effect::Shupe {
                coefficient: shupe,
                window_s: RATE_WINDOW_S,
                input,
            },
            EffectKind::LaggedElement => Effect::LaggedElement {
                coefficient: lagc,
                tau_s: 2400.0,
                t0_c: 20.0,
                input,
            },
            EffectKind::Hysteresis => Effect::Hysteresis {
                coefficient: hyst,
                threshold_c_per_min: 0.05,
                window_s: RATE_WINDOW_S,
                input,
            },
            EffectKind::Warmup => Effect::Warmup {
                coefficient: warm,
                tau_s: 1200.0,
            },
            EffectKind::SupplyVoltage => Effect::SupplyVoltage {
                coefficient: supply,
                nominal_v: 28.0,
            },
        }
    }

    /// Checks the effect for the sensor in `ctx`; errors name `effects[i].<field>`.
    pub(crate) fn validate(&self, ctx: &Context<'_>, at: &str) -> Result<()> {
        if !self.kind().applies_to(ctx.sensor) {
            return Err(Error::invalid(
                format!("{at}.name"),
                format!(
                    "\"{}\" needs anode, cathode and shell thermometers; sensor {} has {}",
                    self.kind().name(),
                    ctx.sensor.name(),
                    ctx.therm_names.join(", ")
                ),
            ));
        }
        match self {
            Effect::Poly {
                coefficients,
                t0_c,
                input,
            } => {
                if coefficients.is_empty() || coefficients.len() > 5 {
                    return Err(Error::invalid(
                        format!("{at}.coefficients"),
                        "give 1 to 5 coefficients (linear, quadratic, ...)",
                    ));
                }
                for (i, c) in coefficients.iter().enumerate() {
                    check_finite(*c, format!("{at}.coefficients[{i}]"))?;
                }
                check_finite(*t0_c, format!("{at}.t0_c"))?;
                ctx.input(input, &format!("{at}.input"))?;
            }
            Effect::Rate {
                coefficient,
                window_s,
                input,
            }
            | Effect::Shupe {
                coefficient,
                window_s,
                input,
            } => {
                check_finite(*coefficient, format!("{at}.coefficient"))?;
                check_pos(*window_s, format!("{at}.window_s"))?;
                ctx.input(input, &format!("{at}.input"))?;
            }
            Effect::Gradient {
                anode_shell,
                cathode_shell,
            } => {
                check_finite(*anode_shell, format!("{at}.anode_shell"))?;
                check_finite(*cathode_shell, format!("{at}.cathode_shell"))?;
            }
            Effect::LaggedElement {
                coefficient,
                tau_s,
                t0_c,
                input,
            } => {
                check_finite(*coefficient, format!("{at}.coefficient"))?;
                check_pos(*tau_s, format!("{at}.tau_s"))?;
                check_finite(*t0_c, format!("{at}.t0_c"))?;
                ctx.input(input, &format!("{at}.input"))?;
            }
            Effect::Hysteresis {
                coefficient,
                threshold_c_per_min,
                window_s,
                input,
            } => {
                check_finite(*coefficient, format!("{at}.coefficient"))?;
                check_pos(*threshold_c_per_min, format!("{at}.threshold_c_per_min"))?;
                check_pos(*window_s, format!("{at}.window_s"))?;
                ctx.input(input, &format!("{at}.input"))?;
            }
            Effect::Warmup { coefficient, tau_s } => {
                check_finite(*coefficient, format!("{at}.coefficient"))?;
                check_pos(*tau_s, format!("{at}.tau_s"))?;
            }
            Effect::SupplyVoltage {
                coefficient,
                nominal_v,
            } => {
                check_finite(*coefficient, format!("{at}.coefficient"))?;
                check_finite(*nominal_v, format!("{at}.nominal_v"))?;
            }
        }
        Ok(())
    }

    /// The streaming state computing this effect from rows. Assumes a validated effect.
    pub(crate) fn state(&self, ctx: &Context<'_>, dt: f64) -> Result<EffectState> {
        let col = |name: &str| -> Result<usize> {
            ctx.therm_names
                .iter()
                .position(|n| n == name)
                .ok_or_else(|| Error::invalid("effects", format!("no column {name}")))
        };
        Ok(match self {
            Effect::Poly {
                coefficients,
                t0_c,
                input,
            } => EffectState::Poly(ctx.input(input, "input")?, *t0_c, coefficients.clone()),
            Effect::Rate {
                coefficient,
                window_s,
                input,
            } => EffectState::Rate(
                ctx.input(input, "input")?,
                *coefficient,
                Rate::new(*window_s),
            ),
            Effect::Gradient {
                anode_shell,
                cathode_shell,
            } => EffectState::Gradient(
                col("t_anode_c")?,
                col("t_cathode_c")?,
                col("t_shell_c")?,
                *anode_shell,
                *cathode_shell,
            ),
            Effect::Shupe {
                coefficient,
                window_s,
                input,
            } => EffectState::Shupe(
                ctx.input(input, "input")?,
                *coefficient,
                Rate::new(*window_s),
            ),
            Effect::LaggedElement {
                coefficient,
                tau_s,
                t0_c,
                input,
            } => EffectState::Lagged(
                ctx.input(input, "input")?,
                *coefficient,
                *t0_c,
                Lag::new(*tau_s),
            ),
            Effect::Hysteresis {
                coefficient,
                threshold_c_per_min,
                window_s,
                input,
            } => EffectState::Hyst(
                ctx.input(input, "input")?,
                *coefficient,
                Rate::new(*window_s),
                Hyst::new(*threshold_c_per_min),
            ),
            Effect::Warmup { coefficient, tau_s } => {
                EffectState::Warmup(*coefficient, warmup_d(dt, *tau_s), Lag::new(*tau_s))
            }
            Effect::SupplyVoltage {
                coefficient,
                nominal_v,
            } => EffectState::Supply(*coefficient, *nominal_v),
        })
    }

    /// The truth entry of this effect: exact expressions over the file's columns (step `dt`).
    pub(crate) fn truth(&self, ctx: &Context<'_>, dt: f64) -> EffectTruth {
        let u = ctx.unit;
        let mk = |coefs: Vec<f64>,
                  units: Vec<String>,
                  exprs: Vec<String>,
                  offset: f64,
                  features: Vec<String>,
                  description: String| EffectTruth {
            name: self.kind().name().to_string(),
            coefficient: coefs.first().copied().unwrap_or(0.0),
            unit: units.first().cloned().unwrap_or_default(),
            expressions: exprs,
            coefficients: coefs,
            coefficient_units: units,
            offset,
            features,
            description,
            contribution_std: 0.0,
            contribution_p2p: 0.0,
        };
        match self {
            Effect::Poly {
                coefficients,
                t0_c,
                input,
            } => {
                let x = ctx.input_expr(input);
                let base = shifted(&x, *t0_c);
                let exprs = (1..=coefficients.len())
                    .map(|k| match k {
                        1 => base.clone(),
                        2 => format!("sq({base})"),
                        _ => {
                            let mut e = format!("sq({base})");
                            for _ in 2..k {
                                e = format!("({base}) * {e}");
                            }
                            e
                        }
                    })
                    .collect();
                let units = (1..=coefficients.len())
                    .map(|k| {
                        if k == 1 {
                            format!("{u} per degC")
                        } else {
                            format!("{u} per degC^{k}")
                        }
                    })
                    .collect();
                mk(
                    coefficients.clone(),
                    units,
                    exprs,
                    0.0,
                    vec![x.clone()],
                    format!(
                        "polynomial in temperature {x} about {t0_c} degC (degree {})",
                        coefficients.len()
                    ),
                )
            }
            Effect::Rate {
                coefficient,
                window_s,
                input,
            } => {
                let x = ctx.input_expr(input);
                let e = rate_expr(&x, *window_s);
                mk(
                    vec![*coefficient],
                    vec![format!("{u} per (degC/min)")],
                    vec![e.clone()],
                    0.0,
                    vec![e],
                    format!("rate of temperature d{x}/dt (degC/min)"),
                )
            }
            Effect::Gradient {
                anode_shell,
                cathode_shell,
            } => {
                let a = "t_anode_c - t_shell_c".to_string();
                let c = "t_cathode_c - t_shell_c".to_string();
                mk(
                    vec![*anode_shell, *cathode_shell],
                    vec![format!("{u} per degC"), format!("{u} per degC")],
                    vec![a.clone(), c.clone()],
                    0.0,
                    vec![a, c],
                    "thermal gradients anode-shell and cathode-shell".into(),
                )
            }
            Effect::Shupe {
                coefficient,
                window_s,
                input,
            } => {
                let x = ctx.input_expr(input);
                let e = format!("{x} * {}", rate_expr(&x, *window_s));
                mk(
                    vec![*coefficient],
                    vec![format!("{u} per (degC * degC/min)")],
                    vec![e.clone()],
                    0.0,
                    vec![e],
                    format!("Shupe-type product {x} * d{x}/dt"),
                )
            }
            Effect::LaggedElement {
                coefficient,
                tau_s,
                t0_c,
                input,
            } => {
                let x = ctx.input_expr(input);
                let e = format!("lag({x}, {})", num(*tau_s));
                mk(
                    vec![*coefficient],
                    vec![format!("{u} per degC")],
                    vec![e.clone()],
                    -coefficient * t0_c,
                    vec![e],
                    format!(
                        "sensing element lagging its thermometer {x}, tau = {} s",
                        num(*tau_s)
                    ),
                )
            }
            Effect::Hysteresis {
                coefficient,
                threshold_c_per_min,
                window_s,
                input,
            } => {
                let x = ctx.input_expr(input);
                let e = format!(
                    "hyst({}, {})",
                    rate_expr(&x, *window_s),
                    num(*threshold_c_per_min)
                );
                mk(
                    vec![*coefficient],
                    vec![u.to_string()],
                    vec![e.clone()],
                    0.0,
                    vec![e],
                    format!(
                        "heating/cooling hysteresis: +c after d{x}/dt rose above {th} degC/min, -c after it fell below -{th}",
                        th = num(*threshold_c_per_min)
                    ),
                )
            }
            Effect::Warmup { coefficient, tau_s } => {
                let d = warmup_d(dt, *tau_s);
                let e = format!("1 - (time_s - lag(time_s, {})) / {}", num(*tau_s), num(d));
                mk(
                    vec![*coefficient],
                    vec![u.to_string()],
                    vec![e.clone()],
                    0.0,
                    vec![e],
                    format!(
                        "warm-up transient c * exp(-(t - t_first)/{} s), written with the time column (exact at this file's step of {} s)",
                        num(*tau_s),
                        num(dt)
                    ),
                )
            }
            Effect::SupplyVoltage {
                coefficient,
                nominal_v,
            } => mk(
                vec![*coefficient],
                vec![format!("{u} per V")],
                vec!["supply_v".into()],
                -coefficient * nominal_v,
                vec!["supply_v".into()],
                format!("supply-voltage sensitivity about {} V", num(*nominal_v)),
            ),
        }
    }
}
