//! `summary.json`: what `tcomp calibrate` did for each channel, in the tool's one JSON vocabulary
//! (inside [`crate::output::json::Output`], `null` where there is no data, `change_pct` negative when
//! the residual fell), validated by `schema/tcomp-output.schema.json`.

use super::channel::ChannelResult;
use super::ship::Shipped;
use super::unit::{UnitResult, blob_name};
use crate::output::json::{self, Subject};
use serde::Serialize;

/// What the report and the JSON say about the shipping gate.
pub const GATE_NOTE: &str = "The choice among model, poly3 and raw is a verification gate decided \
    on the held-out run (the issue's rule): the shipped residual is the smallest of three held-out \
    figures, so it is optimistic, not an unbiased estimate of the error in use. Each candidate's own \
    held-out figure is unbiased: the diagnosis and any --accept refit chose on the training run only.";

/// A window of rows.
#[derive(Serialize)]
pub struct Window {
    /// The file.
    pub file: String,
    /// First time (s).
    pub from_s: Option<f64>,
    /// Last time (s).
    pub until_s: Option<f64>,
    /// Rows.
    pub rows: usize,
}

/// The held-out figures (RMS against the reference).
#[derive(Serialize)]
pub struct Heldout {
    /// The rows.
    #[serde(flatten)]
    pub window: Window,
    /// RMS of target − reference.
    pub raw_rms: Option<f64>,
    /// RMS of the poly3 baseline's residual.
    pub poly3_rms: Option<f64>,
    /// RMS of the model's residual.
    pub model_rms: Option<f64>,
    /// RMS of what ships.
    pub residual_rms: Option<f64>,
    /// From raw to what ships (%; negative when the residual fell).
    pub change_pct: Option<f64>,
    /// From raw to the model (%).
    pub model_change_pct: Option<f64>,
}

/// The diagnosis' verdict.
#[derive(Serialize)]
pub struct DiagnosisSummary {
    /// The verdict.
    pub verdict: tcomp_discover::Verdict,
    /// In words.
    pub text: String,
    /// What it ran on.
    pub on: &'static str,
}

/// What `--accept` did.
#[derive(Serialize)]
pub struct AcceptedSummary {
    /// The instruction applied.
    pub instruction: String,
    /// The model's held-out RMS before it.
    pub before_rms: Option<f64>,
    /// After it.
    pub after_rms: Option<f64>,
    /// From before to after (%).
    pub change_pct: Option<f64>,
    /// The earlier blob.
    pub before_file: String,
}

/// One channel.
#[derive(Serialize)]
pub struct ChannelSummary {
    /// Name.
    pub name: String,
    /// Target column.
    pub target: String,
    /// Unit.
    pub unit: Option<String>,
    /// Board channel id.
    pub id: Option<u16>,
    /// Method.
    pub method: String,
    /// Features of the model.
    pub features: Vec<String>,
    /// The model's blob.
    pub model_file: String,
    /// The poly3 baseline's blob.
    pub poly3_file: String,
    /// The poly3 baseline's coefficients (linear weights of T, T², T³ on normalised features):
    /// what `--units` and `--collect` compare across units.
    pub poly3_coefficients: Vec<f64>,
    /// Training rows.
    pub train: Window,
    /// Held-out rows and figures.
    pub heldout: Heldout,
    /// What ships.
    pub shipped: Shipped,
    /// Why.
    pub reason: String,
    /// Loud flags.
    pub flags: Vec<String>,
    /// The diagnosis.
    pub diagnosis: Option<DiagnosisSummary>,
    /// `--accept`.
    pub accepted: Option<AcceptedSummary>,
}

/// The body of `summary.json`.
#[derive(Serialize)]
pub struct Summary {
    /// Unit serial.
    pub serial: u64,
    /// Board description.
    pub board: Option<String>,
    /// The image file, when written.
    pub image: Option<String>,
    /// The HTML report, when written.
    pub report: Option<String>,
    /// Split time (s), when one log is split.
    pub split_s: Option<f64>,
    /// The shipping gate and what its figure means.
    pub gate_note: &'static str,
    /// Channels flagged.
    pub flagged: usize,
    /// The channels.
    pub channels: Vec<ChannelSummary>,
}

fn window(file: &str, span: Option<(f64, f64)>, rows: usize) -> Window {
    Window {
        file: file.to_string(),
        from_s: span.map(|s| s.0),
        until_s: span.map(|s| s.1),
        rows,
    }
}

/// One channel's summary.
pub fn channel(c: &ChannelResult, u: &UnitResult) -> ChannelSummary {
    let train_file = u.data.train_file.display().to_string();
    let verify_file = u
        .data
        .verify_file
        .as_ref()
        .map_or_else(|| train_file.clone(), |v| v.display().to_string());
    let raw = c.model.figures.raw_rms;
    let model = c.model.figures.residual_rms;
    ChannelSummary {
        name: c.plan.name.clone(),
        target: c.opts.target.clone(),
        unit: (!c.unit.is_empty()).then(|| c.unit.clone()),
        id: c.plan.id,
        method: c.model.summary.method.to_string(),
        features: c.model.summary.features.clone(),
        model_file: blob_name(&c.plan.name, ""),
        poly3_file: blob_name(&c.plan.name, "poly3"),
        poly3_coefficients: c.poly3.summary.linear.clone(),
        train: window(&train_file, c.train_span, c.train_rows),
        heldout: Heldout {
            window: window(&verify_file, c.verify_span, c.verify_rows),
            raw_rms: raw,
            poly3_rms: c.poly3.figures.residual_rms,
            model_rms: model,
            residual_rms: c.choice.residual_rms,
            change_pct: json::change(raw, c.choice.residual_rms),
            model_change_pct: json::change(raw, model),
        },
        shipped: c.choice.shipped,
        reason: c.choice.reason.clone(),
        flags: c.choice.flags.clone(),
        diagnosis: c.analysis.as_ref().map(|a| DiagnosisSummary {
            verdict: a.diagnosis.verdict,
            text: a.diagnosis.verdict_text.clone(),
            on: "the training run (contiguous blocks held out in turn)",
        }),
        accepted: c.accepted.as_ref().map(|a| AcceptedSummary {
            instruction: a.instruction.clone(),
            before_rms: a.before.figures.residual_rms,
            after_rms: model,
            change_pct: json::change(a.before.figures.residual_rms, model),
            before_file: blob_name(&c.plan.name, "before"),
        }),
    }
}

/// The whole summary.
pub fn summary(u: &UnitResult, board: Option<&str>, report: Option<&str>) -> Summary {
    let channels: Vec<ChannelSummary> = u.channels.iter().map(|c| channel(c, u)).collect();
    Summary {
        serial: u.serial,
        board: board.map(str::to_string),
        image: u.image.as_ref().map(|_| "image.bin".to_string()),
        report: report.map(str::to_string),
        split_s: u.data.split_s,
        gate_note: GATE_NOTE,
        flagged: channels.iter().filter(|c| !c.flags.is_empty()).count(),
        channels,
    }
}

/// What the output is about: the unit's data and the blobs that ship.
pub fn subject(u: &UnitResult) -> Subject {
    Subject {
        models: u
            .channels
            .iter()
            .filter_map(|c| match c.choice.shipped {
                Shipped::Model => Some(blob_name(&c.plan.name, "")),
                Shipped::Poly3 => Some(blob_name(&c.plan.name, "poly3")),
                Shipped::Raw => None,
            })
            .collect(),
        target: None,
        unit: None,
        data: Some(u.data.train_file.display().to_string()),
        verify: u.data.verify_file.as_ref().map(|v| v.display().to_string()),
    }
}

/// The text of `summary.json`.
pub fn to_json(
    u: &UnitResult,
    board: Option<&str>,
    report: Option<&str>,
) -> anyhow::Result<String> {
    let subject = subject(u);
    let body = summary(u, board, report);
    Ok(serde_json::to_string_pretty(&json::Output {
        command: "calibrate",
        subject: &subject,
        body: &body,
    })?)
}
