//! The compensation loop's application logic, independent of the board it runs on.
//!
//! Once per period the loop reads every thermometer and pulse counter of the configuration through the
//! [`tcomp_hal`] traits, then steps each channel's compensator and emits one [`Record`] per channel:
//! the compensated rate or acceleration and a [`status`] word. Nothing here touches hardware, so
//! the host runs exactly this code over the replay vector to produce the outputs the QEMU run must
//! reproduce bit for bit.
//!
//! Fault handling, per sample, never a panic:
//! * a thermometer read that fails (bus error, open sensor, …) feeds NaN to the channels that use
//!   it: the core holds the last good features and flags `INPUT_FAULT`; the loop adds
//!   [`status::SENSOR_ERROR`];
//! * a thermometer returning the very same bits for [`STUCK_SAMPLES`] samples flags
//!   [`status::STUCK`] (a 24-bit ADC on a live sensor never does);
//! * a counter read that fails on the bus gives a NaN raw value (flagged); the pulses are not lost,
//!   the next good read covers the missed periods and is divided by their total length;
//! * a counter interval the hardware flags (pulses lost, instrument or clock fault) was consumed: that
//!   sample's raw value is NaN with [`status::SENSOR_ERROR`], and the next interval is one period
//!   again ([`tcomp_hal::Interval`] tells the two apart);
//! * the rate divides the counts by the interval the counter block's own timestamp latched with
//!   them ([`CounterSnapshot::read_snapshot`]) when it is within [`INTERVAL_TOLERANCE`] of the
//!   nominal periods it covers; otherwise by the nominal periods, flagged [`status::TIME_JUMP`];
//! * timer periods the board missed altogether (an overrun longer than a period) are announced
//!   with [`App::skip_periods`]: the next interval covers them, as after a bus error, and for the
//!   feature programs they are a gap, which the core carries the filters across as it does a
//!   logger dropout on the host ([`tcomp_core::Channel::skip`]) — the same code, on the gap
//!   sample only;
//! * a channel whose blob is missing, corrupt or reads inputs it is not wired to runs with
//!   `NO_MODEL`: raw value passed through, flagged.

use tcomp_core::frame::{ChannelOutput, Frame, MAX_CHANNELS as FRAME_CHANNELS};
use tcomp_core::{Channel, MAX_INPUTS, Model};
use tcomp_hal::scale::ChannelScale;
use tcomp_hal::{CounterSnapshot, ErrorKind, Interval, PulseCounter, Thermometer};

/// Centers per model in the firmware (the core's [`tcomp_core::FLIGHT_CENTERS`], which the host
/// tools check blobs against).
pub const CENTERS: usize = tcomp_core::FLIGHT_CENTERS;
/// Features per model in the firmware.
pub const FEATURES: usize = tcomp_core::FLIGHT_FEATURES;
/// Feature-program nodes per model in the firmware.
pub const NODES: usize = tcomp_core::FLIGHT_NODES;
/// A model as the firmware holds it: numbers in RAM, strings borrowed from the image in flash.
pub type FwModel<'a> = Model<'a, CENTERS, FEATURES, NODES>;
/// One channel's streaming state.
pub type FwChannel = Channel<NODES, FEATURES>;

/// The loop period: 200 Hz.
pub const PERIOD_S: f32 = 0.005;
/// Largest relative deviation of a latched interval from the nominal periods it covers that is
/// still believed. The sample timer and the counter block's timestamp clock are crystals (tens of
/// ppm) and the latch is a hardware edge, so a healthy interval is within 0.1 % of nominal even
/// with a microsecond of latch jitter; 10 % (500 µs of a 5 ms period) leaves room for a board
/// that latches from its interrupt rather than the timer's trigger output, yet is far below what
/// a real fault looks like: a period gained or lost without being counted (±100 % of one
/// period, ±50 % of two), a glitch of the timestamp counter (half a period in the QEMU run), a
/// clock switch. Outside it the interval is not known, so the nominal one is used and flagged.
pub const INTERVAL_TOLERANCE: f32 = 0.1;
/// Identical readings in a row that mark a thermometer as stuck (2 s at 200 Hz).
pub const STUCK_SAMPLES: u16 = 400;
/// Most thermometers a configuration reads.
pub const MAX_THERMOMETERS: usize = 12;
/// Most pulse counters a configuration reads.
pub const MAX_COUNTERS: usize = 6;
/// Most channels a configuration has.
pub const MAX_CHANNELS: usize = 6;
/// Largest rate of change a thermometer bonded to an instrument can show, °C/s. The thermal time
/// constants of the instruments are a minute (a QMA's package) to tens of minutes (an RLG block, a
/// fibre coil); even a 100 °C step of the surroundings moves a part with τ ≥ 60 s by at most
/// 100/60 ≈ 1.7 °C/s. 5 °C/s is three times that.
pub const MAX_TEMP_RATE_C_PER_S: f32 = 5.0;
/// Change between two readings allowed on top of [`MAX_TEMP_RATE_C_PER_S`], °C: an ADS1220 at
/// 20 SPS delivers a new conversion every 50 ms (10 loop periods), so a reading moves in steps of up
/// to 50 ms of drift (0.25 °C at the maximum rate) plus the converter's noise (~0.01 °C on a PT1000).
pub const TEMP_STEP_MARGIN_C: f32 = 0.5;

/// The status word of one output: the core's [`tcomp_core::Status`] bits plus the loop's own, defined
/// once with their names in [`tcomp_core::frame::status`] (the frame carries this word).
pub mod status {
    pub use tcomp_core::frame::status::{
        FIRST_SAMPLE, INPUT_FAULT, MODEL_FAULT, NO_MODEL, OK, OUT_OF_RANGE, OVERRUN, SENSOR_ERROR,
        STUCK, TEMP_JUMP, TIME_JUMP, WATCHDOG_RESET,
    };
}

/// One channel of a configuration: which thermometers (by the model's input column names) and which
/// counter it reads, and how counts become its output unit.
#[derive(Clone, Copy, Debug)]
pub struct ChannelConfig {
    /// Channel id, the key of its blob in the image.
    pub id: u16,
    /// Short name for logs.
    pub name: &'static str,
    /// `(input column name, thermometer index)`.
    pub thermometers: &'static [(&'static str, u8)],
    /// Counter index.
    pub counter: u8,
    /// Scale factor of the counter.
    pub scale: ChannelScale,
}

/// Arcsec per pulse of the replayed RLG counters (a fine interpolating read-out, so the replayed
/// rate is not dominated by quantisation).
pub const RLG_ARCSEC_PER_PULSE: f32 = 1.0e-5;
/// µg per Hz of the replayed QMA current-to-frequency converters.
pub const QMA_UG_PER_HZ: f32 = 0.01;

/// The strapdown IMU of `firmware/descriptions/imu6-rlg-qma.toml` (generated, see
/// [`crate::wiring`]): three RLGs (anode, cathode, shell thermometers each) and three QMAs (one
/// each). Thermometers 0–8 are the RLGs', 9–11 the QMAs'; counters 0–2 the RLGs', 3–5 the QMAs'.
pub const IMU6: [ChannelConfig; 6] = crate::wiring::IMU6_RLG_QMA;

/// A single fiber-optic gyro with its coil thermometer: `firmware/descriptions/ifog1.toml`
/// (channel 0, `ifog-x`, as the triad's first channel), whose image the QEMU run loads.
pub const IFOG1: [ChannelConfig; 1] = crate::wiring::IFOG1;

/// One output of one channel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Record {
    /// Compensated rate (°/h) or acceleration (µg); the raw value when there is no model.
    pub compensated: f32,
    /// [`status`] bits.
    pub status: u16,
    /// The model's correction that was subtracted (0 without a model).
    pub correction: f32,
    /// The exact pulse count of the interval …
    pub counts: i32,
    /// … and its length in loop periods (0: no valid count this sample) …
    pub periods: u16,
    /// … and in seconds, as the rate was computed: the latched interval, or the nominal periods
    /// when there is none or it is implausible (0: no valid count).
    pub interval_s: f32,
}

/// One counter's valid pulses this sample and the time they cover.
#[derive(Clone, Copy, Debug)]
struct Pulses {
    counts: i32,
    periods: u16,
    interval_s: f32,
    /// The latched interval was implausible: `interval_s` is the nominal one.
    time_jump: bool,
}

#[derive(Clone, Copy, Debug, Default)]
struct ThermState {
    value: f32,
    last_bits: u32,
    repeats: u16,
    error: bool,
    /// The last reading accepted as plausible (NaN before the first), and the periods since.
    good: f32,
    since_good: u16,
    jump: bool,
}

impl ThermState {
    const NEW: Self = Self {
        value: 0.0,
        last_bits: 0,
        repeats: 0,
        error: false,
        good: f32::NAN,
        since_good: 0,
        jump: false,
    };
}

/// The loop for a configuration of up to [`MAX_CHANNELS`] channels (one type for every
/// configuration, so the firmware carries one copy of the code).
pub struct App<'a> {
    config: &'static [ChannelConfig],
    models: [Option<FwModel<'a>>; MAX_CHANNELS],
    /// For each channel, model input `i` reads thermometer `map[i]`.
    input_map: [[u8; MAX_INPUTS]; MAX_CHANNELS],
    n_inputs: [u8; MAX_CHANNELS],
    channels: [FwChannel; MAX_CHANNELS],
    therms: [ThermState; MAX_THERMOMETERS],
    missed: [u16; MAX_COUNTERS],
}

impl<'a> App<'a> {
    /// The loop with no models yet; channels past [`MAX_CHANNELS`] are ignored. `const`, so a board
    /// can keep the loop in a `static` (about 11 KB on thumbv7em) without building it on the stack.
    ///
    /// Every channel evaluates its model on every sample (200 Hz). Evaluating only on a new
    /// thermometer conversion (every 50 ms at 20 SPS) would not lower the worst case: the ADCs
    /// convert asynchronously to the sample timer, so all six channels can see a new conversion in
    /// the same period, and the budget must hold for that period anyway. It would lower only the
    /// mean, which does not matter at 1–2 % of a 168 MHz M4F, and it would couple the correction's
    /// timing to the ADCs' phase. At full rate the correction also follows the rate features, which
    /// the feature program updates every period.
    pub const fn new(config: &'static [ChannelConfig]) -> Self {
        let config = if config.len() > MAX_CHANNELS {
            config.split_at(MAX_CHANNELS).0
        } else {
            config
        };
        Self {
            config,
            models: [const { None }; MAX_CHANNELS],
            input_map: [[0; MAX_INPUTS]; MAX_CHANNELS],
            n_inputs: [0; MAX_CHANNELS],
            channels: [const { Channel::new(PERIOD_S) }; MAX_CHANNELS],
            therms: [ThermState::NEW; MAX_THERMOMETERS],
            missed: [0; MAX_COUNTERS],
        }
    }

    /// Back to the state of [`App::new`]`(config)`, in place (no `App` on the stack): a board with
    /// the loop in a `static` calls this at boot with the configuration it found.
    pub fn reset(&mut self, config: &'static [ChannelConfig]) {
        self.config = config.get(..MAX_CHANNELS).unwrap_or(config);
        for m in &mut self.models {
            *m = None;
        }
        self.input_map = [[0; MAX_INPUTS]; MAX_CHANNELS];
        self.n_inputs = [0; MAX_CHANNELS];
        for c in &mut self.channels {
            c.reset();
        }
        self.therms = [ThermState::NEW; MAX_THERMOMETERS];
        self.missed = [0; MAX_COUNTERS];
    }

    /// The configuration.
    pub fn config(&self) -> &'static [ChannelConfig] {
        self.config
    }

    /// One period with one [`PulseCounter`] per counter: read all sensors, step all channels, write
    /// one record per channel into `out` (as many as both have). Each counter error is classified by
    /// its kind ([`Interval::from_result`]): a flagged interval was consumed, a bus error was not.
    pub fn sample<T: Thermometer, P: PulseCounter>(
        &mut self,
        thermometers: &mut [T],
        counters: &mut [P],
        out: &mut [Record],
    ) {
        self.read_thermometers(thermometers);
        let mut intervals = [Interval::Unread(ErrorKind::NotReady); MAX_COUNTERS];
        for (c, i) in counters.iter_mut().zip(intervals.iter_mut()) {
            *i = Interval::from_result(c.read_delta());
        }
        let n = counters.len().min(MAX_COUNTERS);
        self.step_all(intervals.get(..n).unwrap_or(&[]), None, out);
    }

    /// One period with a counter block latched once for all channels ([`CounterSnapshot`]: one SPI
    /// frame, every instrument at the same instant): read all sensors, step all channels, write one
    /// record per channel into `out` (as many as both have). Counter `i` of the configuration is
    /// channel `i` of the block. The counters are latched first, a fixed latency after the timer
    /// edge that started the period, and the thermometers read after. The rates divide by the
    /// interval the block latched with the counts when it is plausible (see
    /// [`INTERVAL_TOLERANCE`]); otherwise by the nominal periods, flagged [`status::TIME_JUMP`].
    pub fn sample_snapshot<T: Thermometer, C: CounterSnapshot>(
        &mut self,
        thermometers: &mut [T],
        counters: &mut C,
        out: &mut [Record],
    ) {
        let mut intervals = [Interval::Unread(ErrorKind::NotReady); MAX_COUNTERS];
        let latched = counters.read_snapshot(&mut intervals);
        self.read_thermometers(thermometers);
        self.step_all(&intervals, latched, out);
    }

    /// `n` whole timer periods passed without a sample (the sample interrupt was held off for
    /// longer than a period): the counters kept counting, so the next read of every counter covers
    /// them too and its rate is computed over all of them, and every channel's next step covers
    /// them as a gap in its feature program's input ([`tcomp_core::Channel::skip`]). Never merged
    /// silently: the board flags the next frame ([`status::OVERRUN`]).
    pub fn skip_periods(&mut self, n: u16) {
        if n == 0 {
            return;
        }
        for m in &mut self.missed {
            *m = m.saturating_add(n);
        }
        let skipped = PERIOD_S * f32::from(n);
        for c in &mut self.channels {
            c.skip(skipped);
        }
    }

    fn read_thermometers<T: Thermometer>(&mut self, thermometers: &mut [T]) {
        for (t, s) in thermometers.iter_mut().zip(self.therms.iter_mut()) {
            s.since_good = s.since_good.saturating_add(1);
            s.jump = false;
            match t.read_celsius() {
                Ok(v) => {
                    let bits = v.to_bits();
                    s.repeats = if bits == s.last_bits {
                        s.repeats.saturating_add(1)
                    } else {
                        0
                    };
                    s.last_bits = bits;
                    s.error = false;
                    s.value = v;
                    if v.is_finite() {
                        if plausible_step(s.good, v, s.since_good) {
                            s.good = v;
                            s.since_good = 0;
                        } else {
                            // Implausible within range: held like a failed read, flagged.
                            s.value = f32::NAN;
                            s.jump = true;
                        }
                    }
                }
                Err(_) => {
                    s.value = f32::NAN;
                    s.error = true;
                }
            }
        }
    }

    /// Turns each counter's interval into counts and the time they cover (`latched`: the
    /// snapshot's own measure of it, seconds), then steps every channel.
    fn step_all(&mut self, intervals: &[Interval], latched: Option<f32>, out: &mut [Record]) {
        // Counts and the interval they cover (longer after unread intervals); `None` when there is
        // no valid count this period.
        let mut pulses = [None; MAX_COUNTERS];
        for ((i, p), missed) in intervals.iter().zip(&mut pulses).zip(&mut self.missed) {
            match *i {
                Interval::Counted(counts) => {
                    let periods = missed.saturating_add(1);
                    let nominal = PERIOD_S * f32::from(periods);
                    let (interval_s, time_jump) = match latched {
                        Some(t) if plausible_interval(t, periods) => (t, false),
                        Some(_) => (nominal, true),
                        None => (nominal, false),
                    };
                    *p = Some(Pulses {
                        counts,
                        periods,
                        interval_s,
                        time_jump,
                    });
                    *missed = 0;
                }
                // Consumed: those pulses are gone, the next interval is one period.
                Interval::Flagged(_) => *missed = 0,
                // Still in the counter: the next good read covers this period too.
                Interval::Unread(_) => *missed = missed.saturating_add(1),
            }
        }
        for (k, rec) in out.iter_mut().take(self.config.len()).enumerate() {
            *rec = self.step_channel(k, &pulses);
        }
    }

    fn step_channel(&mut self, k: usize, pulses: &[Option<Pulses>; MAX_COUNTERS]) -> Record {
        let (Some(cfg), Some(channel), Some(map), Some(n)) = (
            self.config.get(k),
            self.channels.get_mut(k),
            self.input_map.get(k),
            self.n_inputs.get(k),
        ) else {
            return Record::default();
        };
        let mut flags = 0u16;
        let pulses = pulses.get(usize::from(cfg.counter)).copied().flatten();
        let raw = match pulses {
            Some(p) => {
                if p.time_jump {
                    flags |= status::TIME_JUMP;
                }
                cfg.scale.rate(p.counts, p.interval_s).unwrap_or(f32::NAN)
            }
            None => {
                flags |= status::SENSOR_ERROR;
                f32::NAN
            }
        };
        let (counts, periods, interval_s) =
            pulses.map_or((0, 0, 0.0), |p| (p.counts, p.periods, p.interval_s));
        for &(_, t) in cfg.thermometers {
            if let Some(s) = self.therms.get(usize::from(t)) {
                if s.error {
                    flags |= status::SENSOR_ERROR;
                }
                if s.repeats >= STUCK_SAMPLES {
                    flags |= status::STUCK;
                }
                if s.jump {
                    flags |= status::TEMP_JUMP;
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
        let o = channel.step(model, inputs, raw);
        Record {
            compensated: o.compensated,
            status: u16::from(o.status.0) | flags,
            correction: o.correction,
            counts,
            periods,
            interval_s,
        }
    }
}

/// Whether a thermometer may have moved from its last plausible reading `good` to `v` in `periods`
/// loop periods: at most [`TEMP_STEP_MARGIN_C`] plus [`MAX_TEMP_RATE_C_PER_S`] times the time
/// elapsed. The allowance grows while readings are refused, so a real step of the sensor (or a
/// reading that stays wrong) is accepted again after the time the physics needs to get there
/// (a 3 °C step: 0.5 s); a spike is refused for its whole length. No reference yet: plausible.
pub fn plausible_step(good: f32, v: f32, periods: u16) -> bool {
    let allowed = TEMP_STEP_MARGIN_C + MAX_TEMP_RATE_C_PER_S * PERIOD_S * f32::from(periods);
    good.is_nan() || (v - good).abs() <= allowed
}

/// Whether a latched interval of `latched` seconds may be the `periods` loop periods it is meant
/// to cover: within [`INTERVAL_TOLERANCE`] of their nominal length (false for NaN).
pub fn plausible_interval(latched: f32, periods: u16) -> bool {
    let nominal = PERIOD_S * f32::from(periods);
    (latched - nominal).abs() <= INTERVAL_TOLERANCE * nominal
}

mod load;
mod output;
mod sources;

pub use load::LoadError;

#[cfg(test)]
#[path = "app_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "load_tests.rs"]
mod load_tests;
