//! The host's side of an update as a state machine without I/O: which request to send next, and
//! what a reply or a timeout changes. `tcomp flash`, the QEMU update run and the power-loss test
//! all drive this one type, each over its own link (a serial port, QEMU's pty, a function call).
//!
//! Each request carries a sequence number; a reply with another number is stale (the reply to an
//! earlier copy) and ignored. A timeout repeats the same request with the same number, so a late
//! reply to the first copy still counts; the receiver treats the repeat as idempotent. A NAK that
//! names the offset the unit expects (a lost or reordered chunk, a COMMIT before all data) moves
//! the sender there; any other NAK or a failed RESULT ends the update.
//!
//! Each sender carries a session number (the caller draws it, e.g. from the clock): a BEGIN of a
//! new session takes over whatever an earlier, failed run left open on the unit. A sender that
//! gives up while the unit holds its session can say so with [`Sender::abort`] (ABORT; the unit's
//! active slot is untouched either way).

use super::wire::{Kind, MAX_CHUNK, MAX_FRAME, MAX_SERIAL, Packet, Reason};
use crate::crc::crc32;
use crate::slots::SlotId;

/// Timeouts in a row on one request before the sender gives up. With the reply timeout derived
/// from the link's speed (`tcomp flash`: 62 ms at 921,600 baud) a dead link fails within
/// 33 timeouts (under 3 s); at 1 % byte loss a 75-byte DATA frame and its 11-byte ACK both arrive
/// with probability 0.99^86 = 0.42, so 33 failures in a row on one chunk have probability
/// 0.58^33 ≈ 1.5·10⁻⁸ (with 8 retries it was 0.58^9 = 0.7 %, per chunk: most updates of a few
/// hundred chunks failed).
pub const MAX_RETRIES: u32 = 32;

/// What the unit said about itself (its INFO reply).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Info {
    /// The slot it runs from, if any.
    pub active: Option<SlotId>,
    /// That slot's generation (0 without one).
    pub generation: u32,
    /// The largest image a slot holds.
    pub capacity: u32,
    serial: [u8; MAX_SERIAL],
    serial_len: usize,
}

impl Info {
    /// The unit's serial number as it sent it.
    pub fn serial(&self) -> &[u8] {
        self.serial.get(..self.serial_len).unwrap_or(&[])
    }

    fn parse(p: &Packet<'_>) -> Option<Self> {
        let active = match *p.payload.first()? {
            0 => Some(SlotId::A),
            1 => Some(SlotId::B),
            _ => None,
        };
        let rest = p.payload.get(9..)?;
        let mut serial = [0u8; MAX_SERIAL];
        let serial_len = rest.len().min(MAX_SERIAL);
        serial
            .get_mut(..serial_len)?
            .copy_from_slice(rest.get(..serial_len)?);
        Some(Self {
            active,
            generation: p.u32_at(1)?,
            capacity: p.u32_at(5)?,
            serial,
            serial_len,
        })
    }
}

/// Where the update stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Requests remain; `sent` image bytes are acknowledged.
    Running {
        /// Image bytes acknowledged.
        sent: u32,
    },
    /// Committed: the unit boots `slot` (generation `generation`) from its next reset.
    Done {
        /// The slot written.
        slot: SlotId,
        /// Its generation.
        generation: u32,
    },
    /// Refused or failed.
    Failed(Failure),
}

/// Why an update failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// The unit refused (NAK) or reported a failed RESULT.
    Unit(Reason),
    /// [`MAX_RETRIES`] timeouts in a row.
    Timeout,
    /// The image is larger than the unit's slot.
    TooLarge {
        /// The unit's slot capacity.
        capacity: u32,
    },
    /// The host gave up the session (ABORT, whether or not the unit acknowledged it).
    Aborted,
}

impl core::fmt::Display for Failure {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Unit(r) => write!(f, "the unit refused: {r}"),
            Self::Timeout => write!(f, "no reply after {MAX_RETRIES} retries"),
            Self::Aborted => write!(f, "aborted by the host"),
            Self::TooLarge { capacity } => {
                write!(
                    f,
                    "the image is larger than the unit's slot ({capacity} bytes)"
                )
            }
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Hello,
    Begin,
    Data(u32),
    Commit,
    /// ABORT sent after `why` (the failure reported once it is answered or times out).
    Abort(Failure),
    End(Status),
}

/// The host's update of one image.
#[derive(Clone, Debug)]
pub struct Sender<'a> {
    image: &'a [u8],
    crc: u32,
    session: u32,
    step: Step,
    seq: u16,
    retries: u32,
    sent: u32,
    info: Option<Info>,
    /// Total timeouts and NAK-driven rewinds, for the report.
    repeats: u32,
    aborted: bool,
}

impl<'a> Sender<'a> {
    /// An update of `image` (checked by the caller) in session `session`, starting with HELLO.
    /// Two runs should not share a session number (a unit still holding the first would take the
    /// second's BEGIN for a repeat).
    pub fn new(image: &'a [u8], session: u32) -> Self {
        Self {
            image,
            crc: crc32(image),
            session,
            step: Step::Hello,
            seq: 1,
            retries: 0,
            sent: 0,
            info: None,
            repeats: 0,
            aborted: false,
        }
    }

    /// Where the update stands.
    pub fn status(&self) -> Status {
        match self.step {
            Step::End(s) => s,
            _ => Status::Running { sent: self.sent },
        }
    }

    /// The unit's INFO, once received.
    pub const fn info(&self) -> Option<Info> {
        self.info
    }

    /// The sequence number of the current request (a reply with it answers that request).
    pub const fn seq(&self) -> u16 {
        self.seq
    }

    /// Requests sent again (after a timeout or a NAK naming another offset).
    pub const fn repeats(&self) -> u32 {
        self.repeats
    }

    /// The image's length.
    pub fn len(&self) -> u32 {
        self.image.len() as u32
    }

    /// True for an empty image (refused by the unit).
    pub fn is_empty(&self) -> bool {
        self.image.is_empty()
    }

    /// Encodes the current request into `out`; `None` once the update has ended.
    pub fn request(&self, out: &mut [u8; MAX_FRAME]) -> Option<usize> {
        let mut payload = [0u8; 4 + MAX_CHUNK];
        let (kind, len) = match self.step {
            Step::Hello => (Kind::Hello, 0),
            Step::Begin => {
                payload[..4].copy_from_slice(&self.len().to_le_bytes());
                payload[4..8].copy_from_slice(&self.crc.to_le_bytes());
                payload[8..12].copy_from_slice(&self.session.to_le_bytes());
                (Kind::Begin, 12)
            }
            Step::Data(offset) => {
                let chunk = self.chunk(offset);
                payload[..4].copy_from_slice(&offset.to_le_bytes());
                payload.get_mut(4..4 + chunk.len())?.copy_from_slice(chunk);
                (Kind::Data, 4 + chunk.len())
            }
            Step::Commit => (Kind::Commit, 0),
            Step::Abort(_) => (Kind::Abort, 0),
            Step::End(_) => return None,
        };
        Packet {
            kind,
            seq: self.seq,
            payload: payload.get(..len)?,
        }
        .encode(out)
    }

    fn chunk(&self, offset: u32) -> &'a [u8] {
        let start = (offset as usize).min(self.image.len());
        let end = (start + MAX_CHUNK).min(self.image.len());
        self.image.get(start..end).unwrap_or(&[])
    }

    fn advance(&mut self, step: Step) {
        self.step = step;
        self.seq = self.seq.wrapping_add(1);
        self.retries = 0;
    }

    /// True while the unit may hold this sender's session open (BEGIN sent, no outcome yet).
    pub const fn holds_session(&self) -> bool {
        matches!(self.step, Step::Data(_) | Step::Commit)
    }

    /// Gives the session up: the next request is ABORT when the unit may hold it open, and the
    /// update ends as [`Failure::Aborted`] (or as the failure that made the caller abort, passed
    /// through [`Sender::abort_after`]).
    pub fn abort(&mut self) {
        self.abort_after(Failure::Aborted);
    }

    /// [`Sender::abort`], reporting `why` as the outcome.
    pub fn abort_after(&mut self, why: Failure) {
        match self.step {
            Step::Begin | Step::Data(_) | Step::Commit => {
                self.aborted = true;
                self.advance(Step::Abort(why));
            }
            Step::Hello => self.step = Step::End(Status::Failed(why)),
            Step::Abort(_) | Step::End(_) => {}
        }
    }

    /// Takes a reply; one for another request is ignored.
    pub fn on_reply(&mut self, reply: &Packet<'_>) {
        if reply.seq != self.seq || matches!(self.step, Step::End(_)) {
            return;
        }
        if let Step::Abort(why) = self.step {
            // ACK or a NAK (no session open any more): the session is over either way.
            if matches!(reply.kind, Kind::Ack | Kind::Nak) {
                self.advance(Step::End(Status::Failed(why)));
            }
            return;
        }
        let reason = Reason::from_u8(reply.payload.first().copied().unwrap_or(0xFF));
        let next = match (reply.kind, self.step) {
            (Kind::Info, Step::Hello) => match Info::parse(reply) {
                Some(info) if info.capacity < self.len() => {
                    Step::End(Status::Failed(Failure::TooLarge {
                        capacity: info.capacity,
                    }))
                }
                Some(info) => {
                    self.info = Some(info);
                    Step::Begin
                }
                None => Step::End(Status::Failed(Failure::Unit(Reason::Malformed))),
            },
            (Kind::Ack, Step::Begin) => Step::Data(0),
            (Kind::Ack, Step::Data(offset)) => {
                let end = offset + self.chunk(offset).len() as u32;
                self.sent = self.sent.max(end);
                if end >= self.len() {
                    Step::Commit
                } else {
                    Step::Data(end)
                }
            }
            (Kind::Nak, Step::Data(_) | Step::Commit)
                if matches!(reason, Reason::OutOfOrder | Reason::Incomplete) =>
            {
                self.repeats += 1;
                match reply.u32_at(1) {
                    Some(expected) if expected < self.len() => Step::Data(expected),
                    Some(expected) if expected == self.len() => Step::Commit,
                    _ => Step::End(Status::Failed(Failure::Unit(reason))),
                }
            }
            (Kind::Result, Step::Commit) if reason == Reason::Ok => {
                let slot = match reply.payload.get(1) {
                    Some(1) => SlotId::B,
                    _ => SlotId::A,
                };
                let generation = reply.u32_at(2).unwrap_or(0);
                self.sent = self.len();
                Step::End(Status::Done { slot, generation })
            }
            (Kind::Nak | Kind::Result, _) => Step::End(Status::Failed(Failure::Unit(reason))),
            _ => return,
        };
        self.advance(next);
    }

    /// No reply in time: the same request goes again, until [`MAX_RETRIES`]. An unanswered
    /// ABORT is given up after one timeout (the link is likely gone; the unit's next BEGIN takes
    /// over anyway).
    pub fn on_timeout(&mut self) {
        match self.step {
            Step::End(_) => return,
            Step::Abort(why) => {
                self.step = Step::End(Status::Failed(why));
                return;
            }
            _ => {}
        }
        self.retries += 1;
        self.repeats += 1;
        if self.retries > MAX_RETRIES {
            // Giving up while the unit may hold the session: say so (one try).
            self.abort_after(Failure::Timeout);
            if !matches!(self.step, Step::Abort(_)) {
                self.step = Step::End(Status::Failed(Failure::Timeout));
            }
        }
    }

    /// True once an ABORT has been the current request.
    pub const fn aborted(&self) -> bool {
        self.aborted
    }

    /// True when the current request is COMMIT: the unit then reads the whole slot back and checks
    /// the image (and its signature) before it answers, so a caller waits longer for it.
    pub const fn is_committing(&self) -> bool {
        matches!(self.step, Step::Commit)
    }
}
