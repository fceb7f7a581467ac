//! How well `bayes`' evidence search does, case by case: the log evidence it reaches, the chosen
//! structure (centers, width, length scales), the number of evidence fits, the held-out figure and
//! the fit time. Cases: the simulated QMA, RLG and IFOG presets (held-out std of 100 s bin means
//! over the noise floor of the verification run), the six hidden-effect presets of the discovery
//! tests refitted with their true features, and the six channels of the real MEMS thermal cycle
//! with (T) and with (T, rate) (verify RMS over poly3's). Run with
//! `RAYON_NUM_THREADS=1 cargo run --release -p tcomp-train --example search_eval`; `ONLY=prefix`
//! keeps the cases whose name starts with it, `SEG=1` adds the per-segment table.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
use tcomp_train::*;
struct Case {
    name: String,
    train: Dataset,
    verify: Dataset,
    floor: f64,
    o: FitOptions,
}
/// Which features a simulated case is fitted with.
enum Feats {
    /// The truth's minimal feature list.
    True,
    /// Every expression of every effect.
    Physics,
    /// These.
    Given(Vec<String>),
}

/// A case from a preset: train on its training run, measure on its verification run.
fn case_of(name: &str, p: &tcomp_sim::Preset, feats: Feats) -> Case {
    let (tt, truth) = tcomp_sim::simulate(&p.train).unwrap();
    let (vt, vtruth) = tcomp_sim::simulate(&p.verify).unwrap();
    let mut o = FitOptions::new(&truth.columns.target, &[]);
    o.spec.signals = truth
        .true_features
        .signals
        .iter()
        .map(|(k, v)| format!("{k} = {v}"))
        .collect();
    o.spec.features = match feats {
        Feats::True => truth.true_features.features.clone(),
        Feats::Given(f) => f,
        Feats::Physics => {
            let mut phys: Vec<String> = Vec::new();
            for x in truth.effects.iter().flat_map(|e| &e.expressions) {
                if !phys.contains(x) {
                    phys.push(x.clone());
                }
            }
            phys
        }
    };
    o.reference = Some(truth.columns.reference.clone());
    Case {
        name: name.into(),
        train: Dataset::from_columns("t", tt.names, tt.columns),
        verify: Dataset::from_columns("v", vt.names, vt.columns),
        floor: vtruth.noise.std_100s,
        o,
    }
}

fn sim(name: &str, feats: Option<Vec<String>>, physics: bool) -> Case {
    let p = tcomp_sim::presets::preset(name).unwrap().with_seed(1);
    let f = match (feats, physics) {
        (Some(f), _) => Feats::Given(f),
        (None, true) => Feats::Physics,
        (None, false) => Feats::True,
    };
    case_of(
        &format!("{name}{}", if physics { "-phys" } else { "" }),
        &p,
        f,
    )
}

fn effects(name: &str, sensor: tcomp_sim::SensorKind, eff: &[tcomp_sim::EffectKind]) -> Case {
    let p = tcomp_sim::presets::with_effects(sensor, eff)
        .unwrap()
        .with_seed(11);
    case_of(name, &p, Feats::True)
}

fn main() {
    let mut cases = vec![
        sim("qma", None, false),
        sim("qma", None, true),
        sim("rlg", None, false),
        sim("rlg", None, true),
        sim(
            "ifog-shupe",
            Some(vec!["t_coil_c".into(), "rate(t_coil_c)".into()]),
            false,
        ),
        sim(
            "ifog-shupe",
            Some(vec![
                "t_coil_c".into(),
                "rate(t_coil_c)".into(),
                "t_coil_c * rate(t_coil_c)".into(),
            ]),
            false,
        ),
    ];
    cases[5].name = "ifog-3".into();
    cases[4].name = "ifog-2".into();
    {
        use tcomp_sim::EffectKind::*;
        use tcomp_sim::SensorKind::*;
        cases.push(effects("h-rate", Ifog, &[Poly, Rate]));
        cases.push(effects("h-shupe", Ifog, &[Poly, Rate, Shupe]));
        cases.push(effects("h-lag", Ifog, &[Poly, Rate, LaggedElement]));
        let mut c = effects("h-lag-refit", Ifog, &[Poly, Rate, LaggedElement]);
        c.o.spec.features = vec![
            "t_coil_c".into(),
            "rate(t_coil_c)".into(),
            "lag(t_coil_c, 1200)".into(),
        ];
        cases.push(c);
        cases.push(effects("h-hyst", Ifog, &[Poly, Rate, Hysteresis]));
        cases.push(effects("h-supply", Ifog, &[Poly, Rate, SupplyVoltage]));
        cases.push(effects("h-grad", Rlg, &[Poly, Rate, Gradient]));
    }
    let mems = Dataset::load(std::path::Path::new("data/realdata/mems_thermal_cycle.csv")).unwrap();
    for ch in [
        "gyro_x_rad_s",
        "gyro_y_rad_s",
        "gyro_z_rad_s",
        "acc_x_m_s2",
        "acc_y_m_s2",
        "acc_z_m_s2",
    ] {
        let mut o = FitOptions::new(ch, &["temp_imu_C"]);
        o.until = Some(3130.0);
        let mut p = o.clone();
        p.method = Method::Poly3;
        let fp = fit(&mems, &p).unwrap();
        let bp = fp.model.to_bytes().unwrap();
        let mp = blob_io::decode(std::path::Path::new("m"), &bp).unwrap();
        let v = mems.select_time("time_s", 3130.0, f64::INFINITY).unwrap();
        let rp = evaluate(&mp, &v, &Roles::of_model(&mp), 100.0, None, None)
            .unwrap()
            .residual_rms;
        let mut o2 = o.clone();
        o2.spec.features.push("rate(temp_imu_C)".into());
        cases.push(Case {
            name: format!("memsR-{ch}"),
            train: mems.clone(),
            verify: v.clone(),
            floor: -rp,
            o: o2,
        });
        cases.push(Case {
            name: format!("mems-{ch}"),
            train: mems.clone(),
            verify: v,
            floor: -rp,
            o,
        });
    }
    let only = std::env::var("ONLY").ok();
    let mut tot = 0.0;
    for c in cases
        .iter()
        .filter(|c| only.as_ref().is_none_or(|o| c.name.starts_with(o.as_str())))
    {
        let t = std::time::Instant::now();
        let f = fit(&c.train, &c.o).unwrap();
        let el = t.elapsed().as_secs_f64();
        tot += el;
        let b = f.model.to_bytes().unwrap();
        let m = blob_io::decode(std::path::Path::new("m"), &b).unwrap();
        let r = evaluate(&m, &c.verify, &Roles::of_model(&m), 100.0, None, None).unwrap();
        let ratio = if c.floor > 0.0 {
            r.binned.residual_std / c.floor
        } else {
            r.residual_rms / -c.floor
        };
        let s = &f.summary;
        let ev = s.details.evidence.as_ref().unwrap();
        println!(
            "{:<22} le {:>10.3} m {:>2} s {:.2} ls {:?} evals {:>3} ratio {:.3}  {:.1} ms",
            c.name,
            ev.log_evidence,
            s.centers,
            s.width,
            s.details.length_scales,
            s.details.settings_evaluated,
            ratio,
            el * 1e3
        );
    }
    println!("total {:.0} ms", tot * 1e3);
}
