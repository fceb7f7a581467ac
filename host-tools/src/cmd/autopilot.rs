//! `tcomp autopilot-params --data LOG --out FILE`: the thermal calibration the autopilot's own tool
//! would compute from the log — PX4's `TC_*` parameters from a ULog, ArduPilot's `INS_TCALn_*`
//! from a DataFlash log — written in its parameter-file format
//! ([`tcomp_train::autopilot`]), so that a drone user can fly it, and compare it with tcomp's model
//! on the same log (`tcomp fit`/`eval` read the log too).
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
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    super::output::check_file_output("--out", &args.out)?;
    super::output::refuse_overwriting_inputs(
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
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&p)?);
    } else if !args.quiet {
        outln!(
            "wrote {} ({} format: {} instance(s))",
            args.out.display(),
            p.format,
            p.px4.len() + p.ardupilot.len()
        );
    }
    Ok(())
}
