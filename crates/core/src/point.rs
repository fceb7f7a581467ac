//! A fixed-size vector of `F` f32 values that serde can carry.
//!
//! The evaluator wants centers as plain `[f32; F]` rows (the inner loop then unrolls at compile time
//! and needs no bounds checks), but serde's derive does not cover arrays of a const-generic length.
//! `Point` serialises as a tuple of `F` floats (postcard writes them back to back, no length prefix).

use core::fmt;
use core::marker::PhantomData;
use serde::de::{Error as _, SeqAccess, Visitor};
use serde::ser::SerializeTuple;
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
        let mut t = serializer.serialize_tuple(F)?;
        for v in &self.0 {
            t.serialize_element(v)?;
        }
        t.end()
    }
}

struct PointVisitor<const F: usize>(PhantomData<[f32; F]>);

impl<'de, const F: usize> Visitor<'de> for PointVisitor<F> {
    type Value = Point<F>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "a tuple of {F} f32 values")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Point<F>, A::Error> {
        let mut p = [0.0f32; F];
        for (i, slot) in p.iter_mut().enumerate() {
            *slot = seq
                .next_element()?
                .ok_or_else(|| A::Error::invalid_length(i, &self))?;
        }
        Ok(Point(p))
    }
}

impl<'de, const F: usize> Deserialize<'de> for Point<F> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_tuple(F, PointVisitor::<F>(PhantomData))
    }
}
