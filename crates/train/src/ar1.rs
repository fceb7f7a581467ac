//! Evidence under AR(1) noise: a series of bin means whose noise is serially correlated, judged
//! with the correlation modelled instead of ignored.
//!
//! Why: bin means of a residual drift (bias instability, a thermometer's lag, a Gauss–Markov
//! wander). Evidence that treats them as independent credits any slow column — a long lag, a
//! warm-up — with explaining the drift, and calls it an effect. Under AR(1) noise the targets and
//! the basis are whitened (Prais–Winsten: `v′ₜ = vₜ − ρ·vₜ₋₁`, the first scaled by `√(1 − ρ²)`) and
//! the evidence of the data as given is `ln p(y) = ln p(y′) + ½ ln(1 − ρ²)` (the whitening's
//! Jacobian); `ρ` is a hyperparameter like α and β, the one of [`RHO_GRID`] with the most evidence.
//!
//! A record with gaps is several series: the noise after a gap is not the continuation of the
//! noise before it (the drift went on unseen for the gap's length). So each stretch is whitened on
//! its own, its first bin scaled like the series' first, and the Jacobian counts once per stretch.
//! Whitening across a gap would read the jump between the stretches as one innovation, and credit
//! any term that happens to change at the seam — a step at the two temperatures on either side of
//! a held-out block — with explaining it.
//! The additive structure search ([`crate::bayes`]) and the discovery's placebo acceptance use it.

use crate::evidence::{GroupFit, Settings, fit_with};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// The AR(1) coefficients of the noise compared by the evidence (bins in time order). In 100 s
/// bins a Gauss–Markov drift of correlation time τ has `ρ = e^(−100 s/τ)`: 0.98 is τ ≈ 83 min,
/// 0.99 ≈ 2.8 h, 0.995 ≈ 5.5 h — the hours of a gyro's or accelerometer's bias instability. A grid
/// that stopped at 0.98 held such a drift to 83 min, left its slow power unmodelled, and credited a
/// slow column with explaining it: on a 3-hour drift the evidence sat at the grid's edge and a
/// curvature in T passed the placebo test that a ρ of 0.995 rejects.
pub const RHO_GRID: [f64; 10] = [0.0, 0.3, 0.5, 0.65, 0.8, 0.9, 0.95, 0.98, 0.99, 0.995];

/// Prais–Winsten whitening of a series under AR(1) coefficient `rho`, in place:
/// `v'ₜ = vₜ − ρ·vₜ₋₁`, the first of each stretch scaled by `√(1 − ρ²)`. `starts`: the indices
/// (ascending) where a stretch after a gap begins; empty for one stretch.
pub fn whiten(v: &mut [f64], rho: f64, starts: &[usize]) {
    if rho == 0.0 {
        return;
    }
    let first = (1.0 - rho * rho).sqrt();
    for t in (1..v.len()).rev() {
        if starts.binary_search(&t).is_ok() {
            v[t] *= first;
        } else {
            v[t] -= rho * v[t - 1];
        }
    }
    if let Some(f) = v.first_mut() {
        *f *= first;
    }
}

/// Every column of `m` whitened by [`whiten`].
pub fn whitened(m: &DMatrix<f64>, rho: f64, starts: &[usize]) -> DMatrix<f64> {
    let mut m = m.clone();
    let n = m.nrows().max(1);
    for col in m.as_mut_slice().chunks_exact_mut(n) {
        whiten(col, rho, starts);
    }
    m
}

/// The number of stretches of an `n`-long series that `starts` splits (see [`whiten`]).
fn stretches(n: usize, starts: &[usize]) -> usize {
    1 + starts.iter().filter(|&&s| s > 0 && s < n).count()
}

/// The evidence fit of `y ≈ Φw` under AR(1) noise of coefficient `rho` in each stretch of
/// `starts` (with `start`, α per group and β, and the trainer's settings), and its log evidence of
/// the data as given (the whitening's Jacobian `½ ln(1 − ρ²)` per stretch included).
pub fn fit(
    phi: &DMatrix<f64>,
    y: &DVector<f64>,
    groups: &[usize],
    start: (&[f64], f64),
    rho: f64,
    starts: &[usize],
) -> Option<(GroupFit, f64)> {
    let p = whitened(phi, rho, starts);
    let mut yw = y.clone();
    whiten(yw.as_mut_slice(), rho, starts);
    let f = fit_with(&p, &yw, groups, Some(start), &Settings::TRAINER)?;
    let ev = f.log_evidence + 0.5 * (1.0 - rho * rho).ln() * stretches(y.len(), starts) as f64;
    Some((f, ev))
}

/// [`fit`] at every `ρ` of [`RHO_GRID`] up to `rho_max`: the noise's serial correlation is a
/// hyperparameter like α and β, chosen by the evidence for each model; returns the best, its log
/// evidence and its `ρ`.
pub fn fit_best_rho(
    phi: &DMatrix<f64>,
    y: &DVector<f64>,
    groups: &[usize],
    start: (&[f64], f64),
    rho_max: f64,
    starts: &[usize],
) -> Option<(GroupFit, f64, f64)> {
    RHO_GRID
        .iter()
        .copied()
        .filter(|r| *r <= rho_max)
        .collect::<Vec<f64>>()
        .par_iter()
        .filter_map(|&r| fit(phi, y, groups, start, r, starts).map(|(f, e)| (f, e, r)))
        .collect::<Vec<_>>()
        .into_iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// Whitening an AR(1) series with its own coefficient leaves its innovations.
    #[test]
    fn whitening_recovers_the_innovations() {
        let e = [0.3, -1.2, 0.7, 0.1, -0.4];
        let rho: f64 = 0.8;
        let mut v = Vec::new();
        let mut prev = 0.0;
        for (i, x) in e.iter().enumerate() {
            let cur = if i == 0 {
                *x / (1.0 - rho * rho).sqrt()
            } else {
                rho * prev + x
            };
            v.push(cur);
            prev = cur;
        }
        whiten(&mut v, rho, &[]);
        for (a, b) in v.iter().zip(&e) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
    }

    /// Across a gap each stretch is whitened on its own: a series of two AR(1) stretches whitened
    /// with the gap given leaves the innovations of both, where whitening it as one series turns
    /// the jump at the seam into an innovation of its own.
    #[test]
    fn each_stretch_is_whitened_on_its_own() {
        let rho: f64 = 0.8;
        let e = [0.3, -1.2, 0.7, 0.1, -0.4, 0.9];
        let mut v = Vec::new();
        let mut prev = 0.0;
        for (i, x) in e.iter().enumerate() {
            // A second stretch from index 3, far from where the first one ended.
            let cur = if i == 0 || i == 3 {
                *x / (1.0 - rho * rho).sqrt() + if i == 3 { 50.0 } else { 0.0 }
            } else {
                rho * prev + x
            };
            v.push(cur);
            prev = cur;
        }
        let mut split = v.clone();
        whiten(&mut split, rho, &[3]);
        let mut one = v.clone();
        whiten(&mut one, rho, &[]);
        for (i, (a, b)) in split.iter().zip(&e).enumerate() {
            let want = if i == 3 {
                b + 50.0 * (1.0 - rho * rho).sqrt()
            } else {
                *b
            };
            assert!((a - want).abs() < 1e-9, "{i}: {a} vs {want}");
        }
        assert!((one[3] - split[3]).abs() > 1.0);
        assert_eq!(stretches(6, &[3]), 2);
        assert_eq!(stretches(6, &[0, 6, 9]), 1);
    }

    /// A strongly correlated noise is given its ρ by the evidence.
    #[test]
    fn evidence_chooses_the_noise_correlation() {
        let n = 400;
        let mut s = 0x2545_F491_4F6C_DD1Du64;
        let mut y = Vec::with_capacity(n);
        let mut v = 0.0;
        for _ in 0..n {
            let mut u = 0.0;
            for _ in 0..12 {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                u += (s >> 11) as f64 / (1u64 << 53) as f64;
            }
            v = 0.9 * v + (u - 6.0);
            y.push(v);
        }
        let phi = DMatrix::from_element(n, 1, 1.0);
        let (_, _, rho) =
            fit_best_rho(&phi, &DVector::from_vec(y), &[0], (&[1e-8], 1.0), 0.99, &[]).unwrap();
        assert!((0.8..=0.95).contains(&rho), "ρ = {rho}");
    }
}
