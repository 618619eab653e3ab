//! The board's stacks in time: each channel's film state (`finger_model::material`'s
//! `StackState`) stepped every control tick, and the guard that keeps it above its floor.
//!
//! What it is: the board's law (the card and geometry of `crate::board`, built once), its
//! stepper for one 1 ms tick, the board's hold ceiling and `s_hold` (the thinnest a held
//! voltage ever gets), and per channel the step (the model's drive step,
//! `material::drive::Channel::step`): slew toward the goal, guard the voltage by
//! `voltage_bound_now(state, s_floor)`, solve the thickness at the guarded voltage from the
//! last one, relax the branches. Invariant: the thickness after every step is at or
//! above the floor given (never below `s_hold`: the floor is `s_hold` or a target's
//! equilibrium ratio, itself above `s_hold`), and the field at or below the breakdown bound.
//!
//! What it is not: the slew, the duties, the ceilings of the command side (`super::Control`).
//!
//! On the Cortex-M3 image (`cfg(m3)`) the integration does not fit its 64 KiB of flash
//! (docs/firmware.md): there the stacks keep the card's hold ceiling and `s_hold` only, a step
//! is a plain slew to the voltage asked ([`plain_slew_step`], compiled on every target so the
//! host tests reach it; the targets are already within the hold ceiling), shaped actuation is
//! plain, and the thickness now is not known (NaN).

#[cfg(not(m3))]
use finger_model::material::drive::{Channel, DriveLimits, Mode};
use finger_model::material::equilibrium_ratio;
#[cfg(not(m3))]
use finger_model::material::Relaxation;
#[cfg(not(m3))]
use finger_model::material::StackLaw;

#[cfg(not(m3))]
use crate::board::HV_MAX_V;
use crate::board::{board_hold_ceiling_of, board_law, HV_CHANNELS};

/// Control tick, s.
pub const TICK_S: f32 = 1e-3;

/// The board's stacks: one law, one stepper, each channel's state.
pub struct Stacks {
    #[cfg(not(m3))]
    law: StackLaw<f32>,
    #[cfg(not(m3))]
    relax: Relaxation<f32>,
    hold_v: f32,
    s_hold: f32,
    /// Each channel's voltage and film state, as the model's drive steps them.
    #[cfg(not(m3))]
    chan: [Channel<f32>; HV_CHANNELS],
}

/// A step the model refused (the state past its pull-in at that voltage): the caller stops.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepRefused;

impl Stacks {
    /// The board's stacks at rest. None when the board constants give no valid law or
    /// ceiling (the core then never arms).
    pub fn board() -> Option<Self> {
        let law = board_law().ok()?;
        let hold_v = board_hold_ceiling_of(&law);
        let s_hold = equilibrium_ratio(&law, hold_v).ok()?;
        if !(hold_v > 0.0 && s_hold > 0.0 && s_hold < 1.0) {
            return None;
        }
        #[cfg(not(m3))]
        let stacks = Stacks { law, relax: Relaxation::new(&law, TICK_S).ok()?, hold_v, s_hold, chan: [Channel::rest(); HV_CHANNELS] };
        #[cfg(m3)]
        let stacks = Stacks { hold_v, s_hold };
        Some(stacks)
    }

    /// The film's branches relax `k` times faster than the card's (tests only, feature
    /// `hv-door`: a plant film as fast, so that ten minutes of creep take one of board time).
    /// False (nothing changes) for a `k` the relaxation refuses.
    #[cfg(all(feature = "hv-door", not(m3)))]
    pub fn set_time_scale(&mut self, k: f32) -> bool {
        match Relaxation::new(&self.law, TICK_S * k) {
            Ok(r) if k >= 1.0 => {
                self.relax = r;
                true
            }
            _ => false,
        }
    }

    /// The board's hold ceiling, V.
    pub fn hold_ceiling_v(&self) -> f32 {
        self.hold_v
    }
    /// The thinnest a held voltage ever gets (the equilibrium at the hold ceiling).
    pub fn s_hold(&self) -> f32 {
        self.s_hold
    }
    /// Each channel's thickness stretch now (NaN on the M3 image: not integrated there).
    #[cfg(m3)]
    pub fn ratios(&self) -> [f32; HV_CHANNELS] {
        [f32::NAN; HV_CHANNELS]
    }
    /// Each channel's thickness stretch now.
    #[cfg(not(m3))]
    pub fn ratios(&self) -> [f32; HV_CHANNELS] {
        let mut r = [1.0; HV_CHANNELS];
        for (ch, s) in r.iter_mut().enumerate() {
            *s = self.chan[ch].state.s;
        }
        r
    }

    /// The floor for a target of `volts`: `s_hold` (plain), or the target's equilibrium
    /// ratio (shaped; never below `s_hold`). None past the law's reach.
    #[cfg_attr(m3, allow(unused_variables))]
    pub fn floor(&self, volts: f32, shaped: bool) -> Option<f32> {
        if !shaped || cfg!(m3) {
            return Some(self.s_hold);
        }
        #[cfg(not(m3))]
        {
            let s = equilibrium_ratio(&self.law, volts).ok()?;
            if s >= self.s_hold {
                return Some(s);
            }
        }
        None
    }

    /// One tick of channel `ch` from `volts_now` toward `target_v` whose floor is `s_floor`
    /// (`s_hold` plain, the target's equilibrium ratio shaped): the model's drive step
    /// (`material::drive::Channel::step`: the goal, the target or shaped the voltage that holds
    /// the film at `s_floor` now capped by the supply; the slew by `slew_step`; `guarded_tick`).
    /// `v_cap`: the most a shaped drive may ask (the supply, or a ceiling the read-back
    /// lowered). The voltage applied, V. Refused (the state past its pull-in, not reachable
    /// under the guard): nothing changes, the caller stops.
    #[cfg(not(m3))]
    #[allow(clippy::too_many_arguments)]
    pub fn step(&mut self, ch: usize, volts_now: f32, target_v: f32, s_floor: f32, shaped: bool, slew_step: f32, v_cap: f32) -> Result<f32, StepRefused> {
        let lim = DriveLimits { s_hold: self.s_hold, slew_step, v_cap: v_cap.min(HV_MAX_V) };
        let mode = if shaped { Mode::Shaped } else { Mode::Plain };
        let c = &mut self.chan[ch];
        c.volts = volts_now;
        match c.step(&self.law, &self.relax, &lim, mode, target_v, s_floor) {
            Ok(()) => Ok(c.volts),
            Err(_) => {
                c.volts = 0.0;
                Err(StepRefused)
            }
        }
    }

    /// Channel `ch`'s film: its incremental capacitance over its capacitance now (the hold
    /// ripple's and a slew's charge measure dQ/dV, the thickness wants Q/V), or 1 where the
    /// model has none (a film past its reach: the read-back then reads thinner, never thicker).
    #[cfg(not(m3))]
    pub fn incremental_capacitance_ratio(&self, ch: usize) -> f32 {
        let st = &self.chan[ch].state;
        finger_model::material::incremental_capacitance_ratio(&self.law, &st.a, st.s).unwrap_or(1.0)
    }

    /// The card's equilibrium voltage of stretch `s`, V (infinite past the film's reach).
    #[cfg(not(m3))]
    pub fn equilibrium_voltage_at(&self, s: f32) -> f32 {
        finger_model::material::equilibrium_voltage(&self.law, s).unwrap_or(f32::INFINITY)
    }

    /// The M3 image's step: the slew toward the target (already within the hold ceiling),
    /// nothing integrated ([`plain_slew_step`]).
    #[cfg(m3)]
    #[allow(clippy::too_many_arguments)]
    pub fn step(&mut self, _ch: usize, volts_now: f32, target_v: f32, _s_floor: f32, _shaped: bool, slew_step: f32, _v_cap: f32) -> Result<f32, StepRefused> {
        Ok(plain_slew_step(volts_now, target_v, slew_step))
    }
}

/// The M3 image's step arithmetic (its `Stacks::step`), compiled on every target so the host
/// tests reach it: the model's slew (`material::drive::slew_toward`) clamped at 0 V; the voltage after one tick from `volts_now` toward `target_v`, by at most
/// `slew_step` (>= 0), never past the target, never below +0 V. Never NaN: a NaN that reaches
/// the end answers 0 V.
pub fn plain_slew_step(volts_now: f32, target_v: f32, slew_step: f32) -> f32 {
    let v = finger_model::material::drive::slew_toward(volts_now, target_v, slew_step);
    if v > 0.0 {
        v
    } else {
        0.0
    }
}
