//! The update protocol's frames and their byte-at-a-time decoder.
//!
//! ```text
//! offset  size  field
//! 0       2     sync 0xEB 0x91 (the output frames' 0xEB 0x90 with the last bit set: one search)
//! 2       1     kind (see [`Kind`])
//! 3       2     sequence u16: the host numbers its requests; a reply carries the request's number
//! 5       2     payload length (≤ MAX_PAYLOAD)
//! 7       len   payload
//! 7+len   4     CRC-32 (the core's) of bytes 2 .. 7+len
//! ```
//!
//! Payloads (little-endian): BEGIN = total length u32, image CRC-32 u32, session u32 (a number
//! the host draws per run of `tcomp flash`: a repeat of this run's BEGIN is acknowledged again, a
//! BEGIN of another session takes over); DATA = offset u32, then
//! 1..=[`MAX_CHUNK`] bytes; NAK = reason u8 (see [`Reason`]), expected offset u32; RESULT = reason
//! u8 (0 ok), slot u8, generation u32; INFO = active slot u8 (0xFF: none), generation u32, slot
//! capacity u32, then the unit's serial (≤ [`MAX_SERIAL`] bytes). HELLO, COMMIT, ABORT and ACK
//! carry nothing.
//!
//! The decoder is the core's sync-word [`Framer`] (the output frames' decoder is the same one):
//! after garbage or a failed CRC it searches again from the byte after the false start, so a host
//! listening to a link that carries both the unit's output frames and its update replies finds
//! every reply (each output frame is garbage to it, and the reverse), and a unit recovers from a
//! corrupt request at the next sync. This module only says how long a frame is and what it means.

use crate::crc::Crc32;
use crate::framer::{CRC_LEN, Framer, Framing};

/// The two bytes every update frame starts with.
pub const SYNC: [u8; 2] = [0xEB, 0x91];
/// Bytes before the payload.
pub const HEADER_LEN: usize = 7;
/// Most image bytes in one DATA frame. 64: a frame is lost whole when one of its bytes is, so on a
/// line that loses bytes at rate p a frame of n bytes arrives with probability (1 − p)^n — at
/// 1 % loss a 79-byte frame 45 % of the time, a 267-byte one (256-byte chunks) 7 %, and the update
/// would stall in repeats (the lossy-link test: `host-tools/tests/flash_lossy.rs`). The cost is the
/// frame overhead, 15 B per 64 (19 %), and a round trip per chunk. (It was first chosen for a
/// 16 KiB RAM budget that no longer exists: the F407's leaves room for any size.)
pub const MAX_CHUNK: usize = 64;
/// Longest payload (DATA: offset + chunk).
pub const MAX_PAYLOAD: usize = 4 + MAX_CHUNK;
/// Longest frame: 79 bytes, the unit's whole receive buffer.
pub const MAX_FRAME: usize = HEADER_LEN + MAX_PAYLOAD + 4;
/// Longest serial number an INFO reply carries (bytes; a longer one is cut).
pub const MAX_SERIAL: usize = 32;

/// What a frame is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Kind {
    /// Host: who are you (reply INFO).
    Hello = 0x01,
    /// Host: an image of this length and CRC follows (erases the inactive slot); a BEGIN of a new
    /// session ends whatever session the unit had open.
    Begin = 0x02,
    /// Host: image bytes at an offset.
    Data = 0x03,
    /// Host: all sent; verify and commit (reply RESULT).
    Commit = 0x04,
    /// Host: give up this update (the active slot is untouched).
    Abort = 0x05,
    /// Unit: request done.
    Ack = 0x81,
    /// Unit: request refused, with a reason.
    Nak = 0x82,
    /// Unit: the update's outcome.
    Result = 0x83,
    /// Unit: serial, active slot, generation.
    Info = 0x84,
}

impl Kind {
    /// The kind of a frame's kind byte.
    pub const fn from_u8(b: u8) -> Option<Self> {
        Some(match b {
            0x01 => Self::Hello,
            0x02 => Self::Begin,
            0x03 => Self::Data,
            0x04 => Self::Commit,
            0x05 => Self::Abort,
            0x81 => Self::Ack,
            0x82 => Self::Nak,
            0x83 => Self::Result,
            0x84 => Self::Info,
            _ => return None,
        })
    }
}

/// Why the unit refused a request or an update failed (the NAK's and RESULT's code).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
#[non_exhaustive]
pub enum Reason {
    /// Success (RESULT only).
    Ok = 0,
    /// A payload of the wrong size for its kind, or an unknown kind.
    Malformed = 1,
    /// DATA or COMMIT without a BEGIN.
    NotStarted = 2,
    // 3 was `Busy` (a BEGIN during another session); a new session now takes over.
    /// The image does not fit a slot.
    TooLarge = 4,
    /// DATA not at the next offset (the NAK says which).
    OutOfOrder = 5,
    /// DATA past the announced length, or a misaligned chunk.
    BadChunk = 6,
    /// COMMIT before every byte arrived.
    Incomplete = 7,
    /// The written image's CRC is not the announced one.
    Crc = 8,
    /// The image does not validate.
    Invalid = 9,
    /// The flash refused an erase, a program or a read.
    Flash = 10,
    /// An update was committed: the next one waits for the reset that activates it.
    RebootPending = 11,
    /// The image was made for another unit (its serial).
    OtherUnit = 12,
    /// The image carries no signature, and this firmware accepts signed images only.
    Unsigned = 13,
    /// The image is signed by a key the unit does not hold.
    UnknownKey = 14,
    /// The image's signature does not verify against the key it names.
    BadSignature = 15,
}

impl Reason {
    /// The reason of a code byte (`Malformed` for an unknown one).
    pub const fn from_u8(b: u8) -> Self {
        match b {
            0 => Self::Ok,
            2 => Self::NotStarted,
            4 => Self::TooLarge,
            5 => Self::OutOfOrder,
            6 => Self::BadChunk,
            7 => Self::Incomplete,
            8 => Self::Crc,
            9 => Self::Invalid,
            10 => Self::Flash,
            11 => Self::RebootPending,
            12 => Self::OtherUnit,
            13 => Self::Unsigned,
            14 => Self::UnknownKey,
            15 => Self::BadSignature,
            _ => Self::Malformed,
        }
    }

    /// A short description.
    pub const fn describe(self) -> &'static str {
        match self {
            Self::Ok => "ok",
            Self::Malformed => "malformed request",
            Self::NotStarted => "no update in progress",
            Self::TooLarge => "image larger than a slot",
            Self::OutOfOrder => "chunk out of order",
            Self::BadChunk => "chunk past the end or misaligned",
            Self::Incomplete => "commit before all data",
            Self::Crc => "image CRC mismatch after writing",
            Self::Invalid => "image does not validate",
            Self::Flash => "flash error",
            Self::RebootPending => "an update is committed; reset the unit first",
            Self::OtherUnit => "image made for another unit",
            Self::Unsigned => "image not signed (this unit accepts signed images only)",
            Self::UnknownKey => "image signed by a key this unit does not hold",
            Self::BadSignature => "image signature does not verify",
        }
    }
}

impl core::fmt::Display for Reason {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.describe())
    }
}

/// A decoded frame; the payload borrows from the decoder (or the caller's bytes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Packet<'a> {
    /// The kind.
    pub kind: Kind,
    /// The sequence number.
    pub seq: u16,
    /// The payload.
    pub payload: &'a [u8],
}

impl Packet<'_> {
    /// Encodes into `out`, returning the length, or `None` when the payload is too long or `out`
    /// too short.
    pub fn encode(&self, out: &mut [u8]) -> Option<usize> {
        let len = self.payload.len();
        if len > MAX_PAYLOAD {
            return None;
        }
        let total = HEADER_LEN + len + 4;
        let frame = out.get_mut(..total)?;
        let (head, rest) = frame.split_at_mut(HEADER_LEN);
        let (body, crc_out) = rest.split_at_mut(len);
        head.copy_from_slice(&[
            SYNC[0],
            SYNC[1],
            self.kind as u8,
            self.seq.to_le_bytes()[0],
            self.seq.to_le_bytes()[1],
            (len as u16).to_le_bytes()[0],
            (len as u16).to_le_bytes()[1],
        ]);
        body.copy_from_slice(self.payload);
        let mut crc = Crc32::new();
        crc.update(head.get(2..).unwrap_or(&[]));
        crc.update(body);
        crc_out.copy_from_slice(&crc.finish().to_le_bytes());
        Some(total)
    }

    /// The little-endian u32 at `at` of the payload.
    pub fn u32_at(&self, at: usize) -> Option<u32> {
        let b: [u8; 4] = self.payload.get(at..at.checked_add(4)?)?.try_into().ok()?;
        Some(u32::from_le_bytes(b))
    }
}

/// The update protocol's framing: a known kind and a payload length of at most [`MAX_PAYLOAD`].
#[derive(Clone, Copy, Debug, Default)]
struct Update;

impl Framing for Update {
    const SYNC: &'static [u8] = &SYNC;
    const HEADER_LEN: usize = HEADER_LEN;

    fn frame_len(header: &[u8]) -> Option<usize> {
        Kind::from_u8(*header.get(2)?)?;
        let len = usize::from(u16::from_le_bytes([*header.get(5)?, *header.get(6)?]));
        (len <= MAX_PAYLOAD).then_some(HEADER_LEN + len + CRC_LEN)
    }
}

/// Byte-at-a-time decoder with one frame of buffer.
#[derive(Clone, Debug)]
pub struct Decoder {
    framer: Framer<Update, MAX_FRAME>,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder that has seen nothing.
    pub const fn new() -> Self {
        Self {
            framer: Framer::new(),
        }
    }

    /// Bytes dropped while searching for a frame (garbage, other frames, corrupt frames; wrapping).
    pub const fn skipped(&self) -> u32 {
        self.framer.skipped() as u32
    }

    /// Feeds one byte; returns a frame if one is complete. Call [`poll`](Self::poll) until `None`
    /// before the next byte (a resynchronisation can leave a second frame buffered).
    pub fn push(&mut self, byte: u8) -> Option<Packet<'_>> {
        self.framer.push(byte).and_then(parse_good)
    }

    /// Looks for a complete frame in the bytes already fed.
    pub fn poll(&mut self) -> Option<Packet<'_>> {
        self.framer.poll().and_then(parse_good)
    }
}

/// The packet of a frame whose sync, kind, length and CRC were checked.
fn parse_good(frame: &[u8]) -> Option<Packet<'_>> {
    let kind = Kind::from_u8(*frame.get(2)?)?;
    let seq = u16::from_le_bytes([*frame.get(3)?, *frame.get(4)?]);
    let payload = frame.get(HEADER_LEN..frame.len().checked_sub(4)?)?;
    Some(Packet { kind, seq, payload })
}
