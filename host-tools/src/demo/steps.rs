//! The six paragraphs of the demo, one function each: simulate, fit the traditional model,
//! diagnose it (where it fails, which effect is missing), add the effect and refit, write the
//! report.

use super::{DemoOptions, Scene, Story, files};
use crate::render::candidates::{Layout, table};
use crate::render::html::{self, ModelRun, ReportInput};
use crate::render::num::{change_pct, num, pct, plain};
use std::fmt::Write as _;
use std::path::PathBuf;
use tcomp_discover::segments::SegmentRow;
use tcomp_discover::{Analysis, DiagnoseOptions, Verdict};
use tcomp_train::{EvalReport, Fitted};

/// Candidates the narrative shows.
const CANDIDATES_SHOWN: usize = 4;

/// The traditional (T, dT/dt) model and how it fares on the verification run.
pub(super) struct Before {
    fitted: Fitted,
    features: Vec<String>,
    path: PathBuf,
    /// On the verification run.
    pub(super) eval: EvalReport,
}

/// The model with the effect the diagnosis named.
pub(super) struct After {
    fitted: Fitted,
    /// The features added.
    pub(super) added: Vec<String>,
    /// On the verification run.
    pub(super) eval: EvalReport,
}

/// Paragraph 1: simulates the demo's scenario and writes both runs as CSV.
pub(super) fn simulate(
    opts: &DemoOptions,
    story: &mut Story<impl FnMut(&str)>,
) -> anyhow::Result<Scene> {
    let preset =
        tcomp_demo::demo_preset(opts.seed)?.with_rate(1.0 / opts.step_s.min(1.0), opts.step_s);
    story.tell(&format!(
        "1. Simulating an IFOG in a temperature chamber (effects of the `ifog-shupe` preset, seed {}).\n   \
         Its bias holds poly(T) + rate(T) + a Shupe-type T·dT/dt term. Training run: 20 °C, \
         cooled and heated at 0.5 °C/min between −10 and 40 °C. Verification run: the same \
         range, cooling at 1 °C/min and heating at 2 °C/min.",
        opts.seed
    ));
    let sim = tcomp_demo::simulated(&preset)?;
    let floor = sim.verify_truth.noise.std_100s;
    let unit = sim.train_truth.unit.clone();
    files::save_csv(&opts.out.join("train.csv"), &sim.train)?;
    files::save_csv(&opts.out.join("verify.csv"), &sim.verify)?;
    Ok(Scene { sim, floor, unit })
}

/// Paragraph 2: fits the traditional model on (T, dT/dt), writes `before.tcm` and evaluates it.
pub(super) fn fit_before(
    opts: &DemoOptions,
    scene: &Scene,
    story: &mut Story<impl FnMut(&str)>,
) -> anyhow::Result<Before> {
    let (sim, unit, floor) = (&scene.sim, &scene.unit, scene.floor);
    let temp = sim
        .train_truth
        .columns
        .thermometers
        .first()
        .cloned()
        .unwrap_or_else(|| "t_coil_c".into());
    let rate = tcomp_core::expr::rate(tcomp_core::expr::name(&temp)).to_string();
    let features = vec![temp.clone(), rate.clone()];
    let fitted = tcomp_demo::fit_features(&sim.train, &sim.train_truth, &[], &features)?;
    let path = opts.out.join("before.tcm");
    tcomp_train::blob_io::write_atomic(&path, &fitted.model.to_bytes()?)?;
    let eval = tcomp_demo::evaluate(&fitted, &sim.verify)?;
    story.tell(&format!(
        "2. Fitting the traditional model on (T, dT/dt): --feature {temp} --feature '{rate}'.\n   \
         Training residual (100 s bins): {}. On the verification run: {} — {}× the noise \
         floor of {}.",
        num(fitted.summary.train.binned.residual_std, unit),
        num(eval.binned.residual_std, unit),
        plain(eval.binned.residual_std / floor, 3),
        num(floor, unit)
    ));
    Ok(Before {
        fitted,
        features,
        path,
        eval,
    })
}

/// Paragraphs 3 and 4: diagnoses the traditional model through its blob: where it fails on the
/// verification run, the leading candidates and the verdict.
pub(super) fn diagnose(
    scene: &Scene,
    before: &Before,
    story: &mut Story<impl FnMut(&str)>,
) -> anyhow::Result<Analysis> {
    let (sim, unit) = (&scene.sim, &scene.unit);
    let bytes = before.fitted.model.to_bytes()?;
    let model = tcomp_train::blob_io::decode(&before.path, &bytes)?;
    let analysis = tcomp_discover::diagnose(
        &model,
        &sim.train,
        Some(&sim.verify),
        &DiagnoseOptions::default(),
    )?;
    let d = &analysis.diagnosis;
    let mut segs: Vec<&SegmentRow> = d
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
                "{} ({}–{} min: {})",
                s.label,
                plain(s.start_s / 60.0, 3),
                plain(s.end_s / 60.0, 3),
                num(s.residual_std, unit)
            )
        })
        .collect();
    story.tell(&format!(
        "3. Where it fails: on the verification run the residual is largest during {}.",
        worst.join(" and ")
    ));
    let mut s = format!(
        "4. Diagnosis: {} candidate fits from the file's columns, scored in {:.1} s.\n   Criterion: {}.\n",
        d.fits, d.elapsed_s, d.criterion
    );
    table(
        &mut s,
        &d.candidates,
        CANDIDATES_SHOWN,
        Layout::Narrative { unit },
    );
    let _ = write!(s, "   Verdict: {}", d.verdict_text);
    story.tell(&s);
    Ok(analysis)
}

/// Paragraph 5: adds the effect the diagnosis named (if any), refits, writes `after.tcm` and tells
/// how the verification residual fell.
pub(super) fn add_effect(
    opts: &DemoOptions,
    scene: &Scene,
    before: &Before,
    analysis: &Analysis,
    story: &mut Story<impl FnMut(&str)>,
) -> anyhow::Result<Option<After>> {
    let (sim, unit, floor) = (&scene.sim, &scene.unit, scene.floor);
    let d = &analysis.diagnosis;
    let added: Vec<String> = match (d.verdict, d.candidates.first()) {
        (Verdict::MissingEffect, Some(c)) => c.expressions.clone(),
        _ => Vec::new(),
    };
    if added.is_empty() {
        story.tell("5. Nothing to add: the diagnosis found no significant missing effect.");
        return Ok(None);
    }
    let mut features = before.features.clone();
    features.extend(added.iter().cloned());
    let fitted = tcomp_demo::fit_features(&sim.train, &sim.train_truth, &[], &features)?;
    tcomp_train::blob_io::write_atomic(&opts.out.join("after.tcm"), &fitted.model.to_bytes()?)?;
    let eval = tcomp_demo::evaluate(&fitted, &sim.verify)?;
    let (was, now) = (before.eval.binned.residual_std, eval.binned.residual_std);
    story.tell(&format!(
        "5. Adding it is one line: tcomp fit ... {}\n   \
         Verification residual (100 s bins): {} → {} ({}; noise floor {}, now {}×).",
        added
            .iter()
            .map(|e| format!("--feature '{e}'"))
            .collect::<Vec<_>>()
            .join(" "),
        num(was, ""),
        num(now, unit),
        pct(change_pct(was, now)),
        num(floor, unit),
        plain(now / floor, 3)
    ));
    Ok(Some(After {
        fitted,
        added,
        eval,
    }))
}

/// Paragraph 6: writes the report: before (and after) on the verification run, with the diagnosis.
pub(super) fn report(
    opts: &DemoOptions,
    scene: &Scene,
    analysis: &Analysis,
    after: Option<&After>,
    story: &mut Story<impl FnMut(&str)>,
) -> anyhow::Result<()> {
    let mut models = vec![ModelRun {
        name: "before: (T, dT/dt)".into(),
        run: analysis
            .verify_run
            .clone()
            .ok_or_else(|| anyhow::anyhow!("no verification run"))?,
    }];
    if let Some(a) = after {
        models.push(ModelRun {
            name: format!("after: + {}", a.added.join(", ")),
            run: tcomp_demo::run_fitted(&a.fitted, "after.tcm", &scene.sim.verify)?,
        });
    }
    let cols = &scene.sim.verify_truth.columns;
    let view = html::View {
        channel: Some(cols.target.clone()),
        temperature: cols.thermometers.first().cloned(),
        data: Some(&scene.sim.verify),
        time: Some(cols.time.clone()),
        gap_s: None,
        run: Some("held-out verification run verify.csv".into()),
    };
    let page = html::render_with(
        &ReportInput {
            title: format!(
                "tcomp demo: IFOG with a Shupe-type term — {} ({})",
                cols.target, scene.unit
            ),
            data_name: "verify.csv (simulated verification run)".into(),
            unit: scene.unit.clone(),
            models,
            analysis: Some(analysis),
            noise_floor: Some(scene.floor),
        },
        &view,
    );
    files::write(&opts.out.join("report.html"), page.as_bytes())?;
    story.tell(&format!(
        "6. Written to {}: train.csv, verify.csv, before.tcm{}, report.html (open it in a browser).",
        opts.out.display(),
        if after.is_some() { ", after.tcm" } else { "" }
    ));
    Ok(())
}
