//! `tcomp eval --model MODEL --data FILE`: measure a blob on a run, through the core's f32 evaluator.
use clap::Args as ClapArgs;
use std::path::PathBuf;
use tcomp_train::{Dataset, EvalReport, Roles};

/// Arguments of `tcomp eval`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The model blob.
    #[arg(long)]
    pub model: PathBuf,
    /// Measurement CSV (or .csv.gz).
    #[arg(long)]
    pub data: PathBuf,
    /// Bin length (s) of the binned figures.
    #[arg(long, default_value_t = 100.0, allow_negative_numbers = true, value_parser = super::check::interval_s)]
    pub bin: f64,
    /// Override the model's reference column.
    #[arg(long)]
    pub reference: Option<String>,
    /// Override the model's reference with a constant.
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::reference_value)]
    pub reference_value: Option<f64>,
    /// Column for segment detection [default: the program's first input].
    #[arg(long)]
    pub temperature: Option<String>,
    /// Evaluate only rows with time ≥ this (s).
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::from_s)]
    pub from: Option<f64>,
    /// Evaluate only rows with time < this (s).
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::until_s)]
    pub until: Option<f64>,
    /// Steps longer than this (s) are gaps [default: 10× the median step].
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::gap_s)]
    pub gap: Option<f64>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// No progress display.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.bin.is_finite() && args.bin > 0.0,
        "--bin must be a positive number of seconds"
    );
    if let (Some(from), Some(until)) = (args.from, args.until) {
        anyhow::ensure!(
            from < until,
            "--from {from} must be less than --until {until} (rows with from ≤ time < until are evaluated)"
        );
    }
    let bytes = tcomp_train::blob_io::read(&args.model)?;
    let model = tcomp_train::blob_io::decode(&args.model, &bytes)?;
    let mut roles = Roles::of_model(&model);
    if let Some(r) = &args.reference {
        roles.reference = Some(r.clone());
    }
    if let Some(v) = args.reference_value {
        roles.reference = None;
        roles.reference_value = Some(v);
    }
    let progress = super::progress::spinner(args.quiet, "loading data");
    let mut data = Dataset::load(&args.data)?;
    if args.from.is_some() || args.until.is_some() {
        data = data.select_time(
            &roles.time,
            args.from.unwrap_or(f64::NEG_INFINITY),
            args.until.unwrap_or(f64::INFINITY),
        )?;
    }
    // One row has no spread: every figure would be a meaningless zero.
    if data.len() < 2 {
        let which = if args.from.is_some() || args.until.is_some() {
            "--from/--until select"
        } else {
            "the file has"
        };
        anyhow::bail!(
            "{}: {which} {} row(s), and at least 2 are needed to measure anything",
            args.data.display(),
            data.len()
        );
    }
    progress.set_message("evaluating");
    let report = tcomp_train::evaluate(
        &model,
        &data,
        &roles,
        args.bin,
        args.temperature.as_deref(),
        args.gap,
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
        "out of range     {:.1} % of samples; input faults {}; gaps {}",
        r.out_of_range_pct,
        r.input_faults,
        r.gaps
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
