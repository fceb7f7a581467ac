//! Time bins: the rows of a record cut into non-overlapping bins of a fixed length, and a column
//! averaged over each.
//!
//! Why a module of its own: binning is not a feature of the program but what is done with any
//! column afterwards, by the fit (`--average`, on the features and the target), by the metrics'
//! binned figures (`--bin`, on the residual), by the report's figures and by the discovery. One
//! definition of a bin keeps them alike: a bin starts at the first sample, and one that holds less
//! than half the samples a full bin would is left out ([`bins`]); the streaming evaluator
//! (`metrics::online`) cuts at the same boundaries.

/// Non-overlapping bins of `bin_s` seconds starting at the first sample: for each bin that holds at
/// least half the samples a full bin would, its row range `[start, end)`. With `bin_s <= 0` every
/// row is its own bin.
pub fn bins(time: &[f64], bin_s: f64) -> Vec<(usize, usize)> {
    let Some(&t0) = time.first() else {
        return Vec::new();
    };
    if bin_s <= 0.0 {
        return (0..time.len()).map(|i| (i, i + 1)).collect();
    }
    let step = crate::dataset::median_step(time);
    let need = ((bin_s / step) * 0.5).floor().max(1.0) as usize;
    let mut out = Vec::new();
    let mut start = 0;
    let mut cur = 0i64;
    for (i, &t) in time.iter().enumerate() {
        // t ≥ t0 (time is checked monotonic), so truncation is the floor, without a libm call.
        let q = (t - t0) / bin_s;
        let b = if q >= 0.0 { q as i64 } else { q.floor() as i64 };
        if b != cur {
            if i - start >= need {
                out.push((start, i));
            }
            start = i;
            cur = b;
        }
    }
    if time.len() - start >= need {
        out.push((start, time.len()));
    }
    out
}

/// The bin length to use for `wanted_s` on this time axis: `wanted_s` halved until [`bins`] gives
/// at least `min_bins` bins that hold data, but not below two sample steps. Continuous records keep
/// `wanted_s`; bursty ones (a few seconds of data every few minutes) get bins that fit their bursts.
pub fn adaptive_bin(time: &[f64], wanted_s: f64, min_bins: usize) -> f64 {
    let floor = 2.0 * crate::dataset::median_step(time);
    let mut bin_s = wanted_s;
    while bins(time, bin_s).len() < min_bins && bin_s / 2.0 >= floor {
        bin_s /= 2.0;
    }
    bin_s
}

/// Mean of `v` over each bin.
pub fn bin_mean(v: &[f64], bins: &[(usize, usize)]) -> Vec<f64> {
    bins.iter()
        .map(|&(a, b)| {
            let s = v.get(a..b).unwrap_or(&[]);
            s.iter().sum::<f64>() / s.len().max(1) as f64
        })
        .collect()
}
