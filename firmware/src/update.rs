//! The update task: bytes from the serial link in, replies out, the inactive slot written — run
//! below the sample loop's priority (the application's `update` task, priority 1, on every board:
//! [`crate::application`]), so the loop never waits for it.
//!
//! It is the core's [`Receiver`] behind the core's frame [`Decoder`]: one protocol frame of
//! receive buffer (79 B, [`tcomp_core::update::wire::MAX_FRAME`]), and the reply encoded into a
//! buffer of one reply frame.

use core::sync::atomic::{AtomicBool, AtomicU16, Ordering};
use embedded_storage::nor_flash::NorFlash;
use tcomp_core::frame::update_state;
use tcomp_core::slots::{Active, Layout, SlotId};
use tcomp_core::update::wire::Kind;
use tcomp_core::update::wire::{HEADER_LEN, MAX_SERIAL};
use tcomp_core::update::{Decoder, Reason, Receiver};

/// The longest reply frame (INFO with the longest serial).
pub const MAX_REPLY: usize = HEADER_LEN + 9 + MAX_SERIAL + 4;

/// The last update's outcome, published for the boot report (state << 8 | reason): the update
/// task runs in its own interrupt, the report is re-sent by the sample task.
static LAST_UPDATE: AtomicU16 = AtomicU16::new(0);

/// Set when an update ends (committed, refused or failed): the loop then sends its boot report
/// at once, so the outcome is on the link while the host still listens.
static REPORT_DUE: AtomicBool = AtomicBool::new(false);

/// The last update since boot as the boot report carries it: ([`update_state`], reason code).
pub fn last_update() -> (u8, u8) {
    let v = LAST_UPDATE.load(Ordering::Relaxed);
    ((v >> 8) as u8, v as u8)
}

/// True once after an update ended: the loop sends its boot report now, besides its cadence.
pub fn take_report_due() -> bool {
    REPORT_DUE.swap(false, Ordering::AcqRel)
}

/// The update task's state.
#[derive(Clone, Debug)]
pub struct UpdateTask {
    decoder: Decoder,
    receiver: Receiver,
    outcome: (u8, u8),
}

impl UpdateTask {
    /// A task for `layout`, running from `active` (the boot's choice).
    pub const fn new(layout: Layout, active: Option<Active>) -> Self {
        Self {
            decoder: Decoder::new(),
            receiver: Receiver::new(layout, active),
            outcome: (update_state::NONE, 0),
        }
    }

    /// Feeds one received byte; when it completes a request, handles it and encodes the reply into
    /// `reply`, returning its length. `serial` is the unit's serial number; `validate(flash,
    /// offset, len)` says whether the written slot holds an image this unit may run, and if not
    /// why ([`crate::image::acceptable`] is the check the boards use).
    pub fn push<F: NorFlash>(
        &mut self,
        byte: u8,
        flash: &mut F,
        serial: &[u8],
        validate: impl FnOnce(&mut F, u32, u32) -> Result<(), Reason>,
        reply: &mut [u8; MAX_REPLY],
    ) -> Option<usize> {
        let request = self.decoder.push(byte)?;
        let answer = self.receiver.handle(flash, &request, serial, validate);
        if answer.kind() == Kind::Result {
            let reason = answer.reason();
            let state = match reason {
                Reason::Ok => update_state::COMMITTED,
                Reason::Invalid
                | Reason::OtherUnit
                | Reason::Unsigned
                | Reason::UnknownKey
                | Reason::BadSignature => update_state::REFUSED,
                _ => update_state::FAILED,
            };
            self.outcome = (state, reason as u8);
            LAST_UPDATE.store(
                u16::from(state) << 8 | u16::from(reason as u8),
                Ordering::Relaxed,
            );
            REPORT_DUE.store(true, Ordering::Release);
        }
        answer.packet().encode(reply)
    }

    /// The last update's outcome on this task: ([`update_state`], reason code).
    pub const fn outcome(&self) -> (u8, u8) {
        self.outcome
    }

    /// The slot and generation committed, if an update has been (it runs from the next boot).
    pub const fn committed(&self) -> Option<(SlotId, u32)> {
        self.receiver.committed()
    }

    /// True while an image is being received.
    pub const fn is_receiving(&self) -> bool {
        self.receiver.is_receiving()
    }
}

/// The unit's serial number as the text the update protocol's HELLO answer carries: `0x` and 16
/// lower-case hex digits, the form `tcomp image --serial` accepts and `tcomp inspect` prints.
pub const fn serial_text(serial: u64) -> [u8; 18] {
    let mut out = [b'0'; 18];
    out[1] = b'x';
    let mut i = 0;
    while i < 16 {
        let nibble = ((serial >> (60 - 4 * i)) & 0xF) as u8;
        out[2 + i] = if nibble < 10 {
            b'0' + nibble
        } else {
            b'a' + nibble - 10
        };
        i += 1;
    }
    out
}
