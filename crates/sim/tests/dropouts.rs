//! Logger dropouts: rows inside a dropout are missing from the file, the physics runs on through
//! it (every written row is the gap-free run's row, bit for bit), the truth lists the dropouts, and
//! the scenario file takes them explicitly or as a seeded random count.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use tcomp_sim::dropout::Dropout;
use tcomp_sim::{EffectKind, Scenario, SensorKind, presets, simulate, truth as truth_file};

fn rlg(kinds: &[EffectKind]) -> Scenario {
    presets::with_effects(SensorKind::Rlg, kinds).unwrap().train
}

#[test]
fn rows_in_a_dropout_are_lost_and_the_rest_are_the_gap_free_run() {
    let kinds = [
        EffectKind::Poly,
        EffectKind::LaggedElement,
        EffectKind::GradientLag,
        EffectKind::GradientRate,
    ];
    let full = rlg(&kinds);
    let holes = vec![
        Dropout {
            start_s: 6000.0,
            length_s: 600.0,
        },
        Dropout {
            start_s: 15_000.0,
            length_s: 120.0,
        },
    ];
    let gappy = full.clone().with_dropouts(holes.clone());
    let (a, ta) = simulate(&full).unwrap();
    let (b, tb) = simulate(&gappy).unwrap();
    assert_eq!(b.rows(), a.rows() - 720);
    assert_eq!(tb.rows, b.rows() as u64);
    assert_eq!(tb.dropouts, holes);
    assert!(ta.dropouts.is_empty());
    let time_a = a.column("time_s").unwrap();
    let time_b = b.column("time_s").unwrap();
    let mut j = 0;
    for (i, t) in time_a.iter().enumerate() {
        if holes.iter().any(|d| d.hides(*t)) {
            continue;
        }
        assert_eq!(time_b[j], *t);
        for (ca, cb) in a.columns.iter().zip(&b.columns) {
            assert_eq!(ca[i].to_bits(), cb[j].to_bits(), "row at {t} s");
        }
        j += 1;
    }
    assert_eq!(j, b.rows());
}

/// Over the gappy file, the truth's expressions (stateful ones carried across the dropouts) are
/// the bias to within what the linear bridge of a 10-minute hole costs — well below the noise.
#[test]
fn the_truth_over_a_gappy_file_is_the_bias_to_well_below_the_noise() {
    let sc =
        rlg(&[EffectKind::LaggedElement, EffectKind::GradientLag]).with_dropouts(vec![Dropout {
            start_s: 6200.0,
            length_s: 600.0,
        }]);
    let (table, truth) = simulate(&sc).unwrap();
    let out = table.column(&truth.columns.target).unwrap();
    let reference = table.column(&truth.columns.reference).unwrap();
    let mut r: Vec<f64> = out.iter().zip(reference).map(|(a, b)| a - b).collect();
    for e in &truth.effects {
        for (x, c) in e.expressions.iter().zip(&e.coefficients) {
            let v = truth_file::evaluate(&table, &truth.signals, x, truth.step_s).unwrap();
            for (ri, vi) in r.iter_mut().zip(&v) {
                *ri -= c * vi;
            }
        }
        r.iter_mut().for_each(|ri| *ri -= e.offset);
    }
    let n = r.len() as f64;
    let m = r.iter().sum::<f64>() / n;
    let s = (r.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt();
    assert!(
        s < 1.05 * truth.noise.std_raw,
        "residual {s} vs noise {}",
        truth.noise.std_raw
    );
}

#[test]
fn the_scenario_file_takes_dropouts_and_names_bad_ones() {
    let base = r#"
seed = 3
[sensor]
kind = "qma"
[profile]
start_c = 20
segments = [{ kind = "hold", duration_s = 3600 }, { kind = "ramp", to_c = 40, rate_c_per_min = 1 }]
"#;
    let sc = Scenario::from_toml_str(&format!(
        "dropouts = [{{ start_s = 100, length_s = 50 }}]\n{base}"
    ))
    .unwrap();
    assert_eq!(
        sc.dropouts,
        vec![Dropout {
            start_s: 100.0,
            length_s: 50.0
        }]
    );
    let sc = Scenario::from_toml_str(&format!(
        "random_dropouts = {{ count = 4, length_s = 60, seed = 9 }}\n{base}"
    ))
    .unwrap();
    assert_eq!(sc.dropouts.len(), 4);
    let (t, _) = simulate(&sc).unwrap();
    assert_eq!(t.rows(), 4800 - 240);
    let e = Scenario::from_toml_str(&format!(
        "dropouts = [{{ start_s = 100, length_s = -5 }}]\n{base}"
    ))
    .unwrap_err();
    assert!(e.to_string().contains("dropouts[0].length_s"), "{e}");
    let e = Scenario::from_toml_str(&format!(
        "dropouts = [{{ start_s = 1e6, length_s = 5 }}]\n{base}"
    ))
    .unwrap_err();
    assert!(e.to_string().contains("dropouts[0].start_s"), "{e}");
    let e = Scenario::from_toml_str(&format!(
        "dropouts = []\nrandom_dropouts = {{ count = 1, length_s = 5 }}\n{base}"
    ))
    .unwrap_err();
    assert!(e.to_string().contains("random_dropouts"), "{e}");
}
