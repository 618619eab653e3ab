//! One HV channel driven in time: the control tick's step on a stack (slew, the guard that
//! keeps the film at or above its floor now, the thickness, the branch flow), and the settling
//! time to a target found by running that same step (docs/firmware.md, `pose`'s `settle=`).
//!
//! Each step, for a target voltage `V_t` (at or below the hold ceiling) whose relaxed stretch is
//! `s_t`: the goal is `V_t` (plain) or, shaped, [`shaped_voltage`]`(state, s_t)` capped at
//! `v_cap` (the voltage that holds the film at `s_t` now: above `V_t` while the branches are
//! unrelaxed, decaying to it); the voltage slews toward the goal; then [`guarded_tick`] at the
//! floor `s_hold` (plain) or `s_t` (shaped): the guard, the thickness, the branch flow. The
//! firmware's control tick (`control::stacks`) is this step at 1 ms.
//!
//! What it is not: the PWM, the ceilings' choice, the board's channels (the firmware's).

use super::{equilibrium_ratio, guarded_tick, shaped_voltage, Relaxation, StackLaw, StackState};
use crate::error::Error;
use crate::real::Real;

/// How a channel reaches its target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// A slewed step to the target voltage; the film creeps to the target's thickness.
    Plain,
    /// Shaped actuation: the voltage that holds the target's thickness now, slewed.
    Shaped,
}

/// What a step needs besides the state: the guard's floor for plain drive, the slew per step,
/// the highest voltage a shaped drive may ask (supply, duty cap), V.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveLimits<R> {
    /// s_hold (`hold_ratio`): the plain drive's floor.
    pub s_hold: R,
    /// Largest voltage change per step, V.
    pub slew_step: R,
    /// Highest voltage ever asked, V.
    pub v_cap: R,
}

/// One channel: its voltage now and its film's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Channel<R> {
    pub volts: R,
    pub state: StackState<R>,
}

impl<R: Real> Channel<R> {
    /// At rest: 0 V, the film unstretched and relaxed.
    pub fn rest() -> Self {
        Channel { volts: R::zero(), state: StackState::rest() }
    }

    /// One step toward `target_v` whose equilibrium stretch is `s_target` (`equilibrium_ratio`).
    /// On an error (the state past its pull-in: not reachable under the guard) nothing changes.
    pub fn step(&mut self, law: &StackLaw<R>, relax: &Relaxation<R>, lim: &DriveLimits<R>, mode: Mode, target_v: R, s_target: R) -> Result<(), Error> {
        let floor = match mode {
            Mode::Plain => lim.s_hold,
            Mode::Shaped => s_target,
        };
        let goal = match mode {
            Mode::Shaped if target_v > R::zero() => {
                let v = shaped_voltage(law, &self.state, floor);
                if v > R::zero() {
                    v.min(lim.v_cap)
                } else {
                    R::zero()
                }
            }
            _ => target_v,
        };
        let v = self.volts;
        let v = slew_toward(v, goal, lim.slew_step);
        let mut next = self.state;
        self.volts = guarded_tick(law, relax, &mut next, v, floor)?;
        self.state = next;
        Ok(())
    }
}

/// One tick's slew: from `v` toward `goal` by at most `step` (>= 0), never past the goal.
#[inline(always)]
pub fn slew_toward<R: Real>(v: R, goal: R, step: R) -> R {
    if goal > v {
        (v + step).min(goal)
    } else {
        (v - step).max(goal)
    }
}

/// The settling time of a channel from rest to within `tol` (relative) of the thickness of
/// `target_v` held forever, s, running [`Channel::step`] at the relaxation's step; None when it
/// has not settled after `max_steps` steps. 0 s for 0 V.
pub fn settling_time<R: Real>(
    law: &StackLaw<R>,
    relax: &Relaxation<R>,
    lim: &DriveLimits<R>,
    mode: Mode,
    target_v: R,
    tol: R,
    max_steps: u32,
) -> Result<Option<R>, Error> {
    if !(target_v > R::zero()) {
        return Ok(Some(R::zero()));
    }
    let s_target = equilibrium_ratio(law, target_v)?;
    let mut ch = Channel::rest();
    for k in 1..=max_steps {
        ch.step(law, relax, lim, mode, target_v, s_target)?;
        // the film thins toward s_target from above, never past it under the guard
        if (ch.state.s - s_target).abs() <= tol * s_target {
            return Ok(Some(relax.dt() * R::from_u32(k)));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{hold_ceiling, hold_ratio, VHB_4905};

    fn setup() -> (StackLaw<f64>, Relaxation<f64>, DriveLimits<f64>, f64) {
        let law = StackLaw::new(&VHB_4905, 0.5, 0.9).unwrap();
        let relax = Relaxation::new(&law, 0.01).unwrap();
        let lim = DriveLimits { s_hold: hold_ratio(&law).unwrap(), slew_step: 2000.0 * 0.01, v_cap: 10_000.0 };
        (law, relax, lim, hold_ceiling(&law, 0.9))
    }

    #[test]
    fn shaped_never_thins_past_its_target_and_settles_first() {
        let (law, relax, lim, hold) = setup();
        for frac in [0.3, 0.7, 1.0] {
            let v = frac * hold;
            let s_t = equilibrium_ratio(&law, v).unwrap();
            let mut ch = Channel::rest();
            let mut above = false;
            for _ in 0..20_000 {
                ch.step(&law, &relax, &lim, Mode::Shaped, v, s_t).unwrap();
                assert!(ch.state.s >= s_t * (1.0 - 1e-12), "{v} V: {} < {s_t}", ch.state.s);
                above |= ch.volts > v * 1.01;
            }
            assert!(above, "{v} V: the shaped drive never went above the target");
            let plain = settling_time(&law, &relax, &lim, Mode::Plain, v, 0.01, 100_000).unwrap().unwrap();
            let shaped = settling_time(&law, &relax, &lim, Mode::Shaped, v, 0.01, 100_000).unwrap().unwrap();
            // at a low voltage the film barely creeps: both settle with the slew
            assert!(shaped <= plain && (frac < 0.5 || shaped < 0.5 * plain), "{v} V: shaped {shaped} s, plain {plain} s");
        }
        assert_eq!(settling_time(&law, &relax, &lim, Mode::Plain, 0.0, 0.01, 10).unwrap(), Some(0.0));
    }

    #[test]
    fn plain_never_thins_past_s_hold_whatever_the_target() {
        let (law, relax, lim, hold) = setup();
        // a target past the hold ceiling (the firmware refuses it first): the guard still holds
        let mut ch = Channel::rest();
        for _ in 0..60_000 {
            ch.step(&law, &relax, &lim, Mode::Plain, 2.0 * hold, lim.s_hold).unwrap();
            assert!(ch.state.s >= lim.s_hold * (1.0 - 1e-12));
        }
    }
}
