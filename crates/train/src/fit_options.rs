//! The resolved fit options: what [`crate::train::fit`] is given, with every number range-checked.
//!
//! Why apart from the trainer: the options are resolved once (from the spec file and the flags, or
//! built in code by a library caller) and checked against the one table of bounds
//! ([`crate::options`]); the trainer then only reads them.

use crate::error::TrainError;
use crate::features::FeatureSpec;
use crate::layer::Layer;
use crate::method::{FitMethod, Shared};
use crate::options;
use crate::registry::{Method, MethodSettings};
use crate::spec::{ChannelOptions, MethodOptions, RunOptions, Spec};
use tcomp_core::SensorKind;

/// Parses a sensor kind name (rlg, qma, ifog, mems-gyro, mems-accel, other).
pub fn parse_sensor(s: &str) -> Result<SensorKind, TrainError> {
    SensorKind::from_name(s).ok_or_else(|| TrainError::Unknown {
        what: "sensor",
        name: s.into(),
        known: SensorKind::ALL
            .iter()
            .map(|k| k.name())
            .collect::<Vec<_>>()
            .join(", "),
    })
}

/// Resolved fit options.
#[derive(Clone, Debug)]
pub struct FitOptions {
    /// Time column.
    pub time: String,
    /// Target column.
    pub target: String,
    /// Reference column.
    pub reference: Option<String>,
    /// Constant reference; with neither, the training mean of the target is used (and stored).
    pub reference_value: Option<f64>,
    /// Signals and features.
    pub spec: FeatureSpec,
    /// Method.
    pub method: Method,
    /// Averaging bin (s), 0 for none; `None`: [`crate::rows::DEFAULT_AVERAGE_S`], shortened on
    /// short runs to leave [`crate::rows::MIN_DEFAULT_BINS`] bins.
    pub average_s: Option<f64>,
    /// Each method's own options (unset: the method's default), e.g. `settings.bayes.cubic`;
    /// [`Method::fitter`] hands the selected method its own.
    pub settings: MethodSettings,
    /// Fixed number of centers.
    pub centers: Option<usize>,
    /// Per feature, how it may enter the Gaussians (from the `linear:` / `additive:` marks of the
    /// features, see [`crate::pin`]); empty: every feature free.
    pub pins: Vec<crate::pin::Pin>,
    /// Gap threshold (s); default 10× the median step.
    pub gap_s: Option<f64>,
    /// Time of power-on on the time column (s); default the first row read.
    pub power_on_s: Option<f64>,
    /// k-means seed.
    pub seed: u64,
    /// Sensor kind.
    pub sensor: SensorKind,
    /// Axis label.
    pub axis: String,
    /// Target unit.
    pub unit: String,
    /// Train on time ≥ this.
    pub from: Option<f64>,
    /// Train on time < this.
    pub until: Option<f64>,
    /// The most memory the fit may take (bytes, estimated before allocating; see [`crate::budget`]).
    pub memory_budget: u64,
    /// Rows of a repeated or backward time (`--repeated-time`, [`crate::dataset::clean`]).
    pub repeated_time: crate::dataset::RepeatedTime,
    /// Empty or NaN cells in used columns (`--missing`).
    pub missing: crate::dataset::Missing,
}

impl FitOptions {
    /// Options with defaults for the given target and features.
    pub fn new(target: &str, features: &[&str]) -> Self {
        Self {
            time: "time_s".into(),
            target: target.into(),
            reference: None,
            reference_value: None,
            spec: FeatureSpec {
                signals: Vec::new(),
                features: features.iter().map(|s| s.to_string()).collect(),
            },
            method: Method::Bayes,
            average_s: None,
            settings: MethodSettings::default(),
            centers: None,
            pins: Vec::new(),
            gap_s: None,
            power_on_s: None,
            seed: 1,
            sensor: SensorKind::Other,
            axis: String::new(),
            unit: String::new(),
            from: None,
            until: None,
            memory_budget: crate::budget::DEFAULT_BUDGET_BYTES,
            repeated_time: crate::dataset::RepeatedTime::default(),
            missing: crate::dataset::Missing::default(),
        }
    }

    /// The selected method, with its own options.
    pub fn fitter(&self) -> &dyn FitMethod {
        self.method.fitter(&self.settings)
    }

    /// The options every method may read besides its own.
    pub fn shared(&self) -> Shared<'_> {
        Shared {
            time: &self.time,
            spec: &self.spec,
            centers: self.centers,
            seed: self.seed,
            pins: &self.pins,
            power_on_s: self.power_on_s,
        }
    }

    /// How to load the training file: the columns the fit uses (target first, so that in an
    /// autopilot log the target's message gives the rows; then the reference and the program's
    /// inputs) and the policies for messy rows.
    pub fn load_options(&self) -> crate::dataset::LoadOptions {
        let mut columns = vec![self.target.clone()];
        columns.extend(self.reference.clone());
        if let Ok(p) = self.spec.program() {
            columns.extend(p.inputs.iter().map(|s| s.to_string()));
        }
        crate::dataset::LoadOptions {
            time: Some(self.time.clone()),
            columns,
            repeated_time: self.repeated_time,
            missing: self.missing,
        }
    }

    /// Options from a spec (file and flags merged). Every number is range-checked here, with a
    /// message naming both the flag and the spec key (see [`crate::options`] for the bounds).
    pub fn from_spec(spec: &Spec) -> Result<Self, TrainError> {
        let target = spec.channel.target.clone().ok_or(TrainError::Missing {
            what: "target",
            hint: "--target COL",
        })?;
        let mut o = Self::new(&target, &[]);
        o.spec = FeatureSpec {
            signals: spec.features.signal.clone(),
            features: spec.features.feature.clone(),
        };
        o.set_run(&spec.run)?;
        o.set_method(&spec.method)?;
        o.set_channel(&spec.channel)?;
        Ok(o)
    }

    /// The reference, the window and the gap threshold.
    fn set_run(&mut self, run: &RunOptions) -> Result<(), TrainError> {
        self.reference.clone_from(&run.reference);
        if let Some(r) = run.repeated_time {
            self.repeated_time = r;
        }
        if let Some(m) = run.missing {
            self.missing = m;
        }
        if let Some(v) = run.reference_value {
            self.reference_value = Some(options::REFERENCE_VALUE.check(v)?);
        }
        if let Some(g) = run.gap {
            self.gap_s = Some(options::GAP.check(g)?);
        }
        if let Some(p) = run.power_on {
            self.power_on_s = Some(options::POWER_ON.check(p)?);
        }
        if let Some(f) = run.from {
            self.from = Some(options::FROM.check(f)?);
        }
        if let Some(u) = run.until {
            self.until = Some(options::UNTIL.check(u)?);
        }
        if let (Some(f), Some(u)) = (self.from, self.until)
            && f >= u
        {
            return Err(TrainError::EmptyWindow {
                from: crate::num::exact(f),
                until: crate::num::exact(u),
            });
        }
        Ok(())
    }

    /// The method and its settings (`--centers` is checked against the method's own bound).
    fn set_method(&mut self, m: &MethodOptions) -> Result<(), TrainError> {
        if let Some(name) = &m.method {
            self.method = name.parse()?;
        }
        if let Some(a) = m.average {
            self.average_s = Some(options::AVERAGE.check(a)?);
        }
        if let Some(c) = m.centers {
            self.fitter()
                .centers_bound()
                .check_count(c, &format!(" with --method {}", self.method))?;
        }
        self.centers = m.centers;
        if let Some(s) = m.seed {
            self.seed = s;
        }
        self.settings.overlay(m.settings.clone());
        self.settings.check()
    }

    /// The columns and the blob's description of the channel (the target is read first).
    fn set_channel(&mut self, c: &ChannelOptions) -> Result<(), TrainError> {
        if let Some(t) = &c.time {
            self.time.clone_from(t);
        }
        if let Some(s) = &c.sensor {
            self.sensor = parse_sensor(s)?;
        }
        if let Some(a) = &c.axis {
            self.axis.clone_from(a);
        }
        if let Some(u) = &c.unit {
            // Parsed, so that a typo is said here rather than at `tcomp image`.
            if !u.is_empty() {
                crate::units::parse(u).map_err(|source| TrainError::Unit {
                    option: "--unit (spec key `unit`)".into(),
                    source,
                })?;
            }
            self.unit.clone_from(u);
        }
        Ok(())
    }
}
