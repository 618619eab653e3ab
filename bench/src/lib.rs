//! What the bench images share: the instruction counter ([`cycles`]), the panic handler, the
//! `CAL` line before the measurements and the `END` line and exit after them. Not the
//! measurements (each image's own), nor `lean`, which keeps a handler without formatting so
//! that its flash figure is the model's.
#![no_std]
// `unsafe` only in the calibration loop's inline asm (cycles.rs).

pub mod cycles;

use cortex_m_semihosting::{debug, hprintln};

/// A panic in the model is a bug (it must return typed errors): say so and fail the run.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("PANIC {}", info);
    debug::exit(debug::EXIT_FAILURE);
    loop {}
}

/// Starts the counter (SysTick) and prints `CAL <instructions> <ticks> <overhead>` from
/// `cycles::calibrate(n)`, the loop of `instructions` = 2 n: the host's ticks-to-instructions
/// conversion. `start!()` is the 1,000,000-iteration loop.
///
/// A macro, not a function: the counts are SysTick ticks, whose phase at a measurement depends on
/// every instruction run before it, and only a literal is formatted into `CAL`'s text at compile
/// time (a function's argument is formatted at run time, which moves counts by a tick).
#[macro_export]
macro_rules! start {
    () => {
        $crate::start!(1_000_000, 2_000_000u32);
    };
    // statements, not a block: the bindings live to the end of `main`, as when written out
    ($n:expr, $instructions:tt) => {
        let cp = ::cortex_m::Peripherals::take().unwrap();
        $crate::cycles::start(cp.SYST);
        let (ticks, overhead) = $crate::cycles::calibrate($n);
        ::cortex_m_semihosting::hprintln!("CAL {} {} {}", $instructions, ticks, overhead);
    };
}

/// Prints `END` and leaves QEMU with success. Inlined, so that `main` is the size it was with
/// these lines written out (the inliner's choices inside it, and so the counts, stay the same).
#[inline(always)]
pub fn end() -> ! {
    hprintln!("END");
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::wfi();
    }
}
