//! Clap value parsers of the numeric flags: thin adapters over the trainer's one table of bounds
//! ([`tcomp_train::options`]), run by clap while it parses the command line.
//!
//! Why at parse time: a flag value that is NaN, infinite, zero, negative or absurdly large does not
//! fail loudly further down — `--min-evidence nan` flips a verdict, `--reference-value inf` prints
//! NaN figures, `--bin 1e-300` overflows the bin index — so every numeric flag of the tool goes
//! through the table and a bad value stops the run before any file is read or written. Clap puts the
//! option's name in front of the message (`invalid value 'nan' for '--bin <BIN>': …`) and exits with
//! its usage code, 2; each message states the valid range. Every flag using these also sets
//! `allow_negative_numbers`, so `--average -5` reaches the check instead of being taken for a flag.
//! The trainer's own flags (`fit`'s and the run's: `--average`, `--centers`, `--from`, …) take
//! their parsers from the table directly, in the option structs of `tcomp_train::spec`; the
//! trainer checks spec files and library callers against the same bounds, so the two cannot
//! disagree.

use tcomp_train::options as o;

/// A bin length in seconds ([`o::BIN`]).
pub fn interval_s(s: &str) -> Result<f64, String> {
    o::BIN.parse(s)
}

/// `demo --step` ([`o::DEMO_STEP`]).
pub fn demo_step_s(s: &str) -> Result<f64, String> {
    o::DEMO_STEP.parse(s)
}

/// `diagnose --min-evidence` ([`o::MIN_EVIDENCE`]).
pub fn min_evidence(s: &str) -> Result<f64, String> {
    o::MIN_EVIDENCE.parse(s)
}

/// `diagnose --min-improvement` ([`o::MIN_IMPROVEMENT`]).
pub fn percent(s: &str) -> Result<f64, String> {
    o::MIN_IMPROVEMENT.parse(s)
}

/// `diagnose --top` ([`o::TOP`]).
pub fn top(s: &str) -> Result<usize, String> {
    o::TOP.parse_count(s)
}

/// `diagnose --placebos` ([`tcomp_discover::verdict::PLACEBO_COUNT`]).
pub fn placebos(s: &str) -> Result<usize, String> {
    tcomp_discover::verdict::PLACEBO_COUNT.parse_count(s)
}

/// A seed: any 64-bit unsigned integer.
pub fn seed(s: &str) -> Result<u64, String> {
    o::parse_seed(s)
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
                o::REFERENCE_VALUE.parse(s).is_err() && min_evidence(s).is_err(),
                "{s}"
            );
            assert!(
                o::FROM.parse(s).is_err() && o::AVERAGE.parse(s).is_err(),
                "{s}"
            );
        }
    }

    #[test]
    fn interval_bounds() {
        assert_eq!(interval_s("100"), Ok(100.0));
        assert_eq!(interval_s(" 0.001 "), Ok(o::MIN_INTERVAL_S));
        assert_eq!(interval_s("1e7"), Ok(o::MAX_INTERVAL_S));
        for s in ["0", "-5", "1e-300", "1e-4", "1.1e7", "abc", ""] {
            assert!(interval_s(s).is_err(), "{s}");
            assert!(o::GAP.parse(s).is_err(), "{s}");
        }
        assert_eq!(o::AVERAGE.parse("0"), Ok(0.0));
        assert_eq!(o::AVERAGE.parse("30"), Ok(30.0));
        for s in ["-5", "1e-300", "-0.5", "1e8"] {
            let e = o::AVERAGE.parse(s).err().unwrap_or_default();
            assert!(e.contains("0 (off)"), "{s}: {e}");
        }
    }

    #[test]
    fn signed_values_keep_their_sign_within_bounds() {
        assert_eq!(o::REFERENCE_VALUE.parse("-12.5"), Ok(-12.5));
        assert!(o::REFERENCE_VALUE.parse("1e10").is_err());
        assert_eq!(o::FROM.parse("-1"), Ok(-1.0));
        assert_eq!(o::UNTIL.parse("1.7e9"), Ok(1.7e9));
        assert!(o::FROM.parse("1e11").is_err() && o::UNTIL.parse("-1e11").is_err());
        assert_eq!(demo_step_s("10"), Ok(10.0));
        assert!(demo_step_s("0.05").is_err() && demo_step_s("10.5").is_err());
        assert_eq!(percent("100"), Ok(100.0));
        assert!(percent("-1").is_err() && percent("101").is_err());
        assert!(min_evidence("-0.1").is_err() && min_evidence("101").is_err());
    }

    #[test]
    fn integers_are_range_checked_with_a_message_not_a_parse_error() {
        assert_eq!(top("3"), Ok(3));
        for s in ["0", "-5", "1.5", "10001", "99999999999999999999999999"] {
            let e = top(s).err().unwrap_or_default();
            assert!(e.contains("from 1 to 10000"), "{s}: {e}");
        }
        assert_eq!(o::CENTERS_BAYES.parse_count("0"), Ok(0));
        assert_eq!(
            o::CENTERS_BAYES.parse_count("64"),
            Ok(tcomp_core::HOST_CENTERS)
        );
        assert!(
            o::CENTERS_BAYES.parse_count("65").is_err()
                && o::CENTERS_BAYES.parse_count("-1").is_err()
        );
        assert!(o::ITERATIONS.parse_count("0").is_err());
        assert_eq!(seed("18446744073709551615"), Ok(u64::MAX));
        assert!(seed("-1").is_err() && seed("18446744073709551616").is_err());
    }
}
