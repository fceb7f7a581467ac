//! The sample interrupt's state and its work: one timer edge served — the replay board's snapshot
//! read, the loop stepped, the record compared with the host's, the frame sent, the watchdog fed.

use super::*;

/// What the sample interrupt owns.
pub(super) struct Loop {
    pub(super) app: &'static mut App<'static>,
    pub(super) run: &'static mut Run,
    pub(super) vector: Vector<'static>,
    pub(super) board: Board,
    pub(super) config: &'static [ChannelConfig],
    pub(super) uart: Uart,
    pub(super) timer: Timer,
    pub(super) time: TimeBase,
    pub(super) watchdog: Watchdog,
    pub(super) counter: InstructionCounter,
    pub(super) check: TimeCheck,
    /// Time base at the next timer edge due (wrapping with the 32-bit time base), and the edges
    /// served so far.
    pub(super) next_edge: u32,
    pub(super) edges: u32,
    /// SysTick at the previous interrupt (for `period_ticks`).
    pub(super) last_entry: u32,
    /// The first frame of this boot carries the reset cause.
    pub(super) boot_flags: u16,
    /// What this boot loaded, re-sent every `REPORT_PERIODS` samples.
    pub(super) report: &'static mut BootReport,
    /// The last period served past the vector's end while holding for an update (0: none).
    pub(super) held: u32,
}

impl Loop {
    /// Past the vector's last sample of a [`HOLD_FOR_UPDATE`] vector while no update has
    /// committed: one more period of the loop on the last record's inputs (its frame sent, not
    /// compared or counted), so an update in progress never sees the unit stop. Bounded by
    /// [`HOLD_LIMIT`] periods of guest time. Returns whether it held.
    fn hold(&mut self, n: usize) -> bool {
        let waiting = self.vector.flags & HOLD_FOR_UPDATE != 0
            && UPDATE_STATE.load(Ordering::Acquire) != COMMITTED;
        let Some(last) = self.vector.samples.checked_sub(1) else {
            return false;
        };
        if !waiting || n - last > HOLD_LIMIT {
            return false;
        }
        self.vector.load(last, &mut self.board);
        let mut out = [Record::default(); MAX_CHANNELS];
        let k = self.config.len().min(MAX_CHANNELS);
        let out = out.get_mut(..k).unwrap_or(&mut []);
        let (thermometers, counters) = self.board.snapshot();
        self.app.sample_snapshot(thermometers, counters, out);
        let timestamp = self
            .vector
            .timestamp(last)
            .wrapping_add((n - last) as u64 * TICKS_PER_PERIOD);
        let frame = self.app.frame(n as u32, timestamp, TICK_HZ, out);
        let mut bytes = [0u8; MAX_FRAME_LEN];
        if let Ok(len) = frame.encode(&mut bytes) {
            self.uart.write_all(bytes.get(..len).unwrap_or(&[]));
        }
        if tcomp_firmware::update::take_report_due() {
            self.send_report(n as u32 + 1);
        }
        self.held = n as u32;
        true
    }

    /// Sends the boot report, stamped with the next data frame's sequence number.
    pub(super) fn send_report(&mut self, sequence: u32) {
        tcomp_firmware::boot::stamp(self.report, sequence);
        send_report(&self.uart, self.report);
    }
}

impl Loop {
    /// One timer period: one sample of the vector through the loop, its frame out of the UART.
    pub(super) fn tick(&mut self) {
        self.timer.clear();
        self.watchdog.feed();
        let entry = self.time.now();
        // Which timer edge this is: lateness beyond a quarter period is an overrun of the previous
        // sample, and whole periods that passed unserved were missed (never merged silently).
        // (Entered before the edge it was due for cannot happen; read as on time, not as 2³² late.)
        let since = match entry.wrapping_sub(self.next_edge) {
            s if s > u32::MAX / 2 => 0,
            s => s,
        };
        let missed = since / PERIOD;
        let late = since % PERIOD > PERIOD / 4 || missed > 0;
        self.next_edge = self.next_edge.wrapping_add(PERIOD.wrapping_mul(missed + 1));
        let previous_edges = self.edges;
        self.edges += 1;
        // The vector's records of the missed edges are skipped: the counter block latched over them.
        let n = self.run.next as usize + missed as usize;
        if n >= self.vector.samples {
            // Past the end: the periods count on from the last one served.
            let n = match self.held {
                0 => n,
                h => h as usize + 1 + missed as usize,
            };
            if self.hold(n) {
                return;
            }
            self.timer.stop();
            DONE.store(true, Ordering::Release);
            return;
        }
        let injected = self.vector.board_faults(n);
        self.vector.load(n, &mut self.board);
        let mut out = [Record::default(); MAX_CHANNELS];
        let k = self.config.len().min(MAX_CHANNELS);
        let out = out.get_mut(..k).unwrap_or(&mut []);
        if missed > 0 {
            self.app
                .skip_periods(u16::try_from(missed).unwrap_or(u16::MAX));
        }
        let (thermometers, counters) = self.board.snapshot();
        let i0 = self.counter.now();
        self.app.sample_snapshot(thermometers, counters, out);
        let i1 = self.counter.now();
        let instr = self.counter.ticks_between(i0, i1) * INSTRUCTIONS_PER_TICK;
        let r = &mut *self.run;
        r.instr_sum = r.instr_sum.saturating_add(instr);
        // The sample after missed periods carries every filter across the gap (more work, once,
        // after an overrun): counted apart, with its own budget.
        if missed > 0 {
            r.instr_max_gap = r.instr_max_gap.max(instr);
        } else if instr > r.instr_max {
            r.instr_max = instr;
            r.instr_max_at = n as u32;
        }
        let systick = self.counter.now();
        if r.period_ticks == 0 && previous_edges != 0 {
            r.period_ticks = self.last_entry.wrapping_sub(systick) & 0xFF_FFFF;
        }
        self.last_entry = systick;
        r.late += u32::from(late);
        r.missed += missed;
        let mut board_flags = self.check.check(self.vector.timestamp(n), missed) | self.boot_flags;
        if late {
            board_flags |= status::OVERRUN;
        }
        self.boot_flags = 0;
        for (c, rec) in out.iter_mut().enumerate() {
            let expected = self.vector.expected(n, c);
            if rec.compensated.to_bits() != expected.compensated.to_bits()
                || rec.status != expected.status
            {
                r.mismatches += 1;
            }
            r.hash = fold_hash(r.hash, rec);
            rec.status |= board_flags;
            if rec.status != 0 {
                r.flagged += 1;
            }
        }
        let frame = self
            .app
            .frame(n as u32, self.vector.timestamp(n), TICK_HZ, out);
        let mut bytes = [0u8; MAX_FRAME_LEN];
        if let Ok(len) = frame.encode(&mut bytes) {
            self.uart.write_all(bytes.get(..len).unwrap_or(&[]));
        }
        if (n as u32 + 1).is_multiple_of(REPORT_PERIODS) || tcomp_firmware::update::take_report_due()
        {
            self.send_report(n as u32 + 1);
        }
        let r = &mut *self.run;
        r.samples += 1;
        r.next = n as u32 + 1;
        if injected & HANG != 0 {
            // The loop hangs: only the watchdog gets the board out of here.
            #[allow(clippy::empty_loop)]
            loop {}
        }
        if injected & STALL != 0 {
            // This sample overruns its period by half a period: the next one is late.
            while self.time.now().wrapping_sub(entry) < PERIOD + PERIOD / 2 {}
        }
        if injected & MISS != 0 {
            // This sample overruns past the next timer edge: that period is missed entirely.
            while self.time.now().wrapping_sub(entry) < 2 * PERIOD + PERIOD / 2 {}
        }
    }
}

/// Encodes and sends a boot report. Not inlined, so its buffer is not part of the sample
/// interrupt's frame.
#[inline(never)]
pub(super) fn send_report(uart: &Uart, report: &BootReport) {
    let mut bytes = [0u8; MAX_FRAME_LEN];
    if let Some(len) = report.encode(&mut bytes) {
        uart.write_all(bytes.get(..len).unwrap_or(&[]));
    }
}
