//! Logger dropouts: stretches of a run whose rows are not written, while the instrument and the
//! physics run on.
//!
//! Why: a real chamber log has holes — a logger restarted, a USB link reset — and a model's
//! stateful features (lags of tens of minutes, rates) must be carried across them, not restarted
//! (see the core's `eval` on gaps). To test that, the simulator must write a file with holes whose
//! bias is still the physical one: every internal sample and every effect's state is computed
//! through the dropout as usual, only the rows whose time falls inside one are left out of the
//! file. The truth file lists the dropouts.
//!
//! In a scenario file, either explicit stretches or a seeded random count:
//! ```toml
//! dropouts = [{ start_s = 3600, length_s = 300 }, { start_s = 9000, length_s = 120 }]
//! # or
//! random_dropouts = { count = 5, length_s = 300, seed = 3 }
//! ```

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// One dropout: rows with `start_s ≤ time < start_s + length_s` are not written.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dropout {
    /// Start, seconds from power-on (the time column).
    pub start_s: f64,
    /// Length, seconds.
    pub length_s: f64,
}

impl Dropout {
    /// Whether a row at `time_s` falls inside.
    pub fn hides(&self, time_s: f64) -> bool {
        time_s >= self.start_s && time_s < self.start_s + self.length_s
    }
}

/// `count` dropouts of `length_s` seconds at random starts within the run (seeded).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomDropouts {
    /// How many.
    pub count: u32,
    /// Length of each, seconds.
    pub length_s: f64,
    /// Seed of their starts (independent of the noise seed).
    #[serde(default = "default_seed")]
    pub seed: u64,
}

fn default_seed() -> u64 {
    1
}

/// Most dropouts a run may have: more are not a logger's holes but a different sampling.
pub const MAX_DROPOUTS: usize = 10_000;

impl RandomDropouts {
    /// The dropouts within a run of `duration_s`: starts uniform over the run after its first
    /// tenth (so that every filter has some history before the first hole), sorted.
    pub fn resolve(&self, duration_s: f64) -> Result<Vec<Dropout>> {
        if self.count as usize > MAX_DROPOUTS {
            return Err(Error::invalid(
                "random_dropouts.count",
                format!("at most {MAX_DROPOUTS}, got {}", self.count),
            ));
        }
        Error::positive("random_dropouts.length_s", self.length_s)?;
        let lo = 0.1 * duration_s;
        let hi = duration_s - self.length_s;
        if self.count > 0 && hi <= lo {
            return Err(Error::invalid(
                "random_dropouts.length_s",
                format!(
                    "{} s does not fit in the {duration_s} s run after its first tenth",
                    self.length_s
                ),
            ));
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut out: Vec<Dropout> = (0..self.count)
            .map(|_| Dropout {
                start_s: rng.random_range(lo..hi),
                length_s: self.length_s,
            })
            .collect();
        out.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
        Ok(out)
    }
}

/// Checks dropouts against a run of `duration_s`: finite, positive lengths, inside the run, not
/// hiding its first row (a file must start somewhere); errors name `dropouts[i].<field>`.
pub fn validate(dropouts: &[Dropout], duration_s: f64, step_s: f64) -> Result<()> {
    if dropouts.len() > MAX_DROPOUTS {
        return Err(Error::invalid(
            "dropouts",
            format!("at most {MAX_DROPOUTS}, got {}", dropouts.len()),
        ));
    }
    for (i, d) in dropouts.iter().enumerate() {
        Error::positive(format!("dropouts[{i}].length_s"), d.length_s)?;
        if !(d.start_s.is_finite() && d.start_s >= step_s && d.start_s < duration_s) {
            return Err(Error::invalid(
                format!("dropouts[{i}].start_s"),
                format!(
                    "must lie after the first row ({step_s} s) and within the {duration_s} s run, \
                     got {}",
                    d.start_s
                ),
            ));
        }
    }
    Ok(())
}

/// Whether any of `dropouts` hides a row at `time_s`.
pub fn hidden(dropouts: &[Dropout], time_s: f64) -> bool {
    dropouts.iter().any(|d| d.hides(time_s))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn random_dropouts_are_seeded_sorted_and_inside_the_run() {
        let r = RandomDropouts {
            count: 6,
            length_s: 300.0,
            seed: 4,
        };
        let a = r.resolve(36_000.0).unwrap();
        assert_eq!(a, r.resolve(36_000.0).unwrap());
        assert_eq!(a.len(), 6);
        assert!(a.windows(2).all(|w| w[0].start_s <= w[1].start_s));
        assert!(
            a.iter()
                .all(|d| d.start_s >= 3600.0 && d.start_s + 300.0 <= 36_000.0)
        );
        validate(&a, 36_000.0, 0.5).unwrap();
        let too_long = RandomDropouts {
            length_s: 40_000.0,
            ..r
        };
        assert!(too_long.resolve(36_000.0).is_err());
    }

    #[test]
    fn a_dropout_hides_its_half_open_stretch() {
        let d = [Dropout {
            start_s: 10.0,
            length_s: 5.0,
        }];
        assert!(!hidden(&d, 9.99));
        assert!(hidden(&d, 10.0));
        assert!(hidden(&d, 14.99));
        assert!(!hidden(&d, 15.0));
        assert!(validate(&d, 100.0, 1.0).is_ok());
        let e = validate(
            &[Dropout {
                start_s: 0.0,
                length_s: 5.0,
            }],
            100.0,
            1.0,
        )
        .unwrap_err();
        assert!(e.to_string().contains("dropouts[0].start_s"), "{e}");
    }
}
