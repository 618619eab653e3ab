//! Test images only (feature `fault-inject`, never in a release): `crash <what>` takes a
//! fault path on purpose, for host-tests/tests/qemu_faults.rs: `hardfault` (a load from an
//! unmapped address; an undefined instruction on the M3 image), `nmi` (NMIPENDSET), `irq` (an
//! interrupt without a handler: DefaultHandler), `overflow` (unbounded recursion into the MPU
//! stack guard).

use finger_fw::rx::Record;

#[inline(never)]
#[allow(unconditional_recursion)]
fn recurse(n: u32, buf: &mut [u32; 64]) -> u32 {
    let mut local = [n; 64];
    local[(n as usize) % 64] ^= buf[0];
    let r = recurse(n.wrapping_add(1), &mut local);
    core::hint::black_box(r) ^ local[3]
}

pub fn run(rec: &Record) {
    let Record::Line(l) = rec else { return };
    let Some(what) = l.strip_prefix(b"crash ") else { return };
    match what {
        #[cfg(not(m3))]
        b"hardfault" => unsafe {
            core::ptr::read_volatile(0x6000_0000 as *const u32);
        },
        // QEMU's netduino2 ignores an unmapped load: an undefined instruction instead
        #[cfg(m3)]
        b"hardfault" => unsafe {
            core::arch::asm!("udf #0");
        },
        b"nmi" => unsafe {
            (*cortex_m::peripheral::SCB::PTR).icsr.write(1 << 31);
        },
        b"irq" => unsafe {
            // WWDG (IRQ 0): no task binds it
            cortex_m::peripheral::NVIC::unmask(stm32f4xx_hal::pac::Interrupt::WWDG);
            cortex_m::peripheral::NVIC::pend(stm32f4xx_hal::pac::Interrupt::WWDG);
        },
        b"overflow" => {
            let mut b = [0u32; 64];
            core::hint::black_box(recurse(0, &mut b));
        }
        _ => {}
    }
}
