//! Properties of the Bayesian search that hold whatever model it picks: the Occam margin's
//! inflation at hand-computed values, equivariance under a change of the target's unit and offset
//! and of the features' origin and scale (the fit is made in standardised units and brought back),
//! a flat model where there is no effect, and the options honoured.
//! Written to kill what `cargo mutants` found untested in `bayes.rs`.
#![allow(clippy::unwrap_used, missing_docs)]

use tcomp_train::bayes::{
    Basis, BayesFit, BayesOptions, MAX_MARGIN_INFLATION, fit, fit_offering_cubic, margin_inflation,
};

fn noise(i: usize) -> f64 {
    ((i * 7919 + 13) % 1009) as f64 / 1009.0 - 0.5
}

/// Rows `[T, r]` over a swing of temperature with a slower second feature, and their cubic columns.
fn rows() -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let x: Vec<Vec<f64>> = (0..160)
        .map(|i| {
            let t = -20.0 + 60.0 * (i as f64 / 160.0) + 2.0 * (i as f64 * 0.3).sin();
            vec![t, (i as f64 * 0.05).cos()]
        })
        .collect();
    let p = x
        .iter()
        .map(|r| vec![r[0] * r[0], r[0] * r[0] * r[0]])
        .collect();
    (x, p)
}

fn bump(r: &[f64]) -> f64 {
    0.5 * (-(r[0] - 15.0) * (r[0] - 15.0) / 30.0).exp() + 0.01 * r[0] + 0.2 * r[1]
}

/// A cubic in the first feature (the PX4 shape) and a linear effect of the second.
fn cubic(r: &[f64]) -> f64 {
    0.02 * r[0] - 4e-4 * r[0] * r[0] + 6e-6 * r[0] * r[0] * r[0] + 0.1 * r[1]
}

fn targets(x: &[Vec<f64>], f: impl Fn(&[f64]) -> f64, k: f64, c: f64) -> Vec<f64> {
    x.iter()
        .enumerate()
        .map(|(i, r)| k * (f(r) + 0.01 * noise(i)) + c)
        .collect()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-12)
}

#[test]
fn margin_inflation_at_hand_computed_correlations() {
    // ρ = Σ r_i r_{i+1} / Σ r_i²; the inflation is (1 + ρ)/(1 − ρ), between 1 and the cap.
    assert!((margin_inflation(&[1.0, 0.5]) - 1.4 / 0.6).abs() < 1e-12);
    assert!(
        (margin_inflation(&[2.0, 1.0, 0.0, 1.0]) - (1.0 + 2.0 / 6.0) / (1.0 - 2.0 / 6.0)).abs()
            < 1e-12
    );
    assert_eq!(margin_inflation(&[1.0, 1.0]), MAX_MARGIN_INFLATION);
    assert_eq!(margin_inflation(&[1.0, -1.0, 1.0]), 1.0);
    assert_eq!(margin_inflation(&[0.0, 0.0, 0.0]), 1.0);
    assert_eq!(margin_inflation(&[]), 1.0);
    assert_eq!(margin_inflation(&[3.0]), 1.0);
}

fn same_structure(a: &BayesFit, b: &BayesFit) {
    assert_eq!(a.basis, b.basis);
    assert_eq!(a.rbf.centers.len(), b.rbf.centers.len());
    assert!(
        (a.width - b.width).abs() <= 1e-12 * a.width.abs(),
        "{} vs {}",
        a.width,
        b.width
    );
    assert_eq!(a.length_scales, b.length_scales);
    assert_eq!(a.evaluated, b.evaluated);
}

fn check_target_units(f: impl Fn(&[f64]) -> f64 + Copy, offer: bool, basis: Basis) {
    let (x, p) = rows();
    let cubic_cols = offer.then_some(p.as_slice());
    let opts = BayesOptions::default();
    let base = fit_offering_cubic(&x, &targets(&x, f, 1.0, 0.0), cubic_cols, &opts).unwrap();
    // Gaussians may be the joint model's or the additive structure's.
    assert!(
        base.basis == basis || (basis == Basis::Gaussians && base.basis == Basis::Additive),
        "{:?}",
        base.basis
    );
    let (k, c) = (250.0, -40.0);
    let y = targets(&x, f, k, c);
    let scaled = fit_offering_cubic(&x, &y, cubic_cols, &opts).unwrap();
    same_structure(&base, &scaled);
    let n = x.len() as f64;
    let (e0, e1) = (&base.evidence, &scaled.evidence);
    assert!(
        rel(e1.beta, e0.beta / (k * k)) < 1e-6,
        "β {} vs {}",
        e1.beta,
        e0.beta
    );
    assert!(rel(e1.alpha, e0.alpha / (k * k)) < 1e-6 || e0.alpha == 0.0 && e1.alpha == 0.0);
    assert!(rel(e1.alpha_linear, e0.alpha_linear / (k * k)) < 1e-6);
    assert!((e1.log_evidence - (e0.log_evidence - n * k.ln())).abs() < 1e-6 * n);
    assert!((e1.gamma - e0.gamma).abs() < 1e-6 * e0.gamma);
    if let (Some(o0), Some(o1)) = (
        base.other_basis_log_evidence,
        scaled.other_basis_log_evidence,
    ) {
        assert!((o1 - (o0 - n * k.ln())).abs() < 1e-6 * n);
    } else {
        assert!(!offer, "the other basis is reported when offered");
    }
    // Same model, in the new unit: f(x) → k·f(x) + c at every row.
    for (r, pr) in x.iter().zip(&p) {
        let row: Vec<f64> = match basis {
            Basis::Cubic => r.iter().chain(pr).copied().collect(),
            Basis::Gaussians | Basis::Additive => r.clone(),
        };
        let (y0, y1) = (base.rbf.eval(&row), scaled.rbf.eval(&row));
        assert!(
            (y1 - (k * y0 + c)).abs() < 1e-6 * k,
            "{y1} vs {}",
            k * y0 + c
        );
    }
    // And it fits: the residual is of the order of the noise (uniform, 0.01 wide: std 0.003).
    let rms = (x
        .iter()
        .zip(&p)
        .zip(&targets(&x, f, 1.0, 0.0))
        .map(|((r, pr), y)| {
            let row: Vec<f64> = match basis {
                Basis::Cubic => r.iter().chain(pr).copied().collect(),
                Basis::Gaussians | Basis::Additive => r.clone(),
            };
            (base.rbf.eval(&row) - y).powi(2)
        })
        .sum::<f64>()
        / n)
        .sqrt();
    assert!(rms < 0.006, "rms {rms}");
}

#[test]
fn a_gaussian_fit_follows_the_targets_unit_and_offset() {
    check_target_units(bump, true, Basis::Gaussians);
}

#[test]
fn a_cubic_fit_follows_the_targets_unit_and_offset() {
    check_target_units(cubic, true, Basis::Cubic);
}

#[test]
fn a_fit_follows_the_features_origin_and_scale() {
    // Features in other units (°F instead of °C, say): the same model of the same physics.
    let (x, _) = rows();
    let y = targets(&x, bump, 1.0, 0.0);
    let base = fit(&x, &y, &BayesOptions::default()).unwrap();
    let moved: Vec<Vec<f64>> = x
        .iter()
        .map(|r| vec![1.8 * r[0] + 32.0, 10.0 * r[1] - 3.0])
        .collect();
    let other = fit(&moved, &y, &BayesOptions::default()).unwrap();
    same_structure(&base, &other);
    assert!(rel(other.evidence.log_evidence, base.evidence.log_evidence) < 1e-6);
    for (r, m) in x.iter().zip(&moved) {
        assert!((base.rbf.eval(r) - other.rbf.eval(m)).abs() < 1e-6);
    }
}

#[test]
fn no_effect_gives_a_flat_model() {
    let (x, _) = rows();
    let y: Vec<f64> = (0..x.len()).map(|i| 3.0 + 0.01 * noise(i)).collect();
    let f = fit(&x, &y, &BayesOptions::default()).unwrap();
    let out: Vec<f64> = x.iter().map(|r| f.rbf.eval(r)).collect();
    let (lo, hi) = out
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
    assert!(hi - lo < 0.002, "the model spans {lo}..{hi}");
    assert!((lo - 3.0).abs() < 0.002 && f.rbf.centers.is_empty());
}

#[test]
fn options_are_honoured() {
    let (x, _) = rows();
    let y = targets(&x, bump, 1.0, 0.0);
    let fixed = fit(
        &x,
        &y,
        &BayesOptions {
            centers: Some(8),
            ..BayesOptions::default()
        },
    )
    .unwrap();
    assert_eq!(fixed.rbf.centers.len(), 8);
    assert!(fixed.evidence.alpha > 0.0);
    let no_linear = fit(
        &x,
        &y,
        &BayesOptions {
            linear: false,
            ..BayesOptions::default()
        },
    )
    .unwrap();
    assert!(no_linear.rbf.linear.iter().all(|l| *l == 0.0));
    assert_eq!(no_linear.evidence.alpha_linear, 0.0);
    assert!(!no_linear.rbf.centers.is_empty());
    let default = fit(&x, &y, &BayesOptions::default()).unwrap();
    assert!(default.rbf.linear.iter().any(|l| *l != 0.0));
    assert!(default.evaluated > 5, "{}", default.evaluated);
    assert!(default.other_basis_log_evidence.is_none());
}

#[test]
fn the_search_visits_at_least_its_fixed_steps() {
    // Two features and 160 rows: the first pass fits the linear term alone (one width) and 4, 8,
    // 16 and 32 centers at four widths each (17); a Gaussian model then walks each length scale
    // (both neighbours of 1 and the far end: 3 each), the width (at least one neighbour), and
    // refits the four other numbers of centers: at least 17 + 6 + 1 + 4 = 28 evidence fits.
    let (x, _) = rows();
    let f = fit(&x, &targets(&x, bump, 1.0, 0.0), &BayesOptions::default()).unwrap();
    assert!(
        matches!(f.basis, Basis::Gaussians | Basis::Additive),
        "{:?}",
        f.basis
    );
    assert!(f.evaluated >= 28, "{} fits", f.evaluated);
}

#[test]
fn a_linear_truth_stays_linear_with_the_cubic_on_offer() {
    // Parsimony orders the bases: the linear term alone, then the cubic, then Gaussians.
    let (x, p) = rows();
    let y = targets(&x, |r| 0.03 * r[0] - 0.2 * r[1], 1.0, 2.0);
    let f = fit_offering_cubic(&x, &y, Some(&p), &BayesOptions::default()).unwrap();
    assert_eq!(f.basis, Basis::Gaussians);
    assert!(f.rbf.centers.is_empty(), "{} centers", f.rbf.centers.len());
    assert!(f.other_basis_log_evidence.is_some());
}

#[test]
fn each_prior_is_reported_for_its_own_group() {
    // Eight Gaussians forced onto a linear truth: their weights are not needed, so their prior
    // precision is far above that of the linear weights, which carry the whole signal.
    let (x, _) = rows();
    let y = targets(&x, |r| 0.03 * r[0] - 0.2 * r[1], 1.0, 2.0);
    let opts = BayesOptions {
        centers: Some(8),
        ..BayesOptions::default()
    };
    let f = fit(&x, &y, &opts).unwrap();
    let e = &f.evidence;
    assert!(e.alpha_linear > 0.0, "{e:?}");
    assert!(e.alpha > 100.0 * e.alpha_linear, "{e:?}");
    // γ counts the bias and the two linear weights; the Gaussians add almost nothing.
    assert!(e.gamma > 2.5 && e.gamma < 4.0, "{e:?}");
}

#[test]
fn a_feature_enters_the_gaussians_only_when_its_effect_is_not_linear() {
    // `bump` is linear in the second feature: its length scale goes to the far end (64), which
    // leaves it to the linear term. A bump in the second feature brings it into the Gaussians.
    let (x, _) = rows();
    let f = fit(&x, &targets(&x, bump, 1.0, 0.0), &BayesOptions::default()).unwrap();
    assert_eq!(f.length_scales.len(), 2);
    assert_eq!(f.length_scales[1], 64.0, "{:?}", f.length_scales);
    assert!(f.length_scales[0] < 64.0, "{:?}", f.length_scales);
    let both = |r: &[f64]| bump(r) + 0.5 * (-(r[1] - 0.5) * (r[1] - 0.5) / 0.1).exp();
    let g = fit(&x, &targets(&x, both, 1.0, 0.0), &BayesOptions::default()).unwrap();
    assert!(
        g.length_scales.iter().all(|l| *l < 64.0),
        "{:?}",
        g.length_scales
    );
}
