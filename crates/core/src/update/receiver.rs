//! The unit's side of an update: one request in, one reply out, the inactive slot written.
//!
//! The state machine is plain `no_std` code over [`NorFlash`], so every path a link can take —
//! lost, duplicated, corrupt or reordered frames, an oversize image, a second BEGIN, an early
//! COMMIT, an image that does not validate — is tested on the host with the flash model. It only
//! ever erases and writes the slot the unit is not running from, and commits only through
//! [`SlotWriter::commit`], so whatever the host sends, the active slot stays as it was.
//!
//! Requests are idempotent where a lost reply makes the host repeat them: a repeated BEGIN of the
//! same session with the same length and CRC, and a DATA chunk that lies wholly inside what is
//! already written, are acknowledged again without touching the flash; a COMMIT after a successful
//! one repeats its RESULT. A BEGIN of another session (a new run of `tcomp flash` after one that
//! died mid-transfer, or another image) takes over: the half-written slot is begun again, so a
//! failed session never leaves the unit refusing updates until a reset. ABORT ends a session
//! without touching the active slot. After a commit the unit refuses a new BEGIN until it is
//! reset: the new image takes effect at the next boot (the running models borrow from the active
//! slot, which the next update would have to erase).
//!
//! The image check before the commit is the caller's (`validate`): it answers with the [`Reason`]
//! the host is told (an image that does not parse, made for another unit, unsigned, signed by an
//! unknown key, with a signature that does not verify), so a refusal says why.

use super::wire::{Kind, MAX_SERIAL, Packet, Reason};
use crate::slots::writer::WriteError;
use crate::slots::{Active, Header, Layout, SlotId, SlotWriter};
use embedded_storage::nor_flash::NorFlash;

/// Bytes of the longest reply payload (INFO).
const REPLY_MAX: usize = 9 + MAX_SERIAL;

/// A reply frame to send.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reply {
    kind: Kind,
    seq: u16,
    payload: [u8; REPLY_MAX],
    len: usize,
}

impl Reply {
    fn new(kind: Kind, seq: u16, parts: &[&[u8]]) -> Self {
        let mut payload = [0u8; REPLY_MAX];
        let mut len = 0;
        for part in parts {
            for &b in *part {
                if let Some(dst) = payload.get_mut(len) {
                    *dst = b;
                    len += 1;
                }
            }
        }
        Self {
            kind,
            seq,
            payload,
            len,
        }
    }

    fn ack(seq: u16) -> Self {
        Self::new(Kind::Ack, seq, &[])
    }

    fn nak(seq: u16, reason: Reason, expected: u32) -> Self {
        Self::new(Kind::Nak, seq, &[&[reason as u8], &expected.to_le_bytes()])
    }

    fn result(seq: u16, reason: Reason, slot: SlotId, generation: u32) -> Self {
        Self::new(
            Kind::Result,
            seq,
            &[&[reason as u8, slot.index()], &generation.to_le_bytes()],
        )
    }

    /// The reply as a packet to encode.
    pub fn packet(&self) -> Packet<'_> {
        Packet {
            kind: self.kind,
            seq: self.seq,
            payload: self.payload.get(..self.len).unwrap_or(&[]),
        }
    }

    /// Its kind.
    pub const fn kind(&self) -> Kind {
        self.kind
    }

    /// The reason of a NAK or RESULT (`Ok` for the others).
    pub fn reason(&self) -> Reason {
        match self.kind {
            Kind::Nak | Kind::Result => {
                Reason::from_u8(self.payload.first().copied().unwrap_or(0xFF))
            }
            _ => Reason::Ok,
        }
    }
}

/// Where the receiver is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    /// Writing, for the session numbered as the BEGIN said.
    Receiving(SlotWriter, u32),
    Committed(SlotId, u32),
}

/// The update receiver of one unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Receiver {
    layout: Layout,
    active: Option<Active>,
    state: State,
}

impl Receiver {
    /// A receiver for `layout`, running from `active` (what [`crate::slots::select`] chose at boot).
    pub const fn new(layout: Layout, active: Option<Active>) -> Self {
        Self {
            layout,
            active,
            state: State::Idle,
        }
    }

    /// True while an image is being received.
    pub const fn is_receiving(&self) -> bool {
        matches!(self.state, State::Receiving(..))
    }

    /// The slot and generation committed by this receiver, if any.
    pub const fn committed(&self) -> Option<(SlotId, u32)> {
        match self.state {
            State::Committed(slot, generation) => Some((slot, generation)),
            _ => None,
        }
    }

    /// The slot an update writes: never the active one.
    pub fn target(&self) -> SlotId {
        self.active.map_or(SlotId::A, |a| a.slot.other())
    }

    /// Handles one request; `serial` is the unit's serial number (bytes, at most [`MAX_SERIAL`]
    /// sent), `validate(flash, offset, len)` the image check run before the commit (after the
    /// read-back CRC), `Err` with the reason the RESULT carries.
    pub fn handle<F: NorFlash>(
        &mut self,
        flash: &mut F,
        request: &Packet<'_>,
        serial: &[u8],
        validate: impl FnOnce(&mut F, u32, u32) -> Result<(), Reason>,
    ) -> Reply {
        let seq = request.seq;
        match request.kind {
            Kind::Hello => self.info(seq, serial),
            Kind::Begin => self.begin(flash, request),
            Kind::Data => self.data(flash, request),
            Kind::Commit => self.commit(flash, seq, validate),
            Kind::Abort => match self.state {
                State::Committed(..) => Reply::nak(seq, Reason::RebootPending, 0),
                _ => {
                    self.state = State::Idle;
                    Reply::ack(seq)
                }
            },
            Kind::Ack | Kind::Nak | Kind::Result | Kind::Info => {
                Reply::nak(seq, Reason::Malformed, 0)
            }
        }
    }

    fn info(&self, seq: u16, serial: &[u8]) -> Reply {
        let (slot, generation) = self
            .active
            .map_or((0xFF, 0), |a| (a.slot.index(), a.header.generation));
        let serial = serial.get(..serial.len().min(MAX_SERIAL)).unwrap_or(&[]);
        Reply::new(
            Kind::Info,
            seq,
            &[
                &[slot],
                &generation.to_le_bytes(),
                &self.layout.capacity().to_le_bytes(),
                serial,
            ],
        )
    }

    fn begin<F: NorFlash>(&mut self, flash: &mut F, request: &Packet<'_>) -> Reply {
        let seq = request.seq;
        let (Some(length), Some(crc), Some(session), 12) = (
            request.u32_at(0),
            request.u32_at(4),
            request.u32_at(8),
            request.payload.len(),
        ) else {
            return Reply::nak(seq, Reason::Malformed, 0);
        };
        match self.state {
            State::Committed(..) => return Reply::nak(seq, Reason::RebootPending, 0),
            State::Receiving(w, open) => {
                let h = w.header();
                if open == session && h.length == length && h.payload_crc == crc {
                    // A repeat (its ACK was lost): nothing is erased again.
                    return Reply::ack(seq);
                }
                // Another session takes over: the slot is begun again below.
                self.state = State::Idle;
            }
            State::Idle => {}
        }
        if length == 0 {
            return Reply::nak(seq, Reason::Malformed, 0);
        }
        if length > self.layout.capacity() {
            return Reply::nak(seq, Reason::TooLarge, self.layout.capacity());
        }
        let generation = self
            .active
            .map_or(1, |a| a.header.generation.wrapping_add(1));
        let header = Header {
            generation,
            length,
            payload_crc: crc,
        };
        match SlotWriter::begin(flash, self.layout, self.target(), header) {
            Ok(w) => {
                self.state = State::Receiving(w, session);
                Reply::ack(seq)
            }
            Err(e) => {
                self.state = State::Idle;
                Reply::nak(seq, reason(&e), 0)
            }
        }
    }

    fn data<F: NorFlash>(&mut self, flash: &mut F, request: &Packet<'_>) -> Reply {
        let seq = request.seq;
        let (mut writer, session) = match self.state {
            State::Receiving(w, session) => (w, session),
            State::Committed(..) => return Reply::nak(seq, Reason::RebootPending, 0),
            State::Idle => return Reply::nak(seq, Reason::NotStarted, 0),
        };
        let (Some(offset), Some(chunk)) = (request.u32_at(0), request.payload.get(4..)) else {
            return Reply::nak(seq, Reason::Malformed, writer.written());
        };
        if chunk.is_empty() {
            return Reply::nak(seq, Reason::Malformed, writer.written());
        }
        let end = offset.saturating_add(chunk.len() as u32);
        if offset < writer.written() && end <= writer.written() {
            // A repeat of a chunk already written (its ACK was lost).
            return Reply::ack(seq);
        }
        match writer.write(flash, offset, chunk) {
            Ok(()) => {
                self.state = State::Receiving(writer, session);
                Reply::ack(seq)
            }
            Err(WriteError::Flash(_)) => {
                self.state = State::Idle;
                Reply::nak(seq, Reason::Flash, 0)
            }
            Err(e) => Reply::nak(seq, reason(&e), writer.written()),
        }
    }

    fn commit<F: NorFlash>(
        &mut self,
        flash: &mut F,
        seq: u16,
        validate: impl FnOnce(&mut F, u32, u32) -> Result<(), Reason>,
    ) -> Reply {
        let writer = match self.state {
            State::Receiving(w, _) => w,
            State::Committed(slot, generation) => {
                return Reply::result(seq, Reason::Ok, slot, generation);
            }
            State::Idle => return Reply::nak(seq, Reason::NotStarted, 0),
        };
        if !writer.is_complete() {
            return Reply::nak(seq, Reason::Incomplete, writer.written());
        }
        let (slot, generation) = (writer.slot(), writer.header().generation);
        // The writer takes a yes or no; the reason of a no is kept here for the RESULT.
        let mut refused = Reason::Invalid;
        let check = |f: &mut F, offset, len| match validate(f, offset, len) {
            Ok(()) => true,
            Err(why) => {
                refused = why;
                false
            }
        };
        match writer.commit(flash, check) {
            Ok(()) => {
                self.state = State::Committed(slot, generation);
                Reply::result(seq, Reason::Ok, slot, generation)
            }
            Err(WriteError::Invalid) => {
                self.state = State::Idle;
                Reply::result(seq, refused, slot, generation)
            }
            Err(e) => {
                self.state = State::Idle;
                Reply::result(seq, reason(&e), slot, generation)
            }
        }
    }
}

/// The wire's reason for a slot write error.
fn reason<E>(e: &WriteError<E>) -> Reason {
    match e {
        WriteError::Flash(_) => Reason::Flash,
        WriteError::TooLarge => Reason::TooLarge,
        WriteError::OutOfOrder { .. } => Reason::OutOfOrder,
        WriteError::Incomplete => Reason::Incomplete,
        WriteError::Crc => Reason::Crc,
        WriteError::Invalid => Reason::Invalid,
        _ => Reason::BadChunk,
    }
}
