//! Regenerates docs/firmware.md's real-time figures (between the `realtime-report` markers)
//! from the emulator image in QEMU (`-icount shift=0`): the firmware's own `timing` reply
//! (control-tick period and latency, stop time in the console interrupt, worst command
//! durations) and the register trace (stop latency in control ticks, largest duty step per
//! tick). Every figure in that section comes from this run.
//!   cd host-tests && cargo run --release --example realtime_report
use host_tests::qemu::{duties_per_tick, hv_full_scale, max_step, stop_latencies, Qemu};

/// The value of `k=` in a reply; "-" where it has none.
fn kv<'a>(r: &'a str, k: &str) -> &'a str {
    host_tests::reply::find(r, k).unwrap_or("-")
}

fn main() {
    let mut q = Qemu::boot_traced(host_tests::image::Image::M4f, "report");
    let arm = |q: &mut Qemu| {
        assert_eq!(q.cmd("arm"), "ok armed=1");
        assert!(q.cmd("volt all 3000").starts_with("ok"));
        assert_eq!(q.cmd("wait 1"), "ok waited=1");
    };
    // stop during the first armed pose (the branch-table build), during help, during wait 600
    arm(&mut q);
    q.write(b"pose 9.58 11.04 12.84\r\nstop\r\n");
    q.finals(2);
    arm(&mut q);
    q.write(b"help\r\nstop\r\n");
    q.finals(2);
    arm(&mut q);
    q.write(b"wait 600\r\n");
    std::thread::sleep(std::time::Duration::from_millis(300));
    q.write(b"stop\r\n");
    q.finals(2);
    // a ramp at 100 kV/s while the long commands run
    assert_eq!(q.cmd("param slew 100000"), "ok slew=100000");
    assert_eq!(q.cmd("arm"), "ok armed=1");
    q.write(b"volt 1 5000\r\nhelp\r\nparam\r\npose 7.08 8.15 9.47\r\nforce 0.3\r\ncontact 1 1.5\r\nlimits\r\nsolve 0.5 0 1000 2000\r\nstatus\r\nversion\r\n");
    q.finals(10);
    // setpoints whose fmax is not cached yet: volt and force with a tension, limits
    q.write(b"volt all 2000\r\nforce 0.5\r\nvolt 2 4000\r\nlimits\r\n");
    q.finals(4);
    assert_eq!(q.cmd("wait 0.2"), "ok waited=0.2");
    let t = q.cmd("timing");
    assert!(t.starts_with("ok tick_period_us="), "{t}");
    let trace = q.finish();

    let stops = stop_latencies(&trace);
    let worst_ticks = stops.iter().map(|s| s.0).max().unwrap_or(0);
    let fs = hv_full_scale(&trace);
    // slew steps: a rise is bounded by the slew; a fall (a lowered setpoint, the voltage loop,
    // a derate) is shown apart, a stop (all duties to 0 at once) is neither
    let ticks: Vec<[u64; 3]> = duties_per_tick(&trace);
    let moves = |up: bool| {
        ticks
            .windows(2)
            .filter(|w| w[1] != [0; 3])
            .flat_map(|w| (0..3).map(move |c| if up { w[1][c].saturating_sub(w[0][c]) } else { w[0][c].saturating_sub(w[1][c]) }))
            .max()
            .unwrap_or(0)
    };
    let (rise, fall) = (moves(true), moves(false));
    let bound = 100 * fs / 10_000 + 1;
    if let Some((i, w)) = ticks.windows(2).enumerate().find(|(_, w)| w[1] != [0; 3] && max_step(w) > bound) {
        eprintln!("realtime_report: a duty step past the slew's bound at tick {i}: {:?} -> {:?}", w[0], w[1]);
    }
    let period: Vec<&str> = kv(&t, "tick_period_us").split(',').collect();
    let lat: Vec<&str> = kv(&t, "tick_latency_us").split(',').collect();
    let mut cmds: Vec<(String, f64)> =
        kv(&t, "cmd_us").split(',').filter_map(|e| e.split_once(':')).map(|(w, us)| (w.to_string(), us.parse().unwrap_or(0.0))).collect();
    cmds.sort_by(|a, b| b.1.partial_cmp(&a.1).unwrap());
    let mut s = String::new();
    s.push_str("<!-- realtime-report:begin (cd host-tests && cargo run --release --example realtime_report) -->\n");
    s.push_str("QEMU netduinoplus2, `-icount shift=0` (1 instruction = 1 ns of virtual time; SysTick at 168 MHz); the\n");
    s.push_str("firmware's own `timing` reply and the register trace of one run (3 stops, a 100 kV/s ramp under load).\n");
    s.push_str("QEMU takes an interrupt at the instruction boundary where it is raised, so its entry jitter is ~0;\n");
    s.push_str("on the board, add the M4's 12-cycle entry and flash wait states. Durations scale to the board as\n");
    s.push_str("instructions at 168 MHz (x ~6).\n\n");
    s.push_str("| figure | value |\n| --- | --- |\n");
    s.push_str(&format!("| control-tick period (entry to entry), min / max | {} / {} us |\n", period[0], period.get(1).unwrap_or(&"-")));
    s.push_str(&format!("| control-task entry after the SysTick reload (jitter), min / max | {} / {} us |\n", lat[0], lat.get(1).unwrap_or(&"-")));
    s.push_str(&format!("| control-task run time, max | {} us |\n", kv(&t, "tick_run_us")));
    // 1 instruction = 1 ns under -icount shift=0
    let stack_us: f64 = kv(&t, "tick_stack_us").parse().unwrap_or(f64::NAN);
    s.push_str(&format!(
        "| the stacks in time, one channel's step in a tick (goal, slew, guard, thickness, relaxation), max | {stack_us:.3} us = {:.0} M4F instructions |\n",
        stack_us * 1000.0
    ));
    let (sense_us, source_us): (f64, f64) = (kv(&t, "tick_sense_us").parse().unwrap_or(f64::NAN), kv(&t, "tick_source_us").parse().unwrap_or(f64::NAN));
    s.push_str(&format!(
        "| the HV read-back's work in a tick (three channels' estimate, checks, thickness guard, voltage loop), max | {sense_us:.3} us = {:.0} M4F instructions |\n",
        sense_us * 1000.0
    ));
    s.push_str(&format!("| the emulator's plant stepped in a tick (no part of the board's cost; its ADC averages replace it), max | {source_us:.3} us |\n"));
    s.push_str(&format!("| control ticks counted | {} |\n", kv(&t, "ticks")));
    s.push_str(&format!("| stop: console interrupt entry to HV off, max ({} stops) | {} us |\n", kv(&t, "stops"), kv(&t, "stop_us")));
    s.push_str(&format!("| stop: control ticks between the stop line's last byte and all duties 0 (trace), worst | {worst_ticks} |\n"));
    s.push_str(&format!("| largest HV duty rise per tick at 100 kV/s (trace; bound 100 V = {} counts of {fs}, + 1) | {rise} counts |\n", 100 * fs / 10_000));
    s.push_str(&format!("| largest HV duty fall per tick, a stop's aside (trace; a fall is not slew-bound) | {fall} counts |\n"));
    s.push_str("\nWorst command durations (the command side running the line, model solves included; replies are\n");
    s.push_str("queued, not waited for, unless the 2 KiB transmit queue is full; the control core takes the\n");
    s.push_str("setpoints at its next tick, within 1 ms):\n\n| command | worst |\n| --- | --- |\n");
    for (w, us) in &cmds {
        s.push_str(&format!("| `{w}` | {:.2} ms |\n", us / 1000.0));
    }
    s.push_str("<!-- realtime-report:end -->\n");
    host_tests::report::write_section("docs/firmware.md", "realtime-report", &s);
    print!("{s}");
}
