//! `tcomp eval --model MODEL --data FILE`: measure a blob on a run, through the core's f32 evaluator.
//!
//! The run is streamed ([`tcomp_train::eval_stream`]): memory stays bounded whatever the log's
//! length, and the figures and errors are those of loading it whole.
use crate::args::run::RunArgs;
use crate::output::json::{self, RunFigures, Subject};
use crate::render::num::{SIG, num, pct, plain, signed};
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
    #[arg(long, default_value_t = 100.0, allow_negative_numbers = true, value_parser = crate::args::check::interval_s)]
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
    let progress = crate::output::progress::spinner(args.quiet, "evaluating");
    let report = tcomp_train::eval_stream(
        &args.run.data,
        &model,
        &args
            .run
            .stream(roles.clone(), args.bin, args.temperature.clone()),
    )?;
    progress.finish_and_clear();
    if !args.quiet && !args.json {
        for n in &report.notes {
            eprintln!("note: {n}");
        }
    }
    let subject = Subject::new(
        vec![args.model.display().to_string()],
        &roles.target,
        model.meta.unit,
        &args.run.data,
    );
    if args.json {
        json::print("eval", &subject, &RunFigures::from(&report))?;
    } else {
        let unit = subject.unit.as_deref().unwrap_or("");
        print_report(&report, &crate::output::printable::text(unit));
    }
    Ok(())
}

fn print_report(r: &EvalReport, unit: &str) {
    let f = RunFigures::from(r);
    let n = |v: Option<f64>| v.map_or_else(|| "no data".into(), |v| num(v, unit));
    outln!("samples          {}", r.samples);
    outln!("raw std          {}", n(f.raw_std));
    outln!("residual std     {}", n(f.residual_std));
    outln!("change           {}", pct(f.change_pct));
    outln!("raw rms          {}", n(f.raw_rms));
    outln!("residual rms     {}", n(f.residual_rms));
    outln!("max |residual|   {}", n(f.max_abs_residual));
    let sq = if unit.is_empty() {
        String::new()
    } else {
        format!("({unit})²")
    };
    outln!("MSD before       {}", num(r.msd_before, &sq));
    outln!("MSD after        {}", num(r.msd_after, &sq));
    outln!(
        "{} s bins ({})  raw std {}  residual std {}  change {}",
        plain(r.binned.seconds, SIG),
        r.binned.bins,
        n(f.binned.raw_std),
        n(f.binned.residual_std),
        pct(f.binned.change_pct)
    );
    outln!(
        "out of range     {} % of samples; input faults {}; gaps {} ({} restarted the \
         feature state)",
        plain(r.out_of_range_pct, 3),
        r.input_faults,
        r.gaps,
        r.gaps_restarted
    );
    if !r.segments.is_empty() {
        outln!();
        outln!(
            "{:<8} {:>10} {:>10} {:>10} {:>16} {:>16}",
            "segment",
            "start s",
            "end s",
            "°/min",
            "raw std",
            "residual std"
        );
        for s in &r.segments {
            outln!(
                "{:<8} {:>10} {:>10} {:>10} {:>16} {:>16}",
                s.kind,
                plain(s.start_s, SIG),
                plain(s.end_s, SIG),
                signed(s.rate_per_min, 3),
                num(s.raw_std, unit),
                num(s.residual_std, unit)
            );
        }
    }
}
