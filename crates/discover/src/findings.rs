//! What the refits and the placebo test found about one candidate: plain records, apart from the
//! code that computes them ([`crate::confirm`], [`crate::placebo`]), so that a scored candidate
//! ([`crate::score::Scored`]) can carry them without the scoring importing that code (which
//! imports the scoring).

use serde::Serialize;

/// The real refit of one candidate.
#[derive(Clone, Debug, Serialize)]
pub struct Confirmation {
    /// Held-out residual std (binned) of the refitted base feature set.
    pub residual_std_before: f64,
    /// The same with the candidate added.
    pub residual_std_after: f64,
    /// 100·(1 − after/before).
    pub improvement_pct: f64,
    /// What the held-out data was.
    pub heldout: String,
    /// Held-out blocks in which the candidate lowered the residual.
    pub splits_improved: usize,
    /// Held-out blocks.
    pub splits: usize,
    /// Δ log evidence of the trainer's refits on the whole training run: with the candidate
    /// minus without.
    pub delta_log_evidence_refit: f64,
    /// The user's own fits with and without the candidate on the verification run, when there is
    /// one and the verdict names the candidate (`confirm::verify`): reported, never used to choose
    /// (the figures above, on blocks of the training run, are what the criterion reads).
    pub verification: Option<Verification>,
}

/// A confirmed candidate's figures on the verification run: what the user's own fit gets there
/// (`tcomp fit` on the training run with the trainer's defaults, its structure chosen by its
/// evidence), not the joint refit the training run's blocks judge the candidate with.
#[derive(Clone, Debug, Serialize)]
pub struct Verification {
    /// What the run was.
    pub run: String,
    /// Binned residual std of the user's fit of the base feature set on it.
    pub residual_std_before: f64,
    /// The same with the candidate added.
    pub residual_std_after: f64,
    /// 100·(after/before − 1): negative when the residual fell.
    pub change_pct: f64,
}

/// One candidate against its placebos.
#[derive(Clone, Debug, Serialize)]
pub struct Placebo {
    /// AR(1) coefficient of the binned noise (chosen by the base design's evidence).
    pub rho: f64,
    /// The candidate's Δ log evidence under that noise.
    pub statistic: f64,
    /// The circular shifts of its placebos (bins).
    pub shifts_bins: Vec<usize>,
    /// Bins of the binned training run the shifts count in.
    pub bins: usize,
    /// The placebos' Δ log evidence, one per shift.
    pub placebos: Vec<f64>,
    /// The largest placebo statistic over every candidate tested: the acceptance threshold.
    pub threshold: f64,
    /// The false-alarm rate the threshold holds: 1 / (placebos + 1).
    pub level: f64,
    /// The second stage, for a candidate with no searched parameter that fails the first: the
    /// trainer's refits of its placebos on the training run's blocks.
    pub refit: Option<RefitPlacebos>,
}

impl Placebo {
    /// Whether the candidate beats every placebo, in its evidence or in its refits.
    pub fn passes(&self) -> bool {
        self.statistic > self.threshold || self.refit.as_ref().is_some_and(RefitPlacebos::passes)
    }
}

/// The second stage of the test: the candidate's held-out improvement — the figure its
/// confirmation measured, the trainer's refits predicting each block of the training run from
/// the others — against the same figure for each placebo, its columns shifted in time and
/// refitted the same way.
///
/// Why a second stage: the scoring design keeps the base model's Gaussians fixed, and some effects
/// leave it nothing to gain in-sample — on a run with one ramp rate the Gaussians over (T, dT/dt)
/// follow T·dT/dt on the training rows, and only a held-out ramp shows which extrapolates. Such a
/// candidate is judged on its held-out figure, so its placebos are too. Only a candidate without
/// a searched parameter gets it: a parameter chosen on those same blocks would make the
/// candidate's figure optimistic against placebos that were not searched.
#[derive(Clone, Debug, Serialize)]
pub struct RefitPlacebos {
    /// The candidate's held-out improvement (%) over the training run's blocks.
    pub improvement_pct: f64,
    /// The same for each placebo.
    pub placebos_pct: Vec<f64>,
    /// The acceptance threshold: the largest placebo improvement over every candidate retested in
    /// this stage (the max-statistic, as the first stage's threshold), so that the stage holds its
    /// rate however many candidates it retests.
    pub threshold_pct: f64,
}

impl RefitPlacebos {
    /// Whether the candidate's improvement beats every placebo of every candidate retested.
    pub fn passes(&self) -> bool {
        !self.placebos_pct.is_empty()
            && self.improvement_pct > self.threshold_pct
            && self.placebos_pct.iter().all(|p| self.improvement_pct > *p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A retested candidate that beats its own refitted placebos but not another retested
    /// candidate's fails the second stage: the threshold is shared.
    #[test]
    fn the_second_stage_threshold_is_shared() {
        let own = RefitPlacebos {
            improvement_pct: 21.0,
            placebos_pct: vec![3.0, 15.0, -2.0],
            threshold_pct: 15.0,
        };
        assert!(own.passes());
        let shared = RefitPlacebos {
            threshold_pct: 24.0,
            ..own.clone()
        };
        assert!(!shared.passes());
        let none = RefitPlacebos {
            placebos_pct: Vec::new(),
            threshold_pct: f64::NEG_INFINITY,
            ..own
        };
        assert!(!none.passes());
    }
}
