//! The FE's material law: neo-Hooke and St Venant-Kirchhoff share E and ν, so they
//! agree at small load; at finite strain (the waist at 2 N) St Venant-Kirchhoff, which softens
//! in compression, bends more.
use finger_calculix::ccx::{Kind, Law};
use finger_calculix::finger_under_cable;
use finger_calculix::mesh::Density;
use finger_model::Params;

#[test]
fn laws_agree_at_small_load_and_part_at_finite_strain() {
    let p = Params::<f64>::default().without_stacks();
    let d = Density::coarse();
    let run = |law| finger_under_cable(&p, &[0.0; 3], Kind::PlaneStrain, &d, law, &[0.05, 2.0]).unwrap();
    let (nh, svk) = (run(Law::NeoHooke), run(Law::StVenantKirchhoff));
    let small = svk[0].joint_angle[1] / nh[0].joint_angle[1] - 1.0;
    let large = svk[1].joint_angle[1] / nh[1].joint_angle[1] - 1.0;
    assert!(small.abs() < 0.002, "0.05 N: laws differ by {:.3} %", 100.0 * small);
    assert!(large > 0.01, "2 N: St Venant-Kirchhoff only {:.3} % softer", 100.0 * large);
}

#[test]
fn the_stacks_law_alone_sets_the_stacked_fingers_growth_with_load() {
    // neo-Hookean stacks soften in the stretch a flexing joint gives them; St Venant-Kirchhoff
    // stacks (the body neo-Hookean in both) do not: the same at small load, stiffer at 2 N
    let p = Params::<f64>::default();
    let d = Density::coarse();
    let run = |law| finger_under_cable(&p, &[2.0; 3], Kind::PlaneStrain, &d, law, &[0.05, 2.0]).unwrap();
    let (nh, mixed) = (run(Law::NeoHooke), run(Law::NeoHookeBodySvkStacks));
    let small = mixed[0].joint_angle[1] / nh[0].joint_angle[1] - 1.0;
    let large = mixed[1].joint_angle[1] / nh[1].joint_angle[1] - 1.0;
    assert!(small.abs() < 0.002, "0.05 N: laws differ by {:.3} %", 100.0 * small);
    assert!(large < -0.02, "2 N: St Venant-Kirchhoff stacks only {:.3} % stiffer", -100.0 * large);
}
