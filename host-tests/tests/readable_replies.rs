//! Replies that say what is wrong, on the simulated board: a negative pose angle is refused as
//! an extension (the cable only flexes), `contact` with P below P0 is refused as a pull-off,
//! joints are numbered 1..3 in every message, and a terminal's escape sequences (arrow keys)
//! get no reply at all.
use finger_fw::sim::SimBoard;
use finger_fw::App;
use host_tests::sim_console::{cmd, feed};
use host_tests::reply::val;

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
        .flat_map(|w| {
            r.match_indices(w)
                .filter_map(|(i, _)| r[i + w.len()..].split(|c: char| !c.is_ascii_digit()).next().and_then(|d| d.parse().ok()))
        })
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
