//! The serial link as the application sees it: a frame queue the sample task and the update task
//! fill whole frames into and the drain empties into the board's transmitter, and a receive ring
//! the board fills (QEMU: its receive interrupt above the sample task; the STM32F407: DMA) and the
//! update task empties.
//!
//! **Overflow policy.** A frame (or a reply) goes into the queue whole or not at all: never split,
//! never cut, so the byte stream stays a sequence of whole frames the host's decoder resyncs on
//! without losing a second one. A data frame that does not fit is dropped and counted; its
//! sequence number is still used, so the host sees the gap (`tcomp frames` counts it lost). A reply
//! that does not fit is dropped too: the host repeats its request after its timeout.
//!
//! **Size.** [`TX_QUEUE`] bytes hold 1,023 bytes: twelve 84-byte six-channel frames, 60 ms of
//! output at 200 Hz; at 921,600 baud one frame leaves in 0.91 ms, so the queue fills only when the
//! line stops.

use heapless::spsc::{Consumer, Producer, Queue};

/// Bytes of the frame queue's storage (it holds one less).
pub const TX_QUEUE: usize = 1024;
/// The frame queue.
pub type TxQueue = Queue<u8, TX_QUEUE>;
/// Its producer side (the sample task's frames, the update task's replies).
pub type TxProducer = Producer<'static, u8>;
/// Its consumer side (the drain).
pub type TxConsumer = Consumer<'static, u8>;

/// A transmitter the drain writes into.
pub trait SerialTx {
    /// Whether the transmitter takes a byte now.
    fn ready(&mut self) -> bool;
    /// Writes a byte (after [`ready`](Self::ready) said yes).
    fn write(&mut self, byte: u8);
    /// Interrupt on "ready" while `on` (the drain's interrupt), off once the queue is empty.
    fn listen(&mut self, on: bool);
}

/// A source of received bytes the update task empties.
pub trait RxSource {
    /// The next received byte, if any.
    fn pop(&mut self) -> Option<u8>;
    /// Bytes lost before they were read (the ring overflowed, the receiver overran), so far.
    fn lost(&self) -> u32 {
        0
    }
}

/// The board's receive interrupt (QEMU: moves the byte into the ring; the STM32F407: the DMA's
/// half/full-transfer flags).
pub trait ReceiveIrq {
    /// Serves the interrupt.
    fn on_interrupt(&mut self);
}

/// Enqueues `bytes` whole or not at all.
pub fn enqueue_whole(p: &mut Producer<'_, u8>, bytes: &[u8]) -> bool {
    if p.capacity() - p.len() < bytes.len() {
        return false;
    }
    for &b in bytes {
        let _ = p.enqueue(b);
    }
    true
}

/// Moves queued bytes into `tx` while it takes them; returns whether bytes are left (the drain's
/// interrupt then stays on).
pub fn drain(c: &mut Consumer<'_, u8>, tx: &mut impl SerialTx) -> bool {
    while tx.ready() {
        match c.dequeue() {
            Some(b) => tx.write(b),
            None => {
                tx.listen(false);
                return false;
            }
        }
    }
    let left = c.peek().is_some();
    tx.listen(left);
    left
}

impl RxSource for Consumer<'_, u8> {
    fn pop(&mut self) -> Option<u8> {
        self.dequeue()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// A transmitter that takes `budget` bytes, then is busy.
    struct Line {
        sent: Vec<u8>,
        budget: usize,
        listening: bool,
    }

    impl SerialTx for Line {
        fn ready(&mut self) -> bool {
            self.sent.len() < self.budget
        }
        fn write(&mut self, byte: u8) {
            self.sent.push(byte);
        }
        fn listen(&mut self, on: bool) {
            self.listening = on;
        }
    }

    #[test]
    fn frames_go_in_whole_or_not_at_all_and_leave_in_order() {
        let mut q: Queue<u8, 16> = Queue::new();
        let (mut p, mut c) = q.split();
        assert!(enqueue_whole(&mut p, &[1; 10]));
        // 5 bytes of room left: a 6-byte frame is dropped whole, a 5-byte one fits.
        assert!(!enqueue_whole(&mut p, &[2; 6]));
        assert!(enqueue_whole(&mut p, &[3; 5]));
        let mut line = Line {
            sent: Vec::new(),
            budget: 12,
            listening: false,
        };
        assert!(drain(&mut c, &mut line));
        assert!(line.listening);
        line.budget = 100;
        assert!(!drain(&mut c, &mut line));
        assert!(!line.listening);
        let mut want = std::vec![1; 10];
        want.extend([3; 5]);
        assert_eq!(line.sent, want);
    }
}
