//! finger-sim as a user runs it: a script on stdin, one reply a line on stdout, exit at the
//! end of input.

#[test]
fn script_on_stdin_replies_on_stdout() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let mut c = Command::new(env!("CARGO_BIN_EXE_finger-sim")).stdin(Stdio::piped()).stdout(Stdio::piped()).spawn().unwrap();
    let script = b"version\r\nbogus\nsolve nan 0 0 0\nvolt 1 100\narm\nvolt 1 500\nwait 0.1\nstatus\nparam l 30\nstop\n\xff\n";
    c.stdin.take().unwrap().write_all(script).unwrap();
    let out = c.wait_with_output().unwrap(); // exits at end of input
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 11, "{text}");
    assert!(lines[0].starts_with("ok version="));
    assert!(lines[1].starts_with("err unknown:"));
    assert!(lines[2].starts_with("err bad-number:"));
    assert!(lines[3].starts_with("err not-armed:"));
    assert_eq!(lines[4], "ok armed=1");
    assert_eq!(lines[6], "ok waited=0.1");
    assert!(lines[7].contains(" volts=200.0,0.0,0.0 "), "{}", lines[7]);
    assert!(lines[8].starts_with("err armed:"));
    assert_eq!(lines[9], "ok stopped");
    assert!(lines[10].starts_with("err unknown:"));
}

#[test]
fn help_usage_and_unknown_flags() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_finger-sim");
    let h = Command::new(bin).arg("--help").output().unwrap();
    assert!(h.status.success());
    let t = String::from_utf8(h.stdout).unwrap();
    assert!(t.starts_with("usage: finger-sim") && t.contains("--virtual"), "{t}");
    let bad = Command::new(bin).arg("--bogus").output().unwrap();
    assert_eq!(bad.status.code(), Some(2));
    let e = String::from_utf8(bad.stderr).unwrap();
    assert!(e.contains("unknown argument `--bogus`"), "{e}");
    assert!(bad.stdout.is_empty());
}

#[test]
fn a_banner_at_a_terminal_and_none_in_a_pipe() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let bin = env!("CARGO_BIN_EXE_finger-sim");
    // piped: the replies alone (the banner would break scripts that read stdout)
    let mut c = Command::new(bin).stdin(Stdio::piped()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    c.stdin.take().unwrap().write_all(b"version\n").unwrap();
    let out = c.wait_with_output().unwrap();
    assert!(out.stderr.is_empty(), "{}", String::from_utf8_lossy(&out.stderr));
    // at a terminal (util-linux `script` gives it a pseudo-terminal): the banner
    let mut c = Command::new("script").args(["-q", "-e", "-c", bin, "/dev/null"]).stdin(Stdio::piped()).stdout(Stdio::piped()).spawn().unwrap();
    c.stdin.take().unwrap().write_all(b"version\n").unwrap();
    let out = c.wait_with_output().unwrap();
    let t = String::from_utf8_lossy(&out.stdout);
    assert!(t.contains("Type `help` for the commands; Ctrl-D quits."), "{t}");
    assert!(t.contains("ok version="), "{t}");
}

/// The board's time runs with the wall clock while finger-sim waits for input: `stop`, then a
/// `status` sent 0.3 s later reads the stacks discharged (the plant's HV modules bleed them in
/// about 0.1 s), as a real board reads them; a script piped in whole has no such waits.
#[test]
fn after_stop_the_stacks_read_discharged_a_moment_later() {
    use std::io::{BufRead, BufReader, Write};
    use std::process::{Command, Stdio};
    let mut c = Command::new(env!("CARGO_BIN_EXE_finger-sim")).stdin(Stdio::piped()).stdout(Stdio::piped()).spawn().unwrap();
    let mut input = c.stdin.take().unwrap();
    let mut replies = BufReader::new(c.stdout.take().unwrap());
    let mut reply = |input: &mut std::process::ChildStdin, line: &str| {
        input.write_all(format!("{line}\n").as_bytes()).unwrap();
        let mut r = String::new();
        replies.read_line(&mut r).unwrap();
        r
    };
    let vmeas = |r: &str| -> Vec<f64> {
        let v = r.split(' ').find_map(|kv| kv.strip_prefix("vmeas=")).unwrap_or_else(|| panic!("{r}"));
        v.split(',').map(|x| x.parse().unwrap()).collect()
    };
    assert_eq!(reply(&mut input, "arm"), "ok armed=1\n");
    assert!(reply(&mut input, "volt all 3000").starts_with("ok volts="));
    assert_eq!(reply(&mut input, "wait 2"), "ok waited=2\n");
    let charged = vmeas(&reply(&mut input, "status"));
    assert!(charged.iter().all(|&v| v > 2500.0), "{charged:?}");
    assert_eq!(reply(&mut input, "stop"), "ok stopped\n");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let st = reply(&mut input, "status");
    // was 2904.7,... : the board's time stood still between lines
    assert!(vmeas(&st).iter().all(|&v| v.abs() < 50.0), "{st}");
    assert!(st.starts_with("ok armed=0 force=0.000 volts=0.0,0.0,0.0 "), "{st}");
    drop(input);
    assert!(c.wait().unwrap().success());
}

/// `help` lists every command the simulated board answers: the plant's test console too, and
/// not `reset` (the chip images' alone), which is refused as unknown here.
#[test]
fn help_lists_the_plant_and_reset_is_the_chips() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let mut c = Command::new(env!("CARGO_BIN_EXE_finger-sim")).stdin(Stdio::piped()).stdout(Stdio::piped()).spawn().unwrap();
    c.stdin.take().unwrap().write_all(b"help\nplant status\nreset\n").unwrap();
    let out = c.wait_with_output().unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.lines().any(|l| l.starts_with("plant film <G_eq kPa>") && l.contains(" | status - ")), "{text}");
    assert!(text.lines().any(|l| l.starts_with("ok plant film_kpa=")), "{text}");
    assert!(!text.lines().any(|l| l.starts_with("reset")), "{text}");
    assert!(text.lines().last().unwrap().starts_with("err unknown: reset"), "{text}");
}
