//! The film's law in time (model/src/material.rs) against its f64 reference, and the guard of
//! the control tick under random voltage histories (docs/materials.md).

use finger_model::material::{equilibrium_ratio, hold_ratio, reference::advance_reference, Relaxation, StackLaw, StackState, LIMIT_RATIO, VHB_4905};
use finger_model_testkit::material::{guarded_history, Rng};

/// Run the f32 per-tick law (1 ms ticks, exponential relaxation) and the f64 reference on the
/// voltage history `volts(t)`; at every whole second the f32 thinning 1 - s is within 1 % of the
/// reference's. Returns the reference's thinnest s.
fn creep_within_one_percent(volts: impl Fn(f64) -> f64, seconds: u32) -> f64 {
    let law = StackLaw::<f32>::new(&VHB_4905, 0.5, 0.9).unwrap();
    let law64 = StackLaw::<f64>::new(&VHB_4905, 0.5, 0.9).unwrap();
    let dt = 0.001;
    let relax = Relaxation::new(&law, dt as f32).unwrap();
    let (mut st, mut st64) = (StackState::<f32>::rest(), StackState::<f64>::rest());
    let mut worst = 0f64;
    let mut thinnest = 1f64;
    for k in 0..=seconds * 1000 {
        let v = volts(k as f64 * dt);
        st.advance(&law, &relax, v as f32).unwrap();
        advance_reference(&law64, &mut st64, v, dt, 2).unwrap();
        thinnest = thinnest.min(st64.s);
        if k % 1000 == 0 && k > 0 {
            let (thin, thin64) = (1.0 - st.s as f64, 1.0 - st64.s);
            let rel = (thin - thin64).abs() / thin64;
            worst = worst.max(rel);
            assert!(rel < 0.01, "t={} s: f32 thinning {thin} vs reference {thin64}", k / 1000);
        }
    }
    assert!(worst > 0.0);
    thinnest
}

#[test]
fn creep_of_a_5kv_step_held_120s_follows_the_reference() {
    let thinnest = creep_within_one_percent(|_| 5000.0, 120);
    // it creeps: the film thins well past its instantaneous response, toward equilibrium
    let law64 = StackLaw::<f64>::new(&VHB_4905, 0.5, 0.9).unwrap();
    let s_eq = equilibrium_ratio(&law64, 5000.0).unwrap();
    let s_now = finger_model::material::ratio_at_voltage(&law64, &[1.0; 3], 5000.0, 1.0).unwrap();
    assert!(thinnest < s_now - 0.05 && thinnest > s_eq, "{s_now} -> {thinnest}, equilibrium {s_eq}");
}

#[test]
fn creep_of_a_ramp_to_6kv_held_follows_the_reference() {
    let thinnest = creep_within_one_percent(|t| 6000.0 * (t / 5.0).min(1.0), 120);
    assert!(thinnest > LIMIT_RATIO);
}

/// At least 10,000 random voltage histories (plain and shaped, every card, z0 and margin, 1, 10
/// and 100 ms ticks) through the guard: the predicted film never below s_hold nor the field
/// past the breakdown bound; every tenth history also against the f64 reference (never past
/// the 33 % limit nor the breakdown field).
#[test]
fn no_voltage_history_passes_the_hold_floor_or_the_breakdown_bound() {
    let mut rng = Rng(0x5DEE_CE66_D1CE_4E5B);
    let (mut guarded, mut ticks, mut near) = (0u64, 0u64, 0u64);
    for i in 0..10_000 {
        let o = guarded_history(&mut rng, i % 10 == 0).unwrap_or_else(|e| panic!("history {i}: {e}"));
        guarded += o.guarded;
        ticks += o.ticks;
        if o.min_s_over_hold < 1.0 + 1e-3 {
            near += 1;
        }
    }
    // the histories reach the floor and the guard acts: the test exercises the bound
    assert!(guarded > 0 && near > 100, "guarded {guarded} of {ticks} ticks, {near} histories near the floor");
}

#[test]
fn the_hold_floor_of_vhb_lies_above_the_limit() {
    let law = StackLaw::<f32>::new(&VHB_4905, 0.5, 0.9).unwrap();
    assert!(hold_ratio(&law).unwrap() > LIMIT_RATIO as f32);
}

/// A floor the guard cannot hold the film above (0, below 0, infinite, NaN) gets a bound of 0 V,
/// whatever the film's branches; a floor in (0, 1] gets a positive bound (the mutants of
/// `voltage_bound_now`'s input test survived without this).
#[test]
fn the_guard_bound_is_zero_for_a_floor_it_cannot_hold() {
    use finger_model::material::voltage_bound_now;
    let law = StackLaw::<f64>::new(&VHB_4905, 0.5, 0.9).unwrap();
    let relax = Relaxation::new(&law, 0.001).unwrap();
    let mut held = StackState::<f64>::rest();
    for _ in 0..30_000 {
        held.advance(&law, &relax, 4000.0).unwrap();
    }
    for state in [StackState::<f64>::rest(), held] {
        for floor in [0.0, -0.0, -0.5, -1.0, -f64::MIN_POSITIVE, f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
            let v = voltage_bound_now(&law, &state, floor);
            assert_eq!(v, 0.0, "floor {floor}, s {}: bound {v} V", state.s);
        }
        for floor in [LIMIT_RATIO, 0.8, 0.9] {
            let v = voltage_bound_now(&law, &state, floor);
            assert!(v > 0.0 && v.is_finite(), "floor {floor}, s {}: bound {v} V", state.s);
        }
    }
}
