//! The "traditional" RBF of both seed papers: k-means centers, one width from the classic heuristic
//! `σ = d_max/√(2M)` (d_max the largest distance between centers), weights by least squares on the
//! mean-square error alone.
//!
//! Why keep it: it is the baseline the papers improve on, and the comparison (`bayes` generalises
//! better than `mse` with many centers) is one of the results this crate must reproduce.

use crate::error::TrainError;
use crate::kmeans::{dist2, kmeans};
use crate::rbf64::{Rbf64, design, least_squares, mean_std, normalise_rows, split_weights};

/// Width heuristic `σ = d_max/√(2M)`; 1 with fewer than two centers.
pub fn width_heuristic(centers: &[Vec<f64>]) -> f64 {
    let mut dmax: f64 = 0.0;
    for (i, a) in centers.iter().enumerate() {
        for b in centers.iter().skip(i + 1) {
            dmax = dmax.max(dist2(a, b).sqrt());
        }
    }
    if centers.len() < 2 || dmax <= 0.0 {
        1.0
    } else {
        dmax / (2.0 * centers.len() as f64).sqrt()
    }
}

/// Fits `m` k-means centers, the width heuristic and least-squares weights (bias, no linear term).
pub fn fit(x: &[Vec<f64>], y: &[f64], m: usize, seed: u64) -> Result<Rbf64, TrainError> {
    let (xm, xs) = mean_std(x);
    let scale: Vec<f64> = xs.iter().map(|s| 1.0 / s.max(1e-300)).collect();
    let z = normalise_rows(x, &xm, &scale);
    let centers = kmeans(&z, m, seed);
    let sigma = width_heuristic(&centers);
    let gamma = vec![1.0 / (2.0 * sigma * sigma); centers.len()];
    let phi = design(&z, false, &centers, &gamma);
    let w = least_squares(&phi, y)?;
    let (bias, _, weights) = split_weights(&w, 0);
    Ok(Rbf64 {
        linear: vec![0.0; xm.len()],
        offset: xm,
        scale,
        centers,
        gamma,
        weights,
        bias,
    })
}
