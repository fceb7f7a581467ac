//! The discovery loop of tcomp: compare a model with the measurements, see where it fails, be told
//! which physical effect is most likely missing (with the evidence), add it with one line, and
//! watch the error fall.
//!
//! Modules: [`segments`] (where it fails: warm-up, holds, ramps, bands, worst intervals),
//! [`candidates`] (which effects could be missing, with physical names and ready expressions;
//! what one is, `hypothesis`, and how one with a parameter is built, [`families`]),
//! [`dynamics`] (through how many lags, and which, the residual responds to each input),
//! [`compose`] (the language's functions composed over every input, for effects no family lists),
//! [`score`] (refit with each candidate in parallel: Δ log evidence and held-out residual, against
//! the base model `base` prepares once from the columns and transform of `design`, each
//! expression's column computed once per run, `column_cache`),
//! (the grouped-prior evidence arithmetic under it is `tcomp_train::evidence`), [`confirm`] (the
//! leading candidates refitted by the trainer; two effects that explain the run only together,
//! [`confirm::together`]; a second look in the additive structure, [`confirm::additive`]),
//! [`placebo`] (each against its own columns shifted in time, under AR(1) noise; what both found,
//! `findings`), [`verdict`] (the stated criterion: a missing effect, "cannot tell" or none). The
//! rendering of a diagnosis (text tables, the HTML report) and the built-in demo live in the tool
//! (`host-tools/src/render/`, `host-tools/src/demo/`): this crate analyses, it does not print,
//! and it needs no simulator.
//!
//! ```no_run
//! use tcomp_discover::{DiagnoseOptions, diagnose};
//! let bytes = tcomp_train::blob_io::read("m.tcm".as_ref()).unwrap();
//! let model = tcomp_train::blob_io::decode("m.tcm".as_ref(), &bytes).unwrap();
//! let data = tcomp_train::Dataset::load("train.csv".as_ref()).unwrap();
//! let a = diagnose(&model, &data, None, &DiagnoseOptions::default()).unwrap();
//! println!("{}", a.diagnosis.verdict_text);
//! ```
#![forbid(unsafe_code)]

mod base;
pub mod candidates;
mod column_cache;
pub mod compose;
pub mod confirm;
pub mod description;
mod design;
pub mod dynamics;
pub mod error;
pub mod families;
mod findings;
mod hypothesis;
pub mod joint;
pub mod param;
pub mod placebo;
pub mod regimes;
pub mod rounds;
pub mod score;
pub mod segments;
mod surrogate;
pub mod user_program;
pub mod verdict;

pub use error::{DiscoverError, Result};
pub use rounds::{Rounds, diagnose_rounds};
pub use verdict::{Criterion, Verdict};

use serde::Serialize;
use std::time::Instant;
use tcomp_train::features::FeatureSpec;
use tcomp_train::metrics::{self, Run};
use tcomp_train::{Dataset, Roles};

/// A decoded model blob as the host reads it (the core's one alias at the host capacities).
pub use tcomp_core::HostModel;

/// What diagnosis needs to know about a model: its program's source and column roles.
#[derive(Clone, Debug)]
pub struct ModelInfo {
    /// Signals and features.
    pub spec: FeatureSpec,
    /// Column roles.
    pub roles: Roles,
    /// Output unit.
    pub unit: String,
}

/// The source of a model's program as the user wrote it (see [`user_program::user_spec`]) and its
/// roles.
pub fn model_info(model: &HostModel<'_>) -> ModelInfo {
    ModelInfo {
        spec: user_program::user_spec(&FeatureSpec {
            signals: model
                .program
                .signals
                .iter()
                .map(|s| tcomp_core::expr::define(s.name, &tcomp_core::expr::Expr::text(s.expr)))
                .collect(),
            features: model
                .program
                .feature_exprs
                .iter()
                .map(|s| s.to_string())
                .collect(),
        }),
        roles: Roles::of_model(model),
        unit: model.meta.unit.to_string(),
    }
}

/// Options of [`diagnose`].
#[derive(Clone, Debug)]
pub struct DiagnoseOptions {
    /// Scoring.
    pub score: score::ScoreOptions,
    /// Verdict thresholds.
    pub criterion: Criterion,
    /// Refits of the leading candidates.
    pub confirm: confirm::ConfirmOptions,
    /// Column for segment detection (default: the program's first input).
    pub temperature: Option<String>,
    /// Override of the model's roles (reference column or value).
    pub roles: Option<Roles>,
    /// Also search the compositions of the language's functions ([`compose`]), for effects no
    /// family lists (on by default; `tcomp diagnose --no-compose` turns it off).
    pub compose: bool,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions {
            score: score::ScoreOptions::default(),
            criterion: Criterion::default(),
            confirm: confirm::ConfirmOptions::default(),
            temperature: None,
            roles: None,
            compose: true,
        }
    }
}

impl DiagnoseOptions {
    /// Checks every threshold and bin against its valid range (the flags are named as typed:
    /// `--min-evidence`, `--min-improvement`, `--bin`). A NaN threshold would compare false
    /// everywhere and silently flip the verdict.
    pub fn validate(&self) -> Result<()> {
        self.criterion.validate()?;
        self.score.validate()?;
        self.confirm.validate()?;
        Ok(())
    }
}

/// The model as given.
#[derive(Clone, Debug, Serialize)]
pub struct ModelSummary {
    /// Signals.
    pub signals: Vec<String>,
    /// Features.
    pub features: Vec<String>,
    /// Target column.
    pub target: String,
    /// Unit.
    pub unit: String,
}

/// Everything `tcomp diagnose` reports.
#[derive(Clone, Debug, Serialize)]
pub struct Diagnosis {
    /// "missing_effect", "cannot_tell" or "none".
    pub verdict: Verdict,
    /// The verdict in one sentence.
    pub verdict_text: String,
    /// The criterion in one sentence.
    pub criterion: String,
    /// Its thresholds.
    pub thresholds: Criterion,
    /// The model diagnosed.
    pub model: ModelSummary,
    /// Figures of the model's features under the scoring machinery.
    pub base: score::BaseFigures,
    /// Candidates, best first.
    pub candidates: Vec<score::Scored>,
    /// Candidates not scored, with the reason.
    pub skipped: Vec<score::Skipped>,
    /// Candidate fits computed (members of all families).
    pub fits: usize,
    /// Segments of the data run (residual of the model as given).
    pub segments: Vec<segments::SegmentRow>,
    /// Worst intervals of the data run.
    pub worst_intervals: Vec<segments::Interval>,
    /// Segments of the verification run.
    pub verify_segments: Vec<segments::SegmentRow>,
    /// Worst intervals of the verification run.
    pub verify_worst_intervals: Vec<segments::Interval>,
    /// Held-out residual of the base feature set refitted by the trainer (the "before" of every
    /// confirmed candidate).
    pub refit_residual_std_before: f64,
    /// The user's own fit of the model's features (`tcomp fit`, the trainer's defaults) on the
    /// verification run, when there is one (reported only: `confirm::verify`).
    pub refit_verification_std_before: Option<f64>,
    /// The noise floor the criterion measured removals against: estimated from the training
    /// blocks' held-out residual.
    pub criterion_noise_floor: f64,
    /// Wall time of the diagnosis (s).
    pub elapsed_s: f64,
}

/// A diagnosis with what the report needs besides it.
pub struct Analysis {
    /// The diagnosis.
    pub diagnosis: Diagnosis,
    /// The scoring state (binned residuals, candidate features).
    pub prepared: score::Prepared,
    /// The model run over the data.
    pub run: Run,
    /// The model run over the verification data.
    pub verify_run: Option<Run>,
}

/// Diagnoses `model` on `data` (normally its training run), with held-out figures on `verify`
/// when given (else on contiguous blocks of `data`).
pub fn diagnose(
    model: &HostModel<'_>,
    data: &Dataset,
    verify: Option<&Dataset>,
    opts: &DiagnoseOptions,
) -> Result<Analysis> {
    let t0 = Instant::now();
    opts.validate()?;
    let info = model_info(model);
    let roles = opts.roles.clone().unwrap_or_else(|| info.roles.clone());
    let temp = opts.temperature.as_deref();
    let step = tcomp_train::dataset::median_step(data.time(&roles.time)?);
    if opts.score.bin_s < step {
        return Err(DiscoverError::Invalid(format!(
            "--bin {}: shorter than the sampling step of {} ({} s), so a bin would hold no sample",
            tcomp_train::num::exact(opts.score.bin_s),
            data.file(),
            tcomp_train::num::exact(step)
        )));
    }
    let run = metrics::run_model(model, data, &roles, temp, opts.score.gap_s)?;
    let verify_run = verify
        .map(|v| metrics::run_model(model, v, &roles, temp, opts.score.gap_s))
        .transpose()?;
    let segs = segments::table(&run);
    let worst = segments::worst_intervals(&run, &segs);
    let (vsegs, vworst) = match &verify_run {
        Some(r) => {
            let s = segments::table(r);
            let w = segments::worst_intervals(r, &s);
            (s, w)
        }
        None => (Vec::new(), Vec::new()),
    };
    let prepared = score::prepare(&info.spec, &roles, data, verify, &opts.score)?;
    let mut exclude = vec![roles.time.as_str(), roles.target.as_str()];
    if let Some(r) = &roles.reference {
        exclude.push(r.as_str());
    }
    let src = candidates::sources(data, &exclude, &info.spec.signals);
    let per_symbol = description::nats_per_symbol(&src);
    let mut families = candidates::generate(&src, &info.spec.features);
    families.extend(dynamics::propose(&prepared, &src, &info.spec.features));
    if opts.compose {
        let composed = compose::propose(&prepared, &src, &families);
        families.extend(composed);
    }
    let fits = families.iter().map(|f| f.members.len()).sum();
    let (mut cands, mut skipped) = score::score(&prepared, &families);
    for e in &src.outputs {
        skipped.push(score::Skipped {
            expression: e.clone(),
            effect: format!("other sensor output {e}"),
            reason: "another inertial output carries the motion in flight, not only drift".into(),
        });
    }
    for e in &src.environment {
        skipped.push(score::Skipped {
            expression: e.clone(),
            effect: format!("chamber/ambient temperature {e}"),
            reason: "the environment's temperature is not available to the firmware in flight; \
                     heat flow from it is what rates and lags of the sensor's thermometers describe"
                .into(),
        });
    }
    let runs = confirm::Runs {
        data,
        verify,
        run: Some(&run),
    };
    let refit_before = confirm::confirm(&info, &roles, runs, &mut cands, &opts.confirm, &prepared)?;
    placebo::calibrate(&prepared, &mut cands, opts.criterion.placebos);
    opts.criterion
        .apply(refit_before.noise_floor, per_symbol, &mut cands);
    // The placebos' second stage: the trainer's refits, for the leading candidates that fail only
    // the first stage and have no searched parameter (see `placebo::RefitPlacebos`).
    let retest: Vec<usize> = (0..cands.len())
        .filter(|&i| {
            cands.get(i).is_some_and(|c| {
                c.search.is_none()
                    && !c.searched.is_read()
                    && c.joined.is_empty()
                    && verdict::fails_only_placebos(c)
            })
        })
        .take(2)
        .collect();
    if !retest.is_empty() {
        for &i in &retest {
            let Some(c) = cands.get(i) else { continue };
            let refit = confirm::refit_placebos(
                &info,
                &roles,
                runs,
                &opts.confirm,
                prepared.gap_s,
                c,
                None,
            );
            if let Some(p) = cands.get_mut(i).and_then(|c| c.placebo.as_mut()) {
                p.refit = refit;
            }
        }
        // One threshold for every candidate retested, as in the first stage: the largest placebo
        // of any of them (a candidate is one of several chances to pass).
        fn refit_of(c: &score::Scored) -> Option<&placebo::RefitPlacebos> {
            c.placebo.as_ref().and_then(|p| p.refit.as_ref())
        }
        let threshold = retest
            .iter()
            .filter_map(|&i| cands.get(i).and_then(refit_of))
            .map(|r| r.threshold_pct)
            .fold(f64::NEG_INFINITY, f64::max);
        for &i in &retest {
            if let Some(r) = cands
                .get_mut(i)
                .and_then(|c| c.placebo.as_mut())
                .and_then(|p| p.refit.as_mut())
            {
                r.threshold_pct = threshold;
            }
        }
        opts.criterion
            .apply(refit_before.noise_floor, per_symbol, &mut cands);
    }
    // A second look, in the additive structure the user's fit chooses, at the leading candidates
    // that beat their placebos and fail only the held-out legs, when none passes or when they
    // outweigh the one that does (see `confirm::additive`).
    let passing = cands.first().filter(|c| c.passes).map(|c| {
        c.confirmation
            .as_ref()
            .map_or(f64::INFINITY, |k| k.delta_log_evidence_refit)
    });
    if confirm::additive::second_look(
        &info,
        &roles,
        runs,
        &opts.confirm,
        &prepared,
        &mut cands,
        |c| opts.criterion.second_look(c) && confirm::additive::outweighs(c, passing),
    )? {
        opts.criterion
            .apply(refit_before.noise_floor, per_symbol, &mut cands);
    }
    // The verification run, reported for the candidates the verdict names (see `confirm::verify`).
    let named = verdict::reported(&cands);
    let verification_std = confirm::verify(
        &info,
        &roles,
        runs,
        &opts.confirm,
        prepared.gap_s,
        &mut cands,
        &named,
    )?;
    let (verdict, verdict_text) = verdict::decide(&cands);
    let diagnosis = Diagnosis {
        verdict,
        verdict_text,
        criterion: opts.criterion.text(),
        thresholds: opts.criterion.clone(),
        model: ModelSummary {
            signals: info.spec.signals.clone(),
            features: info.spec.features.clone(),
            target: roles.target.clone(),
            unit: info.unit.clone(),
        },
        base: prepared.figures.clone(),
        candidates: cands,
        skipped,
        fits,
        segments: segs,
        worst_intervals: worst,
        verify_segments: vsegs,
        verify_worst_intervals: vworst,
        refit_residual_std_before: refit_before.residual_std,
        refit_verification_std_before: verification_std,
        criterion_noise_floor: refit_before.noise_floor,
        elapsed_s: t0.elapsed().as_secs_f64(),
    };
    Ok(Analysis {
        diagnosis,
        prepared,
        run,
        verify_run,
    })
}
