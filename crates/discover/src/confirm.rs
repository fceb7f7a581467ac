//! Confirmation: the leading candidates refitted by the real trainer before any verdict.
//!
//! Why: scoring ([`crate::score`]) is fast because it keeps the base model's Gaussian centers and
//! widths fixed and only adds the candidate's column. That ranks candidates well, but its held-out
//! figure can disagree with what the user gets after `tcomp fit --feature …`: the refit chooses its
//! own centers, widths and length scales (measured on the real MEMS cycle: scoring predicted −24 %
//! for a product term whose real refit doubled the held-out error). So the best few candidates are
//! refitted exactly as the user would — the trainer's default method, the model's features plus the
//! candidate — and evaluated through the core on the held-out data; the verdict then rests on those
//! figures. The base feature set is refitted the same way, so the comparison differs only in the
//! candidate. Held-out data: the verification run, or without one the last 30 % of the training run
//! (training on the first 70 %).

use crate::score::Scored;
use crate::{ModelInfo, Result};
use rayon::prelude::*;
use serde::Serialize;
use std::path::Path;
use tcomp_train::{Dataset, FitOptions, Roles, metrics};

/// Options of the confirmation.
#[derive(Clone, Debug, Serialize)]
pub struct ConfirmOptions {
    /// Candidates refitted (the best by Δ log evidence among those with positive evidence).
    pub top: usize,
    /// Bin of the held-out residual (s).
    pub heldout_bin_s: f64,
    /// Fraction of the training run held out when there is no verification run.
    pub holdout_fraction: f64,
}

impl Default for ConfirmOptions {
    fn default() -> Self {
        Self {
            top: 3,
            heldout_bin_s: 100.0,
            holdout_fraction: 0.3,
        }
    }
}

/// The real refit of one candidate.
#[derive(Clone, Debug, Serialize)]
pub struct Confirmation {
    /// Held-out residual std (binned) of the refitted base feature set.
    pub residual_std_before: f64,
    /// The same with the candidate added.
    pub residual_std_after: f64,
    /// 100·(1 − after/before).
    pub improvement_pct: f64,
    /// What the held-out data was.
    pub heldout: String,
}

/// Held-out residual std of a fit of `features` on `train`, evaluated on `test`.
fn heldout_std(
    info: &ModelInfo,
    roles: &Roles,
    train: &Dataset,
    test: &Dataset,
    extra: &[String],
    bin_s: f64,
) -> Result<f64> {
    let mut o = FitOptions::new(&roles.target, &[]);
    o.time.clone_from(&roles.time);
    o.reference.clone_from(&roles.reference);
    o.reference_value = roles.reference_value;
    o.spec.signals.clone_from(&info.spec.signals);
    o.spec.features.clone_from(&info.spec.features);
    o.spec.features.extend(extra.iter().cloned());
    let fitted = tcomp_train::fit(train, &o)?;
    let bytes = fitted.model.to_bytes()?;
    let model = tcomp_train::blob_io::decode(Path::new("<refit>"), &bytes)?;
    let run = metrics::run_model(&model, test, &Roles::of_model(&model), None, None)?;
    Ok(metrics::report(&run, bin_s).binned.residual_std)
}

/// Refits the leading candidates and replaces their held-out figures with the real ones; every
/// other candidate is marked unconfirmed. Returns the refitted base's held-out residual.
pub fn confirm(
    info: &ModelInfo,
    roles: &Roles,
    data: &Dataset,
    verify: Option<&Dataset>,
    cands: &mut [Scored],
    opts: &ConfirmOptions,
) -> Result<f64> {
    let (train, test, heldout) = match verify {
        Some(v) => (
            data.clone(),
            v.clone(),
            format!("verification run {}", v.file()),
        ),
        None => {
            let t = data.time(&roles.time)?;
            let (t0, t1) = (
                t.first().copied().unwrap_or(0.0),
                t.last().copied().unwrap_or(0.0),
            );
            let split = t0 + (1.0 - opts.holdout_fraction) * (t1 - t0);
            (
                data.select_time(&roles.time, f64::NEG_INFINITY, split)?,
                data.select_time(&roles.time, split, f64::INFINITY)?,
                format!(
                    "last {:.0} % of the training run",
                    100.0 * opts.holdout_fraction
                ),
            )
        }
    };
    let heldout_bin_s =
        tcomp_train::features::adaptive_bin(test.time(&roles.time)?, opts.heldout_bin_s, 10);
    let mut order: Vec<usize> = (0..cands.len())
        .filter(|&i| cands[i].delta_log_evidence >= 0.0)
        .collect();
    order.sort_by(|&a, &b| {
        cands[b]
            .delta_log_evidence
            .total_cmp(&cands[a].delta_log_evidence)
    });
    order.truncate(opts.top);
    let mut jobs: Vec<Option<usize>> = vec![None];
    jobs.extend(order.iter().map(|&i| Some(i)));
    let results: Vec<Result<f64>> = jobs
        .par_iter()
        .map(|job| {
            let extra = job
                .map(|i| cands[i].expressions.clone())
                .unwrap_or_default();
            heldout_std(info, roles, &train, &test, &extra, heldout_bin_s)
        })
        .collect();
    let mut results = results.into_iter();
    let before = results.next().unwrap_or(Ok(f64::NAN))?;
    let mut outcome: Vec<(usize, std::result::Result<f64, String>)> = Vec::new();
    for (&i, r) in order.iter().zip(results) {
        outcome.push((i, r.map_err(|e| e.to_string())));
    }
    for c in cands.iter_mut() {
        c.confirmation = None;
        c.unconfirmed = Some(format!(
            "not among the {} candidates with the most evidence that were refitted",
            opts.top
        ));
    }
    for (i, r) in outcome {
        let Some(c) = cands.get_mut(i) else { continue };
        match r {
            Ok(after) => {
                let improvement_pct = 100.0 * (1.0 - after / before);
                c.confirmation = Some(Confirmation {
                    residual_std_before: before,
                    residual_std_after: after,
                    improvement_pct,
                    heldout: heldout.clone(),
                });
                c.residual_std_before = before;
                c.residual_std_after = after;
                c.improvement_pct = improvement_pct;
                c.unconfirmed = None;
            }
            Err(e) => c.unconfirmed = Some(format!("the refit with it failed: {e}")),
        }
    }
    Ok(before)
}
