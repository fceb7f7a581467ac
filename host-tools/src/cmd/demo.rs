//! `tcomp demo [--out DIR]`: the discovery loop on a simulated IFOG, no user data needed.
use crate::demo::{DemoOptions, run as run_demo};
use clap::Args as ClapArgs;
use std::path::PathBuf;

/// Arguments of `tcomp demo`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Output directory for the simulated runs, the blobs and report.html.
    #[arg(long, default_value = "tcomp-demo")]
    pub out: PathBuf,
    /// Simulation seed.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true, value_parser = super::check::seed)]
    pub seed: u64,
    /// Output step of the simulated runs (s); larger is quicker and coarser.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true, value_parser = super::check::demo_step_s)]
    pub step: f64,
}

/// Runs the command: the demo writes into a staging directory inside `--out`, and its files are
/// moved into `--out` only when the whole loop succeeded, so a failed run leaves the files of an
/// earlier run as they were. The demo reads no input, so no output can overwrite one.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let staging = super::output::Staging::new("--out", &args.out)?;
    let staged = staging.path().display().to_string();
    let shown = args.out.display().to_string();
    let opts = DemoOptions {
        out: staging.path().to_path_buf(),
        seed: args.seed,
        step_s: args.step,
    };
    // Paragraphs naming the staging directory wait until the files are where they say.
    let mut held = Vec::new();
    run_demo(&opts, |p| {
        if p.contains(&staged) {
            held.push(p.replace(&staged, &shown));
        } else {
            outln!("{p}\n");
        }
    })?;
    staging.commit()?;
    for p in held {
        outln!("{p}\n");
    }
    Ok(())
}
