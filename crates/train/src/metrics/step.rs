//! The one loop body that steps a model over rows: [`run_model`](super::run_model) (a
//! [`Dataset`](crate::Dataset) in memory) and the streamed `eval` ([`crate::long_log`], a CSV read
//! a record at a time) differ only in where their rows come from, so both take the model's
//! flight capacity from [`in_flight_capacity`] and step it with a [`Stepper`]: the same time step,
//! gap marking, flag counts and residual, bit for bit.

use crate::blob_io::MAX_BLOB;
use crate::features::{FLIGHT_FEATURES, N};
use crate::rbf64::C;
use tcomp_core::{Channel, HostModel, Model, Status};

/// Work done on a model in whichever capacity [`in_flight_capacity`] decoded it into (a closure
/// cannot be generic over the capacity).
pub(crate) trait AtCapacity {
    /// What the work returns.
    type Output;
    /// Does the work on `model`.
    fn run<const C2: usize, const F2: usize, const N2: usize>(
        self,
        model: &Model<'_, C2, F2, N2>,
    ) -> Self::Output;
}

/// Runs `work` on `model` re-decoded from its own blob into the firmware's feature capacity
/// ([`FLIGHT_FEATURES`]) when it fits — the code path that flies, and half the work of the host's
/// 8-wide types — and on `model` as it is otherwise.
pub(crate) fn in_flight_capacity<W: AtCapacity>(model: &HostModel<'_>, work: W) -> W::Output {
    if usize::from(model.rbf.n_features) <= FLIGHT_FEATURES {
        let mut buf = vec![0u8; MAX_BLOB];
        let narrow = model
            .encode(&mut buf)
            .ok()
            .and_then(|len| buf.get(..len))
            .and_then(|b| Model::<'_, C, FLIGHT_FEATURES, N>::decode(b).ok());
        if let Some(m) = narrow {
            return work.run(&m);
        }
    }
    work.run(model)
}

/// A model stepped through a core [`Channel`] one row at a time, its flags counted.
pub(crate) struct Stepper<'m, const C2: usize, const F2: usize, const N2: usize> {
    model: &'m Model<'m, C2, F2, N2>,
    channel: Channel<N2, F2>,
    /// The previous row's time (s).
    prev: Option<f64>,
    /// Samples flagged out of the trained range.
    pub out_of_range: usize,
    /// Samples flagged as input or model faults.
    pub faults: usize,
}

impl<'m, const C2: usize, const F2: usize, const N2: usize> Stepper<'m, C2, F2, N2> {
    /// A fresh channel for `model`.
    pub(crate) fn new(model: &'m Model<'m, C2, F2, N2>) -> Self {
        Self {
            model,
            channel: Channel::new(1.0),
            prev: None,
            out_of_range: 0,
            faults: 0,
        }
    }

    /// Sets the time since power-on at the first row (s).
    pub(crate) fn set_time_on(&mut self, seconds: f32) {
        self.channel.set_time_on(seconds);
    }

    /// Steps the row at time `t` (s), after a gap when `gap`: the first row's time step is 1 s,
    /// every other row's the time since the previous one. Returns the residual, compensated −
    /// `reference`.
    pub(crate) fn step(
        &mut self,
        t: f64,
        gap: bool,
        inputs: &[f32],
        raw: f64,
        reference: f64,
    ) -> f64 {
        if gap {
            self.channel.mark_gap();
        }
        let dt = match self.prev.replace(t) {
            None => 1.0,
            Some(p) => (t - p) as f32,
        };
        let out = self
            .channel
            .step_dt(Some(self.model), inputs, dt, raw as f32);
        if out.status.contains(Status::OUT_OF_RANGE) {
            self.out_of_range += 1;
        }
        if out.status.contains(Status::INPUT_FAULT) || out.status.contains(Status::MODEL_FAULT) {
            self.faults += 1;
        }
        f64::from(out.compensated) - reference
    }
}
