//! `tcomp`: the command-line tool around the compensation core.
//!
//! Each subcommand lives in its own module under `cmd/`; `main` only parses arguments and dispatches.

mod cmd;

use clap::{Parser, Subcommand};

/// Temperature compensation of inertial sensors (RLG, QMA, IFOG, MEMS).
#[derive(Parser)]
#[command(name = "tcomp", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print the contents of a model blob; a corrupt blob is named as such, with the reason.
    Inspect(cmd::inspect::Args),
    /// Train a compensation model from a chamber run and write its blob.
    Fit(Box<cmd::fit::Args>),
    /// Measure a model on a run (through the core's f32 evaluator).
    Eval(cmd::eval::Args),
    /// Simulate temperature-chamber runs with known physics: train.csv, verify.csv and truth.json.
    Simulate(cmd::simulate::Args),
    /// Pack one model blob per firmware channel into the image flashed at 0x003F0000.
    Image(cmd::image::Args),
    /// Where a model fails and which physical effect is most likely missing (with the evidence).
    Diagnose(cmd::diagnose::Args),
    /// Compare two models on a run, overall and per segment.
    Compare(cmd::compare::Args),
    /// Write a self-contained HTML report with SVG plots.
    Report(cmd::report::Args),
    /// The discovery loop on a simulated IFOG: fit, diagnose, add the missing term, refit.
    Demo(cmd::demo::Args),
    /// Decode a capture of the firmware's serial output frames into CSV (or JSON).
    Frames(cmd::frames::Args),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Inspect(args) => cmd::inspect::run(&args),
        Command::Fit(args) => cmd::fit::run(&args),
        Command::Eval(args) => cmd::eval::run(&args),
        Command::Simulate(args) => cmd::simulate::run(&args),
        Command::Image(args) => cmd::image::run(&args),
        Command::Diagnose(args) => cmd::diagnose::run(&args),
        Command::Compare(args) => cmd::compare::run(&args),
        Command::Report(args) => cmd::report::run(&args),
        Command::Demo(args) => cmd::demo::run(&args),
        Command::Frames(args) => cmd::frames::run(&args),
    }
}
