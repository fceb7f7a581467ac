//! The trainer's error type: one enum, so the CLI prints a single clear line per failure.
//!
//! Why typed variants rather than strings: a caller (the CLI, the diagnosis, a test) can tell an
//! option out of range from a bad expression or a corrupt blob without parsing text, and the
//! core's own errors (`ParseError`, `ProgramError`, `StepError`, `BlobError`) stay reachable as the
//! [`std::error::Error::source`] of the host's error, wrapped in [`Core`] (the core is `no_std` and
//! its errors are plain `Display` types).

use crate::dataset::DataError;
use tcomp_core::{BlobError, ParseError, ProgramError, StepError};

/// A core error as a [`std::error::Error`]: the typed value is `.0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Core<E>(pub E);

impl<E: std::fmt::Display> std::fmt::Display for Core<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl<E: std::fmt::Debug + std::fmt::Display> std::error::Error for Core<E> {}

/// Why training or evaluation failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TrainError {
    /// A problem with the input data (file, line and column are in the message).
    #[error(transparent)]
    Data(#[from] DataError),
    /// A feature or signal expression does not parse.
    #[error("in `{expr}`: {source}\n    {expr}\n    {caret}^")]
    Expr {
        /// The expression.
        expr: String,
        /// Spaces up to the error's column, for the caret line.
        caret: String,
        /// The core's parse error (its column is within `expr`).
        #[source]
        source: Core<ParseError>,
    },
    /// A signal line without `=`.
    #[error("in `{line}`: a signal must be written NAME=EXPR")]
    SignalSyntax {
        /// The line as given.
        line: String,
    },
    /// No feature was given.
    #[error("no features: give at least one --feature EXPR")]
    NoFeatures,
    /// A unit given (`--unit`, a board description's `unit`) does not parse.
    #[error("{option}: {source}")]
    Unit {
        /// Where the unit was given (the option or key).
        option: String,
        /// What is wrong.
        #[source]
        source: crate::units::UnitError,
    },
    /// A model's unit and a channel's are one quantity at another scale: flying one as the other
    /// would be off by the factor.
    #[error(
        "{file}: the model is in {model}, the channel in {board}: one {model} is {factor} {board}, \
         so the model would be off by that factor; fit it with the target in {board} (scale the \
         target column by {factor}) and --unit {board}"
    )]
    UnitScale {
        /// The blob.
        file: String,
        /// The model's unit.
        model: String,
        /// The channel's unit.
        board: String,
        /// One model unit in channel units.
        factor: String,
    },
    /// The expressions parse but do not make a program (too many nodes, an unknown name, …).
    #[error("feature program: {source}")]
    Program {
        /// The core's error.
        #[source]
        source: Core<ProgramError>,
    },
    /// The feature program failed on a sample (e.g. a division by zero).
    #[error("{at}: {message}")]
    Step {
        /// file:line.
        at: String,
        /// The step error in the user's terms (features and inputs named).
        message: String,
        /// The core's error.
        #[source]
        source: Core<StepError>,
    },
    /// A feature does not vary over the training data, so nothing can be learnt from it.
    #[error("feature `{expr}` is constant ({value}) over the training data: remove it")]
    ConstantFeature {
        /// The feature expression.
        expr: String,
        /// Its value.
        value: f64,
    },
    /// Two features carry the same information.
    #[error("features `{a}` and `{b}` are collinear (|correlation| = {corr:.6}): remove one")]
    Collinear {
        /// First feature.
        a: String,
        /// Second feature.
        b: String,
        /// Their correlation.
        corr: f64,
    },
    /// A spec file does not parse (the TOML error holds the line and column).
    #[error("{file}: {source}")]
    Spec {
        /// File name.
        file: String,
        /// The TOML error.
        #[source]
        source: Box<toml::de::Error>,
    },
    /// A spec file sets a key no option has.
    #[error("{file}: line {line}: unknown field `{key}`, expected one of: {known}")]
    UnknownSpecKey {
        /// File name.
        file: String,
        /// The 1-based line (0 when not found).
        line: usize,
        /// The key.
        key: String,
        /// The known keys.
        known: String,
    },
    /// A blob was rejected by the core (on encoding, decoding or loading into the firmware's types).
    #[error("{context}: {source}")]
    Blob {
        /// The file and what was being done, e.g. `m.tcm: corrupt model blob`.
        context: String,
        /// The core's error.
        #[source]
        source: Core<BlobError>,
    },
    /// A model that does not fit the reference firmware's types.
    #[error("{file}: the model does not fit the firmware: {over}")]
    TooLargeForFlight {
        /// File name.
        file: String,
        /// What is too large, and the firmware's capacity.
        over: String,
    },
    /// An I/O error on a named file.
    #[error("{file}: {source}")]
    Io {
        /// File name.
        file: String,
        /// The error.
        source: std::io::Error,
    },
    /// A numeric option outside its valid range (see [`crate::options`]).
    #[error("{option}: must be {range} ({why})")]
    OutOfRange {
        /// The flag, the value and the spec key, e.g. ``--average -1 (spec key `average`)``.
        option: String,
        /// The valid range in words (and the method it applies to).
        range: String,
        /// Why these bounds.
        why: &'static str,
    },
    /// A bin that holds no sample or leaves fewer than two bins of this record.
    #[error(
        "{option}: a bin must be at least the sampling step ({step} s) and at most half the \
         record ({max} s of {span} s), so that it holds samples and at least two bins remain"
    )]
    BinVsData {
        /// The flag and value.
        option: String,
        /// The median sampling step (s).
        step: String,
        /// Half the record (s).
        max: String,
        /// The record's span (s).
        span: String,
    },
    /// An averaging bin shorter than the sampling step.
    #[error(
        "--average {average} (spec key `average`): shorter than the sampling step of {file} \
         ({step} s), so a bin would hold no sample; use 0 for no averaging, or at least {step} s"
    )]
    AverageBelowStep {
        /// The data file.
        file: String,
        /// The averaging bin asked for (s).
        average: String,
        /// The median sampling step (s).
        step: String,
    },
    /// `--from` not before `--until`.
    #[error(
        "--from {from} / --until {until} (spec keys `from`, `until`): an empty window; --from \
         must be before --until"
    )]
    EmptyWindow {
        /// The start (s).
        from: String,
        /// The end (s).
        until: String,
    },
    /// `--power-on` after the first row read: the time on of that row would be negative.
    #[error(
        "--power-on {power_on} (spec key `power-on`) is after the first row read ({first} s): \
         power-on must be at or before the start of the data"
    )]
    PowerOnAfterStart {
        /// The power-on time given (s).
        power_on: String,
        /// The first row's time (s).
        first: String,
    },
    /// A name that is not one of the known ones (method, sensor, center selection).
    #[error("unknown {what} `{name}` (known: {known})")]
    Unknown {
        /// What kind of name.
        what: &'static str,
        /// The name given.
        name: String,
        /// The known names.
        known: String,
    },
    /// A required option was not given.
    #[error("no {what}: give {hint}")]
    Missing {
        /// What is missing.
        what: &'static str,
        /// The flag(s) that give it.
        hint: &'static str,
    },
    /// A method cannot be used with what it was given.
    #[error("{method} needs {what}")]
    MethodNeeds {
        /// The method.
        method: &'static str,
        /// What it needs.
        what: &'static str,
    },
    /// The fit would need more memory than allowed.
    #[error("{0}")]
    OverMemoryBudget(Box<OverBudget>),
    /// The method's numerical search found no model (every candidate failed).
    #[error("{method}: {what}")]
    FitFailed {
        /// The method.
        method: &'static str,
        /// What failed.
        what: &'static str,
    },
    /// The fitted model is larger than the host model's capacities ([`tcomp_core::HostModel`]).
    #[error(
        "model size out of capacity: {features} features (max {max_features}), {centers} centers (max {max_centers})"
    )]
    OverCapacity {
        /// Features of the fitted model.
        features: usize,
        /// Most features the host model holds.
        max_features: usize,
        /// Centers of the fitted model.
        centers: usize,
        /// Most centers the host model holds.
        max_centers: usize,
    },
    /// The least-squares solve failed (nalgebra's SVD reports why).
    #[error("least squares failed: {0}")]
    LeastSquares(&'static str),
}

/// A fit refused for its memory: what it would have needed and what to do instead.
#[derive(Debug, thiserror::Error)]
#[error(
    "{file}: a {method} fit of {rows} rows {averaged} ({samples} samples) would need about \
     {need} of memory, more than the {budget} allowed{suggestion}"
)]
pub struct OverBudget {
    /// The data file.
    pub file: String,
    /// The method.
    pub method: &'static str,
    /// Rows of the selection.
    pub rows: usize,
    /// How the rows were averaged.
    pub averaged: String,
    /// Training samples after averaging.
    pub samples: usize,
    /// Estimated need (human-readable).
    pub need: String,
    /// The budget (human-readable).
    pub budget: String,
    /// What to do instead.
    pub suggestion: String,
}
