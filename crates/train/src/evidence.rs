//! MacKay's evidence framework for a linear-in-parameters model whose weights fall into groups, each
//! with its own prior precision α: the one implementation under the trainer's `bayes` method (groups:
//! bias, linear terms, Gaussians) and the discovery loop's candidate scoring (a candidate column gets
//! its own group, so a useless one is switched off by α → ∞ and its Δ log evidence goes to 0 instead
//! of diluting the prior of the base's weights; the iteration can be warm-started).
//!
//! For `A = βΦᵀΦ + diag(α)`: `γ_g = Σ_{i∈g}(1 − α_g·(A⁻¹)_ii)`, `α_g ← γ_g/‖w_g‖²`,
//! `β ← (N − γ)/‖y − Φw‖²`, iterated until α and β change less than [`Settings`]' tolerances; group 0
//! (the bias) has a fixed, nearly flat prior that cancels in evidence differences. The log evidence
//! is `N/2·ln β − β·E_D − ½ ln|A| − N/2·ln 2π + Σ_g (|g|/2·ln α_g − α_g·E_W,g)`.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Hyperparameters and evidence of one converged fit (in the target's units).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Evidence {
    /// Prior precision of the Gaussian weights.
    pub alpha: f64,
    /// Prior precision of the linear weights (0 when there is no linear term).
    pub alpha_linear: f64,
    /// Noise precision (1/variance of the fitted samples, i.e. of the bin means).
    pub beta: f64,
    /// Effective number of parameters, including the bias.
    pub gamma: f64,
    /// Log evidence ln p(y | α, β, model).
    pub log_evidence: f64,
    /// Iterations until convergence.
    pub iterations: usize,
}

/// Precision of the (nearly flat) prior on group 0.
const FLAT: f64 = 1e-8;
/// Largest α: a group at this value is switched off.
const ALPHA_MAX: f64 = 1e12;

/// Convergence settings.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Most iterations.
    pub max_iterations: usize,
    /// Relative change of every α below which it has converged.
    pub alpha_tolerance: f64,
    /// Relative change of β below which it has converged.
    pub beta_tolerance: f64,
    /// Count a group whose α passed 1e10 (switched off) as converged.
    pub switched_off_converged: bool,
}

impl Settings {
    /// What the trainer uses. A group switched off counts as converged: its α would otherwise
    /// climb by a few per cent an iteration from 1e10 to [`ALPHA_MAX`] while every other group sat
    /// still, which changes the log evidence by `O(βλ/α)` — nothing — and took 28 % of every
    /// iteration of a production line's calibration (measured on 8 units of `tcomp simulate
    /// --preset qma --units 1000`: 1.7 % of the fits ran 200 iterations or more, and held 43 % of
    /// all iterations, two thirds of them in fits with a group switched off). Those are small
    /// fits: 60 units' `tcomp calibrate` went 34.7 → 33.8 s, with the same fleet report.
    pub const TRAINER: Settings = Settings {
        max_iterations: 2000,
        alpha_tolerance: 1e-6,
        beta_tolerance: 1e-6,
        switched_off_converged: true,
    };
    /// What candidate scoring uses (tighter on β, stops once a useless column is switched off).
    pub const SCORING: Settings = Settings {
        max_iterations: 1000,
        alpha_tolerance: 1e-6,
        beta_tolerance: 1e-7,
        switched_off_converged: true,
    };
}

/// A converged fit.
#[derive(Clone, Debug)]
pub struct GroupFit {
    /// Posterior mean weights.
    pub w: DVector<f64>,
    /// α per group (group 0 fixed).
    pub alpha: Vec<f64>,
    /// Noise precision.
    pub beta: f64,
    /// Effective number of parameters.
    pub gamma: f64,
    /// Log evidence (of `y` as given: normalised units).
    pub log_evidence: f64,
    /// Iterations run.
    pub iterations: usize,
}

/// Fits `y ≈ Φw` with weight groups `group[j]` (0 = bias, fixed prior), starting from `start`
/// (α per group and β) when given, with the scoring settings.
pub fn fit(
    phi: &DMatrix<f64>,
    y: &DVector<f64>,
    group: &[usize],
    start: Option<(&[f64], f64)>,
) -> Option<GroupFit> {
    fit_with(phi, y, group, start, &Settings::SCORING)
}

/// [`fit`] with explicit convergence settings. A group with no columns keeps its starting α.
pub fn fit_with(
    phi: &DMatrix<f64>,
    y: &DVector<f64>,
    group: &[usize],
    start: Option<(&[f64], f64)>,
    settings: &Settings,
) -> Option<GroupFit> {
    let normal = Normal::new(phi, y, group, BLOCKED_MIN);
    iterate(&normal, start, settings)
}

/// The MacKay fixed point on prepared normal equations.
fn iterate(normal: &Normal, start: Option<(&[f64], f64)>, settings: &Settings) -> Option<GroupFit> {
    let n = normal.n;
    let ng = normal.members.len();
    let mut alpha = vec![1.0; ng];
    let mut beta = 10.0;
    if let Some((a0, b0)) = start {
        for (a, s) in alpha.iter_mut().zip(a0) {
            *a = *s;
        }
        beta = b0;
    }
    if let Some(a) = alpha.first_mut() {
        *a = FLAT;
    }
    let mut iterations = 0;
    for it in 0..settings.max_iterations {
        iterations = it + 1;
        let s = normal.solve(&alpha, beta, false)?;
        let gam = s.gamma(&normal.members, &alpha);
        let mut next = alpha.clone();
        for k in 1..ng {
            if normal.members[k] > 0 {
                next[k] = (gam[k] / s.ww[k].max(1e-300)).clamp(1e-10, ALPHA_MAX);
            }
        }
        let gamma_total: f64 = gam.iter().sum();
        let next_beta = ((n - gamma_total).max(1e-3) / (2.0 * s.ed)).clamp(1e-10, 1e14);
        let rel = |a: f64, b: f64| ((a - b) / b.abs().max(1e-300)).abs();
        let done = (1..ng).all(|k| {
            rel(next[k], alpha[k]) < settings.alpha_tolerance
                || (settings.switched_off_converged && next[k] > 1e10)
        }) && rel(next_beta, beta) < settings.beta_tolerance;
        alpha = next;
        beta = next_beta;
        if done {
            break;
        }
    }
    let s = normal.solve(&alpha, beta, true)?;
    let gam = s.gamma(&normal.members, &alpha);
    let mut log_ev = 0.5 * n * beta.ln()
        - beta * s.ed
        - 0.5 * s.logdet
        - 0.5 * n * (2.0 * std::f64::consts::PI).ln();
    for ((&size, &a), &ww) in normal.members.iter().zip(&alpha).zip(&s.ww).skip(1) {
        if size > 0 {
            log_ev += 0.5 * size as f64 * a.ln() - 0.5 * a * ww;
        }
    }
    log_ev.is_finite().then_some(GroupFit {
        w: s.w,
        alpha,
        beta,
        gamma: gam.iter().sum(),
        log_evidence: log_ev,
        iterations,
    })
}

/// What one solve of `A w = βΦᵀy` gives the iteration.
struct Solved {
    /// Posterior mean weights (original column order).
    w: DVector<f64>,
    /// Per group: `Σ_{i∈g} (A⁻¹)_ii`.
    trace: Vec<f64>,
    /// Per group: `‖w_g‖²`.
    ww: Vec<f64>,
    /// `E_D = ½‖y − Φw‖²`.
    ed: f64,
    /// `ln |A|`.
    logdet: f64,
}

impl Solved {
    /// `γ_g = |g| − α_g·tr_g(A⁻¹)`.
    fn gamma(&self, members: &[usize], alpha: &[f64]) -> Vec<f64> {
        members
            .iter()
            .zip(alpha)
            .zip(&self.trace)
            .map(|((&m, &a), &t)| m as f64 - a * t)
            .collect()
    }
}

/// The normal equations of `y ≈ Φw`, prepared once so that each MacKay iteration is cheap.
///
/// Why two forms: the trainer's designs have one large group (the Gaussians, M columns) beside a few
/// small ones (bias, linear terms, candidate columns; p columns). Then the Gram block of the large
/// group is eigen-decomposed once, `ΨᵀΨ = VΛVᵀ`; for any (α, β) the Hessian's large block is
/// diagonal in that basis (`βλ_i + α_big`) and the small block is handled by its Schur complement
/// `S = βBᵀB + D_α − β²·C diag(1/(βλ+α_big)) Cᵀ` with `C = BᵀΨV`. An iteration costs O(M·p² + p³)
/// instead of a Cholesky factorisation and an inverse of the whole m × m Hessian. Without a large
/// group the direct form is used.
struct Normal {
    n: f64,
    yy: f64,
    /// Columns per group.
    members: Vec<usize>,
    form: Form,
}

enum Form {
    /// `G = ΦᵀΦ`, `b = Φᵀy`; a Cholesky factorisation per solve.
    Direct {
        g: DMatrix<f64>,
        b: DVector<f64>,
        group: Vec<usize>,
    },
    /// Large group in the eigenbasis of its Gram block, small columns by the Schur complement.
    Blocked(Box<Blocked>),
}

struct Blocked {
    /// Group of the large block.
    big: usize,
    /// Original column index of each small column, and its group.
    small: Vec<(usize, usize)>,
    /// Original column index of each large column.
    large: Vec<usize>,
    /// `BᵀB` (p × p).
    gpp: DMatrix<f64>,
    /// `C = BᵀΨV` (p × M).
    c: DMatrix<f64>,
    /// Eigenvalues λ of `ΨᵀΨ` (clamped at 0).
    lambda: DVector<f64>,
    /// Eigenvectors V of `ΨᵀΨ`.
    v: DMatrix<f64>,
    /// `Bᵀy`.
    bp: DVector<f64>,
    /// `VᵀΨᵀy`.
    bt: DVector<f64>,
}

/// Smallest large group worth the eigen-decomposition.
const BLOCKED_MIN: usize = 4;

impl Normal {
    /// Prepares the normal equations; the blocked form when the largest group (other than the
    /// bias) has at least `blocked_min` columns.
    fn new(phi: &DMatrix<f64>, y: &DVector<f64>, group: &[usize], blocked_min: usize) -> Self {
        let m = phi.ncols();
        let gr = |i: usize| group.get(i).copied().unwrap_or(0);
        let ng = (0..m).map(gr).max().unwrap_or(0) + 1;
        let mut members = vec![0usize; ng];
        for i in 0..m {
            if let Some(c) = members.get_mut(gr(i)) {
                *c += 1;
            }
        }
        let big = (1..ng).max_by_key(|&k| (members[k], std::cmp::Reverse(k)));
        let yy = y.dot(y);
        // ΦᵀΦ through the blocked matrix product (matrixmultiply's kernels: several times faster
        // than column dot products at these sizes).
        let g = phi.transpose() * phi;
        let b = phi.tr_mul(y);
        let form = match big {
            Some(big) if members[big] >= blocked_min => {
                let large: Vec<usize> = (0..m).filter(|&i| gr(i) == big).collect();
                let small: Vec<(usize, usize)> = (0..m)
                    .filter(|&i| gr(i) != big)
                    .map(|i| (i, gr(i)))
                    .collect();
                let (p, mm) = (small.len(), large.len());
                let gmm = DMatrix::from_fn(mm, mm, |a, c| g[(large[a], large[c])]);
                let eig = gmm.symmetric_eigen();
                let v = eig.eigenvectors;
                let lambda = eig.eigenvalues.map(|l| l.max(0.0));
                let gpm = DMatrix::from_fn(p, mm, |a, c| g[(small[a].0, large[c])]);
                let bm = DVector::from_fn(mm, |a, _| b[large[a]]);
                Form::Blocked(Box::new(Blocked {
                    big,
                    gpp: DMatrix::from_fn(p, p, |a, c| g[(small[a].0, small[c].0)]),
                    c: gpm * &v,
                    bp: DVector::from_fn(p, |a, _| b[small[a].0]),
                    bt: v.tr_mul(&bm),
                    lambda,
                    v,
                    small,
                    large,
                }))
            }
            _ => Form::Direct {
                g,
                b,
                group: (0..m).map(gr).collect(),
            },
        };
        Self {
            n: phi.nrows() as f64,
            yy,
            members,
            form,
        }
    }

    /// Solves for (α, β); `weights`: also return the weights in the original column order (the
    /// blocked form otherwise skips rotating the large block's weights back).
    fn solve(&self, alpha: &[f64], beta: f64, weights: bool) -> Option<Solved> {
        let ng = self.members.len();
        let al = |k: usize| alpha.get(k).copied().unwrap_or(1.0);
        match &self.form {
            Form::Direct { g, b, group } => {
                let m = g.ncols();
                let mut a = g * beta;
                for i in 0..m {
                    a[(i, i)] += al(group[i]);
                }
                let chol = a.cholesky()?;
                let ainv = chol.inverse();
                let w = &ainv * b * beta;
                let ed = (0.5 * (self.yy - 2.0 * w.dot(b) + w.dot(&(g * &w)))).max(1e-300);
                let logdet: f64 = chol.l().diagonal().iter().map(|d| 2.0 * d.ln()).sum();
                let mut trace = vec![0.0; ng];
                let mut ww = vec![0.0; ng];
                for i in 0..m {
                    trace[group[i]] += ainv[(i, i)];
                    ww[group[i]] += w[i] * w[i];
                }
                Some(Solved {
                    w,
                    trace,
                    ww,
                    ed,
                    logdet,
                })
            }
            Form::Blocked(bl) => bl.solve(self.yy, ng, alpha, beta, weights),
        }
    }
}

impl Blocked {
    #[allow(clippy::needless_range_loop)] // index loops over small dense blocks read clearest
    fn solve(&self, yy: f64, ng: usize, alpha: &[f64], beta: f64, weights: bool) -> Option<Solved> {
        let al = |k: usize| alpha.get(k).copied().unwrap_or(1.0);
        let (p, mm) = (self.small.len(), self.large.len());
        let a_big = al(self.big);
        let b2 = beta * beta;
        // The large block is diagonal in the eigenbasis: k_i = βλ_i + α_big.
        let kinv: Vec<f64> = self
            .lambda
            .iter()
            .map(|l| 1.0 / (beta * l + a_big))
            .collect();
        // Schur complement S = βBᵀB + D − β² C K⁻¹ Cᵀ (row-major p × p) and its right-hand side.
        // The sums over i run in the outer loop, down each column of C (contiguous), into one
        // accumulator per entry: the same products added in the same order as an inner loop
        // over i, so the same bits, without striding across C for every entry.
        let c = &self.c;
        let cs = c.as_slice();
        let mut acc = vec![0.0; p * p];
        let mut acc_r = vec![0.0; p];
        for i in 0..mm {
            let (k, bt) = (kinv[i], self.bt[i]);
            let ci = &cs[i * p..i * p + p];
            for a in 0..p {
                let ca = ci[a];
                let row = &mut acc[a * p..a * p + a + 1];
                for (r, cb) in row.iter_mut().zip(ci) {
                    *r += ca * cb * k;
                }
                acc_r[a] += ca * k * bt;
            }
        }
        let mut s = vec![0.0; p * p];
        let mut rhs = vec![0.0; p];
        for a in 0..p {
            for b in 0..=a {
                let v = beta * self.gpp[(a, b)] - b2 * acc[a * p + b];
                s[a * p + b] = v;
                s[b * p + a] = v;
            }
            s[a * p + a] += al(self.small[a].1);
            rhs[a] = beta * self.bp[a] - b2 * acc_r[a];
        }
        let (sinv, logdet_s) = spd_inverse(s, p)?;
        let wp: Vec<f64> = (0..p)
            .map(|a| (0..p).map(|b| sinv[a * p + b] * rhs[b]).sum())
            .collect();
        // Large weights in the eigenbasis: u = K⁻¹ β (bt − Cᵀ w_p); the trace of the large block of
        // A⁻¹: Σ 1/k_i + β² Σ_i (c_iᵀ S⁻¹ c_i)/k_i² (c_i = column i of C).
        let mut u = vec![0.0; mm];
        let mut ctw = vec![0.0; mm];
        let mut tr_big = 0.0;
        for i in 0..mm {
            let ci = &cs[i * p..i * p + p];
            let cw: f64 = ci.iter().zip(&wp).map(|(x, w)| x * w).sum();
            ctw[i] = cw;
            u[i] = kinv[i] * beta * (self.bt[i] - cw);
            let mut q = 0.0;
            for a in 0..p {
                let row = &sinv[a * p..a * p + p];
                q += ci[a] * row.iter().zip(ci).map(|(x, y)| x * y).sum::<f64>();
            }
            tr_big += kinv[i] + b2 * kinv[i] * kinv[i] * q;
        }
        let mut trace = vec![0.0; ng];
        let mut ww = vec![0.0; ng];
        if let Some(t) = trace.get_mut(self.big) {
            *t = tr_big;
        }
        if let Some(t) = ww.get_mut(self.big) {
            *t = u.iter().map(|x| x * x).sum();
        }
        let mut w = DVector::zeros(if weights { p + mm } else { 0 });
        for (a, &(col, k)) in self.small.iter().enumerate() {
            trace[k] += sinv[a * p + a];
            ww[k] += wp[a] * wp[a];
            if weights {
                w[col] = wp[a];
            }
        }
        if weights {
            let wm = &self.v * DVector::from_column_slice(&u);
            for (i, &col) in self.large.iter().enumerate() {
                w[col] = wm[i];
            }
        }
        // E_D = ½(yᵀy − 2wᵀb + wᵀGw), in the block form.
        let wb: f64 = wp
            .iter()
            .zip(self.bp.iter())
            .map(|(x, y)| x * y)
            .sum::<f64>()
            + u.iter()
                .zip(self.bt.iter())
                .map(|(x, y)| x * y)
                .sum::<f64>();
        let mut wgw = 0.0;
        for a in 0..p {
            for b in 0..p {
                wgw += wp[a] * self.gpp[(a, b)] * wp[b];
            }
        }
        for i in 0..mm {
            wgw += 2.0 * ctw[i] * u[i] + self.lambda[i] * u[i] * u[i];
        }
        let ed = (0.5 * (yy - 2.0 * wb + wgw)).max(1e-300);
        let logdet = logdet_s - kinv.iter().map(|k| k.ln()).sum::<f64>();
        Some(Solved {
            w,
            trace,
            ww,
            ed,
            logdet,
        })
    }
}

/// Posterior mean weights on the rows `keep` of `Φ`, `y`, with fixed hyperparameters.
pub fn weights_on(
    phi: &DMatrix<f64>,
    y: &DVector<f64>,
    group: &[usize],
    alpha: &[f64],
    beta: f64,
    keep: &[usize],
) -> Option<DVector<f64>> {
    let sub = phi.select_rows(keep);
    let ys = y.select_rows(keep);
    let mut a = sub.tr_mul(&sub) * beta;
    for i in 0..a.ncols() {
        let k = group.get(i).copied().unwrap_or(0);
        a[(i, i)] += alpha.get(k).copied().unwrap_or(1.0);
    }
    let rhs = sub.tr_mul(&ys) * beta;
    a.cholesky().map(|c| c.solve(&rhs))
}

/// The inverse of the symmetric positive definite `p × p` matrix `s` (row-major) and its log
/// determinant, by Cholesky `S = LLᵀ` in place (lower triangle) and `S⁻¹ = L⁻ᵀL⁻¹`; `None` when
/// `s` is not positive definite.
#[allow(clippy::needless_range_loop)] // index loops over small dense blocks read clearest
fn spd_inverse(s: Vec<f64>, p: usize) -> Option<(Vec<f64>, f64)> {
    let mut l = s;
    let mut logdet_s = 0.0;
    for j in 0..p {
        let mut d = l[j * p + j];
        for k in 0..j {
            d -= l[j * p + k] * l[j * p + k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return None;
        }
        let dj = d.sqrt();
        logdet_s += 2.0 * dj.ln();
        l[j * p + j] = dj;
        for i in j + 1..p {
            let mut v = l[i * p + j];
            for k in 0..j {
                v -= l[i * p + k] * l[j * p + k];
            }
            l[i * p + j] = v / dj;
        }
    }
    // L⁻¹ (lower triangular), then S⁻¹ = L⁻ᵀL⁻¹.
    let mut li = vec![0.0; p * p];
    for j in 0..p {
        li[j * p + j] = 1.0 / l[j * p + j];
        for i in j + 1..p {
            let mut v = 0.0;
            for k in j..i {
                v -= l[i * p + k] * li[k * p + j];
            }
            li[i * p + j] = v / l[i * p + i];
        }
    }
    let mut sinv = vec![0.0; p * p];
    for a in 0..p {
        for b in 0..=a {
            let mut v = 0.0;
            for k in a..p {
                v += li[k * p + a] * li[k * p + b];
            }
            sinv[a * p + b] = v;
            sinv[b * p + a] = v;
        }
    }
    Some((sinv, logdet_s))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn useful_column_gains_evidence_useless_does_not() {
        let n = 300;
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.05).sin()).collect();
        let u: Vec<f64> = (0..n).map(|i| (i as f64 * 0.377).cos()).collect();
        let noise: Vec<f64> = (0..n)
            .map(|i| ((i * 7919 % 101) as f64 / 101.0 - 0.5) * 0.2)
            .collect();
        let y = DVector::from_iterator(n, (0..n).map(|i| 2.0 * x[i] + noise[i]));
        let base = DMatrix::from_fn(n, 1, |_, _| 1.0);
        let with_x = DMatrix::from_fn(n, 2, |i, j| if j == 0 { 1.0 } else { x[i] });
        let with_u = DMatrix::from_fn(n, 3, |i, j| match j {
            0 => 1.0,
            1 => x[i],
            _ => u[i],
        });
        let b = fit(&base, &y, &[0], None).unwrap();
        let bx = fit(&with_x, &y, &[0, 1], None).unwrap();
        let bu = fit(&with_u, &y, &[0, 1, 2], None).unwrap();
        assert!(bx.log_evidence - b.log_evidence > 50.0);
        assert!((bu.log_evidence - bx.log_evidence).abs() < 3.0);
    }

    /// The blocked (eigenbasis + Schur complement) form reaches the same fixed point as the direct
    /// Cholesky form: same weights, hyperparameters, γ and log evidence to rounding, on a design
    /// shaped like the trainer's (bias, linear terms, Gaussians) and one like the discovery loop's
    /// (plus a candidate column in its own group).
    #[test]
    fn blocked_form_matches_direct_form() {
        let n = 150;
        let x: Vec<[f64; 2]> = (0..n)
            .map(|i| [(i as f64 * 0.041).sin() * 1.7, (i as f64 * 0.013).cos()])
            .collect();
        let centers: Vec<[f64; 2]> = (0..12)
            .map(|j| [(j as f64 * 1.3).sin() * 1.5, (j as f64 * 0.7).cos()])
            .collect();
        let noise = |i: usize| ((i * 7919 % 101) as f64 / 101.0 - 0.5) * 0.1;
        let y = DVector::from_fn(n, |i, _| {
            (x[i][0] * 1.3).sin() + 0.4 * x[i][1] * x[i][1] + noise(i)
        });
        for candidate in [false, true] {
            let m = 1 + 2 + centers.len() + usize::from(candidate);
            let phi = DMatrix::from_fn(n, m, |i, j| match j {
                0 => 1.0,
                1 | 2 => x[i][j - 1],
                j if j < 3 + centers.len() => {
                    let c = centers[j - 3];
                    let d2 = (x[i][0] - c[0]).powi(2) + (x[i][1] - c[1]).powi(2);
                    (-d2 / 0.8).exp()
                }
                _ => x[i][0] * x[i][1],
            });
            let group: Vec<usize> = (0..m)
                .map(|j| match j {
                    0 => 0,
                    1 | 2 => 1,
                    j if j < 3 + centers.len() => 2,
                    _ => 3,
                })
                .collect();
            let s = Settings::TRAINER;
            let start = [1e-8, 1.0, 1.0, 1.0];
            let direct = iterate(
                &Normal::new(&phi, &y, &group, usize::MAX),
                Some((&start, 10.0)),
                &s,
            )
            .unwrap();
            let normal = Normal::new(&phi, &y, &group, BLOCKED_MIN);
            assert!(matches!(normal.form, Form::Blocked(_)));
            let blocked = iterate(&normal, Some((&start, 10.0)), &s).unwrap();
            let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-12);
            assert!(rel(blocked.log_evidence, direct.log_evidence) < 1e-8);
            assert!(rel(blocked.beta, direct.beta) < 1e-6);
            assert!(rel(blocked.gamma, direct.gamma) < 1e-6);
            for (a, b) in blocked.alpha.iter().zip(&direct.alpha) {
                assert!(rel(*a, *b) < 1e-5, "alpha {a} vs {b}");
            }
            for (a, b) in blocked.w.iter().zip(direct.w.iter()) {
                assert!((a - b).abs() < 1e-7 * (1.0 + b.abs()), "w {a} vs {b}");
            }
            assert_eq!(blocked.iterations, direct.iterations);
        }
    }
}
