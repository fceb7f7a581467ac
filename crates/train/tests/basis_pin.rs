//! `--basis` (spec key `basis`) pins bayes's basis instead of letting the evidence choose it: the
//! cubic in the first feature, the Gaussian search without it, or the additive structure
//! (taken whenever its search finds a term, where free it must beat the joint model by the
//! Occam margin). The diagnosis pins the held-out
//! blocks' refits to the basis the whole training run's evidence chose (`tcomp_discover`'s
//! `confirm`); a user pins it when they know better. A name it does not know, or a cubic it
//! cannot build, is refused with the option named.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_train::method::Basis;
use tcomp_train::{Dataset, FitOptions, Method, fit};

/// A coil temperature swinging ±10 °C over 3 h, a bias with a bend the cubic does not follow
/// exactly (a smooth step at 24 °C), so the evidence alone prefers Gaussians.
fn data() -> Dataset {
    let mut s = String::from("time_s,t_coil_c,gyro_dph,ref_dph\n");
    for i in 0..10_800 {
        let t = i as f64;
        let temp = 20.0 + 10.0 * (t / 900.0).sin();
        let bias = 0.01 * temp + 0.3 * ((temp - 24.0) / 0.8).tanh();
        let noise = 0.002 * ((i * 7919 + 13) % 1009) as f64 / 1009.0;
        s.push_str(&format!("{t},{temp},{},0\n", bias + noise));
    }
    Dataset::from_reader("run.csv", s.as_bytes()).unwrap()
}

fn options(basis: Option<&str>) -> FitOptions {
    let mut o = FitOptions::new("gyro_dph", &["t_coil_c"]);
    o.reference = Some("ref_dph".into());
    o.method = Method::Bayes;
    o.settings.bayes.basis = basis.map(str::to_string);
    o
}

#[test]
fn a_pinned_basis_is_the_one_fitted() {
    let d = data();
    let free = fit(&d, &options(None)).unwrap();
    assert!(
        matches!(
            free.summary.details.basis,
            Some(Basis::Gaussians | Basis::Additive)
        ),
        "the evidence alone should prefer Gaussians (joint or additive) on a smooth step: {:?}",
        free.summary.details.structure
    );
    let cubic = fit(&d, &options(Some("cubic"))).unwrap();
    assert_eq!(cubic.summary.details.basis, Some(Basis::Cubic));
    assert_eq!(cubic.summary.centers, 0);
    let gaussians = fit(&d, &options(Some("gaussians"))).unwrap();
    assert_eq!(gaussians.summary.details.basis, Some(Basis::Gaussians));
    let additive = fit(&d, &options(Some("additive"))).unwrap();
    assert_eq!(additive.summary.details.basis, Some(Basis::Additive));
    assert!(
        additive
            .summary
            .details
            .structure
            .as_ref()
            .is_some_and(|s| s.chosen.starts_with("additive")),
        "{:?}",
        additive.summary.details.structure
    );
    // No cubic was offered: none was compared.
    assert!(
        gaussians
            .summary
            .details
            .structure
            .iter()
            .flat_map(|s| &s.compared)
            .all(|(name, _)| !name.contains("cubic")),
        "{:?}",
        gaussians.summary.details.structure
    );
}

#[test]
fn an_unknown_basis_or_an_impossible_cubic_is_refused_by_name() {
    let d = data();
    let e = fit(&d, &options(Some("spline"))).unwrap_err().to_string();
    assert!(
        e.contains("basis") && e.contains("spline") && e.contains("additive, cubic, gaussians"),
        "{e}"
    );
    let mut o = options(Some("cubic"));
    o.centers = Some(4);
    let e = fit(&d, &o).unwrap_err().to_string();
    assert!(e.contains("basis = cubic"), "{e}");
    let mut o = options(Some("additive"));
    o.settings.bayes.additive = Some(false);
    let e = fit(&d, &o).unwrap_err().to_string();
    assert!(e.contains("basis = additive"), "{e}");
}

/// A pinned cubic is the one fit made (its weights do not depend on the Gaussians, whose search
/// is not run): the same model, to the byte, as the evidence's own choice of the cubic where the
/// bias is one (the additive structure not offered), after one fit instead of the search's
/// dozens, and one structure compared.
#[test]
fn a_pinned_cubic_is_the_one_fit_made() {
    let mut s = String::from("time_s,t_coil_c,gyro_dph,ref_dph\n");
    for i in 0..10_800 {
        let t = i as f64;
        let temp = 20.0 + 10.0 * (t / 900.0).sin();
        let x = temp - 20.0;
        let bias = 0.01 * x + 0.002 * x * x - 0.0001 * x * x * x;
        let noise = 0.002 * ((i * 7919 + 13) % 1009) as f64 / 1009.0;
        s.push_str(&format!("{t},{temp},{},0\n", bias + noise));
    }
    let d = Dataset::from_reader("run.csv", s.as_bytes()).unwrap();
    // The additive structure (a square and a cube of T) is not offered: it would take the run.
    let mut o = options(None);
    o.settings.bayes.additive = Some(false);
    let free = fit(&d, &o).unwrap();
    assert_eq!(
        free.summary.details.basis,
        Some(Basis::Cubic),
        "{:?}",
        free.summary.details.structure
    );
    let pinned = fit(&d, &options(Some("cubic"))).unwrap();
    assert_eq!(
        pinned.model.to_bytes().unwrap(),
        free.model.to_bytes().unwrap()
    );
    assert!(free.summary.details.settings_evaluated > 20);
    assert_eq!(pinned.summary.details.settings_evaluated, 1);
    let compared = &pinned.summary.details.structure.as_ref().unwrap().compared;
    assert_eq!(compared.len(), 1, "{compared:?}");
    assert_eq!(pinned.summary.details.other_basis_log_evidence, None);
}
