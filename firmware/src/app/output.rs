//! What the loop sends: the output frame of one sample, each channel's value at the sensor's full
//! resolution (f64 from the exact pulse count).

use super::*;

impl<'a> App<'a> {
    /// The output frame of one sample: `records` (as [`sample`](Self::sample) wrote them, one per
    /// channel of the configuration) as [`precise_value`](Self::precise_value)s with their status
    /// words, stamped with `sequence` and `timestamp` ticks of `tick_hz`. Encode it with
    /// [`Frame::encode`].
    pub fn frame(&self, sequence: u32, timestamp: u64, tick_hz: u32, records: &[Record]) -> Frame {
        let mut outputs = [ChannelOutput::default(); FRAME_CHANNELS];
        let n = self.config.len().min(records.len()).min(FRAME_CHANNELS);
        for (k, (o, rec)) in outputs.iter_mut().zip(records).take(n).enumerate() {
            *o = ChannelOutput {
                value: self.precise_value(k, rec),
                status: rec.status,
            };
        }
        Frame::new(
            sequence,
            timestamp,
            tick_hz,
            outputs.get(..n).unwrap_or(&[]),
        )
    }

    /// Channel `k`'s output at the sensor's full resolution, for the output frame:
    /// `counts · per_pulse / interval_s − correction` in f64 from the record's exact pulse count (the
    /// f32 [`Record::compensated`] steps by 0.031 °/h at 360,000 °/h; this by 10⁻¹⁰). NaN wherever
    /// `compensated` is NaN (no valid count, a NaN correction). See [`tcomp_core::frame`] for the
    /// error bound. Not on the loop's path: the QEMU replay compares the f32 records.
    pub fn precise_value(&self, k: usize, rec: &Record) -> f64 {
        let Some(cfg) = self.config.get(k) else {
            return f64::NAN;
        };
        if rec.compensated.is_nan() || rec.periods == 0 || rec.interval_s <= 0.0 {
            return f64::NAN;
        }
        let interval = f64::from(rec.interval_s);
        f64::from(rec.counts) * f64::from(cfg.scale.per_pulse()) / interval
            - f64::from(rec.correction)
    }
}
