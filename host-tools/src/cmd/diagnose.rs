//! `tcomp diagnose --model MODEL --data FILE [--verify FILE] [--json]`: where the model fails and
//! which physical effect is most likely missing, with the evidence and a stated criterion.
use clap::Args as ClapArgs;
use std::path::PathBuf;
use tcomp_discover::{Analysis, DiagnoseOptions, Verdict};
use tcomp_train::Dataset;

/// Arguments of `tcomp diagnose`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The model blob.
    #[arg(long)]
    pub model: PathBuf,
    /// The run to diagnose (normally the training run), CSV or .csv.gz.
    #[arg(long)]
    pub data: PathBuf,
    /// A held-out run (else contiguous blocks of --data are held out in turn).
    #[arg(long)]
    pub verify: Option<PathBuf>,
    /// Override the model's reference with a constant.
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::reference_value)]
    pub reference_value: Option<f64>,
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
}

/// Runs the diagnosis (shared with `report`).
pub fn analyse(args: &Args) -> anyhow::Result<(Analysis, Dataset)> {
    anyhow::ensure!(
        args.bin.is_finite() && args.bin > 0.0,
        "--bin must be a positive number of seconds"
    );
    let bytes = tcomp_train::blob_io::read(&args.model)?;
    let model = tcomp_train::blob_io::decode(&args.model, &bytes)?;
    let data = Dataset::load(&args.data)?;
    let verify = args.verify.as_deref().map(Dataset::load).transpose()?;
    let mut opts = DiagnoseOptions::default();
    opts.score.bin_s = args.bin;
    opts.criterion.min_delta_log_evidence = args.min_evidence;
    opts.criterion.min_improvement_pct = args.min_improvement;
    opts.temperature.clone_from(&args.temperature);
    if let Some(v) = args.reference_value {
        let mut roles = tcomp_train::Roles::of_model(&model);
        roles.reference = None;
        roles.reference_value = Some(v);
        opts.roles = Some(roles);
    }
    let a = tcomp_discover::diagnose(&model, &data, verify.as_ref(), &opts)?;
    Ok((a, data))
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let (a, _) = analyse(args)?;
    if args.json {
        let json = serde_json::to_string_pretty(&a.diagnosis)?;
        outln!("{}", super::printable::json(&json));
    } else {
        // The model's target, unit and features come from the blob: no raw control characters.
        out!("{}", super::printable::lines(&text(&a, args.top)));
    }
    Ok(())
}

/// The human-readable diagnosis.
pub fn text(a: &Analysis, top: usize) -> String {
    use std::fmt::Write as _;
    let d = &a.diagnosis;
    let u = &d.model.unit;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "model: {} ~ {}{}",
        d.model.target,
        d.model.features.join(", "),
        if d.model.signals.is_empty() {
            String::new()
        } else {
            format!("  (signals: {})", d.model.signals.join("; "))
        }
    );
    let _ = writeln!(s, "\nWhere it fails (residual of the model as given):");
    let seg = |s: &mut String, rows: &[tcomp_discover::segments::SegmentRow]| {
        let _ = writeln!(
            s,
            "  {:<24} {:>9} {:>9} {:>12} {:>12} {:>12}",
            "segment", "start s", "end s", "raw std", "resid std", "resid mean"
        );
        for r in rows {
            let _ = writeln!(
                s,
                "  {:<24} {:>9.0} {:>9.0} {:>12.4e} {:>12.4e} {:>+12.4e}",
                r.label, r.start_s, r.end_s, r.raw_std, r.residual_std, r.residual_mean
            );
        }
    };
    seg(&mut s, &d.segments);
    let _ = writeln!(s, "  worst intervals:");
    for w in &d.worst_intervals {
        let _ = writeln!(
            s,
            "    {:>7.0}–{:<7.0} s  mean residual {:+.4e} {u}  at {:.1}° {:+.2}°/min  {}",
            w.start_s, w.end_s, w.residual_mean, w.temperature, w.rate_per_min, w.during
        );
    }
    if !d.verify_segments.is_empty() {
        let _ = writeln!(s, "\nOn the verification run:");
        seg(&mut s, &d.verify_segments);
        let _ = writeln!(s, "  worst intervals:");
        for w in &d.verify_worst_intervals {
            let _ = writeln!(
                s,
                "    {:>7.0}–{:<7.0} s  mean residual {:+.4e} {u}  at {:.1}° {:+.2}°/min  {}",
                w.start_s, w.end_s, w.residual_mean, w.temperature, w.rate_per_min, w.during
            );
        }
    }
    let b = &d.base;
    let _ = writeln!(
        s,
        "\nCandidates ({} fits in {:.2} s; {} s bins; held-out: {}, {} s bins):",
        d.fits, d.elapsed_s, b.bin_s, b.heldout, b.heldout_bin_s
    );
    let _ = writeln!(
        s,
        "  held-out residual of the model's features {:.4e} {u} (refitted by the trainer: {:.4e} {u}); noise floor estimate {:.4e} {u}",
        b.heldout_residual_std, d.refit_residual_std_before, b.noise_floor_estimate
    );
    let _ = writeln!(
        s,
        "  {:<3}{:<58} {:>9} {:>12} {:>8}  {:<8} expression",
        "", "effect", "Δ ln E", "held-out", "better", "from"
    );
    for c in d.candidates.iter().take(top) {
        let _ = writeln!(
            s,
            "  {:<3}{:<58} {:>+9.1} {:>12.4e} {:>7.1}%  {:<8} {}",
            if c.passes { "✔" } else { "" },
            c.effect,
            c.delta_log_evidence,
            c.residual_std_after,
            c.improvement_pct,
            if c.confirmation.is_some() {
                "refit"
            } else {
                "scoring"
            },
            c.expressions.join(" ; ")
        );
    }
    for k in &d.skipped {
        let _ = writeln!(s, "  skipped {}: {}", k.expression, k.reason);
    }
    let _ = writeln!(s, "\nCriterion: {}.", d.criterion);
    let _ = writeln!(
        s,
        "Verdict: {}",
        match d.verdict {
            Verdict::MissingEffect => d.verdict_text.clone(),
            Verdict::None => d.verdict_text.clone(),
        }
    );
    s
}
