//! The FE calibration: the calibrated model's small-load element compliance equals the
//! FE's; the cable's small-load joint angle (NLGEOM springs) agrees with the linear unit loads.
use finger_calculix::calibrate::{self, model_element_compliance};
use finger_calculix::ccx::{Kind, Law};
use finger_calculix::mesh::Density;
use finger_calculix::{element_compliance, finger_under_cable};
use finger_model::material::ELASTOSIL_2030;
use finger_model::{Calibration, Params};

#[test]
fn calibrated_element_compliance_equals_the_fe() {
    let p = Params::<f64>::default();
    let run = calibrate::run(&p, Kind::Half3d, &Density::coarse()).unwrap();
    let m = model_element_compliance(&p, &run.cal, 0.0).unwrap();
    let m0 = model_element_compliance(&p, &Calibration::none(), 0.0).unwrap();
    for (r, c) in [(0, 0), (1, 1), (1, 2), (2, 2)] {
        let fe = run.fe_hinge[r][c];
        assert!(((m[r][c] - fe) / fe).abs() < 1e-6, "hinge ({r},{c}): model {} FE {fe}", m[r][c]);
    }
    // uncalibrated, the hinge is much stiffer than the FE's
    assert!(m0[2][2] < 0.95 * run.fe_hinge[2][2]);
    for s in &run.stacks {
        let m = model_element_compliance(&p, &run.cal, s.thickness_mm).unwrap();
        let e = (m[2][2] - s.fe[2][2]) / s.fe[2][2];
        assert!(e.abs() < 0.01, "stack {} mm: θ-M off by {:.3} %", s.thickness_mm, 100.0 * e);
        let e = (m[2][0] - s.fe[2][0]) / s.fe[2][0];
        assert!(e.abs() < 0.02, "stack {} mm: θ-Fx off by {:.3} %", s.thickness_mm, 100.0 * e);
    }
}

#[test]
fn cable_springs_agree_with_unit_loads_at_small_tension() {
    // joint 2 at 0.02 N under the follower springs vs [C_el (-1, 0, e)]_θ from the unit loads
    let p = Params::<f64>::default().without_stacks();
    let d = Density::coarse();
    let t = 0.02;
    let s = finger_under_cable(&p, &[0.0; 3], Kind::PlaneStrain, &d, Law::NeoHooke, &[t]).unwrap();
    let c = element_compliance(&p, 0.0, Kind::PlaneStrain, &d).unwrap();
    let lin = t * (-c[2][0] + p.e * c[2][2]);
    let fe = s[0].joint_angle[1];
    assert!(((fe - lin) / lin).abs() < 0.03, "cable {fe} rad vs unit loads {lin} rad");
}

#[test]
fn calibrated_finger_reproduces_the_fe_small_load_joint_angle() {
    // the model's f32 finger with the calibration, under the cable at a small tension, against
    // the 3D FE: the middle joint (away from the clamp and the free end) within 1 %; without
    // the calibration it is more than 5 % stiffer
    use finger_calculix::ccx::Law;
    use finger_model::{Finger, Method};
    let p = Params::<f64>::default().without_stacks();
    let d = Density::coarse();
    let run = calibrate::run(&p, Kind::Half3d, &d).unwrap();
    let t = 0.05;
    let fe = finger_under_cable(&p, &[0.0; 3], Kind::Half3d, &d, Law::NeoHooke, &[t]).unwrap()[0].joint_angle[1];
    let c = run.cal;
    let cal32 =
        Calibration::<f32> { hinge: c.hinge.map(|x| x as f32), stack_axial: c.stack_axial.map(|x| x as f32), stack_bending: c.stack_bending.map(|x| x as f32) };
    let angle = |cal: Calibration<f32>| {
        let f = Finger::<f32>::with_calibration(p.cast(), cal).unwrap();
        f.solve(t as f32, &[0.0; 3], Method::converged()).unwrap().joint_angle[1] as f64
    };
    let (m1, m0) = (angle(cal32), angle(Calibration::none()));
    assert!((m1 / fe - 1.0).abs() < 0.01, "calibrated {m1} rad vs FE {fe} rad");
    assert!(m0 / fe - 1.0 < -0.05, "uncalibrated {m0} rad vs FE {fe} rad");
}

#[test]
fn the_boards_default_calibration_is_fe_calibrates_line() {
    // `Calibration::model_md` (the firmware's default) is what `fe-calibrate` computes for
    // the default finger (docs/model.md "Geometry"; 3D, fine mesh), to the 6 decimals the line prints; and
    // `Calibration::elastosil_2030` for it on the silicone card, where the stacks still matter
    let cases = [(Params::<f64>::default(), Calibration::<f64>::model_md()), (Params::with_card(&ELASTOSIL_2030), Calibration::elastosil_2030())];
    for (p, a) in cases {
        let run = calibrate::run(&p, Kind::Half3d, &Density::fine()).unwrap();
        let b = run.cal;
        let fa = [a.hinge[0], a.hinge[1], a.hinge[2], a.hinge[3], a.stack_axial[0], a.stack_axial[1], a.stack_bending[0], a.stack_bending[1]];
        let fb = [b.hinge[0], b.hinge[1], b.hinge[2], b.hinge[3], b.stack_axial[0], b.stack_axial[1], b.stack_bending[0], b.stack_bending[1]];
        for (i, (x, y)) in fa.iter().zip(&fb).enumerate() {
            assert!((x - y).abs() < 2e-6, "{}: factor {i}: compiled {x}, fe-calibrate {y}", p.card.name);
        }
    }
    assert_eq!(Calibration::for_params(&Params::<f64>::default()), Calibration::<f64>::model_md());
}

#[test]
fn the_calibration_does_not_see_gravity() {
    // the FE's unit loads carry no body load, so the model's side of the calibration is taken
    // without gravity too: a finger held horizontally under 9.81 m/s² calibrates as one without
    let p = Params::<f64>::default();
    for (q, t) in [(p.without_stacks(), 0.0), (p, 2.0)] {
        let a = model_element_compliance(&q, &Calibration::none(), t).unwrap();
        let b = model_element_compliance(&q.with_gravity(9.81, 90.0), &Calibration::none(), t).unwrap();
        assert_eq!(a, b, "stack {t} mm");
    }
}
