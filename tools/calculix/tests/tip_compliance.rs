//! The design study's FE check (`tip_compliance_under_cable`, docs/design.md): at a cable
//! tension too small to bend the finger, its three tip-load steps give the linear compliance
//! of the whole finger's end section (`compliance_between`, unit loads on the undeformed
//! mesh), column by column; and a mesh with a notch length that rounds (a = 6.3 mm) is one piece.
use finger_calculix::ccx::{Kind, Law};
use finger_calculix::mesh::{finger_segments, Density};
use finger_calculix::{compliance_between, tip_compliance_under_cable};
use finger_model::Params;

fn check(p: &Params<f64>) {
    let d = Density::coarse();
    let stack = [1.0; 3];
    let tip = p.n as f64 * p.l;
    let lin = compliance_between(p, &finger_segments(p, &stack), Kind::PlaneStrain, &d, 0.0, tip).unwrap();
    let (_, c) = tip_compliance_under_cable(p, &stack, Kind::PlaneStrain, &d, Law::NeoHooke, 1e-4, [1e-3, 1e-3, 1e-2]).unwrap();
    for (i, j) in [(1, 1), (2, 2), (1, 2), (2, 1), (0, 0)] {
        let e = c[i][j] / lin[i][j] - 1.0;
        assert!(e.abs() < 0.01, "a = {}: C[{i}][{j}] {:.6e} against the linear {:.6e} ({:+.3} %)", p.a, c[i][j], lin[i][j], 100.0 * e);
    }
}

#[test]
fn tip_load_steps_give_the_linear_tip_compliance_at_a_small_tension() {
    check(&Params::<f64>::vhb4905());
    check(&Params { a: 6.3, ..Params::<f64>::vhb4905() });
}
