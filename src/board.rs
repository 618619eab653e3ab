//! The board the application drives: one servo PWM, three HV control PWMs, the HV enable
//! (interlock) and the watchdog. Everything else about the chip stays in `main.rs`.

use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;

/// Number of HV channels (DE stacks) the board drives.
pub const HV_CHANNELS: usize = 3;

/// Board constants of the HV modules, compiled in (a different module is a different build;
/// no console parameter changes them):
/// the module's output at 100 % control duty, V,
pub const HV_FULL_SCALE_V: f32 = 10_000.0;
/// the control duty that gives 0 V, percent,
pub const HV_ZERO_DUTY_PCT: f32 = 0.0;
/// and the most the board may ever output, V: its duty is the hard cap of the HV writer.
pub const HV_LIMIT_V: f32 = 10_000.0;

pub trait Board {
    /// Servo PWM, 50 Hz; the application sets 1.0..2.0 ms pulses.
    type Servo: SetDutyCycle;
    /// One HV module's 0-5 V control input (a filtered PWM). One type for the three channels.
    type Hv: SetDutyCycle;
    /// HV enable (interlock): high only while armed.
    type Enable: OutputPin;

    fn servo(&mut self) -> &mut Self::Servo;
    /// HV control PWM of channel `ch` (0-based, < HV_CHANNELS).
    fn hv(&mut self, ch: usize) -> &mut Self::Hv;
    fn hv_enable(&mut self) -> &mut Self::Enable;
    /// Feed the independent watchdog. Called by the control loop (`App::tick`) only.
    fn feed_watchdog(&mut self);
    /// Board name for `version` (e.g. "stm32f405", "qemu", "sim").
    fn name(&self) -> &'static str;
    /// Line ending of the replies.
    fn newline(&self) -> &'static str {
        "\r\n"
    }
}
