//! What a channel ships: the model, the poly3 baseline or no compensation.
//!
//! The rule: a model whose held-out RMS (against the reference) is worse than raw or than
//! the poly3 baseline is flagged, and the channel ships the best of the three, with the reason.
//! This is a *verification gate* decided on the held-out run, so the shipped figure is the minimum
//! of three held-out figures and is optimistic — not an unbiased estimate of the flying error. The
//! report and the printed table say so; the unbiased figures are each candidate's own held-out RMS
//! (measured before any choice among them).

use serde::Serialize;

/// The compensation a channel ships.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Shipped {
    /// The fitted model.
    Model,
    /// The cubic baseline.
    Poly3,
    /// No compensation: the image has no model for the channel and the firmware passes the raw
    /// value through with status "no model".
    Raw,
}

impl Shipped {
    /// Its name in tables and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Shipped::Model => "model",
            Shipped::Poly3 => "poly3",
            Shipped::Raw => "raw",
        }
    }
}

/// The choice, its reason and the flags raised.
#[derive(Clone, Debug, Serialize)]
pub struct Choice {
    /// What ships.
    pub shipped: Shipped,
    /// Why.
    pub reason: String,
    /// Loud warnings (the model worse than raw or poly3 on held-out data).
    pub flags: Vec<String>,
    /// Held-out RMS of what ships.
    pub residual_rms: Option<f64>,
}

/// `100·(after/before − 1)` as text.
fn worse(after: f64, before: f64) -> String {
    crate::render::num::pct(crate::render::num::change_pct(before, after))
}

/// Chooses among model, poly3 and raw by their held-out RMS. `gate = false` always ships the model
/// (the flags are still raised).
pub fn choose(raw: Option<f64>, poly3: Option<f64>, model: Option<f64>, gate: bool) -> Choice {
    let Some(m) = model else {
        return Choice {
            shipped: Shipped::Model,
            reason: "no held-out data to verify on: the model ships unverified".into(),
            flags: vec!["no held-out data".into()],
            residual_rms: None,
        };
    };
    let mut flags = Vec::new();
    if let Some(r) = raw.filter(|r| m > *r) {
        flags.push(format!(
            "MODEL WORSE THAN RAW on held-out data (RMS {} vs no compensation)",
            worse(m, r)
        ));
    }
    if let Some(p) = poly3.filter(|p| m > *p) {
        flags.push(format!(
            "MODEL WORSE THAN POLY3 on held-out data (RMS {} vs the cubic baseline)",
            worse(m, p)
        ));
    }
    if flags.is_empty() {
        return Choice {
            shipped: Shipped::Model,
            reason: "the model's held-out RMS is at most raw's and poly3's".into(),
            flags,
            residual_rms: Some(m),
        };
    }
    if !gate {
        return Choice {
            shipped: Shipped::Model,
            reason: "shipped as asked (--no-gate) despite the flags".into(),
            flags,
            residual_rms: Some(m),
        };
    }
    let mut best = (Shipped::Model, m);
    for (s, v) in [(Shipped::Poly3, poly3), (Shipped::Raw, raw)] {
        if let Some(v) = v.filter(|v| *v < best.1) {
            best = (s, v);
        }
    }
    let reason = match best.0 {
        Shipped::Poly3 => "the poly3 baseline has the lowest held-out RMS of model, poly3 and raw",
        Shipped::Raw => {
            "no compensation has the lowest held-out RMS of model, poly3 and raw: the image has \
             no model for this channel"
        }
        Shipped::Model => "the model has the lowest held-out RMS of model, poly3 and raw",
    };
    Choice {
        shipped: best.0,
        reason: reason.into(),
        flags,
        residual_rms: Some(best.1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_model_worse_than_raw_is_flagged_and_the_best_ships() {
        let c = choose(Some(1.0), Some(1.5), Some(2.5), true);
        assert_eq!(c.shipped, Shipped::Raw);
        assert_eq!(c.flags.len(), 2, "{:?}", c.flags);
        assert!(c.flags[0].contains("WORSE THAN RAW") && c.flags[0].contains("+150"));
        assert_eq!(c.residual_rms, Some(1.0));
        let c = choose(Some(3.0), Some(1.0), Some(2.0), true);
        assert_eq!((c.shipped, c.flags.len()), (Shipped::Poly3, 1));
        let c = choose(Some(3.0), Some(1.0), Some(2.0), false);
        assert_eq!((c.shipped, c.flags.len()), (Shipped::Model, 1));
    }

    #[test]
    fn a_model_better_than_both_ships_without_flags() {
        let c = choose(Some(3.0), Some(2.0), Some(1.0), true);
        assert_eq!(c.shipped, Shipped::Model);
        assert!(c.flags.is_empty());
        let c = choose(None, None, None, true);
        assert_eq!(c.shipped, Shipped::Model);
        assert_eq!(c.flags.len(), 1);
    }
}
