//! Blobs, images and channel storage for the C API's tests, made with the core's own writers.
#![allow(dead_code, unsafe_code, clippy::unwrap_used, clippy::expect_used)]

use std::mem::MaybeUninit;
use tcomp_core::SensorKind;
use tcomp_core::image::{
    ChannelRow, Entry, ImageSpec, Input, MAX_ROW_INPUTS, Provenance, Source, ThermKind, Thermometer,
};
use tcomp_core::testing::example_model;
use tcomp_core::{FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES, HOST_CENTERS, Model};
use tcomp_ffi::TcompChannel;

/// The core's example RLG model (mean of three thermometers, its rate, two gradients; 32
/// centers) at the flight capacities, encoded.
pub fn example_blob(seed: u32) -> Vec<u8> {
    let model = example_model::<FLIGHT_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES>(32, seed);
    encode(&model)
}

/// A valid model with more centers than the C API's capacity.
pub fn too_big_blob() -> Vec<u8> {
    let model = example_model::<HOST_CENTERS, FLIGHT_FEATURES, FLIGHT_NODES>(HOST_CENTERS, 5);
    encode(&model)
}

fn encode<const C: usize, const F: usize, const N: usize>(m: &Model<'_, C, F, N>) -> Vec<u8> {
    let mut buf = vec![0u8; 16384];
    let n = m.encode(&mut buf).unwrap();
    buf.truncate(n);
    buf
}

/// The board of the image tests: the example model's three RLG thermometers and a spare one.
pub fn thermometers() -> Vec<Thermometer<'static>> {
    let pt1000 = ThermKind::Rtd {
        r0: 1000.0,
        a: 3.9083e-3,
        b: -5.775e-7,
    };
    ["spare", "x-anode", "x-cathode", "x-shell"]
        .iter()
        .enumerate()
        .map(|(i, &name)| Thermometer {
            name,
            adc: 0,
            input: i as u8,
            kind: pt1000,
        })
        .collect()
}

/// An RLG row for the example model (`axis`), its inputs on thermometers 3, 1, 2 in the order
/// shell, anode, cathode (not the model's order, so the wiring's mapping is visible).
pub fn rlg_row(id: u16, axis: &'static str) -> ChannelRow<'static> {
    let mut inputs = [Input::default(); MAX_ROW_INPUTS];
    for (slot, (name, t)) in
        inputs
            .iter_mut()
            .zip([("t_shell_c", 3), ("t_anode_c", 1), ("t_cathode_c", 2)])
    {
        *slot = Input {
            name,
            thermometer: t,
        };
    }
    ChannelRow {
        id,
        name: "rlg",
        sensor: SensorKind::Rlg,
        axis,
        unit: "deg/h",
        source: Source::Counter(4),
        scale: 2.5e-5,
        inputs,
        n_inputs: 3,
    }
}

/// A version-2 image for unit `serial` with `blob` on channel 3 (row axis `x`), and the same
/// blob on channel 9 whose row says axis `y` (a blob on the wrong channel).
pub fn image(serial: u64, blob: &[u8]) -> (Vec<u8>, u64) {
    let therms = thermometers();
    let rows = [rlg_row(3, "x"), rlg_row(9, "y")];
    let prov = Provenance {
        data: "train.csv",
        data_hash: 1,
        window: [0.0, 100.0],
        method: "bayes",
    };
    let entries = [
        Entry {
            channel: 3,
            blob,
            provenance: prov,
        },
        Entry {
            channel: 9,
            blob,
            provenance: prov,
        },
    ];
    let spec = ImageSpec {
        serial,
        created: 1_763_900_000,
        tool: "test",
        thermometers: &therms,
        channels: &rows,
        entries: &entries,
    };
    let mut buf = vec![0u8; spec.image_len().unwrap()];
    let n = spec.write(&mut buf).unwrap();
    buf.truncate(n);
    (buf, spec.board_hash())
}

/// Caller storage for one channel, as a C caller would declare it.
pub struct Storage(Box<MaybeUninit<TcompChannel>>);

impl Storage {
    pub fn new() -> Self {
        // Zeroed, not uninitialised: the tests read the storage before any initialiser (as the
        // magic check does), which Rust allows only for initialised bytes.
        Self(Box::new(MaybeUninit::zeroed()))
    }

    pub fn ptr(&mut self) -> *mut TcompChannel {
        self.0.as_mut_ptr()
    }
}

/// `buf` up to its NUL as a string.
pub fn text(buf: &[u8]) -> String {
    let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
    String::from_utf8_lossy(&buf[..end]).into_owned()
}
