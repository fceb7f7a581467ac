//! The model update over UART 0: the update task's static, its installation before the loop
//! starts, and the receive interrupt that feeds it, below the sample timer's priority.

use super::*;
use tcomp_core::slots::Active;
use tcomp_core::update::Reason;
use tcomp_firmware::update::{MAX_REPLY, UpdateTask};

/// What the receive interrupt owns.
pub(super) struct Updater {
    pub(super) task: UpdateTask,
    pub(super) flash: RamFlash,
}

/// The update task's state, in its static before the UART interrupt is unmasked. Not inlined,
/// like `start_loop`.
#[inline(never)]
pub(super) fn install_update(flash: RamFlash, active: Option<Active>) {
    let update: *mut Option<Updater> = &raw mut UPDATE;
    // SAFETY: the UART interrupt, UPDATE's only other user, is not unmasked yet.
    unsafe {
        *update = Some(Updater {
            task: UpdateTask::new(QEMU_LAYOUT, active),
            flash,
        });
    }
}

/// The update task runs in UART 0's receive interrupt, below the sample timer's priority, so the
/// loop preempts it (an erase, a chunk, the read-back CRC) at every timer edge.
#[inline(never)]
pub(super) fn start_update(mut nvic: NVIC) -> Uart {
    // SAFETY: priorities change before either interrupt is unmasked; a lower number preempts.
    unsafe {
        nvic.set_priority(Irq(TIMER0_IRQ as u16), 0x00);
        nvic.set_priority(Irq(UART0_RX_IRQ as u16), 0x80);
    }
    Uart::handle0()
}

/// UART 0's receive interrupt: every waiting byte through the update task, each reply sent whole.
pub(super) fn on_receive() {
    let update: *mut Option<Updater> = &raw mut UPDATE;
    // SAFETY: `main` set UPDATE before unmasking this interrupt and touches it again only after
    // masking it; the interrupt does not preempt itself.
    let Some(u) = (unsafe { (*update).as_mut() }) else {
        return;
    };
    let port = Uart::handle0();
    port.clear_rx_interrupt();
    let mut reply = [0u8; MAX_REPLY];
    while let Some(byte) = port.read() {
        // The new image must read and be made for this unit: an image for another unit is
        // refused before the commit, so the unit keeps its models.
        // The new image must pass the unit's trust check (made for this unit, signed by a key
        // of the KEYS region) before the commit word is written: a refused image is never
        // committed, and the unit keeps its models.
        let validate = |f: &mut RamFlash, off, len| {
            f.bytes(off, len)
                .map_or(Err(Reason::Flash), |b| trust().check_payload(b).map(|_| ()))
        };
        if let Some(n) = u
            .task
            .push(byte, &mut u.flash, &SERIAL, validate, &mut reply)
        {
            // Whole, between two frames of the loop: the timer interrupt waits for these bytes.
            cortex_m::interrupt::free(|_| port.write_all(reply.get(..n).unwrap_or(&[])));
        }
    }
    let state = match (u.task.committed(), u.task.is_receiving()) {
        (Some(_), _) => COMMITTED,
        (None, true) => 1,
        (None, false) => 0,
    };
    UPDATE_STATE.store(state, Ordering::Release);
}
