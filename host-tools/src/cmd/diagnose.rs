//! `tcomp diagnose --model MODEL --data FILE [--verify FILE] [--json]`: where the model fails and
//! which physical effect is most likely missing, with the evidence and a stated criterion.
use crate::args::run::RunArgs;
use crate::output::json::{self, Subject};
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
    /// A verification run: where the model fails on it, and the residual there of your own fit
    /// with each effect the verdict names (reported, never used to choose; the choice holds out
    /// blocks of --data in turn).
    #[arg(long)]
    pub verify: Option<PathBuf>,
    /// Column for segment detection [default: the program's first input].
    #[arg(long)]
    pub temperature: Option<String>,
    /// Averaging bin before scoring (s).
    #[arg(long, default_value_t = 60.0, allow_negative_numbers = true, value_parser = crate::args::check::interval_s)]
    pub bin: f64,
    /// Minimum Δ log evidence of the verdict.
    #[arg(long, default_value_t = 5.0, allow_negative_numbers = true, value_parser = crate::args::check::min_evidence)]
    pub min_evidence: f64,
    /// Minimum held-out improvement (%) of the verdict.
    #[arg(long, default_value_t = 5.0, allow_negative_numbers = true, value_parser = crate::args::check::percent)]
    pub min_improvement: f64,
    /// Placebos each candidate must beat: its columns shifted in time, the threshold the best of
    /// them (false-alarm rate 1 / (N + 1) a stage, at most 2 / (N + 1) over the two stages); 0
    /// turns the leg off.
    #[arg(long, default_value_t = tcomp_discover::placebo::PLACEBOS, allow_negative_numbers = true, value_parser = crate::args::check::placebos)]
    pub placebos: usize,
    /// Only the listed effects: do not search compositions of the feature language's functions
    /// over every input (a relay on a shifted temperature, a saturating input, a lagged rate, …).
    #[arg(long)]
    pub no_compose: bool,
    /// Candidates printed.
    #[arg(long, default_value_t = 10, allow_negative_numbers = true, value_parser = crate::args::check::top)]
    pub top: usize,
    /// Rounds: after an effect is confirmed, refit the model with it (as `tcomp fit --feature`
    /// would, on the same rows) and diagnose again, until nothing passes or N rounds ran.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=8))]
    pub rounds: u16,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// No progress display.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs the diagnosis (shared with `report`) on the rows of `--from/--until`.
pub fn analyse(args: &Args) -> anyhow::Result<(Analysis, Dataset)> {
    let p = prepare(args)?;
    let progress = crate::output::progress::spinner(args.quiet, "diagnosing");
    let a = tcomp_discover::diagnose(&p.model()?, &p.data, p.verify.as_ref(), &p.opts)?;
    progress.finish_and_clear();
    Ok((a, p.data))
}

/// What a diagnosis reads: the model's bytes, the rows, the held-out run and the options.
struct Prepared {
    model_path: PathBuf,
    bytes: Vec<u8>,
    data: Dataset,
    verify: Option<Dataset>,
    opts: DiagnoseOptions,
}

impl Prepared {
    fn model(&self) -> anyhow::Result<tcomp_train::blob_io::HostModel<'_>> {
        Ok(tcomp_train::blob_io::decode(&self.model_path, &self.bytes)?)
    }
}

fn prepare(args: &Args) -> anyhow::Result<Prepared> {
    args.run.check_window()?;
    let bytes = tcomp_train::blob_io::read(&args.model)?;
    let model = tcomp_train::blob_io::decode(&args.model, &bytes)?;
    let roles = args.run.roles(&model);
    let window = args.run.model_window(&model);
    let quiet = args.quiet || args.json;
    let mut data = args.run.load(&model, quiet)?;
    let mut verify = args
        .verify
        .as_deref()
        .map(|p| args.run.load_other(p, &model, quiet))
        .transpose()?;
    drop(model);
    // The model's own training window (from its blob) when --data is its training file and no
    // --from/--until says otherwise: diagnosing held-out rows as training data finds nothing.
    if let Some([lo, hi]) = window {
        let rest = rest_of(&data, &roles.time, lo, hi)?;
        data = data.select_time(&roles.time, lo, hi)?;
        if verify.is_none() {
            verify = rest;
        }
        if !args.json && !args.quiet {
            outln!(
                "diagnosing the model's training window {} (from its blob; --from/--until choose \
                 another){}",
                data.file(),
                if args.verify.is_none() && verify.is_some() {
                    "; the rest of the file is the held-out run"
                } else {
                    ""
                }
            );
        }
    }
    let mut opts = DiagnoseOptions::default();
    opts.score.bin_s = args.bin;
    opts.score.gap_s = args.run.run.gap;
    opts.criterion.min_delta_log_evidence = args.min_evidence;
    opts.criterion.min_improvement_pct = args.min_improvement;
    opts.criterion.placebos = args.placebos;
    opts.compose = !args.no_compose;
    opts.temperature.clone_from(&args.temperature);
    if args.run.overrides_reference() {
        opts.roles = Some(roles);
    }
    Ok(Prepared {
        model_path: args.model.clone(),
        bytes,
        data,
        verify,
        opts,
    })
}

/// The rows of `data` outside `[lo, hi)` as one run, when at least two are on one side (the side
/// with more rows: a training window in the middle leaves two runs, and one is enough to report).
fn rest_of(data: &Dataset, time: &str, lo: f64, hi: f64) -> anyhow::Result<Option<Dataset>> {
    let t = data.time(time)?;
    let before = t.iter().filter(|&&v| v < lo).count();
    let after = t.iter().filter(|&&v| v >= hi).count();
    let pick = if after >= before {
        (after >= 2).then(|| data.select_time(time, hi, f64::INFINITY))
    } else {
        (before >= 2).then(|| data.select_time(time, f64::NEG_INFINITY, lo))
    };
    Ok(pick.transpose()?)
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.rounds > 1 {
        return run_rounds(args);
    }
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
            crate::output::printable::lines(&crate::render::diagnosis::text(&a, args.top))
        );
    }
    Ok(())
}

/// `--rounds N`: each round's diagnosis, what it added, the features after the last.
fn run_rounds(args: &Args) -> anyhow::Result<()> {
    let p = prepare(args)?;
    let progress = crate::output::progress::spinner(args.quiet, "diagnosing, round by round");
    let r = tcomp_discover::diagnose_rounds(
        &p.model()?,
        &p.data,
        p.verify.as_ref(),
        &p.opts,
        usize::from(args.rounds),
    )?;
    progress.finish_and_clear();
    let first = r.analyses.first().map(|a| &a.diagnosis);
    let Some(first) = first else {
        anyhow::bail!("no round ran");
    };
    if args.json {
        let mut subject = Subject::new(
            vec![args.model.display().to_string()],
            &first.model.target,
            &first.model.unit,
            &args.run.data,
        );
        subject.verify = args.verify.as_ref().map(|v| v.display().to_string());
        let mut v = body(first)?;
        if let Some(obj) = v.as_object_mut() {
            let rounds = r
                .analyses
                .iter()
                .map(|a| body(&a.diagnosis))
                .collect::<anyhow::Result<Vec<_>>>()?;
            obj.insert("rounds".into(), serde_json::Value::Array(rounds));
            obj.insert("applied".into(), serde_json::to_value(&r.applied)?);
            obj.insert(
                "final_features".into(),
                serde_json::to_value(&r.final_features)?,
            );
            obj.insert("stopped".into(), serde_json::to_value(&r.stopped)?);
        }
        json::print("diagnose", &subject, &v)?;
        return Ok(());
    }
    for (k, a) in r.analyses.iter().enumerate() {
        outln!("══ round {} ══", k + 1);
        out!(
            "{}",
            crate::output::printable::lines(&crate::render::diagnosis::text(a, args.top))
        );
        if let Some(x) = r.applied.iter().find(|x| x.round == k + 1) {
            for m in &x.reestimated {
                outln!(
                    "re-estimated with every added parameter (trainer's refit evidence {:+.1}): \
                     {} → {}",
                    m.delta_log_evidence,
                    crate::output::printable::lines(&m.from),
                    crate::output::printable::lines(&m.to)
                );
            }
            outln!(
                "round {} adds {}: the next round starts from a refit with --feature {}",
                x.round,
                crate::output::printable::lines(&x.effect),
                crate::output::printable::lines(&x.features.join(" --feature "))
            );
        }
        outln!();
    }
    outln!("stopped: {}", r.stopped);
    outln!(
        "features after the rounds: {}",
        crate::output::printable::lines(&r.final_features.join(", "))
    );
    Ok(())
}

/// The diagnosis in the shared vocabulary: each candidate's held-out change as `change_pct`
/// (negative when the residual fell) beside the analysis' `improvement_pct`.
pub fn body(d: &tcomp_discover::Diagnosis) -> anyhow::Result<serde_json::Value> {
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
