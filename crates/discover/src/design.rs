//! The numbers under scoring: binned feature columns and errors, the base design's transform and
//! the small statistics the scores are made of.
//!
//! Why apart: [`crate::base`] (the base model) and [`crate::score`] (each candidate against it)
//! build their design matrices from the same columns the same way.

use crate::error::Result;
use nalgebra::DMatrix;
use tcomp_train::binning::bin_mean;
use tcomp_train::features::{self, FeatureSpec};
use tcomp_train::rbf64::Rbf64;
use tcomp_train::{Dataset, Roles};

/// Feature columns (one `Vec` per feature, one value per bin).
pub(crate) type Columns = Vec<Vec<f64>>;

/// The binned values of the features `exprs` (with `signals`) over `data`.
pub(crate) fn compute_binned(
    signals: &[String],
    exprs: &[String],
    data: &Dataset,
    time_col: &str,
    starts: &[usize],
    b: &[(usize, usize)],
) -> Result<Vec<Vec<f64>>> {
    Ok(compute_per_sample(signals, exprs, data, time_col, starts)?
        .iter()
        .map(|c| bin_mean(c, b))
        .collect())
}

/// The values of the features `exprs` (with `signals`) over `data`, one per sample.
pub(crate) fn compute_per_sample(
    signals: &[String],
    exprs: &[String],
    data: &Dataset,
    time_col: &str,
    starts: &[usize],
) -> Result<Vec<Vec<f64>>> {
    let spec = FeatureSpec {
        signals: signals.to_vec(),
        features: exprs.to_vec(),
    };
    let program = spec.program()?;
    let nf = program.n_features();
    let time = data.time(time_col)?;
    let rows = features::compute(&program, data, time, starts)?;
    Ok((0..nf)
        .map(|k| rows.iter().map(|r| f64::from(r[k])).collect())
        .collect())
}

/// Target − reference over `data`.
pub(crate) fn error_of(data: &Dataset, roles: &Roles) -> Result<Vec<f64>> {
    let target = data.column(&roles.target)?;
    let reference = roles.reference_series(data)?;
    Ok(target.iter().zip(&reference).map(|(a, b)| a - b).collect())
}

/// Base design transform: standardised linear columns and the basis functions of `rbf` (its
/// Gaussians over their masked features, and its steps).
pub(crate) struct Transform {
    pub(crate) mean: Vec<f64>,
    pub(crate) sd: Vec<f64>,
    pub(crate) rbf: Rbf64,
}

impl Transform {
    /// The design matrix of `n` bins: bias, standardised columns, Gaussians.
    pub(crate) fn design(&self, cols: &[Vec<f64>], n: usize) -> DMatrix<f64> {
        let d = cols.len();
        let m = 1 + d + self.rbf.centers.len();
        let mut phi = DMatrix::zeros(n, m);
        let mut x = vec![0.0; d];
        for i in 0..n {
            for (k, c) in cols.iter().enumerate() {
                x[k] = c.get(i).copied().unwrap_or(0.0);
            }
            phi[(i, 0)] = 1.0;
            for k in 0..d {
                phi[(i, 1 + k)] = (x[k] - self.mean[k]) / self.sd[k];
            }
            let z = self.rbf.normalise(&x);
            for j in 0..self.rbf.centers.len() {
                phi[(i, 1 + d + j)] = self.rbf.basis(j, &z);
            }
        }
        phi
    }
}

/// Mean and (population) standard deviation.
pub(crate) fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let m = v.iter().sum::<f64>() / n;
    let s = (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n).sqrt();
    (m, s)
}

/// Robust noise floor from successive differences of binned residuals, within runs of bins.
pub(crate) fn floor_estimate(runs: &[Vec<f64>]) -> f64 {
    let mut d: Vec<f64> = runs
        .iter()
        .flat_map(|r| r.windows(2).map(|w| (w[1] - w[0]).abs()))
        .collect();
    if d.is_empty() {
        return 0.0;
    }
    d.sort_by(f64::total_cmp);
    let med = d[d.len() / 2];
    1.4826 * med / std::f64::consts::SQRT_2
}

/// `a` with the columns `cols` appended.
pub(crate) fn hcat(a: &DMatrix<f64>, cols: &[Vec<f64>]) -> DMatrix<f64> {
    let (n, m) = a.shape();
    let mut out = a.clone().resize_horizontally(m + cols.len(), 0.0);
    for (k, c) in cols.iter().enumerate() {
        for i in 0..n {
            out[(i, m + k)] = c.get(i).copied().unwrap_or(0.0);
        }
    }
    out
}
