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
//! candidate. Held-out data: each of `folds` contiguous blocks of the training run in turn
//! (a verification run is only reported, after the verdict, for the candidates it names, each
//! predicted by the user's own fit: [`verify`]),
//! predicted by a fit on the rest (the time gap resets the feature
//! state), the blocks' binned residual variances pooled — and then the candidate must also lower the
//! residual in a majority of the blocks, so one block's drift cannot carry it. Each feature set's
//! basis (the cubic or the Gaussians) is chosen once, by its refit's evidence on the whole training
//! run, and its blocks' refits are pinned to it (`Refits::whole`): a block's refit that chose
//! again would be judged on that choice, not on the features. Only the blocks in
//! which the candidate's column moves vote; an effect that moves in one block only (a warm-up in a
//! run that soaks first) is tested on parts of that block instead, since a fit on the other blocks
//! never sees it move.
//!
//! Before those refits, the parameter of each leading family (a lag's τ, a window, a threshold) is
//! estimated on a continuous scale by the refits' evidence on the training run ([`crate::param`]),
//! with contiguous blocks of the training run deciding where that evidence is flat — the
//! held-out run is never used to choose. A candidate that replaces some of the model's features
//! (a lag of T in place of T) is refitted with the replaced feature set. Each confirmed candidate
//! also carries the Δ log evidence of the real refits, which ranks the candidates that pass.
//!
//! After them, the leader is joined with each of the next refitted candidates, and the union that
//! earns its place over both parts is refitted and judged like any candidate ([`together`]): two
//! effects missing at once, each standing in for the other in part, are named together.
//!
//! After the verdict's legs, when no candidate passes or when it outweighs the one that does, a
//! candidate that beat its placebos and failed only the held-out legs is judged again with its
//! blocks refitted in the additive structure, when that is what the user's own fit of it chooses
//! ([`additive`]).

pub use crate::findings::{Confirmation, Verification};
use crate::score::{Prepared, Scored};
use crate::{ModelInfo, Result};
use rayon::prelude::*;
use serde::Serialize;
use std::path::Path;
use tcomp_train::method::Basis;
use tcomp_train::{Dataset, FitOptions, Roles, metrics};

/// How the block vote words a candidate it does not confirm (the verdict reads it).
pub(crate) const VOTE: &str = "lowers the held-out residual in only";

pub mod additive;
mod blocks;
pub mod together;
use blocks::{Split, block_splits, parts_of, training_blocks, verification_split};

/// Options of the confirmation.
#[derive(Clone, Debug, Serialize)]
pub struct ConfirmOptions {
    /// Candidates refitted (the best by Δ log evidence among those with positive evidence).
    pub top: usize,
    /// Bin of the held-out residual (s).
    pub heldout_bin_s: f64,
    /// Contiguous blocks of the training run when there is no verification run.
    pub folds: usize,
    /// Where the training run's evidence is flat in a leading family's parameter, choose it by
    /// cross-validation over the blocks ([`crate::param::estimate`]; five refits per block). A
    /// production line's diagnosis turns it off (`tcomp calibrate`: a third of its time) and
    /// takes the evidence's maximum, as it is reported beside the flat interval.
    pub cross_validate: bool,
}

impl Default for ConfirmOptions {
    fn default() -> Self {
        Self {
            top: 5,
            heldout_bin_s: 100.0,
            folds: 5,
            cross_validate: true,
        }
    }
}

impl ConfirmOptions {
    /// Checks the held-out bin and the folds against their valid ranges.
    pub fn validate(&self) -> std::result::Result<(), tcomp_train::TrainError> {
        tcomp_train::options::Bound {
            flag: "heldout_bin_s",
            key: "",
            min: 0.0,
            min_exclusive: true,
            max: 1e7,
            unit: "s",
            why: "the bin of the held-out residual",
        }
        .check(self.heldout_bin_s)?;
        crate::score::FOLDS.check_count(self.folds, "")?;
        Ok(())
    }
}

/// What the confirmation measured of the base feature set, for the criterion and the report.
#[derive(Clone, Copy, Debug)]
pub struct BaseRefit {
    /// Held-out residual std over the training run's blocks.
    pub residual_std: f64,
    /// Noise floor estimated from those blocks' binned residuals (robust, successive
    /// differences): the criterion's yardstick, from the training run only.
    pub noise_floor: f64,
}

/// Pooled held-out residual std, the one of each split, and each split's binned residual.
struct HeldOutFigures {
    pooled: f64,
    each: Vec<f64>,
    binned: Vec<Vec<f64>>,
}

/// A refit's figures on the training blocks, and its log evidence on the whole training run.
type Refitted = (HeldOutFigures, f64);

/// What every refit shares: the model, its roles, the training run and the gap threshold.
pub(crate) struct Refits<'a> {
    info: &'a ModelInfo,
    roles: &'a Roles,
    data: &'a Dataset,
    gap_s: Option<f64>,
}

impl<'a> Refits<'a> {
    /// The refits of the model `info` with `roles` on `data`, gaps above `gap_s`.
    pub(crate) fn new(
        info: &'a ModelInfo,
        roles: &'a Roles,
        data: &'a Dataset,
        gap_s: Option<f64>,
    ) -> Self {
        Refits {
            info,
            roles,
            data,
            gap_s,
        }
    }

    /// The trainer's options for the feature list `features` (the model's signals kept).
    pub(crate) fn options(&self, features: &[String]) -> FitOptions {
        self.options_in(features, None)
    }

    /// The options of the user's own fit of `features`: `tcomp fit` with the model's signals and
    /// these features, the trainer choosing its structure (the additive one offered) as it does
    /// by default. The verification run is predicted by this fit, so the figure the diagnosis
    /// reports there is the one the user gets by adding the candidate. Why not the joint refit
    /// the blocks are judged with: on the fresh `drift_lagging` seed 40000 that refit with
    /// `rate(t_qma_c − t_case_c)` reported the verification run 80 % worse, where the user's fit
    /// with it is 2 % better (it chose the additive structure).
    fn users(&self, features: &[String]) -> FitOptions {
        let mut o = self.options_in(features, None);
        o.settings.bayes.additive = None;
        o.settings.bayes.basis = None;
        o
    }

    /// [`Refits::options`] with the basis pinned to `basis` (see [`Refits::whole`]).
    fn options_in(&self, features: &[String], basis: Option<Basis>) -> FitOptions {
        let mut o = FitOptions::new(&self.roles.target, &[]);
        o.time.clone_from(&self.roles.time);
        o.reference.clone_from(&self.roles.reference);
        o.reference_value = self.roles.reference_value;
        o.gap_s = self.gap_s;
        o.spec.signals.clone_from(&self.info.spec.signals);
        o.spec.features = features.to_vec();
        // The joint model's evidence only: refits of different feature sets are compared on it,
        // and the additive structure's (under AR(1) noise) is another yardstick. Offering it as
        // the user's fit does (where the features read an input, and the blocks' refits pinned
        // to it) named a kink in a second input exactly, 1.21× the floor where the joint refits
        // left it unnamed at 8.23× — but its search in every block's and placebo's refit took a
        // 1,000-unit `calibrate` from 5 min to 8 min 47 s. Pinning the whole run's additive
        // terms in the blocks' refits (weights and hyperparameters refitted, terms the rows
        // cannot weigh left out) made it affordable — `diagnose` 1.8 s, 100 units 31 s against
        // 29 — and passed three more composed scenarios (one lost), but on the negative
        // controls "cannot tell" went from 23 to 49 of 100 and "missing" from 1 to 2 (53 of 100
        // units "cannot tell"), with the model's features compared in the same structure. Why:
        // on the plain controls the same spurious candidates that made the joint refits' blocks
        // worse (−117 %, −386 %, −932 %) made the additive refits' blocks better (−24 % to −48 %
        // of the residual): a feature enters an additive model through a term of its own, and a
        // slow one absorbs a block's extrapolation error by chance, where in a joint model it
        // spoils the Gaussians. The held-out leg's strength here comes from the joint refits;
        // with the additive ones only the placebo leg stands. Not kept: only a candidate that
        // beat its placebos and failed only the held-out legs gets its blocks refitted in the
        // additive structure, judged against its placebos refitted the same way
        // ([`additive`]).
        o.settings.bayes.additive = Some(basis == Some(Basis::Additive));
        o.settings.bayes.basis = basis.map(|b| {
            match b {
                Basis::Cubic => "cubic",
                Basis::Gaussians => "gaussians",
                Basis::Additive => "additive",
            }
            .to_string()
        });
        o
    }

    /// The trainer's refit of `features` on the whole training run: its log evidence (−∞ when
    /// it fails) and the basis its evidence chose there, which the held-out blocks' refits are
    /// then pinned to ([`heldout_std`]).
    ///
    /// Why: a block's refit that chooses its basis again on the rest of the run can choose
    /// otherwise, and its prediction of the block then judges that choice, not the features.
    /// Measured: with `lag(abs(supply_v − 28.1), 900)` (+540 nats), the fit without the cooling
    /// block chose Gaussians in T over the cubic (by 36 nats, where the whole run chose the
    /// cubic) and predicted the block at 38.0 against the model's 20.8, while the candidate
    /// halved the other four blocks' residuals: the pooled figure rejected it. The basis is chosen
    /// on the training run, once, as the user's own fit chooses it.
    fn whole(&self, features: &[String]) -> (f64, Option<Basis>) {
        tcomp_train::fit_unmeasured(self.data, &self.options(features))
            .ok()
            .map_or((f64::NEG_INFINITY, None), |(_, details)| {
                (
                    details
                        .evidence
                        .map_or(f64::NEG_INFINITY, |e| e.log_evidence),
                    details.basis,
                )
            })
    }

    /// [`heldout_std`] with the basis the whole run's refit of `features` chose.
    fn judged(&self, splits: &[Split], features: &[String]) -> Result<HeldOutFigures> {
        let (_, basis) = self.whole(features);
        heldout_std(self, splits, features, basis)
    }

    /// The model's features with the scored candidate `c` applied (none: the model's own).
    fn features(&self, c: Option<&Scored>) -> Vec<String> {
        match c {
            Some(c) => c.candidate().applied_to(&self.info.spec.features),
            None => self.info.spec.features.clone(),
        }
    }

    /// Estimates the parameter of a searched candidate (see [`crate::param`]) and moves the
    /// candidate to the estimate.
    fn estimate(
        &self,
        c: &mut Scored,
        prepared: &Prepared,
        blocks: &[Split],
        cross_validate: bool,
    ) {
        let Some(search) = c.search.clone() else {
            return;
        };
        let features = &self.info.spec.features;
        let evidence = |p: f64| {
            crate::surrogate::log_evidence(
                prepared,
                &search.template.member(p).applied_to(features),
                features.len(),
            )
        };
        let information = |p: f64| {
            crate::surrogate::information(
                prepared,
                &search.template.member(p).applied_to(features),
                features.len(),
            )
        };
        let heldout = |p: f64| {
            if !cross_validate {
                return None;
            }
            self.judged(blocks, &search.template.member(p).applied_to(features))
                .ok()
                .map(|r| r.pooled)
        };
        let Some(est) = crate::param::estimate(&search, &evidence, &information, &heldout) else {
            return;
        };
        let m = search.template.member(est.value);
        if m.expressions != c.expressions {
            c.parameter_scored = c.parameter;
        }
        c.expression = m.expressions.first().cloned().unwrap_or_default();
        c.expressions = m.expressions;
        c.effect = m.effect;
        c.parameter = m.parameter;
        c.replaces = m.replaces;
        c.refines = m.refines;
        c.estimate = Some(est);
    }
}

/// Held-out residual std (binned) of a fit of `features`: pooled over the splits as the root of
/// the bin-weighted mean variance, and per split.
fn heldout_std(
    r: &Refits<'_>,
    splits: &[Split],
    features: &[String],
    basis: Option<Basis>,
) -> Result<HeldOutFigures> {
    heldout_std_with(r, splits, &r.options_in(features, basis))
}

/// [`heldout_std`] of the fit the options `o` make.
fn heldout_std_with(r: &Refits<'_>, splits: &[Split], o: &FitOptions) -> Result<HeldOutFigures> {
    let (mut sum, mut count) = (0.0f64, 0usize);
    let mut each = Vec::with_capacity(splits.len());
    let mut binned = Vec::with_capacity(splits.len());
    for sp in splits {
        // The refit's own training figures are not read: it is measured on the held-out rows.
        let (fitted, _) = tcomp_train::fit_unmeasured(&sp.train, o)?;
        let bytes = fitted.to_bytes()?;
        let model = tcomp_train::blob_io::decode(Path::new("<refit>"), &bytes)?;
        let roles = Roles::of_model(&model);
        let run = match sp.score {
            Some(window) => {
                metrics::run_model_window(&model, &sp.test, &roles, None, r.gap_s, window)?
            }
            None => metrics::run_model(&model, &sp.test, &roles, None, r.gap_s)?,
        };
        let b = metrics::report(&run, sp.bin_s).binned;
        sum += b.residual_std.powi(2) * b.bins as f64;
        count += b.bins;
        each.push(b.residual_std);
        let bins = tcomp_train::binning::bins(&run.time, sp.bin_s);
        binned.push(tcomp_train::binning::bin_mean(&run.residual, &bins));
    }
    let pooled = if count > 0 {
        (sum / count as f64).sqrt()
    } else {
        f64::NAN
    };
    Ok(HeldOutFigures {
        pooled,
        each,
        binned,
    })
}

/// A block's candidate column varies less than this fraction of its variation over the whole run:
/// the block cannot tell the candidate from a constant, and does not vote.
const STILL: f64 = 0.1;

/// Which held-out blocks vote on `c`: those where one of its columns varies (its std inside the
/// block at least [`STILL`] of its std over the run). Why: an effect confined in time — a warm-up
/// after power-on, a relay that switches once — moves the prediction in one block only; in the
/// others the refit's residual goes up or down by its own noise, and counting those as votes
/// made a warm-up found with 576 nats unconfirmable (2 of 5 blocks, 4 of them blind to it). The
/// whole set votes when a column cannot be computed or a block has no window.
fn voting_blocks(
    info: &ModelInfo,
    roles: &Roles,
    data: &Dataset,
    gap_s: Option<f64>,
    splits: &[blocks::Split],
    c: &Scored,
) -> Vec<bool> {
    motion(info, roles, data, gap_s, splits, c)
        .iter()
        .map(|m| *m >= STILL)
        .collect()
}

/// How much `c` moves in each split: the largest ratio over its columns of the std inside the
/// split's window to the std over the run (∞ when it cannot be computed or there is no window).
fn motion(
    info: &ModelInfo,
    roles: &Roles,
    data: &Dataset,
    gap_s: Option<f64>,
    splits: &[blocks::Split],
    c: &Scored,
) -> Vec<f64> {
    let all = vec![f64::INFINITY; splits.len()];
    let Ok(time) = data.time(&roles.time) else {
        return all;
    };
    let spec = tcomp_train::features::FeatureSpec {
        signals: info.spec.signals.clone(),
        features: c.expressions.clone(),
    };
    let Ok(program) = spec.program() else {
        return all;
    };
    let starts = tcomp_train::dataset::stretch_starts(time, gap_s);
    let Ok(rows) = tcomp_train::features::compute(&program, data, time, &starts) else {
        return all;
    };
    let std_of = |k: usize, lo: f64, hi: f64| -> f64 {
        let v: Vec<f64> = rows
            .iter()
            .zip(time)
            .filter(|(_, t)| **t >= lo && **t < hi)
            .filter_map(|(r, _)| r.get(k).copied().map(f64::from))
            .filter(|x| x.is_finite())
            .collect();
        crate::design::mean_sd(&v).1
    };
    let k = c.expressions.len();
    let whole: Vec<f64> = (0..k)
        .map(|j| std_of(j, f64::NEG_INFINITY, f64::INFINITY))
        .collect();
    splits
        .iter()
        .map(|sp| match sp.score {
            Some((lo, hi)) => (0..k)
                .map(|j| {
                    let w = whole.get(j).copied().unwrap_or(f64::NAN);
                    let b = std_of(j, lo, hi);
                    if w.is_finite() && w > 0.0 && b.is_finite() {
                        b / w
                    } else {
                        f64::INFINITY
                    }
                })
                .fold(0.0, f64::max),
            None => f64::INFINITY,
        })
        .collect()
}

/// Parts the one block an effect moves in is cut into (see [`localized`]).
const PARTS: usize = 4;

/// The held-out test of an effect that moves in one block only (a warm-up after power-on in a
/// run that soaks first): a fit on the other blocks never sees it move, so it cannot predict
/// that block, and holding blocks out has no power. That block is cut into [`PARTS`] parts
/// instead, each predicted by a fit on the rest of the run (the base refitted alike), and the
/// parts where the effect moves vote. `None` when it moves in more than one block, or in none.
/// Returns (before, after, improved parts, voting parts, what was held out).
fn localized(
    refits: &Refits<'_>,
    opts: &ConfirmOptions,
    splits: &[Split],
    c: &Scored,
) -> Option<(f64, f64, usize, usize, String)> {
    let (info, roles, data, gap_s) = (refits.info, refits.roles, refits.data, refits.gap_s);
    let m = motion(info, roles, data, gap_s, splits, c);
    let moving: Vec<usize> = (0..m.len()).filter(|&i| m[i] >= STILL).collect();
    let &[only] = moving.as_slice() else {
        return None;
    };
    let window = splits.get(only)?.score?;
    let parts = parts_of(roles, data, opts, window, PARTS).ok()?;
    let before = refits.judged(&parts, &refits.features(None)).ok()?;
    let after = refits.judged(&parts, &refits.features(Some(c))).ok()?;
    let voting = voting_blocks(info, roles, data, gap_s, &parts, c);
    let improved = after
        .each
        .iter()
        .zip(&before.each)
        .zip(&voting)
        .filter(|((a, b), v)| **v && a < b)
        .count();
    let n = voting.iter().filter(|v| **v).count();
    Some((
        before.pooled,
        after.pooled,
        improved,
        n,
        format!(
            "{} parts of [{}, {}) s, the one block it moves in, each predicted by a fit on the rest",
            parts.len(),
            tcomp_train::num::exact(window.0.max(0.0)),
            tcomp_train::num::exact(window.1)
        ),
    ))
}

/// The runs a confirmation reads.
#[derive(Clone, Copy)]
pub struct Runs<'a> {
    /// The training run (the rows diagnosed).
    pub data: &'a Dataset,
    /// The verification run, reported only.
    pub verify: Option<&'a Dataset>,
    /// The model as given, run over `data`: its temperature ramps make the training run's blocks.
    pub run: Option<&'a metrics::Run>,
}

/// Compositions refitted besides the listed families' leading candidates (a slot whose refit
/// cannot be made passes to the next composition, see [`confirm`]).
pub const COMPOSED_REFITS: usize = 2;

/// Compositions ranked for those slots (the most by evidence): as many as the slots and their
/// failover can reach, twice the slots.
pub const RANKED: usize = 2 * COMPOSED_REFITS;

/// How a refitted candidate is judged on the held-out blocks, against the base's refit there.
struct Judge<'a> {
    refits: &'a Refits<'a>,
    opts: &'a ConfirmOptions,
    splits: &'a [Split],
    /// The base feature set's refit on the blocks.
    base: &'a HeldOutFigures,
    /// The base's refit's log evidence on the whole training run.
    base_evidence: f64,
    /// What the held-out data is, in words.
    heldout: &'a str,
}

impl Judge<'_> {
    /// Gives `c` the confirmation of its refit's `figures` on the blocks and its whole-run
    /// `evidence`; `how` says in what structure the refit was made when not the joint one.
    fn judge(&self, c: &mut Scored, figures: HeldOutFigures, evidence: f64, how: Option<&str>) {
        let r = self.refits;
        let voting = voting_blocks(r.info, r.roles, r.data, r.gap_s, self.splits, c);
        let mut splits_improved = figures
            .each
            .iter()
            .zip(&self.base.each)
            .zip(&voting)
            .filter(|((a, b), v)| **v && a < b)
            .count();
        let mut n = voting.iter().filter(|v| **v).count();
        let (mut before, mut after, mut heldout) =
            (self.base.pooled, figures.pooled, self.heldout.to_string());
        if figures.each.len() > 1
            && n <= 1
            && let Some((b, a, k, v, what)) = localized(r, self.opts, self.splits, c)
        {
            (before, after, splits_improved, n, heldout) = (b, a, k, v, what);
        }
        if let Some(how) = how {
            heldout = format!("{heldout}, {how}");
        }
        let improvement_pct = 100.0 * (1.0 - after / before);
        c.confirmation = Some(Confirmation {
            residual_std_before: before,
            residual_std_after: after,
            improvement_pct,
            heldout,
            splits_improved,
            splits: n,
            delta_log_evidence_refit: evidence - self.base_evidence,
            verification: None,
        });
        c.residual_std_before = before;
        c.residual_std_after = after;
        c.improvement_pct = improvement_pct;
        // With blocks, a real effect lowers the residual in most of them; a pooled gain that
        // one block carries is more likely that block's drift. Only the blocks where the
        // candidate moves vote (see `voting_blocks`).
        c.unconfirmed = (figures.each.len() > 1 && 2 * splits_improved <= n)
            .then(|| format!("{} {splits_improved} of {n} blocks", VOTE));
    }
}

/// Refits the leading candidates (their parameters estimated first, on the binned training run of
/// `prepared`) and replaces their held-out figures with the real ones; every other candidate is
/// marked unconfirmed. The refits split the run at the gaps `prepared` does.
///
/// Honest selection: the held-out figures the criterion reads come from blocks of the training run
/// (one per temperature ramp when it has a few, see `blocks::regime_edges`), each predicted by a fit on
/// the rest. A verification run is not read here: it is used once, after the verdict, to say how
/// the choice fares, never to make it ([`verify`]). Returns the refitted base's figures.
pub fn confirm(
    info: &ModelInfo,
    roles: &Roles,
    runs: Runs<'_>,
    cands: &mut Vec<Scored>,
    opts: &ConfirmOptions,
    prepared: &Prepared,
) -> Result<BaseRefit> {
    let Runs { data, run, .. } = runs;
    let refits = Refits::new(info, roles, data, prepared.gap_s);
    let blocks = training_blocks(roles, data, opts, run)?;
    let (splits, heldout) = block_splits(&blocks);
    let mut order: Vec<usize> = (0..cands.len())
        .filter(|&i| cands[i].delta_log_evidence >= 0.0)
        .collect();
    order.sort_by(|&a, &b| {
        cands[b]
            .delta_log_evidence
            .total_cmp(&cands[a].delta_log_evidence)
    });
    // The compositions ([`crate::compose`]) have slots of their own: a search of many shapes must
    // not crowd the listed families out of their refits (measured: the demo's Shupe term, judged
    // on its held-out refits, lost its slot to three compositions and went unnamed).
    let composed = |i: &usize| {
        matches!(
            cands[*i].searched,
            crate::candidates::Searched::Alternatives { .. }
        )
    };
    let listed: Vec<usize> = order
        .iter()
        .copied()
        .filter(|i| !composed(i))
        .take(opts.top)
        .collect();
    // The compositions' slots go to the [`RANKED`] with the most evidence, in the order of the
    // statistic of the leg they must pass: the first stage of the placebos (their parameters are
    // searched, so no second stage). Under independent noise a slow shape that follows the
    // residual's drift outranks a fast one that explains the effect (measured:
    // `sq(rate(t_qma_c))` third by evidence, behind a lagged relay on T and a lagged clamp of the
    // supply, so never refitted; the two refitted, a union of lags was named and the verification
    // run went +99 %). Ranked by that statistic, the slots are chosen by it, so every ranked
    // composition's placebos count in the leg's threshold, refitted or not (the max-statistic
    // over every candidate the choice looked at: [`crate::placebo::calibrate`]).
    let mut compositions: Vec<usize> = order
        .iter()
        .copied()
        .filter(composed)
        .take(RANKED)
        .collect();
    let alone = crate::placebo::statistics_alone(
        prepared,
        &compositions.iter().map(|&i| &cands[i]).collect::<Vec<_>>(),
    );
    let mut ranked: Vec<(usize, f64)> = compositions.iter().copied().zip(alone).collect();
    ranked.sort_by(|a, b| b.1.total_cmp(&a.1));
    compositions = ranked.into_iter().map(|(i, _)| i).collect();
    for c in cands.iter_mut() {
        c.ranked = false;
    }
    for &i in &compositions {
        if let Some(c) = cands.get_mut(i) {
            c.ranked = true;
        }
    }
    // Each batch: the candidates' parameters estimated, then every refit at once (the base's in
    // the first batch only).
    let refit_batch = |batch: &[usize], cands: &mut [Scored], with_base: bool| {
        let mut leading: Vec<Scored> = batch
            .iter()
            .filter_map(|&i| cands.get(i).cloned())
            .collect();
        leading
            .par_iter_mut()
            .for_each(|c| refits.estimate(c, prepared, &blocks, opts.cross_validate));
        for (&i, c) in batch.iter().zip(leading) {
            if let Some(slot) = cands.get_mut(i) {
                *slot = c;
            }
        }
        let mut jobs: Vec<Option<usize>> = Vec::new();
        if with_base {
            jobs.push(None);
        }
        jobs.extend(batch.iter().map(|&i| Some(i)));
        let cands = &*cands;
        jobs.par_iter()
            .map(|job| {
                let features = refits.features(job.and_then(|i| cands.get(i)));
                let (evidence, basis) = refits.whole(&features);
                let figures = heldout_std(&refits, &splits, &features, basis)?;
                Ok((figures, evidence))
            })
            .collect::<Vec<Result<Refitted>>>()
    };
    let first = &compositions[..COMPOSED_REFITS.min(compositions.len())];
    order.retain(|i| listed.contains(i) || first.contains(i));
    let mut results = refit_batch(&order, cands, true).into_iter();
    let (base_figures, base_evidence) = results
        .next()
        .unwrap_or_else(|| Err(crate::DiscoverError::Invalid("no base refit".into())))?;
    let mut outcome: Vec<(usize, std::result::Result<Refitted, String>)> = order
        .iter()
        .copied()
        .zip(results.map(|r| r.map_err(|e| e.to_string())))
        .collect();
    // A composition whose refit cannot be made hands its slot to the next one: a search of many
    // shapes must not lose the shape the run can test to shapes it cannot. Measured: two clamps of
    // a rate to a narrow band that the rate crosses inside one block only (so the refit holding
    // that block out saw a constant column, and failed) took both slots, and a relay on the
    // supply times T, third by evidence, went untested. At most twice the slots are tried, so
    // that a run of shapes that cannot be refitted costs a bounded number of refits.
    let mut next = COMPOSED_REFITS.min(compositions.len());
    loop {
        let ok = outcome
            .iter()
            .filter(|(i, r)| r.is_ok() && compositions.contains(i))
            .count();
        let batch: Vec<usize> = compositions
            .iter()
            .copied()
            .skip(next)
            .take(COMPOSED_REFITS.saturating_sub(ok))
            .collect();
        if batch.is_empty() {
            break;
        }
        next += batch.len();
        let results = refit_batch(&batch, cands, false);
        outcome.extend(
            batch
                .iter()
                .copied()
                .zip(results.into_iter().map(|r| r.map_err(|e| e.to_string()))),
        );
    }
    let before = base_figures.pooled;
    let base = BaseRefit {
        residual_std: before,
        noise_floor: crate::design::floor_estimate(&base_figures.binned),
    };
    for c in cands.iter_mut() {
        c.confirmation = None;
        c.unconfirmed = Some(format!(
            "not among the {} candidates with the most evidence that were refitted",
            opts.top
        ));
    }
    let judge = Judge {
        refits: &refits,
        opts,
        splits: &splits,
        base: &base_figures,
        base_evidence,
        heldout: &heldout,
    };
    for (i, r) in outcome {
        let Some(c) = cands.get_mut(i) else { continue };
        match r {
            Ok((figures, evidence)) => judge.judge(c, figures, evidence, None),
            Err(e) => c.unconfirmed = Some(format!("the refit with it failed: {e}")),
        }
    }
    // Two effects that explain the run only together ([`together`]): the unions' whole-run
    // refits, and the blocks of the one that earns its place.
    let unions = together::pairs(cands);
    if !unions.is_empty() {
        let wholes: Vec<(Scored, f64, Option<Basis>)> = unions
            .into_par_iter()
            .map(|u| {
                let (evidence, basis) = refits.whole(&refits.features(Some(&u)));
                (u, evidence - base_evidence, basis)
            })
            .collect();
        if let Some((mut u, gain, basis)) = together::earning(wholes)
            && let Ok(figures) = heldout_std(&refits, &splits, &refits.features(Some(&u)), basis)
            && let Ok(s) = crate::score::score_member(prepared, &u.candidate())
        {
            // The scoring's figures, as every candidate carries them (leg 1 reads its evidence).
            let scored_before = prepared.figures.heldout_residual_std;
            u.delta_log_evidence = s.delta;
            u.delta_log_evidence_best = s.delta;
            u.train_residual_std_after = s.train_std;
            u.scored_improvement_pct = if scored_before > 0.0 {
                100.0 * (1.0 - s.heldout_std / scored_before)
            } else {
                0.0
            };
            judge.judge(&mut u, figures, base_evidence + gain, None);
            cands.push(u);
        }
    }
    Ok(base)
}

/// The verification run's figures of the candidates at `named` (their places in `cands`, those the
/// verdict's sentence gives: [`crate::verdict::reported`]): each predicted by the user's own fit
/// with the candidate ([`Refits::users`]) against the user's fit of the model's features. Returns
/// the latter's residual std on the run (None without a verification run).
///
/// Why after the verdict and for those only: the run never chooses (the figure is reported), and
/// the user's fit is the trainer's whole search with the additive structure offered, the dearest
/// fit a diagnosis makes. Made for every refitted candidate before the verdict (the base, the
/// leading families, the compositions: six to eight fits) it took `diagnose --verify` on the RLG
/// preset from 2.7–3.5 s to 3.2–4.2 s and the CI's discovery tests 28–72 % longer, for figures
/// the report never printed (the candidate table shows the training run's held-out blocks).
/// With a verification run the JSON gives them for the named candidates alone.
pub(crate) fn verify(
    info: &ModelInfo,
    roles: &Roles,
    runs: Runs<'_>,
    opts: &ConfirmOptions,
    gap_s: Option<f64>,
    cands: &mut [Scored],
    named: &[usize],
) -> Result<Option<f64>> {
    let Some((sp, run)) = verification_split(roles, runs.data, runs.verify, opts)? else {
        return Ok(None);
    };
    let refits = Refits::new(info, roles, runs.data, gap_s);
    let jobs: Vec<Option<usize>> = std::iter::once(None)
        .chain(
            named
                .iter()
                .copied()
                .filter(|&i| cands.get(i).is_some_and(|c| c.confirmation.is_some()))
                .map(Some),
        )
        .collect();
    let shared = &*cands;
    let figures = jobs
        .par_iter()
        .map(|job| {
            let features = refits.features(job.and_then(|i| shared.get(i)));
            heldout_std_with(&refits, std::slice::from_ref(&sp), &refits.users(&features))
                .ok()
                .map(|f| f.pooled)
        })
        .collect::<Vec<Option<f64>>>();
    // A figure that is only reported fails alone: a fit that cannot be made leaves it out, and
    // the verdict stands as the training run decided it.
    let Some((&Some(before), after)) = figures.split_first() else {
        return Ok(None);
    };
    for (job, &after) in jobs.iter().skip(1).zip(after) {
        let Some((k, after)) = job
            .and_then(|i| cands.get_mut(i))
            .and_then(|c| c.confirmation.as_mut())
            .zip(after)
        else {
            continue;
        };
        k.verification = Some(Verification {
            run: run.clone(),
            residual_std_before: before,
            residual_std_after: after,
            change_pct: 100.0 * (after / before - 1.0),
        });
    }
    Ok(Some(before))
}

/// The trainer's refits of `c`'s placebos (the second stage of [`crate::placebo`]): `c`'s feature
/// columns computed over the training run, shifted circularly by the first stage's shifts (bins
/// converted to rows), added to the run as columns and refitted beside the model's features on
/// the same blocks as `c`'s confirmation; each placebo's held-out improvement. None when `c` was
/// not confirmed or tested.
pub(crate) fn refit_placebos(
    info: &ModelInfo,
    roles: &Roles,
    runs: Runs<'_>,
    opts: &ConfirmOptions,
    gap_s: Option<f64>,
    c: &Scored,
    pinned: Option<Basis>,
) -> Option<crate::placebo::RefitPlacebos> {
    let k = c.confirmation.as_ref()?;
    let first = c.placebo.as_ref()?;
    let data = runs.data;
    let spec = tcomp_train::features::FeatureSpec {
        signals: info.spec.signals.clone(),
        features: c.expressions.clone(),
    };
    let program = spec.program().ok()?;
    let time = data.time(&roles.time).ok()?;
    let starts = tcomp_train::dataset::stretch_starts(time, gap_s);
    let rows = tcomp_train::features::compute(&program, data, time, &starts).ok()?;
    let n = rows.len();
    if n == 0 {
        return None;
    }
    let count = first.placebos.len().max(1);
    let nb = crate::placebo::bins_of(first).max(1);
    let mut names = data.names().to_vec();
    let mut cols: Vec<Vec<f64>> = names
        .iter()
        .map(|m| data.column(m).map(<[f64]>::to_vec).unwrap_or_default())
        .collect();
    let mut sets = Vec::with_capacity(count);
    for (p, &s) in first.shifts_bins.iter().enumerate() {
        let shift = s * n / nb;
        let mut set = Vec::new();
        for j in 0..c.expressions.len() {
            let name = format!("placebo_{p}_{j}");
            cols.push(
                (0..n)
                    .map(|i| {
                        rows.get((i + n - shift % n) % n)
                            .and_then(|r| r.get(j))
                            .map_or(f64::NAN, |v| f64::from(*v))
                    })
                    .collect(),
            );
            names.push(name.clone());
            set.push(name);
        }
        sets.push(set);
    }
    let extended = Dataset::from_columns(data.file(), names, cols);
    let blocks = training_blocks(roles, &extended, opts, runs.run).ok()?;
    let (splits, _) = block_splits(&blocks);
    let refits = Refits::new(info, roles, &extended, gap_s);
    // Each placebo is judged in the basis the candidate's whole-run refit chose, as the candidate
    // was (one refit, where a choice per placebo would cost one each), unless `pinned`.
    let basis = match pinned {
        Some(b) => Some(b),
        None => {
            let on_run = Refits::new(info, roles, data, gap_s);
            on_run.whole(&on_run.features(Some(c))).1
        }
    };
    let before = k.residual_std_before;
    let placebos_pct: Vec<f64> = sets
        .par_iter()
        .map(|set| {
            let mut features = info.spec.features.clone();
            features.extend(set.iter().cloned());
            heldout_std(&refits, &splits, &features, basis)
                .map_or(f64::NEG_INFINITY, |f| 100.0 * (1.0 - f.pooled / before))
        })
        .collect();
    let threshold_pct = placebos_pct
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    Some(crate::placebo::RefitPlacebos {
        improvement_pct: k.improvement_pct,
        placebos_pct,
        threshold_pct,
    })
}
