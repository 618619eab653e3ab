//! The `pose` and `contact` console handlers (finger-fw's src/app/pose.rs): reply format,
//! outputs moved only through `apply` and never on an error; and the same commands through
//! the firmware's console on the simulated board (finger-sim's application): `pose` moves
//! the outputs only when armed, through the checks of `volt` and `force`.

use finger_fw::app::pose as inverse_cmds;
use finger_fw::app::CmdError;

use finger_model::{Finger, Method, Params};

use host_tests::reply::field as kv;

#[test]
fn pose_replies_and_applies_once() {
    let f = Finger::new(Params::<f32>::default()).unwrap();
    let s = f.solve(1.0, &[2000.0, 5000.0, 8000.0], Method::converged()).unwrap();
    let deg: Vec<f32> = s.joint_angles().iter().map(|a| a.to_degrees()).collect();
    let mut out = String::new();
    let mut applied = None;
    let ok = inverse_cmds::pose(&mut out, &f, None, &deg, None, |p, v| {
        applied = Some((p, v.to_vec()));
        Ok(())
    })
    .unwrap();
    assert!(ok && out.starts_with("ok force="), "{out}");
    let force = kv(&out, "force")[0];
    let volts = kv(&out, "volts");
    let joints = kv(&out, "joints");
    let range = kv(&out, "range");
    assert_eq!(volts.len(), 3);
    assert!(range[0] <= force && force <= range[1]);
    for k in 0..3 {
        assert!((joints[k] - deg[k] as f64).abs() < 1e-3);
    }
    let (p, v) = applied.expect("apply called");
    assert!((p as f64 - force).abs() < 1e-3 && (v[1] as f64 - volts[1]).abs() < 1.0);
    // the reply's force and voltages hold the posture (forward solve)
    let vv: Vec<f32> = volts.iter().map(|&x| x as f32).collect();
    let back = f.solve(force as f32, &vv, Method::converged()).unwrap();
    for k in 0..3 {
        assert!((back.joint_angle[k].to_degrees() - deg[k]).abs() < 0.01);
    }
}

#[test]
fn pose_unreachable_or_refused_moves_nothing() {
    let f = Finger::new(Params::<f32>::default()).unwrap();
    let mut out = String::new();
    let mut called = false;
    let ok = inverse_cmds::pose(&mut out, &f, None, &[20.0, 5.0, 5.0], None, |_, _| {
        called = true;
        Ok(())
    })
    .unwrap();
    assert!(!ok && !called);
    assert!(out.starts_with("err unreachable: joint 1"), "{out}");
    // wrong number of angles
    out.clear();
    assert!(!inverse_cmds::pose(&mut out, &f, None, &[5.0, 5.0], None, |_, _| panic!("moved")).unwrap());
    assert!(out.starts_with("err usage:"), "{out}");
    // the dispatcher's apply refuses (e.g. a force limit): its error is the reply
    out.clear();
    let ok =
        inverse_cmds::pose(&mut out, &f, None, &[5.0, 5.0, 5.0], None, |_, _| Err(CmdError::new(finger_fw::app::ErrorCode::Limit, "force past fmax"))).unwrap();
    assert!(!ok);
    assert_eq!(out, "err limit: force past fmax");
    // a negative tension
    out.clear();
    assert!(!inverse_cmds::pose(&mut out, &f, None, &[5.0, 5.0, 5.0], Some(-1.0), |_, _| panic!("moved")).unwrap());
    assert!(out.starts_with("err usage:"), "{out}");
}

#[test]
fn contact_reply() {
    let f = Finger::new(Params::<f64>::default()).unwrap();
    let mut out = String::new();
    assert!(inverse_cmds::contact(&mut out, &f, 1.0, 1.5, &[]).unwrap(), "{out}");
    let f0 = kv(&out, "force")[0];
    let (fx, fy) = (kv(&out, "fx")[0], kv(&out, "fy")[0]);
    assert!(((fx * fx + fy * fy).sqrt() - f0).abs() < 1e-3 && f0 > 0.1);
    // one sign everywhere: `force_on_tip` is the model's force (the stop's on the tip, as
    // Python's `force_on_tip_N`); `fx`, `fy` its opposite
    let on_tip = kv(&out, "force_on_tip");
    let c = finger_model::inverse::contact_force(&f, 1.0, &[0.0; 3], 1.5, &[0.0; 3]).unwrap();
    assert!((on_tip[0] - c.force[0]).abs() < 1e-3 && (on_tip[1] - c.force[1]).abs() < 1e-3, "{out} vs {:?}", c.force);
    assert!((on_tip[0] + fx).abs() < 1e-3 && (on_tip[1] + fy).abs() < 1e-3, "{out}");
    out.clear();
    assert!(inverse_cmds::contact(&mut out, &f, 1.0, 1.5, &[9000.0, 9000.0, 9000.0]).unwrap(), "{out}");
    assert!(kv(&out, "force")[0] > f0, "voltage raises the contact force: {out}");
    out.clear();
    assert!(!inverse_cmds::contact(&mut out, &f, 1.0, 1.5, &[1.0]).unwrap());
    assert!(out.starts_with("err usage:"));
    out.clear();
    assert!(!inverse_cmds::contact(&mut out, &f, 1.0, 1.5, &[20000.0, 0.0, 0.0]).unwrap());
    assert!(out.starts_with("err limit:"), "{out}");
}

mod console {
    //! `pose` and `contact` through the firmware's console on the simulated board.
    use finger_fw::sim::SimBoard;
    use finger_fw::App;
    use finger_model::Method;
    use host_tests::console::ceiling;
    use host_tests::sim_console::{cmd, frac_of, Out};

    fn outputs(a: &mut App<SimBoard>) -> String {
        let st = cmd(a, "status");
        let b = a.board();
        format!("{st} | {:?} servo={} hv={:?} en={}", a.targets(), b.servo.duty, b.hv.map(|h| h.duty), b.enable.high)
    }

    use host_tests::reply::field as kv;

    /// A posture of the model itself (forward solve at the console's parameters), in degrees
    /// with 6 decimals as a user would type them.
    fn posture(a: &App<SimBoard>, p: f32, v: [f32; 3]) -> (String, [f64; 3]) {
        let s = a.finger().solve(p, &v, Method::converged()).unwrap();
        let d = [0, 1, 2].map(|k| format!("{:.6}", (s.joint_angle[k] as f64).to_degrees()).parse::<f64>().unwrap());
        (format!("{} {} {}", d[0], d[1], d[2]), d)
    }

    #[test]
    fn pose_moves_only_when_armed() {
        let mut a = App::new(SimBoard::default());
        let vm = ceiling(&mut a);
        let (angles, deg) = posture(&a, 1.0, [0.2, 0.5, 0.8].map(|f| frac_of(vm, f)));
        // the model's answer for the same input
        // the angle as the firmware forms it (f32 degrees times f32 pi/180): the voltages are
        // ill-conditioned in the angle (1 ulp of angle moves them ~0.1 V at a 1 % stiffness
        // range), so the comparison needs the same input, not a nearby one
        let rad = deg.map(|d| (d as f32) * (std::f64::consts::PI / 180.0) as f32);
        // the firmware solves with the finger's branch table (built at the first `pose`)
        let opts = finger_model::inverse::Options { hv_fs: Some(vm as f32), ..Default::default() };
        let table = finger_model::inverse::BranchTable::new(a.finger(), &opts).unwrap();
        let want = finger_model::inverse::solve_pose_tabled(&table, &rad, None).unwrap();
        // disarmed: the answer, nothing moves
        let before = outputs(&mut a);
        let r = cmd(&mut a, &format!("pose {angles}"));
        assert!(r.starts_with("ok force="), "{r}");
        assert!((kv(&r, "force")[0] - want.tension as f64).abs() < 1e-3, "{r}");
        let volts = kv(&r, "volts");
        for k in 0..3 {
            assert!((volts[k] - want.volts[k] as f64).abs() < 0.06, "{r} want {:?}", want.volts);
            assert!((kv(&r, "joints")[k] - deg[k]).abs() < 1e-3, "{r}");
        }
        let range = kv(&r, "range");
        assert!(range[0] <= kv(&r, "force")[0] && kv(&r, "force")[0] <= range[1], "{r}");
        assert_eq!(outputs(&mut a), before, "disarmed pose moved something");
        assert!(!a.board().enable.high_ever);
        // armed: the setpoints are the model's, the cable holds its tension
        assert_eq!(cmd(&mut a, "arm"), "ok armed=1");
        let r2 = cmd(&mut a, &format!("pose {angles}"));
        assert!(r.ends_with(" moved=0"), "{r}");
        assert_eq!(r2, r.replace(" moved=0", " moved=1"));
        assert_eq!(a.targets(), [want.volts[0], want.volts[1], want.volts[2]]);
        let st = cmd(&mut a, "status");
        assert!((kv(&st, "force")[0] - want.tension as f64).abs() < 1e-3, "{st}");
        assert!(kv(&st, "servo")[0] > 0.0, "{st}");
        // after the slew the stacks still creep toward their targets: the posture the console
        // reports (at the stacks' thickness now) is short of the requested one; once `settle`
        // has passed, it is the requested one
        cmd(&mut a, "wait 10");
        let st = cmd(&mut a, "status");
        for k in 0..3 {
            assert!(kv(&st, "joints")[k] < deg[k] + 1e-3, "{st}");
        }
        let settle = kv(&r, "settle")[0];
        cmd(&mut a, &format!("wait {}", (settle - 10.0).ceil().max(1.0)));
        let st = cmd(&mut a, "status");
        for k in 0..3 {
            assert!((kv(&st, "joints")[k] - deg[k]).abs() < 0.01, "{st}");
        }
        // a given tension (inside the range) is kept
        let p = (range[0] + range[1]) / 2.0;
        let r3 = cmd(&mut a, &format!("pose {angles} {p}"));
        assert!((kv(&r3, "force")[0] - p).abs() < 1e-3, "{r3}");
        cmd(&mut a, "stop");
    }

    #[test]
    fn pose_refused_moves_nothing() {
        let mut a = App::new(SimBoard::default());
        assert_eq!(cmd(&mut a, "arm"), "ok armed=1");
        assert!(cmd(&mut a, "volt all 1000").starts_with("ok"));
        cmd(&mut a, "wait 1");
        let before = outputs(&mut a);
        let r = cmd(&mut a, "pose 20 5 5");
        assert!(r.starts_with("err unreachable: joint 1"), "{r}");
        for (bad, code) in [
            ("pose 1 2", "usage"),
            ("pose 1 2 3 4 5", "usage"),
            ("pose nan 1 1", "bad-number"),
            ("pose 1 1 1 -1", "usage"),
            ("pose 1 1 1 1e30", "limit"),
            ("pose 400 1 1", "usage"),
        ] {
            let r = cmd(&mut a, bad);
            assert!(r.starts_with(&format!("err {code}:")), "{bad} -> {r}");
        }
        assert_eq!(outputs(&mut a), before);
        // a latched fault: armed pose refuses through the same check as volt
        let d = a.duty_ceiling()[0];
        assert!(a.write_hv_duty(0, d + 1).is_err());
        let (angles, _) = posture(&a, 0.5, [0.0; 3]);
        let before = outputs(&mut a);
        assert!(cmd(&mut a, &format!("pose {angles}")).starts_with("err fault:"));
        assert_eq!(outputs(&mut a), before);
    }

    #[test]
    fn contact_command() {
        let mut a = App::new(SimBoard::default());
        let before = outputs(&mut a);
        let r = cmd(&mut a, "contact 1 1.5");
        // the handler's own reply on the console's model
        let mut want = String::new();
        assert!(super::inverse_cmds::contact(&mut want, a.finger(), 1.0, 1.5, &[]).unwrap());
        assert_eq!(r, want);
        let (fx, fy, f) = (kv(&r, "fx")[0], kv(&r, "fy")[0], kv(&r, "force")[0]);
        assert!(((fx * fx + fy * fy).sqrt() - f).abs() < 2e-3 && f > 0.0, "{r}");
        // the contact point is the free tip at P0 (0 V)
        let free = a.finger().solve(1.0, &[0.0; 3], Method::converged()).unwrap();
        let pt = kv(&r, "point");
        assert!((pt[0] - free.tip().x as f64).abs() < 2e-3 && (pt[1] - free.tip().y as f64).abs() < 2e-3, "{r}");
        let v = frac_of(ceiling(&mut a), 0.3);
        let r = cmd(&mut a, &format!("contact 1 1.5 {v} {v} {v}"));
        assert!(r.starts_with("ok fx="), "{r}");
        for (bad, code) in [
            ("contact 1", "usage"),
            ("contact 1 2 3", "usage"),
            ("contact nan 1", "bad-number"),
            ("contact 1 1.5 20000 0 0", "limit"),
            ("contact -1 1", "usage"),
        ] {
            let r = cmd(&mut a, bad);
            assert!(r.starts_with(&format!("err {code}:")), "{bad} -> {r}");
        }
        assert_eq!(outputs(&mut a), before, "contact is model only");
        let help = {
            let mut out = Out(String::new());
            a.input(b"help\n", &mut out);
            out.0
        };
        assert!(help.lines().any(|l| l.starts_with("contact ")) && help.lines().any(|l| l.starts_with("pose ")));
    }
}
