//! The Gaussian RBF evaluator: `f(x) = w0 + Σk lk·zk + Σj wj·exp(−γj·‖z − cj‖²)`.
//!
//! Features are normalised per feature, `zk = (xk − offsetk)·scalek`; the trainer folds per-feature
//! length scales into `scale`, so a feature that matters little does not distort distances. Each center
//! has its own `γj = 1/(2σj²)`. The optional linear term `l` (zero when unused) lets a model
//! extrapolate along a trend where Gaussians alone would fade to `w0`.
//!
//! Centers are stored row-major as `[f32; F]` so the inner loop unrolls at compile time. Summation
//! order is fixed and no fused multiply-add is used: host and Cortex-M4F give identical bits.
//! A center whose `γ·d²` exceeds [`EXP_CUTOFF`] contributes less than `2e-9·|w|` and is skipped.

use crate::fastexp::{EXP_CUTOFF, exp_neg};
use crate::point::Point;
use heapless::Vec;
use serde::{Deserialize, Serialize};

/// RBF coefficients for up to `C` centers and `F` features.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Rbf<const C: usize, const F: usize> {
    /// Number of features used (≤ F); entries past it are zero everywhere.
    pub n_features: u8,
    /// Per-feature offset subtracted before scaling (raw units).
    pub offset: Point<F>,
    /// Per-feature scale applied after the offset (1/(std·length scale)).
    pub scale: Point<F>,
    /// Center positions in normalised units.
    pub centers: Vec<Point<F>, C>,
    /// Per-center `γ = 1/(2σ²)` in normalised units.
    pub gamma: Vec<f32, C>,
    /// Per-center output weights.
    pub weights: Vec<f32, C>,
    /// Linear term on the normalised features (zero when unused).
    pub linear: Point<F>,
    /// Output offset `w0`.
    pub bias: f32,
}

/// Why RBF coefficients are unusable; the `&str` names the field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RbfError {
    /// A value is NaN or infinite.
    NonFinite(&'static str),
    /// Sizes disagree, or a value is out of its domain.
    Inconsistent(&'static str),
}

impl<const C: usize, const F: usize> Default for Rbf<C, F> {
    fn default() -> Self {
        Self {
            n_features: 0,
            offset: Point::default(),
            scale: Point::default(),
            centers: Vec::new(),
            gamma: Vec::new(),
            weights: Vec::new(),
            linear: Point::default(),
            bias: 0.0,
        }
    }
}

impl<const C: usize, const F: usize> Rbf<C, F> {
    /// Normalised features `z` of raw features `x` (entries past `n_features` are zero).
    #[inline]
    pub fn normalise(&self, x: &[f32; F]) -> [f32; F] {
        let mut z = [0.0f32; F];
        for (((zk, xk), ok), sk) in z.iter_mut().zip(x).zip(&self.offset.0).zip(&self.scale.0) {
            *zk = (*xk - *ok) * *sk;
        }
        z
    }

    /// The model output for raw features `x`.
    pub fn eval(&self, x: &[f32; F]) -> f32 {
        let z = self.normalise(x);
        let mut acc = self.bias;
        for (l, zk) in self.linear.0.iter().zip(&z) {
            acc += *l * *zk;
        }
        for ((c, g), w) in self.centers.iter().zip(&self.gamma).zip(&self.weights) {
            let mut d2 = 0.0f32;
            for (zk, ck) in z.iter().zip(&c.0) {
                let t = *zk - *ck;
                d2 += t * t;
            }
            let a = d2 * *g;
            if a < EXP_CUTOFF {
                acc += *w * exp_neg(a);
            }
        }
        acc
    }

    /// Checks sizes and values; a decoded blob passes this before it may fly.
    pub fn validate(&self) -> Result<(), RbfError> {
        let nf = self.n_features as usize;
        if nf == 0 || nf > F {
            return Err(RbfError::Inconsistent("rbf.n_features"));
        }
        if self.gamma.len() != self.centers.len() || self.weights.len() != self.centers.len() {
            return Err(RbfError::Inconsistent("rbf.centers/gamma/weights lengths"));
        }
        let finite = |p: &Point<F>| p.is_finite();
        if !finite(&self.offset) {
            return Err(RbfError::NonFinite("rbf.offset"));
        }
        if !finite(&self.scale) {
            return Err(RbfError::NonFinite("rbf.scale"));
        }
        if !finite(&self.linear) {
            return Err(RbfError::NonFinite("rbf.linear"));
        }
        if !self.bias.is_finite() {
            return Err(RbfError::NonFinite("rbf.bias"));
        }
        if !self.centers.iter().all(finite) {
            return Err(RbfError::NonFinite("rbf.centers"));
        }
        if !self.weights.iter().all(|w| w.is_finite()) {
            return Err(RbfError::NonFinite("rbf.weights"));
        }
        if !self.gamma.iter().all(|g| g.is_finite()) {
            return Err(RbfError::NonFinite("rbf.gamma"));
        }
        if !self.gamma.iter().all(|g| *g > 0.0) {
            return Err(RbfError::Inconsistent("rbf.gamma must be > 0"));
        }
        // Unused feature slots must be inert: zero scale, so z is zero there whatever the input.
        let unused_inert = |p: &Point<F>| p.0.iter().skip(nf).all(|v| *v == 0.0);
        if !unused_inert(&self.scale)
            || !unused_inert(&self.linear)
            || !self.centers.iter().all(unused_inert)
        {
            return Err(RbfError::Inconsistent(
                "rbf: entries past n_features must be zero",
            ));
        }
        Ok(())
    }
}
