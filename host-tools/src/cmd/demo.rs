//! `tcomp demo [--out DIR]`: the discovery loop on a simulated IFOG, no user data needed.
use crate::demo::{DemoOptions, run as run_demo};
use crate::output::json::{self, RunFigures, Subject};
use clap::Args as ClapArgs;
use serde::Serialize;
use std::path::PathBuf;

/// Arguments of `tcomp demo`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Output directory for the simulated runs, the blobs and report.html.
    #[arg(long, default_value = "tcomp-demo")]
    pub out: PathBuf,
    /// Simulation seed.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true, value_parser = crate::args::check::seed)]
    pub seed: u64,
    /// Output step of the simulated runs (s); larger is quicker and coarser.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true, value_parser = crate::args::check::demo_step_s)]
    pub step: f64,
    /// Print JSON (the figures before and after on the verification run) instead of the story.
    #[arg(long)]
    pub json: bool,
    /// No narrative (the files are written all the same).
    #[arg(long)]
    pub quiet: bool,
}

/// The JSON of `tcomp demo`.
#[derive(Serialize)]
struct Found {
    out: String,
    seed: u64,
    step_s: f64,
    noise_floor: f64,
    verdict: tcomp_discover::Verdict,
    verdict_text: String,
    added: Vec<String>,
    before: RunFigures,
    after: Option<RunFigures>,
    /// Verification residual on 100 s bins from before to after (%; negative when it fell).
    binned_change_pct: Option<f64>,
}

/// Runs the command: the demo writes into a staging directory inside `--out`, and its files are
/// moved into `--out` only when the whole loop succeeded, so a failed run leaves the files of an
/// earlier run as they were. The demo reads no input, so no output can overwrite one.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let staging = crate::output::files::Staging::new("--out", &args.out)?;
    let staged = staging.path().display().to_string();
    let shown = args.out.display().to_string();
    let opts = DemoOptions {
        out: staging.path().to_path_buf(),
        seed: args.seed,
        step_s: args.step,
    };
    let tell = !(args.quiet || args.json);
    // Paragraphs naming the staging directory wait until the files are where they say.
    let mut held = Vec::new();
    let summary = run_demo(&opts, |p| {
        if tell {
            if p.contains(&staged) {
                held.push(p.replace(&staged, &shown));
            } else {
                outln!("{p}\n");
            }
        }
    })?;
    staging.commit()?;
    for p in held {
        outln!("{p}\n");
    }
    if args.json {
        print_json(args, &summary)?;
    }
    Ok(())
}

/// The demo's findings in the shared vocabulary: the two models on the verification run.
fn print_json(args: &Args, s: &crate::demo::Summary) -> anyhow::Result<()> {
    let before = RunFigures::from(&s.before);
    let after = s.after.as_ref().map(RunFigures::from);
    let mut models = vec![args.out.join("before.tcm").display().to_string()];
    if after.is_some() {
        models.push(args.out.join("after.tcm").display().to_string());
    }
    let subject = Subject::new(models, &s.target, &s.unit, &args.out.join("verify.csv"));
    let found = Found {
        out: args.out.display().to_string(),
        seed: args.seed,
        step_s: args.step,
        noise_floor: s.noise_floor,
        verdict: s.verdict,
        verdict_text: s.verdict_text.clone(),
        added: s.added.clone(),
        binned_change_pct: json::change(
            before.binned.residual_std,
            after.as_ref().and_then(|a| a.binned.residual_std),
        ),
        before,
        after,
    };
    json::print("demo", &subject, &found)
}
