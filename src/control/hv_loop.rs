//! One HV channel's voltage loop: the measured voltage regulated to the voltage the guard
//! allows, every tick. The open-loop calibration's voltage is the feed-forward; a PI term
//! with anti-windup corrects a module whose gain is off its datasheet.
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
}

impl VoltageLoop {
    pub const fn new() -> Self {
        VoltageLoop { integral_v: 0.0 }
    }

    /// The voltage to ask of the module for `drive_v` with `measured_v` read back, in
    /// [0, limit_v]; the integral grows only while the output is not held at a bound.
    pub fn step(&mut self, drive_v: f32, measured_v: f32, limit_v: f32) -> f32 {
        if !(drive_v > 0.0) {
            self.integral_v = 0.0;
            return 0.0;
        }
        let e = drive_v - measured_v;
        if !e.is_finite() {
            return drive_v.min(limit_v);
        }
        let bound = INTEGRAL_FRAC * drive_v + 50.0;
        let trial = (self.integral_v + KI_PER_S * 1e-3 * e).clamp(-bound, bound);
        let u = drive_v + KP * e + trial;
        if (u < limit_v || e < 0.0) && (u > 0.0 || e > 0.0) {
            self.integral_v = trial;
        }
        let u = drive_v + KP * e + self.integral_v;
        if u > limit_v {
            limit_v
        } else if u > 0.0 {
            u
        } else {
            0.0
        }
    }
}
