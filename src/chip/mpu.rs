//! The stack guard: MPU region 0, no access, 16 KiB right past the stack's end, so an overflow
//! faults (HardFault: HV off) before it reaches the statics. The largest stack frame must be
//! smaller than the guard to not step over it.
//! - F405 images: the stack grows down from the top of RAM toward the statics; the guard is
//!   the 16 KiB right above them.
//! - Cortex-M3 image (`cfg(m3)`): the stack is at the bottom of SRAM (memory-m3.x); the guard
//!   is the 16 KiB below SRAM.

/// The guard on, before the tasks run. Its base address.
pub fn stack_guard(mpu: &mut cortex_m::peripheral::MPU) -> u32 {
    const SIZE_LOG2: u32 = 14; // 16 KiB
    #[cfg(not(m3))]
    let base = {
        extern "C" {
            static mut __sheap: u32;
        }
        let heap = core::ptr::addr_of_mut!(__sheap) as u32;
        (heap + (1 << SIZE_LOG2) - 1) & !((1 << SIZE_LOG2) - 1)
    };
    #[cfg(m3)]
    let base = 0x2000_0000 - (1 << SIZE_LOG2);
    // SAFETY: MPU set-up before the tasks run: region 0 = [base, base + 16 KiB) no access
    // (AP = 000), execute never; the default memory map elsewhere (PRIVDEFENA); off in
    // HardFault and NMI (HFNMIENA = 0).
    unsafe {
        mpu.rnr.write(0);
        mpu.rbar.write(base);
        mpu.rasr.write((1 << 28) | ((SIZE_LOG2 - 1) << 1) | 1);
        mpu.ctrl.write(0b101);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
    base
}
