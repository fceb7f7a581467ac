//! Deterministic example models and input streams, shared by tests, benchmarks and the firmware
//! smoke run (whose build script encodes [`example_model`] into the blob it embeds), so every side
//! exercises the same numbers.

use crate::blob::{ColumnRoles, FeatureRange, Meta, Model, ResidualLevel, SensorKind};
use crate::compile::ProgramBuilder;
use crate::point::Point;
use crate::program::Program;
use crate::rbf::{Center, Rbf};
use heapless::Vec;

/// The RLG feature set of the seed paper: mean temperature, its rate, two thermometer gradients.
pub const RLG_SIGNALS: [&str; 1] = ["T = mean(t_anode_c, t_cathode_c, t_shell_c)"];
/// Features over [`RLG_SIGNALS`].
pub const RLG_FEATURES: [&str; 4] = [
    "T",
    "rate(T)",
    "t_anode_c - t_shell_c",
    "t_cathode_c - t_shell_c",
];

/// A small deterministic generator (xorshift32), enough for repeatable example numbers.
#[derive(Clone, Debug)]
pub struct XorShift(pub u32);

impl XorShift {
    /// Next value in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        (x >> 8) as f32 / (1u32 << 24) as f32
    }

    /// Next value in [lo, hi).
    pub fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }
}

/// The RLG example program.
pub fn rlg_program<const N: usize, const F: usize>() -> Program<'static, N, F> {
    let mut b = ProgramBuilder::<'static, N, F>::new();
    let mut ok = true;
    for line in RLG_SIGNALS.iter().chain(RLG_FEATURES.iter()) {
        ok &= b.line(line).is_ok();
    }
    let program = b.finish();
    match (ok, program) {
        (true, Ok(p)) => p,
        _ => Program::new(),
    }
}

/// An RLG model with `n_centers` (≤ C) pseudo-random Gaussian centers over the four RLG features,
/// a linear term, and ranges covering −40…60 °C.
pub fn example_model<const C: usize, const F: usize, const N: usize>(
    n_centers: usize,
    seed: u32,
) -> Model<'static, C, F, N> {
    let mut rng = XorShift(seed.max(1));
    let program = rlg_program::<N, F>();
    let nf = program.n_features();
    let lo = [-40.0, -5.0, -3.0, -3.0];
    let hi = [60.0, 5.0, 3.0, 3.0];
    let mut ranges = Vec::new();
    let mut offset = [0.0f32; F];
    let mut scale = [0.0f32; F];
    for k in 0..nf.min(4) {
        let (l, h) = (
            lo.get(k).copied().unwrap_or(0.0),
            hi.get(k).copied().unwrap_or(1.0),
        );
        let _ = ranges.push(FeatureRange { lo: l, hi: h });
        if let (Some(o), Some(s)) = (offset.get_mut(k), scale.get_mut(k)) {
            *o = 0.5 * (l + h);
            *s = 2.0 / (h - l);
        }
    }
    let mut rbf = Rbf::<C, F> {
        n_features: nf as u8,
        offset: Point(offset),
        scale: Point(scale),
        bias: 0.3,
        ..Rbf::default()
    };
    for (k, l) in rbf.linear.0.iter_mut().take(nf).enumerate() {
        *l = 0.05 * (k as f32 + 1.0);
    }
    for _ in 0..n_centers.min(C) {
        let mut c = [0.0f32; F];
        for ck in c.iter_mut().take(nf) {
            *ck = rng.uniform(-1.0, 1.0);
        }
        let sigma = rng.uniform(0.3, 0.9) as f64;
        let c64: [f64; F] = core::array::from_fn(|k| c.get(k).copied().unwrap_or(0.0) as f64);
        let w = rng.uniform(-0.5, 0.5) as f64;
        let _ = rbf
            .centers
            .push(Center::from_natural(&c64, 1.0 / (2.0 * sigma * sigma), w));
    }
    let meta = Meta {
        sensor: SensorKind::Rlg,
        axis: "x",
        unit: "deg/h",
        method: "example",
        columns: ColumnRoles {
            time: "time_s",
            target: "gyro_dph",
            reference: "ref_dph",
            reference_value: None,
        },
        trained_on: "tcomp_core::testing::example_model",
        train_samples: 0,
    };
    let residual = ResidualLevel {
        std: 0.01,
        binned_std: 0.002,
        bin_s: 100.0,
    };
    Model::new(meta, program, ranges, rbf, residual)
}

/// Thermometer readings (anode, cathode, shell) and raw gyro output of sample `n` of a synthetic
/// chamber run at `period_s`: a ramp from 20 °C at 3 °C/min with a slow anode−shell gradient.
pub fn example_sample(n: u32, period_s: f32) -> ([f32; 3], f32) {
    let t = n as f32 * period_s;
    let chamber = 20.0 + 0.05 * t;
    let shell = chamber - 0.5;
    let anode = chamber + 0.8 + 0.2 * libm::sinf(0.01 * t);
    let cathode = chamber + 0.3;
    let raw = 15.0 + 0.01 * chamber + 0.05 * (anode - shell);
    ([anode, cathode, shell], raw)
}
