//! Signed calibration images: an Ed25519 signature block after the image, the key store a unit
//! is provisioned with, and the one verifier the firmware and `tcomp inspect` run.
//!
//! A CRC stops accidents, not intent: any program that can open a unit's serial port could
//! replace its models with an image that passes every CRC, and a technician could move another
//! unit's calibration to this one by editing its serial. A signature by the calibration station's
//! key stops both: the unit runs only images signed by a key it was provisioned with.
//!
//! # The signature block (after the image, at its length L, which is a multiple of 4)
//!
//! ```text
//! offset  size  field
//! L+0     4     magic b"TCSG"
//! L+4     1     block version (1)
//! L+5     1     algorithm (1: Ed25519, RFC 8032, verified strictly)
//! L+6     2     0
//! L+8     8     key id: the first 8 bytes of SHA-512 of the signer's 32-byte public key
//! L+16    64    signature over bytes [0, L+16): the whole image and the block's first 16 bytes
//! ```
//!
//! The signed message is every byte the unit uses (the image's header, tables, string pool and
//! blobs) plus the block's own header, so neither the key id nor the algorithm can be changed
//! without breaking the signature. A file of `L + 80` bytes is what `tcomp image --sign` writes,
//! `tcomp flash` sends as one slot payload, and a probe may write bare at slot A. An unsigned
//! image is the image alone (the bytes at L are erased flash, or the end of the file).
//!
//! # The key store (what a unit is provisioned with)
//!
//! A run of 32-byte blocks, each an Ed25519 public key: the STM32F407's OTP blocks 1–4
//! (`0x1FFF_7820`, one key per 32-byte OTP block; block 0 holds the unit's serial), or a region
//! outside the model slots on a board without OTP. A block of all `0xFF` was never programmed; a
//! block of all `0x00` is a revoked key (OTP bits can still be cleared after they were
//! programmed, so a factory retires a key by zeroing its block and adds its successor in the next
//! free block). Both are skipped; every other block is a key the unit trusts.
//!
//! # Why Ed25519 and `ed25519-dalek`
//! A well-reviewed scheme with small keys (a key fits one OTP block) and signatures (64 bytes),
//! deterministic signing (no nonce to get wrong at the station), and a maintained `no_std`
//! verifier: `ed25519-dalek` 3 (dalek-cryptography, the most used Rust implementation, audited),
//! whose `verify_strict` refuses non-canonical signatures and small-order keys, so no second
//! valid signature can be made from a first. Measured on thumbv7em (opt-level "s", LTO, a binary
//! doing one verification): ed25519-dalek 3 without precomputed tables 43,152 B of code
//! (56,876 B at the firmware's opt-level 3), `salty` 0.3 10,616 B (Cortex-M4 assembly, last
//! release 2023, one maintainer), `ed25519-compact` 2.6 308,564 B (its tables); the F407 has
//! 768 KiB for the firmware (about 80 KB used before the verifier), so maintenance and review
//! outweighed the 32–46 KB. The host signs with the same crate.

use super::{Image, ImageError};
use ed25519_dalek::{Signature, Signer as _, SigningKey, VerifyingKey};
use sha2::{Digest, Sha512};

/// The four bytes a signature block starts with.
pub const MAGIC: [u8; 4] = *b"TCSG";
/// The block format version.
pub const BLOCK_VERSION: u8 = 1;
/// The algorithm code of Ed25519.
pub const ED25519: u8 = 1;
/// Bytes of the block.
pub const BLOCK_LEN: usize = 80;
/// Bytes of the block covered by its signature (magic, version, algorithm, key id).
pub const SIGNED_HEAD_LEN: usize = 16;
/// Bytes of a public key (and of one key-store block).
pub const PUBLIC_KEY_LEN: usize = 32;
/// Bytes of a secret key (the Ed25519 seed).
pub const SECRET_KEY_LEN: usize = 32;

/// Who signed: the first 8 bytes of SHA-512 of the public key.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KeyId(pub [u8; 8]);

impl KeyId {
    /// The id of `public`.
    pub fn of(public: &[u8; PUBLIC_KEY_LEN]) -> Self {
        let digest = Sha512::digest(public);
        let mut id = [0u8; 8];
        for (d, s) in id.iter_mut().zip(digest.iter()) {
            *d = *s;
        }
        Self(id)
    }

    /// As a number (big-endian, so it prints as its hex bytes in order).
    pub const fn as_u64(&self) -> u64 {
        u64::from_be_bytes(self.0)
    }
}

impl core::fmt::Display for KeyId {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{:016x}", self.as_u64())
    }
}

/// Why an image's signature is not accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SignatureError {
    /// The image does not parse (so there is no length to find the block at).
    Image(ImageError),
    /// No signature block after the image.
    Unsigned,
    /// A block with an unknown version or algorithm, or cut short.
    Malformed,
    /// Signed by a key the key store does not hold.
    UnknownKey(KeyId),
    /// The signature does not verify against the key it names.
    BadSignature(KeyId),
}

impl core::fmt::Display for SignatureError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Image(e) => write!(f, "{e}"),
            Self::Unsigned => f.write_str("the image is not signed"),
            Self::Malformed => f.write_str("malformed signature block"),
            Self::UnknownKey(k) => write!(f, "signed by key {k}, which is not a trusted key"),
            Self::BadSignature(k) => write!(f, "the signature by key {k} does not verify"),
        }
    }
}

impl core::error::Error for SignatureError {}

/// A parsed signature block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block {
    /// Where it starts: the image's length.
    pub at: usize,
    /// The signer's key id.
    pub key: KeyId,
    signature: [u8; 64],
}

/// The image's length and its signature block, if one follows it (`Ok((L, None))`: unsigned).
pub fn block(bytes: &[u8]) -> Result<(usize, Option<Block>), SignatureError> {
    let image = Image::parse(bytes).map_err(SignatureError::Image)?;
    let at = image.byte_len();
    if bytes.get(at..at + 4) != Some(&MAGIC[..]) {
        return Ok((at, None));
    }
    let raw = bytes
        .get(at..at + BLOCK_LEN)
        .ok_or(SignatureError::Malformed)?;
    if raw.get(4..8) != Some(&[BLOCK_VERSION, ED25519, 0, 0][..]) {
        return Err(SignatureError::Malformed);
    }
    let mut key = [0u8; 8];
    key.copy_from_slice(raw.get(8..16).ok_or(SignatureError::Malformed)?);
    let mut signature = [0u8; 64];
    signature.copy_from_slice(raw.get(16..BLOCK_LEN).ok_or(SignatureError::Malformed)?);
    Ok((
        at,
        Some(Block {
            at,
            key: KeyId(key),
            signature,
        }),
    ))
}

/// The keys a unit trusts: 32-byte blocks, all-`0xFF` (never programmed) and all-`0x00`
/// (revoked) ones skipped, a partial last block ignored.
#[derive(Clone, Copy, Debug)]
pub struct KeyStore<'a>(pub &'a [u8]);

impl<'a> KeyStore<'a> {
    /// Every trusted key, in block order.
    pub fn keys(&self) -> impl Iterator<Item = &'a [u8; PUBLIC_KEY_LEN]> + 'a {
        self.0
            .chunks_exact(PUBLIC_KEY_LEN)
            .filter(|k| !k.iter().all(|&b| b == 0xFF) && !k.iter().all(|&b| b == 0))
            .filter_map(|k| <&[u8; PUBLIC_KEY_LEN]>::try_from(k).ok())
    }

    /// The trusted key with id `id`.
    pub fn find(&self, id: KeyId) -> Option<&'a [u8; PUBLIC_KEY_LEN]> {
        self.keys().find(|k| KeyId::of(k) == id)
    }

    /// True when no key is provisioned.
    pub fn is_empty(&self) -> bool {
        self.keys().next().is_none()
    }
}

/// Checks the signature of the image at the start of `bytes` against the trusted `keys`;
/// returns the signer's key id. Strict verification (RFC 8032 with canonical `S` and no
/// small-order key or `R`). Never panics.
pub fn verify(bytes: &[u8], keys: KeyStore<'_>) -> Result<KeyId, SignatureError> {
    let (_, block) = block(bytes)?;
    let block = block.ok_or(SignatureError::Unsigned)?;
    let public = keys
        .find(block.key)
        .ok_or(SignatureError::UnknownKey(block.key))?;
    let bad = SignatureError::BadSignature(block.key);
    let key = VerifyingKey::from_bytes(public).map_err(|_| bad)?;
    let message = bytes.get(..block.at + SIGNED_HEAD_LEN).ok_or(bad)?;
    key.verify_strict(message, &Signature::from_bytes(&block.signature))
        .map_err(|_| bad)?;
    Ok(block.key)
}

/// The public key of the secret key (seed) `secret`.
pub fn public_key(secret: &[u8; SECRET_KEY_LEN]) -> [u8; PUBLIC_KEY_LEN] {
    SigningKey::from_bytes(secret).verifying_key().to_bytes()
}

/// Signs the image at the start of `buf` with `secret`: writes the block after the image and
/// returns the signed length (the image's plus [`BLOCK_LEN`]). `buf` must hold that many bytes;
/// an image that is already signed is signed anew (its block replaced).
pub fn sign(buf: &mut [u8], secret: &[u8; SECRET_KEY_LEN]) -> Result<usize, SignatureError> {
    let at = Image::parse(buf).map_err(SignatureError::Image)?.byte_len();
    let end = at + BLOCK_LEN;
    let key = SigningKey::from_bytes(secret);
    let id = KeyId::of(&key.verifying_key().to_bytes());
    let head = buf
        .get_mut(at..at + SIGNED_HEAD_LEN)
        .ok_or(SignatureError::Image(ImageError::BufferTooSmall {
            needed: end,
        }))?;
    head[..4].copy_from_slice(&MAGIC);
    head[4..8].copy_from_slice(&[BLOCK_VERSION, ED25519, 0, 0]);
    head[8..16].copy_from_slice(&id.0);
    let message = buf
        .get(..at + SIGNED_HEAD_LEN)
        .ok_or(SignatureError::Malformed)?;
    let signature = key.sign(message).to_bytes();
    buf.get_mut(at + SIGNED_HEAD_LEN..end)
        .ok_or(SignatureError::Image(ImageError::BufferTooSmall {
            needed: end,
        }))?
        .copy_from_slice(&signature);
    Ok(end)
}
