//! `tcomp fit --data FILE ... --out MODEL`: train a model and write its blob atomically.
use anyhow::Context;
use clap::Args as ClapArgs;
use std::path::PathBuf;
use tcomp_train::bayes::Basis;
use tcomp_train::mse::CenterSelection;
use tcomp_train::{Dataset, FitOptions, FitSummary, Spec};

/// Arguments of `tcomp fit`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Measurement CSV (or .csv.gz).
    #[arg(long)]
    pub data: PathBuf,
    /// Where to write the model blob (.tcm).
    #[arg(long)]
    pub out: PathBuf,
    /// TOML spec with the same keys as these flags (flags override; features and signals add up).
    #[arg(long)]
    pub spec: Option<PathBuf>,
    /// Time column, seconds [default: time_s].
    #[arg(long)]
    pub time: Option<String>,
    /// Sensor output column.
    #[arg(long)]
    pub target: Option<String>,
    /// Reference column (error = target − reference).
    #[arg(long)]
    pub reference: Option<String>,
    /// Constant reference; with no reference at all the training mean of the target is used.
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::reference_value)]
    pub reference_value: Option<f64>,
    /// Feature expression, e.g. `rate(T)` (repeatable).
    #[arg(long = "feature")]
    pub features: Vec<String>,
    /// Named signal `NAME=EXPR` (repeatable).
    #[arg(long = "signal")]
    pub signals: Vec<String>,
    /// Method: bayes (default), mse, gradient, poly3.
    #[arg(long)]
    pub method: Option<String>,
    /// Average into non-overlapping bins of this many seconds before fitting; 0 = off [default: 120, shortened on short runs to leave 60 bins].
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::average_s)]
    pub average: Option<f64>,
    /// Number of centers (bayes: fixed instead of chosen by evidence; mse/gradient: default 16).
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::centers)]
    pub centers: Option<usize>,
    /// No linear term (bayes).
    #[arg(long)]
    pub no_linear: bool,
    /// Do not offer bayes the cubic in the first feature as a basis (it is chosen only when the
    /// Gaussians do not beat it by ln 20 in log evidence).
    #[arg(long)]
    pub no_cubic: bool,
    /// Center selection of mse: kmeans (default) or ols (orthogonal least squares forward selection).
    #[arg(long)]
    pub select: Option<String>,
    /// Steps longer than this (s) are gaps [default: 10× the median step].
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::gap_s)]
    pub gap: Option<f64>,
    /// k-means seed.
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::seed)]
    pub seed: Option<u64>,
    /// Gradient-descent iterations.
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::iterations)]
    pub iterations: Option<usize>,
    /// Sensor kind: rlg, qma, ifog, mems-gyro, mems-accel, other.
    #[arg(long)]
    pub sensor: Option<String>,
    /// Axis label.
    #[arg(long)]
    pub axis: Option<String>,
    /// Unit of the target.
    #[arg(long)]
    pub unit: Option<String>,
    /// Train only on rows with time ≥ this (s).
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::from_s)]
    pub from: Option<f64>,
    /// Train only on rows with time < this (s).
    #[arg(long, allow_negative_numbers = true, value_parser = super::check::until_s)]
    pub until: Option<f64>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// No progress display.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    super::output::check_file_output("--out", &args.out)?;
    let mut inputs = vec![("--data", args.data.as_path())];
    if let Some(spec) = &args.spec {
        inputs.push(("--spec", spec.as_path()));
    }
    super::output::refuse_overwriting_inputs("--out", std::slice::from_ref(&args.out), &inputs)?;
    let file_spec = match &args.spec {
        Some(p) => Spec::load(p)?,
        None => Spec::default(),
    };
    let flags = Spec {
        time: args.time.clone(),
        target: args.target.clone(),
        reference: args.reference.clone(),
        reference_value: args.reference_value,
        feature: args.features.clone(),
        signal: args.signals.clone(),
        average: args.average,
        method: args.method.clone(),
        centers: args.centers,
        linear: args.no_linear.then_some(false),
        cubic: args.no_cubic.then_some(false),
        select: args.select.clone(),
        gap: args.gap,
        seed: args.seed,
        iterations: args.iterations,
        sensor: args.sensor.clone(),
        axis: args.axis.clone(),
        unit: args.unit.clone(),
        from: args.from,
        until: args.until,
    };
    let opts = FitOptions::from_spec(&file_spec.merged(flags))?;
    let progress = super::progress::Bar::new(args.quiet);
    let data = Dataset::load_with_progress(&args.data, &progress)?;
    let fitted = tcomp_train::fit_with_progress(&data, &opts, &progress)?;
    let bytes = fitted.model.to_bytes()?;
    tcomp_train::blob_io::write_atomic(&args.out, &bytes)
        .with_context(|| format!("writing {}", args.out.display()))?;
    progress.clear();
    let s = &fitted.summary;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(s)?);
    } else {
        for w in &s.warnings {
            eprintln!("warning: {w}");
        }
        print_summary(s, &args.out);
    }
    Ok(())
}

fn print_summary(s: &FitSummary, out: &std::path::Path) {
    let d = &s.details;
    outln!("method      {}", s.method);
    for sig in &s.signals {
        outln!("signal      {sig}");
    }
    for (i, f) in s.features.iter().enumerate() {
        let ls = s
            .details
            .length_scales
            .get(i)
            .map(|l| format!("  length scale {l:.3}"))
            .unwrap_or_default();
        let lin = s
            .linear
            .get(i)
            .map(|l| format!("  linear {l:+.4e}"))
            .unwrap_or_default();
        outln!("feature     {f}{ls}{lin}");
    }
    let by = match d.select {
        Some(CenterSelection::Kmeans) => ", placed by k-means",
        Some(CenterSelection::Ols) => ", chosen by orthogonal least squares",
        None => "",
    };
    outln!("centers     {} (width σ = {:.3}{by})", s.centers, s.width);
    match (d.basis, d.other_basis_log_evidence) {
        (Some(Basis::Cubic), Some(other)) => outln!(
            "basis       cubic in the first feature (chosen by evidence; the best Gaussian model's log evidence is {other:.2})"
        ),
        (Some(Basis::Gaussians), Some(other)) => outln!(
            "basis       Gaussians (chosen by evidence; the cubic in the first feature scored {other:.2})"
        ),
        _ => {}
    }
    if let Some(e) = &d.evidence {
        outln!(
            "evidence    α = {:.4e}  α_linear = {:.4e}  β = {:.4e}  γ = {:.2}  log evidence = {:.2}  ({} settings compared, {} iterations)",
            e.alpha,
            e.alpha_linear,
            e.beta,
            e.gamma,
            e.log_evidence,
            d.settings_evaluated,
            e.iterations
        );
    }
    if let Some(r) = s.reference_value {
        outln!("reference   constant {r}");
    }
    outln!(
        "trained on  {} rows, {} samples after averaging ({} s)",
        s.train_rows,
        s.train_bins,
        s.average_s
    );
    let t = &s.train;
    outln!(
        "training    raw std {:.5e}  residual std {:.5e}  improvement {:.1} %   ({} s bins: {:.5e} → {:.5e})",
        t.raw_std,
        t.residual_std,
        t.improvement_pct,
        t.binned.seconds,
        t.binned.raw_std,
        t.binned.residual_std
    );
    outln!("wrote       {} ({} bytes)", out.display(), s.blob_bytes);
}
