//! `tcomp compare MODEL_A MODEL_B --data FILE [--json]`: before/after, overall and per segment.
use crate::args::run::RunArgs;
use crate::output::json::{self, RunFigures, Subject};
use crate::render::num::{SIG, num, pct, plain};
use clap::Args as ClapArgs;
use serde::Serialize;
use std::path::{Path, PathBuf};
use tcomp_train::Dataset;
use tcomp_train::metrics::{self, Run};

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
    #[arg(long, default_value_t = 100.0, allow_negative_numbers = true, value_parser = crate::args::check::interval_s)]
    pub bin: f64,
    /// Column for segment detection [default: model A's first input].
    #[arg(long)]
    pub temperature: Option<String>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// No progress display.
    #[arg(long)]
    pub quiet: bool,
}

/// One segment of model A's run, with both models' residual std there.
#[derive(Serialize)]
struct SegmentPair {
    label: String,
    start_s: f64,
    end_s: f64,
    raw_std: Option<f64>,
    a_residual_std: Option<f64>,
    b_residual_std: Option<f64>,
    /// From A to B (%; negative when B's residual is smaller).
    change_pct: Option<f64>,
}

/// The JSON of `tcomp compare`.
#[derive(Serialize)]
struct Comparison {
    a: RunFigures,
    b: RunFigures,
    /// Residual std from A to B (%; negative when B's is smaller).
    change_pct: Option<f64>,
    /// The same on bin means.
    binned_change_pct: Option<f64>,
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

/// A blob's target column (with `run`'s overrides) and unit.
pub fn target_and_unit(path: &Path, run: &RunArgs) -> anyhow::Result<(String, String)> {
    let bytes = tcomp_train::blob_io::read(path)?;
    let model = tcomp_train::blob_io::decode(path, &bytes)?;
    Ok((run.roles(&model).target, model.meta.unit.to_string()))
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(args.bin > 0.0, "--bin must be positive");
    args.run.check_window()?;
    let (_, first) = time_and_first_input(&args.model_a)?;
    let progress = crate::output::progress::spinner(args.quiet, "loading data");
    let bytes_a = tcomp_train::blob_io::read(&args.model_a)?;
    let model_a = tcomp_train::blob_io::decode(&args.model_a, &bytes_a)?;
    let data = args.run.load(&model_a, args.quiet || args.json)?;
    drop(model_a);
    progress.set_message("running both models");
    let temp = args.temperature.clone().or(first);
    let ra = run_blob(&args.model_a, &data, temp.as_deref(), &args.run)?;
    let rb = run_blob(&args.model_b, &data, temp.as_deref(), &args.run)?;
    progress.finish_and_clear();
    let (a, b) = (
        RunFigures::from(&metrics::report(&ra, args.bin)),
        RunFigures::from(&metrics::report(&rb, args.bin)),
    );
    let sa = tcomp_discover::segments::table(&ra);
    let sb = tcomp_discover::segments::table(&rb);
    let has = |n: usize, v: f64| (n > 0).then_some(v);
    let segments: Vec<SegmentPair> = sa
        .iter()
        .zip(&sb)
        .map(|(x, y)| SegmentPair {
            label: x.label.clone(),
            start_s: x.start_s,
            end_s: x.end_s,
            raw_std: has(x.samples, x.raw_std),
            a_residual_std: has(x.samples, x.residual_std),
            b_residual_std: has(y.samples, y.residual_std),
            change_pct: json::change(
                has(x.samples, x.residual_std),
                has(y.samples, y.residual_std),
            ),
        })
        .collect();
    let c = Comparison {
        change_pct: json::change(a.residual_std, b.residual_std),
        binned_change_pct: json::change(a.binned.residual_std, b.binned.residual_std),
        a,
        b,
        segments,
    };
    let (target, unit) = target_and_unit(&args.model_a, &args.run)?;
    let subject = Subject::new(
        vec![
            args.model_a.display().to_string(),
            args.model_b.display().to_string(),
        ],
        &target,
        &unit,
        &args.run.data,
    );
    if args.json {
        return json::print("compare", &subject, &c);
    }
    print_text(args, &c, subject.unit.as_deref().unwrap_or(""));
    Ok(())
}

/// The human table: both models' figures, then each segment, every change negative when B's
/// residual is smaller.
fn print_text(args: &Args, c: &Comparison, unit: &str) {
    let unit = crate::output::printable::text(unit);
    let n = |v: Option<f64>| v.map_or_else(|| "no data".into(), |v| num(v, &unit));
    outln!(
        "A = {}\nB = {}",
        crate::output::printable::text(&args.model_a.display().to_string()),
        crate::output::printable::text(&args.model_b.display().to_string())
    );
    outln!("{:<26} {:>16} {:>16} {:>9}", "", "A", "B", "change");
    outln!(
        "{:<26} {:>16} {:>16} {:>9}",
        "residual std",
        n(c.a.residual_std),
        n(c.b.residual_std),
        pct(c.change_pct)
    );
    outln!(
        "{:<26} {:>16} {:>16} {:>9}",
        format!("{} s bins residual std", plain(args.bin, SIG)),
        n(c.a.binned.residual_std),
        n(c.b.binned.residual_std),
        pct(c.binned_change_pct)
    );
    outln!();
    outln!(
        "{:<26} {:>16} {:>16} {:>16} {:>9}",
        "segment",
        "raw std",
        "A resid",
        "B resid",
        "change"
    );
    for s in &c.segments {
        outln!(
            "{:<26} {:>16} {:>16} {:>16} {:>9}",
            s.label,
            n(s.raw_std),
            n(s.a_residual_std),
            n(s.b_residual_std),
            pct(s.change_pct)
        );
    }
}
