//! `shape <P> <V1> <V2> <V3>` (console addition, docs/firmware.md): the poses it reports are
//! the solve's: nodes as `Solution::nodes`, each hinge end as node k marched through its
//! sub-elements (the model's posture, docs/model.md "Equilibrium"), the tip as `solve`'s.
use finger_fw::sim::SimBoard;
use finger_fw::App;
use finger_model::{Calibration, Finger, Method, Pose};
use host_tests::console::ceiling;
use host_tests::reply::{nums, val};
use host_tests::sim_console::{feed, frac_of};

/// One command line: its reply, which must be the only line.
fn cmd(a: &mut App<SimBoard>, line: &str) -> String {
    let lines = feed(a, format!("{line}\n").as_bytes());
    assert_eq!(lines.len(), 1, "{line:?} -> {lines:?}");
    lines[0].clone()
}

#[test]
fn shape_reports_the_poses_of_the_solve() {
    let mut a = App::new(SimBoard::default());
    // the board's default finger: docs/model.md's on the board's film (VHB 4905) under the
    // board's gravity, with its FE calibration
    let f: Finger<f32> = Finger::with_calibration(finger_fw::app::board_params(), Calibration::model_md()).unwrap();
    let p = f.params();
    let sub_len = p.hinge_len() / p.m as f32;
    let vm = ceiling(&mut a);
    let at = |f: [f64; 3]| f.map(|f| frac_of(vm, f));
    for (tension, volts) in [(0.0, [0.0; 3]), (1.0, [0.0; 3]), (3.0, at([0.9, 0.0, 0.4])), (5.0, at([0.2; 3]))] {
        let args = format!("{tension} {} {} {}", volts[0], volts[1], volts[2]);
        let r = cmd(&mut a, &format!("shape {args}"));
        assert!(r.starts_with("ok nodes="), "{r}");
        let (nodes, hinges) = (nums(val(&r, "nodes")), nums(val(&r, "hinges")));
        assert_eq!((nodes.len(), hinges.len()), (12, 9));
        let sol = f.solve(tension, &volts, Method::converged()).unwrap();
        for k in 0..3 {
            // hinge k's distal end: node k marched through its m sub-elements
            let mut end = Pose::origin();
            for q in &sol.q[k][..p.m] {
                end = end.then(sub_len + q[0], q[1], q[2]);
            }
            let h = sol.nodes[k].then(end.x, end.y, end.theta);
            let got = &hinges[3 * k..3 * k + 3];
            assert!((got[0] - h.x as f64).abs() <= 2e-3 && (got[1] - h.y as f64).abs() <= 2e-3, "hinge {k}: {got:?} vs {h:?}");
            assert!((got[2] - (h.theta as f64).to_degrees()).abs() <= 0.01);
            let n = &nodes[3 * k + 3..3 * k + 6];
            let s = sol.nodes[k + 1];
            assert!((n[0] - s.x as f64).abs() <= 1e-3 && (n[1] - s.y as f64).abs() <= 1e-3, "node {}: {n:?} vs {s:?}", k + 1);
        }
        // the tip is solve's
        let tip = nums(val(&cmd(&mut a, &format!("solve {args}")), "tip"));
        assert_eq!(&nodes[9..12], &tip[..]);
        assert_eq!(val(&r, "thick"), val(&cmd(&mut a, &format!("solve {args}")), "thick"));
    }
}

#[test]
fn shape_refuses_as_solve_does() {
    let mut a = App::new(SimBoard::default());
    for bad in ["shape", "shape 1 0 0", "shape x 0 0 0", "shape -1 0 0 0", "shape 1 10000 0 0", "shape 1 0 0 0 0"] {
        let solve = bad.replacen("shape", "solve", 1);
        let (r, s) = (cmd(&mut a, bad), cmd(&mut a, &solve));
        assert!(r.starts_with("err "), "{bad} -> {r}");
        // the same code and message (the usage line names its own command)
        assert_eq!(r.split(':').next(), s.split(':').next(), "{bad}");
        if !r.starts_with("err usage: shape") {
            assert_eq!(r, s);
        }
    }
    assert!(cmd(&mut a, "status").contains("armed=0 force=0.000"), "model only: nothing moved");
}

#[test]
fn shape_takes_the_arguments_solve_takes_on_a_finger_without_stacks() {
    let mut a = App::new(SimBoard::default());
    assert_eq!(cmd(&mut a, "param layers 0"), "ok layers=0");
    for args in ["1", "1 0 0 0"] {
        let solve = cmd(&mut a, &format!("solve {args}"));
        let shape = cmd(&mut a, &format!("shape {args}"));
        assert!(solve.starts_with("ok joints="), "{solve}");
        let nodes = nums(val(&shape, "nodes"));
        let tip = nums(val(&solve, "tip"));
        assert_eq!(&nodes[nodes.len() - 3..], &tip[..], "shape {args}: {shape} vs {solve}");
    }
    assert!(cmd(&mut a, "shape 1 0 100 0").starts_with("err limit:"));
    assert!(cmd(&mut a, "shape").starts_with("err usage:"));
}
