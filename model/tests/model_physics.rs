//! Host tests that pin the model's physics (docs/model.md). Each fails if the feature it names breaks.

use finger_model::{de, hinge, params::EPS0, Error, Finger, Method, Params};
use finger_model_testkit::paper;

fn default_finger() -> Finger<f64> {
    Finger::new(Params::default()).unwrap()
}

fn conv() -> Method<f64> {
    Method::converged()
}

#[test]
fn zero_tension_is_straight() {
    for p in [Params::<f64>::default(), Params::default().without_stacks(), Params::paper()] {
        let f = Finger::new(p).unwrap();
        let s = f.solve(0.0, &[0.0; 3], conv()).unwrap();
        let tip = s.tip();
        assert!((tip.x - 3.0 * 27.0).abs() < 1e-12, "tip x {}", tip.x);
        assert!(tip.y.abs() < 1e-12 && tip.theta.abs() < 1e-12);
        assert!(s.joint_angles().iter().all(|a| a.abs() < 1e-12));
        assert!(s.cable_excursion.abs() < 1e-12);
    }
}

#[test]
fn tension_bends_toward_plus_y_monotonically() {
    let f = default_finger();
    let mut last = [0.0f64; 3];
    for i in 1..=20 {
        let p = 0.25 * i as f64;
        let s = f.solve(p, &[0.0; 3], conv()).unwrap();
        for k in 0..3 {
            assert!(s.joint_angle[k] > last[k], "joint {k} not monotone at {p} N");
            last[k] = s.joint_angle[k];
        }
        for node in &s.nodes[1..=3] {
            assert!(node.y > 0.0, "node bends away from the flexor side at {p} N");
        }
        assert!(s.tip().theta > 0.0);
        assert!(s.cable_excursion > 0.0);
        assert!(s.residual < 1e-8);
    }
}

#[test]
fn equal_voltages_give_equal_joints() {
    let f = default_finger();
    for v in [0.0, 5000.0, 9000.0] {
        let s = f.solve(1.0, &[v; 3], conv()).unwrap();
        let a = s.joint_angles();
        assert!((a[0] - a[1]).abs() < 1e-12 && (a[1] - a[2]).abs() < 1e-12, "{a:?}");
    }
}

/// Adaptive Simpson in x (an independent quadrature of docs/model.md's integrals, no substitution).
fn simpson<F: Fn(f64) -> f64>(f: &F, a: f64, b: f64, tol: f64) -> f64 {
    fn rec<F: Fn(f64) -> f64>(f: &F, a: f64, b: f64, fa: f64, fm: f64, fb: f64, whole: f64, tol: f64, depth: u32) -> f64 {
        let m = 0.5 * (a + b);
        let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
        let (flm, frm) = (f(lm), f(rm));
        let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
        let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
        if depth == 0 || (left + right - whole).abs() <= 15.0 * tol {
            return left + right + (left + right - whole) / 15.0;
        }
        rec(f, a, m, fa, flm, fm, left, tol / 2.0, depth - 1) + rec(f, m, b, fm, frm, fb, right, tol / 2.0, depth - 1)
    }
    let (fa, fb, fm) = (f(a), f(b), f(0.5 * (a + b)));
    rec(f, a, b, fa, fm, fb, (b - a) / 6.0 * (fa + 4.0 * fm + fb), tol, 50)
}

#[test]
fn hinge_compliance_matches_the_integrals() {
    for (p, m) in [(Params::<f64>::default(), 1usize), (Params::default(), 4), (Params { t_min: 0.3, a: 2.0, ..Params::default() }, 3)] {
        let e = p.e_b;
        let t = |x: f64| hinge::notch_thickness(p.b, p.t_min, p.a, x);
        for j in 0..m {
            let (x0, x1) = hinge::sub_element_bounds(p.a, m, j);
            let c = hinge::stretch_compliance(p.b, p.t_min, p.a, e, p.w, x0, x1);
            let ei = |x: f64| e * p.w * t(x).powi(3) / 12.0;
            let reference = [
                (c[0][0], simpson(&|x| 1.0 / (e * p.w * t(x)), x0, x1, 1e-15)),
                (c[1][1], simpson(&|x| (x1 - x).powi(2) / ei(x), x0, x1, 1e-15)),
                (c[1][2], simpson(&|x| (x1 - x) / ei(x), x0, x1, 1e-15)),
                (c[2][1], simpson(&|x| (x1 - x) / ei(x), x0, x1, 1e-15)),
                (c[2][2], simpson(&|x| 1.0 / ei(x), x0, x1, 1e-15)),
            ];
            for (got, want) in reference {
                let rel = ((got - want) / want).abs();
                assert!(rel < 1e-6, "m={m} j={j}: {got} vs {want} (rel {rel:e})");
            }
            assert_eq!(c[0][1], 0.0);
            assert_eq!(c[0][2], 0.0);
        }
    }
}

#[test]
fn hinge_subelements_in_series_recover_the_whole_hinge() {
    // m sub-elements composed linearly (moments carried to the hinge end) give the m = 1
    // compliance: a check that each stretch integrates over its own piece.
    let p = Params::<f64>::default();
    let whole = hinge::stretch_compliance(p.b, p.t_min, p.a, p.e_b, p.w, 0.0, 2.0 * p.a);
    let m = 5;
    let mut c_mm = 0.0;
    for j in 0..m {
        let (x0, x1) = hinge::sub_element_bounds(p.a, m, j);
        c_mm += hinge::stretch_compliance(p.b, p.t_min, p.a, p.e_b, p.w, x0, x1)[2][2];
    }
    assert!((c_mm - whole[2][2]).abs() / whole[2][2] < 1e-10);
}

#[test]
fn de_thinning_root_satisfies_its_equation() {
    // the relaxed free film: G (s - s^4) = eps0 eps_r V^2 / z0^2, G = E_de / (2 (1 + nu))
    for p in [Params::<f64>::default(), Params::paper(), Params::vhb4905()] {
        let g = p.e_de() / (2.0 * (1.0 + p.nu));
        let ceiling = de::voltage_ceiling(&p);
        for frac in [0.0, 0.1, 0.5, 0.999] {
            let v = frac * ceiling;
            let s = de::stack_thickness(&p, 1, v).unwrap() / p.layers as f64 / p.z0;
            let lhs = g * (s - s.powi(4));
            let rhs = EPS0 * p.eps_r * v * v / (p.z0 * p.z0);
            assert!((lhs - rhs).abs() <= 1e-12 * g, "V={v}: {lhs} vs {rhs}");
            assert!(s <= 1.0 && s > 2.0 / 3.0, "V={v}: s={s}");
        }
    }
}

#[test]
fn pull_in_limit_sits_at_4_to_the_minus_third() {
    let p = Params::<f64> { v_supply: 1e5, margin: 0.999_999, ..Params::default() };
    let g = p.e_de() / (2.0 * (1.0 + p.nu));
    let s_pi = 4f64.powf(-1.0 / 3.0);
    let vpi = de::pull_in_voltage(&p);
    let formula = p.z0 * (g * (s_pi - s_pi.powi(4)) / (EPS0 * p.eps_r)).sqrt();
    assert!((vpi - formula).abs() < 1e-9 * formula);
    assert!((vpi - 41_260.0).abs() < 50.0, "V_pi {vpi} (about 41.3 kV expected)");
    // approaching V_pi from below the layer thins toward s_pi, never past it
    let s = de::layer_thickness_ratio(&p, 1, vpi * 0.999_999).unwrap();
    assert!((s - s_pi).abs() < 0.01, "s={s}");
    assert!(s > s_pi);
    assert!(matches!(de::layer_thickness_ratio(&p, 1, vpi * 1.000_001), Err(Error::VoltageCeiling { .. })));
    // the 33 % limit lies on the stable branch, below pull-in: the ceiling keeps the film above it
    let v_limit = p.z0 * (g * (2.0 / 3.0 - (2.0f64 / 3.0).powi(4)) / (EPS0 * p.eps_r)).sqrt();
    assert!(v_limit < vpi);
    assert!((de::layer_thickness_ratio(&p, 1, v_limit).unwrap() - 2.0 / 3.0).abs() < 1e-9);
    let paper = de::pull_in_voltage(&Params::<f64>::paper());
    assert!((paper - 13_850.0).abs() < 100.0, "paper V_pi {paper}");
    // the paper's Eq. 1-2 (pressure on z0, linear) would allow about 1.45x the voltage that
    // holds the free film at the 33 % limit before it predicts a 33 % thinning
    let v_small_strain = (p.e_de() * p.z0 * p.z0 / (3.0 * EPS0 * p.eps_r)).sqrt();
    assert!(v_small_strain / v_limit > 1.4, "{}", v_small_strain / v_limit);
}

#[test]
fn voltage_ceiling_is_refused() {
    let f = default_finger();
    let ceiling = f.voltage_ceiling();
    assert_eq!(ceiling, 10_000.0, "supply-limited with the defaults");
    assert!(matches!(f.solve(1.0, &[0.0, ceiling, 0.0], conv()), Err(Error::VoltageCeiling { joint: 2, .. })));
    assert!(matches!(f.solve(1.0, &[0.0, 0.0, ceiling * 1.5], conv()), Err(Error::VoltageCeiling { joint: 3, .. })));
    assert!(f.solve(1.0, &[0.0, ceiling - 1.0, 0.0], conv()).is_ok());
    // the hold ceiling when the supply is large: margin x min(V holding 2/3 relaxed, the
    // breakdown field at 2/3), for every card
    for base in [Params::<f64>::default(), Params::paper(), Params::vhb4905()] {
        let p = Params::<f64> { v_supply: 1e5, ..base };
        let f2 = Finger::new(p).unwrap();
        let law = p.stack_law().unwrap();
        let s = 2.0 / 3.0;
        let v_film = finger_model::material::equilibrium_voltage(&law, s).unwrap();
        let v_field = law.breakdown_field(s) * s * p.z0;
        let expected = 0.9 * v_film.min(v_field);
        assert!((f2.voltage_ceiling() - expected).abs() < 1e-6 * expected, "{} vs {expected}", f2.voltage_ceiling());
        assert!(f2.voltage_ceiling() < 0.9 * f2.pull_in_voltage());
        assert!(f2.solve(1.0, &[expected; 3], conv()).is_err());
    }
    // VHB 4905 is held below 6.5 kV whatever the supply
    let vhb = Finger::new(Params::<f64> { v_supply: 1e5, ..Params::vhb4905() }).unwrap();
    assert!(vhb.voltage_ceiling() < 6_500.0, "{}", vhb.voltage_ceiling());
    // negative or NaN voltages
    assert!(matches!(f.solve(1.0, &[-1.0, 0.0, 0.0], conv()), Err(Error::Input { .. })));
    assert!(matches!(f.solve(1.0, &[f64::NAN, 0.0, 0.0], conv()), Err(Error::NonFinite { .. })));
}

#[test]
fn paper_two_mm_to_one_mm_is_refused() {
    for p in [Params::<f64>::default(), Params::paper()] {
        let r = de::voltage_for_thickness(&p, 1, 1.0);
        match r {
            Err(Error::ThicknessLimit { joint: 1, requested_mm, limit_mm }) => {
                assert_eq!(requested_mm, 1.0);
                assert!((limit_mm - 4.0 / 3.0).abs() < 1e-12);
            }
            other => panic!("expected the 33 % limit, got {other:?}"),
        }
        // a small reduction is fine and round-trips
        if let Ok(v) = de::voltage_for_thickness(&p, 1, 1.99) {
            let t = de::stack_thickness(&p, 1, v).unwrap();
            assert!((t - 1.99).abs() < 1e-9);
        }
    }
}

#[test]
fn stack_stiffens_and_voltage_softens() {
    let with = default_finger();
    let without = Finger::new(Params::<f64>::default().without_stacks()).unwrap();
    let a_with = with.solve(1.0, &[0.0; 3], conv()).unwrap().joint_angle[0];
    let a_without = without.solve(1.0, &[0.0; 3], conv()).unwrap().joint_angle[0];
    assert!(a_with < 0.7 * a_without, "stack should stiffen: {a_with} vs {a_without}");
    let a_hot = with.solve(1.0, &[9000.0; 3], conv()).unwrap().joint_angle[0];
    assert!(a_hot > a_with, "voltage should soften: {a_hot} vs {a_with}");
    // stiffness view: the tip's rotational compliance (Σ of every element's C_θM, whatever
    // the posture) grows with voltage
    let s0 = with.solve(1.0, &[0.0; 3], conv()).unwrap();
    let s9 = with.solve(1.0, &[9000.0; 3], conv()).unwrap();
    let c_tt = |s| finger_model::mat3::inverse(&with.tip_stiffness(s).unwrap()).unwrap()[2][2];
    assert!(c_tt(&s9) > c_tt(&s0) * 1.001, "{} vs {}", c_tt(&s9), c_tt(&s0));
}

#[test]
fn raising_one_channel_bends_that_joint_most() {
    let f = Finger::new(Params::<f64>::paper()).unwrap(); // paper preset: visible thinning
    let base = f.solve(1.0, &[0.0; 3], conv()).unwrap();
    for k in 0..3 {
        let mut v = [0.0; 3];
        v[k] = 9000.0;
        let s = f.solve(1.0, &v, conv()).unwrap();
        for j in 0..3 {
            let d = s.joint_angle[j] - base.joint_angle[j];
            if j == k {
                assert!(d > 1e-3, "joint {k} did not bend more: {d}");
            } else {
                assert!(d.abs() < 1e-12, "joint {j} moved by {d} when channel {k} was raised");
            }
        }
    }
}

#[test]
fn f32_agrees_with_f64() {
    // f32 carries ~7 digits. The f32 solve stops at the resolution of the guide-hole position
    // (16 eps x (L_h + e + l) = 16 x 1.2e-7 x 37 mm ~ 7e-5 mm); a hole error of that size turns
    // the joint by ~1e-5 rad, which the ~80 mm finger carries to the tip as ~1e-4 mm.
    // Measured: worst tip 9.4e-5 mm, worst joint 4.3e-5 deg over these cases. Asserted with
    // a factor ~5 of headroom: tip < 5e-4 mm, joints < 2e-4 deg.
    let p64 = Params::<f64>::default();
    let f64m = Finger::new(p64).unwrap();
    let f32m = Finger::new(p64.cast::<f32>()).unwrap();
    let mut worst_tip = 0.0f64;
    let mut worst_deg = 0.0f64;
    for &t in &[0.2, 0.5, 1.0, 2.0, 4.0] {
        for v in [[0.0; 3], [3000.0, 6000.0, 9000.0]] {
            let a = f64m.solve(t, &v, Method::converged()).unwrap();
            let v32 = [v[0] as f32, v[1] as f32, v[2] as f32];
            let b = f32m.solve(t as f32, &v32, Method::converged()).unwrap();
            let dtip = ((a.tip().x - b.tip().x as f64).powi(2) + (a.tip().y - b.tip().y as f64).powi(2)).sqrt();
            worst_tip = worst_tip.max(dtip);
            for k in 0..3 {
                worst_deg = worst_deg.max((a.joint_angle[k] - b.joint_angle[k] as f64).abs().to_degrees());
            }
        }
    }
    println!("f32 vs f64: worst tip {worst_tip:.2e} mm, worst joint {worst_deg:.2e} deg");
    assert!(worst_tip < 5e-4, "tip {worst_tip}");
    assert!(worst_deg < 2e-4, "angle {worst_deg}");
}

#[test]
fn load_stepping_converges_at_first_order() {
    let f = default_finger();
    let reference = f.solve(1.0, &[0.0; 3], conv()).unwrap().tip();
    let err = |n: u32| {
        let s = f.solve(1.0, &[0.0; 3], Method::Stepping { n_inc: n }).unwrap().tip();
        ((s.x - reference.x).powi(2) + (s.y - reference.y).powi(2)).sqrt()
    };
    let ns = [10u32, 20, 50, 100, 200, 500, 1000];
    let errs: Vec<f64> = ns.iter().map(|&n| err(n)).collect();
    for w in errs.windows(2) {
        assert!(w[1] < w[0], "stepping error not shrinking: {errs:?}");
    }
    // least-squares slope of log(err) against log(n)
    let xs: Vec<f64> = ns.iter().map(|&n| (n as f64).ln()).collect();
    let ys: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / xs.len() as f64, ys.iter().sum::<f64>() / ys.len() as f64);
    let slope = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum::<f64>() / xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>();
    println!("stepping tip error vs n_inc: {errs:?}, slope {slope:.3}");
    assert!((slope + 1.0).abs() < 0.05, "expected first order, slope {slope}");
}

#[test]
fn bad_inputs_are_typed_errors() {
    let f = default_finger();
    assert!(matches!(f.solve(-1.0, &[0.0; 3], conv()), Err(Error::Input { input: "tension", .. })));
    assert!(matches!(f.solve(f64::INFINITY, &[0.0; 3], conv()), Err(Error::NonFinite { .. })));
    assert!(matches!(f.solve(1.0, &[0.0; 2], conv()), Err(Error::Input { input: "voltages", .. })));
    assert!(matches!(f.solve(1.0, &[0.0; 3], Method::Stepping { n_inc: 0 }), Err(Error::Input { .. })));
    let mut p = Params::<f64>::default();
    assert!(matches!(p.set("t_min", 12.0), Err(Error::Param { name: "t_min", .. })));
    assert!(matches!(p.set("e", 6.0), Err(Error::Param { name: "e", .. })));
    assert!(matches!(p.set("l", f64::NAN), Err(Error::NonFinite { .. })));
    assert!(matches!(p.set("e_de", 1.0), Err(Error::Param { name: "e_de", .. })));
    assert!(p.set("nope", 1.0).is_err());
    assert_eq!(p, Params::default(), "a rejected set changes nothing");
    assert!(Finger::new(Params::<f64> { a: 14.0, ..Params::default() }).is_err());
    assert!(Finger::new(Params::<f64> { w: -1.0, ..Params::default() }).is_err());
}

#[test]
fn contact_is_reported_not_divided_by_zero() {
    // With sub-elements the hinge bends as an arc and the flexor-side corners (the guide holes)
    // meet: the span closes (near 7.5 N with m = 8 and the plate modulus).
    // With m = 1 the paper's single linear compliance shears the hinge instead and the span
    // never closes (see docs/model.md), so contact is a sub-element result.
    let f = Finger::new(Params::<f64> { m: 8, plate: true, ..Params::default() }.without_stacks()).unwrap();
    let near = f.solve(7.4, &[0.0; 3], conv()).unwrap();
    assert!(near.span[0] < 0.5 && near.span[0] >= 0.1, "span {}", near.span[0]);
    match f.solve(50.0, &[0.0; 3], conv()) {
        Err(Error::Contact { joint, tension }) => {
            assert!((1..=3).contains(&joint));
            assert!(tension > 7.4 && tension < 7.7, "contact at {tension}");
        }
        other => panic!("expected contact, got {other:?}"),
    }
    assert!(matches!(f.solve(50.0, &[0.0; 3], Method::Stepping { n_inc: 100 }), Err(Error::Contact { .. })));
    // a large floor makes the paper's m = 1 model report contact too
    let g = Finger::new(Params::<f64> { span_floor: 8.0, ..Params::default() }.without_stacks()).unwrap();
    assert!(matches!(g.solve(5.0, &[0.0; 3], conv()), Err(Error::Contact { joint: 1, .. })));
}

#[test]
fn tip_load_couples_the_joints() {
    let f = default_finger();
    let free = f.solve(1.0, &[0.0; 3], conv()).unwrap();
    // a push on the tip against the flexion direction unbends the proximal joints most
    let s = f.solve_loaded(1.0, &[0.0; 3], [0.0, -0.05], conv()).unwrap();
    assert!(s.residual < 1e-8);
    let d: Vec<f64> = (0..3).map(|k| free.joint_angle[k] - s.joint_angle[k]).collect();
    assert!(d[0] > d[1] && d[1] > d[2] && d[2] > 0.0, "{d:?}");
    // zero tip load reproduces the free solution
    let z = f.solve_loaded(1.0, &[0.0; 3], [0.0, 0.0], conv()).unwrap();
    assert!((z.tip().y - free.tip().y).abs() < 1e-12);
    // a small tip load agrees with the linearised tip compliance
    let dfy = 1e-4;
    let sl = f.solve_loaded(1.0, &[0.0; 3], [0.0, dfy], conv()).unwrap();
    let k = f.tip_stiffness(&free).unwrap();
    let c = finger_model::mat3::inverse(&k).unwrap();
    let dy_lin = c[1][1] * dfy;
    let dy = sl.tip().y - free.tip().y;
    // the cable's own geometric stiffness is not in C_tip (docs/model.md "Tip stiffness"), so agree to ~30 %
    assert!((dy - dy_lin).abs() < 0.3 * dy_lin.abs(), "{dy} vs linear {dy_lin}");
}

#[test]
fn paper_preset_matching_tension() {
    let (p_match, angle) = paper::matching_tension().unwrap();
    println!(
        "paper preset: the finger without stacks reaches the tip angle of the finger with stacks at 1.0 N \
         ({:.3} deg) at {p_match:.4} N (paper: 0.631 N, {:+.1} %)",
        angle.to_degrees(),
        100.0 * (p_match / 0.631 - 1.0)
    );
    assert!(p_match > 0.0 && p_match < 1.0);
    let f = Finger::new(Params::<f64>::paper().without_stacks()).unwrap();
    let s = f.solve(p_match, &[0.0; 3], conv()).unwrap();
    assert!((s.tip().theta - angle).abs() < 1e-9);
}

#[test]
fn fmax_is_the_end_of_the_branch_and_solves_stop_there() {
    use finger_model::BranchEnd;
    let f = Finger::new(Params::<f64> { m: 8, plate: true, ..Params::default() }.without_stacks()).unwrap();
    let end = f.fmax(&[0.0; 3]).unwrap();
    assert_eq!(end.kind, BranchEnd::Contact);
    assert!(end.tension > 7.4 && end.tension < 7.7, "{end:?}");
    assert!(f.solve(0.99 * end.tension, &[0.0; 3], conv()).is_ok());
    assert!(matches!(f.solve(1.01 * end.tension, &[0.0; 3], conv()), Err(Error::Contact { .. })));
    // the paper's m = 1 hinge shears instead of closing: its branch ends only at ~300 N
    let g = Finger::new(Params::<f64>::paper_model().without_stacks()).unwrap();
    let end1 = g.fmax(&[0.0; 3]).unwrap();
    assert!(end1.tension > 100.0, "{end1:?}");
    // a search bound is reported as such: a hinge so stiff that no end is found below it
    let stiff = Finger::new(Params::<f64> { e_b: 1e6, span_floor: 1e-5, ..Params::paper_model() }.without_stacks()).unwrap();
    let end2 = stiff.fmax(&[0.0; 3]).unwrap();
    assert!(end2.tension > 1e6, "{end2:?}");
}

#[test]
fn flexible_links_bend_under_the_eccentric_cable() {
    let rigid = Finger::new(Params::<f64>::paper_model().without_stacks()).unwrap();
    let flex = Finger::new(Params::<f64> { flex_links: true, ..Params::paper_model() }.without_stacks()).unwrap();
    let p = 1.0;
    let a = rigid.solve(p, &[0.0; 3], conv()).unwrap();
    let b = flex.solve(p, &[0.0; 3], conv()).unwrap();
    // a link of length l - 2a = 17 mm, thickness b = 10 mm bends by P e L / (E I)
    let ei = 12.0 * 20.0 * 1000.0 / 12.0;
    let link_rot = p * 5.0 * 17.0 / ei;
    for k in 0..3 {
        assert!((b.links[k][2] - link_rot).abs() < 1e-12, "{:?}", b.links[k]);
        assert!((b.joint_angle[k] - a.joint_angle[k] - link_rot).abs() < 1e-9);
        assert!(a.links[k] == [0.0; 3]);
    }
    // softer chain: lower tip stiffness
    assert!(flex.tip_stiffness(&b).unwrap()[1][1] < rigid.tip_stiffness(&a).unwrap()[1][1]);
    // and the coupled (tip-loaded) path agrees with the decoupled one at zero tip load
    let c = flex.solve_loaded(p, &[0.0; 3], [1e-12, 0.0], conv()).unwrap();
    assert!((c.tip().y - b.tip().y).abs() < 1e-6);
}

#[test]
fn tip_stiffness_in_f32_is_not_singular() {
    // C_tip mixes mm/N and rad/(N·mm) and spans decades: the inverse must judge conditioning,
    // not units (f32 used to report it singular at ordinary loads).
    let f64m = Finger::new(Params::<f64>::default()).unwrap();
    let f32m = Finger::new(Params::<f32>::default()).unwrap();
    for p in [0.0, 0.2, 0.5, 1.0, 3.0] {
        let a = f64m.tip_stiffness(&f64m.solve(p, &[0.0; 3], conv()).unwrap()).unwrap();
        let b = f32m.tip_stiffness(&f32m.solve(p as f32, &[0.0; 3], Method::converged()).unwrap()).unwrap();
        for i in 0..3 {
            let rel = ((a[i][i] - b[i][i] as f64) / a[i][i]).abs();
            assert!(rel < 1e-3, "P={p} k{i}{i}: f64 {} f32 {}", a[i][i], b[i][i]);
        }
    }
}

/// The stacks at a given thickness (the board's `status` while the film creeps): at the
/// relaxed thickness of the voltages the compliances are `compliances`' own; a thicker stack
/// (not yet thinned) bends the joint less; a thickness outside the stack is refused.
#[test]
fn compliances_at_a_thickness_between_rest_and_relaxed() {
    let f = Finger::new(Params::<f64>::vhb4905()).unwrap();
    let v = [0.5 * f.voltage_ceiling(); 3];
    let relaxed = f.compliances(&v).unwrap();
    let same = f.compliances_at_thickness(&v, &relaxed.thickness[..3]).unwrap();
    assert_eq!(same.c, relaxed.c);
    assert_eq!(same.volts, relaxed.volts);
    let rest = 4.0 * 0.5;
    let mid = (relaxed.thickness[0] + rest) / 2.0;
    let creeping = f.compliances_at_thickness(&v, &[mid; 3]).unwrap();
    let at = |c| f.solve_with(c, 1.0, [0.0; 2], conv()).unwrap().joint_angle[0];
    let (a_mid, a_relaxed, a_rest) = (at(&creeping), at(&relaxed), at(&f.compliances(&[0.0; 3]).unwrap()));
    assert!(a_rest < a_mid && a_mid < a_relaxed, "{a_rest} {a_mid} {a_relaxed}");
    for bad in [rest * 1.01, rest * 0.6, f64::NAN, -1.0] {
        assert!(f.compliances_at_thickness(&v, &[bad, rest, rest]).is_err(), "{bad}");
    }
    assert!(f.compliances_at_thickness(&v, &[rest; 2]).is_err());
}

/// The 27 mm one-joint finger of the fuzz find `regressions/model_fmax/forward-not-in-equilibrium-27-mm-one-joint`:
/// a 0.19 MPa body, flexible links, m = 1, at 7,950 V and 19.16 N its joint coils to 7 rad and
/// its span closes to 1.14 times its floor.
fn near_contact_finger() -> (Finger<f64>, f64, [f64; 1]) {
    let p =
        Params { n: 1, e_b: 0.1875, m: 1, plate: false, flex_links: true, nu_b: 0.007801660350477037, span_floor: 2.957507967970532e-5, ..Params::default() };
    (Finger::new(p).unwrap(), 19.16291832247657, [7950.0])
}

/// `equilibrium_residual` is the posture's relative wrench imbalance (docs/model.md
/// "Equilibrium"): a converged solve reads near 0, and a solution whose tension is off by δ
/// reads δ (the cable's loads off by δ against what the posture's deflections hold).
#[test]
fn equilibrium_residual_reads_a_load_error_at_its_size() {
    let f = default_finger();
    let ceiling = f.voltage_ceiling();
    for v in [[0.0; 3], [0.6 * ceiling; 3], [0.0, 0.3 * ceiling, 0.9 * ceiling]] {
        let fmax = f.fmax(&v).unwrap().tension;
        for frac in [0.05, 0.5, 0.95] {
            let s = f.solve(frac * fmax, &v, conv()).unwrap();
            let r = f.equilibrium_residual(&s).unwrap();
            assert!(r < 1e-9, "converged at {frac} fmax, {v:?}: {r:e}");
            for delta in [1e-6, 1e-3] {
                let off = finger_model::Solution { tension: s.tension * (1.0 + delta), ..s };
                let r = f.equilibrium_residual(&off).unwrap();
                assert!(r > 0.5 * delta && r < 2.0 * delta, "tension off by {delta:e} at {frac} fmax, {v:?}: reads {r:e}");
            }
        }
    }
}

/// A posture whose deflections the loads do not hold reads as such: one sub-element's
/// rotation off by 1e-4 rad (the nodes left as they were) reads at least 1e-5.
#[test]
fn equilibrium_residual_reads_a_deflection_the_loads_do_not_hold() {
    let f = default_finger();
    let s = f.solve(1.0, &[0.0; 3], conv()).unwrap();
    for k in 0..3 {
        for j in 0..s.m {
            let mut off = s;
            off.q[k][j][2] += 1e-4;
            let r = f.equilibrium_residual(&off).unwrap();
            assert!(r > 1e-5, "joint {k} sub-element {j}: {r:e}");
        }
    }
}

/// A backward error, not a re-march: on the near-contact finger the forward's answer, converged
/// to 4.2e-10 mm, puts the hole a re-march arrives at 4.6e-3 mm off (the march's gain there is
/// about 1e7); its wrench imbalance is the cable's direction over the span, 4.2e-10 mm over
/// 3.4e-5 mm: 1.2e-5, under what 1e-9 mm over that span allows.
#[test]
fn equilibrium_residual_is_not_the_marchs_gain() {
    let (f, p, v) = near_contact_finger();
    let s = f.solve(p, &v, conv()).unwrap();
    assert!(s.residual <= 1e-9 && s.span[0] < 1.2 * f.params().span_floor, "{:e} mm, span {:e}", s.residual, s.span[0]);
    let r = f.equilibrium_residual(&s).unwrap();
    assert!(r <= 1e-9 / s.span[0], "{r:e} against {:e}", 1e-9 / s.span[0]);
    // tighter holes, a smaller imbalance in proportion (the direction's own)
    let tight = f.solve(p, &v, Method::Converged { tol: 1e-11, max_iter: 800 }).unwrap();
    let rt = f.equilibrium_residual(&tight).unwrap();
    assert!(rt < r / 10.0, "{rt:e} at {:e} mm against {r:e} at {:e} mm", tight.residual, s.residual);
}

/// `set_many` takes its values in any order (each in its range, then the set once) and, when
/// one is refused, changes nothing.
#[test]
fn set_many_is_order_free_and_all_or_nothing() {
    let base = Params::<f64>::default();
    // a = 15 mm fits only a link of 40 mm (2a < l): refused alone, taken with l in either order
    let mut alone = base;
    assert!(alone.set("a", 15.0).is_err());
    assert_eq!(alone, base);
    for sets in [[("a", 15.0), ("l", 40.0)], [("l", 40.0), ("a", 15.0)]] {
        let mut p = base;
        p.set_many(&sets).unwrap();
        assert_eq!((p.a, p.l), (15.0, 40.0));
    }
    // one bad value (out of range, unknown, NaN) and nothing changes, whatever came before it
    for bad in [("t_min", -1.0), ("nope", 1.0), ("w", f64::NAN)] {
        let mut p = base;
        assert!(p.set_many(&[("l", 40.0), bad]).is_err());
        assert_eq!(p, base);
    }
}
