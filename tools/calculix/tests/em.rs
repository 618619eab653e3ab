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
    // the model's laminate beside this run (`em::model_hinge`): its rotation under the voltage
    // alone within a quarter of the FE's (this mesh's is 0.63°, 11 % under the coarse mesh's
    // and 14 % under the medium one's: the model is 20 % above it, 7 % and 3 % above those),
    // its stiffness ratio's excess above the FE's (the table's test has the rest)
    let m = finger_calculix::em::model_hinge(&p, v * 0.999_999).unwrap();
    println!("FE {deg:.4}° {ratio:.5}, model {:.4}° {:.5}", m.rotation.to_degrees(), m.ratio);
    assert!((m.rotation / on.rotation - 1.0).abs() < 0.25, "model {:.4}° vs FE {deg:.4}°", m.rotation.to_degrees());
    assert!(m.ratio > ratio, "model {:.5} vs FE {ratio:.5}", m.ratio);
}

/// The FE has no body load: a set with gravity on is refused before any run, not solved
/// without it.
#[test]
fn gravity_is_refused_not_ignored() {
    let p = Params::<f64>::vhb4905().with_gravity(9.81, 90.0);
    assert!(matches!(free_film(&p, 1000.0, FixedPoint::default()), Err(finger_calculix::ccx::FeError::Mesh(_))));
    assert!(matches!(hinge_em(&p, 1000.0, 0.1, 0.01, &Density::coarse(), FixedPoint::default()), Err(finger_calculix::ccx::FeError::Mesh(_))));
}

/// The model's laminate (`em::model_hinge`: the bonded stack held across its width, its
/// blocked stress off the neutral axis and its softened tangent) against the electromechanical
/// FE's table (`em-hinges.txt`, `cargo run --release --bin fe-em-table`: the board's finger and
/// three designs, coarse mesh, at the film's ceiling), for the same hinges (`em::EM_HINGES`).
/// What holds today (docs/materials.md "Free film and bonded stack" has the table): the
/// rotation under the voltage alone has the FE's sign and is within 30 % of it on every hinge
/// (7 % on the board's); the stiffness ratio's excess at a fixed rotation is between half and 6
/// times the FE's (twice on the board's). Not yet the 5 % (docs/materials.md says why).
#[test]
fn the_laminate_against_the_fe_table() {
    use finger_calculix::em::{model_hinge, EM_HINGES};
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/em-hinges.txt")).unwrap();
    let mut seen = 0;
    for line in text.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty()) {
        let field =
            |k: &str| line.split_whitespace().find_map(|f| f.strip_prefix(k).and_then(|v| v.strip_prefix('='))).unwrap_or_else(|| panic!("{k} in {line}"));
        let num = |k: &str| field(k).parse::<f64>().unwrap();
        let h = EM_HINGES.iter().find(|h| h.name == field("name")).unwrap_or_else(|| panic!("{line}"));
        let p = h.params().unwrap();
        let v = num("volts");
        assert!((v - de::voltage_ceiling(&p)).abs() < 1e-3, "{}: the table's voltage is the ceiling", h.name);
        let m = model_hinge(&p, v * 0.999_999).unwrap();
        let (fe_rot, fe_ratio) = (num("fe_rotation_deg").to_radians(), num("fe_ratio"));
        let e_rot = m.rotation / fe_rot - 1.0;
        let x = (m.ratio - 1.0) / (fe_ratio - 1.0);
        println!(
            "{}: rotation model {:.3}° FE {:.3}° ({:+.1} %), ratio model {:.5} FE {:.5} (excess {x:.2}×)",
            h.name,
            m.rotation.to_degrees(),
            fe_rot.to_degrees(),
            100.0 * e_rot,
            m.ratio,
            fe_ratio
        );
        assert!(fe_rot > 0.0 && e_rot.abs() < 0.3, "{}: rotation {e_rot:+.3}", h.name);
        if h.name == "board" {
            assert!(e_rot.abs() < 0.08, "board: rotation {e_rot:+.3}");
        }
        assert!(fe_ratio > 1.0 && (0.5..6.0).contains(&x), "{}: excess {x}", h.name);
        seen += 1;
    }
    assert_eq!(seen, EM_HINGES.len(), "one line per hinge");
}
