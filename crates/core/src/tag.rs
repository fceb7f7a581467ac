//! Unknown enum tags, told apart from capacity errors.
//!
//! postcard maps every serde custom error to one value, `SerdeDeCustom`: heapless' "too many
//! elements", a [`crate::point::Point`] longer than `F` and serde-derive's "unknown variant index"
//! all arrive the same, so the blob decoder could not say whether a blob is too large for this build
//! or simply malformed. The blob's enums ([`crate::SensorKind`], [`crate::Op`]) therefore keep their
//! derived code and wire format (`#[serde(remote = "Self")]` turns the derive into inherent
//! functions) and implement the serde traits by wrapping the deserializer in [`TagGuard`]. The guard
//! watches the variant index; an index past the enum's variants is turned into a request that
//! postcard refuses by design and that nothing else in a blob makes: `deserialize_any` on a
//! non-self-describing format, `postcard::Error::WontImplement`. [`crate::blob`] maps that error to
//! [`crate::BlobError::UnknownTag`]. Valid blobs take exactly the derived path, bit for bit.
//!
//! A self-describing format (JSON, TOML on the host) names variants instead of numbering them: the
//! guard passes names through, and an unknown name fails with that format's own error.
//! [`crate::SensorKind`] goes one step further in those formats: it is written and read by its text
//! name ([`crate::SensorKind::name`], `"rlg"`, `"mems-gyro"`), the one spelling the command line,
//! the scenario files and the truth file share; postcard (not human-readable) keeps the tag.

use core::cell::Cell;
use core::convert::Infallible;
use core::fmt;
use serde::de::{DeserializeSeed, Deserializer, EnumAccess, VariantAccess, Visitor};

/// A deserializer whose enum variant indices are checked against the enum's variant count.
pub(crate) struct TagGuard<D>(pub D);

impl<'de, D: Deserializer<'de>> Deserializer<'de> for TagGuard<D> {
    type Error = D::Error;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, D::Error> {
        self.0.deserialize_any(visitor)
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        name: &'static str,
        variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        let guarded = EnumVisitor {
            inner: visitor,
            count: variants.len(),
        };
        self.0.deserialize_enum(name, variants, guarded)
    }

    fn is_human_readable(&self) -> bool {
        self.0.is_human_readable()
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map struct identifier
        ignored_any
    }
}

struct EnumVisitor<V> {
    inner: V,
    count: usize,
}

impl<'de, V: Visitor<'de>> Visitor<'de> for EnumVisitor<V> {
    type Value = V::Value;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.inner.expecting(f)
    }

    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<V::Value, A::Error> {
        self.inner.visit_enum(GuardedEnum {
            inner: data,
            count: self.count,
        })
    }
}

struct GuardedEnum<A> {
    inner: A,
    count: usize,
}

impl<'de, A: EnumAccess<'de>> EnumAccess<'de> for GuardedEnum<A> {
    type Error = A::Error;
    type Variant = GuardedVariant<A::Variant>;

    fn variant_seed<S: DeserializeSeed<'de>>(
        self,
        seed: S,
    ) -> Result<(S::Value, Self::Variant), A::Error> {
        let unknown = Cell::new(false);
        let seed = IdSeed {
            inner: seed,
            count: self.count,
            unknown: &unknown,
        };
        let (value, variant) = self.inner.variant_seed(seed)?;
        Ok((
            value,
            GuardedVariant {
                inner: variant,
                unknown: unknown.get(),
            },
        ))
    }
}

/// Reads the variant identifier; an index past `count` is read as 0 and remembered in `unknown`, so
/// the derived code goes on to the variant's content, where [`GuardedVariant`] refuses it.
struct IdSeed<'c, S> {
    inner: S,
    count: usize,
    unknown: &'c Cell<bool>,
}

impl<'de, S: DeserializeSeed<'de>> DeserializeSeed<'de> for IdSeed<'_, S> {
    type Value = S::Value;

    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<S::Value, D::Error> {
        self.inner.deserialize(IdDeserializer {
            inner: deserializer,
            count: self.count,
            unknown: self.unknown,
        })
    }
}

struct IdDeserializer<'c, D> {
    inner: D,
    count: usize,
    unknown: &'c Cell<bool>,
}

impl<'de, D: Deserializer<'de>> Deserializer<'de> for IdDeserializer<'_, D> {
    type Error = D::Error;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, D::Error> {
        self.inner.deserialize_any(IdVisitor {
            inner: visitor,
            count: self.count,
            unknown: self.unknown,
        })
    }

    fn deserialize_identifier<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, D::Error> {
        self.inner.deserialize_identifier(IdVisitor {
            inner: visitor,
            count: self.count,
            unknown: self.unknown,
        })
    }

    fn is_human_readable(&self) -> bool {
        self.inner.is_human_readable()
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map struct enum
        ignored_any
    }
}

struct IdVisitor<'c, V> {
    inner: V,
    count: usize,
    unknown: &'c Cell<bool>,
}

impl<'de, V: Visitor<'de>> Visitor<'de> for IdVisitor<'_, V> {
    type Value = V::Value;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.inner.expecting(f)
    }

    fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<V::Value, E> {
        if usize::try_from(v).map_or(true, |i| i >= self.count) {
            self.unknown.set(true);
            return self.inner.visit_u64(0);
        }
        self.inner.visit_u64(v)
    }

    fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<V::Value, E> {
        self.inner.visit_i64(v)
    }

    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<V::Value, E> {
        self.inner.visit_str(v)
    }

    fn visit_borrowed_str<E: serde::de::Error>(self, v: &'de str) -> Result<V::Value, E> {
        self.inner.visit_borrowed_str(v)
    }

    fn visit_bytes<E: serde::de::Error>(self, v: &[u8]) -> Result<V::Value, E> {
        self.inner.visit_bytes(v)
    }

    fn visit_borrowed_bytes<E: serde::de::Error>(self, v: &'de [u8]) -> Result<V::Value, E> {
        self.inner.visit_borrowed_bytes(v)
    }
}

/// The variant's content; refused outright when its index was unknown.
struct GuardedVariant<A> {
    inner: A,
    unknown: bool,
}

impl<'de, A: VariantAccess<'de>> VariantAccess<'de> for GuardedVariant<A> {
    type Error = A::Error;

    fn unit_variant(self) -> Result<(), A::Error> {
        if self.unknown {
            return refuse(self.inner);
        }
        self.inner.unit_variant()
    }

    fn newtype_variant_seed<T: DeserializeSeed<'de>>(self, seed: T) -> Result<T::Value, A::Error> {
        if self.unknown {
            return refuse(self.inner);
        }
        self.inner.newtype_variant_seed(seed)
    }

    fn tuple_variant<V: Visitor<'de>>(self, len: usize, visitor: V) -> Result<V::Value, A::Error> {
        if self.unknown {
            return refuse(self.inner);
        }
        self.inner.tuple_variant(len, visitor)
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, A::Error> {
        if self.unknown {
            return refuse(self.inner);
        }
        self.inner.struct_variant(fields, visitor)
    }
}

/// Asks the format to describe the variant's content itself: postcard answers `WontImplement`
/// without reading a byte; a self-describing format's answer is refused by [`Refuse`].
fn refuse<'de, A: VariantAccess<'de>, T>(variant: A) -> Result<T, A::Error> {
    match variant.newtype_variant_seed(Refuse)? {}
}

struct Refuse;

impl<'de> DeserializeSeed<'de> for Refuse {
    type Value = Infallible;

    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<Infallible, D::Error> {
        deserializer.deserialize_any(Refuse)
    }
}

impl<'de> Visitor<'de> for Refuse {
    type Value = Infallible;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "a known enum variant")
    }
}

/// The sensor kind: by name in human-readable formats, by the derived tag (guarded) in postcard.
impl serde::Serialize for crate::blob::SensorKind {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        if serializer.is_human_readable() {
            serializer.serialize_str(self.name())
        } else {
            Self::serialize(self, serializer)
        }
    }
}

impl<'de> serde::Deserialize<'de> for crate::blob::SensorKind {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        if deserializer.is_human_readable() {
            deserializer.deserialize_str(SensorName)
        } else {
            Self::deserialize(TagGuard(deserializer))
        }
    }
}

/// Reads a sensor kind's text name.
struct SensorName;

impl Visitor<'_> for SensorName {
    type Value = crate::blob::SensorKind;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "a sensor kind: rlg, qma, ifog, mems-gyro, mems-accel or other"
        )
    }

    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Self::Value, E> {
        crate::blob::SensorKind::from_name(v)
            .ok_or_else(|| E::invalid_value(serde::de::Unexpected::Str(v), &self))
    }
}

// `Op` is generic over its number type; the same two impls, for every `S` serde handles.
impl<S: serde::Serialize> serde::Serialize for crate::program::Op<S> {
    fn serialize<Z: serde::Serializer>(&self, serializer: Z) -> Result<Z::Ok, Z::Error> {
        <crate::program::Op<S>>::serialize(self, serializer)
    }
}

impl<'de, S: serde::Deserialize<'de>> serde::Deserialize<'de> for crate::program::Op<S> {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        <crate::program::Op<S>>::deserialize(TagGuard(deserializer))
    }
}
