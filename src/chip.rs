//! STM32F405 board support: the thin chip part behind `finger_fw::Board`.
//!
//! Two builds (Cargo features):
//! - `qemu` (default; `cargo run --release` boots it in QEMU netduinoplus2): 16 MHz HSI, no
//!   watchdog (QEMU models neither RCC's PLL nor the IWDG), defmt over semihosting.
//! - `hw`: 168 MHz from the PLL (8 MHz crystal), IWDG (fed only by the control loop), defmt
//!   over RTT.
//!
//! Time: SysTick counts the core clock. QEMU's SysTick runs at 168 MHz whatever the RCC says,
//! so a 1 ms tick is 168 000 counts in both builds.

#[path = "mem.rs"]
mod mem;

use core::panic::PanicInfo;
use core::ptr::write_volatile;
use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{entry, exception, ExceptionFrame};
use finger_fw::{App, Board};
use stm32f4xx_hal::{
    gpio::{Output, PinState, PB12},
    pac,
    prelude::*,
    rcc::Config,
    serial::{Rx, Tx},
    timer::{ErasedChannel, PwmChannel},
};

#[cfg(all(feature = "qemu", feature = "hw"))]
compile_error!("features `qemu` and `hw` are exclusive: build the board with --no-default-features --features hw");
#[cfg(not(any(feature = "qemu", feature = "hw")))]
compile_error!("choose a build: feature `qemu` (default) or `hw` (--no-default-features --features hw)");

#[cfg(all(feature = "log", feature = "hw"))]
use defmt_rtt as _;
#[cfg(all(feature = "log", feature = "qemu"))]
use defmt_semihosting as _;

/// SysTick counts per millisecond (core clock 168 MHz on the board and in QEMU).
const SYSTICK_PER_MS: u32 = 168_000;

static MILLIS: AtomicU32 = AtomicU32::new(0);

/// HV enable pin and HV duty registers, written directly by the fault handlers.
const HV_ENABLE_PIN: u32 = 12; // PB12
const GPIO_BSRR: usize = 0x18;
const TIM_CCR1: usize = 0x34; // CCR2 0x38, CCR3 0x3C

/// HV off with raw register writes, nothing else: enable low (GPIOB BSRR reset bit),
/// TIM4 CCR1..3 = 0. Safe to call from any context, any state.
#[inline(always)]
fn force_hv_off() {
    // SAFETY: single-word volatile writes to memory-mapped registers of the STM32F405
    // (addresses from the PAC); writing BSRR/CCRx has no effect besides the outputs.
    unsafe {
        let bsrr = (pac::GPIOB::ptr() as *mut u8).add(GPIO_BSRR) as *mut u32;
        write_volatile(bsrr, 1 << (HV_ENABLE_PIN + 16));
        let tim4 = pac::TIM4::ptr() as *mut u8;
        for i in 0..3 {
            write_volatile(tim4.add(TIM_CCR1 + 4 * i) as *mut u32, 0);
        }
    }
}

/// HV off first (raw register writes), then halt: no message formatting (the PanicInfo is
/// not read, so core's panic formatting is not linked). On the board the IWDG, no longer
/// fed, resets the chip, which boots disarmed with the HV enable low.
#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    force_hv_off();
    #[cfg(feature = "log")]
    defmt::error!("panic: HV forced off");
    loop {
        cortex_m::asm::nop();
    }
}

#[exception]
unsafe fn HardFault(_ef: &ExceptionFrame) -> ! {
    force_hv_off();
    loop {
        cortex_m::asm::nop();
    }
}

#[exception]
fn SysTick() {
    MILLIS.fetch_add(1, Ordering::Relaxed);
}

/// One HV control PWM: the three TIM4 channels, erased to one type.
type HvPwm = ErasedChannel<pac::TIM4>;

struct F405Board {
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
        if cfg!(feature = "qemu") {
            "qemu-netduinoplus2"
        } else {
            "stm32f405"
        }
    }
}

/// Console output: blocking writes to USART1.
struct Console(Tx<pac::USART1>);

impl core::fmt::Write for Console {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.0.write_str(s)
    }
}

#[entry]
fn main() -> ! {
    // HV off before anything else (the pins reset as inputs; the board's pull-down holds the
    // enable low until here).
    force_hv_off();
    let dp = pac::Peripherals::take().unwrap();
    let mut cp = cortex_m::Peripherals::take().unwrap();

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

    let serial = dp.USART1.serial((gpioa.pa9, gpioa.pa10), 115_200.bps(), &mut rcc).unwrap();
    let (tx, mut rx): (Tx<pac::USART1>, Rx<pac::USART1>) = serial.split();
    let mut out = Console(tx);

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
    let mut app = App::new(board);

    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(SYSTICK_PER_MS - 1);
    cp.SYST.clear_current();
    cp.SYST.enable_interrupt();
    cp.SYST.enable_counter();

    #[cfg(feature = "log")]
    defmt::info!("finger-fw {=str} up, board {=str}", finger_fw::VERSION, app.board().name());

    // Boot banner: not a reply; tells a client that input is now received (QEMU drops bytes
    // sent before the USART is enabled, a real UART too).
    let _ = finger_fw::w!(&mut out; "# finger-fw ", finger_fw::VERSION, " ready\r\n");

    let mut last = MILLIS.load(Ordering::Relaxed);
    loop {
        // the control loop: every millisecond (catching up after a long command)
        let now = MILLIS.load(Ordering::Relaxed);
        if now != last {
            app.tick(now.wrapping_sub(last), &mut out);
            last = now;
        }
        if app.busy() {
            // a `wait`: no input is read until it ends; sleep to the next SysTick
            cortex_m::asm::wfi();
            continue;
        }
        match rx.read() {
            Ok(b) => app.input_byte(b, &mut out),
            Err(stm32f4xx_hal::nb::Error::WouldBlock) => {
                // In QEMU, sleep to the next SysTick: with `-icount shift=0,sleep=off` idle
                // time then passes at once, so `wait` runs fast; QEMU holds received bytes
                // until RXNE is clear, so nothing is lost. On the board the loop polls (the
                // UART has a one-byte buffer and no RX interrupt is used).
                #[cfg(feature = "qemu")]
                cortex_m::asm::wfi();
            }
            Err(stm32f4xx_hal::nb::Error::Other(_)) => {} // overrun/framing: the line's bytes are lost
        }
    }
}
