//! STM32F405 board support and the real-time core (RTIC 2): the thin chip part behind
//! `finger_fw::Board`, and the three contexts the application runs in.
//!
//! Priorities and interrupts, the one place they are set:
//!
//! | prio | context | binds | does |
//! | --- | --- | --- | --- |
//! | 3 | `control` | SysTick, 1 kHz | the control core (`finger_fw::control`): slew, the HV duties (single writer), servo, stop requests, watchdog feed |
//! | 2 | `console` | USART1 (RXNE, TXE) | each received byte into `finger_fw::rx` (a `stop` line acts here, on the control core, at once), the transmit queue out |
//! | 0 | `idle` | - | the command side (`finger_fw::Commands`): lines, model solves, `wait`, replies into the transmit queue |
//!
//! Resources: `ctl` (control, console: the console's lock is one `stop`), `mailbox`
//! (setpoints down, the core's view up; control, console after a stop, idle), `rx` (console,
//! idle), `tx` (console, idle). The control task never waits for the console or the model: its locks are free at
//! its priority, and the locks below it last a few hundred instructions.
//!
//! Two builds (Cargo features):
//! - `qemu` (default; `cargo run --release` boots it in QEMU netduinoplus2): 16 MHz HSI, no
//!   watchdog (QEMU models neither RCC's PLL nor the IWDG), defmt over semihosting. It
//!   refuses to arm on a real chip (RCC answers: QEMU does not model it).
//! - `hw`: 168 MHz from the PLL (8 MHz crystal), IWDG (1 s), defmt over RTT.
//!
//! Time: SysTick counts the core clock; QEMU's SysTick runs at 168 MHz whatever the RCC says,
//! so a 1 ms tick is 168 000 counts in both builds.
//!
//! The Cortex-M3 image (`cfg(m3)`: thumbv7m-none-eabi, no FPU; QEMU netduino2, an STM32F205
//! with the same USART1, TIM3/TIM4, GPIOB and RCC addresses and interrupt numbers) is this
//! same code with three differences: SysTick at 120 MHz (QEMU's netduino2), the stack at the
//! bottom of SRAM with the MPU guard below it (memory-m3.x), and the board name. Emulator only.

#[path = "mem.rs"]
mod mem;
#[cfg(feature = "settings")]
#[path = "flash_chip.rs"]
mod flash_chip;

use core::panic::PanicInfo;
use core::sync::atomic::{AtomicU32, Ordering};

use finger_fw::control::{Control, Setpoints, View};
use finger_fw::Board;
use heapless::Deque;
use stm32f4xx_hal::{
    gpio::{Output, PinState, PB12},
    pac,
    prelude::*,
    rcc::Config,
    serial::Event as SerialEvent,
    timer::{ErasedChannel, PwmChannel},
};

#[cfg(all(feature = "qemu", feature = "hw"))]
compile_error!("features `qemu` and `hw` are exclusive: build the board with --no-default-features --features hw");
#[cfg(not(any(feature = "qemu", feature = "hw")))]
compile_error!("choose a build: feature `qemu` (default) or `hw` (--no-default-features --features hw)");

#[cfg(all(m3, feature = "hw"))]
compile_error!("the Cortex-M3 image is an emulator image (QEMU netduino2): build it with --features m3");

#[cfg(all(feature = "log", feature = "hw"))]
use defmt_rtt as _;
#[cfg(all(feature = "log", feature = "qemu"))]
use defmt_semihosting as _;

/// Core clock, MHz: 168 on the board and in QEMU netduinoplus2, 120 in QEMU netduino2 (M3).
#[cfg(not(m3))]
const CORE_MHZ: u32 = 168;
#[cfg(m3)]
const CORE_MHZ: u32 = 120;
/// SysTick counts per millisecond.
const SYSTICK_PER_MS: u32 = CORE_MHZ * 1000;

/// Register addresses the reset and fault paths write without the HAL.
const RCC_CR: usize = 0x4002_3800;
const USART1_SR: usize = 0x4001_1000;
const USART1_DR: usize = 0x4001_1004;
#[cfg(feature = "hw")]
const USART1_CR1: usize = 0x4001_100C;
const SR_ORE: u32 = 1 << 3;
const SR_RXNE: u32 = 1 << 5;
#[cfg(feature = "hw")]
const SR_TXE: u32 = 1 << 7;
#[cfg(feature = "hw")]
const CR1_TXEIE: u32 = 1 << 7;
/// 115200 baud, 10 bits a byte: 11.5 bytes per ms.
#[cfg(feature = "qemu")]
const QEMU_TX_BYTES_PER_TICK: usize = 12;

// HV off without the stack: `__pre_init` (cortex-m-rt: right after reset, before RAM is
// set up) enables the GPIOB clock and drives PB6-8 (HV control PWMs) and PB12 (HV enable) low
// as outputs; `HardFault`, `NonMaskableInt` and `DefaultHandler` (every unhandled interrupt
// and fault) are the vector table's entries themselves, no trampoline: their first
// instructions drive the same pins low and zero TIM4 CCR1..3, and they never touch the stack
// (a stack overflow ends here too). Then they halt; on the board the IWDG, no longer fed,
// resets the chip, which boots with the HV off.
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

fn reg_read(a: usize) -> u32 {
    // SAFETY: a read of a memory-mapped register of the STM32F405 (addresses above).
    unsafe { core::ptr::read_volatile(a as *const u32) }
}
fn reg_write(a: usize, v: u32) {
    // SAFETY: a write of a memory-mapped register of the STM32F405 (addresses above).
    unsafe { core::ptr::write_volatile(a as *mut u32, v) }
}

/// Stack guard (MPU region 0, no access): 16 KiB right above the statics, so the stack,
/// growing down from the top of RAM, faults (HardFault, HV off) before it reaches them. The
/// largest frame (the inverse's branch table, ~4.5 KB) cannot step over it. On the M3 image
/// the stack is at the bottom of SRAM: the guard is the 16 KiB below SRAM.
fn stack_guard(mpu: &mut cortex_m::peripheral::MPU) -> u32 {
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

/// One HV control PWM: the three TIM4 channels, erased to one type.
type HvPwm = ErasedChannel<pac::TIM4>;

pub struct F405Board {
    servo: PwmChannel<pac::TIM3, 0>,
    hv: [HvPwm; 3],
    enable: PB12<Output>,
    #[cfg(feature = "hw")]
    iwdg: stm32f4xx_hal::watchdog::IndependentWatchdog,
}

impl Board for F405Board {
    type Servo = PwmChannel<pac::TIM3, 0>;
    type Hv = HvPwm;
    type Enable = PB12<Output>;
    fn servo(&mut self) -> &mut Self::Servo {
        &mut self.servo
    }
    fn hv(&mut self, ch: usize) -> &mut HvPwm {
        &mut self.hv[ch]
    }
    fn hv_enable(&mut self) -> &mut Self::Enable {
        &mut self.enable
    }
    fn feed_watchdog(&mut self) {
        #[cfg(feature = "hw")]
        self.iwdg.feed();
    }
    fn name(&self) -> &'static str {
        if cfg!(m3) {
            "qemu-netduino2"
        } else if cfg!(feature = "qemu") {
            "qemu-netduinoplus2"
        } else {
            "stm32f405"
        }
    }
}

/// Bytes waiting to be sent (less on the Cortex-M3 image's 20 KiB of RAM).
#[cfg(not(m3))]
pub const TX_RING: usize = 2048;
#[cfg(m3)]
pub const TX_RING: usize = 1024;
/// Kept free in the transmit queue for `ok stopped` (written from the console interrupt).
const TX_RESERVE: usize = 16;
const STOP_REPLY: &[u8] = b"ok stopped\r\n";

/// The transmit queue: whole lines from the command side, `ok stopped` from the console
/// interrupt (between lines), drained by the TXE interrupt.
pub struct TxQueue {
    q: Deque<u8, TX_RING>,
    /// `ok stopped` replies that found no room yet.
    owed_stops: u8,
}

impl TxQueue {
    fn free(&self) -> usize {
        self.q.capacity() - self.q.len()
    }
    fn push_all(&mut self, b: &[u8]) {
        for &c in b {
            let _ = self.q.push_back(c);
        }
        // the board: the TXE interrupt drains the queue; QEMU 7.2 raises no TXE interrupt,
        // so there the control task pends the console interrupt every tick instead
        #[cfg(feature = "hw")]
        reg_write(USART1_CR1, reg_read(USART1_CR1) | CR1_TXEIE);
    }
    fn push_stop_reply(&mut self) {
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
}

/// Setpoints down to the control core, its view back up.
pub struct Mailbox {
    setpoints: Option<Setpoints>,
    /// A `stop` executed as a line on the command side.
    stop: bool,
    view: View,
}

/// The control core's time, ms (written by the control task).
static NOW_MS: AtomicU32 = AtomicU32::new(0);
/// The command side's last check-in, control ms.
static CHECKIN_MS: AtomicU32 = AtomicU32::new(0);

/// Timing, measured by the firmware itself in SysTick counts (`CORE_MHZ` per us) and reported by
/// the `timing` console addition (docs/firmware.md regenerates from it).
pub mod timing {
    use core::sync::atomic::{AtomicU32, Ordering};
    /// Control-task entry, counts after the SysTick reload: the tick's latency (jitter).
    pub static TICK_LATENCY_MAX: AtomicU32 = AtomicU32::new(0);
    pub static TICK_LATENCY_MIN: AtomicU32 = AtomicU32::new(u32::MAX);
    /// Control-task run time, counts.
    pub static TICK_RUN_MAX: AtomicU32 = AtomicU32::new(0);
    /// One channel's stack step in a control tick (goal, slew, guard, thickness, relaxation), counts.
    pub static TICK_STACK_MAX: AtomicU32 = AtomicU32::new(0);
    /// Entry to entry of the control task, counts.
    pub static PERIOD_MIN: AtomicU32 = AtomicU32::new(u32::MAX);
    pub static PERIOD_MAX: AtomicU32 = AtomicU32::new(0);
    /// Stop: from the console interrupt's entry to HV off, counts.
    pub static STOP_MAX: AtomicU32 = AtomicU32::new(0);
    pub static STOPS: AtomicU32 = AtomicU32::new(0);
    /// Ticks counted.
    pub static TICKS: AtomicU32 = AtomicU32::new(0);
    pub fn max(a: &AtomicU32, v: u32) {
        if v > a.load(Ordering::Relaxed) {
            a.store(v, Ordering::Relaxed);
        }
    }
    pub fn min(a: &AtomicU32, v: u32) {
        if v < a.load(Ordering::Relaxed) {
            a.store(v, Ordering::Relaxed);
        }
    }
}

/// SysTick counts since its last reload.
fn systick_elapsed() -> u32 {
    (SYSTICK_PER_MS - 1).saturating_sub(cortex_m::peripheral::SYST::get_current())
}

/// Time now in SysTick counts (control ms x `SYSTICK_PER_MS` + the count within the tick).
fn now_counts() -> u64 {
    loop {
        let ms = NOW_MS.load(Ordering::Acquire);
        let c = systick_elapsed();
        if NOW_MS.load(Ordering::Acquire) == ms {
            return ms as u64 * SYSTICK_PER_MS as u64 + c as u64;
        }
    }
}

/// A real chip answers at RCC (HSIRDY after reset); QEMU does not model RCC (it reads 0).
fn on_real_chip() -> bool {
    reg_read(RCC_CR) & 0b10 != 0
}

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use super::*;
    use finger_fw::rx::{RxEvent, RxLines};
    use finger_fw::Commands;

    #[shared]
    struct Shared {
        ctl: Control<F405Board>,
        mailbox: Mailbox,
        rx: RxLines,
        tx: TxQueue,
    }

    #[local]
    struct Local {
        cmds: Commands,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        // the HV pins are low since __pre_init
        let real_chip = on_real_chip();
        let dp = cx.device;
        let mut cp = cx.core;

        #[cfg(feature = "hw")]
        let mut rcc = dp.RCC.freeze(Config::hse(8.MHz()).sysclk(168.MHz()));
        #[cfg(feature = "qemu")]
        let mut rcc = dp.RCC.freeze(Config::hsi());

        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpiob = dp.GPIOB.split(&mut rcc);
        let enable = gpiob.pb12.into_push_pull_output_in_state(PinState::Low);

        let (_, (s1, ..)) = dp.TIM3.pwm_hz(50.Hz(), &mut rcc);
        let mut servo = s1.with(gpioa.pa6);
        servo.set_duty(0);
        servo.enable();
        let (_, (h1, h2, h3, ..)) = dp.TIM4.pwm_hz(20.kHz(), &mut rcc);
        let mut hv = [h1.with(gpiob.pb6).erase(), h2.with(gpiob.pb7).erase(), h3.with(gpiob.pb8).erase()];
        for ch in hv.iter_mut() {
            ch.set_duty(0);
            ch.enable();
        }

        let mut serial: stm32f4xx_hal::serial::Serial<pac::USART1, u8> = dp.USART1.serial((gpioa.pa9, gpioa.pa10), 115_200.bps(), &mut rcc).unwrap();
        serial.listen(SerialEvent::RxNotEmpty);
        core::mem::forget(serial);

        #[cfg(feature = "hw")]
        let iwdg = {
            let mut w = stm32f4xx_hal::watchdog::IndependentWatchdog::new(dp.IWDG);
            w.start(1000.millis());
            w
        };

        let board = F405Board {
            servo,
            hv,
            enable,
            #[cfg(feature = "hw")]
            iwdg,
        };
        let (mut cmds, mut ctl) = finger_fw::wire(board);
        cmds.set_timing_report(timing_report);
        // the stored settings, before the control tick starts
        #[cfg(feature = "settings")]
        let boot = flash_chip::store(dp.FLASH).map(|s| finger_fw::app::config::boot(&mut cmds, &mut ctl, s));
        if cfg!(feature = "qemu") && real_chip {
            // the emulator image has no watchdog: it never arms a real board
            ctl.lock_out(finger_fw::control::Fault::EmulatorOnChip);
        }
        let view = ctl.view();

        let guard = stack_guard(&mut cp.MPU);

        cp.SYST.set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
        cp.SYST.set_reload(SYSTICK_PER_MS - 1);
        cp.SYST.clear_current();
        cp.SYST.enable_interrupt();
        cp.SYST.enable_counter();

        #[cfg(feature = "log")]
        defmt::info!("finger-fw {=str} up, board {=str}, stack guard at {=u32:#x}", finger_fw::VERSION, ctl.board().name(), guard);
        let _ = guard;

        let mut tx = TxQueue { q: Deque::new(), owed_stops: 0 };
        // Boot banner: not a reply; tells a client that input is now received (QEMU drops
        // bytes sent before the USART is enabled, a real UART too).
        tx.push_all(b"# finger-fw ");
        tx.push_all(finger_fw::VERSION.as_bytes());
        #[cfg(feature = "settings")]
        if let Some(b) = boot {
            let mut note: heapless::String<80> = heapless::String::new();
            let _ = finger_fw::w!(&mut note; " ", b);
            tx.push_all(note.as_bytes());
        }
        tx.push_all(b" ready\r\n");

        (Shared { ctl, mailbox: Mailbox { setpoints: None, stop: false, view }, rx: RxLines::new(), tx }, Local { cmds })
    }

    /// The control task: every 1 ms, at the highest priority.
    #[task(binds = SysTick, priority = 3, shared = [ctl, mailbox], local = [last_entry: u64 = 0])]
    fn control(cx: control::Context) {
        let entry = systick_elapsed();
        timing::max(&timing::TICK_LATENCY_MAX, entry);
        timing::min(&timing::TICK_LATENCY_MIN, entry);
        let at = (NOW_MS.load(Ordering::Relaxed) as u64 + 1) * SYSTICK_PER_MS as u64 + entry as u64;
        if *cx.local.last_entry > 0 {
            let p = (at - *cx.local.last_entry) as u32;
            timing::max(&timing::PERIOD_MAX, p);
            timing::min(&timing::PERIOD_MIN, p);
        }
        *cx.local.last_entry = at;
        let checkin = CHECKIN_MS.load(Ordering::Relaxed);
        let now = (cx.shared.ctl, cx.shared.mailbox).lock(|ctl, mb| {
            if core::mem::take(&mut mb.stop) {
                ctl.stop();
            }
            if let Some(sp) = mb.setpoints.take() {
                ctl.apply(&sp);
            }
            let stack = ctl.tick_timed(checkin, systick_elapsed);
            timing::max(&timing::TICK_STACK_MAX, stack);
            mb.view = ctl.view();
            mb.view.now_ms
        });
        NOW_MS.store(now, Ordering::Release);
        #[cfg(feature = "qemu")]
        {
            // tick marker for the register trace (TIM4 CCR4: channel 4 is not an output)
            reg_write(0x4000_0840, now & 0xFFFF);
            rtic::pend(pac::Interrupt::USART1); // transmit (see TxQueue::push_all)
        }
        timing::TICKS.fetch_add(1, Ordering::Relaxed);
        timing::max(&timing::TICK_RUN_MAX, systick_elapsed().saturating_sub(entry));
    }

    /// USART1: received bytes into the line ring (`stop` acts here), the transmit queue out.
    #[task(binds = USART1, priority = 2, shared = [ctl, mailbox, rx, tx])]
    fn console(cx: console::Context) {
        let t0 = systick_elapsed();
        let (ctl, mailbox, mut rx, mut tx) = (cx.shared.ctl, cx.shared.mailbox, cx.shared.rx, cx.shared.tx);
        let sr = reg_read(USART1_SR);
        if sr & (SR_RXNE | SR_ORE) != 0 {
            let b = reg_read(USART1_DR) as u8; // clears RXNE and ORE
            let ev = rx.lock(|r| {
                let ev = r.push(b);
                if sr & SR_ORE != 0 {
                    r.overrun(); // bytes after b were lost
                }
                ev
            });
            if ev == RxEvent::Stop {
                // HV off now; the command side sees the stop in the view before its next line
                (ctl, mailbox).lock(|c, m| {
                    c.stop();
                    m.view = c.view();
                });
                let t1 = systick_elapsed();
                timing::max(&timing::STOP_MAX, t1.wrapping_sub(t0) % SYSTICK_PER_MS);
                timing::STOPS.fetch_add(1, Ordering::Relaxed);
                tx.lock(|t| t.push_stop_reply());
            }
        }
        #[cfg(feature = "hw")]
        if sr & SR_TXE != 0 && reg_read(USART1_CR1) & CR1_TXEIE != 0 {
            tx.lock(|t| {
                t.pay_stops();
                match t.q.pop_front() {
                    Some(c) => reg_write(USART1_DR, c as u32),
                    None => reg_write(USART1_CR1, reg_read(USART1_CR1) & !CR1_TXEIE),
                }
            });
        }
        // QEMU: TXE is always set (its I/O is synchronous); send what 115200 baud sends in
        // one tick, so replies take the time they take on the board
        #[cfg(feature = "qemu")]
        tx.lock(|t| {
            t.pay_stops();
            for _ in 0..QEMU_TX_BYTES_PER_TICK {
                match t.q.pop_front() {
                    Some(c) => reg_write(USART1_DR, c as u32),
                    None => break,
                }
            }
        });
    }

    /// The command side, at the lowest priority: lines, model solves, `wait`, replies.
    #[idle(shared = [mailbox, rx, tx], local = [cmds])]
    fn idle(cx: idle::Context) -> ! {
        let cmds = cx.local.cmds;
        let (mut mailbox, mut rx, tx) = (cx.shared.mailbox, cx.shared.rx, cx.shared.tx);
        let mut out = TxOut { tx, line: heapless::Vec::new() };
        loop {
            check_in();
            let view = mailbox.lock(|m| m.view);
            cmds.sync(&view);
            if cmds.busy() {
                let input = rx.lock(|r| r.take_input_seen());
                if !cmds.poll_wait(input, &mut out) {
                    cortex_m::asm::wfi();
                    continue;
                }
            }
            let Some(rec) = rx.lock(|r| r.pop()) else {
                cortex_m::asm::wfi();
                continue;
            };
            let word = command_word(&rec);
            #[cfg(feature = "fault-inject")]
            fault_inject::run(&rec);
            let t0 = now_counts();
            cmds.run(rec, &mut out);
            durations::record(word, (now_counts() - t0) as u32);
            let stop = cmds.take_stop();
            let sp = cmds.setpoints();
            mailbox.lock(|m| {
                m.setpoints = Some(sp);
                m.stop |= stop;
            });
            // the next line sees this one's effect: the core takes the setpoints at its next
            // tick (or drops them after a stop)
            loop {
                check_in();
                let v = mailbox.lock(|m| m.view);
                if v.seq == sp.seq || v.epoch != sp.epoch || stop {
                    break;
                }
                cortex_m::asm::wfi();
            }
        }
    }

    /// Replies into the transmit queue, a whole line at a time (the command side waits for
    /// room, checking in meanwhile: a slow console is not a stuck one).
    struct TxOut<M: rtic::Mutex<T = TxQueue>> {
        tx: M,
        line: heapless::Vec<u8, 512>,
    }

    impl<M: rtic::Mutex<T = TxQueue>> TxOut<M> {
        fn flush(&mut self) {
            let n = self.line.len();
            loop {
                let done = self.tx.lock(|t| {
                    t.pay_stops();
                    if t.owed_stops == 0 && t.free() >= n + TX_RESERVE {
                        t.push_all(&self.line);
                        true
                    } else {
                        false
                    }
                });
                if done {
                    break;
                }
                check_in();
                cortex_m::asm::wfi();
            }
            self.line.clear();
        }
    }

    impl<M: rtic::Mutex<T = TxQueue>> core::fmt::Write for TxOut<M> {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            for &b in s.as_bytes() {
                if self.line.push(b).is_err() {
                    self.flush();
                    let _ = self.line.push(b);
                }
                if b == b'\n' {
                    self.flush();
                }
            }
            Ok(())
        }
    }
}

fn check_in() {
    CHECKIN_MS.store(NOW_MS.load(Ordering::Relaxed), Ordering::Relaxed);
}

/// The first word of a queued line, for the durations table.
fn command_word(rec: &finger_fw::rx::Record) -> [u8; 8] {
    let mut w = [0u8; 8];
    if let finger_fw::rx::Record::Line(l) = rec {
        for (i, &c) in l.iter().skip_while(|&&c| c == b' ').take_while(|&&c| c != b' ').take(8).enumerate() {
            w[i] = c;
        }
    }
    w
}

/// Worst command durations by command word (SysTick counts), for `timing`.
pub mod durations {
    use core::cell::RefCell;
    use cortex_m::interrupt::Mutex;
    pub const SLOTS: usize = 12;
    /// Written and read by the command side only (the critical section is a formality).
    pub static TABLE: Mutex<RefCell<[([u8; 8], u32); SLOTS]>> = Mutex::new(RefCell::new([([0; 8], 0); SLOTS]));
    pub fn record(word: [u8; 8], counts: u32) {
        if word[0] == 0 {
            return;
        }
        cortex_m::interrupt::free(|cs| {
            let mut t = TABLE.borrow(cs).borrow_mut();
            for slot in t.iter_mut() {
                if slot.0 == word || slot.0[0] == 0 {
                    slot.0 = word;
                    slot.1 = slot.1.max(counts);
                    return;
                }
            }
        });
    }
}

/// The `timing` reply: `tick_period_us=<min>,<max>` (control-task entry to entry),
/// `tick_latency_us=<min>,<max>` (control-task entry after the SysTick
/// reload: the tick's jitter), `tick_run_us=<max>`, `ticks=<n>`, `stop_us=<max>` (console
/// interrupt entry to HV off), `stops=<n>`, `cmd_us=<word>:<max>,...` (the command side, line
/// run, replies queued).
fn timing_report(o: &mut dyn core::fmt::Write) {
    use finger_fw::num::Fixed;
    use finger_fw::w;
    let us = |c: u32| Fixed(c as f32 / CORE_MHZ as f32, 2);
    let ld = |a: &AtomicU32| a.load(Ordering::Relaxed);
    let min = ld(&timing::TICK_LATENCY_MIN);
    let min = if min == u32::MAX { 0 } else { min };
    let pmin = ld(&timing::PERIOD_MIN);
    let pmin = if pmin == u32::MAX { 0 } else { pmin };
    let _ = w!(o; "tick_period_us=", us(pmin), ",", us(ld(&timing::PERIOD_MAX)), " tick_latency_us=", us(min), ",", us(ld(&timing::TICK_LATENCY_MAX)), " tick_run_us=", us(ld(&timing::TICK_RUN_MAX)), " tick_stack_us=", Fixed(ld(&timing::TICK_STACK_MAX) as f32 / CORE_MHZ as f32, 3), " ticks=", ld(&timing::TICKS));
    let _ = w!(o; " stop_us=", us(ld(&timing::STOP_MAX)), " stops=", ld(&timing::STOPS), " cmd_us=");
    cortex_m::interrupt::free(|cs| {
        let t = durations::TABLE.borrow(cs).borrow();
        let mut first = true;
        for (word, c) in t.iter() {
            if word[0] == 0 {
                continue;
            }
            if !first {
                let _ = o.write_str(",");
            }
            first = false;
            let n = word.iter().position(|&b| b == 0).unwrap_or(8);
            let _ = w!(o; finger_fw::console::printable(&word[..n]), ":", us(*c));
        }
    });
}

/// Test images only (feature `fault-inject`, never in a release): `crash <what>` takes a
/// fault path on purpose, for tests/qemu_faults.rs: `hardfault` (a load from an unmapped
/// address; an undefined instruction on the M3 image), `nmi` (NMIPENDSET), `irq` (an interrupt without a handler: DefaultHandler),
/// `overflow` (unbounded recursion into the MPU stack guard).
#[cfg(feature = "fault-inject")]
mod fault_inject {
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
}
