//! Several effects, one round each: diagnose, add what is confirmed, refit, diagnose again, until
//! nothing passes the criterion or the rounds run out.
//!
//! Why rounds rather than one ranked list: two missing effects mask each other — while one is
//! missing, the residual the other must explain is not the residual it will have once the first is
//! in the model, and a candidate's evidence is measured against the model it is added to. So after
//! a candidate is confirmed, the next round starts from the model refitted with it, exactly as the
//! user would do with `tcomp fit --feature …`: the trainer's default method, the model's signals
//! and features with the candidate applied (added, or put in place of the features it replaces),
//! the same roles and gap threshold. A refinement (the model's rate with another window) is not a
//! missing effect: it ends the loop like "none" does, with its advice in the last verdict.
//!
//! After each round, before the next one (and so at the end), the parameters of every feature
//! the rounds added are re-estimated together against the first round's scoring design
//! ([`crate::joint`]): a round's estimate was made with the later effects missing.

use crate::confirm::Refits;
use crate::verdict::Verdict;
use crate::{Analysis, DiagnoseOptions, Diagnosis, HostModel, Result, diagnose, model_info};
use serde::Serialize;
use std::path::Path;
use tcomp_train::Dataset;

/// What one round added to the model.
#[derive(Clone, Debug, Serialize)]
pub struct Applied {
    /// Round (from 1).
    pub round: usize,
    /// The effect named.
    pub effect: String,
    /// Its kind.
    pub kind: crate::candidates::EffectKind,
    /// The expressions put into the model.
    pub expressions: Vec<String>,
    /// The model's features they replaced (empty: added).
    pub replaces: Vec<String>,
    /// The features of the model the next round starts from.
    pub features: Vec<String>,
    /// The added features whose parameters moved when every added parameter was re-estimated
    /// together after this round ([`crate::joint`]).
    pub reestimated: Vec<crate::joint::Moved>,
}

/// Every round's diagnosis and what was added after each.
#[derive(Clone, Debug, Serialize)]
pub struct RoundsReport {
    /// The diagnosis of each round, in order.
    pub rounds: Vec<Diagnosis>,
    /// What each confirmed round added.
    pub applied: Vec<Applied>,
    /// The model's signals (unchanged by the rounds).
    pub signals: Vec<String>,
    /// The features after the last round.
    pub final_features: Vec<String>,
    /// Why the loop stopped.
    pub stopped: String,
}

/// The rounds with what the report needs besides them.
pub struct Rounds {
    /// The analysis of each round.
    pub analyses: Vec<Analysis>,
    /// What each round added.
    pub applied: Vec<Applied>,
    /// The model's signals.
    pub signals: Vec<String>,
    /// The features after the last round.
    pub final_features: Vec<String>,
    /// Why the loop stopped.
    pub stopped: String,
}

impl Rounds {
    /// The serialisable report (the diagnoses cloned).
    pub fn report(&self) -> RoundsReport {
        RoundsReport {
            rounds: self.analyses.iter().map(|a| a.diagnosis.clone()).collect(),
            applied: self.applied.clone(),
            signals: self.signals.clone(),
            final_features: self.final_features.clone(),
            stopped: self.stopped.clone(),
        }
    }
}

/// Diagnoses `model` on `data` for up to `max_rounds` rounds (see the module doc); `verify` is the
/// held-out run of every round.
pub fn diagnose_rounds(
    model: &HostModel<'_>,
    data: &Dataset,
    verify: Option<&Dataset>,
    opts: &DiagnoseOptions,
    max_rounds: usize,
) -> Result<Rounds> {
    let info = model_info(model);
    let roles = opts.roles.clone().unwrap_or_else(|| info.roles.clone());
    let mut analyses = vec![diagnose(model, data, verify, opts)?];
    // The first round's scoring design: what the added parameters are re-estimated against.
    let first = crate::score::prepare(&info.spec, &roles, data, None, &opts.score)?;
    let mut applied = Vec::new();
    let mut features = info.spec.features.clone();
    let stopped = loop {
        let Some(last) = analyses.last() else {
            break String::from("no round ran");
        };
        let d = &last.diagnosis;
        let top = d.candidates.first();
        let c = match (d.verdict, top) {
            (Verdict::MissingEffect, Some(c)) => c,
            (Verdict::CannotTell, _) => {
                break format!(
                    "round {}: the run cannot tell its candidates apart (the verdict names them \
                     and the run that would separate them)",
                    analyses.len()
                );
            }
            _ => {
                break format!(
                    "round {}: nothing passes the criterion{}",
                    analyses.len(),
                    if top.is_some_and(|c| c.passes) {
                        " as a missing effect (a refinement does)"
                    } else {
                        ""
                    }
                );
            }
        };
        let next = c.candidate().applied_to(&features);
        // Every parameter the rounds added, re-estimated together before the next round (and so
        // at the end).
        let added: Vec<usize> = (0..next.len())
            .filter(|&k| next.get(k).is_some_and(|f| !info.spec.features.contains(f)))
            .collect();
        let (next, reestimated) = crate::joint::reestimate(&first, &next, &added);
        applied.push(Applied {
            round: analyses.len(),
            effect: c.effect.clone(),
            kind: c.kind,
            expressions: c.expressions.clone(),
            replaces: c.replaces.clone(),
            features: next.clone(),
            reestimated,
        });
        features = next;
        if analyses.len() >= max_rounds {
            break format!("{max_rounds} rounds run (--rounds {max_rounds})");
        }
        let refits = Refits::new(&info, &roles, data, opts.score.gap_s);
        let fitted = tcomp_train::fit(data, &refits.options(&features))?;
        let bytes = fitted.model.to_bytes()?;
        let next_model = tcomp_train::blob_io::decode(Path::new("<round refit>"), &bytes)?;
        analyses.push(diagnose(&next_model, data, verify, opts)?);
    };
    Ok(Rounds {
        analyses,
        applied,
        signals: info.spec.signals.clone(),
        final_features: features,
        stopped,
    })
}
