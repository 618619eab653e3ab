//! One HV channel's voltage loop: the measured voltage regulated to the voltage the guard
//! allows, every tick. The open-loop calibration's voltage is the feed-forward; a PI term
//! with anti-windup corrects a module whose gain is off its datasheet. The voltage asked of
//! the module moves at most one slew step a tick, as the open-loop command did: the loop and
//! the hold ripple never step the module's input faster than the slew.
//!
//! What it is not: the ceiling (the caller clamps the output to the channel's duty ceiling:
//! the loop can ask no more than the open loop could), the guard (`super::stacks`).

/// Proportional gain (V asked per V of error) and integral gain, 1/s.
pub const KP: f32 = 0.5;
pub const KI_PER_S: f32 = 30.0;
/// The integral term's bound, as a fraction of the command (a module 20 % off at most).
pub const INTEGRAL_FRAC: f32 = 0.25;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VoltageLoop {
    integral_v: f32,
    asked_v: f32,
}

/// One tick's output: the voltage asked of the module, and whether the slew held it back
/// from what the loop wanted (the module had no chance yet to follow).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ask {
    pub volts: f32,
    pub slew_held: bool,
}

impl Ask {
    /// Nothing asked.
    pub const ZERO: Ask = Ask { volts: 0.0, slew_held: false };
}

impl VoltageLoop {
    pub const fn new() -> Self {
        VoltageLoop { integral_v: 0.0, asked_v: 0.0 }
    }

    /// The voltage last asked of the module, V.
    pub fn asked_v(&self) -> f32 {
        self.asked_v
    }

    /// The voltage to ask of the module for `drive_v` with `measured_v` read back: at most
    /// `top_v` (followed at the slew, as the drive is), within `max_step_v` of the last tick's
    /// ask, then in [0, limit_v] (a ceiling that drops is obeyed at once). A drive of 0 ramps
    /// the ask down to 0 (a stop or a fault zeroes the duties past the loop, at once).
    pub fn step(&mut self, drive_v: f32, measured_v: f32, top_v: f32, limit_v: f32, max_step_v: f32) -> Ask {
        if !(drive_v > 0.0 && limit_v > 0.0) {
            // down to 0 one step a tick (a disarm's ramp ends there); a ceiling of 0 at once
            let u = self.asked_v - max_step_v;
            let u = if u > 0.0 && u <= limit_v { u } else { 0.0 };
            *self = VoltageLoop { integral_v: 0.0, asked_v: u };
            return Ask { volts: u, slew_held: u > 0.0 };
        }
        let (lo, hi) = (self.asked_v - max_step_v, self.asked_v + max_step_v);
        let e = drive_v - measured_v;
        let e = if e.is_finite() { e } else { 0.0 };
        let bound = INTEGRAL_FRAC * drive_v + 50.0;
        let trial = (self.integral_v + KI_PER_S * 1e-3 * e).clamp(-bound, bound);
        // anti-windup by back-calculation: at a bound, the integral grows only as far as
        // puts the output on it
        let (top, bottom) = (hi.min(limit_v).min(top_v), lo.max(0.0));
        let p_v = drive_v + KP * e;
        let integral = if p_v + trial > top && e > 0.0 {
            trial.min(self.integral_v.max(top - p_v))
        } else if p_v + trial < bottom && e < 0.0 {
            trial.max(self.integral_v.min(bottom - p_v))
        } else {
            trial
        };
        if integral.is_finite() {
            self.integral_v = integral;
        }
        let want = (p_v + self.integral_v).min(top_v);
        // NaN-safe: a want that is not a number asks the slewed bound below
        let u = if want > hi {
            hi
        } else if want > lo {
            want
        } else {
            lo
        };
        let u = if u > limit_v {
            limit_v
        } else if u > 0.0 {
            u
        } else {
            0.0
        };
        self.asked_v = u;
        // held back: what the PI term would ask without the anti-windup (which puts the output
        // exactly on the slew's bound, so the output alone flickers between held and not)
        let free = (p_v + trial).min(top_v);
        Ask { volts: u, slew_held: (free > hi && hi < limit_v) || (free < lo && lo > 0.0) }
    }
}
