//! The time steps of a streamed record: their exact median without holding them, and the gap
//! decisions checked against it.
//!
//! Why: a gap is a step longer than `max(--gap, 10 × median step)` ([`crate::dataset::stretch_starts`]),
//! and the median is a property of the whole record, known only at its end, while the compensator
//! must be told of a gap before the sample after it. A logger's clock takes few distinct steps
//! (a fixed rate printed to fixed decimals differs only in the last bits of the parsed time), so
//! the steps are counted by value: the median is then exact, in memory bounded by the number of
//! distinct steps, not by the length. Gaps are decided on the way with the median of the first
//! [`EARLY`] steps, each distinct step remembering how it was decided; at the end every decision is
//! checked against the true limit, and a record where one differs is read again with the true
//! median (the caller's job). A jittery clock with more than [`MAX_DISTINCT`] distinct steps has
//! its median found by [`radix_median`] instead: four readings of the time column, 2¹⁶ counters.

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

/// Distinct step values counted before the median is left to [`radix_median`].
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
    /// The median known in advance (a later reading), or `None`: the limit is provisional, from
    /// the early steps, and the steps are counted.
    known: Option<f64>,
    early: Vec<f64>,
    counts: Counts,
    /// The last value seen and its not-yet-counted entry (a uniform record hashes nothing).
    last: Option<(u64, Entry)>,
    total: u64,
}

impl Steps {
    /// Steps decided with `--gap` `gap_s` (0 when not given) and, on a later reading, the true
    /// `median` step (nothing is counted then).
    pub fn new(gap_s: f64, median: Option<f64>) -> Self {
        Self {
            gap_s,
            known: median,
            early: Vec::new(),
            counts: Counts::default(),
            last: None,
            total: 0,
        }
    }

    fn limit_now(&self) -> f64 {
        let m = match self.known {
            Some(m) => m,
            None => self.early.get(self.early.len() / 2).copied().unwrap_or(0.0),
        };
        self.gap_s.max(10.0 * m)
    }

    /// Records the step `d` (> 0) and says whether it is a gap; `None` when the record has too
    /// many distinct steps to count.
    #[inline]
    pub fn push(&mut self, d: f64) -> Option<bool> {
        if self.known.is_some() {
            return Some(d > self.limit_now());
        }
        if self.early.len() < EARLY {
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
        if let Some(m) = self.known {
            return Some((m, self.gap_s.max(10.0 * m), true));
        }
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

/// Bits of a step's pattern settled by each reading of [`radix_median`].
const RADIX_BITS: u32 = 16;

/// The exact median step (rank `len / 2`, as [`crate::dataset::median_step`]) of a record whose
/// steps are too many distinct values to count: a radix selection over the bits of the steps
/// (positive doubles order as their bit patterns do), 16 bits a reading, so four readings and
/// 2¹⁶ counters whatever the length. `read` feeds every step of the record to its argument once
/// per call; `None` when a reading fails. With no step the median is 1, as `median_step` says.
pub fn radix_median(mut read: impl FnMut(&mut dyn FnMut(f64)) -> Option<()>) -> Option<f64> {
    let mut prefix = 0u64;
    let mut rank: Option<u64> = None;
    for round in 0..64 / RADIX_BITS {
        let settled = round * RADIX_BITS;
        let shift = 64 - settled - RADIX_BITS;
        let mut counts = vec![0u64; 1 << RADIX_BITS];
        read(&mut |d: f64| {
            let b = d.to_bits();
            if settled == 0 || b >> (64 - settled) == prefix {
                let k = ((b >> shift) & ((1 << RADIX_BITS) - 1)) as usize;
                if let Some(c) = counts.get_mut(k) {
                    *c += 1;
                }
            }
        })?;
        let mut r = match rank {
            Some(r) => r,
            None => {
                let total: u64 = counts.iter().sum();
                if total == 0 {
                    return Some(1.0);
                }
                total / 2
            }
        };
        let mut digit = 0u64;
        for (k, &c) in counts.iter().enumerate() {
            if r < c {
                digit = k as u64;
                break;
            }
            r -= c;
        }
        rank = Some(r);
        prefix = (prefix << RADIX_BITS) | digit;
    }
    Some(f64::from_bits(prefix))
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
        let starts = crate::dataset::stretch_starts(time, Some(gap_s));
        let truth: Vec<bool> = (1..time.len()).map(|i| starts.contains(&i)).collect();
        assert_eq!(consistent, decided == truth, "limit {limit}");
        let mut again = Steps::new(gap_s, Some(median));
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
    fn radix_selection_finds_the_median_of_jittery_steps() {
        let mut state = 7u64;
        let mut time = vec![0.0];
        for n in [1usize, 2, 3, 1000, 20_001] {
            time.truncate(1);
            for _ in 0..n {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                let last = *time.last().unwrap();
                time.push(last + 0.01 + 0.004 * (u - 0.5));
            }
            let steps: Vec<f64> = time.windows(2).map(|w| w[1] - w[0]).collect();
            let m = radix_median(|f: &mut dyn FnMut(f64)| {
                steps.iter().for_each(|&d| f(d));
                Some(())
            })
            .unwrap();
            assert_eq!(m, median_step(&time), "{n} steps");
        }
        assert_eq!(radix_median(|_: &mut dyn FnMut(f64)| Some(())), Some(1.0));
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
