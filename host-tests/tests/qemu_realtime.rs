//! The real-time core (issue 12) in QEMU netduinoplus2 with `-icount shift=0`, shown from the
//! registers (the register trace, host_tests::qemu), not from the console's own report:
//! - the largest HV duty step per control tick over a ramp while help, param, pose, force and
//!   contact run is at most slew x 1 ms + 1 count;
//! - a `stop` sent during `wait 600`, during the branch-table build (the first armed `pose`)
//!   and in the middle of the `help` output zeroes the duties within one tick, and nothing
//!   planned before it writes a duty after it;
//! - each line of a 200-line burst sent at once gets exactly one reply;
//! - right after reset, the first register writes drive the HV pins low (GPIOB clock on first).
use host_tests::qemu::{duties_per_tick, hv_full_scale, max_step, stop_latencies, Qemu, TIM4_CCR};

#[test]
fn duty_step_per_tick_within_slew_while_commands_run() {
    let mut q = Qemu::boot("ramp");
    assert_eq!(q.cmd("param slew 100000"), "ok slew=100000");
    assert_eq!(q.cmd("arm"), "ok armed=1");
    q.write(b"volt 1 9000\r\nhelp\r\nparam\r\npose 10 10 10\r\nforce 0.3\r\ncontact 1 1.5\r\nvolt 2 9000\r\n");
    let lines = q.finals(7);
    assert!(lines.iter().any(|l| l.starts_with("ok force=")), "{lines:?}");
    assert_eq!(q.cmd("wait 0.2"), "ok waited=0.2");
    let trace = q.finish();
    let ticks = duties_per_tick(&trace);
    let fs = hv_full_scale(&trace);
    // 100 V per tick at 10 kV full scale, rounded down, + 1
    let bound = 100 * fs / 10_000 + 1;
    let step = max_step(&ticks);
    assert!(step <= bound, "largest duty step per tick {step} > {bound} (full scale {fs})");
    assert!(step + 2 >= bound, "the ramp ran at the slew rate: {step}");
    // channel 2 ramped to 9 kV one slewed step at a time (pose set channel 1 on the way)
    let last = ticks.last().unwrap();
    assert_eq!(last[1], 9000 * fs / 10_000, "{last:?}");
    let moving = ticks.windows(2).filter(|w| w[0][1] != w[1][1]).count() as u64;
    assert!(moving >= 9000 * fs / 10_000 / bound, "{moving} ticks of ramp");
}

fn armed_at_3kv(q: &mut Qemu) {
    assert_eq!(q.cmd("arm"), "ok armed=1");
    assert!(q.cmd("volt all 3000").starts_with("ok volts="));
    assert_eq!(q.cmd("wait 2"), "ok waited=2");
}

fn assert_stopped_within_a_tick(trace: &[host_tests::qemu::Access], what: &str) {
    let s = stop_latencies(trace);
    assert_eq!(s.len(), 1, "{what}: {s:?}");
    let (ticks, later) = s[0];
    assert!(ticks <= 1, "{what}: stop took {ticks} ticks");
    assert!(!later, "{what}: a duty was written non-zero after the stop");
    // the duties were non-zero before it
    assert!(trace.iter().any(|a| a.write && a.addr == TIM4_CCR[0] && a.value > 0), "{what}");
}

#[test]
fn stop_within_one_tick_during_wait_table_build_and_help() {
    // during `wait 600`
    let mut q = Qemu::boot("wait");
    armed_at_3kv(&mut q);
    q.write(b"wait 600\r\n");
    std::thread::sleep(std::time::Duration::from_millis(300));
    q.write(b"stop\r\n");
    let r = q.finals(2);
    assert!(r.iter().any(|l| l == "ok stopped"), "{r:?}");
    assert!(r.iter().any(|l| l.starts_with("ok waited=") && l.ends_with("early=input")), "{r:?}");
    let s = q.cmd("status");
    assert!(s.starts_with("ok armed=0 force=0.000 volts=0.0,0.0,0.0 "), "{s}");
    assert_stopped_within_a_tick(&q.finish(), "wait 600");

    // during the first armed pose (the branch table is built then)
    let mut q = Qemu::boot("pose");
    armed_at_3kv(&mut q);
    q.write(b"pose 10 10 10\r\nstop\r\n");
    let r = q.finals(2);
    assert_eq!(r[0], "ok stopped", "the stop is answered before the pose: {r:?}");
    let s = q.cmd("status");
    assert!(s.starts_with("ok armed=0 force=0.000 volts=0.0,0.0,0.0 ") && s.contains(" enable=0 "), "{s}");
    assert_stopped_within_a_tick(&q.finish(), "pose");

    // in the middle of the help output
    let mut q = Qemu::boot("help");
    armed_at_3kv(&mut q);
    q.write(b"help\r\nstop\r\n");
    let r = q.finals(2);
    assert!(r.iter().any(|l| l == "ok stopped"), "{r:?}");
    let trace = q.finish();
    assert_stopped_within_a_tick(&trace, "help");
    // the stop came in the middle of the help output: most of its bytes went out after it
    let help_bytes: usize = r.iter().filter(|l| !l.starts_with("ok")).map(|l| l.len() + 2).sum();
    let after = host_tests::qemu::tx_bytes_after_stop(&trace);
    assert!(after > help_bytes / 2, "{after} of {help_bytes} help bytes sent after the stop");
}

#[test]
fn burst_of_200_lines_one_reply_each() {
    let mut q = Qemu::boot("burst");
    let cmds = ["version", "status", "bogus", "solve 0.5 0 1000 2000", "param l", "solve nan 0 0 0", "limits", "help"];
    let burst: String = (0..200).map(|i| format!("{}\r\n", cmds[i % cmds.len()])).collect();
    q.write(burst.as_bytes());
    let lines = q.finals(200);
    let finals: Vec<&String> = lines.iter().filter(|l| l.starts_with("ok") || l.starts_with("err ")).collect();
    for (i, r) in finals.iter().enumerate() {
        let want = match cmds[i % cmds.len()] {
            "bogus" => "err unknown:",
            "solve nan 0 0 0" => "err bad-number:",
            "version" => "ok version=",
            _ => "ok",
        };
        assert!(r.starts_with(want), "line {i}: {r}");
    }
    // nothing more: exactly one each
    assert_eq!(q.cmd("version").split_whitespace().next(), Some("ok"));
    q.finish();
}

#[test]
fn hv_pins_low_first_thing_after_reset() {
    let q = Qemu::boot("reset");
    let trace = q.finish();
    let writes: Vec<_> = trace.iter().filter(|a| a.write).collect();
    // RCC AHB1ENR: GPIOB clock on; then GPIOB BSRR: PB6-8 and PB12 low; MODER: outputs
    assert_eq!((writes[0].addr, writes[0].value & 2), (0x4002_3830, 2), "{:x?}", &writes[..4]);
    assert_eq!((writes[1].addr, writes[1].value), (0x4002_0418, 0x11C0_0000));
    assert_eq!(writes[2].addr, 0x4002_0400);
    assert_eq!(writes[2].value & 0x0303_F000, 0x0101_5000);
}
