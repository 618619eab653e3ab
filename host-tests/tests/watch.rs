//! The tick's fault checks (`finger_fw::control::watch::Watch::check`) on synthetic readings:
//! a module's voltage written tick by tick (a first-order fall, a stuck monitor, a rail), the
//! fault read back. The plant runs (hv_measured, hv_in_time) show the checks against a board;
//! these pin each check's own bound (docs/reliability.md "The read-back's files").
use finger_fw::board::{ADC_FULL_CODE, BOARD_STACK_C0_PF, SENSE_STRAY_PF, VMON_FULL_SCALE_V};
use finger_fw::control::hv_loop::Ask;
use finger_fw::control::sense::Estimator;
use finger_fw::control::watch::{
    Reading, ThicknessGuard, Watch, COLLAPSE_FRAC, DISAGREE_FAST_S, DISAGREE_S, DISAGREE_WINDOWS, FLOOR_MARGIN_S, GUARD_HELD_MS, HV_SETTLE_MS, LEAK_BOUND_UA,
    LEAK_BOUND_UA_PER_V, LEAK_CHECK_MIN_V, LEAK_FLOOR_UA, MISMATCH_FRAC, MISMATCH_V, MODULE_FALL_MS, NEAR_GAP_S, OPEN_FRAC, OVER_FRAC, OVER_MS, OVER_V,
    STUCK_MOVE_V, STUCK_MS,
};
use finger_fw::control::Fault;
use host_tests::synthetic::Stack;

/// A reading at `v` volts (its monitor code at the nominal calibration) and `i_ua`.
fn reading(v: f32, i_ua: f32) -> Reading {
    Reading { v, i_ua, v_code: v * (ADC_FULL_CODE / VMON_FULL_SCALE_V) }
}

/// A tick of the checks with the loop asking the drive (not held by the slew), enabled.
fn check(w: &mut Watch, r: &Reading, drive_v: f32, ceiling_v: f32) -> Option<Fault> {
    w.check(r, drive_v, &Ask { volts: drive_v, slew_held: false }, ceiling_v, true, &Estimator::new())
}

/// The first fault of `ticks` readings `v(k)` of a module driven to `drive(k)` (ceiling 5.4 kV),
/// enabled or not, with the tick it came at; the monitor's last bit moves every other tick (a
/// reading that never moves is a stuck sensor).
fn first_fault(ticks: u32, enabled: bool, drive: impl Fn(u32) -> f32, v: impl Fn(u32) -> f32) -> Option<(u32, Fault)> {
    first_fault_with(&Estimator::new(), ticks, enabled, drive, v)
}

/// As [`first_fault`], with `est`'s figures (capacitance, leakage) read by the checks.
fn first_fault_with(est: &Estimator, ticks: u32, enabled: bool, drive: impl Fn(u32) -> f32, v: impl Fn(u32) -> f32) -> Option<(u32, Fault)> {
    first_fault_asking(est, ticks, enabled, &drive, |k| Ask { volts: drive(k), slew_held: false }, v)
}

/// As [`first_fault_with`], the loop asking `ask(k)` of the module (a slew may hold the ask
/// apart from the drive).
fn first_fault_asking(
    est: &Estimator,
    ticks: u32,
    enabled: bool,
    drive: impl Fn(u32) -> f32,
    ask: impl Fn(u32) -> Ask,
    v: impl Fn(u32) -> f32,
) -> Option<(u32, Fault)> {
    let mut w = Watch::new();
    (0..ticks).find_map(|k| {
        let dither_v = (k % 2) as f32 * 0.5;
        w.check(&reading(v(k) + dither_v, 0.1), drive(k), &ask(k), 5_400.0, enabled, est).map(|f| (k, f))
    })
}

/// A reading that is not a number, a monitor code under 0 or at its rail is a sensor fault,
/// each alone (the voltage NaN, the current NaN, the code -1, the code 4095); a healthy reading
/// beside them is none.
#[test]
fn each_reading_out_of_its_range_alone_is_a_sensor_fault() {
    let healthy = reading(1_000.0, 0.1);
    let bad = [
        Reading { v: f32::NAN, ..healthy },
        Reading { i_ua: f32::NAN, ..healthy },
        Reading { v_code: -1.0, ..healthy },
        Reading { v_code: ADC_FULL_CODE, ..healthy },
        Reading { v_code: f32::NAN, ..healthy },
    ];
    for r in bad {
        assert_eq!(check(&mut Watch::new(), &r, 1_000.0, 5_000.0), Some(Fault::Sensor), "{r:?}");
    }
    assert_eq!(check(&mut Watch::new(), &healthy, 1_000.0, 5_000.0), None);
    assert_eq!(check(&mut Watch::new(), &Reading { v_code: ADC_FULL_CODE - 1.0, ..healthy }, 1_000.0, 5_000.0), None);
}

/// Held at 5 kV, then the command and the ceiling cut to 1 kV at once (a guard's cut): a module
/// that falls at its datasheet's 15 ms (the plant's) stays under the over-ceiling bound, which
/// decays from the last command at `MODULE_FALL_MS`; one three times slower than the bound is a
/// module past its ceiling, latched within `OVER_MS` of leaving the bound (well before the
/// mismatch's 300 ms).
#[test]
fn a_module_falls_under_the_decaying_bound_and_a_slow_one_trips_it() {
    let fall = |tau_ms: f32| -> Option<(u32, Fault)> {
        let mut w = Watch::new();
        for _ in 0..500 {
            assert_eq!(check(&mut w, &reading(5_000.0, 0.1), 5_000.0, 5_000.0), None);
        }
        let mut v = 5_000.0f32;
        for k in 1..=1_000u32 {
            v += (1_000.0 - v) / tau_ms;
            if let Some(f) = check(&mut w, &reading(v, 0.1), 1_000.0, 1_000.0) {
                return Some((k, f));
            }
        }
        None
    };
    assert_eq!(fall(15.0), None);
    assert_eq!(fall(MODULE_FALL_MS), None, "a module at the bound's own rate");
    let (k, f) = fall(3.0 * MODULE_FALL_MS).expect("a slow module trips");
    assert_eq!(f, Fault::HvMismatch);
    assert!(k <= 2 * OVER_MS, "latched after {k} ms");
    // the bound's margin: 2 % and 60 V over the ceiling held is no fault, past it is
    let over = |v: f32| {
        let mut w = Watch::new();
        (0..OVER_MS + 5).find_map(|_| check(&mut w, &reading(v, 0.1), 3_000.0, 3_000.0))
    };
    assert_eq!(over(3_000.0 * (1.0 + OVER_FRAC) + OVER_V - 1.0), None);
    assert_eq!(over(3_000.0 * (1.0 + OVER_FRAC) + OVER_V + 1.0), Some(Fault::HvMismatch));
}

/// A short that pulls the output under half a steady drive (the current under the trip: a soft
/// short) is a breakdown within 3 ticks, held at 3 kV or on a ramp at 2 kV/s (a drive moving
/// under 1 V + 1 % a tick is steady); under half while the drive steps up (the module catching
/// up) it is none.
#[test]
fn a_collapse_under_a_steady_drive_is_a_breakdown() {
    let collapsed = 0.9 * COLLAPSE_FRAC * 3_000.0;
    let held = first_fault(600, true, |_| 3_000.0, |k| if k < 500 { 3_000.0 } else { collapsed });
    assert_eq!(held, Some((502, Fault::Breakdown)));
    let ramp = |k: u32| 1_000.0 + 2.0 * k as f32;
    let on_ramp = first_fault(1_100, true, ramp, |k| if k < 1_000 { ramp(k) } else { 0.9 * COLLAPSE_FRAC * ramp(k) });
    assert_eq!(on_ramp, Some((1_002, Fault::Breakdown)));
    // a step from 1.2 kV to 3 kV: the module under half the new drive for its first ticks
    let step = |k: u32| if k < 500 { 1_200.0 } else { 3_000.0 };
    let follow = |k: u32| if k < 500 { 1_200.0 } else { 3_000.0 - 1_800.0 * (-((k - 500) as f32) / 15.0).exp() };
    assert_eq!(first_fault(1_000, true, step, follow), None);
}

/// A module off its command by more than the larger of 300 V and 10 % for `HV_SETTLE_MS` is one
/// that does not follow: at 5 kV, 8 % under (a module 8 % weak) is none, 12 % under latches
/// after the settling time; at 1 kV, 280 V under is none, 320 V under latches.
#[test]
fn a_module_off_its_command_past_the_larger_bound_latches_after_the_settling() {
    for (drive, off, latches) in [(5_000.0, 0.08 * 5_000.0, false), (5_000.0, 0.12 * 5_000.0, true), (1_000.0, 280.0, false), (1_000.0, 320.0, true)] {
        assert!(MISMATCH_V.max(MISMATCH_FRAC * drive) != off);
        let got = first_fault(1_000, true, |_| drive, |_| drive - off);
        let want = latches.then_some((HV_SETTLE_MS, Fault::HvMismatch));
        assert_eq!(got, want, "{off} V under {drive} V");
    }
}

/// While the slew holds the loop's ask back, a module behind its ask by up to the larger of
/// `MISMATCH_V` and `FOLLOW_FRAC` of the ask plus the ask's rate times `MODULE_FALL_MS` follows
/// it: the command stepped from 1 kV to 5 kV, the ask slewing at 2 V/ms (100 V of allowance),
/// a module running 170 ms behind it (340 V, a dead time) is no fault; one 195 ms behind (390 V)
/// is one that does not follow, latched after the settling time once past the allowance.
#[test]
fn a_module_behind_its_slewing_ask_by_the_slews_allowance_follows_it() {
    let (from_v, to_v, v_per_ms) = (1_000.0f32, 5_000.0f32, 2.0f32);
    assert!(MISMATCH_V.max(MISMATCH_FRAC * to_v) < to_v - from_v);
    // held 500 ms at 1 kV, then the step: tick k is k - 500 ms after it
    let step_ms = 500u32;
    let ramp = |k: u32| (from_v + v_per_ms * k.saturating_sub(step_ms) as f32).min(to_v);
    let drive = |k: u32| if k < step_ms { from_v } else { to_v };
    let behind = |dead_ms: u32| {
        let ask = |k: u32| Ask { volts: ramp(k), slew_held: ramp(k) < drive(k) };
        first_fault_asking(&Estimator::new(), step_ms + 3_000, true, drive, ask, |k| ramp(k.saturating_sub(dead_ms)))
    };
    assert_eq!(behind(170), None);
    let (k, f) = behind(195).expect("a module past the allowance");
    let past_from = (MISMATCH_V + v_per_ms * MODULE_FALL_MS) / v_per_ms;
    assert_eq!((f, k - step_ms), (Fault::HvMismatch, past_from as u32 + 1 + HV_SETTLE_MS));
}

/// With the HV enable low, an output that stays above twice `MISMATCH_V` (a module that does
/// not switch off) latches after the settling time; one that reads 500 V is none.
#[test]
fn an_output_left_on_with_the_enable_low_latches() {
    assert_eq!(first_fault(1_000, false, |_| 0.0, |_| 500.0), None);
    assert_eq!(first_fault(1_000, false, |_| 0.0, |_| 700.0), Some((HV_SETTLE_MS, Fault::HvMismatch)));
}

/// A monitor code that does not move for `STUCK_MS` ticks while the command moves more than
/// `STUCK_MOVE_V` (100 V) is a stuck sensor: the command ramping 1 kV -> 1.3 kV at 3 V/ms under
/// a frozen reading latches once both hold (frozen from tick 1, at 1,003 V; past 1,103 V at tick
/// 35, 50 ticks frozen at tick 50); frozen under a still command, or one that moves 90 V, it
/// is none.
#[test]
fn a_reading_frozen_while_its_command_moves_past_the_stuck_bound_is_a_stuck_sensor() {
    let frozen = |ramp_v: f32| {
        let mut w = Watch::new();
        let r = reading(1_000.0, 0.1);
        (0..300u32).find_map(|k| {
            let drive = 1_000.0 + (3.0 * k as f32).min(ramp_v);
            check(&mut w, &r, drive, 5_400.0).map(|f| (k, f))
        })
    };
    assert_eq!(frozen(300.0), Some((STUCK_MS, Fault::Sensor)));
    assert_eq!(frozen(0.0), None);
    assert_eq!(frozen(0.9 * STUCK_MOVE_V), None);
}

/// The stuck rule's bound is strict: a monitor frozen at code 0 (the audit's case: `arm`, then a
/// channel commanded from 0 V to the bound itself) is no fault; 1 V past the bound latches
/// `sensor` after `STUCK_MS` ticks. (With `>=` for `>`, the first latched.)
#[test]
fn a_command_that_moves_exactly_the_stuck_bound_under_a_frozen_code_is_no_fault() {
    let frozen_at_zero = |to_v: f32| {
        let mut w = Watch::new();
        let r = Reading { v: 0.0, i_ua: 0.0, v_code: 0.0 };
        (0..300u32).find_map(|k| check(&mut w, &r, if k < 5 { 0.0 } else { to_v }, 5_400.0).map(|f| (k, f)))
    };
    assert_eq!(frozen_at_zero(STUCK_MOVE_V), None);
    assert_eq!(frozen_at_zero(STUCK_MOVE_V + 1.0), Some((STUCK_MS, Fault::Sensor)));
}

/// An estimator that has measured a stack of `c_pf` leaking `leak_ua` (ohmic) at `v`: held
/// 10 s (rippled above the ripple's voltage, still under it).
fn measured(c_pf: f32, leak_ua: f32, v: f32) -> Estimator {
    let mut est = Estimator::new();
    let mut stack = Stack::new(c_pf, leak_ua / v, 0.0);
    stack.tick(&mut est, v, 0, 1.0);
    stack.hold(&mut est, v, 0.0, 10_000);
    est
}

/// The ticks until `est`'s figures latch a fault, enabled, at a still `drive_v`.
fn with_estimate(est: &Estimator, drive_v: f32) -> Option<(u32, Fault)> {
    first_fault_with(est, 400, true, |_| drive_v, |_| drive_v)
}

/// A sensed capacitance under the stray plus 30 % of the card's stack is an open stack, at once;
/// just over it is none.
#[test]
fn a_capacitance_under_the_open_fraction_is_an_open_stack() {
    let open_at = SENSE_STRAY_PF + OPEN_FRAC * BOARD_STACK_C0_PF;
    assert_eq!(with_estimate(&measured(0.95 * open_at, 0.0, 3_000.0), 3_000.0), Some((0, Fault::StackOpen)));
    assert_eq!(with_estimate(&measured(1.05 * open_at, 0.0, 3_000.0), 3_000.0), None);
}

/// A leakage past the lower of 1 µA and 2e-4 µA/V of the drive (never under the sense's floor,
/// 0.05 µA) for 200 ticks is a leak: 20 % over the bound latches at tick 199, 20 % under is
/// none, at 3 kV (0.6 µA) and at 200 V (the floor's 0.05 µA).
#[test]
fn a_leakage_past_its_bound_for_200_ticks_is_a_leak() {
    for v in [3_000.0f32, 200.0] {
        let bound = LEAK_BOUND_UA.min(LEAK_BOUND_UA_PER_V * v).max(LEAK_FLOOR_UA);
        let c_pf = BOARD_STACK_C0_PF + SENSE_STRAY_PF;
        assert_eq!(with_estimate(&measured(c_pf, 1.2 * bound, v), v), Some((199, Fault::Leakage)), "{v} V");
        assert_eq!(with_estimate(&measured(c_pf, 0.8 * bound, v), v), None, "{v} V");
    }
}

/// The leakage check acts above `LEAK_CHECK_MIN_V` only: a 1 µA leak measured at 50 V is none
/// with the command at 50 V, and latches at tick 199 with it 1 V above. (With `>=` for `>`, the
/// first latched too.)
#[test]
fn a_leak_at_the_leakage_checks_own_voltage_is_not_checked() {
    let c_pf = BOARD_STACK_C0_PF + SENSE_STRAY_PF;
    let est = measured(c_pf, 1.0, LEAK_CHECK_MIN_V);
    assert!(est.leakage_ua().is_some_and(|l| l > 0.5), "{:?}", est.leakage_ua());
    assert_eq!(with_estimate(&est, LEAK_CHECK_MIN_V), None);
    assert_eq!(with_estimate(&est, LEAK_CHECK_MIN_V + 1.0), Some((199, Fault::Leakage)));
}

/// A drive counts as steady when it moves at most 1 V + 1 % a tick: on a 20 kV/s ramp (20 V a
/// tick) from 1 kV, steady from 1,900 V on (tick 45), a collapse under it latches 30 ticks and 3
/// collapsed ticks later. (With the bound 1 % alone, `1.0 * 0.01 * drive_v`, steady from 2 kV:
/// 5 ticks later.)
#[test]
fn a_collapse_on_a_fast_ramp_latches_once_the_ramp_counts_as_steady() {
    let ramp = |k: u32| 1_000.0 + 20.0 * k as f32;
    let got = first_fault(300, true, ramp, |k| 0.9 * COLLAPSE_FRAC * ramp(k));
    assert_eq!(got, Some((76, Fault::Breakdown)));
}

/// The ceiling at 1 and no disagreement.
fn untouched(g: &ThicknessGuard) -> bool {
    g.derate == 1.0 && !g.disagreed
}

/// The thickness guard after `windows` windows of a sensed `s_meas` against the model's 0.9,
/// the floor 0.667, the card's voltages 3,000 V (the model's thickness) and 3,300 V (the
/// sensed one), held `held_ms`, each window `joint` or not.
fn guarded(windows: u32, s_meas: f32, held_ms: u32, joint: bool) -> ThicknessGuard {
    let mut g = ThicknessGuard::new();
    for _ in 0..windows {
        g.update(s_meas, 0.9, 0.667, 3_000.0, 3_300.0, held_ms, joint);
    }
    g
}

/// Held past `GUARD_HELD_MS`, a film sensed thinner than the model's by more than `DISAGREE_S`
/// for `DISAGREE_WINDOWS` windows in a row lowers the ceiling by the card's voltage ratio to
/// the power 1.5 ((3,000 / 3,300)^1.5 = 0.867); one window fewer, or a gap under the bound, or
/// not yet held (a lone window), leaves it at 1; before the hold, a pair's gap past
/// `DISAGREE_FAST_S` counts.
#[test]
fn a_film_sensed_thinner_for_three_windows_lowers_the_ceiling_by_the_cards_voltages() {
    let c = 3_000.0f32 / 3_300.0;
    let thinner = 0.9 - 1.5 * DISAGREE_S;
    let g = guarded(DISAGREE_WINDOWS, thinner, GUARD_HELD_MS, false);
    assert!(g.disagreed && (g.derate - c * c.sqrt()).abs() < 1e-6, "{g:?}");
    assert!(untouched(&guarded(DISAGREE_WINDOWS - 1, thinner, GUARD_HELD_MS, false)));
    assert!(untouched(&guarded(10, 0.9 - 0.5 * DISAGREE_S, GUARD_HELD_MS, false)));
    assert!(untouched(&guarded(10, thinner, GUARD_HELD_MS - 1, false)));
    assert!(untouched(&guarded(10, thinner, GUARD_HELD_MS - 1, true)));
    let fast = guarded(DISAGREE_WINDOWS, 0.9 - 1.5 * DISAGREE_FAST_S, 0, true);
    assert!(fast.disagreed && fast.derate < 1.0, "{fast:?}");
    // a window in between that agrees starts the count again
    let mut g = ThicknessGuard::new();
    for s in [thinner, thinner, 0.9, thinner, thinner] {
        g.update(s, 0.9, 0.667, 3_000.0, 3_300.0, GUARD_HELD_MS, false);
    }
    assert!(untouched(&g));
}

/// A sensed film within `FLOOR_MARGIN_S` of its floor, and thinner than the model's by more
/// than `NEAR_GAP_S` (the sensing's scatter), lowers the ceiling by 4 x its depth into the
/// margin each window (0.01 in: x 0.96, twice 0.9216); one that agrees with the model's within
/// `NEAR_GAP_S` lowers nothing (the card's own film held at the ceiling relaxes into the margin:
/// the model's guard keeps it above the floor); the derate never leaves [0, 1] and a
/// sensed stretch out of (0, 1.5] (not a number, a reading of nothing) changes nothing; a film
/// sensed thinner where the card's voltage says thicker, or the model at 0 V, derates nothing.
#[test]
fn a_film_near_its_floor_lowers_the_ceiling_in_proportion() {
    let floor = 0.667f32;
    let s = floor + FLOOR_MARGIN_S - 0.01;
    let model = s + NEAR_GAP_S + 0.005;
    assert!(model - s < DISAGREE_S);
    let mut g = ThicknessGuard::new();
    g.update(s, model, floor, 3_000.0, 3_000.0, 0, false);
    assert!((g.derate - 0.96).abs() < 1e-5, "{g:?}");
    g.update(s, model, floor, 3_000.0, 3_000.0, 0, false);
    assert!((g.derate - 0.96 * 0.96).abs() < 1e-5, "{g:?}");
    for agreeing in [s, s - 0.005, s + NEAR_GAP_S] {
        let mut g = ThicknessGuard::new();
        for _ in 0..10 {
            g.update(s, agreeing, floor, 3_000.0, 3_000.0, GUARD_HELD_MS, true);
        }
        assert!(untouched(&g), "the model at {agreeing}: {g:?}");
    }
    let mut deep = ThicknessGuard::new();
    deep.update(0.1, 0.9, floor, 3_000.0, 3_000.0, 0, false);
    assert_eq!(deep.derate, 0.0);
    for bad in [f32::NAN, 0.0, -0.5, 1.6] {
        let mut g = ThicknessGuard::new();
        for _ in 0..DISAGREE_WINDOWS {
            g.update(bad, 0.9, floor, 3_000.0, 3_300.0, GUARD_HELD_MS, false);
        }
        assert!(untouched(&g), "{bad}");
    }
    // a model voltage at the sensed thickness under the model's own raises nothing
    let g = {
        let mut g = ThicknessGuard::new();
        for _ in 0..DISAGREE_WINDOWS {
            g.update(0.85, 0.9, floor, 3_300.0, 3_000.0, GUARD_HELD_MS, false);
        }
        g
    };
    assert!(g.disagreed && g.derate == 1.0, "{g:?}");
    // nor does a channel the model holds at 0 V (its voltage ratio would be 0: a cut until stop)
    let mut g = ThicknessGuard::new();
    for _ in 0..DISAGREE_WINDOWS {
        g.update(0.95, 1.0, floor, 0.0, 800.0, GUARD_HELD_MS, false);
    }
    assert!(g.disagreed && g.derate == 1.0, "{g:?}");
}
