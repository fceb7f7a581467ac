//! The built-in demo: an IFOG whose bias holds a Shupe-type T·dT/dt term, fitted first with the
//! traditional (T, dT/dt) model; the diagnosis finds the missing term, one more feature fixes it,
//! and the error falls on a verification profile the fit never saw.
//!
//! Why in the library: the README's main command must work with no user data, and the same steps
//! (simulate in memory, fit, diagnose, refit, evaluate) are what the tests run, so the narrative
//! cannot drift from what the tool does. The helpers [`simulated`] and [`fit_features`] are shared
//! with the tests.

use crate::error::{DiscoverError, Result};
use crate::{DiagnoseOptions, Verdict, diagnose, report};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use tcomp_sim::{Preset, TruthFile};
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
    use tcomp_sim::{Profile, Segment};
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

/// Evaluates a fitted model on `data` with 100 s bins (through the decoded blob, as it flies).
pub fn evaluate(fitted: &Fitted, data: &Dataset) -> Result<EvalReport> {
    let bytes = fitted.model.to_bytes()?;
    let model = tcomp_train::blob_io::decode(Path::new("<model>"), &bytes)?;
    let run = metrics::run_model(&model, data, &Roles::of_model(&model), None, None)?;
    Ok(metrics::report(&run, 100.0))
}

/// Options of the demo.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// Output directory.
    pub out: PathBuf,
    /// Seed of the simulation.
    pub seed: u64,
    /// Output step of the simulated runs (s); 1 s by default, larger for quick checks.
    pub step_s: f64,
}

impl Default for DemoOptions {
    fn default() -> Self {
        Self {
            out: PathBuf::from("tcomp-demo"),
            seed: 1,
            step_s: 1.0,
        }
    }
}

/// What the demo found, besides its narrative.
#[derive(Clone, Debug)]
pub struct DemoOutcome {
    /// The narrative, line by line.
    pub text: String,
    /// Verdict of the diagnosis.
    pub verdict: Verdict,
    /// The feature(s) added.
    pub added: Vec<String>,
    /// Held-out residual std (100 s bins) before and after.
    pub before: f64,
    /// After adding the feature.
    pub after: f64,
    /// The noise floor of the verification run (100 s bins).
    pub noise_floor: f64,
    /// Files written.
    pub files: Vec<PathBuf>,
}

fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).map_err(|source| DiscoverError::Io {
        file: path.display().to_string(),
        source,
    })
}

/// Runs the demo, writing blobs, data and the report into `opts.out`; `say` receives each
/// paragraph of the narrative as it happens.
pub fn run(opts: &DemoOptions, mut say: impl FnMut(&str)) -> Result<DemoOutcome> {
    let mut text = String::new();
    let mut tell = |s: String| {
        say(&s);
        text.push_str(&s);
        text.push('\n');
    };
    std::fs::create_dir_all(&opts.out).map_err(|source| DiscoverError::Io {
        file: opts.out.display().to_string(),
        source,
    })?;
    let preset = demo_preset(opts.seed)?.with_rate(1.0 / opts.step_s.min(1.0), opts.step_s);
    tell(format!(
        "1. Simulating an IFOG in a temperature chamber (effects of the `ifog-shupe` preset, seed {}).\n   \
         Its bias holds poly(T) + rate(T) + a Shupe-type T·dT/dt term. Training run: 20 °C, \
         cooled and heated at 0.5 °C/min between −10 and 40 °C. Verification run: the same \
         range, cooling at 1 °C/min and heating at 2 °C/min.",
        opts.seed
    ));
    let sim = simulated(&preset)?;
    let floor = sim.verify_truth.noise.std_100s;
    let unit = sim.train_truth.unit.clone();
    let mut files = Vec::new();
    let save_csv = |name: &str, d: &Dataset, files: &mut Vec<PathBuf>| -> Result<()> {
        let p = opts.out.join(name);
        let mut s = d.names().join(",");
        s.push('\n');
        let cols: Vec<&[f64]> = d.names().iter().filter_map(|n| d.column(n).ok()).collect();
        for i in 0..d.len() {
            let row: Vec<String> = cols
                .iter()
                .map(|c| format!("{}", c.get(i).copied().unwrap_or(f64::NAN)))
                .collect();
            s.push_str(&row.join(","));
            s.push('\n');
        }
        write(&p, s.as_bytes())?;
        files.push(p);
        Ok(())
    };
    save_csv("train.csv", &sim.train, &mut files)?;
    save_csv("verify.csv", &sim.verify, &mut files)?;
    let temp = sim
        .train_truth
        .columns
        .thermometers
        .first()
        .cloned()
        .unwrap_or_else(|| "t_coil_c".into());
    let base_features = vec![temp.clone(), format!("rate({temp})")];
    let before = fit_features(&sim.train, &sim.train_truth, &[], &base_features)?;
    let before_path = opts.out.join("before.tcm");
    tcomp_train::blob_io::write_atomic(&before_path, &before.model.to_bytes()?)?;
    files.push(before_path.clone());
    let ev_before = evaluate(&before, &sim.verify)?;
    tell(format!(
        "2. Fitting the traditional model on (T, dT/dt): --feature {temp} --feature 'rate({temp})'.\n   \
         Training residual (100 s bins): {:.4} {unit}. On the verification run: {:.4} {unit} — \
         {:.1}× the noise floor of {:.4} {unit}.",
        before.summary.train.binned.residual_std,
        ev_before.binned.residual_std,
        ev_before.binned.residual_std / floor,
        floor
    ));
    let bytes = before.model.to_bytes()?;
    let model = tcomp_train::blob_io::decode(&before_path, &bytes)?;
    let analysis = diagnose(
        &model,
        &sim.train,
        Some(&sim.verify),
        &DiagnoseOptions::default(),
    )?;
    let d = &analysis.diagnosis;
    let mut segs: Vec<&crate::segments::SegmentRow> = d
        .verify_segments
        .iter()
        .filter(|s| s.kind != "band")
        .collect();
    segs.sort_by(|a, b| b.residual_std.total_cmp(&a.residual_std));
    let worst: Vec<String> = segs
        .iter()
        .take(2)
        .map(|s| {
            format!(
                "{} ({:.0}–{:.0} min: {:.4} {unit})",
                s.label,
                s.start_s / 60.0,
                s.end_s / 60.0,
                s.residual_std
            )
        })
        .collect();
    tell(format!(
        "3. Where it fails: on the verification run the residual is largest during {}.",
        worst.join(" and ")
    ));
    let mut s = format!(
        "4. Diagnosis: {} candidate fits from the file's columns, scored in {:.1} s.\n   Criterion: {}.\n",
        d.fits, d.elapsed_s, d.criterion
    );
    for c in d.candidates.iter().take(4) {
        let _ = writeln!(
            s,
            "   {} {:<52} Δ log evidence {:+8.1}   held-out {:.4} → {:.4} {unit} ({:+.1} %){}",
            if c.passes { "✔" } else { " " },
            c.effect,
            c.delta_log_evidence,
            c.residual_std_before,
            c.residual_std_after,
            -c.improvement_pct,
            if c.confirmation.is_some() {
                ", refitted"
            } else {
                ", scoring estimate"
            }
        );
    }
    let _ = write!(s, "   Verdict: {}", d.verdict_text);
    tell(s);
    let added: Vec<String> = match (d.verdict, d.candidates.first()) {
        (Verdict::MissingEffect, Some(c)) => c.expressions.clone(),
        _ => Vec::new(),
    };
    let mut after_fit = None;
    let mut ev_after = ev_before.clone();
    if !added.is_empty() {
        let mut feats = base_features.clone();
        feats.extend(added.iter().cloned());
        let after = fit_features(&sim.train, &sim.train_truth, &[], &feats)?;
        let after_path = opts.out.join("after.tcm");
        tcomp_train::blob_io::write_atomic(&after_path, &after.model.to_bytes()?)?;
        files.push(after_path);
        ev_after = evaluate(&after, &sim.verify)?;
        tell(format!(
            "5. Adding it is one line: tcomp fit ... {}\n   \
             Verification residual (100 s bins): {:.4} → {:.4} {unit} ({:.1} % lower; noise floor {:.4}, now {:.2}×).",
            added
                .iter()
                .map(|e| format!("--feature '{e}'"))
                .collect::<Vec<_>>()
                .join(" "),
            ev_before.binned.residual_std,
            ev_after.binned.residual_std,
            100.0 * (1.0 - ev_after.binned.residual_std / ev_before.binned.residual_std),
            floor,
            ev_after.binned.residual_std / floor
        ));
        after_fit = Some(after);
    } else {
        tell("5. Nothing to add: the diagnosis found no significant missing effect.".into());
    }
    // The report: before (and after) on the verification run, with the diagnosis.
    let mut models = vec![report::ModelRun {
        name: "before: (T, dT/dt)".into(),
        run: analysis
            .verify_run
            .clone()
            .ok_or_else(|| DiscoverError::Invalid("no verification run".into()))?,
    }];
    if let Some(a) = &after_fit {
        let b = a.model.to_bytes()?;
        let m = tcomp_train::blob_io::decode(Path::new("after.tcm"), &b)?;
        let run = metrics::run_model(&m, &sim.verify, &Roles::of_model(&m), None, None)?;
        models.push(report::ModelRun {
            name: format!("after: + {}", added.join(", ")),
            run,
        });
    }
    let html = report::render(&report::ReportInput {
        title: "tcomp demo: IFOG with a Shupe-type term".into(),
        data_name: "verify.csv (simulated verification run)".into(),
        unit: unit.clone(),
        models,
        analysis: Some(&analysis),
        noise_floor: Some(floor),
    })?;
    let rp = opts.out.join("report.html");
    write(&rp, html.as_bytes())?;
    files.push(rp.clone());
    tell(format!(
        "6. Written to {}: train.csv, verify.csv, before.tcm{}, report.html (open it in a browser).",
        opts.out.display(),
        if after_fit.is_some() {
            ", after.tcm"
        } else {
            ""
        }
    ));
    Ok(DemoOutcome {
        text,
        verdict: d.verdict,
        added,
        before: ev_before.binned.residual_std,
        after: ev_after.binned.residual_std,
        noise_floor: floor,
        files,
    })
}

/// The truth file type, re-exported for callers that write presets.
pub type Truth = TruthFile;
