//! The evidence iteration checked against its own definitions, recomputed here independently with a
//! plain dense inverse: at the returned (α, β) the weights are the posterior mean, α and β satisfy
//! MacKay's fixed point (`α_g = γ_g/‖w_g‖²`, `β = (N − γ)/‖y − Φw‖²`), and the log evidence is the
//! formula of the module doc. Both solver forms are covered (direct: small groups only; blocked: a
//! group of ≥ 4 columns), and `weights_on` against a direct solve on the kept rows.
//! Written to kill what `cargo mutants` found untested in `evidence.rs`.
#![allow(clippy::unwrap_used, clippy::needless_range_loop, missing_docs)]

use nalgebra::{DMatrix, DVector};
use tcomp_train::evidence::{GroupFit, Settings, fit, fit_with, weights_on};

const N: usize = 240;

fn noise(i: usize) -> f64 {
    ((i * 7919 + 17) % 1009) as f64 / 1009.0 - 0.5
}

fn x1(i: usize) -> f64 {
    (i as f64 * 0.07).sin()
}

fn x2(i: usize) -> f64 {
    (i as f64 * 0.031).cos()
}

fn target() -> DVector<f64> {
    DVector::from_fn(N, |i, _| {
        0.5 + 1.5 * x1(i) - 0.7 * x2(i) + 0.3 * x1(i) * x1(i) + 0.1 * noise(i)
    })
}

/// Bias, two linear columns (group 1), one quadratic (group 2): the direct form.
fn small_design() -> (DMatrix<f64>, Vec<usize>) {
    let phi = DMatrix::from_fn(N, 4, |i, j| match j {
        0 => 1.0,
        1 => x1(i),
        2 => x2(i),
        _ => x1(i) * x1(i),
    });
    (phi, vec![0, 1, 1, 2])
}

/// Bias, one linear column (group 1), six Gaussians (group 2) and a useless column (group 3): the
/// blocked form, shaped like the trainer's design plus a discovery candidate.
fn large_design() -> (DMatrix<f64>, Vec<usize>) {
    let phi = DMatrix::from_fn(N, 9, |i, j| match j {
        0 => 1.0,
        1 => x1(i),
        8 => (i as f64 * 0.377).cos(),
        _ => {
            let c = [(j as f64 - 4.5) * 0.5, (j as f64 * 0.9).cos()];
            let d2 = (x1(i) - c[0]).powi(2) + (x2(i) - c[1]).powi(2);
            (-d2 / 0.5).exp()
        }
    });
    (phi, vec![0, 1, 2, 2, 2, 2, 2, 2, 3])
}

/// Everything the fit should satisfy, recomputed from `phi`, `y` and the returned α, β.
fn check_against_definitions(phi: &DMatrix<f64>, y: &DVector<f64>, group: &[usize], f: &GroupFit) {
    let (n, m) = (phi.nrows(), phi.ncols());
    let ng = group.iter().max().unwrap() + 1;
    assert_eq!(f.alpha.len(), ng);
    assert!(
        f.alpha[0] < 1e-6,
        "the bias prior is nearly flat: {}",
        f.alpha[0]
    );
    let beta = f.beta;
    let mut a = phi.transpose() * phi * beta;
    for j in 0..m {
        a[(j, j)] += f.alpha[group[j]];
    }
    let ainv = a.clone().try_inverse().unwrap();
    let w = &ainv * phi.transpose() * y * beta;
    for j in 0..m {
        assert!(
            (f.w[j] - w[j]).abs() < 1e-6 * (1.0 + w[j].abs()),
            "w[{j}] {} vs {}",
            f.w[j],
            w[j]
        );
    }
    let r = y - phi * &w;
    let ed = 0.5 * r.dot(&r);
    let mut ww = vec![0.0; ng];
    let mut gamma_g = vec![0.0; ng];
    for j in 0..m {
        ww[group[j]] += w[j] * w[j];
        gamma_g[group[j]] += 1.0 - f.alpha[group[j]] * ainv[(j, j)];
    }
    let gamma: f64 = gamma_g.iter().sum();
    assert!(
        (f.gamma - gamma).abs() < 1e-6 * gamma,
        "γ {} vs {gamma}",
        f.gamma
    );
    assert!(gamma > 1.0 && gamma < m as f64, "γ = {gamma}");
    let rel = |a: f64, b: f64| ((a - b) / b).abs();
    let beta_fixed = (n as f64 - gamma) / (2.0 * ed);
    assert!(rel(beta, beta_fixed) < 1e-4, "β {beta} vs {beta_fixed}");
    for g in 1..ng {
        let fixed = gamma_g[g] / ww[g];
        // A switched-off group sits at the cap instead.
        if f.alpha[g] < 1e9 {
            assert!(
                rel(f.alpha[g], fixed) < 1e-3,
                "α[{g}] {} vs {fixed}",
                f.alpha[g]
            );
        }
    }
    let logdet = a
        .cholesky()
        .unwrap()
        .l()
        .diagonal()
        .iter()
        .map(|d| 2.0 * d.ln())
        .sum::<f64>();
    let mut log_ev = 0.5 * n as f64 * beta.ln()
        - beta * ed
        - 0.5 * logdet
        - 0.5 * n as f64 * (2.0 * std::f64::consts::PI).ln();
    for g in 1..ng {
        log_ev += 0.5 * group.iter().filter(|&&k| k == g).count() as f64 * f.alpha[g].ln()
            - 0.5 * f.alpha[g] * ww[g];
    }
    assert!(
        (f.log_evidence - log_ev).abs() < 1e-6 * log_ev.abs().max(1.0),
        "log evidence {} vs {log_ev}",
        f.log_evidence
    );
}

#[test]
fn direct_form_reaches_the_fixed_point_and_the_evidence_formula() {
    let (phi, group) = small_design();
    let y = target();
    let f = fit(&phi, &y, &group, None).unwrap();
    check_against_definitions(&phi, &y, &group, &f);
    assert!(f.iterations >= 2, "{} iterations", f.iterations);
    // The noise is uniform with amplitude 0.1: variance 0.1²/12.
    let sigma = (1.0 / f.beta).sqrt();
    assert!(
        (sigma - 0.1 / 12f64.sqrt()).abs() < 0.2 * 0.1 / 12f64.sqrt(),
        "σ {sigma}"
    );
    let t = fit_with(&phi, &y, &group, None, &Settings::TRAINER).unwrap();
    check_against_definitions(&phi, &y, &group, &t);
}

#[test]
fn blocked_form_reaches_the_fixed_point_and_the_evidence_formula() {
    let (phi, group) = large_design();
    let y = target();
    for settings in [Settings::SCORING, Settings::TRAINER] {
        let f = fit_with(&phi, &y, &group, None, &settings).unwrap();
        check_against_definitions(&phi, &y, &group, &f);
        assert!(f.iterations >= 2, "{} iterations", f.iterations);
    }
}

#[test]
fn a_warm_start_reaches_the_same_fit() {
    let (phi, group) = large_design();
    let y = target();
    let cold = fit(&phi, &y, &group, None).unwrap();
    let warm = fit(&phi, &y, &group, Some((&cold.alpha, cold.beta))).unwrap();
    assert!(
        warm.iterations < cold.iterations,
        "{} vs {}",
        warm.iterations,
        cold.iterations
    );
    assert!((warm.log_evidence - cold.log_evidence).abs() < 1e-3);
    check_against_definitions(&phi, &y, &group, &warm);
}

#[test]
fn iterations_stop_at_the_limit() {
    let (phi, group) = small_design();
    let y = target();
    let settings = Settings {
        max_iterations: 3,
        ..Settings::TRAINER
    };
    let f = fit_with(&phi, &y, &group, None, &settings).unwrap();
    assert_eq!(f.iterations, 3);
}

#[test]
fn weights_on_a_subset_are_the_posterior_mean_of_those_rows() {
    let (phi, group) = small_design();
    let y = target();
    let alpha = [1e-8, 0.5, 2.0];
    let beta = 300.0;
    let keep: Vec<usize> = (0..N).filter(|i| i % 3 != 1).collect();
    let w = weights_on(&phi, &y, &group, &alpha, beta, &keep).unwrap();
    let sub = phi.select_rows(&keep);
    let ys = y.select_rows(&keep);
    let mut a = sub.transpose() * &sub * beta;
    for j in 0..phi.ncols() {
        a[(j, j)] += alpha[group[j]];
    }
    let want = a.try_inverse().unwrap() * sub.transpose() * ys * beta;
    for j in 0..phi.ncols() {
        assert!(
            (w[j] - want[j]).abs() < 1e-8 * (1.0 + want[j].abs()),
            "w[{j}]"
        );
    }
    // A strong prior on group 2 shrinks its weight towards zero.
    let strong = weights_on(&phi, &y, &group, &[1e-8, 0.5, 1e9], beta, &keep).unwrap();
    assert!(
        strong[3].abs() < 1e-4 && w[3].abs() > 0.1,
        "{} / {}",
        strong[3],
        w[3]
    );
}
