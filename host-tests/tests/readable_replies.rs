//! Replies that say what is wrong, on the simulated board: a negative pose angle is refused as
//! an extension (the cable only flexes), a posture with the tip behind the base as outside the
//! model's domain, `contact` with P below P0 is refused as a pull-off, joints are numbered 1..3
//! in every message, a terminal's escape sequences (arrow keys) and control characters
//! (Ctrl-L) get no reply at all. And replies that say what they did: `pose`'s `moved`,
//! `status`' posture at the stacks' thickness now, `limits`' `vmax_ok`, `help`'s every
//! command, `material`'s units, `factory`'s `store=empty`.
use finger_fw::sim::SimBoard;
use finger_fw::App;
use host_tests::reply::{field, nums, val};
use host_tests::sim_console::{cmd, feed};

fn app() -> App<SimBoard> {
    App::new(SimBoard::default())
}

#[test]
fn a_negative_pose_angle_is_refused_as_an_extension() {
    let mut a = app();
    assert_eq!(cmd(&mut a, "arm"), "ok armed=1");
    let before = cmd(&mut a, "status");
    for (line, joint) in [("pose -20 10 10", 1), ("pose 10 -0.5 10", 2), ("pose 10 10 -3 0.5", 3)] {
        let r = cmd(&mut a, line);
        assert!(r.starts_with(&format!("err unreachable: joint {joint}: ")), "{line} -> {r}");
        assert!(r.contains("the cable only flexes the joints"), "{line} -> {r}");
        assert!(!r.contains("compliance"), "{line} -> {r}");
    }
    // nothing moved
    assert_eq!(cmd(&mut a, "status"), before);
    // a zero angle is no extension: not refused as one
    assert!(!cmd(&mut a, "pose 0 5 5").contains("only flexes"));
}

#[test]
fn contact_below_p0_is_refused_as_a_pull_off() {
    let mut a = app();
    let r = cmd(&mut a, "contact 5 1");
    assert!(r.starts_with("err usage: "), "{r}");
    assert!(r.contains("pull-off") && r.contains("P >= P0"), "{r}");
    // at or above P0 the finger presses: a force pointing into the stop
    let r = cmd(&mut a, "contact 1 1.5");
    assert!(r.starts_with("ok fx="), "{r}");
    let f: f64 = val(&r, "force").parse().unwrap();
    assert!(f > 0.0, "{r}");
    assert!(cmd(&mut a, "contact 1 1").starts_with("ok "));
}

/// Every `joint k` and `channel k` in a reply, as k.
fn joints_named(r: &str) -> Vec<i64> {
    ["joint ", "channel "]
        .iter()
        .flat_map(|w| r.match_indices(w).filter_map(|(i, _)| r[i + w.len()..].split(|c: char| !c.is_ascii_digit()).next().and_then(|d| d.parse().ok())))
        .collect()
}

#[test]
fn joints_are_numbered_one_to_three_in_every_message() {
    let mut a = app();
    let limits = cmd(&mut a, "limits");
    let vmax: f64 = val(&limits, "vmax").split(',').next().unwrap().parse().unwrap();
    let fmax: f64 = val(&limits, "fmax").parse().unwrap();
    let lines = [
        "contact 1 5".to_string(),
        format!("contact 0.5 {}", fmax * 0.99),
        "pose 90 90 90".to_string(),
        "pose 1 2 -3".to_string(),
        format!("solve 1 0 0 {}", vmax * 1.5),
        format!("solve {} 0 0 0", fmax * 1.5),
        "arm".to_string(),
        format!("volt 3 {}", vmax * 1.01),
    ];
    let mut named = 0;
    let mut seen = Vec::new();
    for l in &lines {
        let r = cmd(&mut a, l);
        seen.push(r.clone());
        assert!(!r.contains("joint 0") && !r.contains("channel 0"), "{l} -> {r}");
        for k in joints_named(&r) {
            assert!((1..=3).contains(&k), "{l} -> {r}");
            named += 1;
        }
    }
    assert!(named >= 3, "the refusals name their joints: {seen:#?}");
    // the coupled (tip-loaded) equilibrium that used to say "joint 0" says what it is
    let r = cmd(&mut a, "contact 1 5");
    if r.starts_with("err ") && r.contains("limit point") {
        assert!(r.contains("the tip-loaded finger"), "{r}");
    }
}

#[test]
fn escape_sequences_get_no_reply() {
    let mut a = app();
    // arrow keys (CSI and SS3 forms), Home, F5 and an Alt+key, alone on a line: a blank line
    for keys in [&b"\x1b[A\n"[..], b"\x1b[B\x1b[C\x1b[D\r\n", b"\x1bOA\x1bOP\n", b"\x1b[1;5H\x1b[15~\n", b"\x1bx\n"] {
        assert!(feed(&mut a, keys).is_empty(), "{keys:?} -> a reply");
    }
    // with no line end they are no input at all; the next line is read whole
    assert!(feed(&mut a, b"\x1b[A\x1b[A").is_empty());
    let r = feed(&mut a, b"version\n");
    assert_eq!(r.len(), 1);
    assert!(r[0].starts_with("ok version="), "{r:?}");
    // inside a line they are dropped, the rest of the line stands
    let r = feed(&mut a, b"ver\x1b[Dsion\n");
    assert!(r.len() == 1 && r[0].starts_with("ok version="), "{r:?}");
    // and stop still acts when an arrow key came first
    assert_eq!(feed(&mut a, b"arm\n"), vec!["ok armed=1".to_string()]);
    assert_eq!(feed(&mut a, b"\x1b[Astop\n"), vec!["ok stopped".to_string()]);
    assert!(cmd(&mut a, "status").contains("armed=0"));
}

#[test]
fn control_characters_are_ignored_as_arrow_keys_are() {
    let mut a = app();
    // Ctrl-L (a terminal's clear screen), NUL, backspace, DEL: alone, no reply; inside a line
    // the rest of the line stands
    assert!(feed(&mut a, b"\x0c\n\x00\x08\x7f\n").is_empty());
    for line in [&b"\x0cversion\n"[..], b"ver\x0csion\n", b"\x01version\x7f\n"] {
        let r = feed(&mut a, line);
        assert!(r.len() == 1 && r[0].starts_with("ok version="), "{line:?} -> {r:?}");
    }
    // tab still separates words
    assert!(cmd(&mut a, "param\tl").starts_with("ok l="));
}

#[test]
fn pose_says_whether_it_moved_the_board() {
    let mut a = app();
    let r = cmd(&mut a, "pose 9.58 11.04 12.84");
    assert!(r.starts_with("ok force=") && r.ends_with(" moved=0"), "{r}");
    assert_eq!(a.targets(), [0.0; 3], "disarmed: nothing moves");
    cmd(&mut a, "arm");
    let armed = cmd(&mut a, "pose 9.58 11.04 12.84");
    assert_eq!(armed, r.replace(" moved=0", " moved=1"));
    let volts = nums(val(&armed, "volts"));
    for (t, v) in a.targets().iter().zip(&volts) {
        assert!((*t as f64 - v).abs() < 0.06, "{armed}: targets {:?}", a.targets());
    }
}

#[test]
fn a_posture_with_the_tip_behind_the_base_is_refused_with_its_reason() {
    let mut a = app();
    // the finger without its weight: the geometric refusal comes before any solve (under
    // gravity a uniform posture is refused as unreachable first)
    assert_eq!(cmd(&mut a, "param grav 0"), "ok grav=0");
    cmd(&mut a, "arm");
    let before = cmd(&mut a, "status");
    for line in ["pose 90 90 90", "pose 60 60 60"] {
        let r = cmd(&mut a, line);
        assert!(r.starts_with("err unreachable: pose: the tip would be behind the base (x=-"), "{line} -> {r}");
        assert!(r.contains("outside the model's domain"), "{r}");
    }
    assert_eq!(cmd(&mut a, "status"), before, "nothing moved");
    // a posture inside the domain still passes
    assert!(cmd(&mut a, "pose 40 40 40").starts_with("ok force="));
}

#[test]
fn status_reports_the_posture_at_the_stacks_thickness_now() {
    let mut a = app();
    let p = 1.0;
    let at = |a: &mut App<SimBoard>, v: f64| nums(val(&cmd(a, &format!("solve {p} {v} {v} {v}")), "joints"))[0];
    let v = nums(val(&cmd(&mut a, "limits"), "vmax_ok"))[0].floor();
    let (rest, relaxed) = (at(&mut a, 0.0), at(&mut a, v));
    assert!(relaxed > rest + 0.05, "the voltage bends the joint more once relaxed: {rest} {relaxed}");
    cmd(&mut a, "arm");
    cmd(&mut a, &format!("force {p}"));
    cmd(&mut a, &format!("volt all {v}"));
    // the voltage is there after the slew; the film has not crept yet
    cmd(&mut a, "wait 3");
    let st = cmd(&mut a, "status");
    let (t, eq, j) = (field(&st, "thick"), field(&st, "thick_eq"), field(&st, "joints")[0]);
    assert!(field(&st, "volts")[0] == v && t[0] > eq[0] + 0.05, "{st}");
    assert!(j > rest && j < relaxed - 0.05, "the posture at the film's thickness now: {st} ({rest}..{relaxed})");
    // as the film relaxes, the posture nears `solve`'s at the voltages
    cmd(&mut a, "wait 600");
    let st = cmd(&mut a, "status");
    let later = field(&st, "joints")[0];
    assert!(later > j && later <= relaxed + 1e-3 && relaxed - later < 0.25 * (relaxed - j), "{st}: {j} then {later}, relaxed {relaxed}");
}

#[test]
fn limits_reports_the_largest_voltage_volt_takes() {
    let mut a = app();
    let l = cmd(&mut a, "limits");
    let (vmax, ok) = (field(&l, "vmax"), field(&l, "vmax_ok"));
    cmd(&mut a, "arm");
    for ch in 0..3 {
        assert!(ok[ch] < vmax[ch] && ok[ch] > vmax[ch] - 0.11, "{l}");
        let n = ch + 1;
        assert!(cmd(&mut a, &format!("volt {n} {:.1}", ok[ch])).starts_with("ok volts="), "{l}");
        assert!(cmd(&mut a, &format!("volt {n} {:.1}", ok[ch] + 0.1)).starts_with("err limit:"), "{l}");
    }
}

/// The command words of docs/console.md's command tables (`arm` / `disarm` as two).
fn documented_commands() -> Vec<String> {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/console.md")).unwrap();
    let section = &doc[doc.find("## Commands").unwrap()..doc.find("## What each command does").unwrap()];
    let mut words = Vec::new();
    for row in section.lines().filter(|l| l.starts_with("| `")) {
        let cell = row.split('|').nth(1).unwrap();
        for part in cell.split(" / ") {
            let w = part.trim().trim_start_matches('`').split([' ', '`']).next().unwrap();
            words.push(w.to_string());
        }
    }
    words
}

#[test]
fn help_lists_every_command_the_build_has() {
    let mut a = app();
    let help = feed(&mut a, b"help\n");
    let docs = documented_commands();
    assert!(docs.len() >= 20, "{docs:?}");
    for w in &docs {
        let r = cmd(&mut a, w);
        // (the simulated board has `save` but no store to save to: it says so)
        let absent = r.starts_with("err unknown:") && !r.contains("no settings store");
        let listed = help.iter().any(|l| l.starts_with(&format!("{w} ")) || l.contains(&format!("| {w} ")));
        assert!(absent != listed, "{w}: help {} it, the board answers {r}", if listed { "lists" } else { "omits" });
        if w != "stop" {
            cmd(&mut a, "stop");
        }
    }
    // and only those
    assert_eq!(help.len() - 1, help.iter().filter(|l| docs.iter().any(|w| l.starts_with(&format!("{w} ")))).count());
}

#[test]
fn material_names_the_unit_of_every_field() {
    let mut a = app();
    let r = cmd(&mut a, "material");
    let fields: Vec<&str> = r.trim_start_matches("ok ").split(' ').map(|kv| kv.split('=').next().unwrap()).collect();
    let units = val(&r, "units");
    let named: Vec<&str> = units.split(',').map(|u| u.split(':').next().unwrap()).collect();
    // every field but the card's name and the units themselves
    assert_eq!(named, fields.iter().copied().filter(|f| *f != "card" && *f != "units").collect::<Vec<_>>(), "{r}");
    assert!(units.contains("breakdown:V/um") && units.contains("branches:MPa:s") && units.contains("g_eq:MPa"), "{r}");
}

#[test]
fn factory_says_what_docs_console_md_says() {
    let mut a = app();
    assert_eq!(cmd(&mut a, "factory"), "ok factory=1 store=empty");
}
