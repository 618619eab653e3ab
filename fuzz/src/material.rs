//! The material target: arbitrary voltage histories into one stack's time integration on the
//! board's f32 path (`finger_model::material`: the guarded control tick, plain slewed setpoints
//! or shaped actuation).
//!
//! Input: a card, z0 (0.1..1 mm), margin (0.5..0.95), tick (1, 10 or 100 ms), then segments:
//! a requested voltage (a fraction of the hold ceiling up to 2x, or 0, 20 kV, a negative, NaN,
//! infinity, raw bits), a slew, shaped or not, and a number of ticks (at most [`MAX_TICKS`]).
//!
//! Invariants, every tick: a typed error or the voltage applied, finite, in [0, requested];
//! the film never thinner than the hold ratio (the 33 % limit with its margin) and its field
//! within margin x the breakdown field.
//!
//! What it is not: the seeded soak of model/tests/material_time.rs (random draws from the
//! documented ranges, with the f64 reference); this searches the inputs for a violation.

use finger_model::material::{equilibrium_ratio, guarded_tick, hold_ceiling, hold_ratio, shaped_voltage, Relaxation, StackLaw, StackState, CARDS};

pub const MAX_TICKS: usize = 5_000;

/// Runs one input; panics when an invariant breaks.
pub fn check(data: &[u8]) {
    let mut b = data.iter().copied();
    let mut u8_ = move || b.next();
    let (Some(c), Some(z), Some(m), Some(d)) = (u8_(), u8_(), u8_(), u8_()) else { return };
    let card = CARDS[c as usize % CARDS.len()];
    let z0 = 0.1 + 0.9 * z as f32 / 255.0;
    let margin = 0.5 + 0.45 * m as f32 / 255.0;
    let dt = [0.001f32, 0.01, 0.1][d as usize % 3];
    let Ok(law) = StackLaw::<f32>::new(card, z0, margin) else { return };
    let Ok(relax) = Relaxation::new(&law, dt) else { return };
    let hold = hold_ceiling(&law, law.margin);
    let Ok(s_hold) = hold_ratio(&law) else { return };
    let supply = 10_000f32;
    let mut st = StackState::<f32>::rest();
    let mut v_set = 0f32;
    let mut ticks = 0usize;
    while let (Some(kind), Some(level), Some(slew_b), Some(n)) = (u8_(), u8_(), u8_(), u8_()) {
        let command = match level {
            0..=239 => hold * level as f32 / 120.0,
            240 => 0.0,
            241 => 20_000.0,
            242 => -1.0,
            243 => f32::NAN,
            244 => f32::INFINITY,
            245 => hold,
            246 => hold * (1.0 + 1e-6),
            _ => f32::from_le_bytes([u8_().unwrap_or(0), u8_().unwrap_or(0), u8_().unwrap_or(0), u8_().unwrap_or(0)]),
        };
        let shaped = kind & 1 != 0;
        // the command side caps a setpoint at the hold ceiling (a NaN request stays NaN: the tick's guard sees it)
        let target = if command > hold { hold } else { command };
        let slew = 10f32.powf(5.0 * slew_b as f32 / 255.0) * dt; // 1..1e5 V/s
        let s_target = if shaped {
            match equilibrium_ratio(&law, target) {
                Ok(s) => Some(s),
                Err(_) => continue, // a typed refusal of the target
            }
        } else {
            None
        };
        for _ in 0..n as usize + 1 {
            if ticks >= MAX_TICKS {
                return;
            }
            ticks += 1;
            let (requested, floor) = match s_target {
                Some(s) => (shaped_voltage(&law, &st, s).min(supply), s),
                None => {
                    if target.is_finite() {
                        v_set += (target - v_set).max(-slew).min(slew);
                    } else {
                        v_set = target;
                    }
                    (v_set, s_hold)
                }
            };
            let v = match guarded_tick(&law, &relax, &mut st, requested, floor) {
                Ok(v) => v,
                Err(_) => return, // typed refusal: the stack is left as it was
            };
            assert!(v.is_finite() && v >= 0.0, "{}: applied {v} V for {requested} V", card.name);
            assert!(!(requested >= 0.0) || v <= requested, "{}: applied {v} V past the request {requested} V", card.name);
            assert!(st.s >= s_hold, "{}: s {} below the hold ratio {s_hold} at {v} V (z0 {z0}, margin {margin}, dt {dt}, tick {ticks})", card.name, st.s);
            assert!(
                v / (st.s * law.z0) <= law.margin * law.breakdown_field(st.s),
                "{}: field {} V/mm past margin x breakdown at s {}",
                card.name,
                v / (st.s * law.z0),
                st.s
            );
        }
    }
}
