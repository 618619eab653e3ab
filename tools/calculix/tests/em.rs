//! The electromechanical FE (`em`): the voltage applied (the Maxwell stress on each layer at its
//! current thickness, to a fixed point), not the model's thicknesses. Coarse meshes, one ccx
//! thread; the fine runs are `cargo run --release --bin fe-em` (docs/fidelity-fe.md).
use finger_calculix::em::{free_film, hinge_em, FixedPoint};
use finger_calculix::mesh::Density;
use finger_model::{de, Params};

/// A free film (free in its plane, equal-biaxial) thins as the model's free-film balance says,
/// G (s − s⁴) = ε V² / z0², within 0.1 %: at a low voltage and at the board's ceiling.
#[test]
fn a_free_film_reproduces_the_free_film_balance() {
    let p = Params::<f64>::vhb4905();
    for v in [2000.0, de::voltage_ceiling(&p)] {
        let (s_fe, s_model, sol) = free_film(&p, v, FixedPoint::default()).unwrap();
        let e = s_fe / s_model - 1.0;
        assert!(e.abs() < 1e-3, "{v:.0} V: FE s = {s_fe:.6}, model {s_model:.6} ({:+.4} %, {} runs)", 100.0 * e, sol.iterations);
        // and it thinned: the field was applied, not the model's thickness
        assert!(s_fe < 0.99, "{v:.0} V: s = {s_fe}");
    }
}

/// One hinge of the board's finger (VHB 4905, 4 × 0.5 mm on t_min 1.5 mm) at its ceiling,
/// coarse: the bonded stack off the neutral axis bends the hinge toward the cable (+), by about
/// the 0.72° the independent FE found; held at a fixed rotation (≈ 10°), its stiffness
/// drops by a fraction of a percent (the issue: 0.22 %); the bonded stack thins less at
/// mid-hinge than the free film.
#[test]
fn the_boards_hinge_under_its_ceiling_bends_toward_the_cable_and_barely_softens() {
    let p = Params::<f64>::vhb4905();
    let v = de::voltage_ceiling(&p);
    let d = Density { notch_cols: 6, link_cols: 2, rows: 2, stack_rows: 1, layers: 1 };
    let fp = FixedPoint { rtol: 1e-5, max_iter: 30 };
    let (th, dth) = (10f64.to_radians(), 0.5f64.to_radians());
    let off = hinge_em(&p, 0.0, th, dth, &d, fp).unwrap();
    let on = hinge_em(&p, v, th, dth, &d, fp).unwrap();
    assert_eq!(off.rotation, 0.0, "no voltage, no load: no rotation");
    let deg = on.rotation.to_degrees();
    assert!(deg > 0.4 && deg < 1.0, "rotation under {v:.0} V alone: {deg:.3}°");
    let ratio = off.k / on.k;
    assert!(ratio > 1.0005 && ratio < 1.01, "stiffness ratio at a fixed rotation: {ratio:.5}");
    // both held at the same rotation (the end face's), within the rounding of the two runs
    assert!((on.turned - off.turned).abs() < 0.05f64.to_radians(), "{} vs {}", on.turned, off.turned);
    let s_free = finger_model::de::layer_thickness_ratio(&p, 1, v).unwrap();
    assert!(on.s_mid_centre > s_free && on.s_mid_edge > s_free, "bonded {:.4}/{:.4}, free {s_free:.4}", on.s_mid_centre, on.s_mid_edge);
}

/// The FE has no body load: a set with gravity on is refused before any run, not solved
/// without it.
#[test]
fn gravity_is_refused_not_ignored() {
    let p = Params::<f64>::vhb4905().with_gravity(9.81, 90.0);
    assert!(matches!(free_film(&p, 1000.0, FixedPoint::default()), Err(finger_calculix::ccx::FeError::Mesh(_))));
    assert!(matches!(hinge_em(&p, 1000.0, 0.1, 0.01, &Density::coarse(), FixedPoint::default()), Err(finger_calculix::ccx::FeError::Mesh(_))));
}
