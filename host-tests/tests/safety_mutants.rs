//! The safety core's boundaries, one assertion per rule, written against the mutants that
//! survived the other host tests (scripts/mutants, docs/reliability.md): the control core
//! (the single duty writer's ceiling and cap, the slew step, stale setpoints, the watchdog's
//! check-in bound, stop), the RX ring (overrun counts, a full ring, the `wait` input flag) and
//! the Cortex-M3 image's step arithmetic (`plain_slew_step`, which the host compiles).
use finger_fw::board::{HV_CHANNELS, HV_FULL_SCALE_V, HV_LIMIT_V};
use finger_fw::console::LINE_MAX;
use finger_fw::control::hv_loop::{VoltageLoop, INTEGRAL_FRAC, KI_PER_S, KP};
use finger_fw::control::stacks::plain_slew_step;
use finger_fw::control::{hv_duty_cap, hv_duty_for, Control, Fault, Latched, Setpoints, CHECKIN_BOUND_MS, LOW_CHECK_V};
use finger_fw::plant::{Inject, Plant};
use finger_fw::rx::{Record, RxEvent, RxLines, OVERRUN_RECORD, RX_RING};
use finger_fw::sim::SimBoard;

const MAX: u16 = 8_400;

fn core() -> Control<SimBoard> {
    Control::new(SimBoard::default(), 2_000, 2_000.0)
}

fn setpoints(c: &Control<SimBoard>, volts: f32, ceiling: u16) -> Setpoints {
    let v = c.view();
    Setpoints {
        seq: v.seq + 1,
        epoch: v.epoch,
        armed: true,
        target_v: [volts; HV_CHANNELS],
        servo_duty: 2_000,
        servo_released: 2_000,
        duty_ceiling: [ceiling; HV_CHANNELS],
        slew: 2_000.0,
        shaped: false,
    }
}

/// `n` control ticks, the command side checked in at each.
fn ticks(c: &mut Control<SimBoard>, n: u32) {
    for _ in 0..n {
        c.tick(c.now_ms());
    }
}

#[test]
fn duty_of_a_voltage_and_the_cap() {
    assert_eq!(hv_duty_for(0.0, MAX), 0);
    assert_eq!(hv_duty_for(-1.0, MAX), 0);
    assert_eq!(hv_duty_for(f32::NAN, MAX), 0);
    assert_eq!(hv_duty_for(HV_FULL_SCALE_V, MAX), MAX);
    assert_eq!(hv_duty_for(2.0 * HV_FULL_SCALE_V, MAX), MAX);
    // duty% = zero + (100 - zero) v / full scale, rounded down
    let v = 0.37 * HV_FULL_SCALE_V;
    assert_eq!(hv_duty_for(v, MAX), (v / HV_FULL_SCALE_V * MAX as f32) as u16);
    assert_eq!(hv_duty_for(v, 10_000), (v / HV_FULL_SCALE_V * 10_000.0) as u16);
    assert_eq!(hv_duty_cap(MAX), hv_duty_for(HV_LIMIT_V, MAX));
}

#[test]
fn the_single_writer_refuses_past_the_ceiling_and_accepts_at_it() {
    let mut c = core();
    let ceiling = 3_000;
    assert!(c.apply(&setpoints(&c, 0.0, ceiling)));
    assert!(c.write_hv_duty(0, ceiling).is_ok());
    assert_eq!(c.board().hv[0].duty, ceiling);
    assert_eq!(c.view().duty[0], ceiling);
    assert!(c.write_hv_duty(1, ceiling + 1).is_err());
    assert_eq!(c.board().hv[1].duty, 0, "a refused duty is not written");
    assert_eq!(c.view().fault, Some("hv-refused"));
    assert!(c.write_hv_duty(HV_CHANNELS, 0).is_err(), "no such channel");
    c.stop();
    assert_eq!(c.view().fault, None, "stop clears the latched fault");
    assert!(c.write_hv_duty(2, 0).is_ok(), "0 is always allowed");
}

#[test]
fn slew_moves_exactly_one_step_per_tick_and_stops_at_the_target() {
    let mut c = core();
    let ceiling = hv_duty_for(5_000.0, MAX);
    assert!(c.apply(&setpoints(&c, 3.5, ceiling)));
    assert!(c.view().enable);
    c.tick(c.now_ms());
    // 2000 V/s x 1 ms = 2 V per tick
    assert_eq!(c.view().volts, [2.0; HV_CHANNELS]);
    assert_eq!(c.board().hv[0].duty, hv_duty_for(2.0, MAX));
    c.tick(c.now_ms());
    assert_eq!(c.view().volts, [3.5; HV_CHANNELS], "no overshoot");
    // and down
    assert!(c.apply(&setpoints(&c, 0.5, ceiling)));
    c.tick(c.now_ms());
    assert_eq!(c.view().volts, [1.5; HV_CHANNELS]);
    c.tick(c.now_ms());
    assert_eq!(c.view().volts, [0.5; HV_CHANNELS]);
}

#[test]
fn setpoints_past_the_limit_or_stale_are_refused() {
    let mut c = core();
    let ceiling = hv_duty_for(1_000.0, MAX);
    // a target whose duty is past the ceiling: fault stop
    assert!(c.apply(&setpoints(&c, 1_200.0, ceiling)));
    assert_eq!(c.view().fault, Some("hv-refused"));
    assert!(!c.view().enable);
    c.stop();
    assert!(c.apply(&setpoints(&c, f32::NAN, ceiling)));
    assert_eq!(c.view().fault, Some("hv-refused"), "NaN refused");
    c.stop();
    // planned before a stop: dropped
    let sp = setpoints(&c, 500.0, ceiling);
    c.stop();
    let seq = c.view().seq;
    assert!(!c.apply(&sp));
    assert_eq!(c.view().seq, seq, "a dropped set is not taken");
    assert!(!c.view().enable);
    // a slew out of (0, 1e6] V/s is ignored: the old one stays
    let mut sp = setpoints(&c, 500.0, ceiling);
    sp.slew = 0.0;
    assert!(c.apply(&sp));
    c.tick(c.now_ms());
    assert_eq!(c.view().volts[0], 2.0);
}

#[test]
fn watchdog_fed_only_within_the_check_in_bound() {
    let feeds = |c: &Control<SimBoard>| c.board().watchdog_feeds;
    // the tick that makes now = bound still feeds (checked in `bound` ms ago), the next does not
    let mut c = core();
    let mut fed = Vec::new();
    for _ in 0..CHECKIN_BOUND_MS + 2 {
        let before = feeds(&c);
        c.tick(0);
        fed.push(feeds(&c) > before);
    }
    assert!(fed[..CHECKIN_BOUND_MS as usize].iter().all(|&f| f), "fed while checked in");
    assert!(!fed[CHECKIN_BOUND_MS as usize], "not fed {} ms after the check-in", CHECKIN_BOUND_MS + 1);
    assert_eq!(c.now_ms(), CHECKIN_BOUND_MS + 2, "one ms per tick");
}

#[test]
fn stop_drops_everything_at_once() {
    let mut c = core();
    let ceiling = hv_duty_for(5_000.0, MAX);
    assert!(c.apply(&setpoints(&c, 100.0, ceiling)));
    ticks(&mut c, 10);
    assert!(c.board().hv.iter().all(|h| h.duty > 0) && c.board().enable.high);
    let epoch = c.view().epoch;
    c.stop();
    assert!(c.board().hv.iter().all(|h| h.duty == 0) && !c.board().enable.high);
    assert_eq!(c.view().volts, [0.0; HV_CHANNELS]);
    assert_eq!(c.view().epoch, epoch + 1);
    c.tick(c.now_ms());
    assert!(c.board().hv.iter().all(|h| h.duty == 0), "nothing after the stop's tick");
}

fn line(rx: &mut RxLines, s: &[u8]) -> RxEvent {
    let mut ev = RxEvent::Nothing;
    for &b in s {
        ev = rx.push(b);
    }
    ev
}

/// `n` lines of `text`, each ended by LF.
fn send_lines(rx: &mut RxLines, text: &[u8], n: usize) {
    for _ in 0..n {
        line(rx, text);
        line(rx, b"\n");
    }
}

#[test]
fn rx_overruns_are_counted_per_line() {
    let mut rx = RxLines::new();
    for _ in 0..3 {
        rx.overrun();
        line(&mut rx, b"volt 1 5\n");
    }
    line(&mut rx, b"ok line\n");
    assert_eq!(rx.pop(), Some(Record::Overrun(3)));
    assert!(matches!(rx.pop(), Some(Record::Line(v)) if &v[..] == b"ok line"));
    assert_eq!(rx.pop(), None);
    assert!(!rx.pending());
    // a `stop` whose first word arrived whole acts despite a later overrun
    line(&mut rx, b"stop ");
    rx.overrun();
    assert_eq!(line(&mut rx, b"x\n"), RxEvent::Stop);
    // ... but not when a byte of the word was lost
    line(&mut rx, b"st");
    rx.overrun();
    assert_eq!(line(&mut rx, b"op\n"), RxEvent::Nothing);
    assert_eq!(rx.pop(), Some(Record::Overrun(1)));
}

#[test]
fn rx_full_ring_loses_whole_lines_only() {
    let mut rx = RxLines::new();
    let text = [b'a'; 100];
    let fits = (RX_RING - 2) / (text.len() + 2);
    send_lines(&mut rx, &text, fits + 3);
    let mut whole = 0;
    let mut lost = 0;
    while let Some(r) = rx.pop() {
        match r {
            Record::Line(v) => {
                assert_eq!(&v[..], &text[..]);
                whole += 1;
            }
            Record::Overrun(n) => lost += n as usize,
            Record::TooLong | Record::Stopped(_) => panic!("{r:?}"),
        }
    }
    assert_eq!(whole + lost, fits + 3);
    assert!(whole >= fits - 1 && lost >= 3, "{whole} whole, {lost} lost");
    // the ring works again once emptied
    line(&mut rx, b"again\n");
    assert!(matches!(rx.pop(), Some(Record::Line(v)) if &v[..] == b"again"));
}

#[test]
fn rx_input_flag_for_wait() {
    let mut rx = RxLines::new();
    assert!(!rx.take_input_seen());
    rx.push(b'\n');
    assert!(!rx.take_input_seen(), "a line ending alone is not input");
    rx.push(b'x');
    assert!(rx.take_input_seen());
    assert!(!rx.take_input_seen(), "the flag clears");
    rx.push(b'\n');
    assert!(rx.pending());
    assert!(rx.take_input_seen(), "a queued line counts");
    assert_eq!(rx.received, 3);
}

#[test]
fn a_latched_fault_keeps_the_enable_low_until_a_stop() {
    let mut c = core();
    let ceiling = hv_duty_for(1_000.0, MAX);
    assert!(c.apply(&setpoints(&c, 1_200.0, ceiling)));
    assert_eq!(c.view().fault, Some("hv-refused"));
    // armed setpoints of the new epoch while the fault is latched: taken, never enabled
    assert!(c.apply(&setpoints(&c, 500.0, ceiling)));
    assert!(!c.view().enable && !c.board().enable.high, "a latched fault arms nothing");
    c.stop();
    assert!(c.apply(&setpoints(&c, 500.0, ceiling)));
    assert!(c.view().enable && c.board().enable.high, "after the stop it arms");
}

/// Only a fault of the read-back makes the next arm run the low-voltage check (300 ms at no
/// more than 200 V): after a breakdown the stacks wait under 200 V, after a refused setpoint
/// they ramp at their slew at once. On the plant's board (the read-back present).
#[test]
fn only_a_fault_of_the_read_back_makes_the_next_arm_check_at_low_voltage() {
    let ceiling = hv_duty_for(2_000.0, MAX);
    let after = |fault: &dyn Fn(&mut Control<SimBoard>)| {
        let mut c = Control::new(SimBoard::with_plant(Plant::new(1).unwrap()), 2_000, 2_000.0);
        fault(&mut c);
        assert!(c.view().fault.get().is_some());
        c.stop();
        assert!(c.apply(&setpoints(&c, 1_500.0, ceiling)));
        ticks(&mut c, 250);
        c.view().volts
    };
    let refused = after(&|c| assert!(c.apply(&setpoints(c, 2_400.0, ceiling))));
    assert!(refused.iter().all(|&v| v > 2.0 * LOW_CHECK_V), "250 ms after the arm at 2,000 V/s: {refused:?} V");
    let broke = after(&|c| {
        assert!(c.apply(&setpoints(c, 1_500.0, ceiling)));
        ticks(c, 1_000);
        c.board_mut().plant.as_mut().unwrap().inject(0, Inject::Breakdown { clears_after_ms: Some(1) }).unwrap();
        ticks(c, 5);
        assert_eq!(c.view().fault, Some("breakdown"));
    });
    assert!(broke.iter().all(|&v| v <= LOW_CHECK_V), "250 ms after the arm that follows a breakdown: {broke:?} V");
}

/// A latched fault compares equal to its console text and to nothing else (the tests'
/// `assert_eq!(view.fault, Some("breakdown"))` rest on it).
#[test]
fn a_latched_fault_equals_its_own_text_only() {
    assert_eq!(Latched(None), None);
    assert_ne!(Latched(None), Some("breakdown"));
    assert_eq!(Latched(Some(Fault::Breakdown)), Some("breakdown"));
    assert_ne!(Latched(Some(Fault::Breakdown)), Some("sensor"));
    assert_ne!(Latched(Some(Fault::Breakdown)), None);
}

/// A module whose output is `gain` x the voltage asked, read back without noise, behind a voltage
/// loop at a 5,000 V top and 2 V a tick.
struct Module {
    gain: f32,
    measured: f32,
}

impl Module {
    fn new(gain: f32) -> Self {
        Module { gain, measured: 0.0 }
    }
    /// `ticks` of the loop for `drive` under the ceiling `limit`: the voltage asked at each.
    fn asks(&mut self, l: &mut VoltageLoop, drive: f32, limit: f32, ticks: u32) -> Vec<f32> {
        (0..ticks)
            .map(|_| {
                let a = l.step(drive, self.measured, 5_000.0, limit, 2.0);
                self.measured = self.gain * a.volts;
                a.volts
            })
            .collect()
    }
}

/// A drive of 0 (a disarm) or a ceiling of 0 ends the voltage loop's integral: the ask ramps
/// to 0 (the ceiling: at once) and stays there, and the next drive runs as on a new loop. The
/// module here is 20 % weak, so the integral had grown while held.
#[test]
fn the_voltage_loop_forgets_its_integral_when_the_drive_or_the_ceiling_is_0() {
    let top = 5_000.0;
    for (drive_off, limit_off) in [(0.0, top), (1_000.0, 0.0)] {
        let (mut l, mut module) = (VoltageLoop::new(), Module::new(0.8));
        module.asks(&mut l, 1_000.0, top, 2_000);
        assert!(l.asked_v() > 1_100.0, "the weak module's ask {} V", l.asked_v());
        let off = module.asks(&mut l, drive_off, limit_off, 2_000);
        assert!(off[1_000..].iter().all(|&v| v == 0.0), "drive {drive_off} V, ceiling {limit_off} V: the ask ends at {:?} V", off.last());
        if limit_off == 0.0 {
            assert_eq!(off[0], 0.0, "a ceiling of 0 is obeyed at once");
        }
        let again = module.asks(&mut l, 1_000.0, top, 2_000);
        let new = Module::new(0.8).asks(&mut VoltageLoop::new(), 1_000.0, top, 2_000);
        let differs = again.iter().zip(&new).position(|(a, b)| a != b);
        assert_eq!(differs, None, "drive {drive_off} V, ceiling {limit_off} V: the next drive's asks differ from a new loop's from this tick on");
    }
}

/// The loop's one tick from rest, the slew out of the way: the feed-forward, KP x the error
/// and KI x the error x 1 ms (900 V read for 1,000 V: 1,000 + 50 + 3 V).
#[test]
fn the_voltage_loop_is_feed_forward_plus_its_pi_terms() {
    let mut l = VoltageLoop::new();
    let a = l.step(1_000.0, 900.0, 5_000.0, 5_000.0, 1e6);
    let want = 1_000.0 + KP * 100.0 + KI_PER_S * 1e-3 * 100.0;
    assert!((a.volts - want).abs() < 1e-3, "{} V against {want} V", a.volts);
    assert!(!a.slew_held);
}

/// A monitor that reads half the true voltage: the integral stops at its bound (a quarter of
/// the drive and 50 V), so the ask stays under the drive + KP x the drive + that bound, far
/// under the ceiling, however long it runs.
#[test]
fn the_voltage_loops_integral_is_bounded_under_a_monitor_reading_half() {
    let drive = 1_000.0;
    let asks = Module::new(0.5).asks(&mut VoltageLoop::new(), drive, 5_000.0, 20_000);
    let highest = asks.iter().fold(0.0f32, |h, &v| h.max(v));
    let bound = drive + KP * drive + INTEGRAL_FRAC * drive + 50.0;
    assert!(highest <= bound, "the ask reached {highest} V, bound {bound} V");
}

/// A ramp the slew holds back does not wind the integral up (anti-windup): with a module 10 %
/// weak, the ask settles on what the module needs (drive / 0.9) within 1 V and passes it by no
/// more than 1 %, after each step (up from rest, down, up again), each ramped at 2 V a tick.
/// (A module 10 % strong passes its need by 5 % on the last step up: the proportional term's
/// lag, with or without the anti-windup.)
#[test]
fn the_voltage_loop_does_not_wind_up_while_the_slew_holds_it() {
    let gain = 0.9f32;
    let (mut l, mut module, mut last) = (VoltageLoop::new(), Module::new(gain), 0.0f32);
    for drive in [1_000.0f32, 200.0, 1_000.0] {
        let asks = module.asks(&mut l, drive, 5_000.0, 6_000);
        let need = drive / gain;
        let (lo, hi) = asks.iter().fold((f32::MAX, 0.0f32), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let settled = asks[asks.len() - 1];
        assert!((settled - need).abs() < 1.0, "gain {gain}, drive {drive} V: settled at {settled} V, the module needs {need} V");
        if need > last {
            assert!(hi <= 1.01 * need, "gain {gain}, drive {drive} V: overshoot to {hi} V");
        } else {
            assert!(lo >= 0.99 * need, "gain {gain}, drive {drive} V: undershoot to {lo} V");
        }
        last = need;
    }
    // held on a ceiling under the module's need (1,050 V of 1,111 V) for 3 s, then the ceiling
    // lifted: the integral did not grow past what put the ask on the ceiling
    let (mut l, mut module) = (VoltageLoop::new(), Module::new(gain));
    let mut asks = module.asks(&mut l, 1_000.0, 1_050.0, 3_000);
    asks.extend(module.asks(&mut l, 1_000.0, 5_000.0, 3_000));
    let highest = asks.iter().fold(0.0f32, |h, &v| h.max(v));
    assert!(highest <= 1.01 * 1_000.0 / gain, "after the ceiling lifted: overshoot to {highest} V");
}

/// The loop says when the slew holds it back from what it wants, both ways: a step up from rest
/// and a step down from a settled 3 kV are held; settled (a module 20 % weak, its integral a
/// fifth of the drive) it is not; against the ceiling (up) or at 0 V (down) the slew is not what
/// holds it.
#[test]
fn the_voltage_loop_says_when_the_slew_holds_it_back() {
    let step = |l: &mut VoltageLoop, drive: f32, measured: f32| l.step(drive, measured, 5_000.0, 5_000.0, 2.0);
    assert!(step(&mut VoltageLoop::new(), 3_000.0, 0.0).slew_held, "a step up from rest");
    let (mut l, mut module) = (VoltageLoop::new(), Module::new(0.8));
    module.asks(&mut l, 3_000.0, 5_000.0, 8_000);
    assert!((module.measured - 3_000.0).abs() < 1.0, "settled at {} V", module.measured);
    let settled = l;
    assert!(!step(&mut l, 3_000.0, module.measured).slew_held, "settled, the integral at {} V", l.asked_v() - 3_000.0);
    let mut l = settled;
    assert!(step(&mut l, 1_000.0, module.measured).slew_held, "a step down from 3 kV");
    // the ceiling holds it, not the slew
    let mut l = VoltageLoop::new();
    let near_top: Vec<bool> = (0..3_000).map(|_| l.step(5_000.0, 0.0, 5_000.0, 1_000.0, 2.0).slew_held).collect();
    assert!(near_top[0] && !near_top[2_999], "at the ceiling, {} V asked", l.asked_v());
    // at 0 V the floor holds it, not the slew
    let mut l = VoltageLoop::new();
    assert!(!l.step(100.0, 5_000.0, 5_000.0, 5_000.0, 2.0).slew_held);
}

#[test]
fn the_servo_follows_the_voltages_progress_from_where_they_were() {
    let mut c = core();
    let ceiling = hv_duty_for(5_000.0, MAX);
    assert!(c.apply(&setpoints(&c, 100.0, ceiling)));
    ticks(&mut c, 60);
    assert_eq!(c.view().volts, [100.0; HV_CHANNELS]);
    assert_eq!(c.view().servo_duty, 2_000);
    // 100 V -> 300 V at 2 V per tick while the servo goes 2000 -> 4000: half way after 50 ticks
    let mut sp = setpoints(&c, 300.0, ceiling);
    sp.servo_duty = 4_000;
    assert!(c.apply(&sp));
    ticks(&mut c, 50);
    assert_eq!(c.view().volts, [200.0; HV_CHANNELS]);
    assert_eq!(c.view().servo_duty, 3_000);
    ticks(&mut c, 60);
    assert_eq!(c.view().servo_duty, 4_000);
}

#[test]
fn the_core_reports_its_pwms_full_scale_and_the_boards_floor() {
    let c = core();
    assert_eq!(c.hv_max(), [MAX; HV_CHANNELS]);
    // s_hold: the film's equilibrium at the board's hold ceiling, from the board's own law
    let law = finger_fw::board::board_law().unwrap();
    let hold = finger_fw::board::board_hold_ceiling_of(&law);
    assert_eq!(c.hold_ceiling_v(), hold);
    assert_eq!(c.s_hold(), finger_model::material::equilibrium_ratio(&law, hold).unwrap());
    assert!(c.s_hold() > 0.0 && c.s_hold() < 1.0);
}

#[test]
fn rx_counts_every_lost_line_past_a_byte() {
    // a full ring, then 300 lines lost in a row before the command side takes anything: each
    // lost line keeps its own `err overrun`
    let mut rx = RxLines::new();
    let text = [b'a'; 100];
    let mut sent = (RX_RING / (text.len() + 2)) as u32;
    send_lines(&mut rx, &text, sent as usize);
    for _ in 0..300 {
        line(&mut rx, b"x\n");
        sent += 1;
    }
    let (mut whole, mut lost) = (0u32, 0u32);
    while let Some(r) = rx.pop() {
        match r {
            Record::Line(_) => whole += 1,
            Record::Overrun(n) => lost += n,
            r => panic!("{r:?}"),
        }
    }
    assert_eq!(whole + lost, sent);
    assert!(lost > 255, "{lost} lost");
}

#[test]
fn rx_stop_after_leading_blanks() {
    let mut rx = RxLines::new();
    assert_eq!(line(&mut rx, b"  \tstop\n"), RxEvent::Stop);
    // its first word whole before the overrun: still a stop
    line(&mut rx, b" stop ");
    rx.overrun();
    assert_eq!(line(&mut rx, b"x\n"), RxEvent::Stop);
    assert!(!rx.pending());
}

#[test]
fn rx_crlf_lines_and_blank_lines() {
    let mut rx = RxLines::new();
    let stops = |rx: &mut RxLines, s: &[u8]| s.iter().filter(|&&b| rx.push(b) == RxEvent::Stop).count();
    // the LF of a CRLF is no part of the next line's first word
    assert_eq!(stops(&mut rx, b"stop\r\nstop\r\nvolt 1 5\r\nstop\r\nvolt 1 6\r\n"), 3);
    // the line before the last stop dropped by it, the one after it whole
    assert_eq!(rx.pop(), Some(Record::Stopped(1)));
    assert!(matches!(rx.pop(), Some(Record::Line(v)) if &v[..] == b"volt 1 6"));
    // a line of blanks gives nothing
    line(&mut rx, b"  \t \r\n");
    assert!(!rx.pending());
}

#[test]
fn rx_a_line_that_just_fits_is_kept() {
    // whole lines until the room left is less than one more; then a line that takes exactly
    // that room (its record and an overrun record's reserve), then one that does not fit
    let mut rx = RxLines::new();
    let text = [b'a'; 100];
    let n = (RX_RING - OVERRUN_RECORD) / (text.len() + 2);
    send_lines(&mut rx, &text, n);
    let free = RX_RING - n * (text.len() + 2);
    let fits = vec![b'b'; free - 2 - OVERRUN_RECORD];
    line(&mut rx, &fits);
    line(&mut rx, b"\n");
    line(&mut rx, b"c\n");
    for _ in 0..n {
        assert!(matches!(rx.pop(), Some(Record::Line(v)) if v[..] == text[..]));
    }
    assert!(matches!(rx.pop(), Some(Record::Line(v)) if v[..] == fits[..]), "the line that fits");
    assert_eq!(rx.pop(), Some(Record::Overrun(1)));
    assert_eq!(rx.pop(), None);
}

/// `stop` flushes: the lines queued ahead of it (whole, too long or lost) become one
/// stopped record of their count, in their place; the lines after it queue as before.
#[test]
fn rx_stop_drops_every_line_queued_ahead_of_it() {
    let mut rx = RxLines::new();
    line(&mut rx, b"arm\nvolt all 3000\n");
    line(&mut rx, &[b'x'; LINE_MAX + 1]);
    line(&mut rx, b"\n");
    rx.overrun();
    line(&mut rx, b"volt 1 5\n");
    line(&mut rx, b"  \n"); // blank: nothing queued, nothing to answer
    assert_eq!(line(&mut rx, b"stop\n"), RxEvent::Stop);
    line(&mut rx, b"status\n");
    assert_eq!(rx.pop(), Some(Record::Stopped(4)));
    assert!(matches!(rx.pop(), Some(Record::Line(v)) if &v[..] == b"status"));
    assert_eq!(rx.pop(), None);
    // nothing queued: a stop leaves nothing to answer
    assert_eq!(line(&mut rx, b"stop\n"), RxEvent::Stop);
    assert_eq!(rx.pop(), None);
    assert!(!rx.pending());
    // two stops before the command side takes anything: one record of every line before the second
    line(&mut rx, b"arm\n");
    line(&mut rx, b"stop\n");
    line(&mut rx, b"arm\nvolt 1 5\n");
    line(&mut rx, b"stop\n");
    assert_eq!(rx.pop(), Some(Record::Stopped(3)));
    assert_eq!(rx.pop(), None);
    // a record taken before the stop is the command side's: only the rest is dropped
    line(&mut rx, b"pose 1 2 3\narm\n");
    assert!(matches!(rx.pop(), Some(Record::Line(v)) if &v[..] == b"pose 1 2 3"));
    line(&mut rx, b"stop\n");
    assert_eq!(rx.pop(), Some(Record::Stopped(1)));
    // the count drops with what is taken: a later stop counts only what is queued then
    line(&mut rx, b"a\nb\n");
    assert!(rx.pop().is_some());
    line(&mut rx, b"stop\n");
    assert_eq!(rx.pop(), Some(Record::Stopped(1)));
}

/// A full ring and an open overrun record, flushed: every line they stood for is counted
/// once, and the ring takes whole lines again at once.
#[test]
fn rx_stop_flushes_a_full_ring_with_its_overruns() {
    let mut rx = RxLines::new();
    let text = [b'a'; 100];
    let fits = (RX_RING - OVERRUN_RECORD) / (text.len() + 2);
    send_lines(&mut rx, &text, fits + 300);
    assert_eq!(line(&mut rx, b"STOP now\n"), RxEvent::Stop);
    send_lines(&mut rx, &text, fits);
    assert_eq!(rx.pop(), Some(Record::Stopped(fits as u32 + 300)));
    for _ in 0..fits {
        assert!(matches!(rx.pop(), Some(Record::Line(v)) if v[..] == text[..]));
    }
    assert_eq!(rx.pop(), None);
}

#[test]
fn the_stacks_floor_plain_and_shaped() {
    use finger_fw::control::Stacks;
    let st = Stacks::board().unwrap();
    let law = finger_fw::board::board_law().unwrap();
    let v = 0.5 * st.hold_ceiling_v();
    let s_v = finger_model::material::equilibrium_ratio(&law, v).unwrap();
    assert!(s_v > st.s_hold());
    // plain: the board's floor whatever the target; shaped: the target's own equilibrium
    assert_eq!(st.floor(v, false), Some(st.s_hold()));
    assert_eq!(st.floor(v, true), Some(s_v));
    assert_eq!(st.floor(2.0 * st.hold_ceiling_v(), true), None, "past the hold ceiling");
}

/// The read-back's thickness guard compares the film's equilibrium voltage at the model's and
/// at the measured stretch (`Stacks::equilibrium_voltage_at`); a wrong one hides a soft film.
#[test]
fn the_stacks_equilibrium_voltage_is_the_cards() {
    use finger_fw::control::Stacks;
    let st = Stacks::board().unwrap();
    let law = finger_fw::board::board_law().unwrap();
    let hold = st.hold_ceiling_v();
    // the hold's own stretch gives back the voltage that holds it, within f32's rounding
    let at_hold = st.equilibrium_voltage_at(st.s_hold());
    assert!((at_hold - finger_model::material::equilibrium_voltage(&law, st.s_hold()).unwrap()).abs() <= 1e-3 * hold);
    assert!(at_hold >= hold * 0.9 && at_hold.is_finite(), "{at_hold} V for s_hold (hold ceiling {hold} V)");
    // thinner film, higher voltage; the unstretched film holds at 0 V
    let at_mid = st.equilibrium_voltage_at(0.5 * (1.0 + st.s_hold()));
    assert!(at_mid > 0.0 && at_mid < at_hold, "{at_mid} V between 0 and {at_hold} V");
    assert!(st.equilibrium_voltage_at(1.0).abs() < 1e-3);
    // past the film's reach: no voltage holds it
    assert_eq!(st.equilibrium_voltage_at(f32::NAN), f32::INFINITY);
}

/// The read-back solves a swing's charge for the capacitance with the film's dQ/dV over Q/V
/// (`Stacks::incremental_capacitance_ratio`): 1 at rest, above 1 on a thinned film. A wrong
/// ratio reads a held film thicker or thinner than it is.
#[test]
fn the_stacks_incremental_capacitance_ratio_follows_the_film() {
    use finger_fw::control::Stacks;
    let mut st = Stacks::board().unwrap();
    let target = 0.8 * st.hold_ceiling_v();
    let mut v = 0.0;
    for _ in 0..20_000 {
        v = st.step(0, v, target, st.s_hold(), false, 100.0, target).unwrap();
    }
    assert_eq!(v, target);
    let s = st.ratios()[0];
    assert!(s < 1.0, "the held film thinned: {s}");
    // channel 0 held and thinned; channel 1 at rest
    let r = st.incremental_capacitance_ratio(0);
    assert!(r > 1.0 && r.is_finite(), "{r}");
    assert!((st.incremental_capacitance_ratio(1) - 1.0).abs() < 1e-6, "at rest: {}", st.incremental_capacitance_ratio(1));
}

// The Cortex-M3 image's step (`Stacks::step` under `cfg(m3)`) is `plain_slew_step`: the host
// never builds that image, so its arithmetic is checked here, one rule a test.

#[test]
fn m3_step_slews_up_by_one_step() {
    assert_eq!(plain_slew_step(0.0, 1_000.0, 20.0), 20.0);
    assert_eq!(plain_slew_step(100.0, 1_000.0, 20.0), 120.0);
}

#[test]
fn m3_step_slews_down_by_one_step() {
    assert_eq!(plain_slew_step(1_000.0, 100.0, 20.0), 980.0);
    assert_eq!(plain_slew_step(1_000.0, 0.0, 20.0), 980.0);
}

#[test]
fn m3_step_stops_at_the_target() {
    assert_eq!(plain_slew_step(990.0, 1_000.0, 20.0), 1_000.0, "up, within a step");
    assert_eq!(plain_slew_step(110.0, 100.0, 20.0), 100.0, "down, within a step");
    assert_eq!(plain_slew_step(1_000.0, 1_000.0, 20.0), 1_000.0, "at the target");
    // from rest to the target in whole steps, then held there
    let mut v = 0.0;
    for _ in 0..60 {
        v = plain_slew_step(v, 1_000.0, 20.0);
    }
    assert_eq!(v, 1_000.0);
}

#[test]
fn m3_step_is_never_negative() {
    assert_eq!(plain_slew_step(10.0, 0.0, 20.0), 0.0, "a step past 0 V ends at 0 V");
    assert_eq!(plain_slew_step(10.0, -500.0, 20.0), 0.0, "a negative target");
    assert_eq!(plain_slew_step(-50.0, -100.0, 20.0), 0.0, "a negative start");
    // the floor is +0 V: `status` never shows -0.0
    let v = plain_slew_step(0.0, -0.0, 20.0);
    assert!(v == 0.0 && v.is_sign_positive(), "{v}");
}

#[test]
fn m3_step_of_zero_holds_the_voltage() {
    assert_eq!(plain_slew_step(500.0, 1_000.0, 0.0), 500.0);
    assert_eq!(plain_slew_step(500.0, 100.0, 0.0), 500.0);
    assert_eq!(plain_slew_step(0.0, 1_000.0, 0.0), 0.0);
}

#[test]
fn m3_step_is_never_nan() {
    let n = f32::NAN;
    assert_eq!(plain_slew_step(n, n, 20.0), 0.0, "nothing known: 0 V");
    for (v, t, s) in [(n, 1_000.0, 20.0), (500.0, n, 20.0), (500.0, 1_000.0, n), (n, n, n), (500.0, 100.0, n)] {
        let out = plain_slew_step(v, t, s);
        assert!(out >= 0.0, "({v}, {t}, {s}) -> {out}");
    }
}
