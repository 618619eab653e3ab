//! The `pose` and `contact` console handlers (finger-fw's src/inverse_cmds.rs): reply format,
//! outputs moved only through `apply` and never on an error; and the same commands through
//! the firmware's console on the simulated board (finger-sim's application): `pose` moves
//! the outputs only when armed, through the checks of `volt` and `force`.

use finger_fw::app::CmdError;
use finger_fw::inverse_cmds;

use finger_model::{Finger, Method, Params};

fn kv(reply: &str, key: &str) -> Vec<f64> {
    let v = reply
        .split_whitespace()
        .find_map(|w| w.strip_prefix(&format!("{key}=")))
        .unwrap_or_else(|| panic!("no {key} in {reply}"));
    v.split(',').map(|x| x.parse().unwrap()).collect()
}

#[test]
fn pose_replies_and_applies_once() {
    let f = Finger::new(Params::<f32>::default()).unwrap();
    let s = f.solve(1.0, &[2000.0, 5000.0, 8000.0], Method::converged()).unwrap();
    let deg: Vec<f64> = s.joint_angles().iter().map(|a| (*a as f64).to_degrees()).collect();
    let mut out = String::new();
    let mut applied = None;
    let ok = inverse_cmds::pose(&mut out, &f, &deg, None, |p, v| {
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
        assert!((joints[k] - deg[k]).abs() < 1e-3);
    }
    let (p, v) = applied.expect("apply called");
    assert!((p as f64 - force).abs() < 1e-3 && (v[1] as f64 - volts[1]).abs() < 1.0);
    // the reply's force and voltages hold the posture (forward solve)
    let vv: Vec<f32> = volts.iter().map(|&x| x as f32).collect();
    let back = f.solve(force as f32, &vv, Method::converged()).unwrap();
    for k in 0..3 {
        assert!(((back.joint_angle[k] as f64).to_degrees() - deg[k]).abs() < 0.01);
    }
}

#[test]
fn pose_unreachable_or_refused_moves_nothing() {
    let f = Finger::new(Params::<f32>::default()).unwrap();
    let mut out = String::new();
    let mut called = false;
    let ok = inverse_cmds::pose(&mut out, &f, &[20.0, 5.0, 5.0], None, |_, _| {
        called = true;
        Ok(())
    })
    .unwrap();
    assert!(!ok && !called);
    assert!(out.starts_with("err unreachable: joint 1"), "{out}");
    // wrong number of angles
    out.clear();
    assert!(!inverse_cmds::pose(&mut out, &f, &[5.0, 5.0], None, |_, _| panic!("moved")).unwrap());
    assert!(out.starts_with("err usage:"), "{out}");
    // the dispatcher's apply refuses (e.g. a force limit): its error is the reply
    out.clear();
    let ok = inverse_cmds::pose(&mut out, &f, &[5.0, 5.0, 5.0], None, |_, _| Err(CmdError::new("limit", "force past fmax"))).unwrap();
    assert!(!ok);
    assert_eq!(out, "err limit: force past fmax");
    // a negative tension
    out.clear();
    assert!(!inverse_cmds::pose(&mut out, &f, &[5.0, 5.0, 5.0], Some(-1.0), |_, _| panic!("moved")).unwrap());
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
