//! `tcomp simulate`: write simulated temperature-chamber runs with known physics.
//!
//! Writes `train.csv`, `verify.csv` (`.csv.gz` with `--gzip`) and `truth.json` into `--out`, from a
//! preset (`--preset NAME`, see `--list`) or a scenario TOML file (`--scenario FILE`; format in the
//! documentation of `tcomp_sim::scenario`, example in `crates/sim/examples/ifog_custom.toml`).
//!
//! Every option and the scenario are checked before any file is created, and the three files are
//! written to temporaries and renamed into place together, so a failed run leaves an existing
//! output directory as it was. Long runs show a progress bar (rows, rate, time left).

use std::path::PathBuf;

use anyhow::{Context, bail};
use tcomp_sim::{Preset, presets};

/// Arguments of `tcomp simulate`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples:\n  tcomp simulate --list\n  tcomp simulate --preset ifog-shupe --out sim/ --seed 7\n  tcomp simulate --preset rlg --out sim/ --rate-hz 100 --step-s 1 --gzip\n  tcomp simulate --scenario crates/sim/examples/ifog_custom.toml --out sim/"
)]
pub struct Args {
    /// List the presets with a one-line description and exit.
    #[arg(long)]
    pub list: bool,
    /// Preset to simulate (see --list).
    #[arg(long, conflicts_with = "scenario", required_unless_present_any = ["list", "scenario"])]
    pub preset: Option<String>,
    /// Scenario TOML file to simulate instead of a preset.
    #[arg(long, value_name = "FILE.toml")]
    pub scenario: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR", required_unless_present = "list")]
    pub out: Option<PathBuf>,
    /// Seed of the training run (the verification run uses seed + 1).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Internal sensor rate in Hz (e.g. 100 or 200, at most 1000); rows are still averaged to
    /// --step-s.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub rate_hz: Option<f64>,
    /// Output step in seconds (a multiple of 1/rate); default 1 s, or the scenario's.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub step_s: Option<f64>,
    /// Simulate a production line of this many units instead, each in `OUT/unit-NNNN/` with its
    /// own seeds and a spread of its polynomial bias (for `tcomp calibrate --units OUT`).
    #[arg(long, value_name = "N")]
    pub units: Option<usize>,
    /// With --units: plant this many outlier units (listed in OUT/fleet-truth.json).
    #[arg(long, value_name = "K", default_value_t = 0, requires = "units")]
    pub outliers: usize,
    /// Gzip the CSV files (`train.csv.gz`, `verify.csv.gz`).
    #[arg(long)]
    pub gzip: bool,
    /// Print a machine-readable summary as JSON instead of the table.
    #[arg(long)]
    pub json: bool,
    /// No progress display.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs the subcommand.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.list {
        return list(args.json);
    }
    let Some((truth, out)) = write(args)? else {
        return Ok(());
    };
    if args.json {
        return print_json(&truth, out);
    }
    print_text(&truth, out);
    Ok(())
}

/// The command's work without its summary (also what the Python binding's `simulate` runs):
/// checks every option and the scenario, then writes the runs; the truth and the directory, or
/// `None` for `--units` (which reports its units itself unless `--quiet`).
pub fn write(args: &Args) -> anyhow::Result<Option<(tcomp_sim::TruthFile, &std::path::Path)>> {
    let Some(out) = &args.out else {
        bail!("--out DIR is required");
    };
    let mut preset: Preset = match (&args.preset, &args.scenario) {
        (Some(name), None) => presets::preset(name)?,
        (None, Some(path)) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            Preset::from_toml_str(&text).with_context(|| format!("in {}", path.display()))?
        }
        _ => bail!("give either --preset NAME or --scenario FILE.toml (see --list)"),
    };
    if let Some(seed) = args.seed {
        preset = preset.with_seed(seed);
    }
    if args.rate_hz.is_some() || args.step_s.is_some() {
        let rate = args.rate_hz.unwrap_or(preset.train.rate_hz);
        let step = args.step_s.unwrap_or(preset.train.step_s.max(1.0 / rate));
        preset = preset.with_rate(rate, step);
    }
    // Checked here, before anything is written, with the options named as typed.
    for sc in [&preset.train, &preset.verify] {
        sc.validate().map_err(|e| as_flags(e, args))?;
    }
    if let Some(n) = args.units {
        let planted =
            super::simulate_units::run(&preset, n, args.outliers, args.seed.unwrap_or(1), out)?;
        if !args.quiet {
            outln!("wrote {n} units into {}", out.display());
            for p in &planted {
                outln!("  outlier {}: {}", p.unit, p.kind);
            }
        }
        return Ok(None);
    }
    let mut progress = crate::output::progress::Bar::new(args.quiet);
    let truth = tcomp_sim::write_preset_with_progress(&preset, out, args.gzip, &mut progress)?;
    progress.clear();
    Ok(Some((truth, out.as_path())))
}

/// A scenario error about the rate or the step, named by the flag that set it.
fn as_flags(e: tcomp_sim::Error, args: &Args) -> anyhow::Error {
    match &e {
        tcomp_sim::Error::Invalid { field, message } => {
            let flag = match field.as_str() {
                "rate_hz" if args.rate_hz.is_some() => "--rate-hz",
                "step_s" if args.step_s.is_some() => "--step-s",
                _ => return e.into(),
            };
            anyhow::anyhow!("{flag}: {message}")
        }
        _ => e.into(),
    }
}

/// `--list`: the presets, as text or JSON.
fn list(json: bool) -> anyhow::Result<()> {
    if json {
        let list: Vec<_> = presets::list()
            .iter()
            .map(|p| serde_json::json!({"name": p.name, "description": p.description}))
            .collect();
        outln!("{}", serde_json::to_string_pretty(&list)?);
    } else {
        outln!("Presets (tcomp simulate --preset NAME --out DIR):");
        for p in presets::list() {
            outln!("  {:<12} {}", p.name, p.description);
        }
    }
    Ok(())
}

/// What was written, as JSON.
fn print_json(truth: &tcomp_sim::TruthFile, out: &std::path::Path) -> anyhow::Result<()> {
    let run = |t: &tcomp_sim::Truth, file: Option<&String>| {
        serde_json::json!({
            "file": file.map(|f| out.join(f)),
            "rows": t.rows,
            "bias_std": t.bias_std,
            "noise_std_raw": t.noise.std_raw,
            "noise_std_100s": t.noise.std_100s,
            "noise_std_1000s": t.noise.std_1000s,
        })
    };
    let summary = serde_json::json!({
        "name": truth.name,
        "sensor": truth.sensor,
        "unit": truth.train.unit,
        "truth": out.join("truth.json"),
        "train": run(&truth.train, truth.files.get("train")),
        "verify": run(&truth.verify, truth.files.get("verify")),
        "effects": truth.effects.iter().map(|e| e.name.clone()).collect::<Vec<_>>(),
        "true_features": truth.true_features,
    });
    outln!("{}", serde_json::to_string_pretty(&summary)?);
    Ok(())
}

/// What was written, as text.
fn print_text(truth: &tcomp_sim::TruthFile, out: &std::path::Path) {
    let t = &truth.train;
    outln!(
        "{} ({}): {} Hz internal, {} s rows, seeds {} / {}",
        truth.name,
        t.sensor.name(),
        t.rate_hz,
        t.step_s,
        t.seed,
        truth.verify.seed
    );
    for (role, run) in [("train", &truth.train), ("verify", &truth.verify)] {
        let file = truth.files.get(role).cloned().unwrap_or_default();
        outln!(
            "  wrote {:<40} {:>9} rows  bias std {:.4} {u}  noise std {:.4} raw, {:.4} (100 s bins) {u}",
            out.join(&file).display().to_string(),
            run.rows,
            run.bias_std,
            run.noise.std_raw,
            run.noise.std_100s,
            u = run.unit
        );
    }
    outln!("  wrote {}", out.join("truth.json").display());
    let names: Vec<&str> = truth.effects.iter().map(|e| e.name.as_str()).collect();
    outln!(
        "  effects: {}",
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    );
    for (name, def) in &truth.true_features.signals {
        outln!("  signal:  {name} = {def}");
    }
    outln!(
        "  true features: {}",
        truth.true_features.features.join("; ")
    );
    outln!(
        "  columns: {} (error = {} - {})",
        t.columns.all.join(","),
        t.columns.target,
        t.columns.reference
    );
}
