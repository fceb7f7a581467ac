//! `tcomp demo [--out DIR]`: the discovery loop on a simulated IFOG, no user data needed.
use clap::Args as ClapArgs;
use std::path::PathBuf;
use tcomp_discover::demo::{DemoOptions, run as run_demo};

/// Arguments of `tcomp demo`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Output directory for the simulated runs, the blobs and report.html.
    #[arg(long, default_value = "tcomp-demo")]
    pub out: PathBuf,
    /// Simulation seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output step of the simulated runs (s); larger is quicker and coarser.
    #[arg(long, default_value_t = 1.0)]
    pub step: f64,
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.step.is_finite() && args.step > 0.0 && args.step <= 10.0,
        "--step must be in (0, 10] seconds"
    );
    let opts = DemoOptions {
        out: args.out.clone(),
        seed: args.seed,
        step_s: args.step,
    };
    run_demo(&opts, |p| println!("{p}\n"))?;
    Ok(())
}
