//! A simulated board: PWMs and the enable pin are plain values the host can inspect.
//! `finger-sim` and the host tests run the application against it.

use core::convert::Infallible;
use embedded_hal::digital::{ErrorType as PinErrorType, OutputPin};
use embedded_hal::pwm::{ErrorType as PwmErrorType, SetDutyCycle};

use crate::board::{Board, HV_CHANNELS};

/// A PWM output: the last duty written and how many writes.
#[derive(Clone, Copy, Debug, Default)]
pub struct SimPwm {
    pub duty: u16,
    pub max: u16,
    pub writes: u32,
}

impl PwmErrorType for SimPwm {
    type Error = Infallible;
}

impl SetDutyCycle for SimPwm {
    fn max_duty_cycle(&self) -> u16 {
        self.max
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        self.duty = duty;
        self.writes += 1;
        Ok(())
    }
}

/// An output pin; `high_ever` records whether it was ever driven high.
#[derive(Clone, Copy, Debug, Default)]
pub struct SimPin {
    pub high: bool,
    pub high_ever: bool,
}

impl PinErrorType for SimPin {
    type Error = Infallible;
}

impl OutputPin for SimPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.high = false;
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.high = true;
        self.high_ever = true;
        Ok(())
    }
}

/// The simulated board. Resolutions as on the STM32F405 at 168 MHz: servo TIM3 at 50 Hz,
/// HV TIM4 at 20 kHz (8400 counts).
#[derive(Clone, Debug)]
pub struct SimBoard {
    pub servo: SimPwm,
    pub hv: [SimPwm; HV_CHANNELS],
    pub enable: SimPin,
    pub watchdog_feeds: u64,
}

impl Default for SimBoard {
    fn default() -> Self {
        // 0.5 us resolution: 40000 counts per 20 ms period.
        let servo = SimPwm { duty: 0, max: 40_000, writes: 0 };
        let hv = SimPwm { duty: 0, max: 8_400, writes: 0 };
        SimBoard { servo, hv: [hv; HV_CHANNELS], enable: SimPin::default(), watchdog_feeds: 0 }
    }
}

impl Board for SimBoard {
    type Servo = SimPwm;
    type Hv = SimPwm;
    type Enable = SimPin;
    fn servo(&mut self) -> &mut SimPwm {
        &mut self.servo
    }
    fn hv(&mut self, ch: usize) -> &mut SimPwm {
        &mut self.hv[ch]
    }
    fn hv_enable(&mut self) -> &mut SimPin {
        &mut self.enable
    }
    fn feed_watchdog(&mut self) {
        self.watchdog_feeds += 1;
    }
    fn name(&self) -> &'static str {
        "sim"
    }
    fn newline(&self) -> &'static str {
        "\n"
    }
}
