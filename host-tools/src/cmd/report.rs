//! `tcomp report --model MODEL [--model MODEL2 ...] --data FILE --out report.html`: one
//! self-contained HTML file with SVG plots, the diagnosis of the first model, and the figures.
use super::run::RunArgs;
use crate::render::html::{ModelRun, ReportInput, render};
use clap::Args as ClapArgs;
use std::path::PathBuf;

/// Arguments of `tcomp report`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Model blobs (the first is diagnosed; others are compared with it).
    #[arg(long, required = true)]
    pub model: Vec<PathBuf>,
    /// The run to show.
    #[command(flatten)]
    pub run: RunArgs,
    /// A held-out run for the diagnosis.
    #[arg(long)]
    pub verify: Option<PathBuf>,
    /// Output HTML file.
    #[arg(long, default_value = "report.html")]
    pub out: PathBuf,
    /// Skip the diagnosis (plots and figures only).
    #[arg(long)]
    pub no_diagnosis: bool,
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    super::output::check_file_output("--out", &args.out)?;
    let data_path = args.run.data.as_path();
    let mut inputs: Vec<(&str, &std::path::Path)> = vec![("--data", data_path)];
    inputs.extend(args.model.iter().map(|m| ("--model", m.as_path())));
    if let Some(v) = &args.verify {
        inputs.push(("--verify", v.as_path()));
    }
    super::output::refuse_overwriting_inputs("--out", std::slice::from_ref(&args.out), &inputs)?;
    let first = args
        .model
        .first()
        .ok_or_else(|| anyhow::anyhow!("give at least one --model"))?;
    args.run.check_window()?;
    let bytes = tcomp_train::blob_io::read(first)?;
    let m0 = tcomp_train::blob_io::decode(first, &bytes)?;
    let temp = m0.program.inputs.first().map(|s| s.to_string());
    let data = args.run.load(m0.meta.columns.time)?;
    let analysis = if args.no_diagnosis {
        None
    } else {
        let d = super::diagnose::Args {
            model: first.clone(),
            run: args.run.clone(),
            verify: args.verify.clone(),
            temperature: temp.clone(),
            bin: 60.0,
            min_evidence: 5.0,
            min_improvement: 5.0,
            top: 10,
            json: false,
        };
        Some(super::diagnose::analyse(&d)?.0)
    };
    let mut models = Vec::new();
    for p in &args.model {
        models.push(ModelRun {
            name: p
                .file_name()
                .map_or_else(|| p.display().to_string(), |f| f.to_string_lossy().into()),
            run: super::compare::run_blob(p, &data, temp.as_deref(), &args.run)?,
        });
    }
    let html = render(&ReportInput {
        title: format!("tcomp report: {}", data_path.display()),
        data_name: data_path.display().to_string(),
        unit: m0.meta.unit.to_string(),
        models,
        analysis: analysis.as_ref(),
        noise_floor: None,
    });
    tcomp_train::blob_io::write_atomic(&args.out, html.as_bytes())?;
    outln!("wrote {}", args.out.display());
    if let Some(a) = &analysis {
        outln!("{}", a.diagnosis.verdict_text);
    }
    Ok(())
}
