//! The console USART at interrupt level: the receive read and the transmit queue.
//!
//! Set-up, the receive interrupt and the transmit half are the HAL's (`f405::bring_up`). The
//! receive read is the PAC's, not the HAL's: on an overrun (ORE) the HAL's read drops the byte
//! in DR, which the reference manual says is valid, and that byte may end a `stop` line.
//! QEMU (7.2) raises no transmit-empty interrupt: there the control tick pends the console
//! interrupt, which sends what 115200 baud sends in a tick (docs/firmware.md "QEMU limits").
//! Not here: what the bytes mean (`crate::rx`, the command side).

use super::f405::{ConsoleRx, ConsoleTx};
use heapless::Deque;
use stm32f4xx_hal::{pac, prelude::*};

/// The byte received, if any, and whether bytes after it were lost (overrun). Reading DR
/// clears RXNE and ORE.
pub fn receive(_rx: &mut ConsoleRx) -> Option<(u8, bool)> {
    // SAFETY: reads of USART1's SR and DR; `_rx`, the receive half, is the one reader.
    let usart = unsafe { &*pac::USART1::ptr() };
    let sr = usart.sr().read();
    if sr.rxne().bit_is_set() || sr.ore().bit_is_set() {
        Some((usart.dr().read().dr().bits() as u8, sr.ore().bit_is_set()))
    } else {
        None
    }
}

/// Bytes waiting to be sent (less on the Cortex-M3 image's 20 KiB of RAM: 768 since its
/// plant and read-back checks took 256 bytes of statics, issue 54; a reply line is at most 512).
#[cfg(not(m3))]
pub const TX_RING: usize = 2048;
#[cfg(m3)]
pub const TX_RING: usize = 768;
/// Kept free in the transmit queue for `ok stopped` (written from the console interrupt).
pub const TX_RESERVE: usize = 16;
const STOP_REPLY: &[u8] = b"ok stopped\r\n";
/// 115200 baud, 10 bits a byte: 11.5 bytes per ms.
#[cfg(feature = "qemu")]
const QEMU_TX_BYTES_PER_TICK: usize = 12;

/// The transmit queue and the transmit half: whole lines from the command side, `ok stopped`
/// from the console interrupt (between lines), sent by the console interrupt.
pub struct TxQueue {
    q: Deque<u8, TX_RING>,
    /// `ok stopped` replies that found no room yet.
    owed_stops: u8,
    tx: ConsoleTx,
}

impl TxQueue {
    pub fn new(tx: ConsoleTx) -> Self {
        TxQueue { q: Deque::new(), owed_stops: 0, tx }
    }
    fn free(&self) -> usize {
        self.q.capacity() - self.q.len()
    }
    /// Queue `b` whole (the caller checked the room).
    pub fn push_all(&mut self, b: &[u8]) {
        for &c in b {
            let _ = self.q.push_back(c);
        }
        #[cfg(feature = "hw")]
        self.tx.listen();
    }
    /// Queue one reply line if it fits with `TX_RESERVE` to spare and no `ok stopped` is
    /// owed; false if not (the caller waits).
    pub fn push_line(&mut self, line: &[u8]) -> bool {
        self.pay_stops();
        let fits = self.owed_stops == 0 && self.free() >= line.len() + TX_RESERVE;
        if fits {
            self.push_all(line);
        }
        fits
    }
    /// Nothing left to send (the board's last byte may still be in the shift register).
    pub fn is_empty(&self) -> bool {
        self.q.is_empty() && self.owed_stops == 0
    }
    pub fn push_stop_reply(&mut self) {
        self.pay_stops();
        if self.owed_stops == 0 && self.free() >= STOP_REPLY.len() {
            self.push_all(STOP_REPLY);
        } else {
            self.owed_stops = self.owed_stops.saturating_add(1);
        }
    }
    fn pay_stops(&mut self) {
        while self.owed_stops > 0 && self.free() >= STOP_REPLY.len() {
            self.push_all(STOP_REPLY);
            self.owed_stops -= 1;
        }
    }
    /// From the console interrupt: the board sends one byte per transmit-empty interrupt and
    /// stops listening when the queue is empty; QEMU (its transmit register is always empty)
    /// sends one tick's worth.
    pub fn send(&mut self) {
        #[cfg(feature = "hw")]
        if self.tx.is_tx_empty() {
            self.pay_stops();
            match self.q.pop_front() {
                Some(c) => {
                    let _ = self.tx.write(c);
                }
                None => self.tx.unlisten(),
            }
        }
        #[cfg(feature = "qemu")]
        {
            self.pay_stops();
            for _ in 0..QEMU_TX_BYTES_PER_TICK {
                match self.q.pop_front() {
                    Some(c) => {
                        let _ = self.tx.write(c);
                    }
                    None => break,
                }
            }
        }
    }
}
