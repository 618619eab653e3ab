//! The contact force by continuation (model inverse/contact.rs, finger/pinned.rs) on the
//! default finger: a grid of P0 0.05-5 N, P up to fmax at the voltages, voltages 0 to the
//! ceiling. Every request answers or is refused with a typed reason (past fmax, links
//! touching, limit point); none faults, and every answer holds: a forward solve with that tip
//! load puts the tip on the stop.

use finger_model::inverse::contact_force;
use finger_model::{Error, Finger, Method, Params};

fn grid_volts(ceiling: f64) -> Vec<[f64; 3]> {
    let top = ceiling * (1.0 - 1e-4);
    vec![[0.0; 3], [top / 3.0; 3], [2.0 * top / 3.0; 3], [top; 3], [0.0, top / 2.0, top], [top, 0.0, top / 2.0]]
}

#[test]
fn contact_grid_on_the_default_finger_answers_or_refuses_and_every_answer_holds_the_tip() {
    let f = Finger::new(Params::<f64>::default()).unwrap();
    let ceiling = f.voltage_ceiling();
    let (mut answers, mut refused, mut cases, mut pulls) = (0, 0, 0, 0);
    let mut worst = 0.0f64;
    let (mut agree, mut elsewhere) = (0, 0);
    let (mut worst_fwd, mut small_off) = (0.0f64, 0.0f64);
    for v in grid_volts(ceiling) {
        let fmax = f.fmax(&v).unwrap().tension;
        for i in 0..8 {
            let p0 = 0.05 + (5.0 - 0.05) * i as f64 / 7.0;
            for j in 0..=8 {
                let p = fmax * j as f64 / 8.0;
                cases += 1;
                match contact_force(&f, p0, &[0.0; 3], p, &v) {
                    Ok(c) => {
                        answers += 1;
                        assert!(c.force.iter().all(|x| x.is_finite()), "P0={p0} P={p} V={v:?}: {:?}", c.force);
                        // the answer is a forward equilibrium under that tip load (its relative
                        // wrench imbalance, `equilibrium_residual`, under 1e-8; measured at most
                        // 9.3e-11), with the tip on the stop
                        let sol = &c.solution;
                        let on = ((sol.tip().x - c.point[0]).powi(2) + (sol.tip().y - c.point[1]).powi(2)).sqrt();
                        let fwd = f.equilibrium_residual(sol).unwrap();
                        assert!(
                            sol.residual < 1e-7 && fwd < 1e-8 && on < 1e-6,
                            "P0={p0} P={p} V={v:?}: residual {:.2e} (afresh {fwd:.2e}), tip {on:.2e} mm off",
                            sol.residual
                        );
                        worst_fwd = worst_fwd.max(fwd);
                        // a forward solve with that tip load by load continuation from the straight
                        // finger: the same equilibrium where the loaded branch is unique (a large
                        // tip load on the bent finger has several; then it may find another)
                        match f.solve_loaded(p, &v, c.force, Method::converged()) {
                            Ok(s) => {
                                let d = ((s.tip().x - c.point[0]).powi(2) + (s.tip().y - c.point[1]).powi(2)).sqrt();
                                if d < 1e-5 * 81.0 {
                                    agree += 1;
                                    worst = worst.max(d);
                                } else {
                                    elsewhere += 1;
                                    small_off = small_off.max(if c.magnitude() < 0.5 { d } else { 0.0 });
                                }
                            }
                            Err(_) => {
                                elsewhere += 1;
                                small_off = small_off.max(if c.magnitude() < 0.5 { f64::INFINITY } else { 0.0 });
                            }
                        }
                        if p == p0 && v == [0.0; 3] {
                            assert!(c.magnitude() < 1e-9, "P = P0 at 0 V: no force, got {:?}", c.force);
                        }
                    }
                    // the stop would pull (issue 55; below P0, and near fmax at high voltages): refused
                    Err(Error::PullingStop { .. }) => pulls += 1,
                    Err(e @ (Error::ForceLimit { .. } | Error::Contact { .. } | Error::LimitPoint { .. })) => {
                        refused += 1;
                        eprintln!("P0={p0} P={p} V={v:?}: refused: {e}");
                    }
                    Err(e) => panic!("P0={p0} P={p} V={v:?}: fault {e:?}"),
                }
            }
        }
    }
    eprintln!("{cases} requests: {answers} answers (relative wrench imbalance at most {worst_fwd:.2e}; {agree} also reached by a forward solve from straight, at most {worst:.2e} mm off, {elsewhere} not), {refused} typed refusals");
    assert!(small_off < 1e-5 * 81.0, "a contact force under 0.5 N that the forward solve from straight does not reproduce: {small_off:.2e} mm");
    assert!(agree > 0);
    assert_eq!(answers + refused + pulls, cases);
    assert!(answers + pulls >= cases * 9 / 10, "{answers} of {cases} answered, {pulls} pulling");
}

/// The pair: the fourth digit does not decide between an answer and a fault.
#[test]
fn contact_is_continuous_in_its_arguments() {
    let f = Finger::new(Params::<f32>::default()).unwrap();
    let a = contact_force(&f, 2.2188, &[0.0; 3], 3.8999, &[0.0; 3]).unwrap();
    let b = contact_force(&f, 2.219, &[0.0; 3], 3.9, &[0.0; 3]).unwrap();
    assert!((a.magnitude() - b.magnitude()).abs() < 1e-2 * a.magnitude(), "{} vs {}", a.magnitude(), b.magnitude());
}

/// Issue 55: `contact` answers only the branch the finger reaches from its free posture. The
/// design study's front design (t_min 2.9 mm, a 2.6 mm, E_b 40 MPa, w 30 mm, 7 layers) on the
/// default film, stopped at 35.16 N and pulled to just below fmax: before, one continuation step
/// jumped to a buckled equilibrium (joints -23°, 110°, -155°, 1,389 N); now every joint stays
/// within 30° and bends the way the cable pulls.
#[test]
fn contact_answers_the_branch_the_finger_reaches() {
    let p = Params::<f64> { t_min: 2.9, a: 2.6, e_b: 40.0, w: 30.0, layers: 7, ..Params::default() };
    let f = Finger::new(p).unwrap();
    let fmax = f.fmax(&[0.0; 3]).unwrap().tension;
    let c = contact_force(&f, 35.15564406, &[0.0; 3], fmax - 0.01, &[0.0; 3]).unwrap();
    for k in 0..3 {
        let deg = c.solution.joint_angle[k].to_degrees();
        assert!((0.0..30.0).contains(&deg), "joint {k} at {deg:.1}° ({:?})", c.solution.joint_angle);
    }
}

/// Issue 55: a stop only pushes. Tension lowered below P0 (1 N -> 0.5 N), the pinned tip would
/// need the stop to pull it (before: answered 0.27 N on the board's film, 0.32 N under gravity):
/// refused, typed.
#[test]
fn contact_refuses_a_stop_that_pulls() {
    // without gravity and hanging under it (the board's orientation: the coupled system's
    // centroids among the unknowns)
    for grav in [0.0, 9.81] {
        let p = Params::<f64>::with_card(&finger_model::material::VHB_4905).with_gravity(grav, 0.0);
        let f = Finger::with_calibration(p, finger_model::Calibration::model_md()).unwrap();
        let r = contact_force(&f, 1.0, &[0.0; 3], 0.5, &[0.0; 3]);
        assert!(matches!(r, Err(Error::PullingStop { force, .. }) if force > 0.0), "{grav}: {:?}", r.map(|c| c.force));
        // pulled harder than P0, the same stop pushes
        let c = contact_force(&f, 1.0, &[0.0; 3], 1.5, &[0.0; 3]).unwrap();
        assert!(c.magnitude() > 0.1, "{grav}: {:?}", c.force);
    }
}

/// Issue 54: in f32 (the firmware's scalar) the pinned solve answers what f64 answers. The
/// board's finger as it boots (its FE calibration), the contact bench's cases at 0/5/10 kV and
/// 3.3 kV: with a forward-difference Jacobian each Newton iteration the f32 solves stalled step
/// after step and refused them as limit points at 10.7 N and 5.9 N; on Broyden's estimate they
/// answer within 0.1 % of f64, without gravity and hanging under it.
#[test]
fn contact_in_f32_answers_what_f64_answers() {
    let cases = [(4.292857, 14.098452, [0.0, 4999.5, 9999.0]), (2.8785713, 8.304465, [3333.0; 3])];
    for grav in [0.0, finger_model::params::G_STANDARD] {
        let p32 = Params::<f32>::default().with_gravity(grav as f32, 0.0);
        let p64 = Params::<f64>::default().with_gravity(grav, 0.0);
        let f32_ = Finger::with_calibration(p32, finger_model::Calibration::for_params(&p32)).unwrap();
        let f64_ = Finger::with_calibration(p64, finger_model::Calibration::for_params(&p64)).unwrap();
        for (p0, p, v) in cases {
            let want = contact_force(&f64_, p0 as f64, &[0.0; 3], p as f64, &v.map(|x| x as f64)).unwrap();
            let got = contact_force(&f32_, p0, &[0.0; 3], p, &v).unwrap_or_else(|e| panic!("{grav} P0={p0} P={p} V={v:?}: {e}"));
            let d = ((got.force[0] as f64 - want.force[0]).powi(2) + (got.force[1] as f64 - want.force[1]).powi(2)).sqrt();
            assert!(d <= 1e-3 * want.magnitude(), "{grav} P0={p0} P={p} V={v:?}: f32 {:?}, f64 {:?}", got.force, want.force);
        }
    }
}
