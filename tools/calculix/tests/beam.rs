//! Each idealisation against beam theory on a uniform beam: a strip clamped at one
//! end, L = 10 t, loaded at the other; C_θ-M = L / (E I) (E_eff per idealisation) and
//! C_x-Fx = L / (E A). Coarse meshes: these assert the idealisation, not the last digit.
use finger_calculix::beam_compliance;
use finger_calculix::ccx::Kind;
use finger_calculix::mesh::Density;
use finger_model::Params;

const D: Density = Density { notch_cols: 2, link_cols: 10, rows: 2, stack_rows: 1, layers: 2 };

/// (C_θM / (L/(E I)), C_xx / (L/(E A))) for a strip of thickness b, width w, E = E_b.
fn ratios(b: f64, w: f64, kind: Kind) -> (f64, f64) {
    let p = Params::<f64> { b, w, ..Params::default() };
    let len = 10.0 * b;
    let c = beam_compliance(&p, len, kind, &D).expect("ccx runs");
    let i = w * b * b * b / 12.0;
    (c[2][2] / (len / (p.e_b * i)), c[0][0] / (len / (p.e_b * w * b)))
}

fn plate() -> f64 {
    1.0 - 0.45f64 * 0.45 // E / E' with E' = E / (1 - nu_b^2)
}

#[test]
fn plane_strain_is_the_plate_beam() {
    let (m, x) = ratios(1.5, 20.0, Kind::PlaneStrain);
    assert!((m / plate() - 1.0).abs() < 0.02, "C_θM / plate theory = {}", m / plate());
    assert!((x / plate() - 1.0).abs() < 0.02, "C_xx / plate theory = {}", x / plate());
}

#[test]
fn narrow_3d_beam_is_the_plane_stress_beam() {
    let (m, x) = ratios(1.5, 1.5, Kind::Half3d);
    assert!((m - 1.0).abs() < 0.02, "C_θM / beam theory = {m}");
    assert!((x - 1.0).abs() < 0.02, "C_xx / beam theory = {x}");
}

#[test]
fn wide_3d_beam_lies_between_beam_and_plate() {
    // 20 mm wide, 1.5 mm thick (the hinge's waist): the clamp holds the anticlastic curvature
    // back near it; neither E nor E/(1 - nu^2) is exact
    let (m, _) = ratios(1.5, 20.0, Kind::Half3d);
    assert!(m < 0.97 && m > plate() * 1.03, "C_θM / beam theory = {m} (plate {})", plate());
}

#[test]
fn calculix_plane_stress_of_a_wide_section_is_not_plane_stress() {
    // CPS8R is expanded into one slab of bricks of the section's width: for w >> t it bends
    // like the plate (plane strain), not like σ_z = 0
    let (m, x) = ratios(1.5, 20.0, Kind::PlaneStress);
    assert!((m / plate() - 1.0).abs() < 0.03, "C_θM / plate theory = {}", m / plate());
    assert!((x - 1.0).abs() < 0.02, "axial: free contraction, C_xx / beam theory = {x}");
    // and for a square section it is still stiffer than the beam
    let (m, _) = ratios(1.5, 1.5, Kind::PlaneStress);
    assert!(m < 0.97 && m > 0.9, "square section: C_θM / beam theory = {m}");
}
