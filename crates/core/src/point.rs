//! A fixed-size vector of `F` f32 values that serde can carry.
//!
//! The evaluator wants plain `[f32; F]` rows (the inner loop then unrolls at compile time and needs
//! no bounds checks), but serde's derive does not cover arrays of a const-generic length, and the wire
//! format must not depend on `F`: the host trains with `F = 8` and a firmware built with `F = 4` must
//! read a 4-feature blob. So a `Point` is written as a sequence with its trailing zeros dropped
//! (lossless but for the sign of a trailing zero: missing entries read back as +0), and reading more
//! than `F` values is an error.

use core::fmt;
use core::marker::PhantomData;
use serde::de::{Error as _, SeqAccess, Visitor};
use serde::ser::SerializeSeq;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// `F` f32 values; entries past a model's feature count are zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point<const F: usize>(pub [f32; F]);

impl<const F: usize> Default for Point<F> {
    fn default() -> Self {
        Self([0.0; F])
    }
}

impl<const F: usize> Point<F> {
    /// A point from a slice: the first `min(len, F)` values, the rest zero.
    pub fn from_slice(values: &[f32]) -> Self {
        let mut p = [0.0; F];
        for (dst, src) in p.iter_mut().zip(values) {
            *dst = *src;
        }
        Self(p)
    }

    /// True when every value is finite.
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }
}

impl<const F: usize> Serialize for Point<F> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let len = self.0.iter().rposition(|v| *v != 0.0).map_or(0, |i| i + 1);
        let mut seq = serializer.serialize_seq(Some(len))?;
        for v in self.0.iter().take(len) {
            seq.serialize_element(v)?;
        }
        seq.end()
    }
}

struct PointVisitor<const F: usize>(PhantomData<[f32; F]>);

impl<'de, const F: usize> Visitor<'de> for PointVisitor<F> {
    type Value = Point<F>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "at most {F} f32 values")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Point<F>, A::Error> {
        let mut p = [0.0f32; F];
        let mut i = 0;
        while let Some(v) = seq.next_element::<f32>()? {
            let slot = p
                .get_mut(i)
                .ok_or_else(|| A::Error::invalid_length(i + 1, &self))?;
            *slot = v;
            i += 1;
        }
        Ok(Point(p))
    }
}

impl<'de, const F: usize> Deserialize<'de> for Point<F> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_seq(PointVisitor::<F>(PhantomData))
    }
}
