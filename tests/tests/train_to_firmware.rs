//! End to end across the crates: a simulated RLG chamber run is trained on the host, the blob is
//! decoded into the firmware's small model types, and both sides compensate the verification run
//! with bit-identical outputs while the error falls.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use tcomp_core::{
    Channel, FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES, HostModel, Model, Status,
};
use tcomp_sim::presets;
use tcomp_train::{Dataset, FitOptions, fit};

fn dataset(name: &str, table: tcomp_sim::Table) -> Dataset {
    Dataset::from_columns(name, table.names, table.columns)
}

#[test]
fn host_trained_blob_flies_bit_exact_in_firmware_sized_types() {
    let preset = presets::preset("rlg").unwrap();
    let (train, _) = tcomp_sim::simulate(&preset.train).unwrap();
    let (verify, truth) = tcomp_sim::simulate(&preset.verify).unwrap();
    let train = dataset("train.csv", train);
    let verify = dataset("verify.csv", verify);

    let mut opts = FitOptions::new(
        "gyro_dph",
        &[
            "T",
            "rate(T)",
            "t_anode_c - t_shell_c",
            "t_cathode_c - t_shell_c",
        ],
    );
    opts.spec
        .signals
        .push("T = mean(t_anode_c, t_cathode_c, t_shell_c)".into());
    opts.reference = Some("ref_dph".into());
    opts.centers = Some(32);
    let fitted = fit(&train, &opts).unwrap();
    let blob = fitted.model.to_bytes().unwrap();

    let host = HostModel::decode(&blob).unwrap();
    let flight = Model::<'_, FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES>::decode(&blob)
        .expect("a 32 x 4 blob fits the firmware types");
    let names = host.program.inputs.clone();
    let cols: Vec<&[f64]> = names.iter().map(|n| verify.column(n).unwrap()).collect();
    let time = verify.column("time_s").unwrap();
    let gyro = verify.column("gyro_dph").unwrap();
    let reference = verify.column("ref_dph").unwrap();

    let mut a = Channel::<48, 8>::new(1.0);
    let mut b = Channel::<FLIGHT_NODES, FLIGHT_FEATURES>::new(1.0);
    let (mut raw_err, mut res_err) = (Vec::new(), Vec::new());
    for i in 0..verify.len() {
        let inputs: Vec<f32> = cols.iter().map(|c| c[i] as f32).collect();
        let dt = if i == 0 {
            1.0
        } else {
            (time[i] - time[i - 1]) as f32
        };
        let raw = gyro[i] as f32;
        let oa = a.step_dt(Some(&host), &inputs, dt, raw);
        let ob = b.step_dt(Some(&flight), &inputs, dt, raw);
        assert_eq!(
            oa.compensated.to_bits(),
            ob.compensated.to_bits(),
            "sample {i}"
        );
        assert_eq!(oa.status, ob.status, "sample {i}");
        assert!(!oa.status.contains(Status::INPUT_FAULT));
        raw_err.push(raw as f64 - reference[i]);
        res_err.push(oa.compensated as f64 - reference[i]);
    }
    // Compare on 100 s bin means (1 s samples carry white noise no model can remove). The
    // verification profile goes where training did not (−1 °C/min down to −30 °C, +2 °C/min up): the
    // model must remove most of the temperature-induced error and come near the drawn noise floor.
    let raw_100 = binned_std(&raw_err, 100);
    let res_100 = binned_std(&res_err, 100);
    let floor = truth.noise.std_100s;
    println!("100 s bins: raw {raw_100:.4}, residual {res_100:.4}, noise floor {floor:.4} deg/h");
    assert!(res_100 < 0.2 * raw_100, "raw {raw_100}, residual {res_100}");
    assert!(
        res_100 < 2.0 * floor,
        "residual {res_100} vs noise floor {floor}"
    );
}

/// Std of the means of complete non-overlapping bins of `n` samples from the first.
fn binned_std(v: &[f64], n: usize) -> f64 {
    let means: Vec<f64> = v
        .chunks_exact(n)
        .map(|c| c.iter().sum::<f64>() / n as f64)
        .collect();
    let m = means.iter().sum::<f64>() / means.len() as f64;
    (means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / means.len() as f64).sqrt()
}
