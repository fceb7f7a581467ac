//! The RBF in f64 as the fitters produce it, its design matrix, and its conversion to the core's f32
//! [`Rbf`].
//!
//! Why: every method (bayes, mse, gradient, poly3) ends in the same shape, the one the core
//! evaluates: `f(x) = bias + Σ linear_k·z_k + Σ_j w_j·exp(−γ_j‖z − c_j‖²)` with
//! `z_k = (x_k − offset_k)·scale_k`. Fitting happens in f64; only the final coefficients are rounded.

use crate::error::TrainError;
use crate::features::F;
use nalgebra::DMatrix;
use tcomp_core::point::Point;
use tcomp_core::rbf::Center;
pub use tcomp_core::rbf::{KIND_CUBE, KIND_GAUSSIAN, KIND_RAMP, KIND_SQUARE, KIND_STEP};
use tcomp_core::{HOST_CENTERS, Rbf};

/// Centers per host model.
pub const C: usize = HOST_CENTERS;

/// An RBF network in f64.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rbf64 {
    /// Per-feature offset (raw units).
    pub offset: Vec<f64>,
    /// Per-feature scale (1/(std·length scale)).
    pub scale: Vec<f64>,
    /// Centers in normalised units.
    pub centers: Vec<Vec<f64>>,
    /// `γ = 1/(2σ²)` per Gaussian; a step's slope `1/s` (see [`Rbf64::kinds`]).
    pub gamma: Vec<f64>,
    /// Center weights.
    pub weights: Vec<f64>,
    /// Linear term on `z` (empty or zeros when unused).
    pub linear: Vec<f64>,
    /// Output offset.
    pub bias: f64,
    /// Feature mask per center (bit k: feature k enters its distance; the center's coordinates
    /// outside it are zero), or empty: every center spans every feature. An additive model's
    /// groups (see [`crate::bayes`]), carried to the core's [`Rbf::masks`].
    pub masks: Vec<u8>,
    /// Kind per center ([`KIND_GAUSSIAN`], [`KIND_STEP`], [`KIND_SQUARE`], [`KIND_CUBE`] or
    /// [`KIND_RAMP`]), or empty: every center is a Gaussian. With `uj = γj·Σ_{k∈Mj}(zk − cjk)`, a
    /// step is `S(uj)`, `S(u) = 1/(1 + e^(−u))` (it rises over a width `1/γj` around `cj` and
    /// holds its level on both sides), a square `uj²`, a cube `uj³` and a ramp
    /// `clamp(uj, −1, 1)` (straight over `cj ± 1/γj`, level beyond; the core's [`Rbf::kinds`]).
    pub kinds: Vec<u8>,
}

/// The logistic `1/(1 + e^(−u))`, computed without overflow on either side.
pub fn logistic(u: f64) -> f64 {
    if u >= 0.0 {
        1.0 / (1.0 + (-u).exp())
    } else {
        let e = u.exp();
        e / (1.0 + e)
    }
}

/// The ramp `clamp(u, −1, 1)` (NaN gives 0, as the core's does).
pub fn ramp(u: f64) -> f64 {
    if u.is_nan() { 0.0 } else { u.clamp(-1.0, 1.0) }
}

/// A step's argument `γ·Σ_{k∈mask}(zk − ck)`.
pub fn step_arg(z: &[f64], c: &[f64], slope: f64, mask: Option<u8>) -> f64 {
    let s: f64 = z
        .iter()
        .zip(c)
        .enumerate()
        .filter(|(k, _)| mask.is_none_or(|m| *k < 8 && m >> k & 1 == 1))
        .map(|(_, (a, b))| a - b)
        .sum();
    slope * s
}

impl Rbf64 {
    /// Normalised features.
    pub fn normalise(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(&self.offset)
            .zip(&self.scale)
            .map(|((x, o), s)| (x - o) * s)
            .collect()
    }

    /// The output for raw features `x`.
    pub fn eval(&self, x: &[f64]) -> f64 {
        let z = self.normalise(x);
        let mut acc = self.bias;
        for (l, zk) in self.linear.iter().zip(&z) {
            acc += l * zk;
        }
        for (j, w) in self.weights.iter().enumerate() {
            acc += w * self.basis(j, &z);
        }
        acc
    }

    /// Center `j`'s basis function at normalised features `z`: its Gaussian over its masked
    /// features, or its step (0 for a center that does not exist).
    pub fn basis(&self, j: usize, z: &[f64]) -> f64 {
        let (Some(c), Some(g)) = (self.centers.get(j), self.gamma.get(j)) else {
            return 0.0;
        };
        let mask = self.masks.get(j).copied();
        match self.kind(j) {
            KIND_STEP => logistic(step_arg(z, c, *g, mask)),
            KIND_SQUARE => step_arg(z, c, *g, mask).powi(2),
            KIND_CUBE => step_arg(z, c, *g, mask).powi(3),
            KIND_RAMP => ramp(step_arg(z, c, *g, mask)),
            _ => (-g * masked_dist2(z, c, mask)).exp(),
        }
    }

    /// Center `j`'s kind ([`KIND_GAUSSIAN`] when the model has no kinds).
    pub fn kind(&self, j: usize) -> u8 {
        self.kinds.get(j).copied().unwrap_or(KIND_GAUSSIAN)
    }

    /// The coefficients the core evaluates (f32).
    pub fn to_core(&self) -> Result<Rbf<C, F>, TrainError> {
        let nf = self.offset.len();
        if nf == 0 || nf > F || self.centers.len() > C {
            return Err(self.over_capacity());
        }
        let p =
            |v: &[f64]| Point::<F>::from_slice(&v.iter().map(|&x| x as f32).collect::<Vec<_>>());
        let mut rbf = Rbf::<C, F> {
            n_features: nf as u8,
            offset: p(&self.offset),
            scale: p(&self.scale),
            linear: p(&self.linear),
            bias: self.bias as f32,
            ..Rbf::default()
        };
        for (j, ((c, g), w)) in self
            .centers
            .iter()
            .zip(&self.gamma)
            .zip(&self.weights)
            .enumerate()
        {
            let kind = self.kind(j);
            let center = if kind == KIND_GAUSSIAN {
                Center::from_natural(c, *g, *w)
            } else {
                // γ·Σ_{k∈M}(zk − ck) = Σ ak·zk + b, ak = γ on the mask, b = −γ·Σ ck.
                let mask = self.masks.get(j).copied();
                let on = |k: usize| mask.is_none_or(|m| k < 8 && m >> k & 1 == 1);
                let a: Vec<f64> = (0..c.len()).map(|k| if on(k) { *g } else { 0.0 }).collect();
                let b = -g * (0..c.len()).filter(|&k| on(k)).map(|k| c[k]).sum::<f64>();
                if kind == KIND_STEP {
                    Center::step_from_natural(&a, b, *w)
                } else {
                    Center::power_from_natural(&a, b, *w)
                }
            };
            rbf.centers.push(center).map_err(|_| self.over_capacity())?;
        }
        for m in &self.masks {
            rbf.masks.push(*m).map_err(|_| self.over_capacity())?;
        }
        for k in &self.kinds {
            rbf.kinds.push(*k).map_err(|_| self.over_capacity())?;
        }
        Ok(rbf)
    }

    fn over_capacity(&self) -> TrainError {
        TrainError::OverCapacity {
            features: self.offset.len(),
            max_features: F,
            centers: self.centers.len(),
            max_centers: C,
        }
    }
}

/// `‖z − c‖²` over the features of `mask` (every feature when `None`).
pub fn masked_dist2(z: &[f64], c: &[f64], mask: Option<u8>) -> f64 {
    match mask {
        None => crate::kmeans::dist2(z, c),
        Some(m) => z
            .iter()
            .zip(c)
            .enumerate()
            .filter(|(k, _)| *k < 8 && m >> k & 1 == 1)
            .map(|(_, (a, b))| (a - b) * (a - b))
            .sum(),
    }
}

/// Per-feature mean and standard deviation of the rows of `x`.
pub fn mean_std(x: &[Vec<f64>]) -> (Vec<f64>, Vec<f64>) {
    let d = x.first().map_or(0, Vec::len);
    let n = x.len().max(1) as f64;
    let mut mean = vec![0.0; d];
    for r in x {
        for (m, v) in mean.iter_mut().zip(r) {
            *m += v / n;
        }
    }
    let mut var = vec![0.0; d];
    for r in x {
        for ((s, v), m) in var.iter_mut().zip(r).zip(&mean) {
            *s += (v - m) * (v - m) / n;
        }
    }
    (mean, var.into_iter().map(f64::sqrt).collect())
}

/// Rows of `x` normalised by `offset` and `scale`.
pub fn normalise_rows(x: &[Vec<f64>], offset: &[f64], scale: &[f64]) -> Vec<Vec<f64>> {
    x.iter()
        .map(|r| {
            r.iter()
                .zip(offset)
                .zip(scale)
                .map(|((v, o), s)| (v - o) * s)
                .collect()
        })
        .collect()
}

/// Design matrix: a column of ones, the `z` columns when `linear`, then one Gaussian per center.
pub fn design(z: &[Vec<f64>], linear: bool, centers: &[Vec<f64>], gamma: &[f64]) -> DMatrix<f64> {
    design_scaled(z, linear, None, centers, gamma)
}

/// As [`design`], with the linear columns multiplied by `lin_scale` (per feature) when given — so
/// that the linear weights' prior does not depend on the length scales folded into `z`.
pub fn design_scaled(
    z: &[Vec<f64>],
    linear: bool,
    lin_scale: Option<&[f64]>,
    centers: &[Vec<f64>],
    gamma: &[f64],
) -> DMatrix<f64> {
    let d = z.first().map_or(0, Vec::len);
    let nl = if linear { d } else { 0 };
    let m = 1 + nl + centers.len();
    DMatrix::from_fn(z.len(), m, |i, j| {
        let Some(r) = z.get(i) else { return 0.0 };
        if j == 0 {
            1.0
        } else if j <= nl {
            let f = lin_scale.and_then(|l| l.get(j - 1)).copied().unwrap_or(1.0);
            r.get(j - 1).copied().unwrap_or(0.0) * f
        } else {
            let k = j - 1 - nl;
            match (centers.get(k), gamma.get(k)) {
                (Some(c), Some(g)) => (-g * crate::kmeans::dist2(r, c)).exp(),
                _ => 0.0,
            }
        }
    })
}

/// Least squares `min ‖Φw − y‖` by SVD (rank-revealing, so collinear columns do not blow up).
pub fn least_squares(phi: &DMatrix<f64>, y: &[f64]) -> Result<Vec<f64>, TrainError> {
    let yv = nalgebra::DVector::from_column_slice(y);
    let svd = phi.clone().svd(true, true);
    let eps = svd.singular_values.max() * 1e-10;
    let w = svd.solve(&yv, eps).map_err(TrainError::LeastSquares)?;
    Ok(w.iter().copied().collect())
}

/// Splits a weight vector laid out as [`design`] into (bias, linear, center weights).
pub fn split_weights(w: &[f64], nl: usize) -> (f64, Vec<f64>, Vec<f64>) {
    let bias = w.first().copied().unwrap_or(0.0);
    let lin = w.get(1..1 + nl).unwrap_or(&[]).to_vec();
    let rest = w.get(1 + nl..).unwrap_or(&[]).to_vec();
    (bias, lin, rest)
}
