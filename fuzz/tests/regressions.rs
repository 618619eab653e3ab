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

/// The model target's split (each from its own corpus; the model target's corpus and
/// regressions still run through `model::check` above).
#[test]
fn model_forward_inputs_hold() {
    assert!(run_dir("model_forward", finger_fuzz::model_forward::check) > 0);
}

#[test]
fn model_inverse_inputs_hold() {
    assert!(run_dir("model_inverse", finger_fuzz::model_inverse::check) > 0);
}

#[test]
fn model_contact_inputs_hold() {
    assert!(run_dir("model_contact", finger_fuzz::model_contact::check) > 0);
}

#[test]
fn model_fmax_inputs_hold() {
    assert!(run_dir("model_fmax", finger_fuzz::model_fmax::check) > 0);
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

#[test]
fn plant_inputs_hold() {
    assert!(run_dir("plant", finger_fuzz::plant::check) > 0);
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

/// The plant corpus exercises every kind of fault the target counts (breakdown, stuck, open,
/// leak): each latched within its bound in at least one input, so the "no fault missed"
/// invariant is checked, not vacuous.
#[test]
fn the_plant_corpus_latches_every_kind_of_fault() {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus/plant");
    let (mut counted, mut latched, mut ticks) = ([0u32; 4], [0u32; 4], 0u64);
    let t0 = std::time::Instant::now();
    let mut n = 0;
    for e in std::fs::read_dir(&d).unwrap().flatten() {
        let s = finger_fuzz::plant::run(&std::fs::read(e.path()).unwrap());
        for k in 0..4 {
            counted[k] += s.counted[k];
            latched[k] += s.latched[k];
        }
        ticks += s.ticks as u64;
        n += 1;
    }
    println!("{n} inputs, {ticks} ticks in {:.2} s; counted {counted:?}, latched {latched:?}", t0.elapsed().as_secs_f64());
    assert!(latched.iter().all(|&l| l > 0), "breakdown, stuck, open, leak latched: {latched:?} of {counted:?}");
}

/// The plant target's first find (fixed; docs/reliability.md):
/// a module stuck at 6..9 kV on a channel in shaped actuation is not cut within the 320 ms
/// stated for `hv-mismatch` (plain: 91-107 ms). Shaped, the over-ceiling check's bound is the
/// writer's ceiling, the compiled cap (10 kV), not the 5.4 kV hold ceiling the shaped drive is
/// held under, and the 300 ms mismatch count is reset whenever the loop's ask is held by the
/// slew, which it is every few ticks with the integral at its bound: cut after 0.4-8.5 s, and
/// at 6 kV against a 4.2 kV shaped target (the drive at the 5.4 kV hold ceiling) never.
#[test]
fn a_stuck_module_on_a_shaped_channel_is_cut_within_320_ms() {
    for f in ["stuck-module-shaped-drive", "stuck-6kv-shaped-never-cut", "stuck-shaped-found-by-the-fuzzer"] {
        let data = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions/plant").join(f)).unwrap();
        finger_fuzz::plant::check(&data);
    }
}

/// The plant target's second find (fixed): armed setpoints taken by the core while a fault is
/// latched (no stop since: a breakdown, then a disarm and an arm) set its targets, and the
/// values and the loop's ask climb: nonzero duties written with the enable low (which the
/// fault holds low until a stop, so no HV reaches a stack). Against "a fault cuts the HV:
/// enable low, every duty 0, until stop".
#[test]
fn a_latched_fault_keeps_every_duty_at_0() {
    let data = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions/plant/duty-with-the-enable-low-after-a-fault")).unwrap();
    finger_fuzz::plant::check(&data);
}
