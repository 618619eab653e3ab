//! The firmware answers `solve` and fmax (`limits`) from the finger's cached branch table
//! (model inverse/table.rs), and rebuilds it when a parameter changes: the answers
//! are the full model's converged ones (`Finger::solve`, `Finger::fmax`) to the printed
//! digits, and `iters=0` shows the table's hole was already converged (the full solve from the
//! straight joint iterates).
use finger_fw::sim::SimBoard;
use finger_fw::App;
use finger_model::Method;
use host_tests::console::ceiling;
use host_tests::reply::{nums, val};
use host_tests::sim_console::{cmd, frac_of};

/// `solve P V1 V2 V3` against the app's finger's full solve: joints (3 decimals, degrees) and
/// tip (3 decimals, mm) within a unit of the last digit; returns `iters`.
fn check_solve(a: &mut App<SimBoard>, p: f32, v: [f32; 3]) -> u32 {
    let r = cmd(a, &format!("solve {p} {} {} {}", v[0], v[1], v[2]));
    assert!(r.starts_with("ok "), "{r}");
    let full = a.finger().solve(p, &v, Method::converged()).unwrap();
    let j = nums(val(&r, "joints"));
    for k in 0..3 {
        assert!((j[k] - (full.joint_angle[k] as f64).to_degrees()).abs() <= 1.5e-3, "{r}: joint {k} vs {:?}", full.joint_angle);
    }
    let t = nums(val(&r, "tip"));
    assert!((t[0] - full.tip().x as f64).abs() <= 1.5e-3 && (t[1] - full.tip().y as f64).abs() <= 1.5e-3, "{r}: tip vs {:?}", full.tip());
    val(&r, "iters").parse().unwrap()
}

#[test]
fn solve_and_fmax_come_from_the_table_and_follow_a_parameter_change() {
    let mut a = App::new(SimBoard::default());
    // the table is the finger's without its weight (under gravity the board keeps none)
    assert_eq!(host_tests::sim_console::cmd(&mut a, "param grav 0"), "ok grav=0");
    let vm = ceiling(&mut a);
    let at = |f: [f64; 3]| f.map(|f| frac_of(vm, f));
    let fmax = |a: &mut App<SimBoard>| val(&cmd(a, "limits"), "fmax").parse::<f64>().unwrap();
    // a high tension: 0.45 of fmax at 0 V, well inside the branch (as 7 N was of the paper
    // film's 16 N)
    let high = (0.45 * fmax(&mut a)) as f32;
    for (p, v) in [(1.0, [0.0; 3]), (1.0, at([0.9, 0.5, 0.0])), (high, at([0.2, 0.6, 0.9]))] {
        assert_eq!(check_solve(&mut a, p, v), 0, "P {p} V {v:?}: the table's hole should need no Newton step");
    }
    // fmax at 0 V: the table's (the firmware's) equals the full search's to its 1e-4
    let want = a.finger().fmax(&[0.0; 3]).unwrap().tension as f64;
    let got = fmax(&mut a);
    assert!((got - want).abs() <= 2e-4 * want, "fmax {got} vs {want}");
    // a parameter change rebuilds the table: the answers follow the new finger (a stale
    // table would answer for the old finger, or need Newton steps)
    let r = cmd(&mut a, "param t_min 1.8");
    assert!(r.starts_with("ok"), "{r}");
    let vm = ceiling(&mut a);
    assert_eq!(check_solve(&mut a, 1.0, [0.9, 0.5, 0.0].map(|f| frac_of(vm, f))), 0);
    let want = a.finger().fmax(&[0.0; 3]).unwrap().tension as f64;
    let got = fmax(&mut a);
    assert!((got - want).abs() <= 2e-4 * want, "after the change: fmax {got} vs {want}");
}
