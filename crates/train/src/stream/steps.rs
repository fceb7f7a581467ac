//! The time steps of a streamed record: their exact median without holding them, and the gap
//! decisions checked against it.
//!
//! Why: a gap is a step longer than `max(--gap, 10 × median step)` ([`crate::dataset::segments`]),
//! and the median is a property of the whole record, known only at its end, while the compensator
//! must be told of a gap before the sample after it. A logger's clock takes few distinct steps
//! (a fixed rate printed to fixed decimals differs only in the last bits of the parsed time), so
//! the steps are counted by value: the median is then exact, in memory bounded by the number of
//! distinct steps ([`MAX_DISTINCT`]), not by the length. Gaps are decided on the way with the
//! median of the first [`EARLY`] steps, each distinct step remembering how it was decided; at the
//! end every decision is checked against the true limit, and a record where one differs is read
//! again with the true limit (the caller's job).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A hasher for the bits of a step: one multiply (the keys are not chosen by an adversary).
#[derive(Default)]
struct Mix(u64);

impl Hasher for Mix {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (v ^ (v >> 29)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

type Counts = HashMap<u64, Entry, BuildHasherDefault<Mix>>;

/// Distinct step values counted before the record is declared unfit for streaming.
pub const MAX_DISTINCT: usize = 1 << 16;

/// Steps whose median sets the provisional gap limit.
const EARLY: usize = 1024;

#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    count: u64,
    as_gap: bool,
    as_step: bool,
}

/// Counts of the steps by value, with how each value was decided.
#[derive(Debug)]
pub struct Steps {
    gap_s: f64,
    /// A limit known in advance (a second reading), or `None`: provisional from the early steps.
    fixed: Option<f64>,
    early: Vec<f64>,
    counts: Counts,
    /// The last value seen and its not-yet-counted entry (a uniform record hashes nothing).
    last: Option<(u64, Entry)>,
    total: u64,
}

impl Steps {
    /// Steps decided with `--gap` `gap_s` (0 when not given) and, on a second reading, the true
    /// `limit`.
    pub fn new(gap_s: f64, limit: Option<f64>) -> Self {
        Self {
            gap_s,
            fixed: limit,
            early: Vec::new(),
            counts: Counts::default(),
            last: None,
            total: 0,
        }
    }

    fn limit_now(&self) -> f64 {
        if let Some(l) = self.fixed {
            return l;
        }
        let mid = self.early.len() / 2;
        let m = self.early.get(mid).copied().unwrap_or(0.0);
        self.gap_s.max(10.0 * m)
    }

    /// Records the step `d` (> 0) and says whether it is a gap; `None` when the record has too
    /// many distinct steps to count.
    #[inline]
    pub fn push(&mut self, d: f64) -> Option<bool> {
        if self.fixed.is_none() && self.early.len() < EARLY {
            let at = self.early.partition_point(|&x| x < d);
            self.early.insert(at, d);
        }
        let gap = d > self.limit_now();
        let key = d.to_bits();
        let entry = match &mut self.last {
            Some((k, e)) if *k == key => e,
            _ => {
                if let Some((k, e)) = self.last.take() {
                    self.flush(k, e)?;
                }
                &mut self.last.insert((key, Entry::default())).1
            }
        };
        entry.count += 1;
        entry.as_gap |= gap;
        entry.as_step |= !gap;
        self.total += 1;
        Some(gap)
    }

    fn flush(&mut self, k: u64, e: Entry) -> Option<()> {
        if !self.counts.contains_key(&k) && self.counts.len() >= MAX_DISTINCT {
            return None;
        }
        let c = self.counts.entry(k).or_default();
        c.count += e.count;
        c.as_gap |= e.as_gap;
        c.as_step |= e.as_step;
        Some(())
    }

    /// The median step (as [`crate::dataset::median_step`]: the element at rank `len / 2`; 1 with
    /// no step), the true gap limit, and whether every gap was decided as that limit decides it;
    /// `None` when there were too many distinct steps.
    pub fn finish(mut self) -> Option<(f64, f64, bool)> {
        if let Some((k, e)) = self.last.take() {
            self.flush(k, e)?;
        }
        let mut values: Vec<(f64, Entry)> = self
            .counts
            .iter()
            .map(|(&k, &e)| (f64::from_bits(k), e))
            .collect();
        values.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mid = self.total / 2;
        let mut seen = 0;
        let mut median = 1.0;
        for (v, e) in &values {
            seen += e.count;
            if seen > mid {
                median = *v;
                break;
            }
        }
        let limit = self.gap_s.max(10.0 * median);
        let consistent = values
            .iter()
            .all(|(v, e)| if *v > limit { !e.as_step } else { !e.as_gap });
        Some((median, limit, consistent))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::dataset::median_step;

    fn check(time: &[f64], gap_s: f64) {
        let mut s = Steps::new(gap_s, None);
        let mut decided = Vec::new();
        for w in time.windows(2) {
            decided.push(s.push(w[1] - w[0]).unwrap());
        }
        let (median, limit, consistent) = s.finish().unwrap();
        assert_eq!(median, median_step(time));
        let starts = crate::dataset::segments(time, Some(gap_s));
        let truth: Vec<bool> = (1..time.len()).map(|i| starts.contains(&i)).collect();
        assert_eq!(consistent, decided == truth, "limit {limit}");
        let mut again = Steps::new(gap_s, Some(limit));
        let second: Vec<bool> = time
            .windows(2)
            .map(|w| again.push(w[1] - w[0]).unwrap())
            .collect();
        assert_eq!(second, truth);
    }

    #[test]
    fn median_and_gaps_match_the_whole_column_definitions() {
        let uniform: Vec<f64> = (0..5000).map(|i| 100.0 + f64::from(i) * 0.005).collect();
        check(&uniform, 0.0);
        let mut gappy = uniform.clone();
        for (i, t) in gappy.iter_mut().enumerate() {
            *t += 3.0 * (i / 700) as f64;
        }
        check(&gappy, 0.0);
        check(&gappy, 5.0);
        // Early steps long, later short: the provisional limit is wrong and must be caught.
        let mut t = 0.0;
        let mut early_long = Vec::new();
        for i in 0..4000 {
            t += if i < 1500 { 1.0 } else { 0.01 };
            if i == 2500 {
                t += 2.0;
            }
            early_long.push(t);
        }
        check(&early_long, 0.0);
        let mut s = Steps::new(0.0, None);
        for w in early_long.windows(2) {
            s.push(w[1] - w[0]);
        }
        assert!(
            !s.finish().unwrap().2,
            "the 2 s step was decided with the early 1 s median"
        );
    }

    #[test]
    fn too_many_distinct_steps_are_refused() {
        let mut s = Steps::new(0.0, None);
        let mut refused = false;
        for i in 0..=MAX_DISTINCT + 1 {
            refused |= s.push(1.0 + i as f64 * 1e-9).is_none();
        }
        assert!(refused || s.finish().is_none());
    }
}
