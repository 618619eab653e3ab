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
/// The design's FE calibration factors (`cal`'s order: h1..h4, ea0, ea1, ei0, ei1), computed
/// for its finger by the design tool (docs/design.md "From a design to a board"): the board's
/// default finger carries them (`app::params::calibration_for`); None: docs/model.md's rule.
pub const BOARD_CAL: Option<[f32; 8]> = design::BOARD_CAL;

/// The board's finger's orientation (issue 53): gravity on, at standard gravity, hanging
/// straight down (`grav_dir` 0: a finger on a downward-facing gripper); off on the Cortex-M3
/// image, whose fixed-point model has no gravity. The one switch: false gives the board's
/// finger without gravity (`grav` 0), as before gravity was modelled.
pub const BOARD_GRAVITY: bool = !cfg!(m3);
/// The board's default finger's `grav` (m/s²) and `grav_dir` (degrees from the straight
/// finger's axis toward the cable side); a design file's `grav` and `grav_dir` override them
/// (`BOARD_FINGER`).
pub const BOARD_GRAV_M_S2: f64 = if BOARD_GRAVITY { finger_model::params::G_STANDARD } else { 0.0 };
pub const BOARD_GRAV_DIR_DEG: f64 = 0.0;

/// The constants above as build.rs wrote them from the design file (`FINGER_DESIGN`,
/// docs/design.md), or the paper's finger on VHB 4905 without one.
mod design {
    include!(concat!(env!("OUT_DIR"), "/board_design.rs"));
}

/// The HV read-back chain, board constants (docs/firmware.md "HV read-back"): each channel's
/// module output through an HV divider and each stack's return current through a low-side
/// sense, sampled by the ADCs at [`SENSE_SAMPLES_PER_TICK`] per 1 ms tick and averaged.
/// The ADC's bits, its full-scale code, and its reference (VREF+ = VDDA), V.
pub const ADC_BITS: u32 = 12;
pub const ADC_FULL_CODE: f32 = 4095.0;
pub const ADC_VREF_V: f32 = 3.3;
/// Voltage monitor: the HV at the ADC's full scale, V (1 GΩ over 301 kΩ into 3.3 V).
pub const VMON_FULL_SCALE_V: f32 = 10_967.0;
/// Return-current sense, bipolar (a stack's current flows back as it discharges), its parts:
/// the low-side sense resistor, Ω, and its amplifier's gain around mid-scale.
pub const IMON_SENSE_OHM: f32 = 10_000.0;
pub const IMON_GAIN: f32 = 3.3;
/// The span of the ADC's codes, µA: `ADC_VREF_V` / (`IMON_SENSE_OHM` x `IMON_GAIN`) = 100
/// (-50..+50 µA: ±0.5 V on the resistor, ±1.65 V after the gain, around mid-scale;
/// host-tests/tests/hv_sampling.rs derives it and the watchdog's codes from the parts),
/// and the code of 0 µA.
pub const IMON_SPAN_UA: f32 = 100.0;
pub const IMON_ZERO_CODE: f32 = 2048.0;
/// ADC samples of each reading per tick (10 kHz).
pub const SENSE_SAMPLES_PER_TICK: u32 = 10;
/// The analog watchdog's trip on a return current, µA: past any charging current the
/// module's own slew allows (C at the 2/3 limit x 150 kV/s = 24 µA), below its 100 µA limit.
pub const TRIP_CURRENT_UA: f32 = 30.0;
/// The over-voltage rule's margin past the ceiling in force: this fraction plus `OVER_V`, V
/// (control::watch's rule, the M3's trip and the analog watchdog's voltage code).
pub const OVER_FRAC: f32 = 0.02;
pub const OVER_V: f32 = 60.0;
/// Each stack's electrode area (the hinge's width x its length), mm².
pub const BOARD_STACK_AREA_MM2: f32 = 200.0;
/// The stray capacitance the return sense sees besides the stack (the HV lead beside the
/// return lead in the stack's cable: 10 pF/m x 0.5 m), pF.
pub const SENSE_STRAY_PF: f32 = 5.0;
/// The least stray the parts allow (the lead's length and routing: 5 pF ± 1 pF), pF.
pub const SENSE_STRAY_MIN_PF: f32 = 4.0;

/// The independent watchdog (board build; `chip::f405::start_watchdog`): the LSI divided by
/// `IWDG_DIV` (IWDG_PR = 011), `IWDG_RELOAD` + 1 counts: 1.0 s at the LSI's typical 32 kHz,
/// [`iwdg_timeout_s`] over its 17-47 kHz (DS8626 f_LSI).
pub const IWDG_PR: u16 = 0b011;
pub const IWDG_DIV: u32 = 32;
pub const IWDG_RELOAD: u16 = 999;
pub const LSI_MIN_HZ: f32 = 17_000.0;
pub const LSI_MAX_HZ: f32 = 47_000.0;

/// The watchdog's timeout at an LSI of `lsi_hz`, s (0.68 s at 47 kHz, 1.88 s at 17 kHz).
pub fn iwdg_timeout_s(lsi_hz: f32) -> f32 {
    (IWDG_RELOAD + 1) as f32 * IWDG_DIV as f32 / lsi_hz
}

/// Each stack's capacitance at rest, pF: N_L layers in parallel, eps0 eps_r A / z0 (68 pF).
pub const BOARD_STACK_C0_PF: f32 = BOARD_LAYERS as f32 * 8.854e-3 * BOARD_CARD.eps_r as f32 * BOARD_STACK_AREA_MM2 / BOARD_Z0_MM;

/// One tick's HV read-back, averaged over the tick.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HvSense {
    /// Each channel's voltage monitor, the tick's mean ADC code (0..=4095).
    pub v_code: [f32; HV_CHANNELS],
    /// Each channel's return-current sense, the tick's mean ADC code.
    pub i_code: [f32; HV_CHANNELS],
    /// The analog watchdog fired in the tick (the return current past [`TRIP_CURRENT_UA`];
    /// the hardware dropped the enable): the channel.
    pub trip: Option<u8>,
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
    /// The HV read-back of the tick just ended; None on a board without one (the host's
    /// plain `SimBoard`: the HV runs open loop, as before the read-back).
    fn hv_sense(&mut self) -> Option<HvSense> {
        None
    }
    /// The simulated plant behind the read-back (`plant ...` on the console): the emulator
    /// image and the host's plant board only, never the board build.
    #[cfg(not(feature = "hw"))]
    fn plant(&mut self) -> Option<&mut crate::plant::Plant> {
        None
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
