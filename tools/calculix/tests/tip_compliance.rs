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

/// A stack that nearly fills its notch (the design study's front: 4 mm in a 4.225 mm notch,
/// 4.32 mm in 4.4 mm) ends a few um from the notch's end; the mesh takes that end at the
/// notch's (no column of um beside the link, which made ccx cut back until it gave up), and
/// ccx solves the finger under the cable.
#[test]
fn a_stack_that_nearly_fills_its_notch_meshes_and_solves() {
    use finger_calculix::mesh::mesh2;
    use finger_model::material::cards::CARDS;
    // as `fe-design` makes them: the card's finger, then the console's parameters
    let design = |card: &str, set: &[(&str, f64)]| {
        let mut p = Params::<f64>::with_card(CARDS.iter().find(|c| c.name == card).unwrap());
        for (k, v) in set {
            p.set(k, *v).unwrap();
        }
        p
    };
    let vhb = design("VHB-4905", &[("t_min", 1.55), ("a", 5.6), ("e_b", 40.0), ("w", 30.0), ("layers", 8.0), ("z0", 0.5)]);
    let elastosil = design("Elastosil-2030", &[("t_min", 1.2), ("a", 9.8), ("e_b", 40.0), ("w", 30.0), ("layers", 16.0), ("z0", 0.27)]);
    for (p, stack) in [(vhb, 4.0), (elastosil, 4.32)] {
        let d = Density { notch_cols: 16, ..Density::coarse() };
        let stacks = [stack; 3];
        let m = mesh2(&p, &finger_segments(&p, &stacks), &d);
        let mut xs: Vec<f64> = (0..m.nodes.len()).filter(|&i| m.corner[i]).map(|i| m.nodes[i][0]).collect();
        xs.sort_by(f64::total_cmp);
        xs.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        let narrowest = xs.windows(2).map(|w| w[1] - w[0]).fold(f64::MAX, f64::min);
        assert!(narrowest > 0.05, "t_min {}: a column {narrowest:.2e} mm wide", p.t_min);
        let (s, _) = tip_compliance_under_cable(&p, &stacks, Kind::PlaneStrain, &d, Law::NeoHooke, 4.2, [0.08, 0.08, 0.8])
            .unwrap_or_else(|e| panic!("t_min {}, stack {stack} mm: {e}", p.t_min));
        assert!(s.joint_angle.iter().all(|&q| q > 0.15 && q < 0.25), "{:?}", s.joint_angle);
    }
}
