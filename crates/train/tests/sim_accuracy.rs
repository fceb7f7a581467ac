//! Accuracy on simulated chamber runs with known truth (tcomp-sim): train on one profile, measure
//! on the other, through the decoded blob and the core's f32 channel.
//!
//! Figures are printed (`cargo test -p tcomp-train --test sim_accuracy -- --nocapture`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_train::mse::CenterSelection;
use tcomp_train::{Dataset, EvalReport, FitOptions, Method, Roles, blob_io, fit};

struct Pair {
    train: Dataset,
    verify: Dataset,
    floor_100s: f64,
    reference: String,
    target: String,
    signals: Vec<String>,
    /// The truth's minimal feature list (nonlinear shapes left to the Gaussians).
    features: Vec<String>,
    /// Every expression of every effect: the exact physics as linear features.
    physics: Vec<String>,
}

fn pair(name: &str) -> Pair {
    let p = tcomp_sim::presets::preset(name).unwrap().with_seed(1);
    let (tt, truth) = tcomp_sim::simulate(&p.train).unwrap();
    let (vt, vtruth) = tcomp_sim::simulate(&p.verify).unwrap();
    Pair {
        train: Dataset::from_columns(&format!("{name}-train"), tt.names, tt.columns),
        verify: Dataset::from_columns(&format!("{name}-verify"), vt.names, vt.columns),
        floor_100s: vtruth.noise.std_100s,
        reference: truth.columns.reference.clone(),
        target: truth.columns.target.clone(),
        signals: truth
            .true_features
            .signals
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect(),
        features: truth.true_features.features.clone(),
        physics: {
            let mut all: Vec<String> = Vec::new();
            for e in &truth.effects {
                for x in &e.expressions {
                    if !all.contains(x) {
                        all.push(x.clone());
                    }
                }
            }
            all
        },
    }
}

fn held_out(p: &Pair, method: Method, features: &[String], centers: Option<usize>) -> EvalReport {
    let mut o = FitOptions::new(&p.target, &[]);
    o.spec.signals = p.signals.clone();
    o.spec.features = features.to_vec();
    o.reference = Some(p.reference.clone());
    o.method = method;
    o.centers = centers;
    let f = fit(&p.train, &o).unwrap();
    let bytes = f.model.to_bytes().unwrap();
    let m = blob_io::decode(std::path::Path::new("mem"), &bytes).unwrap();
    tcomp_train::evaluate(&m, &p.verify, &Roles::of_model(&m), 100.0, None, None).unwrap()
}

fn show(name: &str, what: &str, r: &EvalReport, floor: f64) -> f64 {
    let ratio = r.binned.residual_std / floor;
    println!(
        "{name:<11} {what:<22} verify 100 s: raw {:.4e} residual {:.4e} floor {:.4e} ratio {ratio:.2}",
        r.binned.raw_std, r.binned.residual_std, floor
    );
    ratio
}

/// With the truth's minimal feature list the polynomial shape in temperature is left to the
/// Gaussians and the linear term. Measured (seed 1): QMA 0.99×, RLG 1.03× the noise floor; poly3
/// 11.9× and 3.9×. (QMA was 1.07× before the Occam margin grew with the residual's serial
/// correlation: its 4 Gaussians followed bias instability.)
#[test]
fn true_features_reach_near_the_noise_floor_and_beat_poly3() {
    for (name, guard) in [("qma", 1.1), ("rlg", 1.1)] {
        let p = pair(name);
        let b = held_out(&p, Method::Bayes, &p.features, None);
        let ratio = show(name, "bayes true features", &b, p.floor_100s);
        let first = vec![p.features[0].clone()];
        let c = held_out(&p, Method::Poly3, &first, None);
        let pratio = show(name, "poly3", &c, p.floor_100s);
        assert!(ratio < guard, "{name}: {ratio:.2} × floor");
        assert!(
            ratio < 0.5 * pratio,
            "{name}: bayes {ratio:.2} vs poly3 {pratio:.2}"
        );
    }
}

/// Issue target: within 1.1× the noise floor with the true feature set — here every expression the
/// truth gives for its effects (the cubic's powers, the rate, the gradients). Measured (seed 1):
/// QMA 0.99×, RLG 1.02× (both stay linear in the true features).
#[test]
fn exact_physics_features_reach_the_noise_floor() {
    for name in ["qma", "rlg"] {
        let p = pair(name);
        let b = held_out(&p, Method::Bayes, &p.physics, None);
        let ratio = show(name, "bayes exact physics", &b, p.floor_100s);
        assert!(ratio <= 1.1, "{name}: {ratio:.2}");
    }
}

/// The seed papers' comparison, with both ways the traditional RBF places its centers: k-means
/// (where the data are) and orthogonal least squares forward selection (where the training error
/// is — which, with many centers, chases the training run's noise harder still).
#[test]
fn bayes_generalises_better_than_mse_with_many_centers() {
    let p = pair("qma");
    let b = held_out(&p, Method::Bayes, &p.features, None);
    let rb = show("qma", "bayes", &b, p.floor_100s);
    for select in [CenterSelection::Kmeans, CenterSelection::Ols] {
        let mut o = FitOptions::new(&p.target, &[]);
        o.spec.signals = p.signals.clone();
        o.spec.features = p.features.clone();
        o.reference = Some(p.reference.clone());
        o.method = Method::Mse;
        o.centers = Some(32);
        o.settings.mse.select = Some(format!("{select:?}").to_lowercase());
        let f = fit(&p.train, &o).unwrap();
        assert_eq!(f.summary.centers, 32);
        let bytes = f.model.to_bytes().unwrap();
        let m = blob_io::decode(std::path::Path::new("mem"), &bytes).unwrap();
        let r =
            tcomp_train::evaluate(&m, &p.verify, &Roles::of_model(&m), 100.0, None, None).unwrap();
        let rm = show("qma", &format!("mse 32 ({select:?})"), &r, p.floor_100s);
        assert!(rb < 0.5 * rm, "bayes {rb:.2} vs mse {select:?} {rm:.2}");
    }
}

#[test]
fn shupe_product_feature_helps_the_ifog() {
    let p = pair("ifog-shupe");
    let two = vec!["t_coil_c".to_string(), "rate(t_coil_c)".to_string()];
    let three = vec![
        "t_coil_c".to_string(),
        "rate(t_coil_c)".to_string(),
        "t_coil_c * rate(t_coil_c)".to_string(),
    ];
    let r2 = show(
        "ifog-shupe",
        "(T, dT)",
        &held_out(&p, Method::Bayes, &two, None),
        p.floor_100s,
    );
    let r3 = show(
        "ifog-shupe",
        "(T, dT, T*dT)",
        &held_out(&p, Method::Bayes, &three, None),
        p.floor_100s,
    );
    assert!(r3 < r2, "(T, dT, T*dT) {r3:.2} vs (T, dT) {r2:.2}");
}

/// `run_model` runs a model of ≤ 4 features in the firmware's 4-feature types; the host's 8-wide
/// types must give the very same numbers (features past `n_features` are exact zeros). A 32-center
/// RLG model over its verification run: every residual equal, bit for bit.
#[test]
fn narrow_and_wide_runs_agree() {
    let p = pair("rlg");
    let mut o = FitOptions::new(&p.target, &[]);
    o.spec.signals = p.signals.clone();
    o.spec.features = p.features.clone();
    o.reference = Some(p.reference.clone());
    o.centers = Some(32);
    let f = fit(&p.train, &o).unwrap();
    let bytes = f.model.to_bytes().unwrap();
    let m = blob_io::decode(std::path::Path::new("mem"), &bytes).unwrap();
    assert_eq!(m.rbf.n_features, 4);
    assert_eq!(m.rbf.centers.len(), 32);
    let roles = Roles::of_model(&m);
    let narrow = tcomp_train::metrics::run_model(&m, &p.verify, &roles, None, None).unwrap();
    let wide = tcomp_train::metrics::run_at_capacity(&m, &p.verify, &roles, None, None).unwrap();
    assert_eq!(narrow.residual.len(), p.verify.len());
    let differ = narrow
        .residual
        .iter()
        .zip(&wide.residual)
        .filter(|(a, b)| a.to_bits() != b.to_bits())
        .count();
    assert_eq!(
        differ, 0,
        "{differ} residuals differ between 4- and 8-wide types"
    );
    assert_eq!(narrow.out_of_range, wide.out_of_range);
}

/// The diagnosis's held-out refits: `fit_unmeasured` gives `fit`'s model but for the residual level
/// (left at zero, never read by the compensator), and `run_model_window` gives a window of the
/// whole run bit for bit (the model is causal; the gaps are found over the whole run). Windows at
/// the start, in the middle (after a gap cut into the time column) and open-ended.
#[test]
fn unmeasured_refits_and_windowed_runs_agree() {
    let p = pair("qma");
    let mut o = FitOptions::new(&p.target, &[]);
    o.spec.signals = p.signals.clone();
    o.spec.features = p.features.clone();
    o.reference = Some(p.reference.clone());
    let f = fit(&p.train, &o).unwrap();
    let (mut unmeasured, details) = tcomp_train::fit_unmeasured(&p.train, &o).unwrap();
    assert_eq!(
        details.evidence.map(|e| e.log_evidence.to_bits()),
        f.summary.details.evidence.map(|e| e.log_evidence.to_bits())
    );
    assert_eq!(unmeasured.residual.std, 0.0);
    unmeasured.residual = f.model.residual;
    assert_eq!(unmeasured.to_bytes().unwrap(), f.model.to_bytes().unwrap());

    let bytes = f.model.to_bytes().unwrap();
    let m = blob_io::decode(std::path::Path::new("mem"), &bytes).unwrap();
    let roles = Roles::of_model(&m);
    // A gap of 30 rows cut out a third of the way in.
    let time = p.verify.time(&roles.time).unwrap().to_vec();
    let cut = time.len() / 3;
    let cols = p
        .verify
        .names()
        .iter()
        .map(|n| {
            let c = p.verify.column(n).unwrap();
            c.iter()
                .enumerate()
                .filter(|(i, _)| !(cut..cut + 30).contains(i))
                .map(|(_, v)| *v)
                .collect()
        })
        .collect();
    let gappy = Dataset::from_columns("gappy", p.verify.names().to_vec(), cols);
    let t = gappy.time(&roles.time).unwrap();
    let (t0, t1) = (t[0], t[t.len() - 1]);
    let span = t1 - t0;
    for (lo, hi) in [
        (f64::NEG_INFINITY, t0 + 0.2 * span),
        (t0 + 0.3 * span, t0 + 0.6 * span),
        (t0 + 0.7 * span, f64::INFINITY),
    ] {
        let whole = tcomp_train::metrics::run_model(&m, &gappy, &roles, None, None)
            .unwrap()
            .window(lo, hi);
        let part = tcomp_train::metrics::run_model_window(&m, &gappy, &roles, None, None, (lo, hi))
            .unwrap();
        assert!(!part.residual.is_empty());
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&part.time), bits(&whole.time), "[{lo}, {hi})");
        assert_eq!(bits(&part.residual), bits(&whole.residual), "[{lo}, {hi})");
        assert_eq!(bits(&part.error), bits(&whole.error), "[{lo}, {hi})");
        assert_eq!(
            bits(&part.temperature),
            bits(&whole.temperature),
            "[{lo}, {hi})"
        );
        assert_eq!(part.gaps, whole.gaps);
    }
}
