//! The output side of a row: the constant reference, the pulse counter quantising the true output
//! integral, and the statistics of the noise actually drawn.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{RowMeans, round_dec};
use crate::noise::{BinnedStd, PulseCounter, Running};
use crate::scenario::Scenario;
use crate::sensor::SensorExt;

/// Statistics of the noise actually drawn.
pub(super) struct Drawn {
    pub(super) white: Running,
    pub(super) gm: Running,
    pub(super) quant: Running,
    pub(super) total: Running,
    pub(super) bin100: BinnedStd,
    pub(super) bin1000: BinnedStd,
}

impl Drawn {
    pub(super) fn new(h: f64) -> Self {
        Drawn {
            white: Running::default(),
            gm: Running::default(),
            quant: Running::default(),
            total: Running::default(),
            bin100: BinnedStd::new(100.0, h),
            bin1000: BinnedStd::new(1000.0, h),
        }
    }
}

/// The output side of one row: the pulse counter and the constant reference.
pub(super) struct Output {
    counter: PulseCounter,
    pub(super) reference: f64,
    decimals: usize,
}

impl Output {
    /// The counter's phase comes from a second generator, so it draws nothing from the main one.
    pub(super) fn new(sc: &Scenario) -> Self {
        let phase = {
            let mut r2 = ChaCha8Rng::seed_from_u64(sc.seed ^ 0x5eed_9a15_e000_0001);
            r2.random_range(0.0..1.0)
        };
        let decimals = sc.sensor.output_decimals();
        Output {
            counter: PulseCounter::new(sc.noise.pulse_weight, phase),
            reference: round_dec(sc.reference, decimals),
            decimals,
        }
    }

    /// The recorded output of a row with `bias` and the row's mean noise; the drawn noise is
    /// recorded in `drawn`.
    pub(super) fn step(&mut self, m: &RowMeans, bias: f64, h: f64, drawn: &mut Drawn) -> f64 {
        let analog = self.reference + bias + m.white + m.gm;
        let out = round_dec(self.counter.step(analog, h), self.decimals);
        let noise = out - self.reference - bias;
        drawn.white.push(m.white);
        drawn.gm.push(m.gm);
        drawn.quant.push(out - analog);
        drawn.total.push(noise);
        drawn.bin100.push(m.time, noise);
        drawn.bin1000.push(m.time, noise);
        out
    }
}
