//! The real-time core on the simulated board in virtual time
//! (`finger_fw::sim::VirtualSim`): commands take time, the control core ticks every 1 ms
//! meanwhile, bytes arrive at 115200 baud. The properties the chip's RTIC core gives, shown
//! here quickly: the slew bound per tick whatever runs, `stop` within one tick whatever runs,
//! one reply per line of a burst, overruns answered, the watchdog starved by a stuck command.
use finger_fw::control::{hv_duty_for, Control, Setpoints, CHECKIN_BOUND_MS};
use finger_fw::sim::{default_cost, SimBoard, VirtualSim};
use finger_fw::App;

struct Out(String);
impl std::fmt::Write for Out {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.0.push_str(s);
        Ok(())
    }
}

fn finals(text: &str) -> Vec<&str> {
    text.lines().filter(|l| l.starts_with("ok") || l.starts_with("err ")).collect()
}

/// Run the sim until idle; every tick's (t_us, duties, enable, servo, watchdog feeds).
fn run(sim: &mut VirtualSim, out: &mut Out) -> Vec<(u64, [u16; 3], bool, u16, u64)> {
    let mut ticks = Vec::new();
    sim.run_idle(3_600_000_000, out, &mut |a: &App<SimBoard>, t| {
        let b = a.board();
        ticks.push((t, b.hv.map(|h| h.duty), b.enable.high, b.servo.duty, b.watchdog_feeds));
    });
    ticks
}

fn line(sim: &mut VirtualSim, out: &mut Out, l: &str) -> String {
    assert!(sim.send(format!("{l}\n").as_bytes()));
    run(sim, out);
    finals(&out.0).last().unwrap().to_string()
}

/// The largest duty step between consecutive ticks, any channel.
fn max_step(ticks: &[(u64, [u16; 3], bool, u16, u64)]) -> u16 {
    ticks.windows(2).flat_map(|w| (0..3).map(move |c| w[0].1[c].abs_diff(w[1].1[c]))).max().unwrap_or(0)
}

#[test]
fn slew_bound_holds_per_tick_while_long_commands_run() {
    let mut sim = VirtualSim::new(default_cost);
    let mut out = Out(String::new());
    assert_eq!(line(&mut sim, &mut out, "param slew 100000"), "ok slew=100000");
    assert_eq!(line(&mut sim, &mut out, "arm"), "ok armed=1");
    // the ramp, with help, param, pose, force and contact queued behind it (the case of a command queue behind a ramp)
    let t0 = sim.t_us;
    assert!(sim.send(b"volt 1 5000\nhelp\nparam\npose 10 10 10\nforce 0.3\ncontact 1 1.5\nvolt 2 5000\nhelp\n"));
    let ticks = run(&mut sim, &mut out);
    assert_eq!(finals(&out.0).len(), 2 + 8, "{}", out.0);
    // 100 V per 1 ms tick at 10 kV full scale, 8400 counts: 84 counts, +1 for rounding
    let bound = hv_duty_for(100.0, 8400) + 1;
    let step = max_step(&ticks);
    assert!(step <= bound, "largest step {step} > {bound}");
    assert!(step >= bound - 2, "the ramp ran at the slew rate ({step})");
    // the commands took virtual time meanwhile (the ramp ran during them)
    assert!(sim.t_us - t0 > 50_000, "{}", sim.t_us - t0);
    // consecutive ticks 1 ms apart
    assert!(ticks.windows(2).all(|w| w[1].0 - w[0].0 == 1000));
}

/// `stop` sent while `busy` runs: the duties are 0 and the enable low at the first tick
/// after the stop's line ends, and stay so after the running command ends.
fn stop_during(setup: &[&str], busy: &str, delay_us: u64) -> (u64, String) {
    let mut sim = VirtualSim::new(default_cost);
    let mut out = Out(String::new());
    for l in setup {
        let r = line(&mut sim, &mut out, l);
        assert!(r.starts_with("ok"), "{l} -> {r}");
    }
    assert!(sim.board_duties_nonzero(), "HV on before the stop");
    assert!(sim.send(format!("{busy}\n").as_bytes()));
    let t = sim.t_us + delay_us;
    sim.run_until(t, &mut out, &mut |_, _| {});
    assert!(sim.command_running() || sim.app.busy(), "{busy} still running when stop is sent");
    assert!(sim.send(b"stop\n"));
    let stop_end = sim.t_us + (5.0 * finger_fw::sim::BYTE_US).ceil() as u64;
    let ticks = run(&mut sim, &mut out);
    let after: Vec<_> = ticks.iter().filter(|t| t.0 >= stop_end).collect();
    assert!(!after.is_empty());
    let first = after[0];
    assert!(first.0 - stop_end <= 1000, "first tick within 1 ms");
    for t in &after {
        assert_eq!(t.1, [0; 3], "duties at {} us", t.0);
        assert!(!t.2, "enable at {} us", t.0);
    }
    assert!(out.0.lines().any(|l| l == "ok stopped"), "{}", out.0);
    (first.0 - stop_end, out.0)
}

impl VirtualSimExt for VirtualSim {
    fn board_duties_nonzero(&self) -> bool {
        self.app.board().hv.iter().all(|h| h.duty > 0)
    }
}
trait VirtualSimExt {
    fn board_duties_nonzero(&self) -> bool;
}

#[test]
fn stop_acts_within_one_tick_during_wait_table_build_and_help() {
    let setup = ["arm", "volt all 3000", "wait 2"];
    let (_, text) = stop_during(&setup, "wait 600", 20_000);
    // the wait ended early (input), and says so
    assert!(text.lines().any(|l| l.starts_with("ok waited=") && l.ends_with(" early=input")), "{text}");
    // the first armed pose builds the branch table: its setpoints, planned before the stop,
    // are dropped when it ends
    let (_, text) = stop_during(&setup, "pose 10 10 10", 5_000);
    assert!(text.lines().any(|l| l.starts_with("ok force=")), "{text}");
    stop_during(&setup, "help", 30_000);
}

/// `arm`, `volt all 3000`, `stop` pasted at once behind a command that takes time: the stop
/// drops the two lines queued ahead of it, so nothing re-arms the board after the stop. The
/// replies: `ok stopped` at once, the running command's own reply, then `err stopped` for
/// each dropped line, in the order sent; a line after the stop runs.
#[test]
fn stop_drops_the_lines_queued_ahead_of_it() {
    let mut sim = VirtualSim::new(default_cost);
    let mut out = Out(String::new());
    assert!(sim.send(b"limits\narm\nvolt all 3000\nstop\n"));
    let ticks = run(&mut sim, &mut out);
    assert!(!sim.app.armed() && !sim.app.hv_enabled(), "{}", out.0);
    assert_eq!(sim.app.targets(), [0.0; 3]);
    assert!(ticks.iter().all(|t| t.1 == [0; 3] && !t.2), "HV on after the paste");
    let f = finals(&out.0);
    assert_eq!(f.len(), 4, "{}", out.0);
    assert_eq!(f[0], "ok stopped");
    assert!(f[1].starts_with("ok vmax="), "{f:?}");
    assert!(f[2..].iter().all(|l| l.starts_with("err stopped: ")), "{f:?}");
    assert!(line(&mut sim, &mut out, "arm").starts_with("ok armed=1"), "a line after the stop runs");
}

#[test]
fn stop_first_word_any_case_any_arguments() {
    let mut a = App::new(SimBoard::default());
    let mut out = Out(String::new());
    for l in ["arm\n", "volt all 3000\n", "wait 1\n"] {
        a.input(l.as_bytes(), &mut out);
        while a.busy() {
            a.tick(1, &mut out);
        }
    }
    assert!(a.board().hv.iter().all(|h| h.duty > 0));
    out.0.clear();
    a.input(b"  StOp right now please\n", &mut out);
    assert_eq!(out.0, "ok stopped\n");
    assert_eq!(a.board().hv.map(|h| h.duty), [0; 3]);
    out.0.clear();
    a.input(b"stopx\n", &mut out);
    assert!(out.0.starts_with("err unknown:"), "{}", out.0);
}

#[test]
fn burst_of_200_lines_gets_one_reply_each() {
    let mut sim = VirtualSim::new(default_cost);
    let mut out = Out(String::new());
    let cmds = ["version", "status", "solve 0.5 0 1000 2000", "bogus", "limits", "param l", "help", "solve nan 0 0 0"];
    let burst: String = (0..200).map(|i| format!("{}\n", cmds[i % cmds.len()])).collect();
    assert!(sim.send(burst.as_bytes()));
    run(&mut sim, &mut out);
    let f = finals(&out.0);
    assert_eq!(f.len(), 200, "{}", out.0);
    for (i, r) in f.iter().enumerate() {
        let c = cmds[i % cmds.len()];
        let want = match c {
            "bogus" => "err unknown:",
            "solve nan 0 0 0" => "err bad-number:",
            "version" => "ok version=",
            "status" => "ok armed=",
            _ => "ok",
        };
        assert!(r.starts_with(want), "line {i} {c} -> {r}");
    }
}

/// Slower than the wire: lines past the ring's room are lost whole and answered `err
/// overrun`; still one final reply per line, in order.
#[test]
fn ring_overrun_discards_whole_lines_and_answers_err() {
    fn slow(_: &[u8], _: usize) -> u64 {
        2_000_000
    }
    let mut sim = VirtualSim::new(slow);
    let mut out = Out(String::new());
    let burst: String = (0..600).map(|_| "version\n").collect();
    assert!(sim.send(burst.as_bytes()));
    run(&mut sim, &mut out);
    let f = finals(&out.0);
    assert_eq!(f.len(), 600, "{:?}", f.iter().filter(|l| !l.starts_with("ok version")).collect::<Vec<_>>());
    let lost = f.iter().filter(|l| l.starts_with("err overrun:")).count();
    assert!(lost > 0 && lost < 600, "{lost}");
    assert!(f.iter().all(|l| l.starts_with("ok version=") || l.starts_with("err overrun:")));
}

#[test]
fn uart_overrun_discards_the_partial_line() {
    let mut a = App::new(SimBoard::default());
    let mut out = Out(String::new());
    a.input(b"arm\n", &mut out);
    a.input(b"volt 1 1", &mut out);
    a.input_overrun(); // bytes lost here
    a.input(b"00\nversion\n", &mut out);
    let f: Vec<_> = finals(&out.0);
    assert_eq!(f.len(), 3, "{}", out.0);
    assert!(f[1].starts_with("err overrun:"), "{}", out.0);
    assert!(f[2].starts_with("ok version="));
    assert_eq!(a.targets(), [0.0; 3], "the broken line's tail is not executed");
}

#[test]
fn wait_ends_early_on_input_and_says_so() {
    let mut sim = VirtualSim::new(default_cost);
    let mut out = Out(String::new());
    assert!(sim.send(b"wait 5\n"));
    let t = sim.t_us + 100_000;
    sim.run_until(t, &mut out, &mut |_, _| {});
    assert!(sim.app.busy());
    assert!(sim.send(b"version\n"));
    run(&mut sim, &mut out);
    let f = finals(&out.0);
    assert!(f[0].starts_with("ok waited=0.") && f[0].ends_with(" early=input"), "{f:?}");
    assert!(f[1].starts_with("ok version="));
    assert!(sim.t_us < 1_000_000);
}

/// A command stuck past the check-in bound starves the watchdog; it is fed again after.
#[test]
fn watchdog_fed_only_while_the_command_side_checks_in() {
    fn stuck_solve(line: &[u8], _: usize) -> u64 {
        if line.starts_with(b"solve") {
            2_000_000
        } else {
            0
        }
    }
    let mut sim = VirtualSim::new(stuck_solve);
    let mut out = Out(String::new());
    assert!(sim.send(b"solve 0.5 0 0 0\nversion\n"));
    let ticks = run(&mut sim, &mut out);
    let feeds_at = |ms: u64| ticks.iter().find(|t| t.0 >= ms * 1000).unwrap().4;
    let bound = CHECKIN_BOUND_MS as u64;
    // fed in the first `bound` ms of the solve, then not until it ends
    assert!(feeds_at(bound - 10) >= bound - 20);
    assert_eq!(feeds_at(bound + 20), feeds_at(1_900), "fed while the command side was stuck");
    let last = ticks.last().unwrap().4;
    assert!(last > feeds_at(1_900) || ticks.last().unwrap().0 < 2_010_000);
}

/// The servo moves with the slewed voltages: in proportion to the ramp's progress, not at once.
#[test]
fn servo_follows_the_slewed_voltages() {
    use finger_model::Method;
    let mut a = App::new(SimBoard::default());
    let mut out = Out(String::new());
    // a fine servo scale (2000 counts over 20 deg) and 5 kV (the excursion of a few
    // counts), so the excursion's change shows
    for l in ["param slew 2000\n", "param spool_r 5\n", "param servo_range 20\n", "arm\n", "force 0.4\n"] {
        a.input(l.as_bytes(), &mut out);
    }
    let s0 = a.board().servo.duty;
    a.input(b"volt all 5000\n", &mut out);
    assert_eq!(a.board().servo.duty, s0, "no jump before the voltages move");
    let mut servo = vec![s0];
    let mut mid_v = 0.0;
    for t in 0..4000 {
        a.tick(1, &mut out);
        servo.push(a.board().servo.duty);
        if t + 1 == 2000 {
            mid_v = a.volts()[0];
        }
    }
    let s1 = *servo.last().unwrap();
    assert!(s1.abs_diff(s0) >= 4, "{s0} -> {s1}: {}", out.0);
    // 80 % through the ramp, the servo 80 % of its way (in proportion to the ramp's
    // progress: the film creeps, so the excursion is no function of the voltage alone)
    assert!((mid_v - 4000.0).abs() < 10.0, "{mid_v}");
    let e = |v: f32| a.finger().solve(0.4, &[v; 3], Method::converged()).unwrap().cable_excursion as f64;
    assert!(e(5000.0) > e(0.0), "the stacks thin at 5 kV");
    let frac = mid_v as f64 / 5000.0;
    let mid = servo[2000] as f64;
    let want = s0 as f64 + (s1 as f64 - s0 as f64) * frac;
    // (s0, s1 and mid each rounded to a count)
    assert!((mid - want).abs() <= 1.5, "{mid} vs {want}");
    let steps = servo.windows(2).map(|w| w[0].abs_diff(w[1])).max().unwrap();
    assert!(steps <= 1 + (s1.abs_diff(s0) / 4000 + 1), "servo step {steps}");
}

fn setpoints(target: [f32; 3]) -> Setpoints {
    Setpoints { seq: 1, epoch: 0, armed: true, target_v: target, servo_duty: 2000, servo_released: 2000, duty_ceiling: [8400; 3], slew: 2000.0, shaped: false }
}

/// The control core refuses targets that are not finite or past the ceiling (the command
/// side's, the board's hold ceiling, the compiled limit), plain or shaped, whatever the command
/// side sends; HV stays off.
#[test]
fn control_core_refuses_non_finite_and_past_ceiling_targets() {
    let hold = Control::new(SimBoard::default(), 2000, 2000.0).hold_ceiling_v();
    assert!(hold > 1000.0 && hold < 10_000.0, "{hold}");
    let past_hold = f32::from_bits(hold.to_bits() + 1);
    for (bad, shaped) in [(f32::NAN, false), (f32::INFINITY, false), (-1.0, false), (10_001.0, false), (past_hold, false), (past_hold, true), (9990.0, true)] {
        let mut c = Control::new(SimBoard::default(), 2000, 2000.0);
        c.apply(&Setpoints { shaped, ..setpoints([bad, 0.0, 0.0]) });
        for _ in 0..10 {
            c.tick(c.now_ms());
        }
        assert_eq!(c.view().fault, Some("hv-refused"), "{bad}");
        assert!(!c.board().enable.high && c.board().hv.iter().all(|h| h.duty == 0), "{bad}");
    }
    // a ceiling from the command side tightens; nothing above it is written
    let mut c = Control::new(SimBoard::default(), 2000, 2000.0);
    let mut sp = setpoints([1000.0, 0.0, 0.0]);
    sp.duty_ceiling = [hv_duty_for(500.0, 8400); 3];
    c.apply(&sp);
    assert_eq!(c.view().fault, Some("hv-refused"));
}

/// A stale command (planned before a stop) cannot re-arm.
#[test]
fn setpoints_planned_before_a_stop_are_dropped() {
    let mut c = Control::new(SimBoard::default(), 2000, 2000.0);
    assert!(c.apply(&setpoints([1000.0; 3])));
    c.stop();
    assert!(!c.apply(&setpoints([1000.0; 3])), "epoch 0 is stale after the stop");
    for _ in 0..100 {
        c.tick(c.now_ms());
    }
    assert!(!c.board().enable.high && c.board().hv.iter().all(|h| h.duty == 0));
}

/// The emulator image on a real chip: locked out, never arms, a stop does not clear it.
#[test]
fn locked_out_core_never_arms() {
    let mut c = Control::new(SimBoard::default(), 2000, 2000.0);
    c.lock_out(finger_fw::control::Fault::EmulatorOnChip);
    c.stop();
    let mut sp = setpoints([1000.0; 3]);
    sp.epoch = c.view().epoch;
    c.apply(&sp);
    for _ in 0..100 {
        c.tick(c.now_ms());
    }
    assert!(!c.board().enable.high_ever && c.board().hv.iter().all(|h| h.duty == 0));
    assert_eq!(c.view().fault, Some("qemu image on a real chip"));
    // the command side says why `arm` is refused
    let mut cmds = finger_fw::Commands::new("qemu", "\n", [8400; 3], 40_000);
    cmds.sync(&c.view());
    let mut out = Out(String::new());
    cmds.execute(b"arm", &mut out);
    assert_eq!(out.0, "err fault: qemu image on a real chip: this image never arms here\n");
}

/// A clock read across SysTick's reload runs backwards (its count within the millisecond starts
/// again): the emulator under the wall clock does that inside a tick. Each reading here is
/// 1000 counts before the last.
static BACKWARDS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(1_000_000);
fn backwards_clock() -> u32 {
    BACKWARDS.fetch_sub(1000, std::sync::atomic::Ordering::Relaxed)
}

#[test]
fn a_tick_timed_across_a_clock_wrap_costs_no_impossible_time() {
    // with the plant, so the read-back and its source are timed too
    let plant = finger_fw::plant::Plant::new(1).unwrap();
    let mut c = Control::new(SimBoard::with_plant(plant), 2000, 2000.0);
    for _ in 0..5 {
        let cost = c.tick_timed(c.now_ms(), backwards_clock);
        // was 2^32 - 1000 (25,565,275 µs at 168 MHz): a u32 difference that wrapped
        for (what, counts) in [("stack_step", cost.stack_step), ("read_back", cost.read_back), ("sense_source", cost.sense_source)] {
            assert!(counts < 168_000, "{what} = {counts} counts across a wrap");
        }
    }
}
