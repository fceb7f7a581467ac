//! `tcomp inspect FILE`: print what a blob holds; a corrupt blob is named as such, with the reason.
//! A calibration image (`tcomp image`'s output, told apart by its magic) is printed by
//! [`super::inspect_image`].
//!
//! Every string taken from the blob goes through [`crate::output::printable`], in the table and in `--json`:
//! a blob is a file from elsewhere, and its strings must not drive the terminal.
use clap::Args as ClapArgs;
use serde_json::json;
use std::path::PathBuf;
use tcomp_core::HostModel;
use tcomp_core::rbf::{KIND_CUBE, KIND_GAUSSIAN, KIND_RAMP, KIND_SQUARE, KIND_STEP};

use crate::output::printable::text;

/// Arguments of `tcomp inspect`.
#[derive(ClapArgs)]
pub struct Args {
    /// The model blob (.tcm) or calibration image (`tcomp image`'s output).
    pub model: PathBuf,
    /// Print JSON instead of the human summary.
    #[arg(long)]
    pub json: bool,
    /// A public key (`tcomp keygen`'s PREFIX.pub) to verify an image's signature against
    /// (repeatable: a unit's key store); a signature that does not verify fails the command.
    #[arg(long = "key", value_name = "PUB")]
    pub keys: Vec<PathBuf>,
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    // The keys first: a bad --key is named whatever the file holds.
    let keys = args
        .keys
        .iter()
        .map(|k| super::keygen::read_public(k))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let bytes = tcomp_train::blob_io::read(&args.model)?;
    if bytes.starts_with(&tcomp_core::image::MAGIC) {
        return super::inspect_image::run(&args.model, &bytes, args.json, &keys);
    }
    let m = tcomp_train::blob_io::decode(&args.model, &bytes)?;
    if args.json {
        let value = blob_json(args, &bytes, &m);
        outln!(
            "{}",
            crate::output::printable::json(&serde_json::to_string_pretty(&value)?)
        );
        return Ok(());
    }
    print_blob(args, &bytes, &m);
    Ok(())
}

/// The blob's `--json` document.
pub fn blob_json(args: &Args, bytes: &[u8], m: &HostModel<'_>) -> serde_json::Value {
    let nf = m.n_features();
    let centers: Vec<_> = m
        .rbf
        .centers
        .iter()
        .enumerate()
        .map(|(j, c)| {
            if kind(m, j) != KIND_GAUSSIAN {
                let (a, b) = affine(m, j);
                return json!({
                    "kind": kind_name(kind(m, j)),
                    "features": spanned(m, j),
                    "slope": a,
                    "offset": b,
                    "weight": c.w,
                });
            }
            let (pos, gamma, w) = c.to_natural();
            json!({
                "kind": "gaussian",
                "center": pos.0.get(..nf).unwrap_or(&[]),
                "features": spanned(m, j),
                "gamma": gamma,
                "sigma": c.sigma(),
                "weight": w,
            })
        })
        .collect();
    let features: Vec<_> = m
        .program
        .feature_exprs
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let r = m.ranges.get(k);
            json!({
                "expr": e,
                "lo": r.map(|r| r.lo),
                "hi": r.map(|r| r.hi),
                "offset": m.rbf.offset.0.get(k),
                "scale": m.rbf.scale.0.get(k),
                "linear": m.rbf.linear.0.get(k),
            })
        })
        .collect();
    let signals: Vec<_> = m
        .program
        .signals
        .iter()
        .map(|s| format!("{} = {}", s.name, s.expr))
        .collect();
    let c = &m.meta.columns;
    json!({
        "file": args.model.display().to_string(),
        "bytes": bytes.len(),
        "version": m.version,
        "sensor": format!("{:?}", m.meta.sensor),
        "axis": m.meta.axis,
        "unit": m.meta.unit,
        "method": m.meta.method,
        "columns": {
            "time": c.time, "target": c.target, "reference": c.reference,
            "reference_value": c.reference_value,
        },
        "trained_on": m.meta.trained_on,
        "train_samples": m.meta.train_samples,
        "inputs": m.program.inputs.as_slice(),
        "signals": signals,
        "program_nodes": m.program.nodes.len(),
        "features": features,
        "bias": m.rbf.bias,
        "structure": structure(m),
        "centers": centers,
        "residual": {
            "std": m.residual.std, "binned_std": m.residual.binned_std, "bin_s": m.residual.bin_s,
        },
    })
}

/// The blob as text: metadata, program, features with their ranges, centers, residual level.
fn print_blob(args: &Args, bytes: &[u8], m: &HostModel<'_>) {
    let nf = m.n_features();
    let c = &m.meta.columns;
    let signals: Vec<String> = m
        .program
        .signals
        .iter()
        .map(|s| format!("{} = {}", s.name, s.expr))
        .collect();
    outln!(
        "{}: valid tcomp model blob, format version {}, {} bytes",
        args.model.display(),
        m.version,
        bytes.len()
    );
    outln!(
        "sensor       {:?}  axis \"{}\"  unit \"{}\"",
        m.meta.sensor,
        text(m.meta.axis),
        text(m.meta.unit)
    );
    outln!("method       {}", text(m.meta.method));
    outln!(
        "columns      time {}  target {}  reference {}",
        text(c.time),
        text(c.target),
        match c.reference_value {
            Some(v) if c.reference.is_empty() => format!("constant {v}"),
            _ => text(c.reference),
        }
    );
    outln!(
        "trained on   {} ({} samples)",
        text(m.meta.trained_on),
        m.meta.train_samples
    );
    outln!("inputs       {}", text(&m.program.inputs.join(", ")));
    for s in &signals {
        outln!("signal       {}", text(s));
    }
    outln!(
        "{:<32} {:>12} {:>12} {:>12}",
        "feature",
        "lo",
        "hi",
        "linear"
    );
    for (k, e) in m.program.feature_exprs.iter().enumerate() {
        let r = m.ranges.get(k);
        outln!(
            "{:<32} {:>12.5} {:>12.5} {:>12.4e}",
            text(e),
            r.map_or(f32::NAN, |r| r.lo),
            r.map_or(f32::NAN, |r| r.hi),
            m.rbf.linear.0.get(k).copied().unwrap_or(0.0)
        );
    }
    outln!("bias         {:.6e}", m.rbf.bias);
    outln!("centers      {}", m.rbf.centers.len());
    outln!("structure    {}", structure(m));
    for (j, c) in m.rbf.centers.iter().enumerate() {
        let (pos, _, w) = c.to_natural();
        let over = if m.rbf.masks.is_empty() {
            String::new()
        } else {
            format!("  over {:?}", spanned(m, j))
        };
        if kind(m, j) != KIND_GAUSSIAN {
            let (a, b) = affine(m, j);
            outln!(
                "  {j:>3}  {} of u = {b:+.4} + {:?}·z  w {:+.4e}{over}",
                kind_name(kind(m, j)),
                a,
                c.w
            );
            continue;
        }
        outln!(
            "  {j:>3}  σ {:.3}  w {:+.4e}  at {:?}{over}",
            c.sigma(),
            w,
            pos.0.get(..nf).unwrap_or(&[])
        );
    }
    outln!(
        "residual     std {:.4e}  binned std {:.4e} ({} s bins)",
        m.residual.std,
        m.residual.binned_std,
        m.residual.bin_s
    );
}

/// Center `j`'s kind ([`KIND_GAUSSIAN`] for a model without kinds).
fn kind(m: &HostModel<'_>, j: usize) -> u8 {
    m.rbf.kinds.get(j).copied().unwrap_or(KIND_GAUSSIAN)
}

/// A kind's name in the report.
fn kind_name(k: u8) -> &'static str {
    match k {
        KIND_STEP => "step",
        KIND_SQUARE => "square",
        KIND_CUBE => "cube",
        KIND_RAMP => "ramp",
        _ => "gaussian",
    }
}

/// A step's, a ramp's or a power's argument `u = b + Σ ak·zk` in natural units, as `(a, b)` over
/// the used features (a step is `S(u)`, stored in the fast exponential's units).
fn affine(m: &HostModel<'_>, j: usize) -> (Vec<f32>, f32) {
    let c = &m.rbf.centers[j];
    let unit = if kind(m, j) == KIND_STEP {
        tcomp_core::fastexp::EVAL_UNITS_PER_NAT
    } else {
        1.0
    };
    let a =
        c.q.0
            .iter()
            .take(m.n_features())
            .map(|q| q / unit)
            .collect();
    (a, c.p / unit)
}

/// The features center `j` spans (indices into the program's features).
fn spanned(m: &HostModel<'_>, j: usize) -> Vec<usize> {
    (0..m.n_features()).filter(|&k| m.rbf.spans(j, k)).collect()
}

/// The model's structure in words, from the centers' masks (format 3) and kinds (formats 4 and 5):
/// "joint" when every center spans every feature, else each group of features with its number of
/// centers of each kind.
pub fn structure(m: &HostModel<'_>) -> String {
    if m.rbf.centers.is_empty() {
        return "linear term alone (no Gaussians)".into();
    }
    if m.rbf.masks.is_empty() {
        return format!(
            "joint: {} Gaussians over every feature",
            m.rbf.centers.len()
        );
    }
    let mut groups: Vec<(Vec<usize>, u8, usize)> = Vec::new();
    for j in 0..m.rbf.centers.len() {
        let (f, k) = (spanned(m, j), kind(m, j));
        match groups.iter_mut().find(|(g, gk, _)| *g == f && *gk == k) {
            Some((_, _, n)) => *n += 1,
            None => groups.push((f, k, 1)),
        }
    }
    let name = |k: &usize| {
        m.program
            .feature_exprs
            .get(*k)
            .map_or_else(|| format!("f{k}"), |e| e.to_string())
    };
    let parts: Vec<String> = groups
        .iter()
        .map(|(f, k, n)| {
            let names: Vec<String> = f.iter().map(name).collect();
            let what = match *k {
                KIND_STEP => "steps",
                KIND_SQUARE => "squares",
                KIND_CUBE => "cubes",
                KIND_RAMP => "ramps",
                _ => "Gaussians",
            };
            format!("{n} {what} over ({})", names.join(", "))
        })
        .collect();
    format!("additive: {} + the linear term", parts.join(" + "))
}
