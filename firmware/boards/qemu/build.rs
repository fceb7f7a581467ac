//! Links the QEMU board's binaries with this crate's `memory.x` (mps2-an386; the repository root's
//! is the STM32F407's), `device.x` (its interrupt vectors, for cortex-m-rt's `device` feature),
//! cortex-m-rt's `link.x` and defmt's `defmt.x`, and writes the smoke run's test vector.
//!
//! The vector is made here, on the host, by the same `tcomp-core` code the firmware runs: the blob
//! of an example RLG model (32 centers × 4 features) and, for each of a few hundred samples, the
//! inputs and the host's compensated output and status. The firmware replays the inputs and must
//! reproduce every output bit for bit.
// A build script's failure is the build's: `expect` stops it with its message.
#![allow(clippy::expect_used)]

use std::{env, fs, path::PathBuf};
use tcomp_core::testing::{example_model, example_sample};
use tcomp_core::{Channel, Model};

/// Samples in the smoke vector.
const SAMPLES: u32 = 400;
/// The loop period: 200 Hz.
const PERIOD_S: f32 = 0.005;

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let root =
        PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    for file in ["memory.x", "device.x"] {
        fs::copy(root.join(file), out.join(file)).expect("copy the linker scripts");
        println!("cargo:rerun-if-changed={file}");
    }
    // For this crate's binaries only. The linker reads `memory.x` from its working directory first:
    // this crate is a workspace of its own so that it is this directory, not the repository
    // root, whose `memory.x` is the STM32F407's (see Cargo.toml).
    println!("cargo:rustc-link-arg-bins=-L{}", out.display());
    println!("cargo:rerun-if-changed=build.rs");
    if env::var("TARGET").is_ok_and(|t| t.starts_with("thumb")) {
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
        println!("cargo:rustc-link-arg-bin=tcomp-qemu=-Tdefmt.x");
    }

    let model = example_model::<32, 4, 24>(32, 11);
    let mut blob = vec![0u8; 8192];
    let len = model.encode(&mut blob).expect("example model encodes");
    blob.truncate(len);
    fs::write(out.join("smoke_model.tcm"), &blob).expect("write blob");
    fs::write(out.join("smoke_additive.tcm"), additive_blob(&model)).expect("write blob");
    let (kinds, expected) = kinds_blob(&model);
    fs::write(out.join("smoke_kinds.tcm"), kinds).expect("write blob");
    fs::write(out.join("smoke_kinds_expected.bin"), expected).expect("write expected");

    let decoded = Model::<'_, 32, 4, 24>::decode(&blob).expect("example blob decodes");
    let mut channel = Channel::<24, 4>::new(PERIOD_S);
    let mut vector = Vec::new();
    for n in 0..SAMPLES {
        let (mut temps, raw) = example_sample(n, PERIOD_S);
        // Faults the firmware must flag the same way: a NaN anode reading, and an overheated shell.
        if n == 150 {
            temps[0] = f32::NAN;
        }
        if n == 300 {
            temps[2] = 95.0;
        }
        let o = channel.step(Some(&decoded), &temps, raw);
        for v in [temps[0], temps[1], temps[2], raw, o.compensated] {
            vector.extend_from_slice(&v.to_le_bytes());
        }
        vector.extend_from_slice(&u32::from(o.status.0).to_le_bytes());
    }
    fs::write(out.join("smoke_vector.bin"), &vector).expect("write vector");
}

/// The example model made additive with every kind of term (blob format 5): each center over one
/// feature, the features in turn; the even centers logistic steps and saturating ramps in turn,
/// the odd ones Gaussians, the last two a square and a cube. With it, the host's output at [`kinds_points`] (f32 bits, LE), which
/// the firmware must reproduce.
fn kinds_blob(model: &Model<'static, 32, 4, 24>) -> (Vec<u8>, Vec<u8>) {
    use tcomp_core::rbf::{KIND_CUBE, KIND_GAUSSIAN, KIND_RAMP, KIND_SQUARE, KIND_STEP};
    let mut m = model.clone();
    let nf = m.n_features();
    let n = m.rbf.centers.len();
    for j in 0..n {
        let (c, gamma, w) = m.rbf.centers[j].to_natural();
        let k = j % nf;
        let (ck, w) = (f64::from(c.0[k]), f64::from(w));
        let mut a = [0.0f64; 4];
        let kind = if j + 2 == n {
            KIND_SQUARE
        } else if j + 1 == n {
            KIND_CUBE
        } else if j % 4 == 0 {
            KIND_STEP
        } else if j % 4 == 2 {
            KIND_RAMP
        } else {
            KIND_GAUSSIAN
        };
        m.rbf.centers[j] = if kind == KIND_GAUSSIAN {
            a[k] = ck;
            tcomp_core::Center::from_natural(&a, f64::from(gamma), w)
        } else {
            // A step or a ramp as wide as the Gaussian (slope 1/σ), a power of z − c; the powers'
            // weights kept small.
            let slope = f64::from(gamma).sqrt();
            a[k] = slope;
            if kind == KIND_STEP {
                tcomp_core::Center::step_from_natural(&a, -slope * ck, w)
            } else if kind == KIND_RAMP {
                tcomp_core::Center::power_from_natural(&a, -slope * ck, w)
            } else {
                tcomp_core::Center::power_from_natural(&a, -slope * ck, 0.01 * w)
            }
        };
        m.rbf.masks.push(1 << k).expect("32 masks");
        m.rbf.kinds.push(kind).expect("32 kinds");
    }
    m.version = Model::version_for(&m.program, &m.rbf);
    let mut blob = vec![0u8; 8192];
    let len = m
        .encode(&mut blob)
        .expect("example with every kind encodes");
    blob.truncate(len);
    let expected = kinds_points(&m)
        .iter()
        .flat_map(|x| m.rbf.eval(x).to_le_bytes())
        .collect();
    (blob, expected)
}

/// Eight feature vectors across the model's range box, on its diagonal.
fn kinds_points(m: &Model<'static, 32, 4, 24>) -> Vec<[f32; 4]> {
    (0..8)
        .map(|i| {
            let mut x = [0.0f32; 4];
            for (k, r) in m.ranges.iter().enumerate().take(4) {
                x[k] = r.lo + (r.hi - r.lo) * i as f32 / 7.0;
            }
            x
        })
        .collect()
}

/// The example model made additive (blob format 3): each center over one feature, the features in
/// turn, so every center takes the masked path of the evaluator.
fn additive_blob(model: &Model<'static, 32, 4, 24>) -> Vec<u8> {
    let mut m = model.clone();
    let nf = m.n_features();
    for j in 0..m.rbf.centers.len() {
        let (c, gamma, w) = m.rbf.centers[j].to_natural();
        let k = j % nf;
        let mut cm = [0.0f64; 4];
        cm[k] = f64::from(c.0[k]);
        m.rbf.centers[j] = tcomp_core::Center::from_natural(&cm, f64::from(gamma), f64::from(w));
        m.rbf.masks.push(1 << k).expect("32 masks");
    }
    m.version = Model::version_for(&m.program, &m.rbf);
    let mut blob = vec![0u8; 8192];
    let len = m.encode(&mut blob).expect("additive example encodes");
    blob.truncate(len);
    blob
}
