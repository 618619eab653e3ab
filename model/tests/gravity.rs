//! Gravity (docs/model.md "Gravity"): the finger under its own weight in any orientation, in
//! the forward, the inverse, fmax and contact. `-- --nocapture` prints what they measure.

use finger_model::calibration::Calibration;
use finger_model::hinge::{notch_thickness, sub_element_bounds};
use finger_model::inverse::{self, contact_force};
use finger_model::mat3;
use finger_model::params::{Params, G_STANDARD};
use finger_model::{Error, Finger, Method, Pose, Solution};

/// The board's finger (VHB 4905, its calibration) under standard gravity along `dir` degrees.
fn board(dir: f64) -> Finger<f64> {
    let p = Params::<f64>::vhb4905().with_gravity(G_STANDARD, dir);
    Finger::with_calibration(p, Calibration::for_params(&p)).unwrap()
}

/// The orientations the issue names: horizontal curling down and up, hanging, pointing up.
const DIRS: [f64; 4] = [90.0, -90.0, 0.0, 180.0];

/// The weight's moment about node 0 (N·mm) of a solved posture, from the distributed load:
/// each hinge's body (ρ_b w t(x)) and stack (ρ_f N_L z0 w) integrated along its deformed
/// sub-elements (16 Gauss-Legendre points each, positions along each sub-element's chord),
/// each link uniform along its chord. Independent of the model's lumping.
fn distributed_moment(p: &Params<f64>, sol: &Solution<f64>) -> (f64, f64) {
    let (gx, gy) = {
        let d = p.grav_dir.to_radians();
        (p.grav * 1e-3 * d.cos(), p.grav * 1e-3 * d.sin())
    };
    let (n, m) = (p.n, p.m);
    let lh = 2.0 * p.a;
    let sub_len = lh / m as f64;
    let stack_per_mm = p.card.rho_g_cm3 * p.layers as f64 * p.z0 * p.w * 1e-3; // g/mm
                                                                               // 16-point Gauss-Legendre on [0, 1] by the midpoint-refined composite rule (64 panels)
    let quad = |f: &dyn Fn(f64) -> f64| -> f64 {
        let panels = 64;
        let (xs, ws) = (
            [-0.861_136_311_594_052_6, -0.339_981_043_584_856_3, 0.339_981_043_584_856_3, 0.861_136_311_594_052_6],
            [0.347_854_845_137_453_9, 0.652_145_154_862_546_1, 0.652_145_154_862_546_1, 0.347_854_845_137_453_9],
        );
        let h = 1.0 / panels as f64;
        (0..panels).map(|i| xs.iter().zip(ws).map(|(x, w)| w * 0.5 * h * f(h * (i as f64 + 0.5 + 0.5 * x))).sum::<f64>()).sum()
    };
    let (mut moment, mut mass) = (0.0, 0.0);
    let mut node = Pose::origin();
    for k in 0..n {
        let mut pose = node;
        for j in 0..m {
            let q = sol.q[k][j];
            let next = pose.then(sub_len + q[0], q[1], q[2]);
            let (x0, _) = sub_element_bounds(p.a, m, j);
            let dens = |s: f64| p.rho_b * p.w * notch_thickness(p.b, p.t_min, p.a, x0 + s * sub_len) * 1e-3 + stack_per_mm;
            let at = |s: f64| (pose.x + s * (next.x - pose.x), pose.y + s * (next.y - pose.y));
            moment += quad(&|s| {
                let (x, y) = at(s);
                dens(s) * sub_len * (x * gy - y * gx)
            });
            mass += quad(&|s| dens(s) * sub_len);
            pose = next;
        }
        let l = sol.links[k];
        let end = pose.then(p.l - lh + l[0], l[1], l[2]);
        let link_g = p.rho_b * p.b * p.w * (p.l - lh) * 1e-3;
        let mid = (0.5 * (pose.x + end.x), 0.5 * (pose.y + end.y));
        moment += link_g * (mid.0 * gy - mid.1 * gx);
        mass += link_g;
        node = end;
    }
    (moment, mass)
}

/// The moment the first sub-element of joint 1 carries about node 0 (N·mm): its wrench
/// C⁻¹ q at its distal end D (base frame: the joint's proximal frame is the base), moved to
/// node 0.
fn root_moment(f: &Finger<f64>, sol: &Solution<f64>) -> f64 {
    let c = f.compliances(&sol.volts[..sol.n]).unwrap();
    let k = mat3::inverse_spd(&c.c[0][0]).unwrap();
    let q = sol.q[0][0];
    let w = mat3::mul_vec(&k, &q);
    let sub_len = 2.0 * f.params().a / f.params().m as f64;
    let d = Pose::origin().then(sub_len + q[0], q[1], q[2]);
    w[2] + d.x * w[1] - d.y * w[0]
}

/// The hand check: held horizontally with no cable, joint 1 carries the weight of everything
/// distal to it times its lever. The model lumps each hinge (with its stack) half at each end
/// and each link at its midpoint; against the distributed load the root moment agrees to the
/// lumping error, and the whole weight is the distributed one.
#[test]
fn joint_one_carries_the_distal_weight_times_its_lever() {
    for layers in [0, 4] {
        let mut p = Params::<f64>::vhb4905().with_gravity(G_STANDARD, 90.0);
        p.layers = layers;
        let f = Finger::with_calibration(p, Calibration::for_params(&p)).unwrap();
        let sol = f.solve(0.0, &[0.0; 3], Method::converged()).unwrap();
        let (m_dist, mass) = distributed_moment(&p, &sol);
        let m_model = root_moment(&f, &sol);
        // the straight finger's lever: the weight at its centroid, a hand figure
        let straight = {
            let link = p.b * p.w * (p.l - 2.0 * p.a) * 1e-3 * p.rho_b;
            let (x_mid, pitch) = (p.a + 0.5 * p.l, p.l);
            let el = mass / 3.0;
            (0..3).map(|k| (el - link) * (k as f64 * pitch + p.a) + link * (k as f64 * pitch + x_mid)).sum::<f64>() * G_STANDARD * 1e-3
        };
        let rel = (m_model - m_dist).abs() / m_dist.abs();
        println!(
            "layers {layers}: mass {mass:.3} g, root moment model {m_model:.5} N·mm, distributed {m_dist:.5} (lumping {rel:.2e}), straight finger {straight:.4}; joints {:?} deg",
            sol.joint_angle[..3].iter().map(|a| a.to_degrees()).collect::<Vec<_>>()
        );
        assert!(mass > 13.0 && mass < 17.0, "the default finger weighs about 15 g: {mass}");
        assert!(rel < 2e-3, "the root moment is the distal weight times its lever, to the lumping error: {rel:.2e}");
        // the bent finger's lever is shorter than the straight one's
        assert!(m_dist < straight && m_dist > 0.9 * straight);
    }
}

/// Gravity bends the finger toward its direction: horizontal, the weight alone bends joint 1
/// most (it carries the most), curling downward and upward mirror each other without stacks,
/// and the orientations order the angles at 1 N (down > hanging > up).
#[test]
fn the_weight_bends_the_finger_by_its_orientation() {
    let no_stacks = |dir: f64| {
        let p = Params::<f64>::vhb4905().with_gravity(G_STANDARD, dir).without_stacks();
        Finger::with_calibration(p, Calibration::for_params(&p)).unwrap()
    };
    let down = no_stacks(90.0).solve(0.0, &[0.0; 3], Method::converged()).unwrap();
    let up = no_stacks(-90.0).solve(0.0, &[0.0; 3], Method::converged()).unwrap();
    let a = |s: &Solution<f64>, k: usize| s.joint_angle[k].to_degrees();
    println!("no cable, horizontal: {:.3} {:.3} {:.3} deg", a(&down, 0), a(&down, 1), a(&down, 2));
    assert!(a(&down, 0) > a(&down, 1) && a(&down, 1) > a(&down, 2) && a(&down, 2) > 0.0);
    assert!(a(&down, 0) > 8.0 && a(&down, 0) < 20.0, "about 14° by the FE: {}", a(&down, 0));
    for k in 0..3 {
        assert!((a(&down, k) + a(&up, k)).abs() < 1e-9, "mirror");
    }
    let at = |dir: f64| board(dir).solve(1.0, &[0.0; 3], Method::converged()).unwrap();
    let plain = Finger::with_calibration(Params::<f64>::vhb4905(), Calibration::for_params(&Params::<f64>::vhb4905())).unwrap();
    let none = plain.solve(1.0, &[0.0; 3], Method::converged()).unwrap();
    let (d, h, u) = (at(90.0), at(0.0), at(-90.0));
    println!("1 N: down {:.3} hanging {:.3} up {:.3} none {:.3} (joint 1, deg)", a(&d, 0), a(&h, 0), a(&u, 0), a(&none, 0));
    assert!(a(&d, 0) > a(&none, 0) && a(&none, 0) > a(&h, 0) && a(&h, 0) > a(&u, 0));
    // hanging, the weight straightens the bent finger: joint 1 about a third lower
    assert!(a(&h, 0) < 0.8 * a(&none, 0) && a(&h, 0) > 0.5 * a(&none, 0));
}

/// Every solve under gravity is in equilibrium: the independent backward error of each
/// posture (its own loads, the weight at the centroids the posture puts it) is at rounding.
#[test]
fn solves_under_gravity_are_in_equilibrium() {
    for dir in DIRS {
        let f = board(dir);
        for (p, v) in [(0.0, [0.0; 3]), (0.5, [5000.0, 0.0, 2500.0]), (2.0, [1000.0, 3000.0, 5000.0])] {
            let s = f.solve(p, &v, Method::converged()).unwrap();
            let r = f.equilibrium_residual(&s).unwrap();
            assert!(r < 1e-9, "dir {dir} P {p}: {r:e}");
            assert!(s.residual < 1e-6, "dir {dir} P {p}: {}", s.residual);
        }
    }
}

/// The inverse round trip under gravity in each orientation: `pose` answers a tension and
/// voltages, `solve` with them gives the posture back within 0.01° (measured: 1e-10°).
#[test]
fn inverse_round_trip_under_gravity() {
    for dir in DIRS {
        let f = board(dir);
        // voltages inside the stack's range (an answer at its end sits on the interval's end)
        for (pt, v) in [(1.0, [3000.0, 1000.0, 5000.0]), (0.5, [5000.0, 5000.0, 5000.0]), (2.0, [500.0, 4000.0, 2000.0])] {
            let target = f.solve(pt, &v, Method::converged()).unwrap();
            let angles = &target.joint_angle[..3];
            for given in [None, Some(pt)] {
                let s = inverse::solve_pose(&f, angles, given).unwrap_or_else(|e| panic!("dir {dir} P {pt} {given:?}: {e:?}"));
                assert!(s.interval[0] <= s.tension && s.tension <= s.interval[1]);
                let back = f.solve(s.tension, &s.volts[..3], Method::converged()).unwrap();
                let err = (0..3).map(|k| (back.joint_angle[k] - angles[k]).abs().to_degrees()).fold(0.0, f64::max);
                println!("dir {dir} P {pt} given {given:?}: P {:.5} in [{:.5}, {:.5}], back within {err:.1e}°", s.tension, s.interval[0], s.interval[1]);
                assert!(err < 0.01, "dir {dir}: {err}");
                if given.is_some() {
                    // the tension the posture was solved at, and its voltages back
                    for k in 0..3 {
                        assert!((s.volts[k] - v[k]).abs() < 0.5, "dir {dir} joint {k}: {} vs {}", s.volts[k], v[k]);
                    }
                }
            }
        }
    }
}

/// Gravity moves the inverse's answer: the same angles need another tension interval when
/// held horizontally than hanging (the model without gravity answers neither).
#[test]
fn the_inverse_answers_the_weight() {
    let hanging = board(0.0);
    let target = hanging.solve(1.0, &[2500.0; 3], Method::converged()).unwrap();
    let angles = &target.joint_angle[..3];
    let a = inverse::solve_pose(&hanging, angles, None).unwrap();
    let no_g = Finger::with_calibration(Params::<f64>::vhb4905(), Calibration::for_params(&Params::<f64>::vhb4905())).unwrap();
    let b = inverse::solve_pose(&no_g, angles, None);
    println!("hanging: P {:.4}; without gravity: {b:?}", a.tension);
    match b {
        Ok(b) => assert!((b.tension - a.tension).abs() > 0.05, "gravity moves the tension: {} vs {}", b.tension, a.tension),
        Err(e) => assert!(matches!(e, Error::Unreachable { .. }), "{e:?}"),
    }
}

/// fmax under gravity: the coupled solve holds just below it and refuses just above it.
#[test]
fn fmax_under_gravity_bounds_the_coupled_solve() {
    for dir in [90.0, 0.0] {
        let f = board(dir);
        let v = [5000.0, 5000.0, 5000.0];
        let end = f.fmax(&v).unwrap();
        println!("dir {dir}: fmax {:.4} N at joint {} ({:?})", end.tension, end.joint, end.kind);
        assert!(f.solve(end.tension * 0.999, &v, Method::converged()).is_ok());
        assert!(f.solve(end.tension * 1.01, &v, Method::converged()).is_err());
    }
}

/// Contact under gravity: the tip pinned where the free finger puts it, the tension raised,
/// the stop pushes back on the tip; the answer is in equilibrium.
#[test]
fn contact_under_gravity() {
    for dir in DIRS {
        let f = board(dir);
        let c = contact_force(&f, 1.0, &[0.0; 3], 1.3, &[0.0; 3]).unwrap_or_else(|e| panic!("dir {dir}: {e:?}"));
        let r = f.equilibrium_residual(&c.solution).unwrap();
        println!("dir {dir}: force {:?} N, residual {r:.1e}", c.force);
        assert!(c.magnitude() > 0.0 && r < 1e-8);
    }
}

/// A weight the finger cannot hold up (pointing up, twenty metres a second squared, a body a
/// thousand times softer) is a typed error or an answer, never a NaN or a hang.
#[test]
fn a_weight_the_finger_cannot_hold_is_refused_or_answered() {
    for e_b in [12.0, 0.1, 0.012] {
        for dir in [180.0, 170.0, 90.0] {
            let mut p = Params::<f64>::vhb4905().with_gravity(20.0, dir);
            p.e_b = e_b;
            let f = Finger::new(p).unwrap();
            for t in [0.0, 0.5, 2.0] {
                match f.solve(t, &[0.0; 3], Method::converged()) {
                    Ok(s) => assert!(s.joint_angle[..3].iter().all(|a| a.is_finite()), "{e_b} {dir} {t}"),
                    Err(e) => println!("E_b {e_b} dir {dir} P {t}: {e:?}"),
                }
            }
        }
    }
}

/// The board's scalar: f32 agrees with f64 under gravity.
#[test]
fn f32_agrees_with_f64_under_gravity() {
    for dir in DIRS {
        let f64f = board(dir);
        let p32: Params<f32> = f64f.params().cast();
        let f32f = Finger::<f32>::with_calibration(p32, Calibration::for_params(&p32)).unwrap();
        let a = f64f.solve(1.0, &[2000.0; 3], Method::converged()).unwrap();
        let b = f32f.solve(1.0, &[2000.0; 3], Method::converged()).unwrap();
        for k in 0..3 {
            let d = (a.joint_angle[k] - b.joint_angle[k] as f64).abs();
            assert!(d < 1e-4, "dir {dir} joint {k}: {d}");
        }
    }
}

/// Out of range or not a number: refused by name, nothing changed.
#[test]
fn gravity_parameters_are_checked() {
    let mut p = Params::<f64>::vhb4905();
    for (name, bad) in [("grav", 20.5), ("grav", -1.0), ("grav_dir", 181.0), ("rho_b", -0.1), ("grav", f64::NAN)] {
        let before = p;
        assert!(p.set(name, bad).is_err(), "{name} {bad}");
        assert_eq!(p, before);
    }
    p.set("grav", 9.81).unwrap();
    p.set("grav_dir", -90.0).unwrap();
    assert!(p.has_gravity());
    p.set("grav", 0.0).unwrap();
    assert!(!p.has_gravity());
}

/// A uniform posture the board's finger cannot hold under its own weight (its stacks change a
/// joint's stiffness by 1 %, the weight loads joint 1 most) is refused as unreachable and names
/// the joint, as without gravity; before the equal-angle shortcut knew the held loads, every
/// joint took joint 1's state and the answer failed the forward check (`LimitPoint`).
#[test]
fn an_unreachable_posture_under_gravity_is_refused_as_unreachable() {
    for dir in [0.0, -90.0] {
        let f = board(dir);
        let e = inverse::solve_pose(&f, &[5f64.to_radians(); 3], None).unwrap_err();
        println!("dir {dir}: {e:?}");
        assert!(matches!(e, Error::Unreachable { .. }), "dir {dir}: {e:?}");
    }
}

/// Past the branch's end under gravity the coupled solve refuses: its continuation keeps each
/// step on the physical branch (before, 100 N answered a finger coiled to -500° a joint).
#[test]
fn past_fmax_under_gravity_the_solve_refuses() {
    let f = board(0.0);
    let end = f.fmax(&[0.0; 3]).unwrap();
    for p in [1.5 * end.tension, 100.0] {
        let r = f.solve(p, &[0.0; 3], Method::converged());
        assert!(r.is_err(), "{p} N: {:?}", r.map(|s| s.joint_angle));
    }
}

/// A uniform posture the weight alone bends the finger past (held horizontally: curling down
/// at 5°, where the weight alone bends joint 1 about 14°; curling up at -5°, where it bends
/// joint 3 about -1.4° only) needs a cable that pushes: refused as unreachable, naming the
/// joint, in f32 (the board's scalar) as in f64. Before, both ended in `NotConverged` (the
/// tension's root took the joint at P = 0 as straight).
#[test]
fn a_posture_past_the_weight_alone_is_unreachable_in_f32_and_f64() {
    for (dir, deg, joint) in [(90.0, 5.0, 1), (-90.0, -5.0, 3), (90.0, -5.0, 1)] {
        let f = board(dir);
        let e64 = inverse::solve_pose(&f, &[f64::to_radians(deg); 3], None).unwrap_err();
        let p32: Params<f32> = f.params().cast();
        let f32f = Finger::<f32>::with_calibration(p32, Calibration::for_params(&p32)).unwrap();
        let e32 = inverse::solve_pose(&f32f, &[(deg as f32).to_radians(); 3], None).unwrap_err();
        println!("dir {dir} at {deg}°: f64 {e64:?}, f32 {e32:?}");
        for e in [e64, e32] {
            assert!(matches!(e, Error::Unreachable { joint: j, .. } if j == joint), "dir {dir} at {deg}°: {e:?}");
        }
    }
}

/// The tip stiffness under gravity carries the weight's posture-dependent term: its compliance
/// is the forward solve's own response to a small tip force (central differences, ±1e-4 N, x
/// and y), in the four orientations, with no cable (the cable's own geometric term, which K_tip
/// leaves out, is then zero). Σ J C Jᵀ at the same posture (the finger without its weight)
/// misses it by far more.
#[test]
fn tip_compliance_under_gravity_is_the_forward_response() {
    let tight = Method::Converged { tol: 1e-12, max_iter: 400 };
    for dir in DIRS {
        let f = board(dir);
        let v = [0.0; 3];
        let sol = f.solve(0.0, &v, tight).unwrap();
        let c = f.compliances(&v).unwrap();
        let with = f.tip_compliance(&c, &sol);
        let mut p0 = *f.params();
        p0.grav = 0.0;
        let without = Finger::with_calibration(p0, *f.calibration()).unwrap().tip_compliance(&c, &sol);
        let h = 1e-4;
        let (mut err_with, mut err_without) = (0.0f64, 0.0f64);
        for i in 0..2 {
            let mut df = [0.0; 2];
            df[i] = h;
            let plus = f.solve_loaded(0.0, &v, df, tight).unwrap().tip();
            let minus = f.solve_loaded(0.0, &v, [-df[0], -df[1]], tight).unwrap().tip();
            let fd = [(plus.x - minus.x) / (2.0 * h), (plus.y - minus.y) / (2.0 * h), (plus.theta - minus.theta) / (2.0 * h)];
            let size = (fd[0] * fd[0] + fd[1] * fd[1]).sqrt();
            for r in 0..3 {
                // the angle's row in rad/N against mm/N: over the finger's length
                let scale = if r == 2 { size / (3.0 * f.params().l) } else { size };
                err_with = err_with.max((with[r][i] - fd[r]).abs() / scale);
                err_without = err_without.max((without[r][i] - fd[r]).abs() / scale);
            }
        }
        println!("dir {dir}: C_tip against the forward's response: {err_with:.2e} with the weight's term, {err_without:.2e} without");
        assert!(err_with < 1e-4, "dir {dir}: {err_with}");
        assert!(err_without > 1e-2, "dir {dir}: {err_without}");
    }
}

/// The coupled forward started from an earlier answer (`Finger::solve_from`, the board's last
/// posture: another tension, other voltages) answers what the solve from the straight finger
/// does (asked again, with no iteration); from an answer far off (near fmax, for a solve at no
/// tension) it falls back to that solve. f64 and f32 (the board's scalar). The cost:
/// docs/performance.md (the bench's `W` lines).
#[test]
fn a_solve_from_an_earlier_answer_agrees_with_the_solve_from_straight() {
    fn check<R: finger_model::Real>(f: &Finger<R>, dir: f64) {
        let m = Method::converged();
        let v = |x: f64| [R::from_f64(x); 3];
        let (c, c0) = (f.compliances(&v(3000.0)).unwrap(), f.compliances(&v(0.0)).unwrap());
        let p = |x: f64| R::from_f64(x);
        let tip_gap = |a: &finger_model::Solution<R>, b: &finger_model::Solution<R>| {
            let (a, b) = (a.tip(), b.tip());
            ((a.x - b.x).to_f64().powi(2) + (a.y - b.y).to_f64().powi(2)).sqrt()
        };
        let tol_mm = if R::EPS > 1e-10 { 1e-4 } else { 1e-8 };
        let mut last = None;
        let first = f.solve_from(&c0, p(0.7), m, &mut last).unwrap();
        let cold_first = f.solve_with(&c0, p(0.7), [p(0.0); 2], m).unwrap();
        assert!(tip_gap(&first, &cold_first) == 0.0, "dir {dir}: with nothing kept, the solve from straight");
        for (pp, cc) in [(1.0, &c), (1.0, &c), (0.9, &c0), (2.0, &c)] {
            let cold = f.solve_with(cc, p(pp), [p(0.0); 2], m).unwrap();
            let warm = f.solve_from(cc, p(pp), m, &mut last).unwrap();
            println!(
                "dir {dir} {} at {pp} N: iterations {} from the last answer, {} from straight; tip {:.1e} mm apart",
                R::NAME,
                warm.iterations,
                cold.iterations,
                tip_gap(&warm, &cold)
            );
            assert!(tip_gap(&warm, &cold) < tol_mm, "dir {dir} at {pp} N");
            assert!(warm.residual.to_f64() < tol_mm);
        }
        // asked again: the answer kept is checked, no iteration
        let again = f.solve_from(&c, p(2.0), m, &mut last).unwrap();
        assert_eq!(again.iterations, 0);
        // from near fmax to no tension: past the branch rule's 0.8 rad a joint, the solve from straight
        let end = f.fmax(&v(0.0)).unwrap().tension;
        f.solve_from(&c0, end * p(0.98), m, &mut last).unwrap();
        let cold = f.solve_with(&c0, p(0.0), [p(0.0); 2], m).unwrap();
        let back = f.solve_from(&c0, p(0.0), m, &mut last).unwrap();
        assert!(tip_gap(&back, &cold) < tol_mm, "dir {dir}: from near fmax");
        assert_eq!(back.iterations, cold.iterations, "dir {dir}: the fallback is the solve from straight");
    }
    for dir in DIRS {
        let f = board(dir);
        check(&f, dir);
        let p32: Params<f32> = f.params().cast();
        check(&Finger::<f32>::with_calibration(p32, Calibration::for_params(&p32)).unwrap(), dir);
    }
}
