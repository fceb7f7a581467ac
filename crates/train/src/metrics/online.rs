//! Every figure of [`EvalReport`] accumulated one sample at a time.
//!
//! Why: a 6-hour 200 Hz log is 4.3 M rows; holding its time, error, residual and temperature
//! columns to compute a std afterwards costs memory that grows with the log, while every figure
//! needs only running moments (Welford's mean and M2, the sum of squares, the largest |value|) and
//! a short summary per time bin (O(bins), not O(rows)): the `--bin` bins for the binned figures
//! and 60 s bins for the holds/ramps table. Both evaluation paths — the in-memory [`super::report`]
//! over a [`super::Run`] and the streaming [`crate::long_log`] reader — feed this one accumulator in
//! row order, so the two cannot drift: they give the same report bit for bit.
//!
//! A bin closes when the time passes its end; whether it holds enough samples to count (half a
//! full bin, from the median time step) is decided at [`Accumulator::finish`], when the median is
//! known, exactly as [`crate::binning::bins`] decides it over a whole column.

use super::{Binned, EvalReport, HOLD_RATE_PER_MIN, SegmentStats, improvement, std};

/// Running moments of one series: count, mean and M2 (Welford), sum of squares, largest |x|.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Moments {
    n: usize,
    mean: f64,
    m2: f64,
    sum_sq: f64,
    max_abs: f64,
}

impl Moments {
    /// Adds one value.
    #[inline]
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
        self.sum_sq += x * x;
        self.max_abs = self.max_abs.max(x.abs());
    }

    /// Adds the values summarised by `o` (Chan et al.'s pairwise update).
    pub fn merge(&mut self, o: &Self) {
        if o.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *o;
            return;
        }
        let (na, nb) = (self.n as f64, o.n as f64);
        let n = na + nb;
        let d = o.mean - self.mean;
        self.mean += d * nb / n;
        self.m2 += o.m2 + d * d * na * nb / n;
        self.n += o.n;
        self.sum_sq += o.sum_sq;
        self.max_abs = self.max_abs.max(o.max_abs);
    }

    /// Values added.
    pub fn count(&self) -> usize {
        self.n
    }

    /// Population standard deviation (0 with no values).
    pub fn std(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            (self.m2.max(0.0) / self.n as f64).sqrt()
        }
    }

    /// Mean square (0 with no values).
    pub fn msd(&self) -> f64 {
        self.sum_sq / self.n.max(1) as f64
    }

    /// Largest |value| (0 with no values).
    pub fn max_abs(&self) -> f64 {
        self.max_abs
    }
}

/// One time bin's summary.
#[derive(Clone, Copy, Debug, Default)]
struct Bin {
    n: usize,
    t_first: f64,
    t_last: f64,
    sum_t: f64,
    sum_temp: f64,
    sum_e: f64,
    sum_r: f64,
    e: Moments,
    r: Moments,
}

/// Non-overlapping bins of `width` seconds from the first sample (every row its own bin when
/// `width <= 0`), as [`crate::binning::bins`] cuts them; all bins are kept, full or not.
#[derive(Clone, Debug)]
struct Binner {
    width: f64,
    /// Whether the per-bin moments are kept (the segments table needs them, the binned figures
    /// only the sums).
    moments: bool,
    t0: Option<f64>,
    cur: i64,
    rows: i64,
    open: Bin,
    closed: Vec<Bin>,
}

impl Binner {
    fn new(width: f64, moments: bool) -> Self {
        Self {
            width,
            moments,
            t0: None,
            cur: 0,
            rows: 0,
            open: Bin::default(),
            closed: Vec::new(),
        }
    }

    #[inline]
    fn push(&mut self, t: f64, e: f64, r: f64, temp: f64) {
        let t0 = *self.t0.get_or_insert(t);
        let b = if self.width <= 0.0 {
            self.rows
        } else {
            // t ≥ t0 (time is checked monotonic), so truncation is the floor.
            let q = (t - t0) / self.width;
            if q >= 0.0 { q as i64 } else { q.floor() as i64 }
        };
        self.rows += 1;
        if b != self.cur {
            self.closed.push(std::mem::take(&mut self.open));
            self.cur = b;
        }
        let o = &mut self.open;
        if o.n == 0 {
            o.t_first = t;
        }
        o.n += 1;
        o.t_last = t;
        o.sum_e += e;
        o.sum_r += r;
        if self.moments {
            o.sum_t += t;
            o.sum_temp += temp;
            o.e.push(e);
            o.r.push(r);
        }
    }

    /// All bins, the open one last.
    fn finish(mut self) -> Vec<Bin> {
        if self.open.n > 0 {
            self.closed.push(self.open);
        }
        self.closed
    }
}

/// Samples a bin of `width` s must hold to count: half a full bin at the median step `step`.
fn need(width: f64, step: f64) -> usize {
    if width <= 0.0 {
        1
    } else {
        ((width / step) * 0.5).floor().max(1.0) as usize
    }
}

/// Counts that come from the model run rather than from the residuals.
#[derive(Clone, Copy, Debug, Default)]
pub struct Flags {
    /// Samples flagged out of the trained range.
    pub out_of_range: usize,
    /// Samples flagged as input or model faults.
    pub faults: usize,
    /// Gaps in the record.
    pub gaps: usize,
    /// Gaps that restarted the feature state.
    pub restarted: usize,
}

/// Accumulates an [`EvalReport`] one sample at a time, in row order.
#[derive(Clone, Debug)]
pub struct Accumulator {
    bin_s: f64,
    err: Moments,
    res: Moments,
    bins: Binner,
    minutes: Binner,
}

impl Accumulator {
    /// An empty accumulator for binned figures over `bin_s` seconds.
    pub fn new(bin_s: f64) -> Self {
        Self {
            bin_s,
            err: Moments::default(),
            res: Moments::default(),
            bins: Binner::new(bin_s, false),
            minutes: Binner::new(60.0, true),
        }
    }

    /// Adds one sample: time (s), error (target − reference), residual (compensated − reference)
    /// and the temperature used for segment detection.
    #[inline]
    pub fn push(&mut self, t: f64, error: f64, residual: f64, temperature: f64) {
        self.err.push(error);
        self.res.push(residual);
        self.bins.push(t, error, residual, temperature);
        self.minutes.push(t, error, residual, temperature);
    }

    /// Samples added.
    pub fn samples(&self) -> usize {
        self.err.count()
    }

    /// The report, given the median time step of the samples (which decides which bins hold
    /// enough samples to count) and the run's flags.
    pub fn finish(self, median_step: f64, flags: Flags) -> EvalReport {
        let samples = self.err.count();
        let need_bin = need(self.bin_s, median_step);
        let kept: Vec<Bin> = self
            .bins
            .finish()
            .into_iter()
            .filter(|b| b.n >= need_bin)
            .collect();
        let mean = |s: f64, b: &Bin| s / b.n.max(1) as f64;
        let be: Vec<f64> = kept.iter().map(|b| mean(b.sum_e, b)).collect();
        let br: Vec<f64> = kept.iter().map(|b| mean(b.sum_r, b)).collect();
        let (braw, bres) = (std(&be), std(&br));
        let (raw_std, residual_std) = (self.err.std(), self.res.std());
        EvalReport {
            samples,
            raw_std,
            residual_std,
            improvement_pct: improvement(raw_std, residual_std),
            raw_rms: self.err.msd().sqrt(),
            residual_rms: self.res.msd().sqrt(),
            max_abs_residual: self.res.max_abs(),
            msd_before: self.err.msd(),
            msd_after: self.res.msd(),
            binned: Binned {
                seconds: self.bin_s,
                bins: kept.len(),
                raw_std: braw,
                residual_std: bres,
                improvement_pct: improvement(braw, bres),
            },
            segments: segments(&self.minutes.finish(), need(60.0, median_step)),
            out_of_range_pct: 100.0 * flags.out_of_range as f64 / samples.max(1) as f64,
            input_faults: flags.faults,
            gaps: flags.gaps,
            gaps_restarted: flags.restarted,
            notes: Vec::new(),
        }
    }
}

/// Holds, heating and cooling ramps from the 60 s bins `raw` (all of them, full or not): the
/// temperature rate by central differences over the bins holding at least `need` samples, runs
/// of one kind shorter than 5 bins merged into the previous one; each segment's rows run from its
/// first counted bin to the next segment's (the last to the end), partial bins between included.
fn segments(raw: &[Bin], need: usize) -> Vec<SegmentStats> {
    let kept: Vec<usize> = (0..raw.len())
        .filter(|&i| raw.get(i).is_some_and(|b| b.n >= need))
        .collect();
    let n = kept.len();
    if n < 3 {
        return Vec::new();
    }
    let at = |k: usize| {
        raw.get(kept.get(k).copied().unwrap_or(0))
            .copied()
            .unwrap_or_default()
    };
    let tm: Vec<f64> = (0..n)
        .map(|k| at(k).sum_temp / at(k).n.max(1) as f64)
        .collect();
    let ts: Vec<f64> = (0..n)
        .map(|k| at(k).sum_t / at(k).n.max(1) as f64)
        .collect();
    let rate: Vec<f64> = (0..n)
        .map(|i| {
            let (a, c) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let dt = ts.get(c).copied().unwrap_or(0.0) - ts.get(a).copied().unwrap_or(0.0);
            let dtemp = tm.get(c).copied().unwrap_or(0.0) - tm.get(a).copied().unwrap_or(0.0);
            if dt > 0.0 { 60.0 * dtemp / dt } else { 0.0 }
        })
        .collect();
    merged_runs(&rate)
        .iter()
        .map(|&(k, b0, b1)| {
            let first = kept.get(b0).copied().unwrap_or(0);
            let end = if b1 >= n {
                raw.len()
            } else {
                kept.get(b1).copied().unwrap_or(raw.len())
            };
            let span = raw.get(first..end).unwrap_or(&[]);
            let (mut e, mut r) = (Moments::default(), Moments::default());
            for b in span {
                e.merge(&b.e);
                r.merge(&b.r);
            }
            let rates = rate.get(b0..b1).unwrap_or(&[]);
            SegmentStats {
                kind: match k {
                    1 => "heating",
                    -1 => "cooling",
                    _ => "hold",
                }
                .to_string(),
                start_s: span.first().map_or(0.0, |b| b.t_first),
                end_s: span.last().map_or(0.0, |b| b.t_last),
                samples: e.count(),
                rate_per_min: rates.iter().sum::<f64>() / rates.len().max(1) as f64,
                raw_std: e.std(),
                residual_std: r.std(),
            }
        })
        .collect()
}

/// Runs of one kind (heating 1, hold 0, cooling −1) over the bins' rates, as `(kind, first bin,
/// last bin exclusive)`, a run shorter than 5 bins merged into its neighbour.
fn merged_runs(rate: &[f64]) -> Vec<(i8, usize, usize)> {
    let kind = |r: f64| -> i8 {
        if r > HOLD_RATE_PER_MIN {
            1
        } else if r < -HOLD_RATE_PER_MIN {
            -1
        } else {
            0
        }
    };
    let mut runs: Vec<(i8, usize, usize)> = Vec::new();
    for (i, r) in rate.iter().enumerate() {
        let k = kind(*r);
        match runs.last_mut() {
            Some(last) if last.0 == k => last.2 = i + 1,
            _ => runs.push((k, i, i + 1)),
        }
    }
    let mut merged: Vec<(i8, usize, usize)> = Vec::new();
    for r in runs {
        match merged.last_mut() {
            Some(last) if last.0 == r.0 || r.2 - r.1 < 5 => last.2 = r.2,
            Some(last) if last.2 - last.1 < 5 => {
                last.0 = r.0;
                last.2 = r.2;
            }
            _ => merged.push(r),
        }
    }
    merged
}
