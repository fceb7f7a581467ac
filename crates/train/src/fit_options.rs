//! The resolved fit options: what [`crate::train::fit`] is given, with every number range-checked.
//!
//! Why apart from the trainer: the options are resolved once (from the spec file and the flags, or
//! built in code by a library caller) and checked against the one table of bounds
//! ([`crate::options`]); the trainer then only reads them.

use crate::error::TrainError;
use crate::features::FeatureSpec;
use crate::method::Method;
use crate::mse::CenterSelection;
use crate::options;
use crate::spec::Spec;
use tcomp_core::SensorKind;

/// Parses a sensor kind name (rlg, qma, ifog, mems-gyro, mems-accel, other).
pub fn parse_sensor(s: &str) -> Result<SensorKind, TrainError> {
    Ok(match s {
        "rlg" => SensorKind::Rlg,
        "qma" => SensorKind::Qma,
        "ifog" => SensorKind::Ifog,
        "mems-gyro" => SensorKind::MemsGyro,
        "mems-accel" => SensorKind::MemsAccel,
        "other" => SensorKind::Other,
        _ => {
            return Err(TrainError::Unknown {
                what: "sensor",
                name: s.into(),
                known: "rlg, qma, ifog, mems-gyro, mems-accel, other".into(),
            });
        }
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
    /// Averaging bin (s), 0 for none; `None`: [`DEFAULT_AVERAGE_S`], shortened on short runs to
    /// leave [`MIN_DEFAULT_BINS`] bins.
    pub average_s: Option<f64>,
    /// Fixed number of centers.
    pub centers: Option<usize>,
    /// Linear term (bayes).
    pub linear: bool,
    /// Offer `bayes` the cubic in the first feature as a basis (chosen only by evidence).
    pub cubic: bool,
    /// How `mse` places its centers.
    pub select: CenterSelection,
    /// Gap threshold (s); default 10× the median step.
    pub gap_s: Option<f64>,
    /// k-means seed.
    pub seed: u64,
    /// Gradient iterations.
    pub iterations: usize,
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
            centers: None,
            linear: true,
            cubic: true,
            select: CenterSelection::Kmeans,
            gap_s: None,
            seed: 1,
            iterations: 2000,
            sensor: SensorKind::Other,
            axis: String::new(),
            unit: String::new(),
            from: None,
            until: None,
            memory_budget: crate::budget::DEFAULT_BUDGET_BYTES,
        }
    }

    /// Options from a spec (file and flags merged). Every number is range-checked here, with a
    /// message naming both the flag and the spec key (see [`crate::options`] for the bounds).
    pub fn from_spec(spec: &Spec) -> Result<Self, TrainError> {
        let target = spec.target.clone().ok_or(TrainError::Missing {
            what: "target",
            hint: "--target COL",
        })?;
        let mut o = Self::new(&target, &[]);
        o.spec = FeatureSpec {
            signals: spec.signal.clone(),
            features: spec.feature.clone(),
        };
        if let Some(t) = &spec.time {
            o.time.clone_from(t);
        }
        o.reference.clone_from(&spec.reference);
        if let Some(v) = spec.reference_value {
            o.reference_value = Some(options::REFERENCE_VALUE.check(v)?);
        }
        if let Some(m) = &spec.method {
            o.method = m.parse()?;
        }
        if let Some(a) = spec.average {
            o.average_s = Some(options::AVERAGE.check(a)?);
        }
        if let Some(c) = spec.centers {
            o.method
                .fitter()
                .centers_bound()
                .check_count(c, &format!(" with --method {}", o.method))?;
        }
        o.centers = spec.centers;
        if let Some(l) = spec.linear {
            o.linear = l;
        }
        if let Some(c) = spec.cubic {
            o.cubic = c;
        }
        if let Some(s) = &spec.select {
            o.select = s.parse()?;
        }
        if let Some(g) = spec.gap {
            o.gap_s = Some(options::GAP.check(g)?);
        }
        if let Some(s) = spec.seed {
            o.seed = s;
        }
        if let Some(i) = spec.iterations {
            options::ITERATIONS.check_count(i, "")?;
            o.iterations = i;
        }
        if let Some(s) = &spec.sensor {
            o.sensor = parse_sensor(s)?;
        }
        if let Some(a) = &spec.axis {
            o.axis.clone_from(a);
        }
        if let Some(u) = &spec.unit {
            o.unit.clone_from(u);
        }
        if let Some(f) = spec.from {
            o.from = Some(options::FROM.check(f)?);
        }
        if let Some(u) = spec.until {
            o.until = Some(options::UNTIL.check(u)?);
        }
        if let (Some(f), Some(u)) = (o.from, o.until)
            && f >= u
        {
            return Err(TrainError::EmptyWindow {
                from: options::num(f),
                until: options::num(u),
            });
        }
        Ok(o)
    }
}
