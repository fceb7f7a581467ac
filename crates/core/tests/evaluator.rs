//! The f32 RBF evaluator against an f64 reference of the same formula.
#![allow(clippy::unwrap_used, clippy::needless_range_loop, missing_docs)]

use tcomp_core::Model;
use tcomp_core::testing::{XorShift, example_model};

fn reference(m: &Model<'_, 64, 8, 48>, x: &[f32; 8]) -> f64 {
    let r = &m.rbf;
    let nf = r.n_features as usize;
    let z: Vec<f64> = (0..nf)
        .map(|k| (x[k] as f64 - r.offset.0[k] as f64) * r.scale.0[k] as f64)
        .collect();
    let mut y = r.bias as f64;
    for k in 0..nf {
        y += r.linear.0[k] as f64 * z[k];
    }
    for j in 0..r.centers.len() {
        let d2: f64 = (0..nf)
            .map(|k| (z[k] - r.centers[j].0[k] as f64).powi(2))
            .sum();
        y += r.weights[j] as f64 * (-(r.gamma[j] as f64) * d2).exp();
    }
    y
}

#[test]
fn matches_f64_reference() {
    let m = example_model::<64, 8, 48>(64, 7);
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
    let mut m = example_model::<64, 8, 48>(16, 3);
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
