//! Shared by the `fuzz_blobs` test (≥ 100,000 cases per property in every `cargo test`) and the
//! `fuzz_blobs` example (the long run): blob generators and the properties an accepted model must
//! satisfy.
//!
//! Blobs come from two sources:
//! * **structured**: a valid example model whose fields are set to extreme values (0, ±tiny, ±huge,
//!   NaN, ±inf, ±f32::MAX, sign flips, scalings), whose lists get the wrong length, or whose bytes
//!   get a bad enum tag, then written with postcard and sealed with a **valid** CRC by hand
//!   (bypassing `Model::encode`, which would refuse most of them), so the decoder's structure,
//!   value and plausibility checks are what is tested, not the checksum;
//! * **raw**: random bytes behind a valid magic and version, and bit-flipped valid blobs, each
//!   resealed.
//!
//! Every accepted model is then run: `Rbf::eval_split` at random points of, and at the corners of,
//! its range box must stay within the plausibility bound, and `Channel::step` on inputs inside, at the
//! edge of and far outside the range box, NaN and ±inf, must never give a non-finite output without a
//! fault bit, never a non-finite output with `Status::OK`, a correction within the bound, and no
//! model fault for a raw value of a real sensor's magnitude.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use proptest::prelude::*;
use tcomp_core::blob::{FORMAT_VERSION, MAGIC, crc32};
use tcomp_core::testing::example_model;
use tcomp_core::{
    BlobError, Channel, FeatureRange, HOST_CENTERS, HOST_FEATURES, HOST_NODES, Model, Status,
};

/// The host's model type.
pub use tcomp_core::HostModel;
/// The reference firmware's model types.
pub type FlightModel<'a> = Model<'a, 32, 4, 16>;

/// Largest blob written here.
pub const BUF: usize = 8192;

/// A numeric field of the model.
#[derive(Clone, Copy, Debug)]
pub enum Field {
    /// `rbf.bias`.
    Bias,
    /// `rbf.linear[k]`.
    Linear(usize),
    /// `rbf.offset[k]`.
    Offset(usize),
    /// `rbf.scale[k]`.
    Scale(usize),
    /// `ranges[k].lo`.
    RangeLo(usize),
    /// `ranges[k].hi`.
    RangeHi(usize),
    /// `centers[j].p`.
    P(usize),
    /// `centers[j].g`.
    G(usize),
    /// `centers[j].w`.
    W(usize),
    /// `centers[j].q[k]`.
    Q(usize, usize),
    /// Every center's `w`.
    AllW,
    /// `residual.std`.
    ResidualStd,
    /// `meta.columns.reference_value`.
    ReferenceValue,
}

/// What a field is set to.
#[derive(Clone, Copy, Debug)]
pub enum Value {
    /// An extreme constant.
    Const(f32),
    /// `−v`.
    Negate,
    /// `v·10^e`.
    Times10(i8),
    /// `v + d`.
    Plus(f32),
}

/// One edit of a valid model or of its bytes.
#[derive(Clone, Copy, Debug)]
pub enum Mutation {
    /// A numeric field set.
    Set(Field, Value),
    /// `rbf.n_features` set.
    NFeatures(u8),
    /// One more range than features.
    PushRange,
    /// One range fewer.
    PopRange,
    /// One center fewer.
    PopCenter,
    /// A center duplicated.
    DupCenter(usize),
    /// The sensor kind's tag (byte 5 of the blob) set.
    SensorTag(u8),
    /// A byte of the serialized model (before the CRC) XORed, the CRC then recomputed.
    FlipByte(usize, u8),
    /// The serialized model cut short (before the CRC), the CRC then recomputed.
    Truncate(usize),
}

fn extreme() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(0.0f32),
        Just(-0.0f32),
        Just(1.0e-40f32),
        Just(-1.0e-40f32),
        Just(1.0e-30f32),
        Just(-1.0e-30f32),
        Just(1.0e30f32),
        Just(-1.0e30f32),
        Just(3.2e38f32),
        Just(1.0e-7f32),
        Just(f32::MAX),
        Just(-f32::MAX),
        Just(f32::MIN_POSITIVE),
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(1.0e11f32),
        Just(-1.0e11f32),
        any::<f32>(),
        -1.0e3f32..1.0e3f32,
    ]
}

fn value() -> impl Strategy<Value = Value> {
    prop_oneof![
        4 => extreme().prop_map(Value::Const),
        2 => Just(Value::Negate),
        3 => (-40i8..=40).prop_map(Value::Times10),
        1 => (-10.0f32..10.0).prop_map(Value::Plus),
    ]
}

fn field() -> impl Strategy<Value = Field> {
    let k = 0usize..8;
    let j = 0usize..64;
    prop_oneof![
        Just(Field::Bias),
        k.clone().prop_map(Field::Linear),
        k.clone().prop_map(Field::Offset),
        k.clone().prop_map(Field::Scale),
        k.clone().prop_map(Field::RangeLo),
        k.clone().prop_map(Field::RangeHi),
        j.clone().prop_map(Field::P),
        j.clone().prop_map(Field::G),
        j.clone().prop_map(Field::W),
        (j, k).prop_map(|(j, k)| Field::Q(j, k)),
        Just(Field::AllW),
        Just(Field::ResidualStd),
        Just(Field::ReferenceValue),
    ]
}

/// One mutation.
pub fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        12 => (field(), value()).prop_map(|(f, v)| Mutation::Set(f, v)),
        1 => any::<u8>().prop_map(Mutation::NFeatures),
        1 => Just(Mutation::PushRange),
        1 => Just(Mutation::PopRange),
        1 => Just(Mutation::PopCenter),
        1 => (0usize..64).prop_map(Mutation::DupCenter),
        1 => (5u8..=255).prop_map(Mutation::SensorTag),
        2 => (any::<usize>(), 1u8..=255).prop_map(|(i, x)| Mutation::FlipByte(i, x)),
        1 => any::<usize>().prop_map(Mutation::Truncate),
    ]
}

/// A structured case: which example model, and up to four edits.
pub fn structured_case() -> impl Strategy<Value = (usize, u32, Vec<Mutation>)> {
    (
        1usize..=40,
        1u32..u32::MAX,
        proptest::collection::vec(mutation(), 1..=4),
    )
}

fn apply_value(v: f32, val: Value) -> f32 {
    match val {
        Value::Const(c) => c,
        Value::Negate => -v,
        Value::Times10(e) => v * 10f32.powi(i32::from(e)),
        Value::Plus(d) => v + d,
    }
}

fn set(model: &mut HostModel<'static>, f: Field, val: Value) {
    let rbf = &mut model.rbf;
    let n = rbf.centers.len().max(1);
    let slot: Option<&mut f32> = match f {
        Field::Bias => Some(&mut rbf.bias),
        Field::Linear(k) => rbf.linear.0.get_mut(k),
        Field::Offset(k) => rbf.offset.0.get_mut(k),
        Field::Scale(k) => rbf.scale.0.get_mut(k),
        Field::RangeLo(k) => model.ranges.get_mut(k).map(|r| &mut r.lo),
        Field::RangeHi(k) => model.ranges.get_mut(k).map(|r| &mut r.hi),
        Field::P(j) => rbf.centers.get_mut(j % n).map(|c| &mut c.p),
        Field::G(j) => rbf.centers.get_mut(j % n).map(|c| &mut c.g),
        Field::W(j) => rbf.centers.get_mut(j % n).map(|c| &mut c.w),
        Field::Q(j, k) => rbf.centers.get_mut(j % n).and_then(|c| c.q.0.get_mut(k)),
        Field::AllW => {
            for c in rbf.centers.iter_mut() {
                c.w = apply_value(c.w, val);
            }
            None
        }
        Field::ResidualStd => Some(&mut model.residual.std),
        Field::ReferenceValue => {
            let v = model.meta.columns.reference_value.unwrap_or(1.0);
            model.meta.columns.reference_value = Some(apply_value(v, val));
            None
        }
    };
    if let Some(s) = slot {
        *s = apply_value(*s, val);
    }
}

/// Writes `model` with postcard and a valid CRC, bypassing `Model::encode`'s validation, and applies
/// the byte-level edits. Returns the blob, or `None` when postcard cannot write it.
pub fn seal(model: &HostModel<'static>, byte_edits: &[Mutation]) -> Option<Vec<u8>> {
    let mut buf = vec![0u8; BUF];
    let used = postcard::to_slice(model, &mut buf).ok()?.len();
    buf.truncate(used);
    for m in byte_edits {
        match *m {
            Mutation::SensorTag(t) => {
                if let Some(b) = buf.get_mut(5) {
                    *b = t;
                }
            }
            Mutation::FlipByte(i, x) => {
                let len = buf.len().max(1);
                if let Some(b) = buf.get_mut(i % len) {
                    *b ^= x;
                }
            }
            Mutation::Truncate(i) => {
                let len = buf.len().max(1);
                buf.truncate(i % len);
            }
            _ => {}
        }
    }
    let crc = crc32(&buf);
    buf.extend_from_slice(&crc.to_le_bytes());
    Some(buf)
}

/// The blob of a structured case.
pub fn structured_blob(n_centers: usize, seed: u32, edits: &[Mutation]) -> Option<Vec<u8>> {
    let mut model = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(n_centers, seed);
    for m in edits {
        match *m {
            Mutation::Set(f, v) => set(&mut model, f, v),
            Mutation::NFeatures(n) => model.rbf.n_features = n,
            Mutation::PushRange => {
                let _ = model.ranges.push(FeatureRange { lo: 0.0, hi: 1.0 });
            }
            Mutation::PopRange => {
                model.ranges.pop();
            }
            Mutation::PopCenter => {
                model.rbf.centers.pop();
            }
            Mutation::DupCenter(j) => {
                let n = model.rbf.centers.len().max(1);
                if let Some(c) = model.rbf.centers.get(j % n).copied() {
                    let _ = model.rbf.centers.push(c);
                }
            }
            _ => {}
        }
    }
    seal(&model, edits)
}

/// Random bytes behind a valid magic and version, sealed with a valid CRC.
pub fn raw_blob(body: &[u8]) -> Vec<u8> {
    let mut v = MAGIC.to_vec();
    v.push(FORMAT_VERSION as u8);
    v.extend_from_slice(body);
    let crc = crc32(&v);
    v.extend_from_slice(&crc.to_le_bytes());
    v
}

/// A valid blob with bits flipped at `flips` (positions modulo the length), resealed or not.
pub fn flipped_blob(n_centers: usize, seed: u32, flips: &[(usize, u8)], reseal: bool) -> Vec<u8> {
    let model = example_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(n_centers, seed);
    let mut buf = vec![0u8; BUF];
    let n = model.encode(&mut buf).unwrap();
    buf.truncate(n);
    let body = n - 4;
    // One flip per position: two flips of the same byte by the same value would cancel and leave
    // the blob intact (and rightly accepted), which is not a corruption.
    let mut done = Vec::with_capacity(flips.len());
    for &(i, x) in flips {
        let at = if reseal { i % body } else { i % n };
        if !done.contains(&at) {
            done.push(at);
            buf[at] ^= x;
        }
    }
    if reseal {
        let crc = crc32(&buf[..body]);
        buf[body..].copy_from_slice(&crc.to_le_bytes());
    }
    buf
}

/// One input sample of the channel check.
#[derive(Clone, Copy, Debug)]
pub enum Sample {
    /// Thermometers inside the trained −40…60 °C, a raw value of a real sensor's size.
    Inside(f32, f32, f32, f32),
    /// Thermometers far outside (up to ±1e30 °C).
    Far(f32, f32),
    /// A NaN or infinite thermometer or raw value.
    Bad(u8, f32),
    /// A huge but finite raw value.
    HugeRaw(f32),
}

/// Samples for one model.
pub fn samples() -> impl Strategy<Value = Vec<Sample>> {
    let temp = -40.0f32..60.0;
    let sample = prop_oneof![
        6 => (temp.clone(), -1.0f32..1.0, -1.0f32..1.0, -1.0e3f32..1.0e3)
            .prop_map(|(t, a, b, raw)| Sample::Inside(t, a, b, raw)),
        2 => (prop_oneof![-1.0e30f32..-1.0e2, 1.0e2f32..1.0e30, Just(f32::MAX), Just(-f32::MAX)], -1.0e3f32..1.0e3)
            .prop_map(|(t, raw)| Sample::Far(t, raw)),
        1 => (0u8..8, temp).prop_map(|(which, t)| Sample::Bad(which, t)),
        1 => prop_oneof![Just(f32::MAX), Just(-f32::MAX), Just(3.0e38f32)].prop_map(Sample::HugeRaw),
    ];
    proptest::collection::vec(sample, 1..12)
}

/// Points in [0, 1] for the direct evaluation: each coordinate is a fraction of the box (0 and 1
/// are the edges).
pub fn fractions() -> impl Strategy<Value = Vec<[f32; 16]>> {
    let frac = prop_oneof![Just(0.0f32), Just(1.0f32), 0.0f32..=1.0];
    proptest::collection::vec(proptest::array::uniform16(frac), 1..4)
}

/// How a decoded blob fared.
#[derive(Clone, Copy, Debug, Default)]
pub struct Tally {
    /// Cases tried.
    pub cases: u64,
    /// Blobs accepted by the decoder.
    pub accepted: u64,
    /// Accepted models whose evaluation left the bound or gave a non-finite output without a fault
    /// (must stay 0).
    pub implausible: u64,
    /// Rejections by reason, in [`reason_index`] order.
    pub rejected: [u64; 12],
}

/// A small index per rejection reason, for the long run's table.
pub fn reason_index(e: &BlobError) -> usize {
    match e {
        BlobError::Truncated => 0,
        BlobError::BadMagic => 1,
        BlobError::UnsupportedVersion(_) => 2,
        BlobError::Checksum => 3,
        BlobError::CapacityExceeded => 4,
        BlobError::Malformed => 5,
        BlobError::UnknownTag(_) => 6,
        BlobError::NonFinite(_) => 7,
        BlobError::Inconsistent(_) => 8,
        BlobError::Program(_) => 9,
        BlobError::Implausible(_) => 10,
        _ => 11,
    }
}

/// Names of [`reason_index`].
pub const REASONS: [&str; 12] = [
    "truncated",
    "bad magic",
    "unsupported version",
    "checksum",
    "capacity",
    "malformed",
    "unknown tag",
    "non-finite",
    "inconsistent",
    "program",
    "implausible",
    "other",
];

/// Decodes `blob` into the host's and the firmware's types and checks every accepted model with
/// `samples` and `points`. `Err` describes a violated property.
pub fn check_blob(blob: &[u8], samples: &[Sample], points: &[[f32; 16]]) -> Result<bool, String> {
    let host = HostModel::decode(blob);
    let flight = FlightModel::decode(blob);
    if let (Ok(h), Ok(f)) = (&host, &flight)
        && h.rbf.centers.len() != f.rbf.centers.len()
    {
        return Err("host and firmware types read different models".into());
    }
    let mut accepted = false;
    if let Ok(m) = host {
        accepted = true;
        check_model::<HOST_CENTERS, HOST_FEATURES, HOST_NODES>(&m, samples, points)?;
    }
    if let Ok(m) = flight {
        accepted = true;
        check_model::<32, 4, 16>(&m, samples, points)?;
    }
    Ok(accepted)
}

/// `|v| ≤ bound`, false for NaN.
fn within(v: f32, bound: f32) -> bool {
    v.abs() <= bound
}

/// The properties of an accepted model.
pub fn check_model<const C: usize, const F: usize, const N: usize>(
    model: &Model<'_, C, F, N>,
    samples: &[Sample],
    points: &[[f32; 16]],
) -> Result<(), String> {
    let bound = model
        .bound()
        .map_err(|e| format!("accepted but no bound: {e}"))?
        .correction;
    if !(bound.is_finite() && bound <= tcomp_core::bound::MAX_CORRECTION) {
        return Err(format!("bound {bound} out of limits"));
    }
    // Direct evaluation over the box the compensator feeds.
    let nf = model.n_features();
    for frac in points {
        let mut xg = [0.0f32; F];
        let mut xl = [0.0f32; F];
        for (k, r) in model.ranges.iter().enumerate().take(nf) {
            let (a, b) = (frac[k % 16], frac[(k + 8) % 16]);
            let span = r.hi - r.lo;
            xg[k] = (r.lo + a * span).clamp(r.lo, r.hi);
            let (llo, lhi) = (r.lo - span, r.hi + span);
            xl[k] = (llo + b * (lhi - llo)).clamp(llo, lhi);
        }
        let y = model.rbf.eval_split(&xg, &xl);
        if !within(y, bound) {
            return Err(format!(
                "eval_split {y} at {xg:?} / {xl:?} exceeds the bound {bound}"
            ));
        }
    }
    // The compensator, sample by sample.
    let mut ch = Channel::<N, F>::new(1.0);
    let ni = model.program.inputs.len();
    let mut inputs = [0.0f32; 8];
    for s in samples {
        let raw = match *s {
            Sample::Inside(t, a, b, raw) => {
                for (i, v) in inputs.iter_mut().enumerate() {
                    *v = t + if i % 2 == 0 { a } else { b };
                }
                raw
            }
            Sample::Far(t, raw) => {
                inputs.fill(t);
                raw
            }
            Sample::Bad(which, t) => {
                inputs.fill(t);
                let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY][usize::from(which) % 3];
                if which < 3 {
                    if let Some(v) = inputs.get_mut(usize::from(which) % ni.max(1)) {
                        *v = bad;
                    }
                    0.5
                } else {
                    bad
                }
            }
            Sample::HugeRaw(raw) => raw,
        };
        let out = ch.step(Some(model), &inputs[..ni], raw);
        let fault =
            out.status.contains(Status::INPUT_FAULT) || out.status.contains(Status::MODEL_FAULT);
        if !out.compensated.is_finite() && !fault {
            return Err(format!(
                "non-finite output without a fault: {s:?} → {out:?}"
            ));
        }
        if !out.compensated.is_finite() && out.status == Status::OK {
            return Err(format!("non-finite output with status OK: {s:?} → {out:?}"));
        }
        if !within(out.correction, bound) {
            return Err(format!(
                "correction {} exceeds the bound {bound}: {s:?}",
                out.correction
            ));
        }
        if out.status.contains(Status::MODEL_FAULT) && raw.abs() < 1.0e37 {
            return Err(format!(
                "model fault for an accepted model and raw {raw}: {s:?} → {out:?}"
            ));
        }
    }
    Ok(())
}
