//! The F405 under `Board`: clocks, pins, the servo and HV PWMs, the HV enable, the console
//! USART's halves and (board build) the watchdog, brought up once by [`bring_up`].
//!
//! Pin map (docs/firmware.md "Pin map and wiring"):
//! - USART1 TX PA9, RX PA10: console, 115200 8N1
//! - TIM3 CH1 PA6: servo PWM, 50 Hz, 1.0..2.0 ms
//! - TIM4 CH1..CH3 PB6, PB7, PB8: HV modules' control inputs (PWM 20 kHz, RC-filtered to 0..5 V)
//! - PB12: HV enable (interlock), push-pull, low unless armed (external pull-down on the board)
//! - board build: PC0..PC3, PA1, PA2 analog, the HV read-back (`super::hv_adc`)
//!
//! Not here: the HV-off stores of the reset and fault paths (src/image/fault.rs), which run
//! before and without this.

use crate::Board;
use core::convert::Infallible;
use embedded_hal::digital::{ErrorType, OutputPin};
use stm32f4xx_hal::{
    gpio::{Output, PinState, PB12},
    pac,
    prelude::*,
    rcc::Config,
    serial::{Rx, Tx},
    timer::{ErasedChannel, PwmChannel},
};

/// One HV control PWM: the three TIM4 channels, erased to one type.
#[cfg(not(feature = "hw"))]
pub type HvPwm = ErasedChannel<pac::TIM4>;

/// The board build's HV control PWM: a TIM4 channel held at duty 0 while the analog
/// watchdog's cut stands (`crate::cut`), whatever the core writes before it has seen the trip.
#[cfg(feature = "hw")]
pub type HvPwm = crate::cut::CutPwm<ErasedChannel<pac::TIM4>>;

/// The HV enable as the core drives it: the pin, and on the board build the pin under the
/// watchdog's cut (it does not rise until the tick has taken the trip).
#[cfg(not(feature = "hw"))]
pub type Enable = EnablePin;
#[cfg(feature = "hw")]
pub type Enable = crate::cut::CutEnable<EnablePin>;

/// The console USART's halves.
pub type ConsoleRx = Rx<pac::USART1>;
pub type ConsoleTx = Tx<pac::USART1>;

/// The HV enable pin, and the level last written (QEMU models no GPIO: the plant reads this).
pub struct EnablePin {
    pin: PB12<Output>,
    high: bool,
}

impl ErrorType for EnablePin {
    type Error = Infallible;
}

impl OutputPin for EnablePin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.pin.set_low();
        self.high = false;
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.pin.set_high();
        self.high = true;
        Ok(())
    }
}

pub struct F405Board {
    servo: PwmChannel<pac::TIM3, 0>,
    hv: [HvPwm; 3],
    enable: Enable,
    /// The emulator image's HV plant behind the read-back (QEMU's ADC is a sawtooth).
    #[cfg(feature = "qemu")]
    plant: crate::plant::Plant,
    #[cfg(feature = "hw")]
    iwdg: stm32f4xx_hal::watchdog::IndependentWatchdog,
    #[cfg(feature = "hw")]
    adc: super::hv_adc::HvAdc,
}

impl Board for F405Board {
    type Servo = PwmChannel<pac::TIM3, 0>;
    type Hv = HvPwm;
    type Enable = Enable;
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
    /// The board build: the ADCs' read-back (`super::hv_adc`).
    #[cfg(feature = "hw")]
    fn hv_sense(&mut self) -> Option<crate::board::HvSense> {
        Some(self.adc.sense())
    }
    /// The emulator image: the plant stepped over the tick with the duties in TIM4's compare
    /// registers and the enable as last written.
    #[cfg(feature = "qemu")]
    fn hv_sense(&mut self) -> Option<crate::board::HvSense> {
        use embedded_hal::pwm::SetDutyCycle;
        // SAFETY: reads of TIM4's compare registers, which only the HV writer sets.
        let tim4 = unsafe { &*pac::TIM4::ptr() };
        let duty = [tim4.ccr(0).read().bits() as u16, tim4.ccr(1).read().bits() as u16, tim4.ccr(2).read().bits() as u16];
        let max = self.hv[0].max_duty_cycle();
        Some(self.plant.tick(duty, max, self.enable.high))
    }
    #[cfg(feature = "qemu")]
    fn plant(&mut self) -> Option<&mut crate::plant::Plant> {
        Some(&mut self.plant)
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

/// PB6-8 (the HV control PWMs) and PB12 (the HV enable) low as outputs: GPIOB BSRR, then
/// MODER, the stores of `__pre_init` (image/fault.rs).
#[cfg(feature = "hw")]
fn hv_pins_low() {
    // SAFETY: stores to GPIOB that only drive the HV pins low (the port's owner is this
    // bring-up, which configures these pins next).
    unsafe {
        let gpiob = &*pac::GPIOB::ptr();
        gpiob.bsrr().write(|w| w.bits(0x11C0_0000));
        gpiob.moder().modify(|r, w| w.bits((r.bits() & !0x0303_F000) | 0x0101_5000));
    }
}

/// The IWDG started (board build): LSI / [`IWDG_DIV`](crate::board::IWDG_DIV),
/// [`IWDG_RELOAD`](crate::board::IWDG_RELOAD) + 1 counts (docs/firmware.md "Safety": 0.68 s
/// at the LSI's fastest). Init calls it after the stored settings are read (and repaired:
/// erases, with no tick to feed it), before the control tick starts.
#[cfg(feature = "hw")]
pub fn start_watchdog() {
    use crate::board::{IWDG_PR, IWDG_RELOAD};
    // SAFETY: the IWDG's key, prescaler and reload registers (RM0090 §21.3): the access key,
    // the values, their update waited for, then the start key. The board's
    // `IndependentWatchdog` only feeds.
    unsafe {
        let iwdg = &*pac::IWDG::ptr();
        iwdg.kr().write(|w| w.bits(0x5555));
        iwdg.pr().write(|w| w.bits(IWDG_PR));
        iwdg.rlr().write(|w| w.bits(IWDG_RELOAD));
        while iwdg.sr().read().bits() & 0b11 != 0 {}
        iwdg.kr().write(|w| w.bits(0xAAAA));
        iwdg.kr().write(|w| w.bits(0xCCCC));
    }
}

/// The chip brought up: the board, the console's halves (receive interrupt on), whether
/// this is a real chip, and the flash controller (the settings store's).
pub struct Chip {
    pub board: F405Board,
    pub rx: ConsoleRx,
    pub tx: ConsoleTx,
    pub real_chip: bool,
    pub flash: pac::FLASH,
}

/// Clocks (board: 168 MHz from the 8 MHz crystal's PLL, the clock security system on; QEMU:
/// the HSI), the PWMs at duty 0 and running, the HV enable low, USART1 at 115200 with its
/// receive interrupt; on the board the IWDG taken (not started: [`start_watchdog`]).
pub fn bring_up(dp: pac::Peripherals) -> Chip {
    // before the clocks are touched: a real chip answers at RCC, QEMU does not model it
    let real_chip = dp.RCC.cr().read().hsirdy().bit_is_set();
    #[cfg(feature = "hw")]
    let mut rcc = dp.RCC.freeze(Config::hse(8.MHz()).sysclk(168.MHz()));
    #[cfg(feature = "qemu")]
    let mut rcc = dp.RCC.freeze(Config::hsi());
    // the clock security system: a crystal that stops raises the NMI, whose handler drives
    // the HV pins low (image/fault.rs); the IWDG then resets the board
    #[cfg(feature = "hw")]
    rcc.cr().modify(|_, w| w.csson().set_bit());
    // with a probe's log: the IWDG stops while the core is halted, and the debug port stays
    // clocked in WFI (idle), which RTT needs
    #[cfg(all(feature = "hw", feature = "log"))]
    {
        dp.DBGMCU.cr().modify(|_, w| w.dbg_sleep().set_bit());
        dp.DBGMCU.apb1_fz().modify(|_, w| w.dbg_iwdg_stop().set_bit());
    }

    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);
    // the split resets GPIOB (its pins inputs, floating): on the board the HV pins low again
    // at once, as `__pre_init` left them, until their set-up below (the emulator images, which
    // never arm a real chip, leave it: the M3 image's flash budget)
    #[cfg(feature = "hw")]
    hv_pins_low();
    let enable = EnablePin { pin: gpiob.pb12.into_push_pull_output_in_state(PinState::Low), high: false };

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
    #[cfg(feature = "hw")]
    let hv = hv.map(|ch| HvPwm::new(ch, &super::hv_adc::TRIP));
    #[cfg(feature = "hw")]
    let enable = Enable::new(enable, &super::hv_adc::TRIP);

    let serial: stm32f4xx_hal::serial::Serial<pac::USART1, u8> = dp.USART1.serial((gpioa.pa9, gpioa.pa10), 115_200.bps(), &mut rcc).unwrap();
    let (tx, mut rx) = serial.split();
    rx.listen();

    // fed from here on; started by init ([`start_watchdog`])
    #[cfg(feature = "hw")]
    let iwdg = stm32f4xx_hal::watchdog::IndependentWatchdog::new(dp.IWDG);
    // the HV read-back: its pins analog, then the chain started (board build)
    #[cfg(feature = "hw")]
    let adc = {
        let gpioc = dp.GPIOC.split(&mut rcc);
        let _analog = (
            gpioc.pc0.into_analog(),
            gpioc.pc1.into_analog(),
            gpioc.pc2.into_analog(),
            gpioc.pc3.into_analog(),
            gpioa.pa1.into_analog(),
            gpioa.pa2.into_analog(),
        );
        super::hv_adc::start(&mut rcc, dp.ADC1, dp.ADC2, dp.ADC_COMMON, dp.DMA2, dp.TIM2)
    };
    let board = F405Board {
        servo,
        hv,
        enable,
        #[cfg(feature = "qemu")]
        plant: match crate::plant::Plant::new(1) {
            Some(p) => p,
            None => panic!(),
        },
        #[cfg(feature = "hw")]
        iwdg,
        #[cfg(feature = "hw")]
        adc,
    };
    Chip { board, rx, tx, real_chip, flash: dp.FLASH }
}
