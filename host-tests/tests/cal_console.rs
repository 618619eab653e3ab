//! The `cal` console addition (docs/firmware.md "Console additions") on the
//! simulated board: the board boots with docs/model.md's finger's FE calibration; it is read, set
//! and cleared; the calibrated finger is the host model's `Finger::with_calibration` in f32;
//! refusals change nothing.
use finger_fw::sim::SimBoard;
use finger_fw::App;
use finger_model::{Calibration, Finger, Method};
use host_tests::console::{ceiling, err};
use host_tests::reply::{nums, val};
use host_tests::sim_console::{cmd, frac_of, Out};

/// docs/model.md's finger, as `fe-calibrate` (tools/calculix) prints it (docs/firmware.md).
/// Another calibration, for the tests that set one.
const FE_CAL: &str = "1.540745 6.245597 1.066900 1.154625 0.718260 0.054631 5.254023 -1.756332";
const OTHER: &str = "1.5 2 1 1.25 0.5 0 2 -0.25";
const OTHER_REPLY: &str = "ok cal=1.500000,2.000000,1.000000,1.250000,0.500000,0.000000,2.000000,-0.250000";
const NONE_REPLY: &str = "ok cal=1.000000,1.000000,1.000000,1.000000,1.000000,0.000000,1.000000,0.000000";

/// The FE line as the model's type, parsed as the host parses f32 (correctly rounded, as the
/// console's parser).
fn fe_cal() -> Calibration<f32> {
    let g: Vec<f32> = FE_CAL.split(' ').map(|x| x.parse().unwrap()).collect();
    Calibration { hinge: [g[0], g[1], g[2], g[3]], stack_axial: [g[4], g[5]], stack_bending: [g[6], g[7]] }
}

fn fe_reply() -> String {
    format!("ok cal={}", FE_CAL.replace(' ', ","))
}

/// `solve`'s reply up to its stiffness, as the firmware formats it from a host solution
/// (`Fixed` prints as core's `{:.p}`; `Exp`'s last digit may differ, so it is left out).
/// `solve`'s reply is the host's f32 converged solve of `f`: each printed number within one unit
/// of its last printed digit (the board's tabled solve and the host's full one agree to the
/// model's accuracy, 1e-3 mm, not to the rounding of the last digit).
fn assert_solve_reply(r: &str, f: &Finger<f32>, p: f32, v: [f32; 3]) {
    let s = f.solve(p, &v, Method::converged()).unwrap();
    let deg = 180.0f64 / std::f64::consts::PI;
    let t = s.tip();
    let j = s.joint_angle.map(|a| f64::from(a) * deg);
    let th = s.thickness.map(f64::from);
    let want: [(&str, Vec<(f64, f64)>); 4] = [
        ("joints", (0..3).map(|i| (j[i], 1e-3)).collect()),
        ("tip", vec![(f64::from(t.x), 1e-3), (f64::from(t.y), 1e-3), (f64::from(t.theta) * deg, 1e-2)]),
        ("cable", vec![(f64::from(s.cable_excursion), 1e-4)]),
        ("thick", (0..3).map(|i| (th[i], 1e-4)).collect()),
    ];
    assert!(r.starts_with("ok joints="), "{r}");
    for (key, w) in &want {
        let got = nums(val(r, key));
        assert_eq!(got.len(), w.len(), "{key} in {r}");
        for (g, (w, unit)) in got.iter().zip(w) {
            assert!((g - w).abs() <= *unit, "{key}: {g} vs {w} (one printed unit {unit}) in {r}");
        }
    }
}

#[test]
fn cal_round_trip_and_help() {
    let mut a = App::new(SimBoard::default());
    let help = cmd(&mut a, "help");
    assert_eq!(help, "ok");
    let mut out = Out(String::new());
    a.input(b"help\n", &mut out);
    assert!(out.0.lines().any(|l| l.starts_with("cal ")), "help lacks cal: {}", out.0);
    // the firmware's default is docs/model.md's finger with its FE calibration
    assert_eq!(cmd(&mut a, "cal"), fe_reply());
    assert_eq!(*a.finger().calibration(), fe_cal());
    assert_eq!(*a.finger().calibration(), Calibration::<f32>::model_md());
    assert_eq!(cmd(&mut a, "cal none"), NONE_REPLY);
    assert_eq!(*a.finger().calibration(), Calibration::none());
    assert_eq!(cmd(&mut a, &format!("cal {FE_CAL}")), fe_reply());
    assert_eq!(cmd(&mut a, "cal"), fe_reply());
    assert_eq!(*a.finger().calibration(), fe_cal());
    // numbers in any of the console's forms
    assert_eq!(cmd(&mut a, "cal 1.5 +2 1e0 1.25 .5 0.0 2 -0.25E0"), "ok cal=1.500000,2.000000,1.000000,1.250000,0.500000,0.000000,2.000000,-0.250000");
    assert_eq!(cmd(&mut a, "CAL NONE"), NONE_REPLY);
    assert_eq!(*a.finger().calibration(), Calibration::none());
}

#[test]
fn calibrated_solve_is_the_host_model() {
    let mut a = App::new(SimBoard::default());
    let p = *a.finger().params();
    let plain = Finger::new(p).unwrap();
    let cal = Finger::with_calibration(p, fe_cal()).unwrap();
    cmd(&mut a, "cal none");
    let fmax0 = nums(val(&cmd(&mut a, "limits"), "fmax"))[0];
    let evals = a.fmax_evaluations();
    cmd(&mut a, &format!("cal {FE_CAL}"));
    let vm = ceiling(&mut a);
    let at = |f: [f64; 3]| f.map(|f| frac_of(vm, f));
    for (f, v) in [(0.5f32, [0.0f32, 1000.0, 2000.0]), (1.5, at([0.3, 0.0, 0.8])), (0.8, [0.0; 3])] {
        let line = format!("solve {f} {} {} {}", v[0], v[1], v[2]);
        let r = cmd(&mut a, &line);
        assert_solve_reply(&r, &cal, f, v);
        let s = cal.solve(f, &v, Method::converged()).unwrap();
        let k = cal.tip_stiffness(&s).unwrap();
        let got = nums(val(&r, "stiffness"));
        for i in 0..3 {
            assert!((got[i] - k[i][i] as f64).abs() <= 1e-3 * (k[i][i] as f64).abs(), "{r} vs {k:?}");
        }
        // and not the uncalibrated model's answer: the calibrated finger bends more
        let j0 = plain.solve(f, &v, Method::converged()).unwrap().joint_angle;
        let j = nums(val(&r, "joints"));
        for i in 0..3 {
            assert!(j[i] > (j0[i] as f64).to_degrees() * 1.05, "{r} vs uncalibrated {j0:?}");
        }
    }
    // the fmax cache was dropped: recomputed for the calibrated finger, and its answer
    let fmax1 = nums(val(&cmd(&mut a, "limits"), "fmax"))[0];
    assert_eq!(a.fmax_evaluations(), evals + 1);
    let want = cal.fmax(&[0.0; 3]).unwrap().tension as f64;
    // the board's fmax is its branch table's: never above the full search's by more than 1e-4 N,
    // below it by at most the table's 2e-4 (table_console)
    assert!(fmax1 <= want + 1e-4 && fmax1 >= want * (1.0 - 2e-4) && (fmax1 - fmax0).abs() > 1e-3, "{fmax1} vs {want}, uncalibrated {fmax0}");
    // `cal none` is the uncalibrated model again
    cmd(&mut a, "cal none");
    let r = cmd(&mut a, "solve 0.5 0 1000 2000");
    assert_solve_reply(&r, &plain, 0.5, [0.0, 1000.0, 2000.0]);
}

#[test]
fn cal_refused_while_armed() {
    let mut a = App::new(SimBoard::default());
    cmd(&mut a, "arm");
    err(&mut a, &format!("cal {OTHER}"), "armed");
    err(&mut a, "cal none", "armed");
    assert_eq!(cmd(&mut a, "cal"), fe_reply(), "reading is fine armed");
    cmd(&mut a, "disarm");
    cmd(&mut a, "wait 1");
    assert_eq!(cmd(&mut a, "cal none"), NONE_REPLY);
    cmd(&mut a, "arm");
    err(&mut a, &format!("cal {FE_CAL}"), "armed");
    assert_eq!(cmd(&mut a, "cal"), NONE_REPLY);
    assert_eq!(*a.finger().calibration(), Calibration::none());
}

#[test]
fn bad_cal_changes_nothing() {
    let mut a = App::new(SimBoard::default());
    cmd(&mut a, &format!("cal {FE_CAL}"));
    let state = |a: &mut App<SimBoard>| format!("{} | {} | {}", cmd(a, "status"), cmd(a, "limits"), cmd(a, "cal"));
    let before = state(&mut a);
    let evals = a.fmax_evaluations();
    for (line, code) in [
        ("cal 1 2 3", "usage"),
        ("cal bogus", "usage"),
        ("cal none 1", "usage"),
        ("cal 1 1 1 1 1 0 1 0 9", "usage"),
        ("cal nan 1 1 1 1 0 1 0", "bad-number"),
        ("cal 1 1 1 1 1 0 1 inf", "bad-number"),
        ("cal 1 1 0x1 1 1 0 1 0", "bad-number"),
        ("cal 1 1 1 1 1 0 1e999 0", "bad-number"),
        ("cal 1 1 1 1.5abc 1 0 1 0", "bad-number"),
        // refused by the model (Error::Param "cal"): a factor outside 0.1..10
        ("cal 0.05 1 1 1 1 0 1 0", "usage"),
        ("cal 1 1 1 11 1 0 1 0", "usage"),
        // EI factor 2 at 2 mm but below 0.1 at the pull-in thickness 4/3 mm
        ("cal 1 1 1 1 1 0 -6 4", "usage"),
        ("cal 1 1 1 1 -1 0 1 0", "usage"),
    ] {
        err(&mut a, line, code);
        assert_eq!(state(&mut a), before, "{line} changed something");
        assert_eq!(*a.finger().calibration(), fe_cal(), "{line}");
    }
    // the fmax cache survived every refusal
    assert_eq!(a.fmax_evaluations(), evals);
}

#[test]
fn preset_and_mechanical_param_give_their_parameters_calibration() {
    let mut a = App::new(SimBoard::default());
    let other = format!("cal {OTHER}");
    // back to docs/model.md's finger (any mechanical value at its default): its FE calibration
    for back in ["preset default", "param l 27", "param a 5", "param m 8", "param layers 0"] {
        cmd(&mut a, "preset default");
        assert_eq!(cmd(&mut a, &other), OTHER_REPLY);
        assert!(cmd(&mut a, back).starts_with("ok"), "{back}");
        assert_eq!(cmd(&mut a, "cal"), fe_reply(), "{back}");
        assert_eq!(*a.finger().calibration(), fe_cal());
    }
    // another finger: none (the factors were computed for docs/model.md's)
    for clear in ["preset paper", "param l 28", "param a 4", "param layers 10", "param m 4", "param e_b 1"] {
        cmd(&mut a, "preset default");
        cmd(&mut a, &other);
        assert!(cmd(&mut a, clear).starts_with("ok"), "{clear}");
        assert_eq!(cmd(&mut a, "cal"), NONE_REPLY, "{clear} kept the calibration");
        assert_eq!(*a.finger().calibration(), Calibration::none());
    }
    // and back again
    cmd(&mut a, "preset default");
    cmd(&mut a, "param l 28");
    cmd(&mut a, "param v_supply 9000");
    cmd(&mut a, "param l 27");
    assert_eq!(cmd(&mut a, "cal"), fe_reply());
    // electrical, solver and firmware parameters keep the one in force; so do a read and a refused set
    cmd(&mut a, "preset default");
    cmd(&mut a, &other);
    for keep in
        ["param margin 0.5", "param v_supply 9000", "param eps_r 4", "param n_inc 20", "param slew 5000", "param l", "param", "param l 1e9", "param nope 1"]
    {
        cmd(&mut a, keep);
        assert_eq!(cmd(&mut a, "cal"), OTHER_REPLY, "{keep} changed the calibration");
    }
    // and the finger after them is the host's calibrated finger at those parameters
    let g: Vec<f32> = OTHER.split(' ').map(|x| x.parse().unwrap()).collect();
    let c = Calibration { hinge: [g[0], g[1], g[2], g[3]], stack_axial: [g[4], g[5]], stack_bending: [g[6], g[7]] };
    let f = Finger::with_calibration(*a.finger().params(), c).unwrap();
    let r = cmd(&mut a, "solve 1 0 1000 2000");
    assert_solve_reply(&r, &f, 1.0, [0.0, 1000.0, 2000.0]);
}

#[test]
fn pose_after_cal_uses_the_calibrated_finger() {
    let mut a = App::new(SimBoard::default());
    let p = *a.finger().params();
    let plain = Finger::new(p).unwrap();
    // a `pose` before builds the uncalibrated branch table: `cal` must drop it
    cmd(&mut a, "cal none");
    let r0 = cmd(&mut a, "pose 5 5 5");
    assert!(r0.starts_with("ok force="), "{r0}");
    cmd(&mut a, &format!("cal {FE_CAL}"));
    let cal = Finger::with_calibration(p, fe_cal()).unwrap();
    // a posture of the calibrated finger, typed as a user would
    let vm = ceiling(&mut a);
    let s = cal.solve(1.0, &[0.2, 0.5, 0.8].map(|f| frac_of(vm, f)), Method::converged()).unwrap();
    let deg = [0, 1, 2].map(|k| format!("{:.6}", (s.joint_angle[k] as f64).to_degrees()).parse::<f64>().unwrap());
    let rad = deg.map(|d| (d as f32) * (std::f64::consts::PI / 180.0) as f32);
    // the firmware's inverse options: its ceiling in force
    let opts = finger_model::inverse::Options { hv_fs: Some(vm as f32), ..Default::default() };
    let want = finger_model::inverse::solve_pose_tabled(&finger_model::inverse::BranchTable::new(&cal, &opts).unwrap(), &rad, None).unwrap();
    let line = format!("pose {} {} {}", deg[0], deg[1], deg[2]);
    let r = cmd(&mut a, &line);
    assert!(r.starts_with("ok force="), "{r}");
    assert!((nums(val(&r, "force"))[0] - want.tension as f64).abs() < 1e-3, "{r} vs {want:?}");
    let volts = nums(val(&r, "volts"));
    for k in 0..3 {
        assert!((volts[k] - want.volts[k] as f64).abs() < 0.06, "{r} vs {want:?}");
        assert!((nums(val(&r, "joints"))[k] - deg[k]).abs() < 1e-3, "{r}");
    }
    // the uncalibrated finger's answer to the same angles is another one
    let other = finger_model::inverse::solve_pose_tabled(&finger_model::inverse::BranchTable::new(&plain, &opts).unwrap(), &rad, None).unwrap();
    assert!((other.tension - want.tension).abs() > 0.05, "{other:?} vs {want:?}");
    // armed, the same answer moves the outputs
    cmd(&mut a, "arm");
    assert!(r.ends_with(" moved=0"), "{r}");
    assert_eq!(cmd(&mut a, &line), r.replace(" moved=0", " moved=1"));
    assert_eq!(a.targets(), [want.volts[0], want.volts[1], want.volts[2]]);
    cmd(&mut a, "stop");
}

/// A `param` set that changes the calibration in force says so: its reply adds `cal=` with the
/// factors now in force (was `ok e_b=15` alone, the calibration dropped in silence); a set that
/// keeps it adds nothing.
#[test]
fn a_param_that_changes_the_calibration_says_so() {
    let mut a = App::new(SimBoard::default());
    let none = NONE_REPLY.trim_start_matches("ok ");
    assert_eq!(cmd(&mut a, "param e_b 15"), format!("ok e_b=15 {none}"));
    assert_eq!(cmd(&mut a, "cal"), NONE_REPLY);
    // back to docs/model.md's finger: its factors, said again
    assert_eq!(cmd(&mut a, "param e_b 12"), format!("ok e_b=12 {}", fe_reply().trim_start_matches("ok ")));
    // kept: nothing added
    assert_eq!(cmd(&mut a, "param margin 0.5"), "ok margin=0.5");
    assert_eq!(cmd(&mut a, "param l 27"), "ok l=27");
    assert_eq!(cmd(&mut a, "param e_b"), "ok e_b=12");
}
