//! The loop for a board whose channels read sample sources (a digital IMU's registers) instead of
//! pulse counters: the same thermometer handling and model step, a raw value that is the register
//! times the channel's scale.

use super::*;

impl<'a> App<'a> {
    /// One period of a configuration whose channels read sample sources (a digital IMU's
    /// registers, `registers[cfg.counter]`) instead of pulse counters: the raw value is the
    /// register times the channel's scale, a failed read NaN with [`status::SENSOR_ERROR`]; the
    /// thermometers, flags and model step do what the counter path's do (a second copy, see
    /// `sampled_step`). `precise_value` does not apply
    /// (no pulse count): the frame's value is the f32 `compensated`.
    pub fn sample_sources<T: Thermometer>(
        &mut self,
        thermometers: &mut [T],
        registers: &[Result<i32, ErrorKind>],
        out: &mut [Record],
    ) {
        self.read_thermometers(thermometers);
        for (k, rec) in out.iter_mut().take(self.config.len()).enumerate() {
            let Some(cfg) = self.config.get(k) else {
                continue;
            };
            let mut flags = 0u16;
            let raw = match registers.get(usize::from(cfg.counter)) {
                Some(Ok(v)) => *v as f32 * cfg.scale.per_pulse(),
                _ => {
                    flags |= status::SENSOR_ERROR;
                    f32::NAN
                }
            };
            let o = self.sampled_step::<T>(k, raw, &mut flags);
            *rec = Record {
                compensated: o.compensated,
                status: u16::from(o.status.0) | flags,
                correction: o.correction,
                ..Record::default()
            };
        }
    }

    /// Channel `k`'s thermometer flags and model step for the sample-source path. The counter
    /// path (`step_channel`) does the same inline. Kept apart, and generic (over the caller's
    /// thermometer type, unused) so that it is compiled only where a board instantiates
    /// `sample_sources`: a second call site of `Channel::step` compiled into this crate changes
    /// how the counter path is inlined, which cost it 50 to 350 instructions per sample under
    /// QEMU, past the 12,000 budget.
    #[allow(clippy::extra_unused_type_parameters)] // on purpose: see above
    fn sampled_step<T>(&mut self, k: usize, raw: f32, flags: &mut u16) -> tcomp_core::Output {
        let (Some(cfg), Some(channel), Some(map), Some(n)) = (
            self.config.get(k),
            self.channels.get_mut(k),
            self.input_map.get(k),
            self.n_inputs.get(k),
        ) else {
            return tcomp_core::Output {
                compensated: raw,
                correction: 0.0,
                status: tcomp_core::Status::NO_MODEL,
            };
        };
        for &(_, t) in cfg.thermometers {
            if let Some(s) = self.therms.get(usize::from(t)) {
                if s.error {
                    *flags |= status::SENSOR_ERROR;
                }
                if s.repeats >= STUCK_SAMPLES {
                    *flags |= status::STUCK;
                }
                if s.jump {
                    *flags |= status::TEMP_JUMP;
                }
            }
        }
        let mut inputs = [0.0f32; MAX_INPUTS];
        for (x, &t) in inputs.iter_mut().zip(map.iter()).take(usize::from(*n)) {
            *x = self
                .therms
                .get(usize::from(t))
                .map_or(f32::NAN, |s| s.value);
        }
        let model = self.models.get(k).and_then(Option::as_ref);
        let inputs = inputs.get(..usize::from(*n)).unwrap_or(&[]);
        channel.step(model, inputs, raw)
    }
}
