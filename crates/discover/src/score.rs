//! Scoring: refit the model's features plus each candidate, in parallel, and measure what the
//! candidate buys — in log evidence on the training run and in residual on held-out data.
//!
//! Why this shape: a candidate is only worth adding if it explains structure the model's own
//! features cannot, and if that structure is still there on data the fit has not seen.
//! * **Binned first.** Bias instability makes 1 Hz samples strongly correlated; evidence computed
//!   on them as if independent would call drift an effect. Errors and features are averaged into
//!   bins (`bin_s`, default 60 s) before anything is fitted.
//! * **Same base for everyone.** The model's features are fitted once by the trainer's evidence
//!   search (`tcomp_train::bayes`), which fixes the Gaussian centers, width and length scales. Each
//!   candidate is then scored as that design plus the candidate's standardised column(s) with their
//!   own prior precision; all weights and α, β are re-estimated by the evidence iteration. A column
//!   that explains nothing is switched off (α → ∞) and its Δ log evidence tends to 0, so the
//!   comparison is between models that differ by the candidate alone.
//! * **Collinear candidates are refused,** not scored: a column the model's features already span
//!   linearly (1 − R² < 1e-4 against bias + features) adds no information, whatever its name. A
//!   candidate the Gaussians can mimic in-sample (T·dT/dt on a run with one ramp rate) is still
//!   scored: its evidence gain is then small, and the held-out residual decides.
//! * **Held-out residual** on `--verify` (bins of `heldout_bin_s`, default 100 s) or, without one,
//!   on `folds` contiguous blocks of the training run, each predicted from the others with the
//!   converged hyperparameters.
//! * **Families** (a lag's τ, a threshold, a rate window) are marginalised over their grid:
//!   `ln mean(exp Δ)`, so searching more values does not buy evidence; the best member names the
//!   family — but a composition's own estimate, its first member, keeps the name unless a grid
//!   point explains more than the run can tell apart ([`INDISTINCT_NATS`]) — and
//!   [`crate::param`] then estimates the parameter of the families that are confirmed
//!   on a continuous scale by the real refits (the fixed base Gaussians here absorb part of a slow
//!   effect and bias τ short).
//! * **Replacements** (a lag of T put in place of T in every feature) are scored here as the
//!   base design plus their new columns — an approximation that ranks them; whether the element
//!   sees the lagged temperature *instead of* the thermometer's is decided by the real refits of
//!   [`crate::confirm`], which fit the replaced feature set.

/// Log evidence (nats) below which two hypotheses cannot be told apart: "not worth more than a
/// bare mention" on Kass and Raftery's scale (`2 ln B < 2`, odds under e : 1). The verdict's ties,
/// the composer's and the rounds' estimates, and the name a family is given all use it.
pub const INDISTINCT_NATS: f64 = 1.0;

pub use crate::base::{
    BaseFigures, FOLDS, Prepared, ScoreOptions, base_residual, binned_feature, prepare,
};
use crate::candidates::{Candidate, EffectKind, Family, Search, Searched};
use crate::design::mean_sd;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::Serialize;
use tcomp_train::evidence;

/// One scored candidate (the best member of its family).
#[derive(Clone, Debug, Serialize)]
pub struct Scored {
    /// Feature expression to add (the first when several).
    pub expression: String,
    /// All expressions to add.
    pub expressions: Vec<String>,
    /// Physical name.
    pub effect: String,
    /// Effect kind.
    pub kind: EffectKind,
    /// The searched parameter of the best member (τ s, threshold, window s).
    pub parameter: Option<f64>,
    /// Δ log evidence of the family (marginalised over its grid).
    pub delta_log_evidence: f64,
    /// Δ log evidence of the best member alone.
    pub delta_log_evidence_best: f64,
    /// Std of the binned held-out residual with the candidate (the real refit's figure once
    /// confirmed, else the scoring estimate).
    pub residual_std_after: f64,
    /// Std of the binned held-out residual without it.
    pub residual_std_before: f64,
    /// 100·(1 − after/before) on held-out data.
    pub improvement_pct: f64,
    /// The scoring's own estimate of `improvement_pct` (centers and widths of the base held fixed).
    pub scored_improvement_pct: f64,
    /// The real refit of this candidate ([`crate::confirm`]), when it was among those refitted.
    pub confirmation: Option<crate::findings::Confirmation>,
    /// Why there is no confirmation.
    pub unconfirmed: Option<String>,
    /// Std of the binned training residual with the candidate.
    pub train_residual_std_after: f64,
    /// Members scored.
    pub members: usize,
    /// The model's features the expressions replace (empty: they are added).
    pub replaces: Vec<String>,
    /// The model's feature this candidate only re-states with another parameter (a refinement,
    /// not a missing effect).
    pub refines: Option<String>,
    /// How the family's parameter is searched ([`crate::param`]).
    #[serde(skip)]
    pub search: Option<Search>,
    /// How the candidate was read off the data, when it was ([`crate::candidates::Searched`]).
    #[serde(skip)]
    pub searched: crate::candidates::Searched,
    /// The estimate of the parameter, when it was searched.
    pub estimate: Option<crate::param::Estimate>,
    /// The scoring grid's best parameter, when the estimate moved away from it.
    pub parameter_scored: Option<f64>,
    /// The candidate against its placebos ([`crate::placebo`]), when it was refitted.
    pub placebo: Option<crate::findings::Placebo>,
    /// Whether it clears the criterion (set by the verdict).
    pub passes: bool,
    /// Why it does not (set by the verdict).
    pub fails: Vec<String>,
    /// Its description length in the feature language, in nats: the prior over structures the
    /// verdict weighs its refit's evidence against ([`crate::description`]; set by the verdict).
    pub description_nats: f64,
    /// The candidates this one joins, when it is two effects that explain the run only together
    /// ([`crate::confirm::together`]); empty for a single effect.
    #[serde(skip)]
    pub joined: Vec<Scored>,
    /// Whether this composition was ranked for the compositions' refit slots by the placebo leg's
    /// statistic ([`crate::confirm`]): its placebos then count in the leg's threshold whether or
    /// not it was refitted ([`crate::placebo::calibrate`]).
    #[serde(skip)]
    pub ranked: bool,
}

impl Scored {
    /// The candidate as it stands (after any estimate of its parameter).
    pub fn candidate(&self) -> Candidate {
        Candidate {
            kind: self.kind,
            effect: self.effect.clone(),
            expressions: self.expressions.clone(),
            parameter: self.parameter,
            replaces: self.replaces.clone(),
            refines: self.refines.clone(),
        }
    }
}

/// A candidate that was not scored.
#[derive(Clone, Debug, Serialize)]
pub struct Skipped {
    /// Expression.
    pub expression: String,
    /// Physical name.
    pub effect: String,
    /// Why.
    pub reason: String,
}

/// A member's score.
#[derive(Clone, Debug)]
pub(crate) struct MemberScore {
    pub(crate) delta: f64,
    pub(crate) heldout_std: f64,
    pub(crate) train_std: f64,
}

/// The scoring design's figures of `c`'s columns added to the base's (one prior group).
pub(crate) fn score_member(
    p: &Prepared,
    c: &Candidate,
) -> std::result::Result<MemberScore, String> {
    let (cols, vcols) = p.standardised(&c.expressions).map_err(|e| e.to_string())?;
    // Refuse columns the model's features already span linearly (bias + linear columns). The
    // Gaussians are left out on purpose: a product or square of existing features is expressible
    // by them in-sample, yet as an explicit feature it changes how the model extrapolates.
    let lin = p.phi.columns(0, p.n_linear + 1).into_owned();
    for (e, col) in c.expressions.iter().zip(&cols) {
        let cv = DVector::from_column_slice(col);
        let g = lin.tr_mul(&lin) + DMatrix::identity(lin.ncols(), lin.ncols()) * 1e-9;
        let b = g
            .cholesky()
            .map(|ch| ch.solve(&lin.tr_mul(&cv)))
            .ok_or("singular base design")?;
        let r = &cv - &lin * b;
        let unexplained = r.dot(&r) / cv.dot(&cv).max(1e-300);
        if unexplained < 1e-4 {
            return Err(format!(
                "`{e}` is already expressed by the model's features (1 − R² = {unexplained:.1e})"
            ));
        }
    }
    let (phi, groups, a0) = p.with_columns(&cols);
    let fit = evidence::fit(&phi, &p.y, &groups, Some((&a0, p.base.beta)))
        .ok_or("the evidence iteration failed")?;
    let (held, _) = p
        .heldout_residuals(&phi, vcols.as_deref(), &groups, &fit)
        .ok_or("held-out prediction failed")?;
    Ok(MemberScore {
        delta: fit.log_evidence - p.base.log_evidence,
        heldout_std: mean_sd(&held).1,
        train_std: p.train_std(&phi, &fit),
    })
}

/// Scores every family in parallel; returns the scored families (unsorted) and the skipped ones.
pub fn score(p: &Prepared, families: &[Family]) -> (Vec<Scored>, Vec<Skipped>) {
    let members: Vec<(usize, &Candidate)> = families
        .iter()
        .enumerate()
        .flat_map(|(f, fam)| fam.members.iter().map(move |m| (f, m)))
        .collect();
    let exprs: Vec<String> = members
        .iter()
        .flat_map(|(_, m)| m.expressions.iter().cloned())
        .collect();
    p.prefetch(&exprs, true);
    let results: Vec<(usize, &Candidate, std::result::Result<MemberScore, String>)> = members
        .par_iter()
        .map(|&(f, m)| (f, m, score_member(p, m)))
        .collect();
    let mut scored = Vec::new();
    let mut skipped = Vec::new();
    let before = p.figures.heldout_residual_std;
    for (f, _) in families.iter().enumerate() {
        let mine: Vec<&(usize, &Candidate, _)> = results.iter().filter(|r| r.0 == f).collect();
        let ok: Vec<(&Candidate, &MemberScore)> = mine
            .iter()
            .filter_map(|r| r.2.as_ref().ok().map(|s| (r.1, s)))
            .collect();
        let Some(&(top_c, top)) = ok.iter().max_by(|a, b| a.1.delta.total_cmp(&b.1.delta)) else {
            if let Some((_, c, Err(reason))) = mine.first().map(|r| (r.0, r.1, &r.2)) {
                skipped.push(Skipped {
                    expression: c.expressions.join(", "),
                    effect: c.effect.clone(),
                    reason: reason.clone(),
                });
            }
            continue;
        };
        // A composition's first member is its estimate, refined and written to the run's own
        // precision (`compose::plainest`); the others are its shape's grid, there for the
        // marginal below and the placebos. A grid point named in its place must explain more
        // than the run can tell apart (measured: a relay on a heater stepping between levels,
        // its estimate `hyst(heater_v − 12.125, 0.175)`, was named as the grid's `hyst(heater_v
        // − 12.1895, 0.2395)`, the same training column within a nat: 5.24× the floor on the
        // verification run, which visits the levels between).
        let estimate = ok.first().filter(|(c, s)| {
            families.get(f).is_some_and(|fam| {
                matches!(fam.searched, Searched::Alternatives { .. })
                    && fam.members.first().is_some_and(|m| m == *c)
            }) && s.delta >= top.delta - INDISTINCT_NATS
        });
        let (best_c, best) = estimate.copied().unwrap_or((top_c, top));
        let k = mine.len() as f64;
        let mx = top.delta;
        let lse = mx
            + ok.iter()
                .map(|(_, s)| (s.delta - mx).exp())
                .sum::<f64>()
                .ln()
            - k.ln();
        scored.push(Scored {
            expression: best_c.expressions.first().cloned().unwrap_or_default(),
            expressions: best_c.expressions.clone(),
            effect: best_c.effect.clone(),
            kind: best_c.kind,
            parameter: best_c.parameter,
            delta_log_evidence: lse,
            delta_log_evidence_best: best.delta,
            residual_std_after: best.heldout_std,
            residual_std_before: before,
            improvement_pct: if before > 0.0 {
                100.0 * (1.0 - best.heldout_std / before)
            } else {
                0.0
            },
            scored_improvement_pct: if before > 0.0 {
                100.0 * (1.0 - best.heldout_std / before)
            } else {
                0.0
            },
            confirmation: None,
            unconfirmed: None,
            train_residual_std_after: best.train_std,
            members: mine.len(),
            replaces: best_c.replaces.clone(),
            refines: best_c.refines.clone(),
            search: families.get(f).and_then(|x| x.search.clone()),
            searched: families
                .get(f)
                .map(|x| x.searched.clone())
                .unwrap_or_default(),
            estimate: None,
            parameter_scored: None,
            placebo: None,
            passes: false,
            fails: Vec::new(),
            description_nats: 0.0,
            joined: Vec::new(),
            ranked: false,
        });
    }
    (scored, skipped)
}

/// A refitted candidate reading `exprs`, its refit `evidence` nats over the model, not yet tested
/// against placebos: the fixture of the verdict's and the unions' tests.
#[cfg(test)]
pub(crate) fn refitted(exprs: &[&str], evidence: f64) -> Scored {
    let expressions: Vec<String> = exprs.iter().map(|e| e.to_string()).collect();
    Scored {
        expression: expressions.first().cloned().unwrap_or_default(),
        effect: format!("effect {}", expressions.join(", ")),
        expressions,
        kind: EffectKind::LaggedElement,
        parameter: None,
        delta_log_evidence: evidence,
        delta_log_evidence_best: evidence,
        residual_std_after: 1.0,
        residual_std_before: 2.0,
        improvement_pct: 50.0,
        scored_improvement_pct: 50.0,
        confirmation: Some(crate::findings::Confirmation {
            residual_std_before: 2.0,
            residual_std_after: 1.0,
            improvement_pct: 50.0,
            heldout: "blocks".into(),
            splits_improved: 5,
            splits: 5,
            delta_log_evidence_refit: evidence,
            verification: None,
        }),
        unconfirmed: None,
        train_residual_std_after: 1.0,
        members: 1,
        replaces: Vec::new(),
        refines: None,
        search: None,
        searched: crate::candidates::Searched::No,
        estimate: None,
        parameter_scored: None,
        placebo: None,
        passes: false,
        fails: Vec::new(),
        description_nats: 0.0,
        joined: Vec::new(),
        ranked: false,
    }
}
