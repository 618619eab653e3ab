//! The `finger` program as a user runs it, against finger-sim (a child process on pipes) and
//! against the firmware's emulator image in QEMU (its console on a Unix socket): the same
//! commands, replies and typed refusals on both, a board that stops answering reported after
//! the time-out, and the QEMU image's defmt log decoded by `finger log`.
use std::time::{Duration, Instant};

mod common;
use common::{finger, image, scratch, shell_board, sim, text};

/// The console session both boards get, and what each must answer.
fn same_session(board: &[&str]) {
    let mut args = board.to_vec();
    args.extend(["cmd", "version", "status", "limits", "solve 0.5 0 1000 2000", "arm", "volt all 500", "wait 0.3", "status"]);
    let out = finger(&args);
    let so = text(&out.stdout);
    assert!(out.status.success(), "{board:?}: {}\n{so}", text(&out.stderr));
    // nothing on stderr but the board's own: not QEMU's notice that its socket waits for us
    assert!(text(&out.stderr).trim().is_empty(), "{board:?}: stderr {:?}", text(&out.stderr));
    let lines: Vec<&str> = so.lines().collect();
    assert_eq!(lines.len(), 8, "{so}");
    assert!(lines[0].starts_with("ok version=") && lines[0].contains(" name=finger-fw"), "{so}");
    assert!(lines[1].starts_with("ok armed=0 "), "{so}");
    assert!(lines[2].starts_with("ok vmax="), "{so}");
    assert!(lines[3].starts_with("ok joints="), "{so}");
    assert_eq!(lines[4], "ok armed=1");
    assert!(lines[7].contains(" volts=500.0,500.0,500.0 "), "{so}");

    // a refusal comes back typed, with its code, and the exit status says so
    let mut args = board.to_vec();
    args.extend(["cmd", "volt 1 100"]);
    let out = finger(&args);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("volt 1 100: err not-armed:"), "{}", text(&out.stderr));
}

#[test]
fn sim_answers_the_console_contract() {
    same_session(&["--sim", "--sim-bin", sim().to_str().unwrap()]);
    // the finger-sim next to the client is the default, and `--sim` takes no value
    same_session(&["--sim"]);
}

#[test]
fn qemu_answers_the_same_session() {
    let dir = scratch("client-test");
    let log = dir.join("defmt.bin");
    same_session(&["--qemu", "--elf", image().to_str().unwrap(), "--defmt-log", log.to_str().unwrap()]);
    // what that boot logged, decoded with the image's table
    let out = finger(&["log", "--elf", image().to_str().unwrap(), "--file", log.to_str().unwrap(), "--no-follow"]);
    let so = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(so.lines().any(|l| l.contains("finger-fw") && l.contains("qemu-netduinoplus2")), "decoded: {so}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn script_and_monitor_on_the_sim() {
    let dir = scratch("script-test");
    let script = dir.join("s.txt");
    std::fs::write(&script, "# a comment\narm\n\nvolt 2 700\nfrobnicate\nstatus\n").unwrap();
    let sim = sim().to_str().unwrap();
    // stops at the first refusal
    let out = finger(&["--sim", "--sim-bin", sim, "script", script.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let so = text(&out.stdout);
    assert!(so.contains("> volt 2 700\nok volts=0.0,700.0,0.0") && !so.contains("> status"), "{so}");
    assert!(text(&out.stderr).contains("frobnicate: err unknown:"));
    // --keep-going runs the rest, and still reports the refusal in the exit status
    let out = finger(&["--sim", "--sim-bin", sim, "script", "--keep-going", script.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stdout).contains("> status\nok armed=1 "));

    // on the simulated board, which nothing else drives, monitor says so and runs its demo:
    // armed, the voltages slewing up poll after poll
    let out = finger(&["--sim", "--sim-bin", sim, "monitor", "--rate", "50", "--count", "4"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("nothing else drives it, so this is a demo"), "{}", text(&out.stderr));
    let so = text(&out.stdout);
    let polls: Vec<&str> = so.lines().filter(|l| l.starts_with("ok armed=1 ")).collect();
    assert_eq!(polls.len(), 4, "{so}");
    let volts: Vec<f64> = polls.iter().map(|l| l.split(" volts=").nth(1).unwrap().split(',').next().unwrap().parse().unwrap()).collect();
    assert!(volts.windows(2).all(|w| w[1] > w[0]) && volts[0] > 0.0, "the slew plays out: {volts:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_board_that_stops_answering_is_reported_after_the_time_out() {
    let dir = scratch("mute-test");
    // reads its input and never answers
    let mute = dir.join("mute-board");
    shell_board(&mute, "exec sleep 30");
    let t0 = Instant::now();
    let out = finger(&["--sim", "--sim-bin", mute.to_str().unwrap(), "--timeout", "0.5", "cmd", "status"]);
    assert!(t0.elapsed() < Duration::from_secs(10));
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("did not answer within 0.5 s"), "{}", text(&out.stderr));
    // and one whose link ends is reported as such, not waited on
    let out = finger(&["--sim", "--sim-bin", "/bin/true", "cmd", "status"]);
    assert_eq!(out.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn no_board_named_is_a_usage_error() {
    let out = finger(&["cmd", "status"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("name a board"));
    let out = finger(&["--sim", "--port", "/dev/null", "cmd", "status"]);
    assert_eq!(out.status.code(), Some(2), "two boards at once are refused by the argument parser");
}

#[test]
fn the_readmes_ramp_script_runs_on_the_sim() {
    // README: `cargo run -- --port /dev/ttyACM0 script ramp.txt`, the file shipped next to it
    let ramp = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("ramp.txt");
    let out = finger(&["--sim", "--sim-bin", sim().to_str().unwrap(), "script", ramp.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let o = text(&out.stdout);
    // every line answered ok, the ramp read back, and the board stopped at the end
    assert!(!o.contains("err "), "{o}");
    assert!(o.contains("volts=1500.0,0.0,0.0"), "{o}");
    assert!(o.trim_end().ends_with("ok stopped"), "{o}");
}

#[test]
fn save_and_config_reach_the_store() {
    // finger-sim has no store: `config` says so, `save` is refused with its code
    let sim = sim();
    let out = finger(&["--sim", "--sim-bin", sim.to_str().unwrap(), "config"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).starts_with("ok store=none saves=0 boot=none fault=none"), "{}", text(&out.stdout));
    let out = finger(&["--sim", "--sim-bin", sim.to_str().unwrap(), "save"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("save: err unknown: save: this board has no settings store"), "{}", text(&out.stderr));
    // the emulator image stores: a fresh boot has nothing, `save` writes the first record
    let dir = scratch("client-save");
    let log = dir.join("defmt.bin");
    let qemu = ["--qemu", "--elf", image().to_str().unwrap(), "--defmt-log", log.to_str().unwrap()];
    let out = finger(&[&qemu[..], &["config"]].concat());
    assert!(text(&out.stdout).starts_with("ok store=empty saves=0 boot=empty"), "{}{}", text(&out.stdout), text(&out.stderr));
    let out = finger(&[&qemu[..], &["save"]].concat());
    assert!(text(&out.stdout).starts_with("ok saved=1 bytes="), "{}{}", text(&out.stdout), text(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A README line's arguments after `cargo run --`, double quotes grouping words.
fn readme_args(line: &str) -> Vec<String> {
    let rest = line.split("cargo run -- ").nth(1).unwrap().split(" # ").next().unwrap().trim();
    let (mut out, mut word, mut quoted) = (Vec::new(), String::new(), false);
    for c in rest.chars() {
        match c {
            '"' => quoted = !quoted,
            ' ' if !quoted => {
                if !word.is_empty() {
                    out.push(std::mem::take(&mut word));
                }
            }
            c => word.push(c),
        }
    }
    if !word.is_empty() {
        out.push(word);
    }
    out
}

#[test]
fn the_readme_sim_commands_run_as_shown() {
    let readme = std::fs::read_to_string(common::root().join("README.md")).unwrap();
    let section = &readme[readme.find("## The host client: `finger`").unwrap()..];
    let block = &section[section.find("```sh\n").unwrap()..];
    let block = &block[..block[6..].find("```").unwrap()];
    let lines: Vec<&str> = block.lines().filter(|l| l.starts_with("cargo run -- --sim ")).collect();
    assert!(lines.len() >= 2, "{block}");
    let dir = scratch("readme");
    for l in lines {
        let mut args = readme_args(l);
        // the finger-sim this test built; a run's files into the scratch directory
        args.insert(1, "--sim-bin".into());
        args.insert(2, sim().to_str().unwrap().into());
        if args.iter().any(|a| a == "run") {
            args.extend(["--out".into(), dir.to_str().unwrap().into()]);
        }
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_finger")).args(&args).current_dir(common::root().join("tools/finger")).output().unwrap();
        assert!(out.status.success(), "{l}: {}", text(&out.stderr));
        assert!(text(&out.stdout).lines().all(|r| !r.starts_with("err ")), "{l}: {}", text(&out.stdout));
    }
    let _ = std::fs::remove_dir_all(&dir);
}
