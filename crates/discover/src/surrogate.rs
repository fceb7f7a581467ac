//! The smooth criterion a parameter is profiled on: the log evidence, on the binned training run, of
//! a fixed-structure surrogate of the model — each feature with its square and cube (a cubic per
//! feature, no Gaussians), under one prior per power.
//!
//! Why not the trainer's own evidence: the trainer chooses its structure (the number of Gaussians,
//! their width, length scales, the cubic or the Gaussians) anew for every feature set, and each
//! change of structure moves its evidence by tens of nats. Profiled over a lag's τ that evidence
//! is a saw-tooth (measured on a QMA whose proof mass lags in every term: −607.6 at 1549 s,
//! −578.8 at the true 1800 s, −604.7 at 1900 s, −605.0 at 2937 s), and a search on it lands on
//! whichever tooth is highest. The surrogate's structure does not change with τ, so its evidence
//! is a smooth function of τ that a golden-section search can follow, and it peaks where the
//! features explain the error — a lag in every term makes the cubic in the lagged temperature exact
//! at the true τ. The trainer's refits then confirm the candidate at the value found.

use crate::base::Prepared;
use nalgebra::DMatrix;
use tcomp_train::evidence;

/// Powers of each standardised feature in the surrogate.
const POWERS: [i32; 3] = [1, 2, 3];

/// Log evidence of the surrogate of `features` on the binned training run of `p` (normalised
/// units, comparable between feature sets on the same run); −∞ when a feature cannot be computed,
/// is constant, or the evidence iteration fails.
pub(crate) fn log_evidence(p: &Prepared, features: &[String], cubic: usize) -> f64 {
    fitted(p, features, cubic).map_or(f64::NEG_INFINITY, |f| f.0.log_evidence)
}

/// The fraction (1 − ρ)/(1 + ρ) of the binned training run's bins that count as independent
/// observations, ρ the lag-1 autocorrelation of the surrogate's residual (1 when ρ ≤ 0 or the fit
/// fails).
pub(crate) fn information(p: &Prepared, features: &[String], cubic: usize) -> f64 {
    let Some((fit, phi)) = fitted(p, features, cubic) else {
        return 1.0;
    };
    let r = &p.y - phi * &fit.w;
    let ss: f64 = r.iter().map(|v| v * v).sum();
    let lag1: f64 = r.iter().zip(r.iter().skip(1)).map(|(a, b)| a * b).sum();
    let rho = if ss > 0.0 { (lag1 / ss).max(0.0) } else { 0.0 };
    (1.0 - rho) / (1.0 + rho)
}

/// The surrogate's evidence fit and its design matrix.
fn fitted(
    p: &Prepared,
    features: &[String],
    cubic: usize,
) -> Option<(evidence::GroupFit, DMatrix<f64>)> {
    let Ok((cols, _)) = p.standardised(features) else {
        return None;
    };
    // (feature, power) of each column after the constant.
    let terms: Vec<(usize, i32)> = (0..cols.len())
        .flat_map(|k| {
            let powers: &[i32] = if k < cubic { &POWERS } else { &POWERS[..1] };
            powers.iter().map(move |&q| (k, q))
        })
        .collect();
    let n = p.y.len();
    let m = 1 + terms.len();
    let phi = DMatrix::from_fn(n, m, |i, j| {
        match j.checked_sub(1).and_then(|t| terms.get(t)) {
            None => 1.0,
            Some(&(k, q)) => cols
                .get(k)
                .and_then(|c| c.get(i))
                .copied()
                .unwrap_or(0.0)
                .powi(q),
        }
    });
    let mut groups = vec![0usize; m];
    for (g, &(_, q)) in groups.iter_mut().skip(1).zip(&terms) {
        *g = usize::try_from(q).unwrap_or(1);
    }
    evidence::fit(&phi, &p.y, &groups, None).map(|f| (f, phi))
}
