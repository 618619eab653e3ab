//! Tests of the independent planar continuum reference (tools/continuum/src/lib.rs).
//! Each test fails if the physics it names breaks.

use continuum::*;

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

// ---------------------------------------------------------------------------
// Own quadrature of the model's compliance integrals (docs/model.md) (independent of the code
// under test): composite Simpson in the notch angle φ, x = a (1 - cos φ).
// ---------------------------------------------------------------------------

/// ∫_0^{2a} f(x, t(x)) dx for the elliptical notch, Simpson with `m` (even) panels in φ.
fn notch_integral(p: &ContinuumParams, m: usize, f: impl Fn(f64, f64) -> f64) -> f64 {
    let h = std::f64::consts::PI / m as f64;
    let mut sum = 0.0;
    for i in 0..=m {
        let phi = i as f64 * h;
        let x = p.a * (1.0 - phi.cos());
        let t = p.t_min + (p.b - p.t_min) * (1.0 - phi.sin());
        let wgt = if i == 0 || i == m {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        sum += wgt * f(x, t) * p.a * phi.sin();
    }
    sum * h / 3.0
}

/// C_θ-M = ∫ dx / (E I(x)) of the hinge.
fn c_theta_m(p: &ContinuumParams) -> f64 {
    let e = p.body_modulus();
    notch_integral(p, 4000, |_, t| 12.0 / (e * p.w * t * t * t))
}

/// Link bending compliance (l - 2a) / (E I_b).
fn c_link(p: &ContinuumParams) -> f64 {
    (p.l - 2.0 * p.a) * 12.0 / (p.body_modulus() * p.w * p.b.powi(3))
}

// ---------------------------------------------------------------------------
// Closed-form checks on the lower-level uniform-beam integrator.
// ---------------------------------------------------------------------------

#[test]
fn tip_moment_bends_a_uniform_cantilever_into_an_exact_circle() {
    let beam = UniformBeam { length: 50.0, ei: 2000.0, ea: None };
    // M L / EI = 3 rad: a large, nearly closed arc.
    let m = 3.0 * beam.ei / beam.length;
    let r = beam.ei / m;
    let sh = uniform_cantilever(&beam, [0.0, 0.0], m, 400).unwrap();
    let phi = beam.length / r;
    assert!((sh.tip.theta - phi).abs() < 1e-12, "tip angle {} vs {}", sh.tip.theta, phi);
    assert!((sh.tip.x - r * phi.sin()).abs() < 1e-9, "tip x {} vs {}", sh.tip.x, r * phi.sin());
    assert!((sh.tip.y - r * (1.0 - phi.cos())).abs() < 1e-9);
    // Every sample lies on the circle of radius EI/M centred at (0, R).
    let worst = sh.points.iter().map(|q| ((q[1] * q[1] + (q[2] - r).powi(2)).sqrt() - r).abs()).fold(0.0f64, f64::max);
    assert!(worst < 1e-9, "distance from the circle {worst}");
    // A negative moment curls the other way, symmetric.
    let neg = uniform_cantilever(&beam, [0.0, 0.0], -m, 400).unwrap();
    assert!((neg.tip.y + sh.tip.y).abs() < 1e-9 && (neg.tip.x - sh.tip.x).abs() < 1e-9);
}

#[test]
fn small_tip_force_matches_euler_bernoulli() {
    let beam = UniformBeam { length: 40.0, ei: 5000.0, ea: None };
    let f = 1e-4;
    let sh = uniform_cantilever(&beam, [0.0, f], 0.0, 200).unwrap();
    let lin = f * beam.length.powi(3) / (3.0 * beam.ei);
    // Geometric nonlinearity is O((F L² / EI)²) relative ~ 1e-10 here.
    assert!(((sh.tip.y - lin) / lin).abs() < 1e-8, "tip {} vs FL^3/3EI {}", sh.tip.y, lin);
    let th = f * beam.length.powi(2) / (2.0 * beam.ei);
    assert!(((sh.tip.theta - th) / th).abs() < 1e-8);
    // Axial compliance: an axial tip force stretches by F L / EA.
    let ax = UniformBeam { ea: Some(1.0e4), ..beam };
    let st = uniform_cantilever(&ax, [3.0, 0.0], 0.0, 50).unwrap();
    assert!((st.tip.x - beam.length * (1.0 + 3.0 / 1.0e4)).abs() < 1e-12);
}

/// Independent large-deflection check: the inextensible cantilever with a
/// transverse dead tip load F (α = F L² / EI) has tip angle θ0 with
/// sqrt(2α) = ∫_0^θ0 dθ / sqrt(sin θ0 - sin θ), and x_tip = L sqrt(2 sin θ0 / α)
/// (Bisshopp & Drucker 1945). Quadrature with θ = θ0 (1 - v²) removes the singularity.
#[test]
fn large_tip_force_matches_the_elliptic_integral_elastica() {
    let alpha: f64 = 2.0;
    let g = |th0: f64| -> f64 {
        let m = 20000;
        let h = 1.0 / m as f64;
        let mut s = 0.0;
        for i in 0..m {
            let v = (i as f64 + 0.5) * h;
            let th = th0 * (1.0 - v * v);
            s += 2.0 * th0 * v / (th0.sin() - th.sin()).sqrt() * h;
        }
        s
    };
    let (mut lo, mut hi) = (1e-3, 1.5);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < (2.0 * alpha).sqrt() {
            lo = mid
        } else {
            hi = mid
        }
    }
    let th0 = 0.5 * (lo + hi);
    let beam = UniformBeam { length: 30.0, ei: 900.0, ea: None };
    let f = alpha * beam.ei / beam.length.powi(2);
    let sh = uniform_cantilever(&beam, [0.0, f], 0.0, 400).unwrap();
    let x_tip = beam.length * (2.0 * th0.sin() / alpha).sqrt();
    assert!((sh.tip.theta - th0).abs() < 1e-6, "tip angle {} vs {}", sh.tip.theta, th0);
    assert!((sh.tip.x - x_tip).abs() < 1e-4, "x_tip {} vs {}", sh.tip.x, x_tip);
    println!("alpha = {alpha}: tip angle {th0:.8} rad, x/L {:.8}, y/L {:.8}", x_tip / beam.length, sh.tip.y / beam.length);
}

// ---------------------------------------------------------------------------
// The finger.
// ---------------------------------------------------------------------------

/// Successive refinements by 2 in both hinge and link steps: the differences
/// must fall by about 2^4 = 16 (RK4 on smooth integrands thanks to the φ map).
#[test]
fn finger_converges_at_fourth_order_under_refinement() {
    let p = ContinuumParams::default();
    for stacks in [vec![], vec![2.0, 1.5, 1.0]] {
        let sols: Vec<ContinuumSolution> = (0..4).map(|k| solve(&p, 1.0, &stacks, [0.0, 0.0], Discretisation::new(32, 8).refined(1 << k)).unwrap()).collect();
        let d: Vec<f64> = sols.windows(2).map(|w| max_diff(&w[0].joint_angles, &w[1].joint_angles)).collect();
        let dt: Vec<f64> = sols.windows(2).map(|w| ((w[0].tip.x - w[1].tip.x).powi(2) + (w[0].tip.y - w[1].tip.y).powi(2)).sqrt()).collect();
        println!("stacks {stacks:?}: joint-angle differences {d:?} rad, tip {dt:?} mm");
        for i in 1..d.len() {
            let ratio = d[i - 1] / d[i];
            assert!(ratio > 12.0 && ratio < 20.0, "angle ratio {ratio} (expected ~16), diffs {d:?}");
            let rt = dt[i - 1] / dt[i];
            assert!(rt > 12.0 && rt < 20.0, "tip ratio {rt}, diffs {dt:?}");
        }
        // The default discretisation is converged (docs/continuum.md).
        let def = solve(&p, 1.0, &stacks, [0.0, 0.0], Discretisation::default()).unwrap();
        assert!(max_diff(&def.joint_angles, &sols[3].joint_angles) < 1e-7);
        assert!(def.residual < 1e-9);
    }
}

/// At small P the joint angle per unit tension is the linear estimate from the
/// model's compliance integrals (docs/model.md): the wrench on hinge k's distal end is
/// (-P, 0, P e), so Δθ_hinge = C_θ-M e P (C_θ-Fx = 0 by symmetry), and the
/// link carries N = -P, M = P e, so it adds e (l - 2a) / (E I_b) P.
#[test]
fn small_load_limit_matches_the_compliance_integrals() {
    for plate in [false, true] {
        let p = ContinuumParams { plate, ..Default::default() };
        let ctm = c_theta_m(&p);
        let cl = c_link(&p);
        let pt = 1e-4;
        let s = solve(&p, pt, &[], [0.0, 0.0], Discretisation::default()).unwrap();
        let hinge_lin = p.e * ctm;
        let joint_lin = p.e * (ctm + cl);
        println!("plate {plate}: C_theta-M = {ctm:.6e} rad/(N mm), link {cl:.6e}; link share {:.3} %", 100.0 * cl / (ctm + cl));
        for k in 0..p.n {
            let hinge = s.hinge_angles[k] / pt;
            let joint = s.joint_angles[k] / pt;
            assert!(((hinge - hinge_lin) / hinge_lin).abs() < 2e-4, "hinge {hinge} vs {hinge_lin}");
            assert!(((joint - joint_lin) / joint_lin).abs() < 2e-4, "joint {joint} vs {joint_lin}");
            let link = s.link_angles[k] / pt;
            assert!(((link - p.e * cl) / (p.e * cl)).abs() < 1e-3, "link {link} vs {}", p.e * cl);
        }
        // The links are not negligible at the percent level, but small.
        assert!(cl / (ctm + cl) > 0.005 && cl / (ctm + cl) < 0.05);
        // With rigid links the joint angle is the hinge's alone.
        let r = ContinuumParams { rigid_links: true, ..p.clone() };
        let sr = solve(&r, pt, &[], [0.0, 0.0], Discretisation::default()).unwrap();
        assert!(((sr.joint_angles[0] / pt - hinge_lin) / hinge_lin).abs() < 2e-4);
        assert_eq!(sr.link_angles[0], 0.0);
    }
}

/// With a stack, the bonded layer is the continuum limit of docs/model.md's
/// K = C_h⁻¹ + Tᵀ C_de⁻¹ T: section N = EA ε + B κ, M = B ε + D κ with
/// B = E_de A_de d, D = E I_h + E_de (I_de + A_de d²). At small P (N = -P, M = P e)
/// κ = P (EA e + B) / (EA D - B²).
#[test]
fn small_load_limit_with_stacks_matches_the_composite_section() {
    let p = ContinuumParams::default();
    let stacks = [2.0, 1.2, 0.0];
    let pt = 1e-4;
    let s = solve(&p, pt, &stacks, [0.0, 0.0], Discretisation::default()).unwrap();
    for (k, &tk) in stacks.iter().enumerate() {
        let eb = p.body_modulus();
        let d = 0.5 * (p.t_min + tk);
        let ade = p.w * tk;
        let lin = notch_integral(&p, 4000, |_, t| {
            let ea = eb * p.w * t + p.e_de * ade;
            let bc = p.e_de * ade * d;
            let dd = eb * p.w * t.powi(3) / 12.0 + p.e_de * (p.w * tk.powi(3) / 12.0 + ade * d * d);
            (ea * p.e + bc) / (ea * dd - bc * bc)
        });
        let got = s.hinge_angles[k] / pt;
        assert!(((got - lin) / lin).abs() < 2e-4, "joint {}: {got} vs {lin}", k + 1);
    }
}

/// A tip force alone on the straight finger: θ_tip = F ∫ (L - s) / E I(s) ds.
#[test]
fn small_tip_force_matches_the_linear_finger() {
    let p = ContinuumParams::default();
    let f = 1e-5;
    let s = solve(&p, 0.0, &[], [0.0, f], Discretisation::default()).unwrap();
    let len = p.n as f64 * p.l;
    let eb = p.body_modulus();
    let mut lin = 0.0;
    for k in 0..p.n {
        let x0 = k as f64 * p.l;
        lin += notch_integral(&p, 4000, |x, t| (len - x0 - x) * 12.0 / (eb * p.w * t.powi(3)));
        // Link: ∫ (L - s) ds / (E I_b) over [x0 + 2a, x0 + l].
        let (s0, s1) = (x0 + 2.0 * p.a, x0 + p.l);
        lin += ((len - s0).powi(2) - (len - s1).powi(2)) / 2.0 * 12.0 / (eb * p.w * p.b.powi(3));
    }
    let got = s.tip.theta / f;
    assert!(((got - lin) / lin).abs() < 1e-4, "{got} vs {lin}");
    // A tip force couples the joints: the proximal joint bends most.
    assert!(s.joint_angles[0] > s.joint_angles[1] && s.joint_angles[1] > s.joint_angles[2]);
}

#[test]
fn tension_bends_toward_flexor_monotonically_and_stacks_stiffen() {
    let p = ContinuumParams::default();
    let disc = Discretisation::new(64, 16);
    let mut last = vec![0.0; p.n];
    let mut last_ratio = 0.0;
    for &t in &[0.05, 0.2, 0.5, 1.0, 2.0, 3.0] {
        let s = solve(&p, t, &[], [0.0, 0.0], disc).unwrap();
        for (k, (now, before)) in s.joint_angles.iter().zip(&last).enumerate() {
            assert!(now > before, "P {t}: joint {} not increasing", k + 1);
            assert!(s.nodes[k + 1].y > 0.0, "node {} not on the flexor side", k + 1);
        }
        assert!(s.tip.y > 0.0 && s.excursion > 0.0);
        // Beam-column softening: the angle per unit tension grows with P.
        let ratio = s.joint_angles[0] / t;
        assert!(ratio > last_ratio, "no softening at {t}");
        last_ratio = ratio;
        last = s.joint_angles.clone();
        // Under tension alone identical joints decouple to identical angles.
        assert!(max_diff(&s.joint_angles, &[s.joint_angles[0]; 3]) < 1e-9);
        // Stacks stiffen, thicker stacks more.
        let thin = solve(&p, t, &[1.0; 3], [0.0, 0.0], disc).unwrap();
        let thick = solve(&p, t, &[2.0; 3], [0.0, 0.0], disc).unwrap();
        assert!(thin.joint_angles[0] < s.joint_angles[0] && thick.joint_angles[0] < thin.joint_angles[0]);
        // The least stiff joint bends most.
        let mixed = solve(&p, t, &[2.0, 1.0, 0.0], [0.0, 0.0], disc).unwrap();
        assert!(mixed.joint_angles[0] < mixed.joint_angles[1] && mixed.joint_angles[1] < mixed.joint_angles[2]);
    }
    // The plate modulus stiffens by about 1/(1 - ν²).
    let a = solve(&p, 0.01, &[], [0.0, 0.0], disc).unwrap();
    let b = solve(&ContinuumParams { plate: true, ..p.clone() }, 0.01, &[], [0.0, 0.0], disc).unwrap();
    let r = a.joint_angles[0] / b.joint_angles[0];
    assert!((r - 1.0 / (1.0 - 0.45f64.powi(2))).abs() < 0.01, "plate ratio {r}");
}

#[test]
fn span_closure_is_reported_not_returned() {
    let p = ContinuumParams::default();
    let disc = Discretisation::new(64, 16);
    let rep = closing_tension(&p, &[], [0.0, 0.0], disc, 20.0).unwrap().expect("a span closes below 20 N");
    assert!(rep.tension > 3.0 && rep.tension < 20.0, "closing at {}", rep.tension);
    assert!((rep.solution.spans.iter().cloned().fold(f64::INFINITY, f64::min) - p.contact_floor).abs() < 1e-5);
    // Past it, solve refuses with a typed error naming the span.
    match solve(&p, rep.tension * 1.05, &[], [0.0, 0.0], disc) {
        Err(ContinuumError::Contact { joint, span, tension }) => {
            assert!((1..=3).contains(&joint));
            assert!(span <= p.contact_floor && tension <= rep.tension * 1.05 + 1e-12);
        }
        other => panic!("expected contact, got {other:?}"),
    }
    // Below it, an answer with every number finite.
    let s = solve(&p, rep.tension * 0.95, &[], [0.0, 0.0], disc).unwrap();
    assert!(s.spans.iter().all(|v| *v > p.contact_floor));
    assert!(s.centreline.iter().flatten().all(|v| v.is_finite()));
    // Nothing closes at 2 N.
    assert!(closing_tension(&p, &[], [0.0, 0.0], disc, 2.0).unwrap().is_none());
    // With a fixed tip force the report is consistent with `solve` under the same loads.
    let held = closing_tension(&p, &[], [0.0, -0.05], disc, 20.0).unwrap().unwrap();
    assert_eq!(held.solution.tip_force, [0.0, -0.05]);
    let below = solve(&p, held.tension * 0.99, &[], [0.0, -0.05], disc).unwrap();
    assert!(below.spans.iter().all(|v| *v > p.contact_floor));
    assert!(matches!(solve(&p, held.tension * 1.01, &[], [0.0, -0.05], disc), Err(ContinuumError::Contact { .. })));
    // A larger dead force toward -y makes the curling finger snap through: the load
    // path folds near 3.40 N, reported as a limit point, never as an answer past it.
    let coarse = Discretisation::new(32, 8);
    match closing_tension(&p, &[], [0.0, -0.3], coarse, 20.0) {
        Err(ContinuumError::LimitPoint { from, to }) => {
            assert!(from > 3.3 && from < 3.5 && to >= from, "fold at {from}..{to}");
            assert!(matches!(solve(&p, 3.6, &[], [0.0, -0.3], coarse), Err(ContinuumError::LimitPoint { .. })));
            let s = solve(&p, 3.3, &[], [0.0, -0.3], coarse).unwrap();
            assert!(s.joint_angles.iter().all(|v| v.is_finite()));
        }
        other => panic!("expected a limit point, got {other:?}"),
    }
    println!("closing: {} N alone, {} N with a 0.05 N tip force toward -y", rep.tension, held.tension);
}

#[test]
fn invalid_inputs_are_errors_not_nan() {
    let p = ContinuumParams::default();
    let d = Discretisation::new(16, 4);
    assert!(matches!(solve(&p, -1.0, &[], [0.0, 0.0], d), Err(ContinuumError::InvalidInput(_))));
    assert!(matches!(solve(&p, f64::NAN, &[], [0.0, 0.0], d), Err(ContinuumError::InvalidInput(_))));
    assert!(matches!(solve(&p, 1.0, &[1.0], [0.0, 0.0], d), Err(ContinuumError::InvalidInput(_))));
    assert!(matches!(solve(&p, 1.0, &[-1.0, 0.0, 0.0], [0.0, 0.0], d), Err(ContinuumError::InvalidInput(_))));
    let bad = ContinuumParams { a: 20.0, ..p.clone() };
    assert!(matches!(solve(&bad, 1.0, &[], [0.0, 0.0], d), Err(ContinuumError::InvalidInput(_))));
    // Zero load: the straight finger.
    let s = solve(&p, 0.0, &[], [0.0, 0.0], d).unwrap();
    assert!((s.tip.x - 81.0).abs() < 1e-12 && s.tip.y == 0.0 && s.spans.iter().all(|v| (v - 10.0).abs() < 1e-12));
}
