//! The FE's material law: neo-Hooke and St Venant-Kirchhoff share E and ν, so they
//! agree at small load; at finite strain (the waist at 2 N) St Venant-Kirchhoff, which softens
//! in compression, bends more.
use finger_calculix::ccx::{Kind, Law};
use finger_calculix::finger_under_cable;
use finger_calculix::mesh::Density;
use finger_model::Params;

/// Joint 2's angle under `law` relative to neo-Hooke's, minus one, at 0.05 N and at 2 N
/// (coarse plane-strain mesh, `volts` on every stack).
fn against_neo_hooke(p: &Params<f64>, volts: f64, law: Law) -> (f64, f64) {
    let d = Density::coarse();
    let run = |law| finger_under_cable(p, &[volts; 3], Kind::PlaneStrain, &d, law, &[0.05, 2.0]).unwrap();
    let (nh, other) = (run(Law::NeoHooke), run(law));
    (other[0].joint_angle[1] / nh[0].joint_angle[1] - 1.0, other[1].joint_angle[1] / nh[1].joint_angle[1] - 1.0)
}

#[test]
fn laws_agree_at_small_load_and_part_at_finite_strain() {
    let (small, large) = against_neo_hooke(&Params::<f64>::default().without_stacks(), 0.0, Law::StVenantKirchhoff);
    assert!(small.abs() < 0.002, "0.05 N: laws differ by {:.3} %", 100.0 * small);
    assert!(large > 0.01, "2 N: St Venant-Kirchhoff only {:.3} % softer", 100.0 * large);
}

#[test]
fn the_stacks_law_alone_sets_the_stacked_fingers_growth_with_load() {
    // neo-Hookean stacks soften in the stretch a flexing joint gives them; St Venant-Kirchhoff
    // stacks (the body neo-Hookean in both) do not: the same at small load, stiffer at 2 N
    let (small, large) = against_neo_hooke(&Params::<f64>::default(), 2.0, Law::NeoHookeBodySvkStacks);
    assert!(small.abs() < 0.002, "0.05 N: laws differ by {:.3} %", 100.0 * small);
    assert!(large < -0.02, "2 N: St Venant-Kirchhoff stacks only {:.3} % stiffer", -100.0 * large);
}
