//! TOML scenarios: the shipped example parses; bad input names the field.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use tcomp_sim::{EffectKind, Error, Preset, Scenario, SensorKind, simulate};

const EXAMPLE: &str = include_str!("../examples/ifog_custom.toml");

#[test]
fn shipped_example_parses_and_runs() {
    let sc = Scenario::from_toml_str(EXAMPLE).unwrap();
    assert_eq!(sc.sensor, SensorKind::Ifog);
    assert_eq!(sc.seed, 42);
    assert_eq!(sc.thermometers[0].tau_s, 1000.0);
    let kinds: Vec<EffectKind> = sc.effects.iter().map(|e| e.kind()).collect();
    assert_eq!(
        kinds,
        [
            EffectKind::Poly,
            EffectKind::Rate,
            EffectKind::Shupe,
            EffectKind::LaggedElement
        ]
    );
    let p = Preset::from_toml_str(EXAMPLE).unwrap();
    assert_eq!(p.verify.profile.range_c(), (-10.0, 40.0));
    assert_eq!(p.verify.seed, 43);
    let (_, truth) = simulate(&p.train).unwrap();
    assert!(
        truth
            .true_features
            .features
            .contains(&"lag(t_coil_c, 2400)".to_string())
    );
}

#[test]
fn scenario_without_verify_profile_gets_a_random_one() {
    let text = EXAMPLE
        .split("[verify_profile]")
        .next()
        .unwrap()
        .to_string()
        + "[[effects]]\nname = \"warmup\"\ncoefficient = 0.5\ntau_s = 900\n";
    let p = Preset::from_toml_str(&text).unwrap();
    let (lo, hi) = p.verify.profile.range_c();
    assert!(lo >= 10.0 && hi <= 40.0, "{lo} {hi}");
    assert_ne!(p.verify.profile, p.train.profile);
}

fn field_of(text: &str) -> String {
    match Scenario::from_toml_str(text) {
        Err(Error::Invalid { field, message }) => {
            assert!(!message.is_empty());
            field
        }
        Err(other) => panic!("expected a field error, got {other}"),
        Ok(_) => panic!("accepted:\n{text}"),
    }
}

const BASE: &str = r#"
[sensor]
kind = "qma"
[profile]
start_c = 20
segments = [
  { kind = "hold", duration_s = 600 },
  { kind = "ramp", to_c = 30, rate_c_per_min = 1 },
  { kind = "hold", duration_s = 600 },
]
"#;

#[test]
fn base_is_valid() {
    let sc = Scenario::from_toml_str(BASE).unwrap();
    assert_eq!(sc.sensor, SensorKind::Qma);
    assert!(sc.effects.is_empty());
}

#[test]
fn unknown_effect_names_the_field_and_the_known_ones() {
    let text = format!(
        "{BASE}\n[[effects]]\nname = \"poly\"\ncoefficients = [1.0]\n[[effects]]\nname = \"shupee\"\ncoefficient = 1\n"
    );
    let err = Scenario::from_toml_str(&text).unwrap_err().to_string();
    assert!(
        err.starts_with("effects[1].name: unknown effect \"shupee\""),
        "{err}"
    );
    assert!(
        err.contains("shupe") && err.contains("lagged_element"),
        "{err}"
    );
}

#[test]
fn zero_ramp_rate_names_the_segment() {
    let text = BASE.replace("rate_c_per_min = 1", "rate_c_per_min = 0");
    assert_eq!(field_of(&text), "profile.segments[1].rate_c_per_min");
    let err = Scenario::from_toml_str(&text).unwrap_err().to_string();
    assert!(err.contains("a ramp needs a non-zero rate"), "{err}");
}

#[test]
fn negative_time_constant_names_the_field() {
    let text = format!("{BASE}\n[sensor.thermal.t_qma_c]\ntau_s = -5\n");
    // `[sensor.thermal...]` after `[profile]` is still a sub-table of sensor in TOML.
    assert_eq!(field_of(&text), "sensor.thermal.t_qma_c.tau_s");
    let text =
        format!("{BASE}\n[[effects]]\nname = \"lagged_element\"\ncoefficient = 1\ntau_s = -1\n");
    assert_eq!(field_of(&text), "effects[0].tau_s");
}

#[test]
fn empty_profile_names_the_field() {
    let text = "[sensor]\nkind = \"ifog\"\n[profile]\nstart_c = 20\nsegments = []\n";
    assert_eq!(field_of(text), "profile.segments");
    let text = "[sensor]\nkind = \"ifog\"\n";
    assert_eq!(field_of(text), "profile");
}

#[test]
fn other_bad_values_name_their_fields() {
    assert_eq!(
        field_of(&BASE.replace("kind = \"qma\"", "kind = \"mems\"")),
        "sensor.kind"
    );
    assert_eq!(
        field_of(&format!("{BASE}\n[sensor.thermal.t_coil_c]\ntau_s = 5\n")),
        "sensor.thermal.t_coil_c"
    );
    assert_eq!(
        field_of(&format!(
            "{BASE}\n[[effects]]\nname = \"gradient\"\nanode_shell = 1\ncathode_shell = 1\n"
        )),
        "effects[0].name"
    );
    assert_eq!(
        field_of(&format!(
            "{BASE}\n[[effects]]\nname = \"rate\"\ncoefficient = 1\ninput = \"t_coil_c\"\n"
        )),
        "effects[0].input"
    );
    assert_eq!(
        field_of(&format!("rate_hz = 100\nstep_s = 0.015\n{BASE}")),
        "step_s"
    );
    assert_eq!(
        field_of(&format!("{BASE}\n[noise]\narw_deg_per_sqrt_h = 0.1\n")),
        "noise.arw_deg_per_sqrt_h"
    );
    assert_eq!(
        field_of(&format!("{BASE}\n[noise]\ncorrelation_s = 0\n")),
        "noise.correlation_s"
    );
    assert_eq!(
        field_of(&BASE.replace("to_c = 30", "to_c = 20")),
        "profile.segments[1].to_c"
    );
}

#[test]
fn shape_errors_are_reported() {
    // Unknown keys and wrong types are rejected by the TOML layer with a message naming them.
    let err = Scenario::from_toml_str(&format!("{BASE}\nbogus = 1\n"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("bogus"), "{err}");
    let err = Scenario::from_toml_str(&format!(
        "{BASE}\n[[effects]]\nname = \"rate\"\ncoeficient = 1\n"
    ))
    .unwrap_err()
    .to_string();
    assert!(
        err.starts_with("effects[0]") && err.contains("coeficient"),
        "{err}"
    );
}

#[test]
fn sensor_kinds_the_simulator_does_not_simulate_are_refused_by_name() {
    // The core knows six sensor kinds; the simulator simulates three and says so.
    for name in ["mems-gyro", "mems-accel", "other"] {
        let text = BASE.replace("kind = \"qma\"", &format!("kind = \"{name}\""));
        let err = Scenario::from_toml_str(&text).unwrap_err().to_string();
        assert!(
            err.starts_with("sensor.kind:") && err.contains(name) && err.contains("not simulated"),
            "{err}"
        );
    }
    let p = Scenario::from_toml_str(BASE).unwrap().profile;
    let err = Scenario::new(SensorKind::MemsAccel, p)
        .validate()
        .unwrap_err();
    assert!(err.to_string().starts_with("sensor.kind:"), "{err}");
}

#[test]
fn the_sensor_kind_reads_and_writes_by_its_text_name() {
    let sc = Scenario::from_toml_str(BASE).unwrap();
    let (_, truth) = simulate(&sc).unwrap();
    let json = serde_json::to_value(&truth).unwrap();
    assert_eq!(json["sensor"], "qma");
    let back: tcomp_sim::Truth = serde_json::from_value(json).unwrap();
    assert_eq!(back.sensor, SensorKind::Qma);
    for k in SensorKind::ALL {
        assert_eq!(SensorKind::from_name(k.name()), Some(k));
    }
}
