//! The simulation loop: chamber air → internal temperatures → recorded columns → bias → output.
//!
//! Why one streaming loop: every quantity is produced sample by sample at the internal rate,
//! averaged into output rows on the fly and handed to a [`RowSink`], so a run of any length needs
//! only the state of its filters. Order per output row:
//!
//! 1. At each internal sample: chamber air from the profile; each location's internal temperature
//!    (exact first-order lag of the air plus self-heating); thermometer reading (plus white noise,
//!    quantised to its LSB); supply voltage (slow Gauss–Markov wander plus noise); output white noise
//!    and Gauss–Markov bias instability. All are summed over the row.
//! 2. At the end of a row: the averages are rounded to the decimals written in the file; the bias
//!    effects are evaluated from those *recorded* values with the core's streaming operators at
//!    `dt = step_s` (so the truth expressions are exact over the file); the true output integral over
//!    the row (reference + bias + noise) feeds the pulse counter; the quantised, rounded output is
//!    written, and `output − reference − bias` is the noise actually drawn. A row inside a logger
//!    dropout ([`crate::dropout`]) is computed all the same and not written.
//!
//! Parts: [`Physics`] (step 1), the effects' states (step 2's bias), `output` (the counter, the
//! reference and the statistics of the noise drawn), `record` (the truth of the finished run).

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use crate::effects::{Context, EffectState, EffectTruth, RowInputs};
use crate::error::Result;
use crate::noise::{GaussMarkov, Running};
use crate::profile::ProfileCursor;
use crate::scenario::Scenario;
use crate::sensor::SensorExt;
use crate::thermal::{FohLag, SelfHeating, ThermometerSpec, quantise};
use crate::truth::Truth;
use crate::writer::RowSink;

mod output;
mod record;

use output::{Drawn, Output};

const TIME_DECIMALS: usize = 4;
const TEMP_DECIMALS: usize = 4;
const VOLT_DECIMALS: usize = 4;

/// Rounds to `d` decimals so that the value printed with `{:.d$}` parses back to the same f64.
fn round_dec(v: f64, d: usize) -> f64 {
    let p = 10f64.powi(d as i32);
    (v * p).round() / p
}

/// Running statistics and range of one series.
struct Extremes {
    run: Running,
    lo: f64,
    hi: f64,
}

impl Extremes {
    fn new() -> Self {
        Extremes {
            run: Running::default(),
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
        }
    }
    fn push(&mut self, x: f64) {
        self.run.push(x);
        self.lo = self.lo.min(x);
        self.hi = self.hi.max(x);
    }
    fn p2p(&self) -> f64 {
        if self.hi >= self.lo {
            self.hi - self.lo
        } else {
            0.0
        }
    }
}

/// Whether `expr` uses the identifier `name`.
pub(crate) fn uses_ident(expr: &str, name: &str) -> bool {
    expr.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .any(|tok| tok == name)
}

/// The run's time grid: internal period `dt`, `k` samples per output row of length `h`.
#[derive(Clone, Copy)]
struct Grid {
    dt: f64,
    k: u64,
    h: f64,
    rows: u64,
}

/// The sums of one output row's internal samples.
struct RowSums {
    time: f64,
    air: f64,
    supply: f64,
    white: f64,
    gm: f64,
    therms: Vec<f64>,
}

/// The averages of one output row, rounded to the decimals written.
struct RowMeans {
    time: f64,
    chamber: f64,
    supply: f64,
    white: f64,
    gm: f64,
}

impl RowSums {
    fn new(nt: usize) -> Self {
        RowSums {
            time: 0.0,
            air: 0.0,
            supply: 0.0,
            white: 0.0,
            gm: 0.0,
            therms: vec![0.0; nt],
        }
    }

    fn clear(&mut self) {
        (self.time, self.air, self.supply, self.white, self.gm) = (0.0, 0.0, 0.0, 0.0, 0.0);
        self.therms.iter_mut().for_each(|s| *s = 0.0);
    }

    /// The row's averages over `k` samples; the thermometers' go to `therms`.
    fn means(&self, k: u64, therms: &mut [f64]) -> RowMeans {
        let kf = k as f64;
        for (dst, s) in therms.iter_mut().zip(&self.therms) {
            *dst = round_dec(s / kf, TEMP_DECIMALS);
        }
        RowMeans {
            time: round_dec(self.time / kf, TIME_DECIMALS),
            chamber: round_dec(self.air / kf, TEMP_DECIMALS),
            supply: round_dec(self.supply / kf, VOLT_DECIMALS),
            white: self.white / kf,
            gm: self.gm / kf,
        }
    }
}

/// The physics sampled at the internal rate: chamber air, thermometers, supply and output noise.
struct Physics<'a> {
    cursor: ProfileCursor,
    air0: f64,
    air_prev: f64,
    specs: &'a [ThermometerSpec],
    lags: Vec<FohLag>,
    decays: Vec<f64>,
    heat: Vec<SelfHeating>,
    nominal_v: f64,
    supply_noise_v: f64,
    wander: GaussMarkov,
    white_sigma: f64,
    gm: GaussMarkov,
    n: u64,
    dt: f64,
}

impl<'a> Physics<'a> {
    /// The state at power-on; draws the initial supply wander and bias instability, in that order.
    fn new(sc: &'a Scenario, dt: f64, normal: &mut impl FnMut() -> f64) -> Self {
        let mut cursor = sc.profile.cursor();
        let air0 = cursor.at(0.0);
        let th = &sc.thermometers;
        let sup = sc.supply;
        let wander = GaussMarkov::new(sup.wander_v, sup.wander_tau_s, dt, sup.wander_v * normal());
        let noise = sc.noise;
        let gm = GaussMarkov::new(
            noise.bias_instability,
            noise.correlation_s,
            dt,
            noise.bias_instability * normal(),
        );
        Physics {
            cursor,
            air0,
            air_prev: air0,
            specs: th,
            lags: th.iter().map(|t| FohLag::new(t.tau_s, air0)).collect(),
            decays: th.iter().map(|t| (-dt / t.tau_s).exp()).collect(),
            heat: th
                .iter()
                .map(|t| SelfHeating::new(t.self_heating_c, t.self_heating_tau_s, dt))
                .collect(),
            nominal_v: sup.nominal_v,
            supply_noise_v: sup.noise_v,
            wander,
            white_sigma: noise.white_std(dt),
            gm,
            n: 0,
            dt,
        }
    }

    /// One internal sample, added to `sums`. The draws per sample, in order: each thermometer's
    /// noise, the supply wander (not at power-on), the supply noise, the white output noise, the
    /// bias instability (not at power-on).
    fn sample(&mut self, sums: &mut RowSums, normal: &mut impl FnMut() -> f64) {
        let (n, dt) = (self.n, self.dt);
        let t = n as f64 * dt;
        let air = if n == 0 { self.air0 } else { self.cursor.at(t) };
        for i in 0..self.specs.len() {
            let (Some(lag), Some(sh), Some(spec), Some(decay), Some(acc)) = (
                self.lags.get_mut(i),
                self.heat.get_mut(i),
                self.specs.get(i),
                self.decays.get(i),
                sums.therms.get_mut(i),
            ) else {
                continue;
            };
            let (inside, rise) = if n == 0 {
                (lag.value(), sh.value())
            } else {
                (lag.step(self.air_prev, air, dt, *decay), sh.step())
            };
            let reading = quantise(inside + rise + spec.noise_c * normal(), spec.lsb_c);
            *acc += reading;
        }
        let v_w = if n == 0 {
            self.wander.value()
        } else {
            self.wander.step(normal())
        };
        sums.supply += self.nominal_v + v_w + self.supply_noise_v * normal();
        sums.white += self.white_sigma * normal();
        sums.gm += if n == 0 {
            self.gm.value()
        } else {
            self.gm.step(normal())
        };
        sums.time += t;
        sums.air += air;
        self.air_prev = air;
        self.n += 1;
    }
}

/// The bias effects' streaming states and the statistics of their contributions.
struct Effects {
    states: Vec<Box<dyn EffectState>>,
    truth: Vec<EffectTruth>,
    stats: Vec<Extremes>,
    bias: Extremes,
}

impl Effects {
    fn new(sc: &Scenario, ctx: &Context<'_>, h: f64) -> Result<Self> {
        Ok(Effects {
            states: sc
                .effects
                .iter()
                .map(|e| e.state(ctx, h))
                .collect::<Result<_>>()?,
            truth: sc.effects.iter().map(|e| e.truth(ctx, h)).collect(),
            stats: sc.effects.iter().map(|_| Extremes::new()).collect(),
            bias: Extremes::new(),
        })
    }

    /// The bias of one row: the sum of the effects' contributions.
    fn step(&mut self, inputs: &RowInputs<'_>, h: f64) -> f64 {
        let mut bias = 0.0;
        for (st, stats) in self.states.iter_mut().zip(self.stats.iter_mut()) {
            let c = st.step(inputs, h);
            stats.push(c);
            bias += c;
        }
        self.bias.push(bias);
        bias
    }

    /// The effects' truth entries with their contributions' statistics filled in.
    fn finish(mut self) -> (Vec<EffectTruth>, Extremes) {
        for (t, s) in self.truth.iter_mut().zip(&self.stats) {
            t.contribution_std = s.run.std();
            t.contribution_p2p = s.p2p();
        }
        (self.truth, self.bias)
    }
}

/// Writes the header: names and decimals of every column.
fn header<S: RowSink>(sc: &Scenario, sink: &mut S) -> Result<Vec<String>> {
    let columns = sc.columns();
    let out_dec = sc.sensor.output_decimals();
    let mut decimals = vec![TIME_DECIMALS, TEMP_DECIMALS];
    decimals.extend(std::iter::repeat_n(TEMP_DECIMALS, sc.thermometers.len()));
    decimals.extend([VOLT_DECIMALS, out_dec, out_dec]);
    sink.header(&columns, &decimals)?;
    Ok(columns)
}

/// Fills `row` in column order.
fn fill_row(row: &mut [f64], m: &RowMeans, therms: &[f64], out: f64, reference: f64) {
    let values = [m.time, m.chamber]
        .into_iter()
        .chain(therms.iter().copied())
        .chain([m.supply, out, reference]);
    for (slot, v) in row.iter_mut().zip(values) {
        *slot = v;
    }
}

/// Runs `sc` into `sink`; returns the truth.
pub(crate) fn run<S: RowSink>(sc: &Scenario, sink: &mut S) -> Result<Truth> {
    sc.validate()?;
    let mut rng = ChaCha8Rng::seed_from_u64(sc.seed);
    let mut normal = move || -> f64 { rng.sample(StandardNormal) };
    let dt = 1.0 / sc.rate_hz;
    let k = sc.samples_per_row();
    let grid = Grid {
        dt,
        k,
        h: k as f64 * dt,
        rows: sc.rows(),
    };
    let (names, unit) = sc.context();
    let ctx = Context {
        sensor: sc.sensor,
        therm_names: &names,
        unit,
    };
    let mut effects = Effects::new(sc, &ctx, grid.h)?;
    let mut physics = Physics::new(sc, grid.dt, &mut normal);
    let mut output = Output::new(sc);
    let columns = header(sc, sink)?;
    let mut drawn = Drawn::new(grid.h);
    let mut sums = RowSums::new(sc.thermometers.len());
    let mut therms = vec![0.0; sc.thermometers.len()];
    let mut row = vec![0.0; columns.len()];
    let mut written = 0u64;
    for _ in 0..grid.rows {
        sums.clear();
        for _ in 0..grid.k {
            physics.sample(&mut sums, &mut normal);
        }
        let m = sums.means(grid.k, &mut therms);
        let inputs = RowInputs {
            time_s: m.time,
            therms: &therms,
            supply_v: m.supply,
        };
        let bias = effects.step(&inputs, grid.h);
        let out = output.step(&m, bias, grid.h, &mut drawn);
        // A logger dropout loses the row; everything above ran on.
        if crate::dropout::hidden(&sc.dropouts, m.time) {
            continue;
        }
        written += 1;
        fill_row(&mut row, &m, &therms, out, output.reference);
        sink.row(&row)?;
    }
    sink.finish()?;
    Ok(record::truth(
        sc,
        &ctx,
        Grid {
            rows: written,
            ..grid
        },
        columns,
        effects,
        drawn,
        output.reference,
    ))
}
