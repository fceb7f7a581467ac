//! The verdict: a named missing effect, or "no significant missing effect", by a stated criterion.
//!
//! Why a criterion with three legs: a tool that always finds something is worse than none. Each leg
//! guards against a different way of fooling oneself.
//! 1. **Evidence:** Δ log evidence ≥ `min_delta_log_evidence` (default 5, "strong" on Jeffreys'
//!    scale) on binned training data — the candidate is worth its extra parameter there. Or, when
//!    the training run cannot tell the candidate from what the model's Gaussians mimic in-sample
//!    (T·dT/dt on a run with a single ramp rate), Δ log evidence ≥ 0 together with a held-out
//!    improvement of at least `strong_improvement_pct` (default 20 %): data the fit has not seen
//!    can tell them apart.
//! 2. **Held-out improvement:** the held-out residual falls by at least `min_improvement_pct`
//!    (default 5 %) — the structure is still there on data the fit has not seen (drift that the
//!    training run happened to share does not survive this).
//! 3. **Above the noise floor:** the held-out error removed, √(before² − after²), is at least
//!    `min_removed_vs_floor` (default 0.5) times the noise floor estimated from the held-out
//!    residual — an effect smaller than that cannot be told from noise, and a model that already
//!    holds the physics sits at the floor with nothing left to remove.
//!
//! The held-out figures of legs 1 (its held-out path), 2 and 3 are those of a real refit by the
//! trainer ([`crate::confirm`]): only the few candidates so refitted can be named, so a verdict never
//! rests on the scoring's fixed-center estimate alone.
//!
//! Among the candidates that pass, the one named is the one whose real refit has the most log
//! evidence on the training run (a lag of T in place of T against the same lag beside T: the data
//! say which). A candidate that only re-states a feature the model has (its rate with a longer
//! window) is a refinement, named as such and never as a missing effect.

use crate::score::Scored;
use serde::Serialize;
use tcomp_train::TrainError;
use tcomp_train::num::{SIG, change_pct, pct, plain, signed};
use tcomp_train::options::Bound;
// `--min-evidence` and `--min-improvement` (and the strong-improvement threshold) are bounded by
// the trainer's one table, which the command line parses with too.
use tcomp_train::options::{MIN_EVIDENCE, MIN_IMPROVEMENT as IMPROVEMENT};

/// The thresholds of the verdict.
#[derive(Clone, Debug, Serialize)]
pub struct Criterion {
    /// Minimum Δ log evidence.
    pub min_delta_log_evidence: f64,
    /// Minimum held-out improvement (%).
    pub min_improvement_pct: f64,
    /// Held-out improvement (%) that stands in for the evidence threshold when Δ log evidence ≥ 0.
    pub strong_improvement_pct: f64,
    /// Minimum held-out error removed, as a multiple of the noise floor estimate.
    pub min_removed_vs_floor: f64,
}

impl Default for Criterion {
    fn default() -> Self {
        Self {
            min_delta_log_evidence: 5.0,
            min_improvement_pct: 5.0,
            strong_improvement_pct: 20.0,
            min_removed_vs_floor: 0.5,
        }
    }
}

/// The noise-floor multiple: 0 turns the leg off; above 100 nothing is ever above the floor.
const FLOOR: Bound = Bound {
    flag: "min_removed_vs_floor",
    key: "",
    min: 0.0,
    min_exclusive: false,
    max: 100.0,
    unit: "",
    why: "a multiple of the noise floor",
};

impl Criterion {
    /// Checks every threshold against its valid range.
    pub fn validate(&self) -> Result<(), TrainError> {
        MIN_EVIDENCE.check(self.min_delta_log_evidence)?;
        IMPROVEMENT.check(self.min_improvement_pct)?;
        Bound {
            flag: "strong_improvement_pct",
            ..IMPROVEMENT
        }
        .check(self.strong_improvement_pct)?;
        FLOOR.check(self.min_removed_vs_floor)?;
        Ok(())
    }

    /// The criterion in one sentence.
    pub fn text(&self) -> String {
        format!(
            "a candidate is a missing effect when (1) Δ log evidence ≥ {} on binned training data \
             (or ≥ 0 with a held-out improvement ≥ {} %), (2) the held-out residual falls by ≥ {} %, \
             and (3) the held-out error it removes, √(before² − after²), is ≥ {}× the noise floor \
             estimated from the held-out residual — held out meaning contiguous blocks of the \
             training run, each predicted by a fit on the rest (a verification run is only \
             reported: it never chooses)",
            self.min_delta_log_evidence,
            self.strong_improvement_pct,
            self.min_improvement_pct,
            self.min_removed_vs_floor
        )
    }

    /// Marks each candidate as passing or not (with the reasons) and sorts: passing first, then by
    /// Δ log evidence.
    /// `noise_floor` is the one estimated from the training blocks' held-out residual
    /// ([`crate::confirm::BaseRefit::noise_floor`]).
    pub fn apply(&self, noise_floor: f64, cands: &mut [Scored]) {
        for c in cands.iter_mut() {
            let mut fails = Vec::new();
            let strong =
                c.delta_log_evidence >= 0.0 && c.improvement_pct >= self.strong_improvement_pct;
            if c.delta_log_evidence < self.min_delta_log_evidence && !strong {
                fails.push(format!(
                    "Δ log evidence {:.1} < {} (and not ≥ 0 with ≥ {} % held-out improvement)",
                    c.delta_log_evidence, self.min_delta_log_evidence, self.strong_improvement_pct
                ));
            }
            if c.improvement_pct < self.min_improvement_pct {
                fails.push(format!(
                    "held-out improvement {:.1} % < {} %",
                    c.improvement_pct, self.min_improvement_pct
                ));
            }
            let removed = (c.residual_std_before.powi(2) - c.residual_std_after.powi(2))
                .max(0.0)
                .sqrt();
            let need = self.min_removed_vs_floor * noise_floor;
            if removed < need {
                fails.push(format!(
                    "removes {} of held-out error < {} ({}× noise floor {})",
                    plain(removed, SIG),
                    plain(need, SIG),
                    self.min_removed_vs_floor,
                    plain(noise_floor, SIG)
                ));
            }
            if let Some(why) = &c.unconfirmed {
                fails.push(format!("unconfirmed: {why}"));
            }
            c.passes = fails.is_empty();
            c.fails = fails;
        }
        // Passing first; among them missing effects before refinements, then by the real refits'
        // evidence; the rest by the scoring's evidence.
        let rank = |c: &Scored| match (&c.confirmation, c.passes) {
            (Some(k), true) => k.delta_log_evidence_refit,
            _ => c.delta_log_evidence,
        };
        cands.sort_by(|a, b| {
            b.passes
                .cmp(&a.passes)
                .then((a.passes && a.refines.is_some()).cmp(&(b.passes && b.refines.is_some())))
                .then(rank(b).total_cmp(&rank(a)))
        });
    }
}

/// "missing_effect" or "none".
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// A candidate cleared the criterion.
    MissingEffect,
    /// None did.
    None,
}

/// `--feature 'e'` for each expression.
fn flags(exprs: &[String]) -> String {
    exprs
        .iter()
        .map(|e| format!("--feature '{e}'"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// What to do with a candidate: add its features, or put them in place of the model's.
pub fn instruction(c: &Scored) -> String {
    if c.replaces.is_empty() {
        format!("add {}", flags(&c.expressions))
    } else {
        format!(
            "replace {} by {}",
            flags(&c.replaces),
            flags(&c.expressions)
        )
    }
}

/// The parameter's estimate in a few words, when it was estimated.
fn estimate_text(c: &Scored) -> String {
    c.estimate.as_ref().map_or_else(String::new, |e| {
        let n = |v: f64| crate::candidates::num(crate::param::two_significant(v));
        format!(
            "; parameter {} ({} … {} cannot be told apart{})",
            n(e.value),
            n(e.interval[0]),
            n(e.interval[1]),
            if e.chosen_by == crate::param::ChosenBy::CrossValidation {
                ", chosen by cross-validation on the training run"
            } else {
                ""
            }
        )
    })
}

/// The held-out figures of `c` in words: over the training run's blocks (what chose it), and on
/// the verification run when there is one (what it is reported on).
fn heldout_text(c: &Scored) -> String {
    let mut t = format!(
        "held-out residual {} → {} ({})",
        plain(c.residual_std_before, SIG),
        plain(c.residual_std_after, SIG),
        pct(change_pct(c.residual_std_before, c.residual_std_after))
    );
    if let Some(v) = c
        .confirmation
        .as_ref()
        .and_then(|k| k.verification.as_ref())
    {
        t += &format!(
            "; on the verification run {} → {} ({})",
            plain(v.residual_std_before, SIG),
            plain(v.residual_std_after, SIG),
            pct(Some(v.change_pct))
        );
    }
    t
}

/// The verdict for sorted candidates, with a sentence.
pub fn decide(cands: &[Scored]) -> (Verdict, String) {
    match cands.first() {
        Some(c) if c.passes && c.refines.is_none() => (
            Verdict::MissingEffect,
            format!(
                "missing effect: {} — {} (Δ log evidence {}; {}{})",
                c.effect,
                instruction(c),
                signed(c.delta_log_evidence, 1),
                heldout_text(c),
                estimate_text(c)
            ),
        ),
        Some(c) if c.passes => (
            Verdict::None,
            format!(
                "no significant missing effect; a refinement passes the criterion: {} — {} ({}{})",
                c.effect,
                instruction(c),
                heldout_text(c),
                estimate_text(c)
            ),
        ),
        Some(c) => (
            Verdict::None,
            format!(
                "no significant missing effect: no candidate clears the criterion (closest: {}, {})",
                c.effect,
                c.fails.join("; ")
            ),
        ),
        None => (
            Verdict::None,
            "no significant missing effect: no candidate could be scored".into(),
        ),
    }
}
