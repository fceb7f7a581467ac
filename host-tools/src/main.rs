//! `tcomp`: the command-line tool around the compensation core.
//!
//! Each subcommand lives in its own module under `cmd/`; `main` only parses arguments and dispatches.
//! What several commands show (candidate table, diagnosis text, HTML report) is written once in
//! `render/`; the built-in demo's narrative is `demo/`; the helpers the commands share (output,
//! shared arguments, image building) are `output/`, `args/` and `image.rs`, below the commands.
//!
//! A user error is not a crash: `main` prints the error and its causes on one line (`error: …`) on
//! stderr and exits with 1, whatever `RUST_BACKTRACE` says; bad usage exits with clap's 2. A panic
//! keeps the default hook, since it is a bug, and no user input reaches one. Standard output closed
//! by its reader (`tcomp … | head`) ends the run quietly with 0; any other failure to write it is an
//! error.

use tcomp::cmd;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Temperature compensation of inertial sensors (RLG, QMA, IFOG, MEMS).
#[derive(Parser)]
#[command(name = "tcomp", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print the contents of a model blob or a calibration image; a corrupt one is named as such,
    /// with the reason.
    Inspect(cmd::inspect::Args),
    /// Train a compensation model from a chamber run and write its blob.
    Fit(Box<cmd::fit::Args>),
    /// Measure a model on a run (through the core's f32 evaluator).
    Eval(cmd::eval::Args),
    /// Simulate temperature-chamber runs with known physics: train.csv, verify.csv and truth.json.
    Simulate(cmd::simulate::Args),
    /// Pack model blobs, checked against a board description, into a unit's calibration image.
    #[command(about = cmd::image::about())]
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
    /// Calibrate a whole unit (or a folder of units) from one spec: fit, verify on held-out data,
    /// diagnose, report, and pack the image.
    Calibrate(Box<cmd::calibrate::Args>),
    /// Write the thermal calibration an autopilot's own tool computes from its log: PX4's TC_*
    /// parameters from a ULog, ArduPilot's INS_TCALn_* from a DataFlash log.
    AutopilotParams(cmd::autopilot::Args),
    /// Replace a unit's model image over its serial link (A/B slots, verified, committed last).
    Flash(cmd::flash::Args),
    /// Make an Ed25519 key pair for signing calibration images, and the key block a unit is
    /// provisioned with.
    Keygen(cmd::keygen::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = run(cli.command);
    let output = tcomp::output::stdout::finish();
    match (result, output) {
        (Err(err), _) => {
            eprintln!("error: {}", message(&err));
            ExitCode::FAILURE
        }
        (Ok(()), Ok(())) => ExitCode::SUCCESS,
        // The reader stopped reading (`| head`): what it wanted, it got.
        (Ok(()), Err(e)) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        (Ok(()), Err(e)) => {
            eprintln!("error: writing to standard output: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Inspect(args) => cmd::inspect::run(&args),
        Command::Fit(args) => cmd::fit::run(&args),
        Command::Eval(args) => cmd::eval::run(&args),
        Command::Simulate(args) => cmd::simulate::run(&args),
        Command::Image(args) => cmd::image::run(&args),
        Command::Calibrate(args) => cmd::calibrate::run(&args),
        Command::AutopilotParams(args) => cmd::autopilot::run(&args),
        Command::Diagnose(args) => cmd::diagnose::run(&args),
        Command::Compare(args) => cmd::compare::run(&args),
        Command::Report(args) => cmd::report::run(&args),
        Command::Demo(args) => cmd::demo::run(&args),
        Command::Frames(args) => cmd::frames::run(&args),
        Command::Flash(args) => cmd::flash::run(&args),
        Command::Keygen(args) => cmd::keygen::run(&args),
    }
}

/// The error and its causes on one line, like `{err:#}`, but without a cause whose text the message
/// already holds (the trainer's I/O errors print their source and also return it as the cause).
fn message(err: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in err.chain() {
        let c = cause.to_string();
        if text.is_empty() {
            text = c;
        } else if !text.contains(&c) {
            text.push_str(": ");
            text.push_str(&c);
        }
    }
    text
}
