//! Chamber air-temperature profiles: piecewise holds and ramps.
//!
//! Why: a chamber run is specified the way a test engineer writes it ("20 °C held 1.5 h; +3 °C/min to
//! 50 °C; …"), so a profile is a start temperature and a list of segments, each a hold (a duration)
//! or a ramp (a target temperature and a rate). Presets, TOML files and seeded random profiles all
//! produce this one type, and the simulator evaluates it as a piecewise-linear function of time.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// One piece of a chamber profile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Segment {
    /// Hold the current temperature for `duration_s` seconds.
    Hold {
        /// Length of the hold in seconds.
        duration_s: f64,
    },
    /// Ramp linearly to `to_c` at `rate_c_per_min` (its sign is ignored: the target sets the
    /// direction).
    Ramp {
        /// Target temperature in °C.
        to_c: f64,
        /// Ramp rate in °C per minute (magnitude).
        rate_c_per_min: f64,
    },
}

impl Segment {
    /// A hold of `hours` hours.
    pub fn hold_h(hours: f64) -> Self {
        Segment::Hold {
            duration_s: hours * 3600.0,
        }
    }

    /// A ramp to `to_c` at `rate_c_per_min`.
    pub fn ramp(to_c: f64, rate_c_per_min: f64) -> Self {
        Segment::Ramp {
            to_c,
            rate_c_per_min,
        }
    }
}

/// A chamber profile: start temperature and segments.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    /// Chamber air temperature at t = 0, °C.
    pub start_c: f64,
    /// Holds and ramps, in order.
    pub segments: Vec<Segment>,
}

/// What a resolved segment does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SegmentKind {
    /// Constant temperature.
    Hold,
    /// Rising ramp.
    Heat,
    /// Falling ramp.
    Cool,
}

/// A segment resolved to absolute times and temperatures (what the truth file lists).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ResolvedSegment {
    /// `hold`, `heat` (rising ramp) or `cool` (falling ramp).
    pub kind: SegmentKind,
    /// Start time, s.
    pub start_s: f64,
    /// End time, s.
    pub end_s: f64,
    /// Temperature at the start, °C.
    pub from_c: f64,
    /// Temperature at the end, °C.
    pub to_c: f64,
    /// Signed rate, °C/min (0 for holds).
    pub rate_c_per_min: f64,
}

impl Profile {
    /// A profile starting at `start_c` with `segments`.
    pub fn new(start_c: f64, segments: Vec<Segment>) -> Self {
        Profile { start_c, segments }
    }

    /// Checks the profile; errors name the field under `prefix` (e.g. `profile`).
    pub fn validate(&self, prefix: &str) -> Result<()> {
        if !self.start_c.is_finite() {
            return Err(Error::invalid(
                format!("{prefix}.start_c"),
                "must be a finite temperature",
            ));
        }
        if self.segments.is_empty() {
            return Err(Error::invalid(
                format!("{prefix}.segments"),
                "the profile is empty: give at least one hold or ramp",
            ));
        }
        let mut temp = self.start_c;
        for (i, seg) in self.segments.iter().enumerate() {
            let at = format!("{prefix}.segments[{i}]");
            match *seg {
                Segment::Hold { duration_s } => {
                    if !(duration_s.is_finite() && duration_s > 0.0) {
                        return Err(Error::invalid(
                            format!("{at}.duration_s"),
                            format!("a hold needs a duration > 0 s, got {duration_s}"),
                        ));
                    }
                }
                Segment::Ramp {
                    to_c,
                    rate_c_per_min,
                } => {
                    if !to_c.is_finite() {
                        return Err(Error::invalid(format!("{at}.to_c"), "must be finite"));
                    }
                    if !rate_c_per_min.is_finite() || rate_c_per_min == 0.0 {
                        return Err(Error::invalid(
                            format!("{at}.rate_c_per_min"),
                            "a ramp needs a non-zero rate",
                        ));
                    }
                    if to_c == temp {
                        return Err(Error::invalid(
                            format!("{at}.to_c"),
                            format!("the ramp goes nowhere: the temperature is already {to_c} °C"),
                        ));
                    }
                    temp = to_c;
                }
            }
        }
        Ok(())
    }

    /// Segments with absolute times and temperatures. Assumes a valid profile.
    pub fn resolved(&self) -> Vec<ResolvedSegment> {
        let mut out = Vec::with_capacity(self.segments.len());
        let (mut t, mut temp) = (0.0, self.start_c);
        for seg in &self.segments {
            let r = match *seg {
                Segment::Hold { duration_s } => ResolvedSegment {
                    kind: SegmentKind::Hold,
                    start_s: t,
                    end_s: t + duration_s,
                    from_c: temp,
                    to_c: temp,
                    rate_c_per_min: 0.0,
                },
                Segment::Ramp {
                    to_c,
                    rate_c_per_min,
                } => {
                    let rate = rate_c_per_min.abs() * (to_c - temp).signum();
                    let dur = if rate == 0.0 {
                        0.0
                    } else {
                        60.0 * (to_c - temp) / rate
                    };
                    ResolvedSegment {
                        kind: if rate > 0.0 {
                            SegmentKind::Heat
                        } else {
                            SegmentKind::Cool
                        },
                        start_s: t,
                        end_s: t + dur,
                        from_c: temp,
                        to_c,
                        rate_c_per_min: rate,
                    }
                }
            };
            t = r.end_s;
            temp = r.to_c;
            out.push(r);
        }
        out
    }

    /// Total duration, s.
    pub fn duration_s(&self) -> f64 {
        self.resolved().last().map_or(0.0, |s| s.end_s)
    }

    /// Lowest and highest temperature reached, °C.
    pub fn range_c(&self) -> (f64, f64) {
        self.resolved()
            .iter()
            .fold((self.start_c, self.start_c), |(lo, hi), s| {
                (lo.min(s.to_c), hi.max(s.to_c))
            })
    }

    /// A streaming evaluator of the air temperature for increasing times.
    pub fn cursor(&self) -> ProfileCursor {
        ProfileCursor {
            segs: self.resolved(),
            idx: 0,
            start_c: self.start_c,
        }
    }

    /// Air temperature at time `t_s` (random access; clamps outside the profile).
    pub fn temperature_at(&self, t_s: f64) -> f64 {
        self.cursor().at(t_s)
    }

    /// A seeded random profile (alternating holds and ramps) within the limits of `spec`.
    pub fn random(spec: &RandomProfile) -> Result<Profile> {
        spec.validate("profile.random")?;
        let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
        let mut segs = Vec::new();
        let (mut t, mut temp) = (0.0, spec.start_c.clamp(spec.min_c, spec.max_c));
        let span = spec.max_c - spec.min_c;
        let min_step = (span / 4.0).min(10.0);
        while t < spec.duration_s {
            let hold = rng.random_range(spec.min_hold_s..=spec.max_hold_s);
            segs.push(Segment::Hold { duration_s: hold });
            t += hold;
            if t >= spec.duration_s {
                break;
            }
            // A target at least `min_step` away from the current temperature.
            let mut to = temp;
            for _ in 0..64 {
                to = rng.random_range(spec.min_c..=spec.max_c);
                if (to - temp).abs() >= min_step {
                    break;
                }
            }
            if (to - temp).abs() < 1e-6 {
                to = if temp - spec.min_c > spec.max_c - temp {
                    spec.min_c
                } else {
                    spec.max_c
                };
            }
            let rate = rng.random_range(spec.min_rate_c_per_min..=spec.max_rate_c_per_min);
            let to = (to * 10.0).round() / 10.0;
            let rate = (rate * 100.0).round().max(1.0) / 100.0;
            if to == temp {
                continue;
            }
            segs.push(Segment::Ramp {
                to_c: to,
                rate_c_per_min: rate,
            });
            t += 60.0 * (to - temp).abs() / rate;
            temp = to;
        }
        Ok(Profile {
            start_c: spec.start_c.clamp(spec.min_c, spec.max_c),
            segments: segs,
        })
    }
}

/// Limits of a seeded random profile.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomProfile {
    /// Seed of the profile (independent of the noise seed).
    pub seed: u64,
    /// Start temperature, °C.
    pub start_c: f64,
    /// Lowest temperature, °C.
    pub min_c: f64,
    /// Highest temperature, °C.
    pub max_c: f64,
    /// Fastest ramp, °C/min.
    pub max_rate_c_per_min: f64,
    /// Slowest ramp, °C/min.
    #[serde(default = "default_min_rate")]
    pub min_rate_c_per_min: f64,
    /// Shortest hold, s.
    #[serde(default = "default_min_hold")]
    pub min_hold_s: f64,
    /// Longest hold, s.
    #[serde(default = "default_max_hold")]
    pub max_hold_s: f64,
    /// Approximate total duration, s (the last segment may end a little later).
    pub duration_s: f64,
}

fn default_min_rate() -> f64 {
    0.2
}
fn default_min_hold() -> f64 {
    1800.0
}
fn default_max_hold() -> f64 {
    5400.0
}

impl RandomProfile {
    /// Limits with default holds (30–90 min) and slowest rate (0.2 °C/min).
    pub fn new(
        seed: u64,
        min_c: f64,
        max_c: f64,
        max_rate_c_per_min: f64,
        duration_s: f64,
    ) -> Self {
        RandomProfile {
            seed,
            start_c: 20.0,
            min_c,
            max_c,
            max_rate_c_per_min,
            min_rate_c_per_min: default_min_rate().min(max_rate_c_per_min),
            min_hold_s: default_min_hold(),
            max_hold_s: default_max_hold(),
            duration_s,
        }
    }

    fn validate(&self, p: &str) -> Result<()> {
        let pos = |v: f64, f: &str| Error::positive(format!("{p}.{f}"), v);
        pos(self.max_rate_c_per_min, "max_rate_c_per_min")?;
        pos(self.min_rate_c_per_min, "min_rate_c_per_min")?;
        pos(self.min_hold_s, "min_hold_s")?;
        pos(self.max_hold_s, "max_hold_s")?;
        pos(self.duration_s, "duration_s")?;
        if !(self.min_c.is_finite() && self.max_c.is_finite() && self.max_c > self.min_c) {
            return Err(Error::invalid(format!("{p}.max_c"), "must be above min_c"));
        }
        if self.min_rate_c_per_min > self.max_rate_c_per_min {
            return Err(Error::invalid(
                format!("{p}.min_rate_c_per_min"),
                "must not exceed max_rate_c_per_min",
            ));
        }
        if self.min_hold_s > self.max_hold_s {
            return Err(Error::invalid(
                format!("{p}.min_hold_s"),
                "must not exceed max_hold_s",
            ));
        }
        Ok(())
    }
}

/// Evaluates a profile at non-decreasing times in O(1) amortised.
#[derive(Debug, Clone)]
pub struct ProfileCursor {
    segs: Vec<ResolvedSegment>,
    idx: usize,
    start_c: f64,
}

impl ProfileCursor {
    /// Air temperature at `t_s`; times should not decrease between calls (it rewinds if they do).
    pub fn at(&mut self, t_s: f64) -> f64 {
        if self.segs.is_empty() {
            return self.start_c;
        }
        if self.idx >= self.segs.len() || self.segs.get(self.idx).is_some_and(|s| t_s < s.start_s) {
            self.idx = 0;
        }
        while let Some(s) = self.segs.get(self.idx) {
            if t_s < s.end_s || self.idx + 1 == self.segs.len() {
                break;
            }
            self.idx += 1;
        }
        match self.segs.get(self.idx) {
            None => self.start_c,
            Some(s) if t_s <= s.start_s => s.from_c,
            Some(s) if t_s >= s.end_s => s.to_c,
            Some(s) => s.from_c + s.rate_c_per_min * (t_s - s.start_s) / 60.0,
        }
    }
}
