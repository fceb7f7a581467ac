//! `tcomp report --model MODEL [--model MODEL2 ...] --data FILE [--verify FILE] --out report.html`:
//! one self-contained HTML file with SVG plots, the diagnosis of the first model, and the figures.
//!
//! The plots are on the held-out run when there is one (`--verify`, or the `--from/--until`
//! window of `--data`): that is where a base model fails and what the diagnosis is about; on the
//! training run the base model already fits and the candidate plots are flat clouds.
use crate::args::run::RunArgs;
use crate::output::json::{self, RunFigures, Subject};
use crate::render::html::{ModelRun, ReportInput, View, render_with};
use clap::Args as ClapArgs;
use serde::Serialize;
use std::path::PathBuf;
use tcomp_discover::Analysis;
use tcomp_train::Dataset;

/// Arguments of `tcomp report`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Model blobs (the first is diagnosed; others are compared with it).
    #[arg(long, required = true)]
    pub model: Vec<PathBuf>,
    /// The run to diagnose (and to plot, without --verify).
    #[command(flatten)]
    pub run: RunArgs,
    /// A held-out run: the diagnosis holds it out, and the plots show the models on it.
    #[arg(long)]
    pub verify: Option<PathBuf>,
    /// Output HTML file.
    #[arg(long, default_value = "report.html")]
    pub out: PathBuf,
    /// Skip the diagnosis (plots and figures only).
    #[arg(long)]
    pub no_diagnosis: bool,
    /// Print JSON (the file written, the verdict, each model's figures on the plotted run).
    #[arg(long)]
    pub json: bool,
    /// No progress display and no summary lines.
    #[arg(long)]
    pub quiet: bool,
}

/// One model's figures on the plotted run.
#[derive(Serialize)]
struct ModelFigures {
    name: String,
    figures: RunFigures,
}

/// The JSON of `tcomp report`.
#[derive(Serialize)]
struct Written {
    out: String,
    plotted: String,
    verdict: Option<tcomp_discover::Verdict>,
    verdict_text: Option<String>,
    models: Vec<ModelFigures>,
    plots: usize,
    plots_without_data: usize,
}

/// Refuses an `--out` that is one of the inputs, before anything is read.
fn check_output(args: &Args) -> anyhow::Result<()> {
    crate::output::files::check_file_output("--out", &args.out)?;
    let mut inputs: Vec<(&str, &std::path::Path)> = vec![("--data", args.run.data.as_path())];
    inputs.extend(args.model.iter().map(|m| ("--model", m.as_path())));
    if let Some(v) = &args.verify {
        inputs.push(("--verify", v.as_path()));
    }
    crate::output::files::refuse_overwriting_inputs(
        "--out",
        std::slice::from_ref(&args.out),
        &inputs,
    )
}

/// The diagnosis of the first model, unless `--no-diagnosis`.
fn diagnose(
    args: &Args,
    first: &std::path::Path,
    temp: Option<&str>,
) -> anyhow::Result<Option<Analysis>> {
    if args.no_diagnosis {
        return Ok(None);
    }
    let d = super::diagnose::Args {
        model: first.to_path_buf(),
        run: args.run.clone(),
        verify: args.verify.clone(),
        temperature: temp.map(str::to_string),
        bin: 60.0,
        min_evidence: 5.0,
        min_improvement: 5.0,
        placebos: tcomp_discover::placebo::PLACEBOS,
        no_compose: false,
        top: 10,
        rounds: 1,
        json: false,
        quiet: args.quiet,
    };
    Ok(Some(super::diagnose::analyse(&d)?.0))
}

/// Each model run over the plotted run.
fn model_runs(args: &Args, shown: &Dataset, temp: Option<&str>) -> anyhow::Result<Vec<ModelRun>> {
    args.model
        .iter()
        .map(|p| {
            Ok(ModelRun {
                name: p
                    .file_name()
                    .map_or_else(|| p.display().to_string(), |f| f.to_string_lossy().into()),
                run: super::compare::run_blob(p, shown, temp, &args.run)?,
            })
        })
        .collect()
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    check_output(args)?;
    let data_path = args.run.data.as_path();
    let first = args
        .model
        .first()
        .ok_or_else(|| anyhow::anyhow!("give at least one --model"))?;
    args.run.check_window()?;
    let bytes = tcomp_train::blob_io::read(first)?;
    let m0 = tcomp_train::blob_io::decode(first, &bytes)?;
    let temp = m0.program.inputs.first().map(|s| s.to_string());
    let data = args.run.load(&m0, args.quiet)?;
    let analysis = diagnose(args, first, temp.as_deref())?;
    let verify = args
        .verify
        .as_deref()
        .map(|p| args.run.load_other(p, &m0, args.quiet))
        .transpose()?;
    let (shown, plotted) = match (&verify, &args.verify) {
        (Some(v), Some(p)) => (v, format!("held-out run {}", p.display())),
        _ => (&data, format!("run {}", data_path.display())),
    };
    let models = model_runs(args, shown, temp.as_deref())?;
    let roles = args.run.roles(&m0);
    let mut subject = Subject::new(
        args.model.iter().map(|m| m.display().to_string()).collect(),
        &roles.target,
        m0.meta.unit,
        data_path,
    );
    subject.verify = args.verify.as_ref().map(|v| v.display().to_string());
    let unit = subject.unit.clone().unwrap_or_default();
    let figures: Vec<ModelFigures> = models
        .iter()
        .map(|m| ModelFigures {
            name: m.name.clone(),
            figures: RunFigures::from(&tcomp_train::metrics::report(&m.run, 100.0)),
        })
        .collect();
    let view = View {
        channel: Some(roles.target.clone()),
        temperature: temp.clone(),
        data: Some(shown),
        time: Some(roles.time.clone()),
        gap_s: args.run.run.gap,
        run: Some(plotted.clone()),
    };
    let html = render_with(
        &ReportInput {
            title: format!(
                "tcomp report: {}{}",
                roles.target,
                if unit.is_empty() {
                    String::new()
                } else {
                    format!(" ({unit})")
                }
            ),
            data_name: match &args.verify {
                Some(v) => format!("{} (held out: {})", data_path.display(), v.display()),
                None => data_path.display().to_string(),
            },
            unit,
            models,
            analysis: analysis.as_ref(),
            noise_floor: None,
        },
        &view,
    );
    tcomp_train::blob_io::write_atomic(&args.out, html.as_bytes())?;
    let plots = html.matches("<svg class=\"plot\"").count();
    if args.json {
        let written = Written {
            out: args.out.display().to_string(),
            plotted,
            verdict: analysis.as_ref().map(|a| a.diagnosis.verdict),
            verdict_text: analysis.as_ref().map(|a| a.diagnosis.verdict_text.clone()),
            models: figures,
            plots,
            plots_without_data: html.matches("data-points=\"0\"").count(),
        };
        return json::print("report", &subject, &written);
    }
    if !args.quiet {
        outln!(
            "wrote {} ({plots} plots on the {plotted})",
            args.out.display()
        );
        if let Some(a) = &analysis {
            outln!("{}", a.diagnosis.verdict_text);
        }
    }
    Ok(())
}
