//! HV off without the stack, for the image only (the on-target tests have their own fault
//! handlers): `__pre_init` (cortex-m-rt: right after reset, before RAM is set up) enables the
//! GPIOB clock and drives PB6-8 (HV control PWMs) and PB12 (HV enable) low as outputs;
//! `HardFault`, `NonMaskableInt` and `DefaultHandler` (every unhandled interrupt and fault)
//! are the vector table's entries themselves, no trampoline: their first instructions drive
//! the same pins low and zero TIM4 CCR1..3, and they never touch the stack (a stack overflow
//! ends here too). Then they halt; on the board the IWDG, no longer fed, resets the chip,
//! which boots with the HV off. A panic does the same stores from Rust.

use core::panic::PanicInfo;

core::arch::global_asm!(
    ".macro HV_OFF",
    "    ldr r0, =0x40020418", // GPIOB BSRR: PB6, PB7, PB8, PB12 low
    "    ldr r1, =0x11C00000",
    "    str r1, [r0]",
    "    ldr r0, =0x40020400", // GPIOB MODER: PB6-8, PB12 outputs (off the timer)
    "    ldr r1, [r0]",
    "    ldr r2, =0x0303F000",
    "    bic r1, r1, r2",
    "    ldr r2, =0x01015000",
    "    orr r1, r1, r2",
    "    str r1, [r0]",
    "    ldr r0, =0x40000834", // TIM4 CCR1..3 = 0
    "    movs r1, #0",
    "    str r1, [r0]",
    "    str r1, [r0, #4]",
    "    str r1, [r0, #8]",
    ".endm",
    ".section .text.__pre_init,\"ax\",%progbits",
    ".global __pre_init",
    ".type __pre_init,%function",
    ".thumb_func",
    "__pre_init:",
    "    ldr r0, =0x40023830", // RCC AHB1ENR |= GPIOBEN
    "    ldr r1, [r0]",
    "    orr r1, r1, #2",
    "    str r1, [r0]",
    "    ldr r1, [r0]", // read back: the clock is on before the port is written
    "    HV_OFF",
    "    bx lr",
    ".ltorg",
    ".size __pre_init, . - __pre_init",
    ".section .text.fw_fault_handlers,\"ax\",%progbits",
    ".global HardFault",
    ".global NonMaskableInt",
    ".global DefaultHandler",
    ".type HardFault,%function",
    ".type NonMaskableInt,%function",
    ".type DefaultHandler,%function",
    ".thumb_func",
    "HardFault:",
    ".thumb_func",
    "NonMaskableInt:",
    ".thumb_func",
    "DefaultHandler:",
    "    HV_OFF",
    "9:  b 9b",
    ".ltorg",
    ".size HardFault, . - HardFault",
);

/// HV off (the fault handlers' stores, from Rust), then halt: no message formatting (the
/// PanicInfo is not read, so core's panic formatting is not linked).
#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    force_hv_off();
    #[cfg(feature = "log")]
    defmt::error!("panic: HV forced off");
    loop {
        cortex_m::asm::nop();
    }
}

/// HV enable low, PB6-8 low as outputs, TIM4 CCR1..3 = 0 (raw register writes).
fn force_hv_off() {
    // SAFETY: volatile writes to the STM32F405's GPIOB and TIM4 registers; they only drive
    // the HV outputs low.
    unsafe {
        let bsrr = 0x4002_0418 as *mut u32;
        core::ptr::write_volatile(bsrr, 0x11C0_0000);
        let moder = 0x4002_0400 as *mut u32;
        let m = core::ptr::read_volatile(moder);
        core::ptr::write_volatile(moder, (m & !0x0303_F000) | 0x0101_5000);
        for i in 0..3 {
            core::ptr::write_volatile((0x4000_0834 + 4 * i) as *mut u32, 0);
        }
    }
}
