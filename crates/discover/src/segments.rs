//! Where a model fails: residual figures per segment of the run (warm-up, holds, heating and cooling
//! ramps, temperature bands) and the worst intervals with their times.
//!
//! Why: one overall residual averages the failure away. A missing rate term shows on ramps, a
//! missing hysteresis as opposite signs on heating and cooling, a lagged element just after each
//! ramp ends, a warm-up transient at the start; locating the failure is the first half of naming it.
//! Holds and ramps come from the trainer's `segment_table` (so `eval`, `compare` and `diagnose`
//! cut a run the same way); warm-up and bands are added here.

use serde::Serialize;
use tcomp_train::binning::{bin_mean, bins};
use tcomp_train::metrics::{self, Run};

/// Length of the warm-up segment at the start of a run (s).
pub const WARMUP_S: f64 = 1200.0;
/// Number of temperature bands.
pub const BANDS: usize = 4;
/// Number of worst intervals reported.
pub const WORST: usize = 5;

/// Residual figures of one segment.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SegmentRow {
    /// "warm-up", "hold", "heating", "cooling" or "band".
    pub kind: String,
    /// Human label, e.g. "heating 3.0 °/min" or "band 20…40 °".
    pub label: String,
    /// Start time (s).
    pub start_s: f64,
    /// End time (s).
    pub end_s: f64,
    /// Samples.
    pub samples: usize,
    /// Mean temperature.
    pub mean_temperature: f64,
    /// Mean temperature rate (per minute); 0 for bands.
    pub rate_per_min: f64,
    /// Std of the error before compensation.
    pub raw_std: f64,
    /// Std of the residual.
    pub residual_std: f64,
    /// Mean of the residual (a systematic offset in this segment).
    pub residual_mean: f64,
}

/// One of the worst intervals.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Interval {
    /// Start time (s).
    pub start_s: f64,
    /// End time (s).
    pub end_s: f64,
    /// Mean residual over the interval.
    pub residual_mean: f64,
    /// RMS residual over the interval.
    pub residual_rms: f64,
    /// Mean temperature.
    pub temperature: f64,
    /// Temperature rate (per minute).
    pub rate_per_min: f64,
    /// Segment kind the interval falls in.
    pub during: String,
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn row(run: &Run, kind: &str, label: String, s: usize, e: usize, rate: f64) -> SegmentRow {
    let sl = |v: &[f64]| v.get(s..e).unwrap_or(&[]).to_vec();
    let res = sl(&run.residual);
    SegmentRow {
        kind: kind.into(),
        label,
        start_s: run.time.get(s).copied().unwrap_or(0.0),
        end_s: run.time.get(e.saturating_sub(1)).copied().unwrap_or(0.0),
        samples: e.saturating_sub(s),
        mean_temperature: mean(&sl(&run.temperature)),
        rate_per_min: rate,
        raw_std: metrics::std(&sl(&run.error)),
        residual_std: metrics::std(&res),
        residual_mean: mean(&res),
    }
}

fn index_at(time: &[f64], t: f64) -> usize {
    time.partition_point(|&x| x < t)
}

/// The segment table of a run: warm-up, holds and ramps, temperature bands.
pub fn table(run: &Run) -> Vec<SegmentRow> {
    let mut out = Vec::new();
    let (Some(&t0), Some(&t1)) = (run.time.first(), run.time.last()) else {
        return out;
    };
    if t1 - t0 > 3.0 * WARMUP_S {
        let e = index_at(&run.time, t0 + WARMUP_S);
        out.push(row(
            run,
            "warm-up",
            format!("warm-up (first {} min)", WARMUP_S / 60.0),
            0,
            e,
            0.0,
        ));
    }
    for s in metrics::segment_table(run) {
        let a = index_at(&run.time, s.start_s);
        let b = a + s.samples;
        let label = if s.kind == "hold" {
            format!(
                "hold at {:.1}°",
                mean(run.temperature.get(a..b).unwrap_or(&[]))
            )
        } else {
            format!("{} {:+.2}°/min", s.kind, s.rate_per_min)
        };
        out.push(row(run, &s.kind, label, a, b, s.rate_per_min));
    }
    let (lo, hi) = run
        .temperature
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(*v), h.max(*v))
        });
    if hi - lo > 1.0 {
        let w = (hi - lo) / BANDS as f64;
        for k in 0..BANDS {
            let (a, b) = (lo + k as f64 * w, lo + (k + 1) as f64 * w);
            let idx: Vec<usize> = (0..run.temperature.len())
                .filter(|&i| {
                    let t = run.temperature.get(i).copied().unwrap_or(f64::NAN);
                    t >= a && (t < b || k + 1 == BANDS)
                })
                .collect();
            if idx.is_empty() {
                continue;
            }
            let pick =
                |v: &[f64]| -> Vec<f64> { idx.iter().filter_map(|&i| v.get(i).copied()).collect() };
            let res = pick(&run.residual);
            out.push(SegmentRow {
                kind: "band".into(),
                label: format!("band {a:.1}…{b:.1}°"),
                start_s: run.time.get(idx[0]).copied().unwrap_or(0.0),
                end_s: idx
                    .last()
                    .and_then(|&i| run.time.get(i))
                    .copied()
                    .unwrap_or(0.0),
                samples: idx.len(),
                mean_temperature: mean(&pick(&run.temperature)),
                rate_per_min: 0.0,
                raw_std: metrics::std(&pick(&run.error)),
                residual_std: metrics::std(&res),
                residual_mean: mean(&res),
            });
        }
    }
    out
}

/// The worst intervals: the run cut into intervals of `interval_s` (default: 1/24 of the run, at
/// least 300 s), ranked by |mean residual| (a systematic error the model leaves, not noise).
pub fn worst_intervals(run: &Run, segments: &[SegmentRow]) -> Vec<Interval> {
    let (Some(&t0), Some(&t1)) = (run.time.first(), run.time.last()) else {
        return Vec::new();
    };
    let len = ((t1 - t0) / 24.0).max(300.0);
    let b = bins(&run.time, len);
    let rm = bin_mean(&run.residual, &b);
    let tm = bin_mean(&run.temperature, &b);
    let mut iv: Vec<Interval> = b
        .iter()
        .enumerate()
        .map(|(k, &(s, e))| {
            let r = run.residual.get(s..e).unwrap_or(&[]);
            let ts = run.time.get(s).copied().unwrap_or(0.0);
            let te = run.time.get(e.saturating_sub(1)).copied().unwrap_or(0.0);
            let dtemp = run
                .temperature
                .get(e.saturating_sub(1))
                .copied()
                .unwrap_or(0.0)
                - run.temperature.get(s).copied().unwrap_or(0.0);
            let mid = 0.5 * (ts + te);
            let during = segments
                .iter()
                .filter(|g| g.kind != "band" && g.kind != "warm-up")
                .find(|g| g.start_s <= mid && mid <= g.end_s)
                .map_or_else(String::new, |g| g.label.clone());
            Interval {
                start_s: ts,
                end_s: te,
                residual_mean: rm.get(k).copied().unwrap_or(0.0),
                residual_rms: (r.iter().map(|x| x * x).sum::<f64>() / r.len().max(1) as f64).sqrt(),
                temperature: tm.get(k).copied().unwrap_or(0.0),
                rate_per_min: if te > ts {
                    60.0 * dtemp / (te - ts)
                } else {
                    0.0
                },
                during,
            }
        })
        .collect();
    // Relative to the run's mean residual: a constant offset is not a located failure.
    let m = mean(&run.residual);
    iv.sort_by(|a, b| {
        (b.residual_mean - m)
            .abs()
            .total_cmp(&(a.residual_mean - m).abs())
    });
    iv.truncate(WORST);
    iv
}
