//! One HV channel's checks on what it measures, every tick: the faults the read-back shows
//! (breakdown, a module off its command, an open stack, a sensor at its rail or stuck, a
//! rising leakage), and the thickness guard that lowers the channel's own ceiling when the
//! sensed film is thinner than the model's.
//!
//! What it is not: the cut itself (`super::Control::fault_stop`), the estimate
//! (`super::sense`). Every comparison is written so that NaN fails safe.

use super::fault::Fault;
use super::hv_loop::Ask;
use super::sense::Estimator;
use crate::board::{ADC_FULL_CODE, BOARD_STACK_C0_PF, SENSE_STRAY_PF, TRIP_CURRENT_UA};

/// The loop's settling: a measured voltage off its command longer than this is a module
/// that does not follow, ms.
pub const HV_SETTLE_MS: u32 = 300;
/// Off its command: by more than this many volts or this fraction of the command.
pub const MISMATCH_V: f32 = 300.0;
pub const MISMATCH_FRAC: f32 = 0.1;
/// While the slew holds the loop's ask back, a healthy module still follows the ask: within
/// this fraction of it (a gain off its datasheet) or [`MISMATCH_V`], plus its lag (the ask's
/// rate over [`MODULE_FALL_MS`]). Off that, the mismatch counts.
pub const FOLLOW_FRAC: f32 = 0.15;
/// A monitor code unchanged for [`STUCK_MS`] while the command moved more than this, V: a
/// stuck sensor. Half the low-voltage check's voltage, so the check's own ramp shows one (at
/// 200 V, the check's voltage itself, the rule could not fire during the check); 37 codes of
/// the monitor.
pub const STUCK_MOVE_V: f32 = 0.5 * super::LOW_CHECK_V;
pub const STUCK_MS: u32 = 50;
/// Past the ceiling in force by this fraction plus [`OVER_V`], for [`OVER_MS`]: at once (board
/// constants: the analog watchdog's voltage code uses them too).
pub use crate::board::{OVER_FRAC, OVER_V};
pub const OVER_MS: u32 = 60;
/// The module's fall, the time constant the over-ceiling bound decays with after a command
/// drops (the module's datasheet lag, with margin), ms.
pub const MODULE_FALL_MS: f32 = 25.0;
/// A held command whose measured voltage fell under this fraction of it (and of the module's
/// ask): a collapse.
pub const COLLAPSE_FRAC: f32 = 0.5;
/// An open stack: the sensed capacitance under this fraction of the stack's.
pub const OPEN_FRAC: f32 = 0.3;
/// The leakage bound, µA, and as a conductance, µA/V (0.2 nS: 5 GΩ; a healthy stack of the
/// board's film leaks under 0.01 nS at its ceiling), checked at a command above
/// [`LEAK_CHECK_MIN_V`]: the lower of the two. A leak that a lowered ceiling holds at a low
/// voltage is still one.
pub const LEAK_BOUND_UA: f32 = 1.0;
pub const LEAK_BOUND_UA_PER_V: f32 = 2e-4;
pub const LEAK_CHECK_MIN_V: f32 = 50.0;
/// The leakage bound is never under two counts of the current sense (24.4 nA each): the
/// conductance's bound at a low voltage (14 nA at 69 V) was under the sense's resolution, and
/// a film's creep current there latched `leakage` in a fault-free history.
pub const LEAK_FLOOR_UA: f32 = 0.05;
/// The thickness guard lowers the ceiling once the sensed film is within this of its floor
/// and thinner than the model's by more than [`NEAR_GAP_S`].
pub const FLOOR_MARGIN_S: f32 = 0.03;
/// A sensed film thinner than the model's by no more than this (the disagreement's own bound)
/// agrees with it: the model's own guard keeps its film above the floor, and the card's film
/// held at the ceiling relaxes to within [`FLOOR_MARGIN_S`] of it by design (s_hold 0.818:
/// 0.848 after 227 s at 5,394 V, where the guard lowered a healthy film's ceiling). The
/// sensing's scatter about the model on the card's film and its spread, held at 0.9-1.0 of the
/// ceiling: at most 0.0084 thinner over 60 holds of 900 s (docs/reliability.md "Measured HV").
pub const NEAR_GAP_S: f32 = DISAGREE_S;
/// The sensed and the model's thickness disagree past this (absolute, in s), over this many
/// windows in a row (one window's outlier lowers nothing; near the floor the guard acts at once).
pub const DISAGREE_S: f32 = 0.02;
pub const DISAGREE_WINDOWS: u32 = 3;
/// The disagreement counts only on a channel held this long, ms (ten ripple windows: a slew's
/// charge carries the film's creep, which reads thinner, and the running mean keeps the
/// slew's windows for a while).
pub const GUARD_HELD_MS: u32 = 1000;
/// A disagreement this large counts at once, on a window that solved its capacitance jointly
/// with the leakage (a pair): past the 0.02-0.03 a slew's windows read thin
/// (`hv_measured`'s `the_sensed_thickness_follows_the_film`). A film half the card's modulus
/// creeping 94 times faster, held at the ceiling, passed 2/3 within 3.2 s while the guard
/// waited out its hold (`fuzz/regressions/plant/soft-film-5399-fast-slew`). A slew's lone
/// windows do not count: a leak that arose on a ramp reads there as charge, so as a thick
/// capacitance (a 2-5 µA leak on a 2,000 V/s ramp read s 0.87 for 0.998, and the guard held
/// the channel under the leakage check's voltage: the leak never latched).
pub const DISAGREE_FAST_S: f32 = 0.06;

/// One tick's reading of a channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reading {
    pub v: f32,
    pub i_ua: f32,
    pub v_code: f32,
}

/// One channel's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Watch {
    steady_ms: u32,
    collapse_ms: u32,
    mismatch_ms: u32,
    over_ms: u32,
    stuck_ms: u32,
    stuck_from_v: f32,
    last_code: f32,
    leak_ms: u32,
    prev_drive: f32,
    prev_ask: f32,
    fall_env: f32,
}

impl Watch {
    pub const fn new() -> Self {
        Watch {
            steady_ms: 0,
            collapse_ms: 0,
            mismatch_ms: 0,
            over_ms: 0,
            stuck_ms: 0,
            stuck_from_v: 0.0,
            last_code: -1.0,
            leak_ms: 0,
            prev_drive: 0.0,
            prev_ask: 0.0,
            fall_env: 0.0,
        }
    }

    /// The checks of one tick: `drive_v` the voltage the loop drives to, `ask` what the loop
    /// asked of the module (held back by the slew, a module off its command is not yet one that
    /// does not follow, as long as it follows the ask), `ceiling_v` the channel's ceiling in
    /// force, `enabled` the HV enable.
    pub fn check(&mut self, r: &Reading, drive_v: f32, ask: &Ask, ceiling_v: f32, enabled: bool, est: &Estimator) -> Option<Fault> {
        if !(r.v.is_finite() && r.i_ua.is_finite() && r.v_code >= 0.0) || r.v_code >= ADC_FULL_CODE - 0.5 {
            return Some(Fault::Sensor);
        }
        if !(r.i_ua <= TRIP_CURRENT_UA) {
            return Some(Fault::Breakdown);
        }
        // the ceiling applies to the measured voltage: past it is a module that runs away
        // a command that drops (a guard's cut, a stop) is followed at the module's own fall:
        // the bound decays from the last command with MODULE_FALL_MS
        self.fall_env = if drive_v >= self.fall_env { drive_v } else { self.fall_env + (drive_v - self.fall_env) * (1.0 / MODULE_FALL_MS) };
        let over_bound = ceiling_v.max(self.fall_env);
        self.over_ms = if !(r.v <= over_bound * (1.0 + OVER_FRAC) + OVER_V) { self.over_ms + 1 } else { 0 };
        if self.over_ms >= OVER_MS {
            return Some(Fault::HvMismatch);
        }
        let steady = (drive_v - self.prev_drive).abs() <= 1.0 + 0.01 * drive_v;
        self.prev_drive = drive_v;
        self.steady_ms = if steady { self.steady_ms.saturating_add(1) } else { 0 };
        let off = (r.v - drive_v).abs() > MISMATCH_V.max(MISMATCH_FRAC * drive_v);
        let want = if enabled { drive_v } else { 0.0 };
        let off = if enabled { off } else { r.v > 2.0 * MISMATCH_V };
        // the slew holding the loop's ask back: a module that follows the ask had no chance
        // yet to follow the command (no mismatch); one off its ask counts
        let lag_v = (ask.volts - self.prev_ask).abs() * MODULE_FALL_MS;
        self.prev_ask = ask.volts;
        let follows_ask = !((r.v - ask.volts).abs() > MISMATCH_V.max(FOLLOW_FRAC * ask.volts) + lag_v);
        self.mismatch_ms = if !off || (enabled && ask.slew_held && follows_ask) { 0 } else { self.mismatch_ms + 1 };
        // against what the module was asked as well: one still catching up with its ask (a drive
        // that stepped up) follows it; a short pulls the output under an ask at or above the drive
        if enabled && self.steady_ms >= 30 && drive_v > 1000.0 && r.v < COLLAPSE_FRAC * drive_v.min(ask.volts) {
            self.collapse_ms += 1;
            if self.collapse_ms >= 3 {
                return Some(Fault::Breakdown);
            }
        } else {
            self.collapse_ms = 0;
        }
        if self.mismatch_ms > HV_SETTLE_MS {
            return Some(Fault::HvMismatch);
        }
        // a reading that does not move while its command moves by STUCK_MOVE_V: stuck
        if r.v_code == self.last_code {
            if self.stuck_ms == 0 {
                self.stuck_from_v = want;
            }
            self.stuck_ms += 1;
            if self.stuck_ms >= STUCK_MS && (want - self.stuck_from_v).abs() > STUCK_MOVE_V {
                return Some(Fault::Sensor);
            }
        } else {
            self.stuck_ms = 0;
        }
        self.last_code = r.v_code;
        if enabled {
            if let Some(c) = est.capacitance_pf() {
                if !(c - SENSE_STRAY_PF >= OPEN_FRAC * BOARD_STACK_C0_PF) {
                    return Some(Fault::StackOpen);
                }
            }
            let bound = LEAK_BOUND_UA.min(LEAK_BOUND_UA_PER_V * drive_v).max(LEAK_FLOOR_UA);
            let leaking = drive_v > LEAK_CHECK_MIN_V && est.leakage_ua().is_some_and(|l| !(l <= bound));
            self.leak_ms = if leaking { self.leak_ms + 1 } else { 0 };
            if self.leak_ms >= 200 {
                return Some(Fault::Leakage);
            }
        }
        None
    }
}

/// The thickness guard of one channel: a factor (0, 1] on its ceiling, lowered when the
/// sensed film is thinner than the model's (a film softer than the card), never raised until
/// a stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThicknessGuard {
    pub derate: f32,
    /// The sensed thickness disagreed with the model's past [`DISAGREE_S`].
    pub disagreed: bool,
    disagree_windows: u32,
}

impl Default for ThicknessGuard {
    fn default() -> Self {
        Self::new()
    }
}

impl ThicknessGuard {
    pub const fn new() -> Self {
        ThicknessGuard { derate: 1.0, disagreed: false, disagree_windows: 0 }
    }

    /// After a window that measured the film (a stale thickness acts on nothing: held under
    /// the ripple's voltage, a channel keeps its last swing's, and a guard that acted on it
    /// window after window took a healthy film's ceiling down to 300 V): `s_meas` sensed, `s_model` the model's, `s_floor` the floor, the
    /// card's equilibrium voltages of the two thicknesses, and `held_ms` how long the channel
    /// has been held, `joint` whether the window solved its capacitance with the leakage.
    pub fn update(&mut self, s_meas: f32, s_model: f32, s_floor: f32, volts_model_at_model: f32, volts_model_at_meas: f32, held_ms: u32, joint: bool) {
        if !(s_meas > 0.0 && s_meas <= 1.5) {
            return;
        }
        // before the channel has been held GUARD_HELD_MS, only a pair's disagreement past what
        // a slew's windows read (DISAGREE_FAST_S)
        let gap = s_model - s_meas;
        let thinner = gap > DISAGREE_S && (held_ms >= GUARD_HELD_MS || (joint && gap > DISAGREE_FAST_S));
        self.disagree_windows = if thinner { self.disagree_windows.saturating_add(1) } else { 0 };
        if self.disagree_windows >= DISAGREE_WINDOWS {
            self.disagreed = true;
            // the film's voltage scale: at equilibrium a film g times the card's modulus needs
            // sqrt(g) times the card's voltage for the same thickness
            // (to the power 1.5: while both films creep, the ratio understates the softness)
            if volts_model_at_meas > volts_model_at_model && volts_model_at_model > 0.0 {
                let c = volts_model_at_model / volts_model_at_meas;
                self.derate = self.derate.min(c * libm::sqrtf(c));
            }
        }
        // the sensed film near or under its floor, and thinner than the model's past the
        // sensing's scatter: lower the ceiling in proportion
        let near = s_floor + FLOOR_MARGIN_S;
        if s_meas < near && gap > NEAR_GAP_S {
            self.derate *= 1.0 - 4.0 * (near - s_meas);
        }
        self.derate = self.derate.clamp(0.0, 1.0);
    }
}
