//! The valid range of every numeric option, with the reason for each bound next to it.
//!
//! Why one table: an option is checked where it is resolved (the fit spec, the evaluator, the
//! diagnosis), and the message must name it the way the user wrote it — the flag (`--average`) and
//! the spec key (`average`) — with the range and why. NaN, infinities, zero where it means nothing,
//! negative and absurdly large values are refused instead of flowing into NaN figures, overflowing
//! bin numbers or runs of days. The command line parses its flags through the same table
//! ([`Bound::parse`]; its clap value parser, `Bound::parser`, is behind the crate's `cli` feature),
//! so a flag and its spec key cannot disagree. Bounds that depend on the data (a bin against the
//! sampling step and the record's length) are checked by [`check_bin`] once the data are known.

use crate::error::TrainError;
use crate::num::exact;

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

    /// The unit as a word for the message (`s` reads `seconds`).
    fn unit_word(&self) -> &'static str {
        match self.unit {
            "" => "",
            "s" => " seconds",
            u => u,
        }
    }

    /// The range in words, e.g. `between 0.001 and 1e7 seconds`.
    pub fn range(&self) -> String {
        let u = self.unit_word();
        if self.min_exclusive {
            format!(
                "greater than {} and at most {}{u}",
                bound_num(self.min),
                bound_num(self.max)
            )
        } else {
            format!(
                "between {} and {}{u}",
                bound_num(self.min),
                bound_num(self.max)
            )
        }
    }

    /// Whether `v` is a finite number within the bounds.
    pub fn contains(&self, v: f64) -> bool {
        let low_ok = if self.min_exclusive {
            v > self.min
        } else {
            v >= self.min
        };
        v.is_finite() && low_ok && v <= self.max
    }

    /// The error naming this option, the value and the range.
    fn refuse(&self, value: String, range: String, context: &str) -> TrainError {
        TrainError::OutOfRange {
            option: self.name(&value),
            range: format!("{range}{context}"),
            why: self.why,
        }
    }

    /// `v` when it is a finite number within the bounds, else an error naming the option.
    pub fn check(&self, v: f64) -> Result<f64, TrainError> {
        if self.contains(v) {
            return Ok(v);
        }
        Err(self.refuse(exact(v), self.range(), ""))
    }

    /// [`Bound::check`] for a count; `context` follows the range in the message (e.g.
    /// " with --method mse").
    pub fn check_count(&self, v: usize, context: &str) -> Result<usize, TrainError> {
        let f = v as f64;
        if f >= self.min && f <= self.max {
            return Ok(v);
        }
        Err(self.refuse(v.to_string(), self.range(), context))
    }

    /// Parses a command-line value and checks it (clap prints the option's name in front of the
    /// message): the same bounds as [`Bound::check`], so a flag and a spec key cannot disagree.
    pub fn parse(&self, s: &str) -> Result<f64, String> {
        let v = s
            .trim()
            .parse::<f64>()
            .map_err(|_| format!("`{s}` is not a number"))?;
        if !v.is_finite() {
            return Err(format!(
                "must be a finite number ({}), got {s}",
                self.range()
            ));
        }
        if self.contains(v) {
            Ok(v)
        } else {
            Err(format!("must be {} ({}), got {s}", self.range(), self.why))
        }
    }

    /// Parses a command-line count and checks it against the same bounds.
    pub fn parse_count(&self, s: &str) -> Result<usize, String> {
        let (lo, hi) = (self.min.max(0.0) as u128, self.max.max(0.0) as u128);
        let range = format!("an integer from {lo} to {hi}");
        let v: i128 = s
            .trim()
            .parse()
            .map_err(|_| format!("must be {range}, got `{s}`"))?;
        match u128::try_from(v) {
            Ok(v) if (lo..=hi).contains(&v) => {
                usize::try_from(v).map_err(|_| format!("must be {range}, got {s}"))
            }
            _ => Err(format!("must be {range} ({}), got {s}", self.why)),
        }
    }

    /// A clap value parser for this bound (feature `cli`).
    #[cfg(feature = "cli")]
    pub fn parser(self) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
        move |s| self.parse(s)
    }

    /// A clap value parser for a count within this bound (feature `cli`).
    #[cfg(feature = "cli")]
    pub fn count_parser(
        self,
    ) -> impl Fn(&str) -> Result<usize, String> + Clone + Send + Sync + 'static {
        move |s| self.parse_count(s)
    }
}

/// A bound of the messages: `1e7` rather than `10000000`.
fn bound_num(v: f64) -> String {
    if v != 0.0 && v.is_finite() && v.abs() >= 1e6 {
        format!("{v:e}")
    } else {
        exact(v)
    }
}

/// An interval that may also be 0 for "off" (`--average`): 0, or within the inner bound.
#[derive(Clone, Copy, Debug)]
pub struct OffOr(pub Bound);

impl OffOr {
    fn range(&self) -> String {
        format!(
            "between 0 and {}{}: 0 (off) or at least {}",
            bound_num(self.0.max),
            self.0.unit_word(),
            bound_num(self.0.min)
        )
    }

    /// `v` when it is 0 or within the inner bound, else an error naming the option.
    pub fn check(&self, v: f64) -> Result<f64, TrainError> {
        if v == 0.0 || self.0.contains(v) {
            return Ok(v);
        }
        Err(self.0.refuse(exact(v), self.range(), ""))
    }

    /// Parses and checks a command-line value.
    pub fn parse(&self, s: &str) -> Result<f64, String> {
        let v = s
            .trim()
            .parse::<f64>()
            .map_err(|_| format!("`{s}` is not a number"))?;
        if v == 0.0 || self.0.contains(v) {
            Ok(v)
        } else {
            Err(format!(
                "must be {} ({}), got {s}",
                self.range(),
                self.0.why
            ))
        }
    }

    /// A clap value parser (feature `cli`).
    #[cfg(feature = "cli")]
    pub fn parser(self) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
        move |s| self.parse(s)
    }
}

/// Parses a seed: any 64-bit unsigned integer (every value is a valid seed; this only gives a
/// negative or fractional one a message with the range instead of a bare parse error).
pub fn parse_seed(s: &str) -> Result<u64, String> {
    s.trim()
        .parse::<u64>()
        .map_err(|_| format!("must be an integer from 0 to {}, got {s}", u64::MAX))
}

/// `--reference-value`: no inertial output comes near 10⁹ in its unit (1 g is 10⁶ µg, the earth
/// rate 15 °/h), and the value is stored as f32 in the blob, whose 24-bit mantissa no longer
/// resolves the residual of a much larger value; a larger one is a typo.
pub const REFERENCE_VALUE: Bound = Bound {
    flag: "--reference-value",
    key: "reference-value",
    min: -1e9,
    min_exclusive: false,
    max: 1e9,
    unit: "",
    why: "a constant true input in the target's unit; 1 g is 1e6 µg",
};

/// Shortest bin, averaging interval or gap threshold: 1 ms. The fastest loop the firmware runs is
/// 200 Hz (5 ms), so a shorter interval holds at most one sample; and a bin index is
/// `(t − t0) / bin` cast to an `i64`, which a 1e-300 s bin saturates from the first step on.
pub const MIN_INTERVAL_S: f64 = 1e-3;

/// Longest bin, averaging interval or gap threshold: 10⁷ s (16 weeks), longer than any chamber run,
/// so a larger value can only be a typo (it would leave a single bin with no spread to measure).
pub const MAX_INTERVAL_S: f64 = 1e7;

const fn interval(flag: &'static str, key: &'static str, why: &'static str) -> Bound {
    Bound {
        flag,
        key,
        min: MIN_INTERVAL_S,
        min_exclusive: false,
        max: MAX_INTERVAL_S,
        unit: "s",
        why,
    }
}

/// `--average`: 0 turns averaging off; otherwise an interval as [`MIN_INTERVAL_S`] and
/// [`MAX_INTERVAL_S`] say. Against the data, a bin must also be at least the sampling step.
pub const AVERAGE: OffOr = OffOr(interval(
    "--average",
    "average",
    "0 is no averaging; 1e7 s is longer than any chamber run",
));

/// `--bin` of the evaluating commands (their defaults differ; their range does not). Against the
/// data, [`check_bin`].
pub const BIN: Bound = interval("--bin", "", "the length of the bins of the binned figures");

/// `--gap`: a step length; 10⁷ s is longer than any run, so every step would be kept.
pub const GAP: Bound = interval(
    "--gap",
    "gap",
    "steps longer than this are gaps, across which feature state is carried or restarted",
);

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

/// `--centers` of `bayes` (and the command line, before the method is known): 0 is the linear
/// part alone (a model the evidence may well prefer).
pub const CENTERS_BAYES: Bound = Bound {
    flag: "--centers",
    key: "centers",
    min: 0.0,
    min_exclusive: false,
    max: crate::rbf64::C as f64,
    unit: "",
    why: "0 is the linear part alone; a blob holds at most 64 centers",
};

/// `--iterations` of `gradient`: each is a full pass over the training rows; with the halving
/// learning rate the fits of the test cases settle within a few thousand, and 10⁶ passes over an
/// unaveraged run would take days. At least one: zero leaves the initial guess as the model.
pub const ITERATIONS: Bound = Bound {
    flag: "--iterations",
    key: "iterations",
    min: 1.0,
    min_exclusive: false,
    max: 1e6,
    unit: "",
    why: "each iteration is a full pass over the training rows",
};

/// `--from`: a time in seconds of magnitude at most 10¹⁰ s. Time columns count seconds from the
/// start of the run or from the Unix epoch (1.8·10⁹ s today, 10¹⁰ s in the year 2286); a larger
/// value is a unit error, e.g. a Unix time in milliseconds (1.8·10¹²).
pub const FROM: Bound = Bound {
    flag: "--from",
    key: "from",
    min: -1e10,
    min_exclusive: false,
    max: 1e10,
    unit: "s",
    why: "a time of the record's time column, from its start or the Unix epoch",
};

/// `--power-on`: a time of the record's time column, as `--from`.
pub const POWER_ON: Bound = Bound {
    flag: "--power-on",
    key: "power-on",
    min: -1e10,
    min_exclusive: false,
    max: 1e10,
    unit: "s",
    why: "a time of the record's time column, from its start or the Unix epoch",
};

/// `--until`: as [`FROM`].
pub const UNTIL: Bound = Bound {
    flag: "--until",
    key: "until",
    ..FROM
};

/// `diagnose --min-evidence` (Δ ln evidence, a log odds): below 0 a candidate the evidence prefers
/// to leave out would pass; 5 is "strong" on Jeffreys' scale, and above 100 (odds of e¹⁰⁰) no real
/// candidate could pass. (The command line allowed up to 10⁶, a bound against typos only, and the
/// diagnosis then refused anything above 100; the physical bound is the one kept.)
pub const MIN_EVIDENCE: Bound = Bound {
    flag: "--min-evidence",
    key: "",
    min: 0.0,
    min_exclusive: false,
    max: 100.0,
    unit: "",
    why: "a Δ log evidence; 5 is strong on Jeffreys' scale",
};

/// `diagnose --min-improvement` (%): a residual cannot fall by more than all of it (100 % would
/// demand a perfect fit), and below 0 a candidate that makes the model worse would pass.
pub const MIN_IMPROVEMENT: Bound = Bound {
    flag: "--min-improvement",
    key: "",
    min: 0.0,
    min_exclusive: false,
    max: 100.0,
    unit: "",
    why: "the share (%) of the held-out residual a candidate must remove",
};

/// `diagnose --top`: at least one (a diagnosis printing no candidate hides its own evidence);
/// 10 000 is a bound against typos only (larger values print the whole list anyway).
pub const TOP: Bound = Bound {
    flag: "--top",
    key: "",
    min: 1.0,
    min_exclusive: false,
    max: 10_000.0,
    unit: "",
    why: "candidates printed",
};

/// `demo --step` (s): the demo's training profile lasts about 6.8 hours, one row per step: below
/// 0.1 s that is more than 240 000 rows and the demo stops being quick; above 10 s the fastest ramp
/// (2 °C/min) moves more than 0.3 °C between rows and the rate features get coarse.
pub const DEMO_STEP: Bound = Bound {
    flag: "--step",
    key: "",
    min: 0.1,
    min_exclusive: false,
    max: 10.0,
    unit: "s",
    why: "the output step of the demo's simulated runs",
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
    Err(TrainError::BinVsData {
        option: format!("{flag} {}", exact(bin_s)),
        step: exact(step),
        max: exact(max),
        span: exact(span),
    })
}
