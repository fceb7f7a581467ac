//! `tcomp compare MODEL_A MODEL_B --data FILE [--json]`: before/after, overall and per segment.
use super::run::RunArgs;
use clap::Args as ClapArgs;
use serde::Serialize;
use std::path::{Path, PathBuf};
use tcomp_train::metrics::{self, Run};
use tcomp_train::{Dataset, EvalReport};

/// Arguments of `tcomp compare`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The first model ("before").
    pub model_a: PathBuf,
    /// The second model ("after").
    pub model_b: PathBuf,
    /// The run to compare on.
    #[command(flatten)]
    pub run: RunArgs,
    /// Bin length (s) of the binned figures.
    #[arg(long, default_value_t = 100.0, allow_negative_numbers = true, value_parser = super::check::interval_s)]
    pub bin: f64,
    /// Column for segment detection [default: model A's first input].
    #[arg(long)]
    pub temperature: Option<String>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Serialize)]
struct SegmentPair {
    label: String,
    start_s: f64,
    end_s: f64,
    raw_std: f64,
    a_residual_std: f64,
    b_residual_std: f64,
    change_pct: f64,
}

#[derive(Serialize)]
struct Comparison {
    a: EvalReport,
    b: EvalReport,
    binned_change_pct: f64,
    segments: Vec<SegmentPair>,
}

/// Runs a blob over `data` with the segment temperature `temp`, the reference override and the
/// gap threshold of `run`.
pub fn run_blob(
    path: &Path,
    data: &Dataset,
    temp: Option<&str>,
    run: &RunArgs,
) -> anyhow::Result<Run> {
    let bytes = tcomp_train::blob_io::read(path)?;
    let model = tcomp_train::blob_io::decode(path, &bytes)?;
    Ok(metrics::run_model(
        &model,
        data,
        &run.roles(&model),
        temp,
        run.run.gap,
    )?)
}

/// A blob's time column and first input (the default segment temperature).
pub fn time_and_first_input(path: &Path) -> anyhow::Result<(String, Option<String>)> {
    let bytes = tcomp_train::blob_io::read(path)?;
    let model = tcomp_train::blob_io::decode(path, &bytes)?;
    Ok((
        model.meta.columns.time.to_string(),
        model.program.inputs.first().map(|s| s.to_string()),
    ))
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(args.bin > 0.0, "--bin must be positive");
    args.run.check_window()?;
    let (time, first) = time_and_first_input(&args.model_a)?;
    let data = args.run.load(&time)?;
    let temp = args.temperature.clone().or(first);
    let ra = run_blob(&args.model_a, &data, temp.as_deref(), &args.run)?;
    let rb = run_blob(&args.model_b, &data, temp.as_deref(), &args.run)?;
    let (a, b) = (
        metrics::report(&ra, args.bin),
        metrics::report(&rb, args.bin),
    );
    let sa = tcomp_discover::segments::table(&ra);
    let sb = tcomp_discover::segments::table(&rb);
    let segments: Vec<SegmentPair> = sa
        .iter()
        .zip(&sb)
        .map(|(x, y)| SegmentPair {
            label: x.label.clone(),
            start_s: x.start_s,
            end_s: x.end_s,
            raw_std: x.raw_std,
            a_residual_std: x.residual_std,
            b_residual_std: y.residual_std,
            change_pct: 100.0 * (y.residual_std / x.residual_std.max(1e-300) - 1.0),
        })
        .collect();
    let c = Comparison {
        binned_change_pct: 100.0
            * (b.binned.residual_std / a.binned.residual_std.max(1e-300) - 1.0),
        a,
        b,
        segments,
    };
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&c)?);
        return Ok(());
    }
    outln!(
        "A = {}\nB = {}",
        args.model_a.display(),
        args.model_b.display()
    );
    outln!("{:<26} {:>12} {:>12} {:>9}", "", "A", "B", "change");
    outln!(
        "{:<26} {:>12.4e} {:>12.4e} {:>+8.1}%",
        "residual std",
        c.a.residual_std,
        c.b.residual_std,
        100.0 * (c.b.residual_std / c.a.residual_std.max(1e-300) - 1.0)
    );
    outln!(
        "{:<26} {:>12.4e} {:>12.4e} {:>+8.1}%",
        format!("{} s bins residual std", args.bin),
        c.a.binned.residual_std,
        c.b.binned.residual_std,
        c.binned_change_pct
    );
    outln!();
    outln!(
        "{:<26} {:>12} {:>12} {:>12} {:>9}",
        "segment",
        "raw std",
        "A resid",
        "B resid",
        "change"
    );
    for s in &c.segments {
        outln!(
            "{:<26} {:>12.4e} {:>12.4e} {:>12.4e} {:>+8.1}%",
            s.label,
            s.raw_std,
            s.a_residual_std,
            s.b_residual_std,
            s.change_pct
        );
    }
    Ok(())
}
