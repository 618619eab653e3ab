//! Instruction counting under QEMU `-icount shift=0`: every guest instruction advances the
//! virtual clock by 1 ns, and SysTick (clocked from the core clock as QEMU models it) counts
//! a fixed number of ticks per ns. SysTick runs free with a 24-bit reload; its exception
//! counts wraps. `calibrate` measures ticks per instruction on a loop of known length, so
//! the host converts ticks to instructions without assuming the board's clock.

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use cortex_m_rt::exception;

static WRAPS: AtomicU32 = AtomicU32::new(0);
const RELOAD: u32 = 0x00FF_FFFF;

#[exception]
fn SysTick() {
    WRAPS.fetch_add(1, Ordering::Relaxed);
}

#[inline]
pub fn start(mut syst: SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(RELOAD);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// Ticks since `start` (monotonic, 64-bit).
#[inline(never)]
pub fn now() -> u64 {
    loop {
        let w0 = WRAPS.load(Ordering::SeqCst);
        let cur = SYST::get_current();
        let w1 = WRAPS.load(Ordering::SeqCst);
        if w0 == w1 {
            return w0 as u64 * (RELOAD as u64 + 1) + (RELOAD - cur) as u64;
        }
    }
}

/// A loop of exactly `2 n` instructions (`subs`, `bne`).
#[inline(never)]
pub fn spin(n: u32) {
    if n == 0 {
        return;
    }
    unsafe {
        core::arch::asm!("2:", "subs {0}, {0}, #1", "bne 2b", inout(reg) n => _, options(nomem, nostack));
    }
}

/// (ticks for `2 n` instructions of `spin(n)`, ticks for `spin(0)`): the host takes the
/// difference over `2 n` as ticks per instruction, and the second as the timing overhead.
#[inline]
pub fn calibrate(n: u32) -> (u64, u64) {
    let t0 = now();
    spin(0);
    let t1 = now();
    spin(n);
    let t2 = now();
    (t2 - t1, t1 - t0)
}
