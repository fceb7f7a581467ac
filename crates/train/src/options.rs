//! The valid range of every numeric option, with the reason for each bound next to it.
//!
//! Why one table: an option is checked where it is resolved (the fit spec, the evaluator, the
//! diagnosis), and the message must name it the way the user wrote it — the flag (`--average`) and
//! the spec key (`average`) — with the range and why. NaN, infinities, zero where it means nothing,
//! negative and absurdly large values are refused instead of flowing into NaN figures, overflowing
//! bin numbers or runs of days. Bounds that depend on the data (a bin against the sampling step and
//! the record's length) are checked by [`check_bin`] once the data are known.

use crate::error::TrainError;

/// A number as a user would write it: `1e-300` rather than three hundred zeros.
pub fn num(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e9).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// The valid range of one numeric option.
#[derive(Clone, Copy, Debug)]
pub struct Bound {
    /// The flag, e.g. `--average`.
    pub flag: &'static str,
    /// The spec key, e.g. `average` (empty when the option has no spec key).
    pub key: &'static str,
    /// Smallest valid value.
    pub min: f64,
    /// Whether `min` itself is excluded.
    pub min_exclusive: bool,
    /// Largest valid value.
    pub max: f64,
    /// Unit, for the message (`s`, empty for counts).
    pub unit: &'static str,
    /// Why these bounds.
    pub why: &'static str,
}

impl Bound {
    fn name(&self, v: &dyn std::fmt::Display) -> String {
        if self.key.is_empty() {
            format!("{} {v}", self.flag)
        } else {
            format!("{} {v} (spec key `{}`)", self.flag, self.key)
        }
    }

    fn range(&self) -> String {
        let u = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        if self.min_exclusive {
            format!(
                "greater than {} and at most {}{u}",
                num(self.min),
                num(self.max)
            )
        } else {
            format!("between {} and {}{u}", num(self.min), num(self.max))
        }
    }

    /// `v` when it is a finite number within the bounds, else an error naming the option.
    pub fn check(&self, v: f64) -> Result<f64, TrainError> {
        let low_ok = if self.min_exclusive {
            v > self.min
        } else {
            v >= self.min
        };
        if v.is_finite() && low_ok && v <= self.max {
            return Ok(v);
        }
        Err(TrainError::Invalid(format!(
            "{}: must be {} ({})",
            self.name(&num(v)),
            self.range(),
            self.why
        )))
    }

    /// [`Bound::check`] for a count; `context` follows the range in the message (e.g.
    /// " with --method mse").
    pub fn check_count(&self, v: usize, context: &str) -> Result<usize, TrainError> {
        let f = v as f64;
        if f >= self.min && f <= self.max {
            return Ok(v);
        }
        Err(TrainError::Invalid(format!(
            "{}: must be {}{context} ({})",
            self.name(&v),
            self.range(),
            self.why
        )))
    }
}

/// `--reference-value`: no inertial output comes near 10⁹ in its unit (1 g is 10⁶ µg, the earth
/// rate 15 °/h), and the value is stored as f32 in the blob; a larger one is a typo.
pub const REFERENCE_VALUE: Bound = Bound {
    flag: "--reference-value",
    key: "reference-value",
    min: -1e9,
    min_exclusive: false,
    max: 1e9,
    unit: "",
    why: "a constant true input in the target's unit; 1 g is 1e6 µg",
};

/// `--average`: 0 turns averaging off; a bin longer than 10⁷ s (116 days) is longer than any
/// chamber run. Against the data, a bin must also be at least the sampling step ([`check_bin`]).
pub const AVERAGE: Bound = Bound {
    flag: "--average",
    key: "average",
    min: 0.0,
    min_exclusive: false,
    max: 1e7,
    unit: "s",
    why: "0 is no averaging; 1e7 s is longer than any chamber run",
};

/// `--centers` of `mse` and `gradient`: at least one Gaussian (with none, the model is the
/// constant mean and says nothing), at most what a host blob holds.
pub const CENTERS: Bound = Bound {
    flag: "--centers",
    key: "centers",
    min: 1.0,
    min_exclusive: false,
    max: crate::rbf64::C as f64,
    unit: "",
    why: "a Gaussian network needs a Gaussian; a blob holds at most 64",
};

/// `--centers` of `bayes`: 0 is the linear part alone (a model the evidence may well prefer).
pub const CENTERS_BAYES: Bound = Bound {
    flag: "--centers",
    key: "centers",
    min: 0.0,
    min_exclusive: false,
    max: crate::rbf64::C as f64,
    unit: "",
    why: "0 is the linear part alone; a blob holds at most 64 centers",
};

/// `--gap`: a positive step length; 10⁷ s is longer than any run, so every step would be kept.
pub const GAP: Bound = Bound {
    flag: "--gap",
    key: "gap",
    min: 0.0,
    min_exclusive: true,
    max: 1e7,
    unit: "s",
    why: "steps longer than this are gaps where feature state is reset",
};

/// `--iterations` of `gradient`: each is a full pass over the training rows; with the halving
/// learning rate the fits of the test cases settle within a few thousand, and 10⁶ passes over an
/// unaveraged run would take days.
pub const ITERATIONS: Bound = Bound {
    flag: "--iterations",
    key: "iterations",
    min: 1.0,
    min_exclusive: false,
    max: 1e6,
    unit: "",
    why: "each iteration is a full pass over the training rows",
};

/// `--from`: a time in seconds. 10¹² s (31,700 years) leaves room for Unix time stamps (1.7·10⁹).
pub const FROM: Bound = Bound {
    flag: "--from",
    key: "from",
    min: -1e12,
    min_exclusive: false,
    max: 1e12,
    unit: "s",
    why: "a time of the record's time column",
};

/// `--until`: as [`FROM`].
pub const UNTIL: Bound = Bound {
    flag: "--until",
    key: "until",
    ..FROM
};

/// Checks a bin length against the data: at least the median sampling step (a shorter bin holds no
/// sample at all, and its index overflows on long records) and at most half the record (so that
/// at least two bins remain to compare). `flag` names the option in the message.
pub fn check_bin(flag: &str, bin_s: f64, time: &[f64]) -> Result<f64, TrainError> {
    let step = crate::dataset::median_step(time);
    let span = time.last().copied().unwrap_or(0.0) - time.first().copied().unwrap_or(0.0);
    let max = span / 2.0;
    if bin_s.is_finite() && bin_s >= step && bin_s <= max {
        return Ok(bin_s);
    }
    Err(TrainError::Invalid(format!(
        "{flag} {}: a bin must be at least the sampling step ({} s) and at most half the record \
         ({} s of {} s), so that it holds samples and at least two bins remain",
        num(bin_s),
        num(step),
        num(max),
        num(span)
    )))
}
