//! The baseline every report compares against: a cubic polynomial in one temperature, clamped to the
//! trained range — what PX4 and ArduPilot fly.
//!
//! Why through the RBF evaluator: the cubic is written as three features of the core's language,
//! `Tclamped = clamp(T, lo, hi)`, `Tclamped`, `sq(Tclamped)`, `Tclamped * sq(Tclamped)`, with the linear
//! term and zero centers, so the same blob format, evaluator and firmware fly it and the comparison
//! with the RBF methods is on equal terms.
//!
//! The same cubic is also a basis `bayes` may choose ([`crate::cubic`] builds its program and
//! columns): on a tie in evidence with the Gaussians it is the simpler model.

use crate::dataset::Dataset;
use crate::error::TrainError;
use crate::features::{self, FeatureSpec};
use crate::method::{FitMethod, MethodDetails, MethodFit, Shared, TrainingSet};
use crate::progress::Progress;
use crate::rbf64::{Rbf64, design, least_squares, mean_std, normalise_rows, split_weights};
use serde::Deserialize;
use tcomp_core::expr::{self, Expr};

/// Name of the clamped-temperature signal poly3 defines.
pub const SIGNAL: &str = "Tclamped";

/// The signal line and feature expressions of a cubic in `feature` (an expression's text) clamped
/// to `[lo, hi]` (written in scientific notation, as the blobs of earlier builds have them).
pub fn program_lines(feature: &str, lo: f64, hi: f64) -> (String, Vec<String>) {
    let clamped = expr::clamp(Expr::text(feature), Expr::sci(lo), Expr::sci(hi));
    let t = expr::name(SIGNAL);
    (
        expr::define(SIGNAL, &clamped),
        [t.clone(), expr::sq(t.clone()), t.clone() * expr::sq(t)]
            .iter()
            .map(Expr::to_string)
            .collect(),
    )
}

/// Least-squares cubic on the three features (rows `x` = [T, T², T³] as computed by the core).
pub fn fit(x: &[Vec<f64>], y: &[f64]) -> Result<Rbf64, TrainError> {
    let (xm, xs) = mean_std(x);
    let scale: Vec<f64> = xs.iter().map(|s| 1.0 / s.max(1e-300)).collect();
    let z = normalise_rows(x, &xm, &scale);
    let phi = design(&z, true, &[], &[]);
    let w = least_squares(&phi, y)?;
    let (bias, linear, _) = split_weights(&w, xm.len());
    Ok(Rbf64 {
        offset: xm,
        scale,
        centers: Vec::new(),
        gamma: Vec::new(),
        weights: Vec::new(),
        linear,
        bias,
        masks: Vec::new(),
        kinds: Vec::new(),
    })
}

crate::layer! {
    /// The `poly3` method (it has no options of its own).
    #[derive(Clone, Debug, Default, PartialEq, Deserialize)]
    #[cfg_attr(feature = "cli", derive(clap::Args))]
    pub struct Poly3 {}
}

impl FitMethod for Poly3 {
    fn name(&self) -> &'static str {
        "poly3"
    }

    fn about(&self) -> &'static str {
        "the PX4/ArduPilot cubic in the first feature, clamped to its trained range"
    }

    fn min_samples(&self, _opts: &Shared<'_>) -> usize {
        8
    }

    fn features_fitted(&self, _opts: &Shared<'_>) -> usize {
        1
    }

    /// The program around one clamped temperature: the first feature's range over the selected
    /// rows, then [`program_lines`].
    fn program(
        &self,
        opts: &Shared<'_>,
        data: &Dataset,
        starts: &[usize],
        warnings: &mut Vec<String>,
    ) -> Result<FeatureSpec, TrainError> {
        let expr = opts.spec.features.first().ok_or(TrainError::MethodNeeds {
            method: "poly3",
            what: "one feature: the temperature expression",
        })?;
        if opts.spec.features.len() > 1 {
            warnings.push(format!(
                "poly3 uses only the first feature `{expr}`; the others are ignored"
            ));
        }
        let probe = FeatureSpec {
            signals: opts.spec.signals.clone(),
            features: vec![expr.clone()],
        };
        let time = data.time(opts.time)?;
        let time_on = features::time_on_s(time, opts.power_on_s)?;
        let t = features::compute_from(&probe.program()?, data, time, starts, time_on)?;
        let (lo, hi) = t
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), r| {
                (l.min(f64::from(r[0])), h.max(f64::from(r[0])))
            });
        let (sig, feats) = program_lines(expr, lo, hi);
        let mut signals = opts.spec.signals.clone();
        signals.push(sig);
        Ok(FeatureSpec {
            signals,
            features: feats,
        })
    }

    fn memory(&self, s: &crate::budget::Shape) -> f64 {
        crate::budget::lsq(s.samples, 4)
    }

    /// T, T², T³ of one temperature are collinear on purpose.
    fn refuses_collinear(&self) -> bool {
        false
    }

    fn fit(
        &self,
        set: &mut TrainingSet,
        _opts: &Shared<'_>,
        _progress: &dyn Progress,
    ) -> Result<MethodFit, TrainError> {
        Ok(MethodFit {
            rbf: fit(&set.x, &set.y)?,
            width: None,
            details: MethodDetails::default(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn program_lines_spell_the_cubic_as_before() {
        let (signal, features) = program_lines("mean(t_a, t_b)", -10.0, 21.5);
        assert_eq!(signal, "Tclamped = clamp(mean(t_a, t_b), -1e1, 2.15e1)");
        assert_eq!(
            features,
            ["Tclamped", "sq(Tclamped)", "Tclamped * sq(Tclamped)"]
        );
    }
}
