//! Real MEMS data (`data/realdata/`, MIT-licensed copies of the shared recordings): train on
//! t < 3130 s of the thermal cycle, verify on the final cooling, each channel against its training
//! mean. Figures are the verify RMS (it counts the bias offset a model leaves, which is what
//! compensation is for) and the std. Print the table with
//! `cargo test -p tcomp-train --release --test realdata -- --nocapture --include-ignored`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::path::PathBuf;
use tcomp_train::{Dataset, EvalReport, FitOptions, Method, Roles, blob_io, fit};

const CHANNELS: [&str; 6] = [
    "gyro_x_rad_s",
    "gyro_y_rad_s",
    "gyro_z_rad_s",
    "acc_x_m_s2",
    "acc_y_m_s2",
    "acc_z_m_s2",
];

fn data_dir() -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    [root.join("data/realdata"), root.join("../shared/realdata")]
        .into_iter()
        .find(|d| d.join("mems_thermal_cycle.csv").exists())
}

fn verify(
    data: &Dataset,
    time: &str,
    target: &str,
    split: f64,
    method: Method,
    features: &[&str],
) -> EvalReport {
    verify_avg(data, time, target, split, method, features, None)
}

fn verify_avg(
    data: &Dataset,
    time: &str,
    target: &str,
    split: f64,
    method: Method,
    features: &[&str],
    average_s: Option<f64>,
) -> EvalReport {
    let mut o = FitOptions::new(target, features);
    o.time = time.into();
    o.method = method;
    o.average_s = average_s;
    o.until = Some(split);
    let f = fit(data, &o).unwrap();
    if let Some(s) = &f.summary.details.structure {
        println!("  {target} {features:?}: {}", s.chosen);
        if std::env::var("SHOW").is_ok() {
            for (n, e) in &s.compared {
                println!("      {e:>10.1}  {n}");
            }
        }
    }
    let bytes = f.model.to_bytes().unwrap();
    let m = blob_io::decode(std::path::Path::new("mem"), &bytes).unwrap();
    let v = data.select_time(time, split, f64::INFINITY).unwrap();
    tcomp_train::evaluate(&m, &v, &Roles::of_model(&m), 100.0, None, None).unwrap()
}

fn load(name: &str) -> Option<Dataset> {
    let Some(dir) = data_dir() else {
        println!("real data not found (data/realdata or ../shared/realdata): skipped");
        return None;
    };
    Some(Dataset::load(&dir.join(name)).unwrap())
}

/// The second clause, and what holds of the first. With the die temperature alone, the
/// verification (the final cooling, 74 → 36 °C) runs along the cooling branch of a hysteresis loop
/// that no function of T can reach, so every model of T ties: the Gaussian models `bayes` finds are
/// within 3 nats of log evidence of the cubic basis it is offered, and it keeps the simpler, the
/// cubic under MacKay's prior, on all six channels (measured bayes/poly3 0.959–1.008; before the cubic
/// basis was offered, the Gaussian models measured 0.963–1.074). Asserted: never worse than raw by
/// more than 5 % (the evidence keeps low-dependence channels nearly flat), and within 2 % of poly3 on
/// every channel.
#[test]
fn mems_cycle_bayes_t_ties_poly3_and_never_hurts() {
    let Some(d) = load("mems_thermal_cycle.csv") else {
        return;
    };
    println!("channel        raw rms    poly3 rms  bayes(T) rms  bayes/poly3  bayes/raw");
    let mut wins = 0;
    for ch in CHANNELS {
        let p = verify(&d, "time_s", ch, 3130.0, Method::Poly3, &["temp_imu_C"]);
        let b = verify(&d, "time_s", ch, 3130.0, Method::Bayes, &["temp_imu_C"]);
        println!(
            "{ch:<14} {:.3e}  {:.3e}  {:.3e}     {:.3}        {:.3}",
            p.raw_rms,
            p.residual_rms,
            b.residual_rms,
            b.residual_rms / p.residual_rms,
            b.residual_rms / b.raw_rms
        );
        assert!(b.residual_rms <= 1.05 * b.raw_rms, "{ch}: worse than raw");
        assert!(
            b.residual_rms <= 1.02 * p.residual_rms,
            "{ch}: behind poly3"
        );
        wins += usize::from(b.residual_rms <= p.residual_rms);
    }
    println!("bayes(T) no worse than poly3 on {wins} of 6 channels");
}

/// What `bayes` chose on the thermal cycle with (T) is a model the firmware can fly: the cubic basis
/// adds `Tclamped = clamp(T, trained range)`, `sq(Tclamped)` and `Tclamped * sq(Tclamped)` to the
/// program, and the blob must still decode into the firmware's 32 × 4 types with its 16 program
/// nodes (`firmware/src/app.rs`).
#[test]
fn mems_cycle_cubic_models_fit_the_firmware() {
    let Some(d) = load("mems_thermal_cycle.csv") else {
        return;
    };
    let mut cubic = 0;
    for ch in CHANNELS {
        let mut o = FitOptions::new(ch, &["temp_imu_C"]);
        o.until = Some(3130.0);
        let f = fit(&d, &o).unwrap();
        let s = &f.summary.details;
        let other = s.other_basis_log_evidence.expect("the cubic was offered");
        let ev = s.evidence.as_ref().unwrap().log_evidence;
        if s.basis == Some(tcomp_train::bayes::Basis::Cubic) {
            cubic += 1;
            assert_eq!(f.summary.centers, 0, "{ch}");
            assert_eq!(f.model.spec.features.len(), 3, "{ch}");
            assert!(ev >= other - tcomp_train::bayes::PARSIMONY, "{ch}");
        } else {
            assert!(ev > other + tcomp_train::bayes::PARSIMONY, "{ch}");
        }
        let bytes = f.model.to_bytes().unwrap();
        let host = blob_io::decode(std::path::Path::new("mem"), &bytes).unwrap();
        let fw = tcomp_core::Model::<'_, 32, 4, 16>::decode(&bytes)
            .unwrap_or_else(|e| panic!("{ch}: does not fit the firmware: {e:?}"));
        assert_eq!(fw.rbf.n_features, host.rbf.n_features);
    }
    println!("bayes(T) chose the cubic basis on {cubic} of 6 channels");
    assert!(cubic >= 1, "no tie was broken towards the cubic");
    // `--no-cubic`: the Gaussians alone, and nothing compared with them.
    let mut o = FitOptions::new("acc_z_m_s2", &["temp_imu_C"]);
    o.until = Some(3130.0);
    o.settings.bayes.cubic = Some(false);
    let f = fit(&d, &o).unwrap();
    assert_eq!(
        f.summary.details.basis,
        Some(tcomp_train::bayes::Basis::Gaussians)
    );
    assert_eq!(f.summary.details.other_basis_log_evidence, None);
    assert_eq!(f.model.spec.features, vec!["temp_imu_C".to_string()]);
}

/// With the rate of temperature as a second feature (the thermal gradients inside the package
/// follow dT/dt), the hysteresis is modelled: on the three accelerometers the verify RMS falls to
/// 0.19–0.58 of poly3's (measured). It is not the answer on every channel: on gyro_z the training
/// run's cooling runs above the heating branch and the verification's cooling below it (a drift
/// temperature does not explain; leaving the first 5 or 10 minutes out of training does not remove
/// it), so the rate term learned in training doubles the verify error — while the log evidence
/// prefers (T, rate) over (T) on every channel, gyro_z included. Training data alone cannot tell.
#[test]
fn mems_cycle_rate_feature_pays_on_accelerometers() {
    let Some(d) = load("mems_thermal_cycle.csv") else {
        return;
    };
    let f = ["temp_imu_C", "rate(temp_imu_C)"];
    println!("channel        poly3 rms  bayes(T, rate) rms  ratio");
    for ch in CHANNELS {
        let p = verify(&d, "time_s", ch, 3130.0, Method::Poly3, &["temp_imu_C"]);
        let r = verify(&d, "time_s", ch, 3130.0, Method::Bayes, &f);
        let ratio = r.residual_rms / p.residual_rms;
        println!(
            "{ch:<14} {:.3e}  {:.3e}           {ratio:.3}",
            p.residual_rms, r.residual_rms
        );
        if ch.starts_with("acc") {
            assert!(ratio <= 0.7, "{ch}: (T, rate) {ratio:.3} of poly3");
        }
    }
}

/// The LSM6DSM cold ramp (25 bursts of ~5 s every ~5 min; train t < 4000 s, verify the rest): 2 s
/// bins keep a few per burst (longer bins would span the gaps between bursts, where the feature
/// state is reset). Asserted: bayes(T) never worse than raw by more than 5 %.
#[test]
fn lsm6dsm_ramp_table() {
    let Some(l) = load("lsm6dsm_tvac_cold_ramp.csv") else {
        return;
    };
    println!("LSM6DSM cold ramp, train t < 4000 s, verify the rest (2 s bins)");
    for ch in ["gyro_x_rad_s", "gyro_y_rad_s", "gyro_z_rad_s"] {
        let f = ["temp_lsm6dsm_C"];
        let p = verify_avg(&l, "time_s", ch, 4000.0, Method::Poly3, &f, Some(2.0));
        let b = verify_avg(&l, "time_s", ch, 4000.0, Method::Bayes, &f, Some(2.0));
        println!(
            "{ch:<14} raw {:.3e}  poly3 {:.3e}  bayes(T) {:.3e}",
            p.raw_rms, p.residual_rms, b.residual_rms
        );
        assert!(b.residual_rms <= 1.05 * b.raw_rms, "{ch}: worse than raw");
    }
}

/// Issue 4's literal target: bayes no worse than poly3 on every MEMS channel. Not met by an honest
/// method on this record (see the two tests above): with (T) `bayes` chooses the cubic, and the
/// prior's shrinkage of its weights leaves gyro_x, gyro_y and acc_y 0.3–0.8 % behind the least-squares
/// cubic (and gyro_z, acc_z 4 % and 1 % ahead); with (T, rate) gyro_z doubles.
#[test]
#[ignore = "issue target not met on this record: bayes(T) is the Bayesian cubic, 0.3-0.8 % behind least squares on 3 channels; bayes(T, rate) doubles gyro_z"]
fn mems_cycle_no_worse_than_poly3_everywhere() {
    let Some(d) = load("mems_thermal_cycle.csv") else {
        return;
    };
    for ch in CHANNELS {
        let p = verify(&d, "time_s", ch, 3130.0, Method::Poly3, &["temp_imu_C"]);
        let b = verify(&d, "time_s", ch, 3130.0, Method::Bayes, &["temp_imu_C"]);
        assert!(b.residual_rms <= p.residual_rms, "{ch}");
    }
}
