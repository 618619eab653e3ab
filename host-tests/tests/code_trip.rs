//! The Cortex-M3 image's read-back checks in integers (`finger_fw::control::trip::CodeWatch`,
//! issue 54: a trip on every image) against the plant (src/plant.rs) on the host, driven open
//! loop as that image drives it (the duty of the slewed voltage): fault-free ramps, holds at the
//! ceiling and stops latch nothing; a module past its ceiling is `hv-mismatch`, a monitor stuck
//! while the duty moves or at its rail `sensor`, a return current past the analog watchdog's code
//! `breakdown`. The same checks in QEMU on the M3 image: qemu_plant's `m3::` tests.
use finger_fw::board::{ADC_FULL_CODE, HV_CHANNELS, HV_LIMIT_V, VMON_FULL_SCALE_V};
use finger_fw::control::trip::{CodeScale, CodeWatch};
use finger_fw::control::watch::{OVER_FRAC, OVER_MS, OVER_V, STUCK_MS};
use finger_fw::control::{hv_duty_for, Fault};
use finger_fw::plant::{Inject, Plant};

/// The emulator's HV PWM full scale (TIM4 at 20 kHz from the 16 MHz HSI).
const MAX_DUTY: u16 = 800;
/// The board's hold ceiling on the card's film, V (a duty ceiling at it).
const CEILING_V: f32 = 5_394.0;

/// The plant driven open loop: each channel slews toward its target at `slew` V/s, its duty
/// written, the checks run on the tick's read-back.
struct Rig {
    plant: Plant,
    watch: [CodeWatch; HV_CHANNELS],
    scale: CodeScale,
    volts: [f32; HV_CHANNELS],
    enable: bool,
    ms: u32,
}

impl Rig {
    fn new(seed: u32) -> Self {
        Rig {
            plant: Plant::new(seed).unwrap(),
            watch: [CodeWatch::new(); HV_CHANNELS],
            scale: CodeScale::new(MAX_DUTY),
            volts: [0.0; HV_CHANNELS],
            enable: true,
            ms: 0,
        }
    }

    /// `ticks` ms toward `target` (V per channel) at `slew` V/s; the first fault, its channel
    /// and the tick it came at.
    fn run(&mut self, ticks: u32, target: [f32; HV_CHANNELS], slew: f32) -> Option<(u32, usize, Fault)> {
        let ceiling = hv_duty_for(CEILING_V, MAX_DUTY);
        for _ in 0..ticks {
            self.ms += 1;
            let mut duty = [0u16; HV_CHANNELS];
            for ch in 0..HV_CHANNELS {
                let t = if self.enable { target[ch] } else { 0.0 };
                let step = slew * 1e-3;
                self.volts[ch] = if self.enable { t.min(self.volts[ch] + step).max(self.volts[ch] - step) } else { 0.0 };
                duty[ch] = hv_duty_for(self.volts[ch], MAX_DUTY);
            }
            let hs = self.plant.tick(duty, MAX_DUTY, self.enable);
            for ch in 0..HV_CHANNELS {
                if let Some(f) = self.watch[ch].check(&self.scale, hs.v_code[ch], hs.i_code[ch], duty[ch], ceiling, self.enable) {
                    return Some((self.ms, ch, f));
                }
            }
        }
        None
    }
}

/// Fault-free: ramps at the default slew and at 100 kV/s to the ceiling and back, a hold at
/// the ceiling, steps between channels, a stop with the stacks charged (the enable low, the
/// module discharging them): nothing latches, over five seeds of the ADC's noise.
#[test]
fn fault_free_ramps_holds_and_stops_latch_nothing() {
    for seed in 1..=5 {
        let mut r = Rig::new(seed);
        let top = [CEILING_V; HV_CHANNELS];
        assert_eq!(r.run(4_000, top, 2_000.0), None, "seed {seed}: ramp up at 2 kV/s");
        assert_eq!(r.run(5_000, top, 2_000.0), None, "seed {seed}: hold at the ceiling");
        assert_eq!(r.run(3_000, [0.0, 2_000.0, 5_000.0], 100_000.0), None, "seed {seed}: steps at 100 kV/s");
        assert_eq!(r.run(1_000, top, 100_000.0), None, "seed {seed}: back up");
        r.enable = false;
        assert_eq!(r.run(1_000, top, 2_000.0), None, "seed {seed}: a stop at the ceiling");
    }
}

/// Module 2 at 1.5 times its gain, driven to 4.8 kV: past the ceiling by OVER_FRAC + OVER_V
/// (5,562 V), `hv-mismatch` on channel 2 after OVER_MS ticks there, not before.
#[test]
fn a_module_past_its_ceiling_is_hv_mismatch_after_the_bound() {
    let mut r = Rig::new(7);
    assert_eq!(r.run(3_000, [4_800.0; HV_CHANNELS], 2_000.0), None);
    r.plant.inject(1, Inject::Gain(1.5)).unwrap();
    let bound = hv_duty_for(CEILING_V, MAX_DUTY) as f32 / MAX_DUTY as f32 * finger_fw::board::HV_FULL_SCALE_V * (1.0 + OVER_FRAC) + OVER_V;
    // tick by tick: the first tick the plant's voltage passed the bound
    let mut past_at = None;
    let mut got = None;
    for _ in 0..2_000 {
        if let Some(f) = r.run(1, [4_800.0; HV_CHANNELS], 2_000.0) {
            got = Some(f);
            break;
        }
        if past_at.is_none() && r.plant.truth()[1].volts > bound + 5.0 {
            past_at = Some(r.ms);
        }
    }
    let (ms, ch, f) = got.expect("the module past its ceiling latched nothing");
    assert_eq!((ch, f), (1, Fault::HvMismatch));
    let past = past_at.expect("the voltage never passed the bound");
    assert!(ms >= past + OVER_MS - 2 && ms <= past + OVER_MS + 5, "latched at {ms} ms, past the bound at {past} ms");
}

/// Monitor 1 stuck where it reads (about 2 kV): held still, no fault for a second; then a ramp
/// to 3 kV: `sensor` once the duty has moved past STUCK_MOVE_V with the code unchanged for
/// STUCK_MS ticks (within 120 ms of the ramp's start at 2 kV/s).
#[test]
fn a_monitor_stuck_while_the_duty_moves_is_a_sensor_fault() {
    let mut r = Rig::new(3);
    assert_eq!(r.run(3_000, [2_000.0; HV_CHANNELS], 2_000.0), None);
    let code = 2_000.0 * ADC_FULL_CODE / VMON_FULL_SCALE_V;
    r.plant.inject(0, Inject::MonitorStuck(code.round())).unwrap();
    assert_eq!(r.run(1_000, [2_000.0; HV_CHANNELS], 2_000.0), None, "a still voltage: no stuck monitor");
    let t0 = r.ms;
    let (ms, ch, f) = r.run(1_000, [3_000.0; HV_CHANNELS], 2_000.0).expect("the stuck monitor latched nothing");
    assert_eq!((ch, f), (0, Fault::Sensor));
    assert!(ms - t0 >= STUCK_MS && ms - t0 <= 120, "latched {} ms into the ramp", ms - t0);
}

/// A monitor at its rail, and readings not finite or negative: `sensor` at once.
#[test]
fn a_reading_at_the_rail_or_not_a_number_is_a_sensor_fault() {
    let mut r = Rig::new(5);
    assert_eq!(r.run(500, [1_000.0; HV_CHANNELS], 2_000.0), None);
    r.plant.inject(2, Inject::MonitorStuck(ADC_FULL_CODE)).unwrap();
    let (_, ch, f) = r.run(1, [1_000.0; HV_CHANNELS], 2_000.0).expect("a monitor at its rail latched nothing");
    assert_eq!((ch, f), (2, Fault::Sensor));
    let s = CodeScale::new(MAX_DUTY);
    for (v, i) in [(f32::NAN, 2048.0), (100.0, f32::NAN), (-1.0, 2048.0), (100.0, f32::INFINITY)] {
        assert_eq!(CodeWatch::new().check(&s, v, i, 10, 700, true), Some(Fault::Sensor), "v {v} i {i}");
    }
    assert_eq!(CodeWatch::new().check(&s, 100.0, 2048.0, 10, 700, true), None);
}

/// A short through stack 3 at 3 kV: the plant's analog watchdog trips (the core's
/// `HvSense::trip`) and the tick's mean return current passes the watchdog's code too:
/// `breakdown` on channel 3 within 2 ms.
#[test]
fn a_short_is_a_breakdown_on_its_channel() {
    let mut r = Rig::new(9);
    assert_eq!(r.run(3_000, [3_000.0; HV_CHANNELS], 2_000.0), None);
    let t0 = r.ms;
    r.plant.inject(2, Inject::Breakdown { clears_after_ms: None }).unwrap();
    let (ms, ch, f) = r.run(100, [3_000.0; HV_CHANNELS], 2_000.0).expect("the short latched nothing");
    assert_eq!((ch, f), (2, Fault::Breakdown));
    assert!(ms - t0 <= 2, "{} ms", ms - t0);
}

/// The bound is the ceiling's: a module held just under ceiling x (1 + OVER_FRAC) + OVER_V is
/// no fault (the hard limit's, the analog watchdog's voltage code, is above it).
#[test]
fn just_under_the_over_voltage_bound_is_no_fault() {
    let mut r = Rig::new(11);
    // gain so that the held ceiling reads just under the bound
    let bound = CEILING_V * (1.0 + OVER_FRAC) + OVER_V;
    assert!(bound < HV_LIMIT_V * (1.0 + OVER_FRAC) + OVER_V + 1.0);
    r.plant.inject(0, Inject::Gain((bound - 40.0) / CEILING_V)).unwrap();
    assert_eq!(r.run(8_000, [CEILING_V; HV_CHANNELS], 2_000.0), None);
}

/// The checks' own bounds, tick by tick on synthetic readings (the plant runs above show them
/// against a board): a mean current exactly at the watchdog's code is no fault, a sixteenth of
/// a code above it `breakdown`.
#[test]
fn the_current_trips_above_the_watchdogs_code_not_at_it() {
    let s = CodeScale::new(MAX_DUTY);
    let at = s.current_high_c16() as f32 / 16.0;
    assert_eq!(CodeWatch::new().check(&s, 100.0, at, 10, 700, true), None);
    assert_eq!(CodeWatch::new().check(&s, 100.0, at + 1.0 / 16.0, 10, 700, true), Some(Fault::Breakdown));
}

/// A reading exactly at the over-voltage bound, held, is no fault; a sixteenth of a code above
/// it is `hv-mismatch` at its OVER_MS-th tick.
#[test]
fn over_voltage_counts_above_the_bound_not_at_it() {
    let s = CodeScale::new(MAX_DUTY);
    let ceiling = 431;
    let at = s.over_bound_c16(ceiling) as f32 / 16.0;
    let mut w = CodeWatch::new();
    for _ in 0..500 {
        assert_eq!(w.check(&s, at, 2048.0, ceiling, ceiling, true), None);
    }
    let mut w = CodeWatch::new();
    let first = (1..=500).find(|_| w.check(&s, at + 1.0 / 16.0, 2048.0, ceiling, ceiling, true).is_some());
    assert_eq!(first, Some(OVER_MS));
}

/// A code that does not move while the duty moves by exactly the duty of STUCK_MOVE_V is no
/// fault; one count more is `sensor`.
#[test]
fn a_stuck_code_counts_when_the_duty_moved_past_the_bound_not_by_it() {
    let s = CodeScale::new(MAX_DUTY);
    let m = s.stuck_move_duty();
    assert!(m > 0);
    for (moved, want) in [(m, None), (m + 1, Some(Fault::Sensor))] {
        let mut w = CodeWatch::new();
        // still for 5 ticks, then one count a tick up to `moved`, the code frozen throughout
        let got = (0..300u16).find_map(|k| w.check(&s, 300.0, 2048.0, 100 + moved.min(k.saturating_sub(5)), 700, true));
        assert_eq!(got, want, "the duty moved by {moved} (the bound {m})");
    }
}

/// A ceiling that drops from 5 kV to 4 kV (duty 400 to 320 of 800): the bound falls from the
/// old one at the module's fall (MODULE_FALL_MS, 25 ms). A module falling at its own 15 ms is no
/// fault; a reading that stays at 4.9 kV (under the old bound, past the new 4,140 V) counts from
/// when the falling bound passes it (about 8 ms after the drop), `hv-mismatch` OVER_MS later.
#[test]
fn the_bound_falls_at_the_modules_fall_after_the_ceiling_drops() {
    let s = CodeScale::new(MAX_DUTY);
    let (hi, lo) = (400u16, 320u16);
    let code = |v: f32| v * ADC_FULL_CODE / VMON_FULL_SCALE_V;
    // the monitor's last quarter code alternates (a moving code: no stuck monitor)
    let run = |after: &dyn Fn(u32) -> f32| -> Option<(u32, Fault)> {
        let mut w = CodeWatch::new();
        for k in 0..100u32 {
            assert_eq!(w.check(&s, code(5_000.0) + (k % 2) as f32 * 0.25, 2048.0, hi, hi, true), None);
        }
        (1..=300u32).find_map(|t| w.check(&s, code(after(t)) + (t % 2) as f32 * 0.25, 2048.0, lo, lo, true).map(|f| (t, f)))
    };
    assert_eq!(run(&|t| 4_000.0 + 1_000.0 * (-(t as f32) / 15.0).exp()), None, "the module's own fall");
    let (t, f) = run(&|_| 4_900.0).expect("a module that stays past the new ceiling latched nothing");
    assert_eq!(f, Fault::HvMismatch);
    assert!((OVER_MS + 4..=OVER_MS + 12).contains(&t), "latched {t} ms after the drop");
}
