//! The update over any byte link (`Read + Write`): a serial port for `tcomp flash`, a pair of pipes
//! in the tests. Requests go out one at a time; the bytes that come back are fed to two decoders,
//! the update replies' and the output frames', each skipping the other's frames as garbage.
//!
//! An update that fails while the unit holds its session (the link died mid-transfer) ends with
//! one ABORT, best effort: the unit's active slot is untouched either way, and the next run's
//! BEGIN (another session number) takes over what is left open.

use std::io::{ErrorKind, Read, Write};
use std::time::{Duration, Instant};
use tcomp_core::frame;
use tcomp_core::update::wire::{Decoder, MAX_FRAME};
use tcomp_core::update::{Failure, Info, Sender, Status};

/// How long to wait for replies.
#[derive(Clone, Copy, Debug)]
pub struct Timing {
    /// For every request but COMMIT.
    pub reply: Duration,
    /// For COMMIT: the unit reads its slot back and checks the image and its signature first.
    pub commit: Duration,
}

/// What an update did.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// How it ended.
    pub status: Status,
    /// The unit's INFO.
    pub info: Option<Info>,
    /// Requests sent again.
    pub repeats: u32,
    /// Whether an ABORT was sent (the update failed while the unit held its session).
    pub aborted: bool,
    /// The unit's output frames seen meanwhile.
    pub output: frame::Stats,
    /// Their first and last sequence numbers.
    pub first_sequence: Option<u32>,
    /// The unit's last boot report seen (the unit sends one as soon as an update ends: its image
    /// state, signer and the update's outcome with its reason).
    pub report: Option<frame::BootReport>,
    /// See `first_sequence`.
    pub last_sequence: Option<u32>,
}

/// Sends `image` in session `session` and waits for each reply as `timing` says;
/// `progress(sent, total)` after each ACK.
/// The output frames are counted from the unit's first reply (INFO) to its last: what came before
/// is not part of the update (and a port opened a moment ago may have passed it through a line
/// discipline that was not raw yet).
pub fn transfer<L: Read + Write>(
    link: &mut L,
    image: &[u8],
    session: u32,
    timing: Timing,
    mut progress: impl FnMut(u32, u32),
) -> std::io::Result<Outcome> {
    let mut tx = Sender::new(image, session);
    let mut replies = Decoder::new();
    let mut outputs = frame::Decoder::new();
    let (mut first, mut last) = (None, None);
    let mut report = None;
    let mut request = [0u8; MAX_FRAME];
    let mut buf = [0u8; 4096];
    while let Some(n) = tx.request(&mut request) {
        // A link whose other end is not there (yet) — a pty before QEMU reads it, a port mid-reset —
        // loses this request like a noisy line would: the timeout sends it again.
        match link
            .write_all(request.get(..n).unwrap_or(&[]))
            .and_then(|()| link.flush())
        {
            Err(e) if e.kind() != ErrorKind::BrokenPipe => return Err(e),
            _ => {}
        }
        let seq = tx.seq();
        let wait = if tx.is_committing() {
            timing.commit.max(timing.reply)
        } else {
            timing.reply
        };
        let deadline = Instant::now() + wait;
        let answered = loop {
            let got = match link.read(&mut buf) {
                Ok(0) => 0,
                Ok(k) => k,
                Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock) => 0,
                Err(e) if e.kind() == ErrorKind::Interrupted => 0,
                Err(e) if e.kind() == ErrorKind::BrokenPipe => {
                    std::thread::sleep(Duration::from_millis(10));
                    0
                }
                Err(e) => return Err(e),
            };
            for &b in buf.get(..got).unwrap_or(&[]) {
                // Counted from the unit's first reply on: the update's span.
                let counting = tx.info().is_some();
                outputs.feed_items(&[b], |item| match item {
                    frame::Item::Data(f) if counting => {
                        first.get_or_insert(f.sequence);
                        last = Some(f.sequence);
                    }
                    frame::Item::Boot(r) => report = Some(r),
                    frame::Item::Data(_) => {}
                });
                if !counting {
                    outputs = frame::Decoder::new();
                }
                if let Some(p) = replies.push(b) {
                    tx.on_reply(&p);
                }
                while let Some(p) = replies.poll() {
                    tx.on_reply(&p);
                }
            }
            if tx.seq() != seq || !matches!(tx.status(), Status::Running { .. }) {
                break true;
            }
            if Instant::now() >= deadline {
                break false;
            }
        };
        if !answered {
            tx.on_timeout();
        }
        if let Status::Running { sent } = tx.status() {
            progress(sent, tx.len());
        }
    }
    // The unit answers the update's end with a boot report (its outcome and reason): when the
    // unit answered the last request (not after a timeout), listen for it a little longer, ten
    // reply timeouts at most (620 ms at 921,600 baud; a board sends it within one period).
    let answered = matches!(
        tx.status(),
        Status::Done { .. } | Status::Failed(Failure::Unit(_))
    );
    if answered {
        let deadline = Instant::now() + timing.commit.min(timing.reply * 10);
        let ended = |r: &Option<frame::BootReport>| {
            r.is_some_and(|r| r.update != frame::update_state::NONE)
        };
        while !ended(&report) && Instant::now() < deadline {
            let got = match link.read(&mut buf) {
                Ok(k) => k,
                Err(e) if e.kind() == ErrorKind::BrokenPipe => break,
                Err(_) => 0,
            };
            // Still counted: the frames while it listens are in the counts, so in the span too.
            outputs.feed_items(buf.get(..got).unwrap_or(&[]), |item| match item {
                frame::Item::Boot(r) => report = Some(r),
                frame::Item::Data(f) => {
                    first.get_or_insert(f.sequence);
                    last = Some(f.sequence);
                }
            });
        }
    }
    Ok(Outcome {
        report,
        status: tx.status(),
        info: tx.info(),
        repeats: tx.repeats(),
        aborted: tx.aborted(),
        output: outputs.stats(),
        first_sequence: first,
        last_sequence: last,
    })
}
