//! The "traditional" RBF of both seed papers: centers by k-means or by orthogonal least squares
//! forward selection ([`crate::ols`]), one width from the classic heuristic `σ = d_max/√(2M)`
//! (d_max the largest distance between centers — for OLS, between the candidate rows, since the
//! width must be known before the selection), weights by least squares on the mean-square error
//! alone.
//!
//! Why keep it: it is the baseline the papers improve on, and the comparison (`bayes` generalises
//! better than `mse` with many centers) is one of the results this crate must reproduce.

use crate::error::TrainError;
use crate::kmeans::{dist2, kmeans};
pub use crate::method::CenterSelection;
use crate::rbf64::{Rbf64, design, least_squares, mean_std, normalise_rows, split_weights};
use serde::Deserialize;

/// Width heuristic `σ = d_max/√(2M)`; 1 with fewer than two centers.
pub fn width_heuristic(centers: &[Vec<f64>]) -> f64 {
    heuristic_width(max_distance(centers), centers.len())
}

/// The largest distance between two of `points` (0 with fewer than two).
fn max_distance(points: &[Vec<f64>]) -> f64 {
    let mut dmax: f64 = 0.0;
    for (i, a) in points.iter().enumerate() {
        for b in points.iter().skip(i + 1) {
            dmax = dmax.max(dist2(a, b).sqrt());
        }
    }
    dmax
}

/// `d_max/√(2M)`, or 1 when there is no spread to scale.
fn heuristic_width(dmax: f64, m: usize) -> f64 {
    if m < 1 || dmax <= 0.0 {
        1.0
    } else {
        dmax / (2.0 * m as f64).sqrt()
    }
}

/// Fits `m` k-means centers, the width heuristic and least-squares weights (bias, no linear term).
pub fn fit(x: &[Vec<f64>], y: &[f64], m: usize, seed: u64) -> Result<Rbf64, TrainError> {
    fit_selecting(x, y, m, seed, CenterSelection::Kmeans)
}

/// [`fit`] with the centers placed by `select`.
pub fn fit_selecting(
    x: &[Vec<f64>],
    y: &[f64],
    m: usize,
    seed: u64,
    select: CenterSelection,
) -> Result<Rbf64, TrainError> {
    let (xm, xs) = mean_std(x);
    let scale: Vec<f64> = xs.iter().map(|s| 1.0 / s.max(1e-300)).collect();
    let z = normalise_rows(x, &xm, &scale);
    let (centers, sigma) = match select {
        CenterSelection::Kmeans => {
            let centers = kmeans(&z, m, seed);
            let sigma = width_heuristic(&centers);
            (centers, sigma)
        }
        CenterSelection::Ols => {
            let candidates: Vec<Vec<f64>> = crate::ols::candidate_rows(z.len())
                .into_iter()
                .filter_map(|i| z.get(i).cloned())
                .collect();
            let sigma = heuristic_width(max_distance(&candidates), m.max(1));
            let picked = crate::ols::select(&z, y, m, sigma);
            let centers = picked.iter().filter_map(|&i| z.get(i).cloned()).collect();
            (centers, sigma)
        }
    };
    let gamma = vec![1.0 / (2.0 * sigma * sigma); centers.len()];
    let phi = design(&z, false, &centers, &gamma);
    let w = least_squares(&phi, y)?;
    let (bias, _, weights) = split_weights(&w, 0);
    Ok(Rbf64 {
        linear: vec![0.0; xm.len()],
        offset: xm,
        scale,
        centers,
        gamma,
        weights,
        bias,
        masks: Vec::new(),
        kinds: Vec::new(),
    })
}

/// The memory of a fit of `mse` (and of `gradient`'s starting point): the standardised rows, the
/// candidates' Gaussians over every row with `--select ols`, and the least-squares solve.
pub(crate) fn memory(s: &crate::budget::Shape, select: CenterSelection) -> f64 {
    let (m, mf) = (s.samples, s.samples as f64);
    let centers = s.centers.unwrap_or(crate::method::DEFAULT_CENTERS);
    let select = match select {
        CenterSelection::Kmeans => 0.0,
        // Every candidate's Gaussian over every row.
        CenterSelection::Ols => 8.0 * mf * m.min(crate::ols::MAX_CANDIDATES) as f64 + 8.0 * mf,
    };
    crate::budget::rows_of(m, s.features) + select + crate::budget::lsq(m, centers)
}

crate::layer! {
    /// The `mse` method, with its own options: keys of the fit spec and (with the `cli` feature)
    /// flags, unset for the default.
    #[derive(Clone, Debug, Default, PartialEq, Deserialize)]
    #[cfg_attr(feature = "cli", derive(clap::Args))]
    #[serde(rename_all = "kebab-case")]
    pub struct Mse {
        /// Center selection of mse: kmeans (default) or ols (orthogonal least squares forward
        /// selection).
        #[cfg_attr(feature = "cli", arg(long))]
        pub select: Option<String>,
    }
}

impl Mse {
    /// How the centers are placed [default: k-means].
    pub fn select(&self) -> Result<CenterSelection, TrainError> {
        self.select
            .as_deref()
            .map_or(Ok(CenterSelection::Kmeans), str::parse)
    }
}

/// The centers asked for, or the default.
fn centers(opts: &crate::method::Shared<'_>) -> usize {
    opts.centers.unwrap_or(crate::method::DEFAULT_CENTERS)
}

impl crate::method::FitMethod for Mse {
    fn name(&self) -> &'static str {
        "mse"
    }

    fn about(&self) -> &'static str {
        "the seed papers' traditional RBF, centers by k-means or orthogonal least squares \
         (--select ols), one heuristic width, least squares"
    }

    fn centers_bound(&self) -> &'static crate::options::Bound {
        &crate::options::CENTERS
    }

    fn check_settings(&self) -> Result<(), TrainError> {
        self.select().map(|_| ())
    }

    fn check(&self, opts: &crate::method::Shared<'_>) -> Result<(), TrainError> {
        self.check_settings()?;
        crate::options::CENTERS
            .check_count(centers(opts), " with --method mse")
            .map(|_| ())
    }

    fn min_samples(&self, opts: &crate::method::Shared<'_>) -> usize {
        2 * centers(opts) + 2
    }

    fn memory(&self, s: &crate::budget::Shape) -> f64 {
        memory(s, self.select().unwrap_or_default())
    }

    fn fit(
        &self,
        set: &mut crate::method::TrainingSet,
        opts: &crate::method::Shared<'_>,
        _progress: &dyn crate::progress::Progress,
    ) -> Result<crate::method::MethodFit, TrainError> {
        let m = centers(opts);
        let select = self.select()?;
        let rbf = fit_selecting(&set.x, &set.y, m, opts.seed, select)?;
        if rbf.centers.len() < m {
            set.warnings.push(format!(
                "{} of the {m} centers asked for: every further candidate was a \
                 combination of those chosen, or the error was used up",
                rbf.centers.len()
            ));
        }
        Ok(crate::method::MethodFit {
            rbf,
            width: None,
            details: crate::method::MethodDetails {
                select: Some(select),
                ..Default::default()
            },
        })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// A knee and a ripple on a ramp, over two features.
    fn case() -> (Vec<Vec<f64>>, Vec<f64>) {
        let x: Vec<Vec<f64>> = (0..200)
            .map(|i| {
                let t = -20.0 + 0.4 * i as f64;
                vec![t, (i as f64 * 0.07).sin()]
            })
            .collect();
        let y = x
            .iter()
            .map(|r| 0.02 * r[0] + 0.4 * (-(r[0] - 30.0).powi(2) / 20.0).exp() + 0.05 * r[1])
            .collect();
        (x, y)
    }

    fn train_rms(f: &Rbf64, x: &[Vec<f64>], y: &[f64]) -> f64 {
        let s: f64 = x.iter().zip(y).map(|(r, v)| (f.eval(r) - v).powi(2)).sum();
        (s / y.len() as f64).sqrt()
    }

    #[test]
    fn ols_training_error_falls_with_every_center_and_beats_kmeans() {
        let (x, y) = case();
        let mut last = f64::INFINITY;
        for m in [2, 4, 8, 16] {
            let f = fit_selecting(&x, &y, m, 1, CenterSelection::Ols).unwrap();
            assert_eq!(f.centers.len(), m);
            let rms = train_rms(&f, &x, &y);
            // Nested models would never rise; a new width per M allows a little.
            assert!(rms <= last * 1.05, "m={m}: {rms} after {last}");
            last = rms;
        }
        // Placed where the error is, 8 OLS centers leave less than 8 k-means centers.
        let o = fit_selecting(&x, &y, 8, 1, CenterSelection::Ols).unwrap();
        let k = fit_selecting(&x, &y, 8, 1, CenterSelection::Kmeans).unwrap();
        assert!(train_rms(&o, &x, &y) < train_rms(&k, &x, &y));
    }

    #[test]
    fn selection_names_parse() {
        assert_eq!(
            "ols".parse::<CenterSelection>().unwrap(),
            CenterSelection::Ols
        );
        assert!("k-means".parse::<CenterSelection>().is_err());
    }
}
