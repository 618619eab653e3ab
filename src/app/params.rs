//! The parameter registry: the firmware's own parameters ([`FwParams`], [`FW_PARAMS`]: name,
//! range, the one range check), the board's default finger and its FE calibration, the presets,
//! and `cal`'s factor names. The model's parameters are `finger_model::params::PARAMS`.
//!
//! What it is not: the `param` command (`super::commands`) or the stored record
//! (`super::stored`); both set values through the checks here.

use finger_model::{Calibration, Finger, Params};

use super::errors::CmdError;
use crate::board::{HV_CHANNELS, HV_FULL_SCALE_V, HV_ZERO_DUTY_PCT};

/// Number of HV channels / joints the board drives.
pub const CHANNELS: usize = HV_CHANNELS;

/// Firmware-only parameters (not in the model).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FwParams {
    /// HV setpoint slew rate, V/s.
    pub slew: f32,
    /// Servo spool radius, mm: servo angle = cable excursion / spool_r.
    pub spool_r: f32,
    /// Servo travel for pulses 1.0..2.0 ms, degrees.
    pub servo_range: f32,
    /// Servo direction: +1 (cable pulled in as the pulse grows from 1.0 ms) or -1.
    pub servo_dir: f32,
    /// Shaped actuation (docs/firmware.md): the control tick drives the voltage that holds
    /// the target's thickness now, instead of a slewed step to the target voltage.
    pub shaped: bool,
}

impl Default for FwParams {
    fn default() -> Self {
        FwParams { slew: 2000.0, spool_r: 10.0, servo_range: 180.0, servo_dir: 1.0, shaped: false }
    }
}

/// A firmware parameter's name and range (as the console reports it).
pub struct FwParamInfo {
    pub name: &'static str,
    pub min: f32,
    pub max: f32,
    pub range: &'static str,
}

pub const FW_PARAMS: &[FwParamInfo] = &[
    FwParamInfo { name: "slew", min: 1.0, max: 1e5, range: "1..1e5 V/s" },
    FwParamInfo { name: "spool_r", min: 0.5, max: 100.0, range: "0.5..100 mm" },
    FwParamInfo { name: "servo_range", min: 10.0, max: 360.0, range: if cfg!(m3) { "10..360 deg" } else { "10..360 deg (1.0..2.0 ms)" } },
    FwParamInfo { name: "servo_dir", min: -1.0, max: 1.0, range: "1 or -1" },
    #[cfg(not(m3))]
    FwParamInfo { name: "shaped", min: 0.0, max: 1.0, range: "0 (plain step) or 1 (shaped actuation)" },
    // read-only: the HV module's calibration is compiled in (crate::board); a set is refused
    FwParamInfo {
        name: "hv_fs",
        min: 1.0,
        max: 0.0,
        range: if cfg!(m3) { "read-only" } else { "read-only: V at 100 % duty, a board constant (a different HV module is a different build)" },
    },
    FwParamInfo {
        name: "hv_zero",
        min: 1.0,
        max: 0.0,
        range: if cfg!(m3) { "read-only" } else { "read-only: % duty at 0 V, a board constant (a different HV module is a different build)" },
    },
];

impl FwParams {
    pub fn get(&self, name: &str) -> Option<f32> {
        Some(match name {
            "slew" => self.slew,
            "spool_r" => self.spool_r,
            "servo_range" => self.servo_range,
            "servo_dir" => self.servo_dir,
            #[cfg(not(m3))]
            "shaped" => self.shaped as u8 as f32,
            "hv_fs" => HV_FULL_SCALE_V,
            "hv_zero" => HV_ZERO_DUTY_PCT,
            _ => return None,
        })
    }

    /// Set by name; on error nothing changes.
    pub(crate) fn set(&mut self, name: &str, v: f32) -> Result<(), CmdError> {
        let info = FW_PARAMS.iter().find(|i| i.name == name).ok_or_else(|| err!(Unknown; "no parameter ", name))?;
        let bad = || err!(Usage; "parameter ", info.name, " out of range: ", info.range);
        if !(v >= info.min && v <= info.max) {
            return Err(bad());
        }
        let f = v;
        match name {
            "slew" => self.slew = f,
            "spool_r" => self.spool_r = f,
            "servo_range" => self.servo_range = f,
            "servo_dir" if v == 1.0 || v == -1.0 => self.servo_dir = f,
            #[cfg(not(m3))]
            "shaped" if v == 0.0 || v == 1.0 => self.shaped = v == 1.0,
            _ => return Err(bad()),
        }
        Ok(())
    }
}

/// `cal`'s factors in console order (`Calibration`: hinge, stack_axial, stack_bending).
pub(crate) const CAL_NAMES: [&str; 8] = ["h1", "h2", "h3", "h4", "ea0", "ea1", "ei0", "ei1"];

/// The board's default finger: docs/model.md's on the board's film (`Params::with_card`: the card's
/// equilibrium modulus, permittivity, branches and breakdown field) under the board's gravity
/// (`board::BOARD_GRAVITY`: 9.81 m/s², hanging straight down), with a design's values
/// (`board::BOARD_FINGER`, docs/design.md) set as the console sets them. Generic so that the
/// host's f64 model (the web view's overlay) is the board's finger too.
pub fn board_params<R: finger_model::Real>() -> Params<R> {
    use crate::board::{BOARD_GRAVITY, BOARD_GRAV_DIR_DEG, BOARD_GRAV_M_S2};
    let mut p = Params::with_card(crate::board::BOARD_CARD);
    // (a constant: no code where it is off, the Cortex-M3 image)
    if BOARD_GRAVITY {
        (p.grav, p.grav_dir) = (R::from_f64(BOARD_GRAV_M_S2), R::from_f64(BOARD_GRAV_DIR_DEG));
    }
    for &(name, v) in crate::board::BOARD_FINGER {
        // build.rs checked the ranges; a refused value would keep the default's
        let _ = p.set(name, v.into());
    }
    p
}

/// The FE calibration of a parameter set (`Calibration::for_params`) judged by its structure:
/// docs/model.md's finger on the board's film has docs/model.md's calibration. Its hinge factors belong
/// to the geometry; its stack factors were computed for the paper's film, and on VHB 4905 the
/// stacks add almost nothing to the joints (docs/materials.md), so the film does not clear it.
/// A board built from a design file with `cal` (docs/design.md) gives the design's finger the
/// design's factors (build.rs checked them as `Finger::with_calibration` does).
pub fn calibration_for<R: finger_model::Real>(p: &Params<R>) -> Calibration<R> {
    let d = Params::<R>::default();
    let board = board_params::<R>();
    if let Some(g) = crate::board::BOARD_CAL {
        let cal = Calibration::from_factors(g.map(|x| R::from_f64(x as f64))).if_for(p, &board);
        if cal != Calibration::none() {
            return cal;
        }
    }
    let film_is_the_boards = p.card == board.card && p.g == board.g && p.nu == board.nu && p.de_rule == board.de_rule;
    let mut q = *p;
    if film_is_the_boards {
        (q.card, q.g, q.nu, q.de_rule) = (d.card, d.g, d.nu, d.de_rule);
    }
    Calibration::for_params(&q)
}

/// A preset as this build can hold it: without the `de` feature the finger has no stacks.
pub(crate) fn preset(p: Params<f32>) -> Params<f32> {
    if cfg!(feature = "de") {
        p
    } else {
        p.without_stacks()
    }
}

/// The compiled defaults' finger: docs/model.md's on the board's film with its FE calibration
/// (as this build holds it; `preset default`). The defaults are valid (a model test); no Debug
/// formatting of the error on the target.
pub fn default_finger() -> Finger<f32> {
    let p = preset(board_params());
    match Finger::with_calibration(p, calibration_for(&p)) {
        Ok(f) => f,
        Err(_) => panic!("default parameters"),
    }
}
