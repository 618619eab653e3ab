//! The tick's fault checks (`finger_fw::control::watch::Watch::check`) on synthetic readings:
//! a module's voltage written tick by tick (a first-order fall, a stuck monitor, a rail), the
//! fault read back. The plant runs (hv_measured, hv_in_time) show the checks against a board;
//! these pin each check's own bound (docs/reliability.md "The read-back's files").
use finger_fw::board::{ADC_FULL_CODE, VMON_FULL_SCALE_V};
use finger_fw::control::hv_loop::Ask;
use finger_fw::control::sense::Estimator;
use finger_fw::control::watch::{Reading, Watch, COLLAPSE_FRAC, HV_SETTLE_MS, MISMATCH_FRAC, MISMATCH_V, MODULE_FALL_MS, OVER_FRAC, OVER_MS, OVER_V};
use finger_fw::control::Fault;

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
    let mut w = Watch::new();
    (0..ticks).find_map(|k| {
        let ask = Ask { volts: drive(k), slew_held: false };
        let dither_v = (k % 2) as f32 * 0.5;
        w.check(&reading(v(k) + dither_v, 0.1), drive(k), &ask, 5_400.0, enabled, &Estimator::new()).map(|f| (k, f))
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

/// With the HV enable low, an output that stays above twice `MISMATCH_V` (a module that does
/// not switch off) latches after the settling time; one that reads 500 V is none.
#[test]
fn an_output_left_on_with_the_enable_low_latches() {
    assert_eq!(first_fault(1_000, false, |_| 0.0, |_| 500.0), None);
    assert_eq!(first_fault(1_000, false, |_| 0.0, |_| 700.0), Some((HV_SETTLE_MS, Fault::HvMismatch)));
}
