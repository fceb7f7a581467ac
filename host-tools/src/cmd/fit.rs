//! `tcomp fit --data FILE ... --out MODEL`: train a model and write its blob atomically.
use crate::args::run::RunArgs;
use crate::output::json::{self, RunFigures, Subject};
use crate::render::num::{SIG, num, pct, plain};
use anyhow::Context;
use clap::Args as ClapArgs;
use std::path::PathBuf;
use tcomp_train::bayes::Basis;
use tcomp_train::mse::CenterSelection;
use tcomp_train::{
    ChannelOptions, Dataset, FeatureOptions, FitOptions, FitSummary, MethodOptions, Spec,
};

/// Arguments of `tcomp fit`: the run, and one flattened struct per concern of the trainer's
/// options (the same structs the spec file is read into, so a flag and its spec key are one field).
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The run to fit on.
    #[command(flatten)]
    pub run: RunArgs,
    /// Where to write the model blob (.tcm).
    #[arg(long)]
    pub out: PathBuf,
    /// TOML spec with the same keys as these flags (flags override; features and signals add up).
    #[arg(long)]
    pub spec: Option<PathBuf>,
    /// Columns and the blob's description of the channel.
    #[command(flatten)]
    pub channel: ChannelOptions,
    /// Signals and features.
    #[command(flatten)]
    pub features: FeatureOptions,
    /// Method and settings.
    #[command(flatten)]
    pub method: MethodOptions,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Quiet: no progress display and no summary (warnings and errors still reach standard
    /// error; the model is still written, and `--json` still prints).
    #[arg(long)]
    pub quiet: bool,
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let data_path = args.run.data.as_path();
    crate::output::files::check_file_output("--out", &args.out)?;
    let mut inputs = vec![("--data", data_path)];
    if let Some(spec) = &args.spec {
        inputs.push(("--spec", spec.as_path()));
    }
    crate::output::files::refuse_overwriting_inputs(
        "--out",
        std::slice::from_ref(&args.out),
        &inputs,
    )?;
    let file_spec = match &args.spec {
        Some(p) => Spec::load(p)?,
        None => Spec::default(),
    };
    let flags = Spec {
        run: args.run.run.clone(),
        channel: args.channel.clone(),
        features: args.features.clone(),
        method: args.method.clone(),
    };
    let opts = FitOptions::from_spec(&file_spec.merged(flags))?;
    let progress = crate::output::progress::Bar::new(args.quiet);
    let data = Dataset::load_with(data_path, &opts.load_options(), &progress)?;
    let fitted = tcomp_train::fit_with_progress(&data, &opts, &progress)?;
    let bytes = fitted.model.to_bytes()?;
    tcomp_train::blob_io::write_atomic(&args.out, &bytes)
        .with_context(|| format!("writing {}", args.out.display()))?;
    progress.clear();
    let s = &fitted.summary;
    if args.json {
        let subject = Subject::new(
            vec![args.out.display().to_string()],
            &opts.target,
            &opts.unit,
            data_path,
        );
        // The training figures in the shared vocabulary (null where no bin held data).
        let mut body = serde_json::to_value(s)?;
        if let Some(obj) = body.as_object_mut() {
            obj.insert(
                "train".into(),
                serde_json::to_value(RunFigures::from(&s.train))?,
            );
        }
        json::print("fit", &subject, &body)?;
    } else {
        // Warnings (a model the firmware cannot hold, rows a messy file lost) are not chatter:
        // they reach standard error under --quiet too.
        for w in &s.warnings {
            eprintln!("warning: {w}");
        }
        if !args.quiet {
            let unit = crate::render::num::unit_or_column(&opts.unit, &opts.target);
            print_summary(s, &args.out, &crate::output::printable::text(&unit));
        }
    }
    Ok(())
}

fn print_summary(s: &FitSummary, out: &std::path::Path, unit: &str) {
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
    if let Some(st) = &d.structure {
        outln!("structure   {}", st.chosen);
        for (name, ev) in &st.compared {
            outln!("  compared  log evidence {ev:>10.2}  {name}");
        }
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
    let t = RunFigures::from(&s.train);
    let n = |v: Option<f64>| v.map_or_else(|| "no data".into(), |v| num(v, unit));
    outln!(
        "training    raw std {}  residual std {}  change {}   ({} s bins: {} → {})",
        n(t.raw_std),
        n(t.residual_std),
        pct(t.change_pct),
        plain(t.binned.seconds, SIG),
        n(t.binned.raw_std),
        n(t.binned.residual_std)
    );
    outln!("wrote       {} ({} bytes)", out.display(), s.blob_bytes);
}

#[cfg(test)]
mod tests {
    use super::*;
    use tcomp_train::layer::Layer;

    /// The spec keys and the flags are the same fields: every key is a flag of `fit` (`--KEY`, or
    /// `--no-KEY` for a switch that turns a default on off).
    #[test]
    fn every_spec_key_is_a_flag() {
        let cmd = <Args as clap::Args>::augment_args(clap::Command::new("fit"));
        let longs: Vec<String> = cmd
            .get_arguments()
            .filter_map(|a| a.get_long().map(str::to_string))
            .collect();
        let mut keys = Vec::new();
        Spec::keys(&mut keys);
        assert!(keys.len() >= 20, "{keys:?}");
        for k in keys {
            assert!(
                longs.contains(&k) || longs.contains(&format!("no-{k}")),
                "spec key `{k}` has no flag among {longs:?}"
            );
        }
    }

    /// An absent switch leaves the spec file's value; a given one overrides it.
    #[test]
    fn switches_are_unset_unless_given() {
        let cmd = <Args as clap::Args>::augment_args(clap::Command::new("fit"));
        let parse = |extra: &[&str]| {
            let mut argv = vec!["fit", "--data", "d.csv", "--out", "m.tcm"];
            argv.extend_from_slice(extra);
            let m = cmd.clone().try_get_matches_from(argv).ok()?;
            <Args as clap::FromArgMatches>::from_arg_matches(&m).ok()
        };
        let plain = parse(&[]).map(|a| {
            (
                a.method.settings.bayes.linear,
                a.method.settings.bayes.cubic,
            )
        });
        assert_eq!(plain, Some((None, None)));
        let off = parse(&["--no-linear", "--no-cubic"]).map(|a| {
            (
                a.method.settings.bayes.linear,
                a.method.settings.bayes.cubic,
            )
        });
        assert_eq!(off, Some((Some(false), Some(false))));
        let mut file = Spec::default();
        file.method.settings.bayes.linear = Some(false);
        let flags = parse(&[]).map(|a| Spec {
            method: a.method,
            ..Spec::default()
        });
        let merged = file.merged(flags.unwrap_or_default());
        assert_eq!(merged.method.settings.bayes.linear, Some(false));
    }
}
