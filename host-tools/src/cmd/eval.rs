//! `tcomp eval --model MODEL --data FILE`: measure a blob on a run, through the core's f32 evaluator.
use super::run::RunArgs;
use clap::Args as ClapArgs;
use std::path::PathBuf;
use tcomp_train::EvalReport;

/// Arguments of `tcomp eval`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The model blob.
    #[arg(long)]
    pub model: PathBuf,
    /// The run to evaluate on.
    #[command(flatten)]
    pub run: RunArgs,
    /// Bin length (s) of the binned figures.
    #[arg(long, default_value_t = 100.0, allow_negative_numbers = true, value_parser = super::check::interval_s)]
    pub bin: f64,
    /// Column for segment detection [default: the program's first input].
    #[arg(long)]
    pub temperature: Option<String>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// No progress display.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    args.run.check_window()?;
    let bytes = tcomp_train::blob_io::read(&args.model)?;
    let model = tcomp_train::blob_io::decode(&args.model, &bytes)?;
    let roles = args.run.roles(&model);
    let progress = super::progress::spinner(args.quiet, "loading data");
    let data = args.run.load(&roles.time)?;
    progress.set_message("evaluating");
    let report = tcomp_train::evaluate(
        &model,
        &data,
        &roles,
        args.bin,
        args.temperature.as_deref(),
        args.run.run.gap,
    )?;
    progress.finish_and_clear();
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_report(&report, &super::printable::text(model.meta.unit));
    }
    Ok(())
}

fn print_report(r: &EvalReport, unit: &str) {
    let u = if unit.is_empty() { "" } else { unit };
    outln!("samples          {}", r.samples);
    outln!("raw std          {:.6e} {u}", r.raw_std);
    outln!("residual std     {:.6e} {u}", r.residual_std);
    outln!("improvement      {:.1} %", r.improvement_pct);
    outln!("raw rms          {:.6e} {u}", r.raw_rms);
    outln!("residual rms     {:.6e} {u}", r.residual_rms);
    outln!("max |residual|   {:.6e} {u}", r.max_abs_residual);
    outln!("MSD before       {:.6e}", r.msd_before);
    outln!("MSD after        {:.6e}", r.msd_after);
    outln!(
        "{} s bins ({})  raw std {:.6e}  residual std {:.6e}  improvement {:.1} %",
        r.binned.seconds,
        r.binned.bins,
        r.binned.raw_std,
        r.binned.residual_std,
        r.binned.improvement_pct
    );
    outln!(
        "out of range     {:.1} % of samples; input faults {}; gaps {} ({} restarted the \
         feature state)",
        r.out_of_range_pct,
        r.input_faults,
        r.gaps,
        r.gaps_restarted
    );
    if !r.segments.is_empty() {
        outln!();
        outln!(
            "{:<8} {:>10} {:>10} {:>10} {:>14} {:>14}",
            "segment",
            "start s",
            "end s",
            "°/min",
            "raw std",
            "residual std"
        );
        for s in &r.segments {
            outln!(
                "{:<8} {:>10.0} {:>10.0} {:>10.3} {:>14.6e} {:>14.6e}",
                s.kind,
                s.start_s,
                s.end_s,
                s.rate_per_min,
                s.raw_std,
                s.residual_std
            );
        }
    }
}
