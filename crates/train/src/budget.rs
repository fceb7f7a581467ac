//! How much memory a fit will take, estimated from rows × method before anything is allocated.
//!
//! Why: an unaveraged fit of a 100 Hz, 6-hour run (2.2 M rows) needs 7.5 GB with `--select ols`
//! (every candidate center's Gaussian over every row) and about 3 GB with `bayes` (one design matrix
//! per thread), and the process was killed by the allocator half-way through. The estimate lets
//! the trainer refuse up front, say how much would be needed, and suggest the averaging bin that
//! fits. Nothing in the trainer grows with rows²: the largest structures are rows × (centers or
//! candidates), with the candidates capped at [`crate::ols::MAX_CANDIDATES`].

/// The default memory a fit may take: 2 GiB. A developer laptop has 8–16 GB shared with the OS,
/// an editor and a browser; every averaged fit of the test cases and the real-data case needs
/// under 100 MB, and an unaveraged fit of a 1 Hz day-long run (86,400 rows) about 60 MB with
/// `bayes`, so only unaveraged fits of fast, long records (millions of rows) are refused.
pub const DEFAULT_BUDGET_BYTES: u64 = 2 << 30;

/// What a fit's size depends on.
#[derive(Clone, Copy, Debug)]
pub struct Shape {
    /// Rows of the record used (before averaging).
    pub rows: usize,
    /// Training samples the method sees (bins after averaging; `rows` without).
    pub samples: usize,
    /// Features.
    pub features: usize,
    /// Centers asked for (`None`: the method's default or search).
    pub centers: Option<usize>,
    /// Threads that build design matrices at once (`bayes` evaluates settings in parallel).
    pub threads: usize,
}

/// Bytes of a `Vec<Vec<f64>>` of `n` rows of `d` values (header, data and allocator overhead).
pub fn rows_of(n: usize, d: usize) -> f64 {
    n as f64 * (24.0 + 16.0 + 8.0 * d as f64)
}

/// The estimated peak memory of a fit of this shape, bytes, given `method`, what the method
/// itself holds (its `FitMethod::memory`).
pub fn estimate(s: &Shape, method: f64) -> u64 {
    let (n, m, d) = (s.rows as f64, s.samples, s.features);
    let mf = m as f64;
    // Per record row: target − reference, the reference series, the feature vectors (f32, host
    // capacity), one f64 column per feature, and the training-residual run (time, error, residual,
    // temperature).
    let per_row = n * (8.0 + 8.0 + 4.0 * crate::features::F as f64 + 8.0 * d as f64 + 32.0);
    // The training rows the method sees.
    let train = rows_of(m, d) + 8.0 * mf;
    // `method`: what the method itself holds (its design matrices, copies, candidates).
    (per_row + train + method) as u64
}

/// Bytes of a least-squares solve by SVD over `samples` rows and `cols` columns besides the bias:
/// the design, its copy and U.
pub fn lsq(samples: usize, cols: usize) -> f64 {
    3.0 * 8.0 * samples as f64 * (1 + cols) as f64
}

/// Bytes in a human unit.
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.1} GB", b / 1e9)
    } else {
        format!("{:.0} MB", (b / 1e6).max(1.0))
    }
}
