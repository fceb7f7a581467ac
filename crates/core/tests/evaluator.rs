//! The f32 RBF evaluator against an f64 reference of the same formula.
#![allow(clippy::unwrap_used, clippy::needless_range_loop, missing_docs)]

use tcomp_core::testing::{XorShift, example_model};
use tcomp_core::{HOST_CENTERS, HOST_FEATURES, HOST_NODES, HostModel};

fn reference(m: &HostModel<'_>, x: &[f32; 8]) -> f64 {
    let r = &m.rbf;
    let nf = r.n_features as usize;
    let z: Vec<f64> = (0..nf)
        .map(|k| (x[k] as f64 - r.offset.0[k] as f64) * r.scale.0[k] as f64)
        .collect();
    let mut y = r.bias as f64;
    for k in 0..nf {
        y += r.linear.0[k] as f64 * z[k];
    }
    for center in &r.centers {
        let (c, gamma, w) = center.to_natural();
        let d2: f64 = (0..nf).map(|k| (z[k] - c.0[k] as f64).powi(2)).sum();
        y += w as f64 * (-(gamma as f64) * d2).exp();
    }
    y
}

#[test]
fn matches_f64_reference() {
    let m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(64, 7);
    let mut rng = XorShift(99);
    let mut worst = 0.0f64;
    for _ in 0..5000 {
        let mut x = [0.0f32; 8];
        x[0] = rng.uniform(-40.0, 60.0);
        x[1] = rng.uniform(-5.0, 5.0);
        x[2] = rng.uniform(-3.0, 3.0);
        x[3] = rng.uniform(-3.0, 3.0);
        let got = m.rbf.eval(&x) as f64;
        worst = worst.max((got - reference(&m, &x)).abs());
    }
    // Weights are O(0.5) and 64 of them: f32 rounding and the fast exp leave < 1e-5 absolute.
    assert!(worst < 1e-5, "worst abs error {worst}");
}

#[test]
fn linear_term_extrapolates_and_gaussians_fade() {
    let mut m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(16, 3);
    let far = [1.0e4f32, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let y = m.rbf.eval(&far) as f64;
    let z0 = (far[0] - m.rbf.offset.0[0]) * m.rbf.scale.0[0];
    let linear_only = m.rbf.bias as f64 + m.rbf.linear.0[0] as f64 * z0 as f64
        - (0..4)
            .map(|k| m.rbf.linear.0[k] as f64 * (m.rbf.offset.0[k] * m.rbf.scale.0[k]) as f64)
            .sum::<f64>()
        + m.rbf.linear.0[0] as f64 * (m.rbf.offset.0[0] * m.rbf.scale.0[0]) as f64;
    assert!((y - linear_only).abs() < 1e-3, "{y} vs {linear_only}");
    m.rbf.linear = Default::default();
    assert!((m.rbf.eval(&far) - m.rbf.bias).abs() < 1e-6);
}

#[test]
fn natural_parameters_round_trip() {
    let c = tcomp_core::Center::<4>::from_natural(&[0.5, -1.0, 0.25, 0.0], 2.0, 0.75);
    let (pos, gamma, w) = c.to_natural();
    assert!(
        (pos.0[0] - 0.5).abs() < 1e-6
            && (pos.0[1] + 1.0).abs() < 1e-6
            && (pos.0[2] - 0.25).abs() < 1e-6
    );
    assert!((gamma - 2.0).abs() < 1e-6 && w == 0.75);
    assert!((c.sigma() - 0.5).abs() < 1e-6);
}

#[test]
fn expanded_form_stays_accurate_at_the_edges_of_the_range() {
    // Features three half-ranges out on every axis: ‖z‖² ≈ 36 is where the expanded distance loses
    // the most to cancellation. The error must stay far below any sensor's noise (1e-4 of Σ|w|).
    let m = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(64, 21);
    let sum_w: f64 = m.rbf.centers.iter().map(|c| c.w.abs() as f64).sum();
    let mut worst = 0.0f64;
    for corner in 0..16u32 {
        let mut x = [0.0f32; 8];
        let half = [50.0f32, 5.0, 3.0, 3.0];
        let mid = [10.0f32, 0.0, 0.0, 0.0];
        for k in 0..4 {
            let sign = if corner & (1 << k) != 0 { 1.0 } else { -1.0 };
            x[k] = mid[k] + sign * 3.0 * half[k] * 0.33;
        }
        worst = worst.max((m.rbf.eval(&x) as f64 - reference(&m, &x)).abs());
    }
    assert!(worst < 1e-4 * sum_w, "worst {worst} vs sum |w| {sum_w}");
}
