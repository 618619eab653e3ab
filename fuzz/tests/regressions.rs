//! Every committed input (corpus/<target>/ and regressions/<target>/) through its target's
//! checks, without libFuzzer: a regression in a known input fails here too
//! (`cd fuzz && cargo test --release`).
use std::path::Path;

fn run_dir(target: &str, check: fn(&[u8])) -> usize {
    let mut n = 0;
    for dir in ["corpus", "regressions"] {
        let d = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir).join(target);
        let Ok(entries) = std::fs::read_dir(&d) else { continue };
        let mut files: Vec<_> = entries.flatten().map(|e| e.path()).collect();
        files.sort();
        for f in files {
            let data = std::fs::read(&f).unwrap();
            let r = std::panic::catch_unwind(|| check(&data));
            assert!(r.is_ok(), "{} fails its invariants", f.display());
            n += 1;
        }
    }
    n
}

#[test]
fn console_inputs_hold() {
    assert!(run_dir("console", finger_fuzz::console::check) > 0);
}

#[test]
fn rx_inputs_hold() {
    assert!(run_dir("rx", finger_fuzz::rx::check) > 0);
}

#[test]
fn model_inputs_hold() {
    assert!(run_dir("model", finger_fuzz::model::check) > 0);
}

#[test]
fn scene_inputs_hold() {
    assert!(run_dir("scene", finger_fuzz::scene::check) > 0);
}

#[test]
fn material_inputs_hold() {
    assert!(run_dir("material", finger_fuzz::material::check) > 0);
}

#[test]
fn config_inputs_hold() {
    assert!(run_dir("config", finger_fuzz::config::check) > 0);
}

/// The finds, each by name (docs/reliability.md "Crashes found and fixed").
#[test]
fn inverse_never_answers_a_negative_tension() {
    // four joints, m = 1, rigid links, a soft body: the fast inverse path, tension free, found
    // a posture's tension at -1118 N
    let data = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions/model/inverse-negative-tension")).unwrap();
    finger_fuzz::model::check(&data);
}

#[test]
fn escape_sequences_are_no_part_of_a_line() {
    for (t, check) in [("console", finger_fuzz::console::check as fn(&[u8])), ("rx", finger_fuzz::rx::check)] {
        let data = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions").join(t).join("escape-sequences")).unwrap();
        check(&data);
    }
}

#[test]
fn inverse_refuses_a_joint_past_half_a_turn() {
    // two joints, 752 mm flexible links, a 58 mm moment arm: the forward reached 14.3 rad per
    // joint and the inverse answered an equilibrium 2 pi away from the one the finger reaches
    let data = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions/model/inverse-wrong-branch")).unwrap();
    finger_fuzz::model::check(&data);
}

#[test]
fn every_lost_line_keeps_its_reply() {
    // more than 255 lines lost in a row while the ring was full: the overrun record's count
    // saturated at a byte and the lines past it got no `err overrun`
    let data = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions/rx/overrun-count-past-255")).unwrap();
    finger_fuzz::rx::check(&data);
}

#[test]
fn a_stop_drops_the_lines_queued_ahead_of_it() {
    // `arm`, `volt all 3000`, `stop` received before the command side ran: the stop drops the
    // two lines ahead of it (each answered `err stopped`); the board stays disarmed, HV at 0
    for t in ["console", "rx"] {
        let data = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions").join(t).join("stop-drops-queued-lines")).unwrap();
        let check = if t == "console" { finger_fuzz::console::check as fn(&[u8]) } else { finger_fuzz::rx::check };
        check(&data);
    }
}
