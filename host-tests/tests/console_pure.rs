//! Every model-only console command (`solve`, a disarmed `pose`, `contact`,
//! `limits`, `shape`) is a pure function of the parameters and its arguments. Each probe runs
//! after a random sequence of other requests (model-only ones, reads, refused requests, and
//! parameter changes that are undone) and its reply must be byte-identical to a fresh App's
//! with the same parameters.
use finger_fw::sim::SimBoard;
use finger_fw::App;
use host_tests::console::ceiling;
use host_tests::sim_console::{at_ceiling, feed_text};
use proptest::prelude::*;

thread_local!(static VMAX: f64 = ceiling(&mut App::new(SimBoard::default())));

/// One command line; its output, every line (the control loop run through any `wait`). Its
/// `@f` words are voltages, `f` times the board's ceiling in force at boot (`at_ceiling`).
fn run(a: &mut App<SimBoard>, line: &str) -> String {
    let line = VMAX.with(|&v| at_ceiling(line, v));
    feed_text(a, format!("{line}\n").as_bytes())
}

/// The probes: model-only commands with arguments inside and outside the domain.
const PROBES: &[&str] = &[
    "solve 0.5 0 @0.1 @0.2",
    "solve 2 @0.3 @0.3 @0.3",
    "solve 6 @0.9 0 @0.45",
    "solve 0 0 0 0",
    "pose 5 5 5",
    "pose 10 10 10",
    "pose 10.03 10 9.97",
    "pose 12 8 10 1.9",
    "pose 30 30 30",
    "contact 1 2 0 0 0",
    "contact 2.219 3.9 0 0 0",
    "contact 0.5 1.5 @0.3 @0.3 @0.3",
    "contact 1 40 0 0 0",
    "limits",
    "shape 1 0 0 0",
    "shape 3 @0.6 @0.2 @0.9",
];

/// Other requests: model-only, reads, refusals, and a parameter changed then restored.
const OTHERS: &[&str] = &[
    "status",
    "version",
    "param",
    "param l",
    "param layers",
    "help",
    "solve 1.7 @0.25 100 @0.9999",
    "solve 9 0 0 0",
    "solve 1 50000 0 0",
    "pose 7 11 3",
    "pose 10 10 10 1.7",
    "pose 1 1",
    "contact 0.3 4.1 @0.9 @0.9 @0.9",
    "contact 3 2 0 0 0",
    "shape 0.7 0 @0.8 @0.8",
    "volt 1 @0.1",
    "force 1",
    "bogus",
    "param l 30\nparam l 27",
    "param span_floor 0.001\nparam span_floor 0.1",
    "param layers 0\nparam layers 4",
    "preset paper\npreset default",
    "param m 1\nparam m 8",
    "arm\nvolt all @0.3\nforce 1.2\npose 8 9 10\ndisarm",
    "arm\nvolt 2 @0.9\nstop",
    "force 0.8\nstop",
];

fn fresh_replies() -> Vec<String> {
    PROBES.iter().map(|p| run(&mut App::new(SimBoard::default()), p)).collect()
}

#[test]
fn undo_requests_restore_the_parameters() {
    // the restoring half of each `OTHERS` pair is the default value
    let mut a = App::new(SimBoard::default());
    let before = run(&mut a, "param");
    for o in OTHERS.iter().filter(|o| o.contains('\n')) {
        run(&mut a, o);
        assert_eq!(run(&mut a, "param"), before, "{o:?} did not restore the parameters");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn model_only_replies_do_not_depend_on_earlier_requests(
        history in proptest::collection::vec(0..OTHERS.len() + PROBES.len(), 1..8),
        order in Just(()).prop_perturb(|_, mut rng| {
            let mut v: Vec<usize> = (0..PROBES.len()).collect();
            for i in (1..v.len()).rev() {
                v.swap(i, (rng.next_u32() as usize) % (i + 1));
            }
            v
        }),
    ) {
        thread_local!(static FRESH: Vec<String> = fresh_replies());
        let mut a = App::new(SimBoard::default());
        for &h in &history {
            let line = if h < OTHERS.len() { OTHERS[h] } else { PROBES[h - OTHERS.len()] };
            for l in line.lines() {
                run(&mut a, l);
            }
        }
        // the probes themselves in a random order, each after all the others so far
        for &i in &order {
            let got = run(&mut a, PROBES[i]);
            let want = FRESH.with(|f| f[i].clone());
            prop_assert_eq!(&got, &want, "{:?} after {:?}", PROBES[i], history);
        }
    }
}
