//! The read-back's hard checks in integers: the Cortex-M3 image's (no FPU; docs/firmware.md
//! "Cortex-M3 image"), on the same constants as the F405's `super::watch` and the analog
//! watchdog's codes (`crate::sampling::awd_codes`). Compiled on every target so the host tests
//! reach it (host-tests/tests/code_trip.rs).
//!
//! What it is: per channel, each tick, on the tick's mean codes in sixteenths of a code (the
//! only float work: the two means into integers) and the duty the core wrote:
//! - a reading not finite or at the monitor's rail: `sensor`;
//! - a return current past the analog watchdog's trip code: `breakdown` (the watchdog's own
//!   trip, `HvSense::trip`, is the caller's);
//! - a voltage past the ceiling in force by `OVER_FRAC` + `OVER_V` for `OVER_MS` ticks: `hv-mismatch`
//!   (the bound decays from a ceiling that dropped at the module's fall, `MODULE_FALL_MS`);
//! - a monitor code that does not move for `STUCK_MS` ticks while the duty moved past the duty
//!   of `STUCK_MOVE_V`: `sensor`.
//!
//! What it is not: the F405's finer checks (the mismatch against the loop's drive, the
//! collapse, an open stack, the leakage, the thickness guard: `super::watch`, on the estimator).

use super::fault::Fault;
use super::watch::{MODULE_FALL_MS, OVER_FRAC, OVER_MS, OVER_V, STUCK_MOVE_V, STUCK_MS};
use crate::board::{ADC_FULL_CODE, HV_FULL_SCALE_V, VMON_FULL_SCALE_V};

/// A channel's scales, from its PWM's full-scale duty (the only float work, once).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CodeScale {
    /// The monitor's code of one duty count, sixteenths of a code, Q16.
    c16_per_duty_q16: u32,
    /// `OVER_V` in sixteenths of a code.
    over_v_c16: u32,
    /// The monitor's rail: at or above it, a reading is `sensor`.
    rail_c16: u32,
    /// The current code the analog watchdog trips past (its HTR), in sixteenths.
    current_high_c16: u32,
    /// `OVER_FRAC`, Q16.
    over_frac_q16: u32,
    /// The duty of `STUCK_MOVE_V`.
    stuck_move_duty: u16,
}

/// The bound's fall after a ceiling drops: one part in this many a tick.
const FALL_TICKS: u32 = MODULE_FALL_MS as u32;

impl CodeScale {
    /// The scales of a PWM whose full-scale duty is `max_duty`.
    pub fn new(max_duty: u16) -> Self {
        let c16_per_v = 16.0 * ADC_FULL_CODE / VMON_FULL_SCALE_V;
        let v_per_duty = HV_FULL_SCALE_V / max_duty.max(1) as f32;
        CodeScale {
            c16_per_duty_q16: (c16_per_v * v_per_duty * 65536.0) as u32,
            over_v_c16: (OVER_V * c16_per_v) as u32,
            rail_c16: ((ADC_FULL_CODE - 0.5) * 16.0) as u32,
            current_high_c16: crate::sampling::awd_codes().current_high as u32 * 16,
            over_frac_q16: (OVER_FRAC * 65536.0) as u32,
            stuck_move_duty: super::hv_duty_for(STUCK_MOVE_V, max_duty),
        }
    }

    /// The monitor's code of `duty`, sixteenths.
    fn c16_of_duty(&self, duty: u32) -> u32 {
        ((duty as u64 * self.c16_per_duty_q16 as u64) >> 16) as u32
    }

    /// The over-voltage bound of a ceiling of `duty`, sixteenths of a code: its code x (1 +
    /// `OVER_FRAC`) + `OVER_V`'s (a reading above it counts).
    pub fn over_bound_c16(&self, duty: u16) -> u32 {
        let c = self.c16_of_duty(duty as u32);
        c + ((c as u64 * self.over_frac_q16 as u64) >> 16) as u32 + self.over_v_c16
    }

    /// The current code the checks trip above (the analog watchdog's HTR), sixteenths.
    pub fn current_high_c16(&self) -> u32 {
        self.current_high_c16
    }

    /// The duty a stuck monitor's command must move past.
    pub fn stuck_move_duty(&self) -> u16 {
        self.stuck_move_duty
    }
}

/// A tick's mean code in sixteenths: None for a reading not finite or negative.
pub fn c16_of_code(code: f32) -> Option<u32> {
    if (0.0..=ADC_FULL_CODE).contains(&code) {
        Some((code * 16.0) as u32)
    } else {
        None
    }
}

/// One channel's counters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CodeWatch {
    over_ms: u16,
    stuck_ms: u16,
    stuck_from_duty: u16,
    /// The last monitor code, sixteenths (`u16::MAX`: none yet; a reading there is at the rail).
    last_c16: u16,
    /// The ceiling's duty x 16, falling at the module's fall after a drop.
    fall_env16: u32,
}

impl Default for CodeWatch {
    fn default() -> Self {
        Self::new()
    }
}

impl CodeWatch {
    pub const fn new() -> Self {
        CodeWatch { over_ms: 0, stuck_ms: 0, stuck_from_duty: 0, last_c16: u16::MAX, fall_env16: 0 }
    }

    /// One tick: the mean codes `v_code`, `i_code`, the `duty` written, the channel's duty
    /// ceiling `ceiling_duty`, the HV enable.
    pub fn check(&mut self, s: &CodeScale, v_code: f32, i_code: f32, duty: u16, ceiling_duty: u16, enabled: bool) -> Option<Fault> {
        let (Some(v), Some(i)) = (c16_of_code(v_code), c16_of_code(i_code)) else { return Some(Fault::Sensor) };
        if v >= s.rail_c16 {
            return Some(Fault::Sensor);
        }
        if i > s.current_high_c16 {
            return Some(Fault::Breakdown);
        }
        // the bound: the ceiling in force, a drop followed at the module's fall
        let c16 = ceiling_duty as u32 * 16;
        self.fall_env16 = if c16 >= self.fall_env16 { c16 } else { self.fall_env16 - (self.fall_env16 - c16) / FALL_TICKS };
        let bound = s.over_bound_c16((self.fall_env16 / 16) as u16);
        self.over_ms = if v > bound { self.over_ms.saturating_add(1) } else { 0 };
        if self.over_ms as u32 >= OVER_MS {
            return Some(Fault::HvMismatch);
        }
        let want = if enabled { duty } else { 0 };
        if v == self.last_c16 as u32 {
            if self.stuck_ms == 0 {
                self.stuck_from_duty = want;
            }
            self.stuck_ms = self.stuck_ms.saturating_add(1);
            if self.stuck_ms as u32 >= STUCK_MS && want.abs_diff(self.stuck_from_duty) > s.stuck_move_duty {
                return Some(Fault::Sensor);
            }
        } else {
            self.stuck_ms = 0;
        }
        self.last_c16 = v as u16;
        None
    }
}
