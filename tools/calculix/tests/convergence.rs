//! Mesh convergence by refinement: one element's small-load compliance (plane
//! strain at three densities, 3D at two) and the finger's joint angles under the cable.
use finger_calculix::ccx::{Kind, Law};
use finger_calculix::mesh::Density;
use finger_calculix::{element_compliance, finger_under_cable};
use finger_model::Params;

#[test]
fn element_compliance_converges_plane_strain() {
    let p = Params::<f64>::default();
    for stack in [0.0, 2.0] {
        let c: Vec<f64> = (1..=3).map(|k| element_compliance(&p, stack, Kind::PlaneStrain, &Density::coarse().times(k)).unwrap()[2][2]).collect();
        let (d1, d2) = ((c[1] - c[0]).abs(), (c[2] - c[1]).abs());
        assert!(d2 < 0.5 * d1, "stack {stack}: C_θM {c:?} does not converge");
        assert!(d2 / c[2] < 0.005, "stack {stack}: C_θM {c:?}: x2 -> x3 changes {:.3} %", 100.0 * d2 / c[2]);
    }
}

#[test]
fn element_compliance_3d_coarse_is_within_2_percent_of_refined() {
    let p = Params::<f64>::default();
    let c1 = element_compliance(&p, 0.0, Kind::Half3d, &Density::coarse()).unwrap()[2][2];
    let c2 = element_compliance(&p, 0.0, Kind::Half3d, &Density::coarse().times(2)).unwrap()[2][2];
    assert!(((c1 - c2) / c2).abs() < 0.02, "3D C_θM {c1} vs {c2}");
    assert!(c2 > c1, "refining softens (the coarse mesh is too stiff): {c1} vs {c2}");
}

#[test]
fn finger_joint_angles_converge_under_the_cable() {
    let p = Params::<f64>::default().without_stacks();
    let a = finger_under_cable(&p, &[0.0; 3], Kind::PlaneStrain, &Density::coarse(), Law::NeoHooke, &[1.0]).unwrap();
    let b = finger_under_cable(&p, &[0.0; 3], Kind::PlaneStrain, &Density::coarse().times(2), Law::NeoHooke, &[1.0]).unwrap();
    for k in 0..3 {
        let (x, y) = (a[0].joint_angle[k], b[0].joint_angle[k]);
        assert!(((x - y) / y).abs() < 0.015, "joint {}: {x} vs {y} rad", k + 1);
    }
}
