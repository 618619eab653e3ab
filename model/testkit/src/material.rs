//! Random voltage histories for the film's guard (model/tests/material_time.rs and the soak):
//! one history is a board (card, z0, margin, tick) and a few commanded segments (plain or shaped,
//! each with a slew), run through the control tick's step in f32 (`material::drive`) and
//! checked every tick: the predicted film never below s_hold, the field never past margin x the
//! breakdown field; optionally the f64 reference of the same applied voltages never past the
//! 33 % limit nor the breakdown field.

use finger_model::material::drive::{Channel, DriveLimits, Mode};
use finger_model::material::{equilibrium_ratio, hold_ceiling, hold_ratio, reference::advance_reference, Relaxation, StackLaw, StackState, CARDS, LIMIT_RATIO};

/// xorshift64*: a uniform number in [0, 1).
pub struct Rng(pub u64);
impl Rng {
    #[allow(clippy::should_implement_trait)] // a generator, never exhausted: not an iterator
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// What one history did.
#[derive(Clone, Copy, Debug, Default)]
pub struct Outcome {
    pub ticks: u64,
    /// Ticks where the guard lowered the requested voltage.
    pub guarded: u64,
    /// The thinnest predicted film over s_hold (>= 1 by the invariant).
    pub min_s_over_hold: f64,
    /// Largest |s_f32 - s_ref| (0 without the reference).
    pub max_ref_error: f64,
}

/// Run one random history drawn from `rng`; `reference`: also integrate the f64 reference.
/// `Err` names the first violation.
pub fn guarded_history(rng: &mut Rng, reference: bool) -> Result<Outcome, String> {
    let card = CARDS[(rng.next() * CARDS.len() as f64) as usize % CARDS.len()];
    let z0 = 0.1 + 0.9 * rng.next();
    let margin = 0.5 + 0.45 * rng.next();
    let dt = [0.001, 0.01, 0.1][(rng.next() * 3.0) as usize % 3];
    let law = StackLaw::<f32>::new(card, z0 as f32, margin as f32).map_err(|e| format!("{e}"))?;
    let law64 = StackLaw::<f64>::new(card, z0, margin).map_err(|e| format!("{e}"))?;
    let relax = Relaxation::new(&law, dt as f32).map_err(|e| format!("{e}"))?;
    let hold = hold_ceiling(&law, law.margin);
    let s_hold = hold_ratio(&law).map_err(|e| format!("{e}"))?;
    let supply = 10_000f32;
    let mut ch = Channel::<f32>::rest();
    let mut st64 = StackState::<f64>::rest();
    let mut out = Outcome { min_s_over_hold: f64::INFINITY, ..Outcome::default() };
    for _ in 0..1 + (rng.next() * 6.0) as usize {
        let ticks = 1 + (rng.next() * 300.0) as usize;
        let r = rng.next();
        let command = if r < 0.1 {
            0.0
        } else if r < 0.2 {
            20_000.0
        } else {
            (1.5 * rng.next()) as f32 * hold
        };
        let target = command.min(hold);
        let mode = if rng.next() < 0.4 { Mode::Shaped } else { Mode::Plain };
        // 1..1e5 V/s, or no slew limit
        let slew_step = if rng.next() < 0.2 { f32::INFINITY } else { (10f64.powf(5.0 * rng.next()) * dt) as f32 };
        let lim = DriveLimits { s_hold, slew_step, v_cap: supply };
        let s_target = equilibrium_ratio(&law, target).map_err(|e| format!("target {target}: {e}"))?;
        for _ in 0..ticks {
            let before = ch.volts;
            ch.step(&law, &relax, &lim, mode, target, s_target).map_err(|e| format!("step toward {target} V: {e}"))?;
            let (v, st) = (ch.volts, ch.state);
            out.ticks += 1;
            // plain: the guard acted when the voltage stands below the slewed setpoint
            let slewed = if target > before { (before + slew_step).min(target) } else { (before - slew_step).max(target) };
            if mode == Mode::Plain && v < slewed {
                out.guarded += 1;
            }
            if !(st.s >= s_hold) {
                return Err(format!("{}: s {} below s_hold {s_hold} at {v} V (z0 {z0}, margin {margin}, dt {dt})", card.name, st.s));
            }
            if !(v / (st.s * law.z0) <= law.margin * law.breakdown_field(st.s)) {
                return Err(format!("{}: field {} V/mm past the bound at s {}", card.name, v / (st.s * law.z0), st.s));
            }
            out.min_s_over_hold = out.min_s_over_hold.min((st.s / s_hold) as f64);
            if reference {
                let v64 = v as f64;
                advance_reference(&law64, &mut st64, v64, dt, 1).map_err(|e| format!("reference: {e}"))?;
                if !(st64.s > LIMIT_RATIO) || !(v64 / (st64.s * z0) < law64.breakdown_field(st64.s)) {
                    return Err(format!("{}: reference film at s {} under {v64} V", card.name, st64.s));
                }
                out.max_ref_error = out.max_ref_error.max((st64.s - st.s as f64).abs());
            }
        }
    }
    Ok(out)
}
