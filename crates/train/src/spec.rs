//! The fit options, one struct per concern, each both the command-line flags (`clap::Args`, with
//! the crate's `cli` feature) and the keys of the TOML fit spec (`serde::Deserialize`) — so adding
//! an effect is one more line of the file, and adding an option is one field here.
//!
//! The clap derive and its `arg` attributes are behind the `cli` feature (off by default): the
//! trainer is a library that programs without a command line link (the discovery, a user's own
//! tool), and they should not carry clap for it; `tcomp` enables it and flattens these structs
//! into its commands. Without it the structs, their keys and the checks are the same.
//!
//! ```toml
//! time = "time_s"
//! target = "gyro_dph"
//! reference = "ref_dph"
//! signal = ["T = mean(t_anode_c, t_cathode_c, t_shell_c)"]
//! feature = ["T", "rate(T)", "t_anode_c - t_shell_c"]
//! average = 30
//! method = "bayes"
//! ```
//! Unknown keys are errors (a typo must not be silently ignored). Command-line flags override
//! single values and add to the `feature`/`signal` lists ([`crate::layer`]); numbers are checked
//! against the one table of bounds ([`crate::options`]) by clap's value parsers (with `cli`) and
//! again, for spec files and library callers, by [`crate::FitOptions::from_spec`].
//!
//! The spec is read flat (every key at the top level); each concern's struct takes its keys from
//! the same text, so a type error is still reported at its line and column.

use crate::error::TrainError;
use crate::layer::Layer;
#[cfg(feature = "cli")]
use crate::options::{
    AVERAGE, CENTERS_BAYES, FROM, GAP, POWER_ON, REFERENCE_VALUE, UNTIL, parse_seed,
};
use crate::registry::MethodSettings;
use serde::Deserialize;
use std::path::Path;

impl RunOptions {
    /// How a command reads its run: `time` the time column, `columns` those it uses (target
    /// first), with these policies.
    pub fn load_options(&self, time: &str, columns: Vec<String>) -> crate::dataset::LoadOptions {
        crate::dataset::LoadOptions {
            time: Some(time.to_string()),
            columns,
            repeated_time: self.repeated_time.unwrap_or_default(),
            missing: self.missing.unwrap_or_default(),
        }
    }
}

crate::layer! {
    /// Which rows of a run are read and against what reference: shared by every command that
    /// reads a run (`fit`, `eval`, `diagnose`, `compare`, `report`), and keys of the fit spec.
    #[derive(Clone, Debug, Default, PartialEq, Deserialize)]
    #[cfg_attr(feature = "cli", derive(clap::Args))]
    #[serde(rename_all = "kebab-case")]
    pub struct RunOptions {
        /// Reference column: error = target − reference (when evaluating: instead of the model's).
        #[cfg_attr(feature = "cli", arg(long))]
        pub reference: Option<String>,
        /// Constant reference in the target's unit (when fitting with no reference at all, the
        /// training mean of the target is used).
        #[cfg_attr(
            feature = "cli",
            arg(long, allow_negative_numbers = true, value_parser = REFERENCE_VALUE.parser())
        )]
        pub reference_value: Option<f64>,
        /// Use only rows with time ≥ this (s).
        #[cfg_attr(
            feature = "cli",
            arg(long, allow_negative_numbers = true, value_parser = FROM.parser())
        )]
        pub from: Option<f64>,
        /// Use only rows with time < this (s).
        #[cfg_attr(
            feature = "cli",
            arg(long, allow_negative_numbers = true, value_parser = UNTIL.parser())
        )]
        pub until: Option<f64>,
        /// Steps longer than this (s) are gaps: rate and lag are carried across as for an input
        /// moving linearly, or restarted (with a warning) when the gap is longer than 5× the
        /// program's longest time constant [default: 10× the median step].
        #[cfg_attr(
            feature = "cli",
            arg(long, allow_negative_numbers = true, value_parser = GAP.parser())
        )]
        pub gap: Option<f64>,
        /// Time (s, on the time column) the instrument was switched on: `warmup(τ)` counts from
        /// here [default: the first row read].
        #[cfg_attr(
            feature = "cli",
            arg(long, allow_negative_numbers = true, value_parser = POWER_ON.parser())
        )]
        pub power_on: Option<f64>,
        /// Rows whose time repeats the previous row's: `average` them into one [default],
        /// `drop` all but the first, or `refuse` the file. With average or drop, time stepping
        /// back by more than 10 median steps is a clock restart: the rows from there continue
        /// after a gap.
        #[cfg_attr(feature = "cli", arg(long, value_enum))]
        pub repeated_time: Option<crate::dataset::RepeatedTime>,
        /// Empty or NaN cells in a column the model uses: `dropout` drops the row, a logger
        /// dropout the feature state is carried across [default]; `refuse` the file.
        #[cfg_attr(feature = "cli", arg(long, value_enum))]
        pub missing: Option<crate::dataset::Missing>,
    }
}

crate::layer! {
    /// The channel a model compensates: its columns and what the blob says about it.
    #[derive(Clone, Debug, Default, PartialEq, Deserialize)]
    #[cfg_attr(feature = "cli", derive(clap::Args))]
    #[serde(rename_all = "kebab-case")]
    pub struct ChannelOptions {
        /// Time column, seconds [default: time_s].
        #[cfg_attr(feature = "cli", arg(long))]
        pub time: Option<String>,
        /// Sensor output column.
        #[cfg_attr(feature = "cli", arg(long))]
        pub target: Option<String>,
        /// Sensor kind: rlg, qma, ifog, mems-gyro, mems-accel, other.
        #[cfg_attr(feature = "cli", arg(long))]
        pub sensor: Option<String>,
        /// Axis label.
        #[cfg_attr(feature = "cli", arg(long))]
        pub axis: Option<String>,
        /// Unit of the target.
        #[cfg_attr(feature = "cli", arg(long))]
        pub unit: Option<String>,
    }
}

crate::layer! {
    /// The feature program: named signals and the feature expressions (lists that add up).
    #[derive(Clone, Debug, Default, PartialEq, Deserialize)]
    #[cfg_attr(feature = "cli", derive(clap::Args))]
    #[serde(rename_all = "kebab-case")]
    pub struct FeatureOptions {
        /// Feature expression, e.g. `rate(T)` (repeatable).
        #[cfg_attr(feature = "cli", arg(long))]
        #[serde(default)]
        pub feature: Vec<String>,
        /// Named signal `NAME=EXPR` (repeatable).
        #[cfg_attr(feature = "cli", arg(long))]
        #[serde(default)]
        pub signal: Vec<String>,
    }
}

crate::layer! {
    /// How the model is fitted: the method, the settings every method shares, and each method's
    /// own ([`MethodSettings`], from the registry: a method's options live in its module).
    #[derive(Clone, Debug, Default, PartialEq, Deserialize)]
    #[cfg_attr(feature = "cli", derive(clap::Args))]
    #[serde(rename_all = "kebab-case")]
    pub struct MethodOptions {
        /// The method (see the list below).
        #[cfg_attr(feature = "cli", arg(long, help = crate::registry::Method::help()))]
        pub method: Option<String>,
        /// Average into non-overlapping bins of this many seconds before fitting; 0 = off
        /// [default: 120, shortened on short runs to leave 60 bins].
        #[cfg_attr(
            feature = "cli",
            arg(long, allow_negative_numbers = true, value_parser = AVERAGE.parser())
        )]
        pub average: Option<f64>,
        /// Number of centers (bayes: fixed instead of chosen by evidence; mse/gradient: default 16).
        #[cfg_attr(
            feature = "cli",
            arg(long, allow_negative_numbers = true, value_parser = CENTERS_BAYES.count_parser())
        )]
        pub centers: Option<usize>,
        /// Each method's own options (its struct's fields are keys and flags here).
        #[serde(flatten)]
        #[cfg_attr(feature = "cli", command(flatten))]
        pub settings: MethodSettings,
        /// k-means seed.
        #[cfg_attr(
            feature = "cli",
            arg(long, allow_negative_numbers = true, value_parser = parse_seed)
        )]
        pub seed: Option<u64>,
    }
}

/// A fit spec: every concern's options, every field optional.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Spec {
    /// Rows and reference.
    pub run: RunOptions,
    /// Columns and the blob's description of the channel.
    pub channel: ChannelOptions,
    /// Signals and features.
    pub features: FeatureOptions,
    /// Method and settings.
    pub method: MethodOptions,
}

impl Layer for Spec {
    fn overlay(&mut self, other: Self) {
        self.run.overlay(other.run);
        self.channel.overlay(other.channel);
        self.features.overlay(other.features);
        self.method.overlay(other.method);
    }

    fn keys(out: &mut Vec<String>) {
        RunOptions::keys(out);
        ChannelOptions::keys(out);
        FeatureOptions::keys(out);
        MethodOptions::keys(out);
    }
}

impl Spec {
    /// Reads a TOML spec file.
    pub fn load(path: &Path) -> Result<Self, TrainError> {
        let text = std::fs::read_to_string(path).map_err(|source| TrainError::Io {
            file: path.display().to_string(),
            source,
        })?;
        Self::parse(&path.display().to_string(), &text)
    }

    /// Parses the text of a TOML spec; `file` names it in errors.
    pub fn parse(file: &str, text: &str) -> Result<Self, TrainError> {
        let spec_error = |e| TrainError::Spec {
            file: file.to_string(),
            source: Box::new(e),
        };
        let table: toml::Table = toml::from_str(text).map_err(spec_error)?;
        let mut known = Vec::new();
        Self::keys(&mut known);
        if let Some(key) = table.keys().find(|k| !known.contains(k)) {
            return Err(TrainError::UnknownSpecKey {
                file: file.to_string(),
                line: key_line(text, key),
                key: key.clone(),
                known: known.join(", "),
            });
        }
        Ok(Self {
            run: toml::from_str(text).map_err(spec_error)?,
            channel: toml::from_str(text).map_err(spec_error)?,
            features: toml::from_str(text).map_err(spec_error)?,
            method: toml::from_str(text).map_err(spec_error)?,
        })
    }

    /// `other` laid over `self`: its single values win, its lists are appended.
    #[must_use]
    pub fn merged(mut self, other: Spec) -> Spec {
        self.overlay(other);
        self
    }
}

/// The 1-based line where `key` is set (0 when it cannot be found, e.g. a quoted key).
fn key_line(text: &str, key: &str) -> usize {
    text.lines()
        .position(|l| {
            l.trim_start()
                .strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with('='))
        })
        .map_or(0, |i| i + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_concern_reads_its_keys_from_one_flat_file() {
        let s = Spec::parse(
            "s.toml",
            "target = \"gyro_dph\"\nreference-value = 2\nfeature = [\"T\"]\naverage = 30\n\
             linear = false\nseed = 7\nuntil = 100.5\n",
        );
        let s = s.unwrap_or_default();
        assert_eq!(s.channel.target.as_deref(), Some("gyro_dph"));
        assert_eq!(s.run.reference_value, Some(2.0));
        assert_eq!(s.run.until, Some(100.5));
        assert_eq!(s.features.feature, ["T"]);
        assert_eq!(s.method.average, Some(30.0));
        assert_eq!(s.method.settings.bayes.linear, Some(false));
        assert_eq!(s.method.seed, Some(7));
    }

    #[test]
    fn an_unknown_key_is_named_with_its_line_and_a_type_error_with_its_column() {
        let e = Spec::parse("s.toml", "target = \"x\"\n\nfeatuer = [\"T\"]\n")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("s.toml") && e.contains("line 3") && e.contains("unknown field `featuer`"),
            "{e}"
        );
        let e = Spec::parse("s.toml", "average = \"long\"\n")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("s.toml") && e.contains("line 1"), "{e}");
    }

    #[test]
    fn flags_override_single_values_and_add_to_lists() {
        let mut file = Spec::default();
        file.method.average = Some(30.0);
        file.features.feature = vec!["T".into()];
        file.run.from = Some(5.0);
        let mut flags = Spec::default();
        flags.method.average = Some(60.0);
        flags.features.feature = vec!["rate(T)".into()];
        let m = file.merged(flags);
        assert_eq!(m.method.average, Some(60.0));
        assert_eq!(m.run.from, Some(5.0));
        assert_eq!(m.features.feature, ["T", "rate(T)"]);
    }
}
