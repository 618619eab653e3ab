//! The board the application drives: one servo PWM, three HV control PWMs, the HV enable
//! (interlock) and the watchdog; and the board constants of the HV modules and of the stacks
//! (their film card, layer thickness and count, the ceiling's margin), from which alone the
//! board's hold ceiling is computed. The STM32F405 behind the trait is the `chip` module.

use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;
use finger_model::material::{hold_ceiling, StackLaw};
use finger_model::Error as ModelError;

/// Number of HV channels (DE stacks) the board drives.
pub const HV_CHANNELS: usize = 3;

/// Board constants of the HV modules, compiled in (a different module is a different build;
/// no console parameter changes them):
/// the module's output at 100 % control duty, V (a design's supply, docs/design.md),
pub const HV_FULL_SCALE_V: f32 = design::HV_FULL_SCALE_V;
/// the control duty that gives 0 V, percent,
pub const HV_ZERO_DUTY_PCT: f32 = 0.0;
/// and the most the board may ever output, V: its duty is the hard cap of the HV writer.
pub const HV_LIMIT_V: f32 = design::HV_LIMIT_V;
/// What the HV modules can be asked for at all: min(full scale, limit), V. The model's ceiling
/// in force takes it as its `hv_fs` term, so previews and the board agree.
pub const HV_MAX_V: f32 = if HV_FULL_SCALE_V < HV_LIMIT_V { HV_FULL_SCALE_V } else { HV_LIMIT_V };

/// The board's film, compiled in (a different film, layer or margin is a different build; the
/// console's parameters can only lower the ceiling these give, docs/materials.md):
/// the material card of the stacks' film,
pub const BOARD_CARD: &finger_model::material::Card = design::BOARD_CARD;
/// the thickness of one layer at rest, mm,
pub const BOARD_Z0_MM: f32 = design::BOARD_Z0_MM;
/// the layers per stack,
pub const BOARD_LAYERS: u32 = design::BOARD_LAYERS;
/// and the fraction of the film's hold and breakdown bounds the ceiling allows.
pub const BOARD_MARGIN: f32 = design::BOARD_MARGIN;
/// The design's finger (console names and values) the board's default parameters take
/// (`app::params::board_params`); empty for the paper's finger.
pub const BOARD_FINGER: &[(&str, f32)] = design::BOARD_FINGER;

/// The constants above as build.rs wrote them from the design file (`FINGER_DESIGN`,
/// docs/design.md), or the paper's finger on VHB 4905 without one.
mod design {
    include!(concat!(env!("OUT_DIR"), "/board_design.rs"));
}

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

/// One layer of the board's stacks as the material law sees it (the card, z0, the margin).
pub fn board_law() -> Result<StackLaw<f32>, ModelError> {
    StackLaw::new(BOARD_CARD, BOARD_Z0_MM, BOARD_MARGIN)
}

/// The board's hold ceiling, V, from the board's law (`board_law`) its caller already has:
/// min(the card's hold ceiling at the board's z0 and margin, the supply `HV_MAX_V`); 0 when
/// the law gives none (NaN-proof).
pub fn board_hold_ceiling_of(law: &StackLaw<f32>) -> f32 {
    let v = hold_ceiling(law, BOARD_MARGIN);
    if v > 0.0 {
        v.min(HV_MAX_V)
    } else {
        0.0
    }
}
