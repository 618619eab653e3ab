//! The real-time core in QEMU with `-icount shift=0`, shown from the registers (the
//! register trace, host_tests::qemu), not from the console's own report; each test runs
//! against the F405 image (netduinoplus2) and the Cortex-M3 image (netduino2):
//! - the largest HV duty step per control tick over a ramp while help, param, pose, force and
//!   contact run is at most slew x 1 ms + 1 count;
//! - a `stop` sent during `wait 600`, during a long model solve (the branch-table build of the
//!   first armed `pose`; `force` on the M3 image, whose `pose` builds no table) and in the middle of the
//!   `help` output zeroes the duties within one tick, and nothing planned before it writes a
//!   duty after it;
//! - each line of a burst sent at once (200 lines; 64 on the M3 image, its 1 KiB line ring)
//!   gets exactly one reply;
//! - right after reset, the first register writes drive the HV pins low (GPIOB clock on first);
//! - at boot, `volt all 9990` is refused and the largest voltage a channel holds after a long
//!   `wait` (the TIM4 compare registers read with the monitor's `xp`, in volts at the HV full
//!   scale) is below the board card's hold ceiling (computed here in f64);
//! - the harness itself: a traced run stops QEMU at its log's cap and says so, and a test
//!   process that aborts with QEMU running leaves neither QEMU nor its files behind.
use finger_fw::board::{BOARD_CARD, BOARD_MARGIN, BOARD_Z0_MM, HV_FULL_SCALE_V};
use finger_fw::control::sense::RIPPLE_PP_V;
use finger_model::material::{hold_ceiling, StackLaw};
use host_tests::image::Image;
use host_tests::qemu::{duties_per_tick, hv_full_scale, max_step, stop_latencies, Qemu, TIM4_ARR, TIM4_CCR};
use host_tests::reply::{nums, val};

// one `#[test]` per image for each check below
host_tests::on_both_images! {
    duty_step_per_tick_within_slew_while_commands_run => duty_step_within_slew;
    stop_within_one_tick_during_wait_solve_and_help => stop_within_one_tick;
    burst_of_lines_one_reply_each => burst_one_reply_each;
    hv_pins_low_first_thing_after_reset => hv_pins_low_after_reset;
    largest_held_voltage_below_the_hold_ceiling_at_boot => held_below_hold_ceiling;
}

fn held_below_hold_ceiling(img: Image) {
    let law = StackLaw::<f64>::new(BOARD_CARD, BOARD_Z0_MM as f64, BOARD_MARGIN as f64).unwrap();
    let hold = hold_ceiling(&law, BOARD_MARGIN as f64);
    let mut q = Qemu::boot_on(img, "hold");
    assert_eq!(q.cmd("arm"), "ok armed=1");
    let r = q.cmd("volt all 9990");
    assert!(r.starts_with("err limit"), "{r}");
    let vmax = nums(val(&q.cmd("limits"), "vmax")).into_iter().fold(f64::INFINITY, f64::min);
    assert!(vmax <= hold * (1.0 + 1e-5), "vmax {vmax} V past the hold ceiling {hold} V");
    // the most the console takes, held
    let v = (vmax - 1.0).floor();
    let r = q.cmd(&format!("volt all {v}"));
    assert!(r.starts_with("ok volts="), "{v} V: {r}");
    // the F405's film creeps and its guard acts over minutes; the M3 drives open loop (its duty
    // is the target's once the ramp ends, 2.7 s at the default slew), and its soft-float plant
    // costs QEMU 25 times the instructions a tick: 120 s there passes the harness's read timeout
    let wait = if img == Image::M3 { "wait 10" } else { "wait 120" };
    assert_eq!(q.cmd(wait), format!("ok waited={}", &wait[5..]));
    let fs = q.read_words(TIM4_ARR, 1)[0] as f64 + 1.0;
    let duty = q.read_words(TIM4_CCR[0], 3);
    assert_eq!(duty.len(), 3);
    for (ch, &d) in duty.iter().enumerate() {
        let volts = d as f64 / fs * HV_FULL_SCALE_V as f64;
        assert!(volts <= hold, "channel {}: {volts} V held past the hold ceiling {hold} V", ch + 1);
        assert!(volts > 0.95 * v, "channel {}: {volts} V held for {v} V", ch + 1);
    }
    assert!(q.cmd("status").starts_with("ok armed=1"));
    q.end();
}

fn duty_step_within_slew(img: Image) {
    let mut q = Qemu::boot_traced(img, "ramp");
    assert_eq!(q.cmd("param slew 100000"), "ok slew=100000");
    assert_eq!(q.cmd("arm"), "ok armed=1");
    q.write(b"volt 1 5000\r\nhelp\r\nparam\r\npose 9.58 11.04 12.84\r\nforce 0.3\r\ncontact 1 1.5\r\nvolt 2 5000\r\n");
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
    // channel 2 ramped to 5 kV one slewed step at a time (pose set channel 1 on the way)
    let last = ticks.last().unwrap();
    if img.reads_hv_back() {
        // the loop holds the measured voltage at the value less the hold ripple (0..100 V)
        let (lo, hi) = ((5000.0 - RIPPLE_PP_V) * 0.99, 5000.0 * 1.01);
        let v = last[1] as f32 * 10_000.0 / fs as f32;
        assert!(v >= lo && v <= hi, "{v} V held for 5000: {last:?}");
    } else {
        assert_eq!(last[1], 5000 * fs / 10_000, "{last:?}");
    }
    let moving = ticks.windows(2).filter(|w| w[0][1] != w[1][1]).count() as u64;
    assert!(moving >= 5000 * fs / 10_000 / bound, "{moving} ticks of ramp");
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

fn stop_within_one_tick(img: Image) {
    // during `wait 600`
    let mut q = Qemu::boot_traced(img, "wait");
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

    // during the first armed pose (the branch table is built then); on the M3 image (no
    // table), during `force` (its fmax bisection: many fixed-point solves)
    let mut q = Qemu::boot_traced(img, "pose");
    armed_at_3kv(&mut q);
    let long = if img.has_inverse() { "pose 9.58 11.04 12.84" } else { "force 0.5" };
    q.write(format!("{long}\r\nstop\r\n").as_bytes());
    let r = q.finals(2);
    assert_eq!(r[0], "ok stopped", "the stop is answered before {long}: {r:?}");
    let s = q.cmd("status");
    assert!(s.starts_with("ok armed=0 force=0.000 volts=0.0,0.0,0.0 ") && s.contains(" enable=0 "), "{s}");
    assert_stopped_within_a_tick(&q.finish(), long);

    // in the middle of the help output
    let mut q = Qemu::boot_traced(img, "help");
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

fn burst_one_reply_each(img: Image) {
    let mut q = Qemu::boot_on(img, "burst");
    let cmds = ["version", "status", "bogus", "solve 0.5 0 1000 2000", "param l", "solve nan 0 0 0", "limits", "help"];
    // what the line ring holds while `help` waits for room in the transmit queue
    let n = if img == Image::M3 { 64 } else { 200 };
    let burst: String = (0..n).map(|i| format!("{}\r\n", cmds[i % cmds.len()])).collect();
    q.write(burst.as_bytes());
    let lines = q.finals(n);
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
    q.end();
}

fn hv_pins_low_after_reset(img: Image) {
    let q = Qemu::boot_traced(img, "reset");
    let trace = q.finish();
    let writes: Vec<_> = trace.iter().filter(|a| a.write).collect();
    // RCC AHB1ENR: GPIOB clock on; then GPIOB BSRR: PB6-8 and PB12 low; MODER: outputs (the
    // values where QEMU models the registers: not on netduino2, which logs the addresses)
    assert_eq!(writes[0].modelled, img.models_gpio(), "{:x?}", &writes[..4]);
    assert_eq!((writes[0].addr, writes[0].value & 2), (0x4002_3830, if img.models_gpio() { 2 } else { 0 }), "{:x?}", &writes[..4]);
    assert!(writes[1].writes(0x4002_0418, 0x11C0_0000), "{:x?}", writes[1]);
    assert_eq!(writes[2].addr, 0x4002_0400);
    if img.models_gpio() {
        assert_eq!(writes[2].value & 0x0303_F000, 0x0101_5000);
    }
    // then TIM4 CCR1..3 = 0 (modelled on both machines)
    for (k, &r) in TIM4_CCR.iter().enumerate() {
        assert_eq!((writes[3 + k].addr, writes[3 + k].value, writes[3 + k].modelled), (r, 0, true), "{:x?}", &writes[..8]);
    }
}

/// QEMU processes whose command line names `dir` (the run's directory is in its socket paths).
fn qemu_processes_of(dir: &std::path::Path) -> Vec<String> {
    let want = dir.to_string_lossy().into_owned();
    let mut found = Vec::new();
    for e in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(cmd) = std::fs::read(e.path().join("cmdline")) else { continue };
        let cmd = String::from_utf8_lossy(&cmd).replace('\0', " ");
        if cmd.starts_with("qemu-system-arm") && cmd.contains(&want) {
            found.push(e.file_name().to_string_lossy().into_owned());
        }
    }
    found
}

/// Polls `gone` for up to 10 s.
fn within_10_s(gone: impl Fn() -> bool) -> bool {
    let t0 = std::time::Instant::now();
    while t0.elapsed() < std::time::Duration::from_secs(10) {
        if gone() {
            return true;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    false
}

#[test]
fn a_traced_run_keeps_its_log_within_the_cap_and_fails_saying_so() {
    // a second of control ticks writes far more than 16 KiB of register trace
    let cap = 16 << 10;
    let mut q = Qemu::boot_traced_capped(Image::M4f, "cap", cap);
    assert_eq!(q.cmd("wait 1"), "ok waited=1");
    assert!(q.cmd("version").starts_with("ok version="), "QEMU runs on past the cap");
    assert_eq!(q.log_size(), cap, "the log stops at its cap");
    let dir = q.dir().to_path_buf();
    let msg = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| q.finish())) {
        Ok(t) => panic!("a cut trace of {} accesses read as whole", t.len()),
        Err(e) => e.downcast_ref::<String>().cloned().unwrap_or_default(),
    };
    assert!(msg.contains("reached the cap of 16384 bytes"), "{msg}");
    assert!(within_10_s(|| !dir.exists() && qemu_processes_of(&dir).is_empty()), "{} left behind", dir.display());
}

#[test]
fn an_aborted_run_leaves_no_qemu_and_no_files() {
    const CHILD: &str = "FINGER_QEMU_ABORT_CHILD";
    if std::env::var_os(CHILD).is_some() {
        // the child: a traced run, then the process aborts (no unwinding, no Drop)
        let mut q = Qemu::boot_traced(Image::M4f, "abort");
        assert_eq!(q.cmd("arm"), "ok armed=1");
        println!("dir={}", q.dir().display());
        std::process::abort();
    }
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["an_aborted_run_leaves_no_qemu_and_no_files", "--exact", "--nocapture", "--test-threads=1"])
        .env(CHILD, "1")
        .output()
        .unwrap();
    assert!(!out.status.success(), "the child did not abort");
    let so = String::from_utf8_lossy(&out.stdout);
    let dir = so.lines().find_map(|l| l.split_once("dir=")).map(|(_, d)| d).unwrap_or_else(|| panic!("child: {so}"));
    let dir = std::path::PathBuf::from(dir);
    assert!(within_10_s(|| qemu_processes_of(&dir).is_empty()), "QEMU still running for {}", dir.display());
    assert!(within_10_s(|| !dir.exists()), "{} left behind", dir.display());
}
