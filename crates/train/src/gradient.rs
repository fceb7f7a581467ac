//! RBF trained by gradient descent on the squared error, with the IFOG paper's update rules for the
//! weights W, the centers c and the widths σ.
//!
//! Why: it is the second seed paper's method. It starts from the `mse` solution (k-means centers,
//! heuristic width, least-squares weights) and descends on `E = ½·mean((y − f)²)` with, for
//! `φ_j = exp(−‖z − c_j‖²/(2σ_j²))` and error `e = y − f`:
//! `Δw_j = η_w·mean(e·φ_j)`, `Δc_j = η_c·mean(e·w_j·φ_j·(z − c_j)/σ_j²)`,
//! `Δσ_j = η_σ·mean(e·w_j·φ_j·‖z − c_j‖²/σ_j³)`, bias with `η_w`. Iterations are bounded; a step that
//! increases the error halves the learning rates (so it cannot diverge).

use crate::error::TrainError;
use crate::progress::{Progress, Silent, Unit};
use crate::rbf64::Rbf64;
use serde::Deserialize;

/// Fits by gradient descent from the `mse` starting point; `iterations` full-batch steps at most.
pub fn fit(
    x: &[Vec<f64>],
    y: &[f64],
    m: usize,
    seed: u64,
    iterations: usize,
) -> Result<Rbf64, TrainError> {
    fit_with_progress(x, y, m, seed, iterations, &Silent)
}

/// [`fit`], reporting each iteration to `progress` (on an unaveraged run each is a pass over
/// millions of rows, and the whole fit takes minutes).
pub fn fit_with_progress(
    x: &[Vec<f64>],
    y: &[f64],
    m: usize,
    seed: u64,
    iterations: usize,
    progress: &dyn Progress,
) -> Result<Rbf64, TrainError> {
    let mut rbf = crate::mse::fit(x, y, m, seed)?;
    let z: Vec<Vec<f64>> = x.iter().map(|r| rbf.normalise(r)).collect();
    let n = z.len().max(1) as f64;
    let ym = y.iter().sum::<f64>() / n;
    let ys = (y.iter().map(|v| (v - ym) * (v - ym)).sum::<f64>() / n)
        .sqrt()
        .max(1e-300);
    let mut sigma: Vec<f64> = rbf.gamma.iter().map(|g| (0.5 / g).sqrt()).collect();
    let mut eta = 0.5;
    let k = rbf.centers.len();
    let loss = |rbf: &Rbf64| {
        z.iter()
            .zip(y)
            .map(|(zr, yv)| {
                let e = (yv - eval_z(rbf, zr)) / ys;
                e * e
            })
            .sum::<f64>()
            / (2.0 * n)
    };
    let mut current = loss(&rbf);
    progress.start("gradient descent", iterations as u64, Unit::Iterations);
    for it in 0..iterations {
        progress.set(it as u64);
        let mut gw = vec![0.0; k];
        let mut gb = 0.0;
        let mut gc = vec![vec![0.0; z.first().map_or(0, Vec::len)]; k];
        let mut gs = vec![0.0; k];
        for (zr, yv) in z.iter().zip(y) {
            let e = (yv - eval_z(&rbf, zr)) / ys;
            gb += e / n;
            for j in 0..k {
                let (Some(c), Some(s), Some(w)) =
                    (rbf.centers.get(j), sigma.get(j), rbf.weights.get(j))
                else {
                    continue;
                };
                let d2 = crate::kmeans::dist2(zr, c);
                let phi = (-d2 / (2.0 * s * s)).exp();
                if let Some(g) = gw.get_mut(j) {
                    *g += e * phi / n;
                }
                let common = e * (w / ys) * phi / n;
                if let Some(gcj) = gc.get_mut(j) {
                    for ((g, zk), ck) in gcj.iter_mut().zip(zr).zip(c) {
                        *g += common * (zk - ck) / (s * s);
                    }
                }
                if let Some(g) = gs.get_mut(j) {
                    *g += common * d2 / (s * s * s);
                }
            }
        }
        let mut next = rbf.clone();
        let mut next_sigma = sigma.clone();
        next.bias += eta * gb * ys;
        for j in 0..k {
            if let (Some(w), Some(g)) = (next.weights.get_mut(j), gw.get(j)) {
                *w += eta * g * ys;
            }
            if let (Some(c), Some(g)) = (next.centers.get_mut(j), gc.get(j)) {
                for (cv, gv) in c.iter_mut().zip(g) {
                    *cv += 0.1 * eta * gv;
                }
            }
            if let (Some(s), Some(g)) = (next_sigma.get_mut(j), gs.get(j)) {
                *s = (*s + 0.1 * eta * g).max(0.05);
            }
        }
        next.gamma = next_sigma.iter().map(|s| 0.5 / (s * s)).collect();
        let l = loss(&next);
        if l <= current {
            rbf = next;
            sigma = next_sigma;
            current = l;
        } else {
            eta *= 0.5;
            if eta < 1e-8 {
                break;
            }
        }
    }
    progress.finish();
    Ok(rbf)
}

fn eval_z(rbf: &Rbf64, z: &[f64]) -> f64 {
    let mut acc = rbf.bias;
    for ((c, g), w) in rbf.centers.iter().zip(&rbf.gamma).zip(&rbf.weights) {
        acc += w * (-g * crate::kmeans::dist2(z, c)).exp();
    }
    acc
}

/// Gradient-descent iterations when `--iterations` is not given.
pub const DEFAULT_ITERATIONS: usize = 2000;

crate::layer! {
    /// The `gradient` method, with its own options: keys of the fit spec and (with the `cli`
    /// feature) flags, unset for the default.
    #[derive(Clone, Debug, Default, PartialEq, Deserialize)]
    #[cfg_attr(feature = "cli", derive(clap::Args))]
    #[serde(rename_all = "kebab-case")]
    pub struct Gradient {
        /// Gradient-descent iterations.
        #[cfg_attr(
            feature = "cli",
            arg(long, allow_negative_numbers = true, value_parser = crate::options::ITERATIONS.count_parser())
        )]
        pub iterations: Option<usize>,
    }
}

impl Gradient {
    /// The iterations [default: [`DEFAULT_ITERATIONS`]].
    pub fn iterations(&self) -> usize {
        self.iterations.unwrap_or(DEFAULT_ITERATIONS)
    }
}

/// The centers asked for, or the default.
fn centers(opts: &crate::method::Shared<'_>) -> usize {
    opts.centers.unwrap_or(crate::method::DEFAULT_CENTERS)
}

impl crate::method::FitMethod for Gradient {
    fn name(&self) -> &'static str {
        "gradient"
    }

    fn about(&self) -> &'static str {
        "weights, centers and widths adapted by gradient descent from the mse solution"
    }

    fn centers_bound(&self) -> &'static crate::options::Bound {
        &crate::options::CENTERS
    }

    fn check_settings(&self) -> Result<(), TrainError> {
        crate::options::ITERATIONS.check_count(self.iterations(), "")?;
        Ok(())
    }

    fn check(&self, opts: &crate::method::Shared<'_>) -> Result<(), TrainError> {
        crate::options::CENTERS.check_count(centers(opts), " with --method gradient")?;
        self.check_settings()
    }

    fn min_samples(&self, opts: &crate::method::Shared<'_>) -> usize {
        2 * centers(opts) + 2
    }

    /// The `mse` starting point (k-means centers), and the normalised rows of the descent.
    fn memory(&self, s: &crate::budget::Shape) -> f64 {
        crate::mse::memory(s, crate::mse::CenterSelection::Kmeans)
            + crate::budget::rows_of(s.samples, s.features)
    }

    fn fit(
        &self,
        set: &mut crate::method::TrainingSet,
        opts: &crate::method::Shared<'_>,
        progress: &dyn Progress,
    ) -> Result<crate::method::MethodFit, TrainError> {
        let rbf = fit_with_progress(
            &set.x,
            &set.y,
            centers(opts),
            opts.seed,
            self.iterations(),
            progress,
        )?;
        progress.start("measuring the fit", 0, Unit::Iterations);
        Ok(crate::method::MethodFit {
            rbf,
            width: None,
            details: crate::method::MethodDetails::default(),
        })
    }
}
