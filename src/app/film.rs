//! The board's film on the command side: its law (the compiled card, layer thickness and margin
//! of `crate::board`), the hold ceiling the console can only lower, the `material` reply, the
//! equilibrium thickness `status` and `solve` report, and `pose`'s settling time (the model's
//! drive step, `finger_model::material::drive`, run from rest).
//!
//! What it is not: the control tick's integration of the stacks (`crate::control`), the
//! finger's model parameters (`param`: they can lower the ceiling in force, never raise it).

#[cfg(not(m3))]
use finger_model::material::drive::{settling_time, DriveLimits, Mode};
#[cfg(not(m3))]
use finger_model::material::hold_ratio;
#[cfg(not(m3))]
use finger_model::material::Relaxation;
use finger_model::material::{equilibrium_ratio, StackLaw};
use finger_model::Error as ModelError;
#[cfg(not(m3))]
use finger_protocol::field;

#[cfg(not(m3))]
use super::help::Reply;
#[cfg(not(m3))]
use crate::board::HV_LIMIT_V;
use crate::board::{board_hold_ceiling_of, board_law};
#[cfg(not(m3))]
use crate::board::{BOARD_CARD, BOARD_MARGIN, BOARD_Z0_MM};
#[cfg(not(m3))]
use crate::num::Short;

/// The settling simulation's step, s (the control tick's drive step at a coarser step: the
/// exponential branch step is exact for a held thickness).
#[cfg(not(m3))]
pub const SETTLE_STEP_S: f32 = 0.02;
/// Longest settling time `pose` looks for, s (past it: `settle=-`).
#[cfg(not(m3))]
pub const SETTLE_MAX_S: f32 = 600.0;
/// Settled: within this fraction of the target thickness.
#[cfg(not(m3))]
pub const SETTLE_TOL: f32 = 0.01;

/// `material`'s `units=`: each field's unit (`1`: a ratio), `branches` as its pairs' g:tau.
#[cfg(not(m3))]
pub const MATERIAL_UNITS: &str = "g_eq:MPa,branches:MPa:s,eps_r:1,breakdown:V/um,z0:mm,margin:1,s_hold:1,vhold:V";

/// The board's film, built once from the board constants.
pub(crate) struct BoardFilm {
    law: StackLaw<f32>,
    vhold: f32,
    /// The M3 image neither settles nor replies `material`: no `s_hold` there.
    #[cfg(not(m3))]
    s_hold: f32,
    #[cfg(not(m3))]
    settle_step: Relaxation<f32>,
}

impl BoardFilm {
    /// The compiled card's law. The board constants are valid (a host test checks them); a
    /// card the law refuses would leave no voltage at all.
    pub fn new() -> Self {
        let law = match board_law() {
            Ok(l) => l,
            Err(_) => panic!("board card"),
        };
        let vhold = board_hold_ceiling_of(&law);
        #[cfg(not(m3))]
        let s_hold = hold_ratio(&law).unwrap_or(1.0);
        #[cfg(not(m3))]
        let settle_step = match Relaxation::new(&law, SETTLE_STEP_S) {
            Ok(r) => r,
            Err(_) => panic!("settle step"),
        };
        BoardFilm {
            law,
            vhold,
            #[cfg(not(m3))]
            s_hold,
            #[cfg(not(m3))]
            settle_step,
        }
    }

    /// The board's hold ceiling, V per layer (`board_hold_ceiling_of`): margin x min(the voltage
    /// that holds the relaxed film at 2/3 of its thickness, the breakdown bound there), at most
    /// the HV modules' maximum.
    pub fn hold_ceiling(&self) -> f32 {
        self.vhold
    }

    /// Thickness stretch once fully relaxed at `volts` (1 at 0 V).
    pub fn equilibrium_ratio(&self, volts: f32) -> Result<f32, ModelError> {
        equilibrium_ratio(&self.law, volts)
    }

    /// Settling time from rest to within [`SETTLE_TOL`] of the thickness `target_v` gives once
    /// relaxed, s, slewed at `slew` V/s, plain or shaped (the shaped voltage at most the HV
    /// limit, as the control tick has it); None past [`SETTLE_MAX_S`].
    #[cfg(not(m3))]
    pub fn settle(&self, target_v: f32, slew: f32, shaped: bool) -> Result<Option<f32>, ModelError> {
        let lim = DriveLimits { s_hold: self.s_hold, slew_step: slew * SETTLE_STEP_S, v_cap: HV_LIMIT_V };
        let mode = if shaped { Mode::Shaped } else { Mode::Plain };
        settling_time(&self.law, &self.settle_step, &lim, mode, target_v, SETTLE_TOL, (SETTLE_MAX_S / SETTLE_STEP_S) as u32)
    }

    #[cfg(not(m3))]
    /// `material`'s reply (its last field, `units=`, the unit of each one before it): `card= g_eq= branches=g:tau,.. eps_r= breakdown= z0=
    /// margin= s_hold= vhold=` (MPa, s, V/um, mm, V; docs/firmware.md).
    pub fn write_material(&self, r: &mut Reply) {
        let c = BOARD_CARD;
        let _ = w!(r; field::CARD.first(), c.name, field::G_EQ.after(), Short(c.g_eq_mpa as f32), field::BRANCHES.after());
        if c.branches().is_empty() {
            let _ = w!(r; "-");
        }
        for (i, b) in c.branches().iter().enumerate() {
            let _ = w!(r; if i > 0 { "," } else { "" }, Short(b.g_mpa as f32), ":", Short(b.tau_s as f32));
        }
        let _ = w!(r; field::EPS_R.after(), Short(c.eps_r as f32), field::BREAKDOWN.after(), Short(c.breakdown.field0_v_per_um as f32));
        let _ = w!(r; field::Z0.after(), Short(BOARD_Z0_MM), field::MARGIN.after(), Short(BOARD_MARGIN), field::S_HOLD.after(), crate::num::Fixed(self.s_hold, 4), field::VHOLD.after(), crate::num::Fixed(self.vhold, 1));
        let _ = w!(r; field::UNITS.after(), MATERIAL_UNITS);
    }
}
