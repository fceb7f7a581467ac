//! Which images this unit runs: made for it (its serial), readable, and signed by a key it was
//! provisioned with (`tcomp_core::image::sign`). One check, [`Trust::check`], made twice: at
//! boot, before a slot is chosen (`slots::choose` skips a slot it refuses), and by the update
//! task at COMMIT, before the commit word is written ([`Trust::check_payload`]), so an image
//! that fails it never runs and is never committed; the unit keeps its models and says why (the
//! RESULT's reason, the boot report's image state and last-update fields).
//!
//! **Keys.** The board hands over its key store: on the STM32F407 OTP blocks 1–4 (`0x1FFF_7820`,
//! 128 bytes, one Ed25519 public key per 32-byte block, programmed at the factory next to the
//! serial in block 0, see the board's README); under QEMU the `KEYS` region of `memory.x`,
//! loaded like an OTP image by QEMU's loader. Not the board description: a description is
//! per design and lives in the repository, while keys are provisioned per unit (a customer's
//! units can trust its own station's key) and must survive every firmware and image update.
//!
//! **Development builds.** With the `unsigned-images` feature (chosen at build time, never by
//! an image or a command) an image without a signature block is accepted; a signature that is
//! present must still verify. Every boot report of such a build carries the `DEVELOPMENT` flag,
//! so such a unit cannot pass for a production one.

use tcomp_core::image::Image;
use tcomp_core::image::sign::{self, BLOCK_LEN, KeyId, KeyStore, SignatureError};
use tcomp_core::update::Reason;

/// True in a development build (`unsigned-images`): unsigned images run.
pub const DEVELOPMENT: bool = cfg!(feature = "unsigned-images");

/// Who vouches for an accepted image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum Signer {
    /// Signed by this trusted key.
    Key(KeyId),
    /// Not signed, accepted by a development build.
    Unsigned,
}

impl Signer {
    /// The key id as the boot report carries it (0: unsigned).
    pub const fn report_id(&self) -> u64 {
        match self {
            Self::Key(k) => k.as_u64(),
            Self::Unsigned => 0,
        }
    }
}

/// The unit's identity and keys, and whether unsigned images run.
#[derive(Clone, Copy, Debug)]
pub struct Trust<'k> {
    /// The unit's serial (an image made for another unit is refused).
    pub unit: u64,
    /// The provisioned public keys.
    pub keys: KeyStore<'k>,
    /// Whether an unsigned image is accepted ([`DEVELOPMENT`] on a board).
    pub development: bool,
}

impl<'k> Trust<'k> {
    /// The unit `unit` with the key store `keys` (raw blocks), in this build's mode.
    pub const fn new(unit: u64, keys: &'k [u8]) -> Self {
        Self {
            unit,
            keys: KeyStore(keys),
            development: DEVELOPMENT,
        }
    }

    /// Whether the image at the start of `bytes` (a slot's payload, or a region a probe wrote)
    /// may run here: it reads, it was made for this unit, and it is signed by a trusted key (or
    /// unsigned, in a development build). The error is the update protocol's reason. Not
    /// inlined: the verifier's frame is not under a caller's on the boot's stack.
    #[inline(never)]
    pub fn check(&self, bytes: &[u8]) -> Result<Signer, Reason> {
        let image = Image::parse(bytes).map_err(|_| Reason::Invalid)?;
        image.check_unit(self.unit).map_err(|_| Reason::OtherUnit)?;
        match sign::verify(bytes, self.keys) {
            Ok(key) => Ok(Signer::Key(key)),
            Err(SignatureError::Unsigned) if self.development => Ok(Signer::Unsigned),
            Err(SignatureError::Unsigned) => Err(Reason::Unsigned),
            Err(SignatureError::UnknownKey(_)) => Err(Reason::UnknownKey),
            Err(SignatureError::Image(_)) => Err(Reason::Invalid),
            Err(_) => Err(Reason::BadSignature),
        }
    }

    /// [`check`](Self::check) for an update's whole payload, which must end where the image (or
    /// its signature block) ends: no byte is committed that the checks did not cover.
    pub fn check_payload(&self, payload: &[u8]) -> Result<Signer, Reason> {
        let signer = self.check(payload)?;
        let image_len = Image::parse(payload)
            .map_err(|_| Reason::Invalid)?
            .byte_len();
        let expected = match signer {
            Signer::Key(_) => image_len + BLOCK_LEN,
            // A development build: the image alone, or with a block that verified above.
            Signer::Unsigned => image_len,
        };
        if payload.len() != expected {
            return Err(Reason::Invalid);
        }
        Ok(signer)
    }
}

/// The boot report's image state for a refusal reason.
pub const fn image_state(reason: Reason) -> u8 {
    use tcomp_core::frame::image_state as s;
    match reason {
        Reason::OtherUnit => s::OTHER_UNIT,
        Reason::Unsigned => s::UNSIGNED,
        Reason::UnknownKey => s::UNKNOWN_KEY,
        Reason::BadSignature => s::BAD_SIGNATURE,
        _ => s::INVALID,
    }
}
