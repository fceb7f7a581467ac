//! Range checks of the numeric flags, run by clap while it parses the command line.
//!
//! Why here and at parse time: a flag value that is NaN, infinite, zero, negative or absurdly large
//! does not fail loudly further down — `--min-evidence nan` flips a verdict, `--reference-value inf`
//! prints NaN figures, `--bin 1e-300` overflows the bin index — so every numeric flag of the tool goes
//! through one of these functions and a bad value stops the run before any file is read or written.
//! Clap puts the option's name in front of the message (`invalid value 'nan' for '--bin <BIN>': …`)
//! and exits with its usage code, 2; each message states the valid range. Every flag using these also
//! sets `allow_negative_numbers`, so `--average -5` reaches the check instead of being taken for a
//! flag. The trainer checks the same options again for library callers and spec files.

/// Shortest bin, averaging interval or gap threshold: 1 ms. The fastest loop the firmware runs is
/// 200 Hz (5 ms), so a shorter interval holds at most one sample; and the trainer's bin index is
/// `(t − t0) / bin` cast to an `i64`, which a 1e-300 s bin saturates from the first step on, putting
/// every later sample into one bin.
pub const MIN_INTERVAL_S: f64 = 1e-3;

/// Longest bin, averaging interval or gap threshold: 1e7 s (16 weeks). No chamber run is that long,
/// so a larger value can only be a typo, and it would leave a single bin with no spread to measure.
pub const MAX_INTERVAL_S: f64 = 1e7;

/// Largest magnitude of a time bound (`--from`, `--until`): 1e10 s. Time columns count seconds from
/// the start of the run or from the Unix epoch (about 1.8e9 s today); both fit with room to spare.
pub const MAX_TIME_S: f64 = 1e10;

/// Largest magnitude of a constant reference: 1e9 in the target's unit. That is beyond any sensor
/// output in the units used (1 g is 1e6 µg; Earth rate is 15 °/h), and the blob stores the reference
/// as an `f32`, whose 24-bit mantissa no longer resolves the residual of a value much larger.
pub const MAX_REFERENCE: f64 = 1e9;

/// Shortest and longest output step of `demo` (s). The demo's training profile lasts about 6.8
/// hours, one row per step: below 0.1 s that is more than 240 000 rows and the demo stops being a
/// quick demonstration; above 10 s the fastest ramp (2 °C/min) moves more than 0.3 °C between rows
/// and the rate features get coarse.
pub const DEMO_STEP_S: (f64, f64) = (0.1, 10.0);

/// Largest `--min-evidence` (Δ ln evidence): 1e6, a bound against typos only (a million nats is
/// odds of e^1000000 to one). Below 0 a candidate the evidence prefers to leave out would pass, so
/// 0 is the smallest.
pub const MAX_MIN_EVIDENCE: f64 = 1e6;

/// Most candidates `diagnose --top` prints: 10 000, a bound against typos only (larger values print
/// the whole list anyway); at least one, since a diagnosis printing no candidate hides its own
/// evidence.
pub const MAX_TOP: usize = 10_000;

/// Most gradient-descent iterations: 10 million, hours of fitting; at least one, since zero
/// iterations leave the initial guess as the model.
pub const MAX_ITERATIONS: usize = 10_000_000;

fn number(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .map_err(|_| format!("`{s}` is not a number"))
}

fn finite(s: &str, range: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("must be a finite number ({range}), got {s}"))
    }
}

fn in_range(s: &str, lo: f64, hi: f64, range: &str) -> Result<f64, String> {
    let v = finite(s, range)?;
    if (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(format!("must be {range}, got {s}"))
    }
}

fn integer(s: &str, lo: u128, hi: u128) -> Result<u128, String> {
    let range = format!("an integer from {lo} to {hi}");
    let v: i128 = s
        .trim()
        .parse()
        .map_err(|_| format!("must be {range}, got `{s}`"))?;
    match u128::try_from(v) {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!("must be {range}, got {s}")),
    }
}

/// A bin length or gap threshold in seconds: from [`MIN_INTERVAL_S`] to [`MAX_INTERVAL_S`].
pub fn interval_s(s: &str) -> Result<f64, String> {
    in_range(
        s,
        MIN_INTERVAL_S,
        MAX_INTERVAL_S,
        &format!("between {MIN_INTERVAL_S} and {MAX_INTERVAL_S:e} seconds"),
    )
}

/// `fit --average`: 0 (no averaging) or an interval as in [`interval_s`].
pub fn average_s(s: &str) -> Result<f64, String> {
    let range = format!("0 (off) or between {MIN_INTERVAL_S} and {MAX_INTERVAL_S:e} seconds");
    let v = finite(s, &range)?;
    if v == 0.0 || (MIN_INTERVAL_S..=MAX_INTERVAL_S).contains(&v) {
        Ok(v)
    } else {
        Err(format!("must be {range}, got {s}"))
    }
}

/// A time bound (`--from`, `--until`) in seconds, of magnitude at most [`MAX_TIME_S`].
pub fn time_s(s: &str) -> Result<f64, String> {
    in_range(
        s,
        -MAX_TIME_S,
        MAX_TIME_S,
        &format!("a time in seconds between -{MAX_TIME_S:e} and {MAX_TIME_S:e}"),
    )
}

/// A constant reference, of magnitude at most [`MAX_REFERENCE`].
pub fn reference_value(s: &str) -> Result<f64, String> {
    in_range(
        s,
        -MAX_REFERENCE,
        MAX_REFERENCE,
        &format!("between -{MAX_REFERENCE:e} and {MAX_REFERENCE:e} in the target's unit"),
    )
}

/// `demo --step`: within [`DEMO_STEP_S`].
pub fn demo_step_s(s: &str) -> Result<f64, String> {
    let (lo, hi) = DEMO_STEP_S;
    in_range(s, lo, hi, &format!("between {lo} and {hi} seconds"))
}

/// `diagnose --min-evidence`: from 0 to [`MAX_MIN_EVIDENCE`].
pub fn min_evidence(s: &str) -> Result<f64, String> {
    in_range(
        s,
        0.0,
        MAX_MIN_EVIDENCE,
        &format!("a Δ ln evidence between 0 and {MAX_MIN_EVIDENCE:e}"),
    )
}

/// `diagnose --min-improvement`: a percentage from 0 to 100 (a residual cannot fall by more than
/// all of it; below 0 a candidate that makes the model worse would pass).
pub fn percent(s: &str) -> Result<f64, String> {
    in_range(s, 0.0, 100.0, "a percentage between 0 and 100")
}

/// `diagnose --top`: from 1 to [`MAX_TOP`].
pub fn top(s: &str) -> Result<usize, String> {
    count(s, 1, MAX_TOP)
}

/// `fit --centers`: from 0 (no Gaussians) to [`tcomp_core::HOST_CENTERS`], the most the host's model
/// type holds (the firmware holds [`tcomp_core::FLIGHT_CENTERS`]; `fit` warns above that).
pub fn centers(s: &str) -> Result<usize, String> {
    count(s, 0, tcomp_core::HOST_CENTERS)
}

/// `fit --iterations`: from 1 to [`MAX_ITERATIONS`].
pub fn iterations(s: &str) -> Result<usize, String> {
    count(s, 1, MAX_ITERATIONS)
}

/// A seed: any 64-bit unsigned integer (every value is a valid seed; this only gives a negative or
/// fractional one a message with the range instead of a parse error).
pub fn seed(s: &str) -> Result<u64, String> {
    let v = integer(s, 0, u128::from(u64::MAX))?;
    u64::try_from(v).map_err(|_| format!("must be an integer from 0 to {}", u64::MAX))
}

fn count(s: &str, lo: usize, hi: usize) -> Result<usize, String> {
    let to = |n: usize| u128::try_from(n).unwrap_or(u128::MAX);
    let v = integer(s, to(lo), to(hi))?;
    usize::try_from(v).map_err(|_| format!("must be an integer from {lo} to {hi}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_values_are_refused_with_the_range() {
        for s in ["nan", "NaN", "inf", "-inf", "infinity"] {
            let e = interval_s(s).err().unwrap_or_default();
            assert!(e.contains("finite") && e.contains("seconds"), "{s}: {e}");
            assert!(
                reference_value(s).is_err() && min_evidence(s).is_err(),
                "{s}"
            );
            assert!(time_s(s).is_err() && average_s(s).is_err(), "{s}");
        }
    }

    #[test]
    fn interval_bounds() {
        assert_eq!(interval_s("100"), Ok(100.0));
        assert_eq!(interval_s(" 0.001 "), Ok(MIN_INTERVAL_S));
        assert_eq!(interval_s("1e7"), Ok(MAX_INTERVAL_S));
        for s in ["0", "-5", "1e-300", "1e-4", "1.1e7", "abc", ""] {
            assert!(interval_s(s).is_err(), "{s}");
        }
        assert_eq!(average_s("0"), Ok(0.0));
        assert_eq!(average_s("30"), Ok(30.0));
        for s in ["-5", "1e-300", "-0.5", "1e8"] {
            let e = average_s(s).err().unwrap_or_default();
            assert!(e.contains("0 (off)"), "{s}: {e}");
        }
    }

    #[test]
    fn signed_values_keep_their_sign_within_bounds() {
        assert_eq!(reference_value("-12.5"), Ok(-12.5));
        assert!(reference_value("1e10").is_err());
        assert_eq!(time_s("-1"), Ok(-1.0));
        assert_eq!(time_s("1.7e9"), Ok(1.7e9));
        assert!(time_s("1e11").is_err() && time_s("-1e11").is_err());
        assert_eq!(demo_step_s("10"), Ok(10.0));
        assert!(demo_step_s("0.05").is_err() && demo_step_s("10.5").is_err());
        assert_eq!(percent("100"), Ok(100.0));
        assert!(percent("-1").is_err() && percent("101").is_err());
        assert!(min_evidence("-0.1").is_err() && min_evidence("2e6").is_err());
    }

    #[test]
    fn integers_are_range_checked_with_a_message_not_a_parse_error() {
        assert_eq!(top("3"), Ok(3));
        for s in ["0", "-5", "1.5", "10001", "99999999999999999999999999"] {
            let e = top(s).err().unwrap_or_default();
            assert!(e.contains("from 1 to 10000"), "{s}: {e}");
        }
        assert_eq!(centers("0"), Ok(0));
        assert_eq!(centers("64"), Ok(tcomp_core::HOST_CENTERS));
        assert!(centers("65").is_err() && centers("-1").is_err());
        assert!(iterations("0").is_err());
        assert_eq!(seed("18446744073709551615"), Ok(u64::MAX));
        assert!(seed("-1").is_err() && seed("18446744073709551616").is_err());
    }
}
