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
pub(crate) fn log_evidence(p: &Prepared, features: &[String]) -> f64 {
    let Ok((cols, _)) = p.standardised(features) else {
        return f64::NEG_INFINITY;
    };
    let n = p.y.len();
    let m = 1 + cols.len() * POWERS.len();
    let mut groups = vec![0usize; m];
    let phi = DMatrix::from_fn(n, m, |i, j| {
        if j == 0 {
            return 1.0;
        }
        let (k, q) = ((j - 1) / POWERS.len(), (j - 1) % POWERS.len());
        let z = cols.get(k).and_then(|c| c.get(i)).copied().unwrap_or(0.0);
        z.powi(POWERS.get(q).copied().unwrap_or(1))
    });
    for (j, g) in groups.iter_mut().enumerate().skip(1) {
        *g = 1 + (j - 1) % POWERS.len();
    }
    evidence::fit(&phi, &p.y, &groups, None).map_or(f64::NEG_INFINITY, |f| f.log_evidence)
}
