//! `tcomp autopilot-params --data LOG --out FILE`: the thermal calibration the autopilot's own tool
//! would compute from the log — PX4's `TC_*` parameters from a ULog, ArduPilot's `INS_TCALn_*`
//! from a DataFlash log — written in its parameter-file format
//! ([`tcomp_train::autopilot`]), so that a drone user can fly it, and compare it with tcomp's model
//! on the same log (`tcomp fit`/`eval` read the log too).
//!
//! `--held-out-from SECONDS` adds the side-by-side a drone user needs: on the log's records from
//! that time on, what each axis spreads by with nothing removed, with the autopilot's cubic
//! (fitted by the tool's own procedure on the records before it) and with tcomp's model (the
//! default `tcomp fit` on the same records, the instance's temperature as its feature), and what
//! tcomp's diagnosis of that model on the training records says is missing. The parameter file
//! written is still the whole log's, as the tool writes it. Figures are standard deviations: both
//! autopilots leave the constant to another calibration.
use anyhow::Context;
use clap::Args as ClapArgs;
use std::path::PathBuf;

/// Arguments of `tcomp autopilot-params`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The log: PX4 ULog (.ulg) or ArduPilot DataFlash (.bin).
    #[arg(long)]
    pub data: PathBuf,
    /// The parameter file to write (PX4: QGroundControl's .params; ArduPilot: NAME VALUE lines).
    #[arg(long)]
    pub out: PathBuf,
    /// Print the parameters as JSON too.
    #[arg(long)]
    pub json: bool,
    /// No notes.
    #[arg(long)]
    pub quiet: bool,
    /// Also compare, on the records from this time on (seconds, the log's `time_s`), the
    /// autopilot's cubic and tcomp's model, both fitted on the records before it.
    #[arg(long, value_name = "SECONDS")]
    pub held_out_from: Option<f64>,
}

/// The diagnosis' bin (s): ArduPilot's tool averages over 2 s before fitting, the shortest span
/// an autopilot calibration treats as one temperature. (tcomp's default bin, 60 s, is longer
/// than the short logs autopilot users have.)
const DIAGNOSIS_BIN_S: f64 = 2.0;

/// One axis of the side-by-side.
#[derive(Debug, serde::Serialize)]
pub struct Row {
    /// The autopilot's figures on the held-out records.
    #[serde(flatten)]
    pub autopilot: tcomp_train::autopilot::HeldOutAxis,
    /// What tcomp's model leaves there (standard deviation), or why it could not be fitted.
    pub tcomp_std: Result<f64, String>,
    /// What the diagnosis says is missing (an instruction), that nothing is, or why it did not run.
    pub diagnosis: String,
}

/// tcomp's model of `a`'s axis (the signal the cubic saw) on the records before `from`, its
/// spread over the records from `from` on, and its diagnosis on the training records.
fn tcomp_side(a: &tcomp_train::autopilot::HeldOutAxis, from: f64) -> (Result<f64, String>, String) {
    let mut o = tcomp_train::FitOptions::new(&a.column, &[a.temperature.as_str()]);
    o.reference_value = Some(0.0);
    o.until = Some(from);
    let d = &a.data;
    let f = match tcomp_train::fit(d, &o) {
        Ok(f) => f,
        Err(e) => return (Err(format!("{e:#}")), "not run: no model".into()),
    };
    let model = match f.model.model() {
        Ok(m) => m,
        Err(e) => return (Err(format!("{e:#}")), "not run: no model".into()),
    };
    let roles = tcomp_train::Roles::of_model(&model);
    let std = tcomp_train::metrics::run_model(&model, d, &roles, Some(&a.temperature), None)
        .map(|r| tcomp_train::autopilot::std(&r.window(from, f64::INFINITY).residual))
        .map_err(|e| format!("{e:#}"));
    let diagnosis = (|| -> anyhow::Result<String> {
        let train = d.select_time(&roles.time, f64::NEG_INFINITY, from)?;
        let mut opts = tcomp_discover::DiagnoseOptions::default();
        opts.score.bin_s = DIAGNOSIS_BIN_S;
        let a = tcomp_discover::diagnose(&model, &train, None, &opts)?;
        Ok(match a.diagnosis.candidates.first() {
            Some(c) if a.diagnosis.verdict == tcomp_discover::Verdict::MissingEffect => {
                tcomp_discover::verdict::instruction(c)
            }
            _ => "nothing missing".into(),
        })
    })()
    .unwrap_or_else(|e| format!("not run: {e:#}"));
    (std, diagnosis)
}

/// The side-by-side on the records from `from` on.
pub fn side_by_side(path: &std::path::Path, from: f64) -> anyhow::Result<Vec<Row>> {
    let (_, axes) = tcomp_train::autopilot::held_out(path, from)?;
    Ok(axes
        .into_iter()
        .map(|a| {
            let (tcomp_std, diagnosis) = tcomp_side(&a, from);
            Row {
                autopilot: a,
                tcomp_std,
                diagnosis,
            }
        })
        .collect())
}

/// The side-by-side as a table.
fn print_rows(rows: &[Row], from: f64) {
    let n = tcomp_train::num::exact;
    outln!(
        "held out: the records from {} s on; standard deviation of what is left (the log's units)",
        n(from)
    );
    outln!(
        "{:<22} {:>5} {:>13} {:>11} {:>15} {:>13}  diagnosis of tcomp's model",
        "axis",
        "rows",
        "held-out °C",
        "raw",
        "autopilot cubic",
        "tcomp model"
    );
    for r in rows {
        let a = &r.autopilot;
        let t = match &r.tcomp_std {
            Ok(v) => format!("{v:.4e}"),
            Err(_) => "not fitted".into(),
        };
        outln!(
            "{:<22} {:>5} {:>13} {:>11.4e} {:>15.4e} {:>13}  {}",
            crate::output::printable::text(&a.column),
            a.rows,
            format!("{:.1}–{:.1}", a.held_out_range[0], a.held_out_range[1]),
            a.raw_std,
            a.cubic_std,
            t,
            crate::output::printable::text(&r.diagnosis)
        );
    }
    for r in rows {
        if let Err(e) = &r.tcomp_std {
            outln!(
                "{}: tcomp's model: {}",
                crate::output::printable::text(&r.autopilot.column),
                crate::output::printable::text(e)
            );
        }
    }
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    crate::output::files::check_file_output("--out", &args.out)?;
    crate::output::files::refuse_overwriting_inputs(
        "--out",
        std::slice::from_ref(&args.out),
        &[("--data", args.data.as_path())],
    )?;
    let p = tcomp_train::autopilot::from_log(&args.data)?;
    tcomp_train::blob_io::write_atomic(&args.out, p.text().as_bytes())
        .with_context(|| format!("writing {}", args.out.display()))?;
    if !args.quiet {
        for s in &p.skipped {
            eprintln!("note: {s}");
        }
    }
    let rows = args
        .held_out_from
        .map(|from| side_by_side(&args.data, from))
        .transpose()?;
    if args.json {
        let mut v = serde_json::to_value(&p)?;
        if let (Some(rows), Some(o)) = (&rows, v.as_object_mut()) {
            o.insert("held_out".into(), serde_json::to_value(rows)?);
        }
        outln!("{}", serde_json::to_string_pretty(&v)?);
    } else if !args.quiet {
        outln!(
            "wrote {} ({} format: {} instance(s))",
            args.out.display(),
            p.format,
            p.px4.len() + p.ardupilot.len()
        );
    }
    if let (Some(rows), Some(from), false) = (&rows, args.held_out_from, args.json) {
        print_rows(rows, from);
    }
    Ok(())
}
