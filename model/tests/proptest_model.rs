//! Property tests over the valid parameter domain: no panic, no NaN or infinity in
//! any Ok result, every failure a typed error; the converged solver converges or returns its
//! branch-end (contact, limit point) or non-convergence error in every case. Case counts are
//! kept moderate so the suite stays fast.

use finger_model::{Error, Finger, Method, Params, Real, Solution};
use proptest::prelude::*;

/// A valid parameter set: geometry built so that every documented constraint holds
/// (t_min < b, 2a < l, 0 < e <= b/2, span_floor < 2a), bodies from soft (1 MPa) to PLA-like
/// (3,500 MPa), with or without stacks, m = 1..3 sub-elements, 1..5 joints.
fn params() -> impl Strategy<Value = Params<f64>> {
    (
        (1usize..=5, 1usize..=3, 0.5f64..20.0, 0.02f64..0.95, 0.3f64..8.0),
        (0.5f64..40.0, 0.2f64..1.0, 1.0f64..40.0, 0.0f64..1.0, prop::bool::ANY),
        (prop::sample::select(vec![0u32, 1, 4, 8]), 0.1f64..2.0, 0.05f64..0.49, prop::bool::ANY),
    )
        .prop_map(|((n, m, b, tmin_frac, a), (gap, e_frac, w, e_b_u, plate), (layers, z0, nu, paper))| {
            // E_b log-uniform in [1, 3500] MPa
            let e_b = 10f64.powf(e_b_u * 3500f64.log10());
            let base = if paper { Params::paper() } else { Params::default() };
            Params { n, m, b, t_min: tmin_frac * b, a, l: 2.0 * a + gap, e: e_frac * b / 2.0, w, e_b, plate, layers, z0, nu, span_floor: 0.01 * a, ..base }
        })
}

fn finite<R: Real>(s: &Solution<R>) -> bool {
    let n = s.n;
    s.nodes[..=n].iter().all(|p| p.x.is_finite() && p.y.is_finite() && p.theta.is_finite())
        && s.joint_angle[..n].iter().all(|a| a.is_finite())
        && s.span[..n].iter().all(|a| a.is_finite())
        && s.tangent_det[..n].iter().all(|a| a.is_finite())
        && s.cable_excursion.is_finite()
        && s.residual.is_finite()
}

fn branch_end_or_not_converged(e: &Error) -> bool {
    matches!(e, Error::Contact { .. } | Error::LimitPoint { .. } | Error::ForceLimit { .. } | Error::NotConverged { .. })
}

/// One solve in scalar R: Ok results are finite; errors are the ones valid input may end in.
fn check<R: Real>(p: Params<f64>, tension: f64, vfrac: [f64; 3], n_inc: u32) -> Result<(), TestCaseError> {
    let f = Finger::new(p.cast::<R>()).map_err(|e| TestCaseError::fail(format!("valid params refused: {e:?}")))?;
    let ceil = f.voltage_ceiling().to_f64();
    let volts: Vec<R> = (0..p.n).map(|k| R::from_f64(if p.layers > 0 { vfrac[k % 3] * ceil } else { 0.0 })).collect();
    let t = R::from_f64(tension);
    for method in [Method::converged(), Method::Stepping { n_inc }] {
        match f.solve(t, &volts, method) {
            Ok(s) => {
                prop_assert!(finite(&s), "non-finite solution {method:?}: {s:?}");
                prop_assert!(s.span[..p.n].iter().all(|&x| x >= f.params().span_floor), "span below the floor");
            }
            Err(e) => match method {
                Method::Converged { .. } => {
                    prop_assert!(branch_end_or_not_converged(&e) || matches!(e, Error::Singular { .. }), "converged: {e:?}")
                }
                Method::Stepping { .. } => {
                    prop_assert!(matches!(e, Error::Contact { .. } | Error::Singular { .. }), "stepping: {e:?}")
                }
            },
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn f64_solves_are_finite_or_typed(
        p in params(),
        tension in prop_oneof![0.0f64..2.0, 0.0f64..50.0, 0.0f64..2000.0],
        vfrac in prop::array::uniform3(0.0f64..0.999),
        n_inc in 1u32..40,
    ) {
        check::<f64>(p, tension, vfrac, n_inc)?;
    }

    #[test]
    fn f32_solves_are_finite_or_typed(
        p in params(),
        tension in prop_oneof![0.0f64..2.0, 0.0f64..50.0],
        vfrac in prop::array::uniform3(0.0f64..0.999),
        n_inc in 1u32..40,
    ) {
        check::<f32>(p, tension, vfrac, n_inc)?;
    }

    /// Voltages at or past the ceiling are refused with the ceiling error, never solved.
    #[test]
    fn voltages_at_or_past_the_ceiling_are_refused(p in params(), over in 1.0f64..3.0, joint in 0usize..5) {
        let p = Params { layers: 4, ..p };
        let f = Finger::new(p).unwrap();
        let mut v = vec![0.0; p.n];
        let k = joint % p.n;
        v[k] = over * f.voltage_ceiling();
        match f.solve(1.0, &v, Method::converged()) {
            Err(Error::VoltageCeiling { joint, .. }) => prop_assert_eq!(joint, k + 1),
            other => prop_assert!(false, "not refused: {:?}", other.map(|s| s.joint_angle)),
        }
    }

    /// Any f64 input, finite or not, to `solve`: a finite solution or a typed error, no panic.
    #[test]
    fn arbitrary_inputs_never_panic(
        tension in prop::num::f64::ANY,
        v in prop::num::f64::ANY,
        fx in prop::num::f64::ANY,
        n_inc in 0u32..5,
    ) {
        let f = Finger::new(Params::<f64>::default()).unwrap();
        for method in [Method::converged(), Method::Stepping { n_inc }] {
            if let Ok(s) = f.solve(tension, &[v, 0.0, 0.0], method) {
                prop_assert!(finite(&s));
            }
            if let Ok(s) = f.solve_loaded(tension.abs().min(5.0), &[0.0; 3], [fx.clamp(-1.0, 1.0), 0.0], method) {
                prop_assert!(finite(&s));
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    /// The inverse of any posture the forward model reaches under tension alone is
    /// found and holds it: forward(inverse) within 1e-8 rad in f64. Over the hardware's
    /// parameter sets (the default and the paper preset) with every hinge model (m = 1..8,
    /// plate modulus on/off, flexible links on/off), voltages from 0 to 90 % of the ceiling,
    /// tensions up to 60 % of the branch end (fmax) or of 8 N. (Over the whole domain of `params()`
    /// some geometries still end in non-convergence or a contact on the way: docs/inverse.md,
    /// "Limits".)
    #[test]
    fn inverse_of_a_reachable_posture_holds_it(
        paper in prop::bool::ANY,
        m in 1usize..=8,
        plate in prop::bool::ANY,
        flex_links in prop::bool::ANY,
        frac in 0.02f64..0.6,
        vfrac in prop::array::uniform3(0.0f64..0.9),
    ) {
        let base = if paper { Params::paper() } else { Params::default() };
        let p = Params { m, plate, flex_links, ..base };
        let f = Finger::new(p).map_err(|e| TestCaseError::fail(format!("valid params refused: {e:?}")))?;
        let ceil = f.voltage_ceiling();
        let volts: Vec<f64> = (0..p.n).map(|k| vfrac[k % 3] * ceil).collect();
        // (the forward model's own branch-end search is the other properties' subject)
        let Ok(fmax) = f.fmax(&volts).map(|b| b.tension) else { return Ok(()) };
        // the m = 1 hinge never closes: its fmax is the search bound (hundreds of N), far past
        // any cable the hardware pulls; 8 N is four times the default posture's tension
        let tension = frac * fmax.min(8.0);
        let s = f.solve(tension, &volts, Method::converged()).map_err(|e| TestCaseError::fail(format!("forward: {e:?}")))?;
        let angles = &s.joint_angle[..p.n];
        let inv = finger_model::inverse::solve_pose(&f, angles, None)
            .map_err(|e| TestCaseError::fail(format!("reachable posture refused: P={tension} V={volts:?} {e:?}")))?;
        let back = f.solve(inv.tension, &inv.volts[..p.n], Method::converged())
            .map_err(|e| TestCaseError::fail(format!("forward of the inverse failed: {e:?}")))?;
        for k in 0..p.n {
            let err = (back.joint_angle[k] - angles[k]).abs();
            prop_assert!(err <= 1e-8, "joint {k}: {err:e} rad (P={tension}, inverse P={})", inv.tension);
        }
    }
}
