//! Evidence under AR(1) noise: a series of bin means whose noise is serially correlated, judged
//! with the correlation modelled instead of ignored.
//!
//! Why: bin means of a residual drift (bias instability, a thermometer's lag, a Gauss–Markov
//! wander). Evidence that treats them as independent credits any slow column — a long lag, a
//! warm-up — with explaining the drift, and calls it an effect. Under AR(1) noise the targets and
//! the basis are whitened (Prais–Winsten: `v′ₜ = vₜ − ρ·vₜ₋₁`, the first scaled by `√(1 − ρ²)`) and
//! the evidence of the data as given is `ln p(y) = ln p(y′) + ½ ln(1 − ρ²)` (the whitening's
//! Jacobian); `ρ` is a hyperparameter like α and β, the one of [`RHO_GRID`] with the most evidence.
//! The additive structure search ([`crate::bayes`]) and the discovery's placebo acceptance use it.

use crate::evidence::{GroupFit, Settings, fit_with};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// The AR(1) coefficients of the noise compared by the evidence (bins in time order).
pub const RHO_GRID: [f64; 8] = [0.0, 0.3, 0.5, 0.65, 0.8, 0.9, 0.95, 0.98];

/// Prais–Winsten whitening of one series under AR(1) coefficient `rho`, in place:
/// `v'ₜ = vₜ − ρ·vₜ₋₁`, the first scaled by `√(1 − ρ²)`.
pub fn whiten(v: &mut [f64], rho: f64) {
    if rho == 0.0 {
        return;
    }
    for t in (1..v.len()).rev() {
        v[t] -= rho * v[t - 1];
    }
    if let Some(f) = v.first_mut() {
        *f *= (1.0 - rho * rho).sqrt();
    }
}

/// Every column of `m` whitened by [`whiten`].
pub fn whitened(m: &DMatrix<f64>, rho: f64) -> DMatrix<f64> {
    let mut m = m.clone();
    let n = m.nrows().max(1);
    for col in m.as_mut_slice().chunks_exact_mut(n) {
        whiten(col, rho);
    }
    m
}

/// The evidence fit of `y ≈ Φw` under AR(1) noise of coefficient `rho` (with `start`, α per
/// group and β, and the trainer's settings), and its log evidence of the data as given (the
/// whitening's Jacobian `½ ln(1 − ρ²)` included).
pub fn fit(
    phi: &DMatrix<f64>,
    y: &DVector<f64>,
    groups: &[usize],
    start: (&[f64], f64),
    rho: f64,
) -> Option<(GroupFit, f64)> {
    let p = whitened(phi, rho);
    let mut yw = y.clone();
    whiten(yw.as_mut_slice(), rho);
    let f = fit_with(&p, &yw, groups, Some(start), &Settings::TRAINER)?;
    let ev = f.log_evidence + 0.5 * (1.0 - rho * rho).ln();
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
) -> Option<(GroupFit, f64, f64)> {
    RHO_GRID
        .iter()
        .copied()
        .filter(|r| *r <= rho_max)
        .collect::<Vec<f64>>()
        .par_iter()
        .filter_map(|&r| fit(phi, y, groups, start, r).map(|(f, e)| (f, e, r)))
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
        whiten(&mut v, rho);
        for (a, b) in v.iter().zip(&e) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
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
            fit_best_rho(&phi, &DVector::from_vec(y), &[0], (&[1e-8], 1.0), 0.99).unwrap();
        assert!((0.8..=0.95).contains(&rho), "ρ = {rho}");
    }
}
