//! One channel's pipeline: fit the model and the poly3 baseline on the training rows, diagnose on
//! the training rows only (blocks of them are held out in turn), optionally refit with the effect
//! the diagnosis confirmed, run every candidate once over the held-out rows, and choose what ships.
//!
//! Why the held-out run is touched only at the end: the diagnosis and the `--accept` refit choose
//! on the training run, so each candidate's held-out figure is an honest estimate; only the
//! shipping gate ([`super::ship`]) then looks at the held-out figures, and the report says that
//! this last choice makes the shipped figure optimistic.

use super::ship::{self, Choice};
use super::spec::ChannelPlan;
use crate::output::json::RunFigures;
use anyhow::Context;
use tcomp_discover::{Analysis, DiagnoseOptions, Verdict};
use tcomp_train::metrics::{self, Run};
use tcomp_train::{Dataset, FitOptions, FitSummary, Method};

/// The rows a channel trains and verifies on.
pub struct Windows<'a> {
    /// What `fit` reads (the whole log, limited by `until`, or the training log).
    pub fit_data: &'a Dataset,
    /// Train on time < this (the split), when one log is split.
    pub until: Option<f64>,
    /// The training rows alone (the diagnosis' data).
    pub train: Dataset,
    /// The held-out rows.
    pub verify: Dataset,
}

/// How a channel is run.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Run the diagnosis.
    pub diagnose: bool,
    /// Refit with the effect the diagnosis confirmed.
    pub accept: bool,
    /// Ship the best of model/poly3/raw when the model is flagged.
    pub gate: bool,
}

/// One fitted model and its held-out run.
pub struct Fit {
    /// The blob.
    pub bytes: Vec<u8>,
    /// The trainer's summary.
    pub summary: FitSummary,
    /// The run over the held-out rows.
    pub run: Run,
    /// Its figures.
    pub figures: RunFigures,
}

/// What `--accept` did.
pub struct Accepted {
    /// The diagnosis' instruction that was applied.
    pub instruction: String,
    /// The model before it.
    pub before: Fit,
}

/// A calibrated channel.
pub struct ChannelResult {
    /// The plan it ran.
    pub plan: ChannelPlan,
    /// Resolved options of the model.
    pub opts: FitOptions,
    /// Unit to show.
    pub unit: String,
    /// Segment temperature (the program's first input).
    pub temperature: Option<String>,
    /// Training rows and time span.
    pub train_rows: usize,
    /// Training window (s).
    pub train_span: Option<(f64, f64)>,
    /// Held-out rows.
    pub verify_rows: usize,
    /// Held-out window (s).
    pub verify_span: Option<(f64, f64)>,
    /// The model (after `--accept`, the refit).
    pub model: Fit,
    /// The poly3 baseline.
    pub poly3: Fit,
    /// The diagnosis on the training rows.
    pub analysis: Option<Analysis>,
    /// What `--accept` applied.
    pub accepted: Option<Accepted>,
    /// What ships.
    pub choice: Choice,
}

/// First and last time of `data`.
fn span(data: &Dataset, time: &str) -> Option<(f64, f64)> {
    let t = data.time(time).ok()?;
    Some((*t.first()?, *t.last()?))
}

/// Fits `opts` and runs the blob over the held-out rows.
fn fit_one(w: &Windows<'_>, opts: &FitOptions, gap: Option<f64>) -> anyhow::Result<Fit> {
    let fitted = tcomp_train::fit(w.fit_data, opts)?;
    let bytes = fitted.model.to_bytes()?;
    let model = fitted.model.model()?;
    let roles = tcomp_train::Roles::of_model(&model);
    let temp = model.program.inputs.first().map(|s| s.to_string());
    let run = metrics::run_model(&model, &w.verify, &roles, temp.as_deref(), gap)?;
    let figures = RunFigures::from(&metrics::report(&run, 100.0));
    drop(model);
    Ok(Fit {
        bytes,
        summary: fitted.summary,
        run,
        figures,
    })
}

/// The options of a plan, with the split and the unit resolved.
pub fn options(plan: &ChannelPlan, until: Option<f64>) -> anyhow::Result<FitOptions> {
    let mut opts =
        FitOptions::from_spec(&plan.spec).with_context(|| format!("channel `{}`", plan.name))?;
    opts.until = until;
    if opts.unit.is_empty() {
        opts.unit = crate::render::num::unit_of_column(&opts.target)
            .unwrap_or("")
            .to_string();
    }
    Ok(opts)
}

/// Runs one channel.
pub fn run(plan: &ChannelPlan, w: &Windows<'_>, s: Settings) -> anyhow::Result<ChannelResult> {
    let name = &plan.name;
    let opts = options(plan, w.until)?;
    let gap = plan.spec.run.gap;
    let mut model = fit_one(w, &opts, gap).with_context(|| format!("channel `{name}`: fit"))?;
    let mut poly_opts = opts.clone();
    poly_opts.method = Method::Poly3;
    let poly3 =
        fit_one(w, &poly_opts, gap).with_context(|| format!("channel `{name}`: poly3 baseline"))?;
    let analysis = if s.diagnose {
        Some(
            diagnose(&model, &w.train, gap)
                .with_context(|| format!("channel `{name}`: diagnosis"))?,
        )
    } else {
        None
    };
    let mut accepted = None;
    let mut final_opts = opts.clone();
    if s.accept
        && let Some(a) = &analysis
        && a.diagnosis.verdict == Verdict::MissingEffect
        && let Some(c) = a.diagnosis.candidates.first()
    {
        let mut o = opts.clone();
        o.spec.features.retain(|f| !c.replaces.contains(f));
        o.spec.features.extend(c.expressions.iter().cloned());
        let refit =
            fit_one(w, &o, gap).with_context(|| format!("channel `{name}`: --accept refit"))?;
        accepted = Some(Accepted {
            instruction: tcomp_discover::verdict::instruction(c),
            before: std::mem::replace(&mut model, refit),
        });
        final_opts = o;
    }
    let choice = ship::choose(
        model.figures.raw_rms,
        poly3.figures.residual_rms,
        model.figures.residual_rms,
        s.gate,
    );
    // The segment temperature: the model's first input, as `tcomp report` takes it.
    let temperature = tcomp_train::blob_io::decode(std::path::Path::new(name), &model.bytes)
        .ok()
        .and_then(|m| m.program.inputs.first().map(|s| s.to_string()));
    Ok(ChannelResult {
        unit: final_opts.unit.clone(),
        train_rows: w.train.len(),
        train_span: span(&w.train, &final_opts.time),
        verify_rows: w.verify.len(),
        verify_span: span(&w.verify, &final_opts.time),
        plan: plan.clone(),
        opts: final_opts,
        temperature,
        model,
        poly3,
        analysis,
        accepted,
        choice,
    })
}

/// The diagnosis of `fit` on the training rows alone (blocks of them held out in turn).
fn diagnose(fit: &Fit, train: &Dataset, gap: Option<f64>) -> anyhow::Result<Analysis> {
    let model = tcomp_train::blob_io::decode(std::path::Path::new("model"), &fit.bytes)?;
    // The listed effects only: a line's diagnosis flags units whose model misses a known effect,
    // and the search of compositions would cost the fleet's time budget (issue 24: 1,000 units in
    // 5 min) for effects a line does not act on. `tcomp diagnose` searches them, and
    // cross-validates a parameter the evidence leaves flat.
    let mut opts = DiagnoseOptions {
        compose: false,
        ..DiagnoseOptions::default()
    };
    // A flat parameter at the evidence's maximum, not cross-validated: a third of a line's time
    // (issue 24's budget); the flat interval is reported beside it.
    opts.confirm.cross_validate = false;
    opts.score.gap_s = gap;
    opts.score.bin_s = 60.0;
    Ok(tcomp_discover::diagnose(&model, train, None, &opts)?)
}
