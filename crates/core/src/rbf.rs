//! The Gaussian RBF evaluator: `f(x) = w0 + Σk lk·zk + Σj wj·exp(−γj·‖z − cj‖²)`.
//!
//! Features are normalised per feature, `zk = (xk − offsetk)·scalek`; the trainer folds per-feature
//! length scales into `scale`, so a feature that matters little does not distort distances. Each center
//! has its own `γj = 1/(2σj²)`. The optional linear term `l` (zero when unused) lets a model
//! extrapolate along a trend where Gaussians alone would fade to `w0`.
//!
//! # Stored form
//! A center is stored *expanded*, in the eval units of [`crate::fastexp`] (`g = γ·16·log2 e`):
//! `uj = pj + gj·‖z‖² + Σk qjk·zk` with `pj = gj·‖cj‖²` and `qj = −2gj·cj`, so that
//! `exp(−γj‖z − cj‖²) = 2^(−uj/16)`. Per center that is one multiply-add per feature plus one, instead
//! of a subtraction, a multiply-add and a scaling, and the record `[p, q…, g, w]` is contiguous: on a
//! Cortex-M4F a 32 × 4 evaluation takes about 1,000 instructions, 1,600 with masks (see
//! BENCHMARKS.md).
//! [`Center::from_natural`] and [`Center::to_natural`] convert from and to `(c, γ, w)`. The price is
//! rounding in `‖z‖² + ‖c‖²` instead of `‖z − c‖²`: an error in the exponent of about
//! `γ·(‖z‖² + ‖c‖²)·2.4e-7`, i.e. a relative error below 1e-5 for normalised features within ±2.
//!
//! # Additive structure
//! A model may be a sum of terms over groups of features (a thermal bias plus a term in a supply
//! voltage, say): then each center carries a feature mask ([`Rbf::masks`]), and its distance runs
//! over the masked features only, `uj = pj + gj·Σ_{k∈Mj} zk² + Σ_{k∈Mj} qjk·zk` (`qjk = 0` outside
//! `Mj`). A Gaussian over the thermal group then does not fade where the supply voltage goes
//! somewhere the training run never took it. Without masks (blob formats 1 and 2, or a model whose
//! centers all span every feature) the evaluation is the plain one above, bit for bit; with masks
//! the masked sum runs in the same feature order, so a full mask gives the same bits too.
//!
//! # Steps
//! An additive model may also hold logistic steps ([`Rbf::kinds`], blob format 4): a center of kind
//! [`KIND_STEP`] contributes `wj·S(uj)` with `S(u) = 1/(1 + e^(−u))` and `uj = pj + Σ_{k∈Mj} qjk·zk`
//! (eval units; `gj` is zero and unused). Why: a Gaussian fades back to zero on both sides, so a bias
//! that changes level at some temperature and stays there (a knee, a mode change, a smooth step)
//! needs Gaussians to hold the level all along its flat part, and beyond the trained range they
//! fade where the physics stays put. A step holds its level on both sides by construction, and a
//! wide one bends like a cubic inside the range without diverging outside it. `S` is computed from
//! the same fast exponential, `e = 2^(−|u|/16)`, as `1/(1 + e)` for `u ≥ 0` and `e/(1 + e)` below:
//! one exponential and one division, and never an exponential of a positive argument.
//!
//! Kinds [`KIND_SQUARE`] and [`KIND_CUBE`] are the powers `wj·uj²` and `wj·uj³` of the same
//! `uj = pj + Σ qjk·zk`, in natural units: the low-order polynomial in one feature that a thermal
//! bias mostly is (the cubic PX4 and ArduPilot fly), as terms of an additive model beside
//! Gaussians and steps in other features, without spending a feature slot of the program on each
//! power. Like the Gaussians they see the features clamped to the trained range
//! ([`Rbf::eval_split`]), so they hold their edge values outside it as the clamped cubic does.
//!
//! Kind [`KIND_RAMP`] (blob format 5) is the saturating ramp `wj·clamp(uj, −1, 1)` of the same
//! natural-units `uj`: a level that changes linearly between two temperatures and holds on both
//! sides (a knee, a saturation — the language's `clamp` as a term). Why beside the step: a
//! logistic rises over its whole width with soft shoulders, so a change of slope that ends at a
//! sharp corner (a clamped ramp 16 °C wide, measured in `tcomp-train`'s `additive_fits`) costs a
//! step plus Gaussians at each corner, and the Gaussians fade beyond the range. A ramp holds
//! its levels outside `[−1, 1]` as a step does, so it extrapolates flat, never along a slope as
//! a hinge would. Two comparisons, no exponential.
//!
//! Summation order is fixed and no fused multiply-add is used: host and Cortex-M4F give identical
//! bits. A center whose exponent exceeds [`EXP_CUTOFF`] contributes less than `2e-9·|w|` and is skipped.

use crate::fastexp::{EVAL_CUTOFF, EVAL_UNITS_PER_NAT, EXP_CUTOFF, exp2_16_neg};

/// [`Rbf::kinds`]: a Gaussian center (the only kind before blob format 4).
pub const KIND_GAUSSIAN: u8 = 0;
/// [`Rbf::kinds`]: a logistic step along the center's masked features (see the module doc).
pub const KIND_STEP: u8 = 1;
/// [`Rbf::kinds`]: the square `u²` of `u = p + Σ qk·zk` (natural units; see the module doc).
pub const KIND_SQUARE: u8 = 2;
/// [`Rbf::kinds`]: the cube `u³` of `u = p + Σ qk·zk` (natural units; see the module doc).
pub const KIND_CUBE: u8 = 3;
/// [`Rbf::kinds`]: the ramp `clamp(u, −1, 1)` of `u = p + Σ qk·zk` (natural units; see the
/// module doc), blob format 5.
pub const KIND_RAMP: u8 = 4;
/// The largest kind this build evaluates.
pub const KIND_LAST: u8 = KIND_RAMP;
use crate::point::Point;
use heapless::Vec;
use serde::{Deserialize, Serialize};

/// One Gaussian center in the evaluator's expanded form (see the module doc).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Center<const F: usize> {
    /// `g·‖c‖²`.
    pub p: f32,
    /// `−2g·c`.
    pub q: Point<F>,
    /// `g = γ·16·log2(e)`, `γ = 1/(2σ²)` in normalised units.
    pub g: f32,
    /// Output weight.
    pub w: f32,
}

impl<const F: usize> Center<F> {
    /// From a center position `c` (normalised units), `γ = 1/(2σ²)` and weight `w`; computed in f64.
    pub fn from_natural(c: &[f64], gamma: f64, w: f64) -> Self {
        let g = gamma * EVAL_UNITS_PER_NAT as f64;
        let mut q = [0.0f32; F];
        let mut cc = 0.0f64;
        for (qk, ck) in q.iter_mut().zip(c) {
            // `+ 0.0` turns −0 into +0, so unused features are plain zeros on the wire.
            *qk = (-2.0 * g * ck) as f32 + 0.0;
            cc += ck * ck;
        }
        Self {
            p: (g * cc) as f32,
            q: Point(q),
            g: g as f32,
            w: w as f32,
        }
    }

    /// Back to `(c, γ, w)` (up to f32 rounding).
    pub fn to_natural(&self) -> (Point<F>, f32, f32) {
        let mut c = [0.0f32; F];
        for (ck, qk) in c.iter_mut().zip(&self.q.0) {
            *ck = -*qk / (2.0 * self.g);
        }
        (Point(c), self.g / EVAL_UNITS_PER_NAT, self.w)
    }

    /// A logistic step `w·S(b + Σk ak·zk)` (natural units; `a` zero outside the step's features),
    /// computed in f64 and stored in eval units with `g = 0`.
    pub fn step_from_natural(a: &[f64], b: f64, w: f64) -> Self {
        let e = EVAL_UNITS_PER_NAT as f64;
        let mut q = [0.0f32; F];
        for (qk, ak) in q.iter_mut().zip(a) {
            *qk = (e * ak) as f32 + 0.0;
        }
        Self {
            p: (e * b) as f32,
            q: Point(q),
            g: 0.0,
            w: w as f32,
        }
    }

    /// A power `w·(b + Σk ak·zk)^n` (kind [`KIND_SQUARE`] or [`KIND_CUBE`]) or a ramp
    /// `w·clamp(b + Σk ak·zk, −1, 1)` ([`KIND_RAMP`]), natural units, `g = 0`.
    pub fn power_from_natural(a: &[f64], b: f64, w: f64) -> Self {
        let mut q = [0.0f32; F];
        for (qk, ak) in q.iter_mut().zip(a) {
            *qk = *ak as f32 + 0.0;
        }
        Self {
            p: b as f32,
            q: Point(q),
            g: 0.0,
            w: w as f32,
        }
    }

    /// σ of this Gaussian in normalised units.
    pub fn sigma(&self) -> f32 {
        libm::sqrtf(EVAL_UNITS_PER_NAT / (2.0 * self.g))
    }
}

/// RBF coefficients for up to `C` centers and `F` features.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Rbf<const C: usize, const F: usize> {
    /// Number of features used (≤ F); entries past it are zero everywhere.
    pub n_features: u8,
    /// Per-feature offset subtracted before scaling (raw units).
    pub offset: Point<F>,
    /// Per-feature scale applied after the offset (1/(std·length scale)).
    pub scale: Point<F>,
    /// The Gaussians.
    pub centers: Vec<Center<F>, C>,
    /// Linear term on the normalised features (zero when unused).
    pub linear: Point<F>,
    /// Output offset `w0`.
    pub bias: f32,
    /// Feature mask of each center (bit k: feature k enters its distance), or empty: every center
    /// spans every feature. Stored after the rest of the blob, from format 3 on (see
    /// [`crate::blob`]), so the derived layout of this struct is the one formats 1 and 2 have.
    #[serde(skip)]
    pub masks: Vec<u8, C>,
    /// Kind of each center ([`KIND_GAUSSIAN`], [`KIND_STEP`], [`KIND_SQUARE`], [`KIND_CUBE`] or
    /// [`KIND_RAMP`]), or empty: every center is a Gaussian. Only with [`Rbf::masks`]; stored
    /// after them, from format 4 on (ramps from format 5).
    #[serde(skip)]
    pub kinds: Vec<u8, C>,
}

/// `zk²` per feature.
#[inline(always)]
fn squares<const F: usize>(z: &[f32; F]) -> [f32; F] {
    let mut sq = [0.0f32; F];
    for (s, zk) in sq.iter_mut().zip(z) {
        *s = *zk * *zk;
    }
    sq
}

/// One Gaussian over the features of `mask` (`sq`: the squares of `z`).
#[inline(always)]
fn masked_gaussian<const F: usize>(c: &Center<F>, mask: u8, sq: &[f32; F], z: &[f32; F]) -> f32 {
    let mut zz = 0.0f32;
    for (k, s) in sq.iter().enumerate() {
        if mask >> k & 1 == 1 {
            zz += *s;
        }
    }
    let mut u = c.p + c.g * zz;
    for (qk, zk) in c.q.0.iter().zip(z) {
        u += *qk * *zk;
    }
    if u < EVAL_CUTOFF {
        c.w * exp2_16_neg(u)
    } else {
        0.0
    }
}

/// `p + Σ qk·zk`, in feature order.
#[inline(always)]
fn affine<const F: usize>(c: &Center<F>, z: &[f32; F]) -> f32 {
    let mut u = c.p;
    for (qk, zk) in c.q.0.iter().zip(z) {
        u += *qk * *zk;
    }
    u
}

/// One logistic step, `w·S(p + Σ qk·zk)` (`q` is zero outside its mask). Past the cutoff the
/// exponential is flushed to zero, so `S` is exactly 0 or 1 there; a NaN exponent gives 0.
#[inline(always)]
fn step<const F: usize>(c: &Center<F>, z: &[f32; F]) -> f32 {
    let u = affine(c, z);
    let a = if u < 0.0 { -u } else { u };
    let e = if a < EVAL_CUTOFF { exp2_16_neg(a) } else { 0.0 };
    let s = if u >= 0.0 {
        1.0 / (1.0 + e)
    } else if u < 0.0 {
        e / (1.0 + e)
    } else {
        0.0
    };
    c.w * s
}

/// `clamp(u, −1, 1)`, with a NaN argument giving 0 as a step's does. Two comparisons: no
/// exponential, no division.
#[inline(always)]
fn ramp(u: f32) -> f32 {
    if u >= 1.0 {
        1.0
    } else if u <= -1.0 {
        -1.0
    } else if u > -1.0 {
        u
    } else {
        0.0
    }
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
            linear: Point::default(),
            bias: 0.0,
            masks: Vec::new(),
            kinds: Vec::new(),
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
        let mut zz = 0.0f32;
        for (l, zk) in self.linear.0.iter().zip(&z) {
            acc += *l * *zk;
            zz += *zk * *zk;
        }
        acc + self.gaussians(&z, zz)
    }

    /// The model output with the Gaussians evaluated at `x_gauss` and the linear term at `x_linear`
    /// (the compensator clamps the two differently). `eval_split(x, x)` equals `eval(x)` bit for bit.
    pub fn eval_split(&self, x_gauss: &[f32; F], x_linear: &[f32; F]) -> f32 {
        let zl = self.normalise(x_linear);
        let zg = self.normalise(x_gauss);
        let mut acc = self.bias;
        let mut zz = 0.0f32;
        for ((l, zlk), zgk) in self.linear.0.iter().zip(&zl).zip(&zg) {
            acc += *l * *zlk;
            zz += *zgk * *zgk;
        }
        acc + self.gaussians(&zg, zz)
    }

    /// `Σj wj·exp(−γj‖z − cj‖²)` in the expanded form, `zz = ‖z‖²`.
    #[inline(always)]
    fn gaussians(&self, z: &[f32; F], zz: f32) -> f32 {
        if !self.kinds.is_empty() {
            return self.mixed_centers(z);
        }
        if !self.masks.is_empty() {
            return self.masked_gaussians(z);
        }
        let mut acc = 0.0f32;
        for c in &self.centers {
            let mut u = c.p + c.g * zz;
            for (qk, zk) in c.q.0.iter().zip(z) {
                u += *qk * *zk;
            }
            if u < EVAL_CUTOFF {
                acc += c.w * exp2_16_neg(u);
            }
        }
        acc
    }

    /// The Gaussians of an additive model: each center's squared distance over its masked features
    /// only, summed in feature order as `‖z‖²` is (so a full mask gives the plain sum's bits).
    #[inline(always)]
    fn masked_gaussians(&self, z: &[f32; F]) -> f32 {
        let sq = squares(z);
        let mut acc = 0.0f32;
        for (c, &mask) in self.centers.iter().zip(&self.masks) {
            acc += masked_gaussian(c, mask, &sq, z);
        }
        acc
    }

    /// The centers of an additive model with steps: each by its kind, in order (a model whose
    /// kinds are all Gaussian gives [`Self::masked_gaussians`]' bits).
    #[inline(always)]
    fn mixed_centers(&self, z: &[f32; F]) -> f32 {
        let sq = squares(z);
        let mut acc = 0.0f32;
        for ((c, &mask), &kind) in self.centers.iter().zip(&self.masks).zip(&self.kinds) {
            acc += match kind {
                KIND_STEP => step(c, z),
                KIND_SQUARE => {
                    let u = affine(c, z);
                    c.w * (u * u)
                }
                KIND_CUBE => {
                    let u = affine(c, z);
                    c.w * (u * u * u)
                }
                KIND_RAMP => c.w * ramp(affine(c, z)),
                _ => masked_gaussian(c, mask, &sq, z),
            };
        }
        acc
    }

    /// Whether feature `k` enters center `j`'s distance.
    pub fn spans(&self, j: usize, k: usize) -> bool {
        self.masks.get(j).is_none_or(|m| m >> k & 1 == 1)
    }

    /// Cutoff of the basis in natural units (for documentation and tools).
    pub const fn cutoff() -> f32 {
        EXP_CUTOFF
    }

    /// Checks sizes and values; a decoded blob passes this before it may fly.
    pub fn validate(&self) -> Result<(), RbfError> {
        let nf = self.n_features as usize;
        if nf == 0 || nf > F {
            return Err(RbfError::Inconsistent("rbf.n_features"));
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
        for c in &self.centers {
            if !(c.p.is_finite() && c.g.is_finite() && c.q.is_finite()) {
                return Err(RbfError::NonFinite("rbf.centers"));
            }
            if !c.w.is_finite() {
                return Err(RbfError::NonFinite("rbf.centers.w"));
            }
        }
        if !self.kinds.is_empty() {
            if self.kinds.len() != self.centers.len() || self.masks.is_empty() {
                return Err(RbfError::Inconsistent(
                    "rbf.kinds: one per center, and only with masks",
                ));
            }
            if self.kinds.iter().any(|k| *k > KIND_LAST) {
                return Err(RbfError::Inconsistent("rbf.kinds: unknown kind"));
            }
        }
        for (j, c) in self.centers.iter().enumerate() {
            if self.kinds.get(j).is_some_and(|k| *k != KIND_GAUSSIAN) {
                if c.g != 0.0 {
                    return Err(RbfError::Inconsistent(
                        "rbf.centers: a step's or a power's g must be 0",
                    ));
                }
            } else if c.g <= 0.0 || c.p < 0.0 {
                return Err(RbfError::Inconsistent(
                    "rbf.centers: g must be > 0 and p >= 0",
                ));
            }
        }
        if !self.masks.is_empty() {
            if self.masks.len() != self.centers.len() {
                return Err(RbfError::Inconsistent("rbf.masks: one per center"));
            }
            // u8 masks: at most 8 features (the host's capacity), and only used ones.
            if nf > 8 {
                return Err(RbfError::Inconsistent("rbf.masks: more than 8 features"));
            }
            let used = if nf >= 8 { u8::MAX } else { (1u8 << nf) - 1 };
            for (c, &m) in self.centers.iter().zip(&self.masks) {
                if m == 0 || m & !used != 0 {
                    return Err(RbfError::Inconsistent(
                        "rbf.masks: a mask must name at least one used feature and no other",
                    ));
                }
                let outside_zero =
                    c.q.0
                        .iter()
                        .enumerate()
                        .all(|(k, q)| m >> k & 1 == 1 || *q == 0.0);
                if !outside_zero {
                    return Err(RbfError::Inconsistent(
                        "rbf.masks: q must be zero outside a center's mask",
                    ));
                }
            }
        }
        // Unused feature slots must be inert: zero scale, so z is zero there whatever the input.
        let unused_inert = |p: &Point<F>| p.0.iter().skip(nf).all(|v| *v == 0.0);
        if !unused_inert(&self.scale)
            || !unused_inert(&self.linear)
            || !self.centers.iter().all(|c| unused_inert(&c.q))
        {
            return Err(RbfError::Inconsistent(
                "rbf: entries past n_features must be zero",
            ));
        }
        Ok(())
    }
}
