//! `tcomp calibrate SPEC.toml --out DIR [--units DIR] [--accept]`: fit, verify, diagnose, report
//! and pack a whole unit (or a folder of units) in one command.
//!
//! Everything is checked (the spec, the board, the data) before anything is written, and the
//! outputs are staged and renamed into `--out` at the end ([`crate::output::files::Staging`]): a failed
//! run leaves `--out` as it was. The work itself is in [`crate::calibrate`].
use crate::calibrate::channel::Settings;
use crate::calibrate::fleet::FleetOptions;
use crate::calibrate::spec::CalSpec;
use crate::calibrate::unit::{self, UnitData, UnitResult};
use crate::calibrate::{summary, table};
use crate::output::files::Staging;
use anyhow::Context;
use clap::Args as ClapArgs;
use std::path::PathBuf;
use tcomp_board_description::Board;

/// Arguments of `tcomp calibrate`.
#[derive(ClapArgs, Debug)]
#[command(
    after_help = "Example:\n  tcomp calibrate data/realdata/mems_thermal_cycle.calibrate.toml --out cal/\n  tcomp calibrate examples/calibrate/fleet.calibrate.toml --units fleet/ --out fleet-cal/"
)]
pub struct Args {
    /// The calibration spec (TOML: [unit], [data], [defaults], [[channel]]).
    pub spec: PathBuf,
    /// Output directory: report.html, summary.json, the blobs and image.bin (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// A folder of units: each subfolder (its files named as in [data]) or log file (split at
    /// split-s) is one unit, calibrated with the same spec; writes one folder per unit and a
    /// fleet page.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["unit", "collect"])]
    pub units: Option<PathBuf>,
    /// One unit of such a folder (a batch job's share of a fleet: its serial is the number its
    /// name ends in, its [data] files are looked up in it); writes the single-unit outputs.
    #[arg(long, value_name = "PATH", conflicts_with = "collect")]
    pub unit: Option<PathBuf>,
    /// The fleet page of units calibrated one by one (by batch jobs with --unit): reads each
    /// DIR/*/summary.json and writes fleet.html and fleet.json into --out.
    #[arg(long, value_name = "DIR")]
    pub collect: Option<PathBuf>,
    /// Refit each channel with the effect its diagnosis confirmed (on the training run) and
    /// report before and after.
    #[arg(long)]
    pub accept: bool,
    /// Skip the diagnosis (and so --accept).
    #[arg(long)]
    pub no_diagnosis: bool,
    /// Ship the model even when it is worse than raw or poly3 on the held-out run (still flagged).
    #[arg(long)]
    pub no_gate: bool,
    /// Print summary.json instead of the table.
    #[arg(long)]
    pub json: bool,
    /// No progress display.
    #[arg(long)]
    pub quiet: bool,
}

impl Args {
    /// The channel settings.
    pub fn settings(&self) -> Settings {
        Settings {
            diagnose: !self.no_diagnosis,
            accept: self.accept && !self.no_diagnosis,
            gate: !self.no_gate,
        }
    }
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let spec = CalSpec::load(&args.spec)?;
    let board = spec.board.as_deref().map(Board::load).transpose()?;
    let plans = unit::apply_board(&spec, board.as_ref())?;
    if let Some(dir) = &args.units {
        let options = FleetOptions {
            out: &args.out,
            settings: args.settings(),
            quiet: args.quiet,
        };
        let (fleet, json) =
            crate::calibrate::fleet::run(&options, &spec, &plans, board.as_ref(), dir)?;
        print_fleet(args, &fleet, &json);
        return Ok(());
    }
    if let Some(dir) = &args.collect {
        let rows = crate::calibrate::collect::collect(&plans, dir)?;
        let staging = Staging::new("--out", &args.out)?;
        let (fleet, json) =
            crate::calibrate::fleet::write_fleet(&plans, rows, &spec, dir, staging.path())?;
        staging.commit()?;
        print_fleet(args, &fleet, &json);
        return Ok(());
    }
    let (source, serial) = match &args.unit {
        Some(u) => {
            let e = crate::calibrate::fleet::entry(&spec, u, spec.serial)?.ok_or_else(|| {
                anyhow::anyhow!(
                    "--unit {}: neither a folder nor a .csv/.csv.gz log",
                    u.display()
                )
            })?;
            (e.source, e.serial)
        }
        None => (spec.source_in(&spec.base)?, spec.serial),
    };
    let data = UnitData::load(&source, &plans)?;
    let mut inputs: Vec<(&str, &std::path::Path)> = vec![("SPEC", args.spec.as_path())];
    inputs.push(("[data]", data.train_file.as_path()));
    let outputs: Vec<PathBuf> = ["summary.json", "report.html", "image.bin"]
        .iter()
        .map(|f| args.out.join(f))
        .collect();
    crate::output::files::refuse_overwriting_inputs("--out", &outputs, &inputs)?;
    let bar =
        crate::output::progress::counter(args.quiet, "calibrating", plans.len() as u64, "channels");
    let u = unit::run(
        &plans,
        data,
        serial,
        board.as_ref(),
        args.settings(),
        &|| bar.inc(1),
    )?;
    bar.finish_and_clear();
    let staging = Staging::new("--out", &args.out)?;
    let json = write_unit(&u, &spec, board.as_ref(), staging.path())?;
    staging.commit()?;
    if args.json {
        outln!("{}", crate::output::printable::json(&json));
    } else if !args.quiet {
        out!("{}", table::text(&u));
        outln!("wrote {}", args.out.display());
    }
    Ok(())
}

/// Writes one unit's files (blobs, image, report, summary.json) into `dir`; returns the JSON.
pub fn write_unit(
    u: &UnitResult,
    spec: &CalSpec,
    board: Option<&Board>,
    dir: &std::path::Path,
) -> anyhow::Result<String> {
    unit::write_blobs(u, dir)?;
    let html = crate::render::html::calibrate::page(u, spec);
    let report = dir.join("report.html");
    std::fs::write(&report, html).with_context(|| format!("writing {}", report.display()))?;
    let board_name = board.map(|b| b.path.display().to_string());
    let json = summary::to_json(u, board_name.as_deref(), Some("report.html"))?;
    let p = dir.join("summary.json");
    std::fs::write(&p, &json).with_context(|| format!("writing {}", p.display()))?;
    Ok(json)
}

/// The fleet's outcome: its JSON, or a line and one line per outlier.
fn print_fleet(args: &Args, fleet: &crate::calibrate::fleet::Fleet, json: &str) {
    if args.json {
        outln!("{}", crate::output::printable::json(json));
        return;
    }
    if args.quiet {
        return;
    }
    outln!(
        "{} units calibrated into {}; outliers ({}): {}",
        fleet.units,
        args.out.display(),
        fleet.rule,
        if fleet.outlier_units.is_empty() {
            "none".to_string()
        } else {
            fleet.outlier_units.join(", ")
        }
    );
    for o in &fleet.outliers {
        outln!(
            "  {} {}: {} = {} (z {})",
            o.unit,
            o.channel,
            o.statistic,
            crate::render::num::plain(o.value, 4),
            crate::render::num::signed(o.z, 1)
        );
    }
    outln!("fleet page: {}", args.out.join("fleet.html").display());
}
