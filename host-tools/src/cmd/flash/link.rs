//! The update over any byte link (`Read + Write`): a serial port for `tcomp flash`, a pair of pipes
//! in the tests. Requests go out one at a time; the bytes that come back are fed to two decoders,
//! the update replies' and the output frames', each skipping the other's frames as garbage.
//!
//! An update that fails while the unit holds its session (the link died mid-transfer) ends with
//! one ABORT, best effort: the unit's active slot is untouched either way, and the next run's
//! BEGIN (another session number) takes over what is left open.
//!
//! Nothing erases flash while the unit's loop runs (an erase would stall it for seconds): when the
//! slot an update needs still holds an earlier session's bytes, the unit refuses the BEGIN with a
//! flash error, resets, and its boot erases the slot before its watchdog starts.
//! [`transfer_through_reset`] waits for that boot and sends the image again, once, so a user's one
//! `tcomp flash` goes through.

use std::io::{ErrorKind, Read, Write};
use std::time::{Duration, Instant};
use tcomp_core::frame;
use tcomp_core::frame::status::FIRST_SAMPLE;
use tcomp_core::update::wire::{Decoder, MAX_FRAME};
use tcomp_core::update::{Failure, Info, Reason, Sender, Status};

/// How long to wait for replies.
#[derive(Clone, Copy, Debug)]
pub struct Timing {
    /// For every request but COMMIT.
    pub reply: Duration,
    /// For COMMIT: the unit reads its slot back and checks the image and its signature first.
    pub commit: Duration,
    /// For the unit's reset after it refused a BEGIN whose slot needs erasing: its boot erases
    /// one slot before the loop starts ([`RESET_ERASE`] on the STM32F407).
    pub reset: Duration,
}

/// The longest a unit takes to reset, erase a model slot at boot and send its first frame: the
/// STM32F407's 128 KiB sector erase takes 1–2 s typically and 4 s at most at ×32 parallelism
/// (DS8626, t_ERASE128KB), its boot a few ms more; 10 s leaves a margin for a slower part.
pub const RESET_ERASE: Duration = Duration::from_secs(10);

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
    /// Whether a data frame flagged `FIRST_SAMPLE` came after the unit's first reply: the unit
    /// booted during the update (it resets after refusing a BEGIN whose slot needs erasing).
    pub rebooted: bool,
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
    let mut rebooted = false;
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
                        rebooted |= first_sample(&f);
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
                    rebooted |= first_sample(&f);
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
        rebooted,
    })
}

/// Whether `f` is a unit's first sample after a boot.
fn first_sample(f: &frame::Frame) -> bool {
    f.channels().iter().any(|c| c.status & FIRST_SAMPLE != 0)
}

/// [`transfer`], then once more if the unit refused the BEGIN with a flash error and then reset:
/// the slot held an earlier session's bytes, which only the unit's boot erases (see the module
/// doc). The reset shows as a data frame flagged `FIRST_SAMPLE` (seen while the first transfer
/// listened for the unit's report, or within `timing.reset` after it); then the
/// image is sent again in session `session + 1`. Without that frame the first outcome stands (a
/// real flash error). Returns the outcome and whether the unit was waited for through its reset.
pub fn transfer_through_reset<L: Read + Write>(
    link: &mut L,
    image: &[u8],
    session: u32,
    timing: Timing,
    mut progress: impl FnMut(u32, u32),
) -> std::io::Result<(Outcome, bool)> {
    let first = transfer(link, image, session, timing, &mut progress)?;
    if first.status != Status::Failed(Failure::Unit(Reason::Flash))
        || !(first.rebooted || rebooted(link, timing.reset)?)
    {
        return Ok((first, false));
    }
    let again = transfer(link, image, session.wrapping_add(1), timing, progress)?;
    Ok((again, true))
}

/// Reads the link for up to `limit`, until a data frame flagged `FIRST_SAMPLE` (the unit's first
/// sample after a boot) arrives.
fn rebooted<L: Read>(link: &mut L, limit: Duration) -> std::io::Result<bool> {
    let deadline = Instant::now() + limit;
    let mut frames = frame::Decoder::new();
    let mut buf = [0u8; 4096];
    let mut booted = false;
    while !booted && Instant::now() < deadline {
        let got = match link.read(&mut buf) {
            Ok(k) => k,
            Err(e) if e.kind() == ErrorKind::BrokenPipe => {
                std::thread::sleep(Duration::from_millis(10));
                0
            }
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
                ) =>
            {
                0
            }
            Err(e) => return Err(e),
        };
        frames.feed_items(buf.get(..got).unwrap_or(&[]), |item| {
            if let frame::Item::Data(f) = item {
                booted |= first_sample(&f);
            }
        });
    }
    Ok(booted)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
    use tcomp_core::frame::{ChannelOutput, Frame};
    use tcomp_core::image::{Image, write_image};
    use tcomp_core::slots::Layout;
    use tcomp_core::slots::sim::{SimError, SimNor};
    use tcomp_core::update::Receiver;

    const SECTOR: usize = 4096;
    type Sim = SimNor<{ 2 * SECTOR }, SECTOR>;
    const LAYOUT: Layout = Layout {
        a: 0,
        b: SECTOR as u32,
        size: SECTOR as u32,
    };

    /// The unit's flash as the firmware's run-time flash (`slots::RunTime`) presents it while the
    /// loop runs: an erase of a blank range passes (nothing to do), of a written one fails; the
    /// boot erases.
    struct Flash {
        sim: Sim,
        loop_running: bool,
    }

    impl ErrorType for Flash {
        type Error = SimError;
    }

    impl ReadNorFlash for Flash {
        const READ_SIZE: usize = 1;
        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), SimError> {
            self.sim.read(offset, bytes)
        }
        fn capacity(&self) -> usize {
            self.sim.capacity()
        }
    }

    impl NorFlash for Flash {
        const WRITE_SIZE: usize = <Sim as NorFlash>::WRITE_SIZE;
        const ERASE_SIZE: usize = <Sim as NorFlash>::ERASE_SIZE;
        fn erase(&mut self, from: u32, to: u32) -> Result<(), SimError> {
            let blank = self
                .sim
                .bytes()
                .get(from as usize..to as usize)
                .is_some_and(|r| r.iter().all(|&b| b == 0xFF));
            match (self.loop_running, blank) {
                (true, true) => Ok(()),
                (true, false) => Err(SimError::PowerLost),
                (false, _) => self.sim.erase(from, to),
            }
        }
        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), SimError> {
            self.sim.write(offset, bytes)
        }
    }

    /// A unit on the other end of the link: the core's receiver over [`Flash`]. A BEGIN whose
    /// erase fails is answered (NAK, flash error) and then, if `resets`, the unit reboots: its
    /// boot erases, and the next read carries a data frame flagged `FIRST_SAMPLE`.
    struct Unit {
        flash: Flash,
        rx: Receiver,
        decoder: tcomp_core::update::wire::Decoder,
        out: Vec<u8>,
        resets: bool,
        boots: u32,
    }

    impl Unit {
        fn new(resets: bool) -> Self {
            Self {
                flash: Flash {
                    sim: Sim::new(),
                    loop_running: true,
                },
                rx: Receiver::new(LAYOUT, None),
                decoder: tcomp_core::update::wire::Decoder::new(),
                out: Vec::new(),
                resets,
                boots: 0,
            }
        }

        fn frame(&mut self, status: u16) {
            let f = Frame::new(0, 0, 200, &[ChannelOutput { value: 0.5, status }]);
            let mut b = [0u8; 64];
            let k = f.encode(&mut b).unwrap();
            self.out.extend_from_slice(&b[..k]);
        }
    }

    impl Write for Unit {
        fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
            for &b in bytes {
                let Some(p) = self.decoder.push(b) else {
                    continue;
                };
                let reply = self.rx.handle(&mut self.flash, &p, b"SN-1", |f, o, l| {
                    let mut bytes = vec![0u8; l as usize];
                    f.read(o, &mut bytes).map_err(|_| Reason::Flash)?;
                    Image::parse(&bytes)
                        .map(|_| ())
                        .map_err(|_| Reason::Invalid)
                });
                let mut f = [0u8; MAX_FRAME];
                let m = reply.packet().encode(&mut f).unwrap();
                self.out.extend_from_slice(&f[..m]);
                let refused_flash = reply.kind() == tcomp_core::update::wire::Kind::Nak
                    && reply.reason() == Reason::Flash;
                if refused_flash && self.resets {
                    // The reset: the boot erases both slots' leftovers, then the loop runs.
                    self.flash.loop_running = false;
                    self.flash.sim.erase(0, (2 * SECTOR) as u32).unwrap();
                    self.flash.loop_running = true;
                    self.rx = Receiver::new(LAYOUT, None);
                    self.boots += 1;
                    self.frame(FIRST_SAMPLE);
                }
            }
            Ok(bytes.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    impl Read for Unit {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if self.out.is_empty() {
                std::thread::sleep(Duration::from_millis(1));
                self.frame(0);
            }
            let n = buf.len().min(self.out.len());
            buf[..n].copy_from_slice(&self.out[..n]);
            self.out.drain(..n);
            Ok(n)
        }
    }

    fn image() -> Vec<u8> {
        let blob: Vec<u8> = (0..700u32).map(|i| (i as u8).wrapping_mul(7)).collect();
        let mut buf = vec![0u8; SECTOR];
        let n = write_image(&[(0, &blob), (1, &blob)], &mut buf).unwrap();
        buf.truncate(n);
        buf
    }

    const TIMING: Timing = Timing {
        reply: Duration::from_millis(50),
        commit: Duration::from_millis(200),
        reset: Duration::from_millis(500),
    };

    /// A slot left written (here: programmed before the session) makes the BEGIN's erase fail;
    /// the unit resets and its boot erases; one call goes through in a second session.
    #[test]
    fn a_begin_refused_for_a_written_slot_goes_through_the_units_reset() {
        let mut unit = Unit::new(true);
        unit.flash.sim.write(0, &[0u8; 8]).unwrap();
        let img = image();
        let (outcome, through_reset) =
            transfer_through_reset(&mut unit, &img, 7, TIMING, |_, _| {}).unwrap();
        assert!(through_reset);
        assert_eq!(unit.boots, 1);
        assert!(
            matches!(outcome.status, Status::Done { .. }),
            "{:?}",
            outcome.status
        );
    }

    /// The same refusal with no reset after it (a real flash error): the flash error stands,
    /// after waiting `timing.reset` for a boot that does not come.
    #[test]
    fn a_flash_error_without_a_reset_stands() {
        let mut unit = Unit::new(false);
        unit.flash.sim.write(0, &[0u8; 8]).unwrap();
        let t = Instant::now();
        let (outcome, through_reset) =
            transfer_through_reset(&mut unit, &image(), 7, TIMING, |_, _| {}).unwrap();
        assert!(!through_reset);
        assert_eq!(outcome.status, Status::Failed(Failure::Unit(Reason::Flash)));
        assert!(t.elapsed() >= TIMING.reset);
    }
}
