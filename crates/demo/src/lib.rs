//! The scenario of `tcomp demo` and the simulate → fit → evaluate steps it shares with the tests of
//! the discovery loop.
//!
//! Why a crate of its own: the demo's narrative (diagnose, print, render the report) lives in the
//! tool (`host-tools/src/demo/`), above the analysis crate, so `tcomp-discover` needs no simulator.
//! Its scenario must still be the one the discovery tests run (`hidden_shupe` diagnoses the demo's
//! profiles and effects, with its own seed), so the narrative cannot drift from what is tested. This crate sits below
//! `tcomp-discover` (it needs only the simulator and the trainer): the tool depends on it, and the
//! analysis crate's tests and benchmark use it as a dev-dependency, without a cycle.

mod error;

pub use error::{DemoError, Result};

use std::path::Path;
use tcomp_sim::{Preset, Profile, Segment};
use tcomp_train::metrics::{self, EvalReport, Roles};
use tcomp_train::{Dataset, FitOptions, Fitted};

/// A simulated train/verify pair in memory.
pub struct Simulated {
    /// Training run.
    pub train: Dataset,
    /// Verification run.
    pub verify: Dataset,
    /// Truth of the training run.
    pub train_truth: tcomp_sim::Truth,
    /// Truth of the verification run.
    pub verify_truth: tcomp_sim::Truth,
}

fn dataset(name: &str, t: tcomp_sim::Table) -> Dataset {
    Dataset::from_columns(name, t.names, t.columns)
}

/// The demo's scenario: the `ifog-shupe` preset's sensor and effects, trained on a run that cools
/// and heats at 0.5 °C/min over −10…40 °C, verified on a run over the same range that cools at
/// 1 °C/min and heats at 2 °C/min (rates the training run never saw).
///
/// Why not the preset's own training run: it only heats from 10 to 40 °C, where the (T, dT/dt)
/// model already sits at the noise floor, and its failure on the verification run (down to −10 °C)
/// is temperature extrapolation, which no added feature can repair — the diagnosis rightly finds
/// nothing there. On this run, T·dT/dt is identifiable, and the faster ramps of the verification
/// run are where the (T, dT/dt) model fails.
pub fn demo_preset(seed: u64) -> Result<Preset> {
    let mut p = tcomp_sim::presets::preset("ifog-shupe")?.with_seed(seed);
    p.train.profile = Profile::new(
        20.0,
        vec![
            Segment::hold_h(1.0),
            Segment::ramp(-10.0, 0.5),
            Segment::hold_h(1.0),
            Segment::ramp(40.0, 0.5),
            Segment::hold_h(1.0),
            Segment::ramp(20.0, 0.5),
            Segment::hold_h(0.5),
        ],
    );
    p.verify.profile = Profile::new(
        20.0,
        vec![
            Segment::hold_h(1.0),
            Segment::ramp(-10.0, 1.0),
            Segment::hold_h(1.0),
            Segment::ramp(40.0, 2.0),
            Segment::hold_h(1.0),
            Segment::ramp(20.0, 1.0),
            Segment::hold_h(0.5),
        ],
    );
    Ok(p)
}

/// Simulates both runs of `preset` in memory.
pub fn simulated(preset: &Preset) -> Result<Simulated> {
    let (tt, train_truth) = tcomp_sim::simulate(&preset.train)?;
    let (vt, verify_truth) = tcomp_sim::simulate(&preset.verify)?;
    Ok(Simulated {
        train: dataset("train.csv", tt),
        verify: dataset("verify.csv", vt),
        train_truth,
        verify_truth,
    })
}

/// Fits the default (bayes) model with `signals` and `features` on a simulated run's columns.
pub fn fit_features(
    data: &Dataset,
    truth: &tcomp_sim::Truth,
    signals: &[String],
    features: &[String],
) -> Result<Fitted> {
    let refs: Vec<&str> = features.iter().map(String::as_str).collect();
    let mut o = FitOptions::new(&truth.columns.target, &refs);
    o.spec.signals = signals.to_vec();
    o.reference = Some(truth.columns.reference.clone());
    o.unit.clone_from(&truth.unit);
    Ok(tcomp_train::fit(data, &o)?)
}

/// Runs a fitted model over `data` through its decoded blob, as it flies; `name` is the blob's
/// name in error messages.
pub fn run_fitted(fitted: &Fitted, name: &str, data: &Dataset) -> Result<metrics::Run> {
    let bytes = fitted.model.to_bytes()?;
    let model = tcomp_train::blob_io::decode(Path::new(name), &bytes)?;
    Ok(metrics::run_model(
        &model,
        data,
        &Roles::of_model(&model),
        None,
        None,
    )?)
}

/// Evaluates a fitted model on `data` with 100 s bins (through the decoded blob, as it flies).
pub fn evaluate(fitted: &Fitted, data: &Dataset) -> Result<EvalReport> {
    let run = run_fitted(fitted, "<model>", data)?;
    Ok(metrics::report(&run, 100.0))
}
