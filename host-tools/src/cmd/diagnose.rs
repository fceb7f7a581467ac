//! `tcomp diagnose --model MODEL --data FILE [--verify FILE] [--json]`: where the model fails and
//! which physical effect is most likely missing, with the evidence and a stated criterion.
use super::json::{self, Subject};
use super::run::RunArgs;
use clap::Args as ClapArgs;
use std::path::PathBuf;
use tcomp_discover::{Analysis, DiagnoseOptions};
use tcomp_train::Dataset;

/// Arguments of `tcomp diagnose`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The model blob.
    #[arg(long)]
    pub model: PathBuf,
    /// The run to diagnose (normally the training run), CSV or .csv.gz.
    #[command(flatten)]
    pub run: RunArgs,
    /// A held-out run (else contiguous blocks of --data are held out in turn).
    #[arg(long)]
    pub verify: Option<PathBuf>,
    /// Column for segment detection [default: the program's first input].
    #[arg(long)]
    pub temperature: Option<String>,
    /// Averaging bin before scoring (s).
    #[arg(long, default_value_t = 60.0, allow_negative_numbers = true, value_parser = super::check::interval_s)]
    pub bin: f64,
    /// Minimum Δ log evidence of the verdict.
    #[arg(long, default_value_t = 5.0, allow_negative_numbers = true, value_parser = super::check::min_evidence)]
    pub min_evidence: f64,
    /// Minimum held-out improvement (%) of the verdict.
    #[arg(long, default_value_t = 5.0, allow_negative_numbers = true, value_parser = super::check::percent)]
    pub min_improvement: f64,
    /// Candidates printed.
    #[arg(long, default_value_t = 10, allow_negative_numbers = true, value_parser = super::check::top)]
    pub top: usize,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// No progress display.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs the diagnosis (shared with `report`) on the rows of `--from/--until`.
pub fn analyse(args: &Args) -> anyhow::Result<(Analysis, Dataset)> {
    args.run.check_window()?;
    let bytes = tcomp_train::blob_io::read(&args.model)?;
    let model = tcomp_train::blob_io::decode(&args.model, &bytes)?;
    let roles = args.run.roles(&model);
    let data = args.run.load(&roles.time)?;
    let verify = args.verify.as_deref().map(Dataset::load).transpose()?;
    let mut opts = DiagnoseOptions::default();
    opts.score.bin_s = args.bin;
    opts.score.gap_s = args.run.run.gap;
    opts.criterion.min_delta_log_evidence = args.min_evidence;
    opts.criterion.min_improvement_pct = args.min_improvement;
    opts.temperature.clone_from(&args.temperature);
    if args.run.overrides_reference() {
        opts.roles = Some(roles);
    }
    let progress = super::progress::spinner(args.quiet, "diagnosing");
    let a = tcomp_discover::diagnose(&model, &data, verify.as_ref(), &opts)?;
    progress.finish_and_clear();
    Ok((a, data))
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let (a, _) = analyse(args)?;
    if args.json {
        let d = &a.diagnosis;
        let mut subject = Subject::new(
            vec![args.model.display().to_string()],
            &d.model.target,
            &d.model.unit,
            &args.run.data,
        );
        subject.verify = args.verify.as_ref().map(|v| v.display().to_string());
        json::print("diagnose", &subject, &body(d)?)?;
    } else {
        // The model's target, unit and features come from the blob: no raw control characters.
        out!(
            "{}",
            super::printable::lines(&crate::render::diagnosis::text(&a, args.top))
        );
    }
    Ok(())
}

/// The diagnosis in the shared vocabulary: each candidate's held-out change as `change_pct`
/// (negative when the residual fell) beside the analysis' `improvement_pct`.
fn body(d: &tcomp_discover::Diagnosis) -> anyhow::Result<serde_json::Value> {
    let mut v = serde_json::to_value(d)?;
    if let Some(cands) = v.get_mut("candidates").and_then(|c| c.as_array_mut()) {
        for (c, s) in cands.iter_mut().zip(&d.candidates) {
            if let Some(obj) = c.as_object_mut() {
                let change = json::change(Some(s.residual_std_before), Some(s.residual_std_after));
                obj.insert("change_pct".into(), serde_json::to_value(change)?);
            }
        }
    }
    Ok(v)
}
