//! MacKay's evidence framework for a linear-in-parameters model whose weights fall into groups, each
//! with its own prior precision α: the one implementation under the trainer's `bayes` method (groups:
//! bias, linear terms, Gaussians) and the discovery loop's candidate scoring (a candidate column gets
//! its own group, so a useless one is switched off by α → ∞ and its Δ log evidence goes to 0 instead
//! of diluting the prior of the base's weights; the iteration can be warm-started).
//!
//! For `A = βΦᵀΦ + diag(α)`: `γ_g = Σ_{i∈g}(1 − α_g·(A⁻¹)_ii)`, `α_g ← γ_g/‖w_g‖²`,
//! `β ← (N − γ)/‖y − Φw‖²`, iterated until α and β change less than [`Settings`]' tolerances; group 0
//! (the bias) has a fixed, nearly flat prior that cancels in evidence differences. The log evidence
//! is `N/2·ln β − β·E_D − ½ ln|A| − N/2·ln 2π + Σ_g (|g|/2·ln α_g − α_g·E_W,g)`.

use nalgebra::{DMatrix, DVector};

/// Precision of the (nearly flat) prior on group 0.
const FLAT: f64 = 1e-8;
/// Largest α: a group at this value is switched off.
const ALPHA_MAX: f64 = 1e12;

/// Convergence settings.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Most iterations.
    pub max_iterations: usize,
    /// Relative change of every α below which it has converged.
    pub alpha_tolerance: f64,
    /// Relative change of β below which it has converged.
    pub beta_tolerance: f64,
    /// Count a group whose α passed 1e10 (switched off) as converged.
    pub switched_off_converged: bool,
}

impl Settings {
    /// What the trainer uses.
    pub const TRAINER: Settings = Settings {
        max_iterations: 2000,
        alpha_tolerance: 1e-6,
        beta_tolerance: 1e-6,
        switched_off_converged: false,
    };
    /// What candidate scoring uses (tighter on β, stops once a useless column is switched off).
    pub const SCORING: Settings = Settings {
        max_iterations: 1000,
        alpha_tolerance: 1e-6,
        beta_tolerance: 1e-7,
        switched_off_converged: true,
    };
}

/// A converged fit.
#[derive(Clone, Debug)]
pub struct GroupFit {
    /// Posterior mean weights.
    pub w: DVector<f64>,
    /// α per group (group 0 fixed).
    pub alpha: Vec<f64>,
    /// Noise precision.
    pub beta: f64,
    /// Effective number of parameters.
    pub gamma: f64,
    /// Log evidence (of `y` as given: normalised units).
    pub log_evidence: f64,
    /// Iterations run.
    pub iterations: usize,
}

/// Fits `y ≈ Φw` with weight groups `group[j]` (0 = bias, fixed prior), starting from `start`
/// (α per group and β) when given, with the scoring settings.
pub fn fit(
    phi: &DMatrix<f64>,
    y: &DVector<f64>,
    group: &[usize],
    start: Option<(&[f64], f64)>,
) -> Option<GroupFit> {
    fit_with(phi, y, group, start, &Settings::SCORING)
}

/// [`fit`] with explicit convergence settings. A group with no columns keeps its starting α.
pub fn fit_with(
    phi: &DMatrix<f64>,
    y: &DVector<f64>,
    group: &[usize],
    start: Option<(&[f64], f64)>,
    settings: &Settings,
) -> Option<GroupFit> {
    let n = phi.nrows() as f64;
    let m = phi.ncols();
    let ng = group.iter().copied().max().unwrap_or(0) + 1;
    let g = phi.tr_mul(phi);
    let b = phi.tr_mul(y);
    let yy = y.dot(y);
    let mut alpha = vec![1.0; ng];
    let mut beta = 10.0;
    if let Some((a0, b0)) = start {
        for (a, s) in alpha.iter_mut().zip(a0) {
            *a = *s;
        }
        beta = b0;
    }
    if let Some(a) = alpha.first_mut() {
        *a = FLAT;
    }
    let gr = |i: usize| group.get(i).copied().unwrap_or(0);
    let mut members = vec![0usize; ng];
    for i in 0..m {
        if let Some(c) = members.get_mut(gr(i)) {
            *c += 1;
        }
    }
    let solve = |alpha: &[f64], beta: f64| {
        let mut a = &g * beta;
        for i in 0..m {
            a[(i, i)] += alpha.get(gr(i)).copied().unwrap_or(1.0);
        }
        let chol = a.cholesky()?;
        let ainv = chol.inverse();
        let w = &ainv * &b * beta;
        let ed = (0.5 * (yy - 2.0 * w.dot(&b) + w.dot(&(&g * &w)))).max(1e-300);
        let logdet: f64 = chol.l().diagonal().iter().map(|d| 2.0 * d.ln()).sum();
        Some((ainv, w, ed, logdet))
    };
    let mut iterations = 0;
    for it in 0..settings.max_iterations {
        iterations = it + 1;
        let (ainv, w, ed, _) = solve(&alpha, beta)?;
        let mut gam = vec![0.0f64; ng];
        let mut ew = vec![0.0f64; ng];
        for i in 0..m {
            let k = gr(i);
            gam[k] += 1.0 - alpha[k] * ainv[(i, i)];
            ew[k] += 0.5 * w[i] * w[i];
        }
        let mut next = alpha.clone();
        for k in 1..ng {
            if members[k] > 0 {
                next[k] = (gam[k] / (2.0 * ew[k]).max(1e-300)).clamp(1e-10, ALPHA_MAX);
            }
        }
        let gamma_total: f64 = gam.iter().sum();
        let next_beta = ((n - gamma_total).max(1e-3) / (2.0 * ed)).clamp(1e-10, 1e14);
        let rel = |a: f64, b: f64| ((a - b) / b.abs().max(1e-300)).abs();
        let done = (1..ng).all(|k| {
            rel(next[k], alpha[k]) < settings.alpha_tolerance
                || (settings.switched_off_converged && next[k] > 1e10)
        }) && rel(next_beta, beta) < settings.beta_tolerance;
        alpha = next;
        beta = next_beta;
        if done {
            break;
        }
    }
    let (ainv, w, ed, logdet) = solve(&alpha, beta)?;
    let mut gamma = 0.0;
    let mut log_ev = 0.5 * n * beta.ln()
        - beta * ed
        - 0.5 * logdet
        - 0.5 * n * (2.0 * std::f64::consts::PI).ln();
    for i in 0..m {
        let k = gr(i);
        gamma += 1.0 - alpha[k] * ainv[(i, i)];
        if k > 0 {
            log_ev += 0.5 * alpha[k].ln() - 0.5 * alpha[k] * w[i] * w[i];
        }
    }
    log_ev.is_finite().then_some(GroupFit {
        w,
        alpha,
        beta,
        gamma,
        log_evidence: log_ev,
        iterations,
    })
}

/// Posterior mean weights on the rows `keep` of `Φ`, `y`, with fixed hyperparameters.
pub fn weights_on(
    phi: &DMatrix<f64>,
    y: &DVector<f64>,
    group: &[usize],
    alpha: &[f64],
    beta: f64,
    keep: &[usize],
) -> Option<DVector<f64>> {
    let sub = phi.select_rows(keep);
    let ys = y.select_rows(keep);
    let mut a = sub.tr_mul(&sub) * beta;
    for i in 0..a.ncols() {
        let k = group.get(i).copied().unwrap_or(0);
        a[(i, i)] += alpha.get(k).copied().unwrap_or(1.0);
    }
    let rhs = sub.tr_mul(&ys) * beta;
    a.cholesky().map(|c| c.solve(&rhs))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn useful_column_gains_evidence_useless_does_not() {
        let n = 300;
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.05).sin()).collect();
        let u: Vec<f64> = (0..n).map(|i| (i as f64 * 0.377).cos()).collect();
        let noise: Vec<f64> = (0..n)
            .map(|i| ((i * 7919 % 101) as f64 / 101.0 - 0.5) * 0.2)
            .collect();
        let y = DVector::from_iterator(n, (0..n).map(|i| 2.0 * x[i] + noise[i]));
        let base = DMatrix::from_fn(n, 1, |_, _| 1.0);
        let with_x = DMatrix::from_fn(n, 2, |i, j| if j == 0 { 1.0 } else { x[i] });
        let with_u = DMatrix::from_fn(n, 3, |i, j| match j {
            0 => 1.0,
            1 => x[i],
            _ => u[i],
        });
        let b = fit(&base, &y, &[0], None).unwrap();
        let bx = fit(&with_x, &y, &[0, 1], None).unwrap();
        let bu = fit(&with_u, &y, &[0, 1, 2], None).unwrap();
        assert!(bx.log_evidence - b.log_evidence > 50.0);
        assert!((bu.log_evidence - bx.log_evidence).abs() < 3.0);
    }
}
