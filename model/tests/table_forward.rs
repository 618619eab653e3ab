//! The forward solve from the branch table (`BranchTable::solve`, model inverse/table.rs): the
//! table only chooses where Newton starts, so its answers are the full converged solve's, for
//! the default model (m = 8), the calibrated one and the paper's (m = 1), in f64 and f32.

use finger_model::inverse::{BranchTable, Options};
use finger_model::{Calibration, Finger, Method, Params, Real, Solution};

/// The default finger's calibration factors (docs/fidelity-fe.md).
fn calibration<R: Real>() -> Calibration<R> {
    let r = R::from_f64;
    Calibration { hinge: [r(1.5407), r(6.2456), r(1.0669), r(1.1546)], stack_axial: [r(0.7183), r(0.0546)], stack_bending: [r(5.2540), r(-1.7563)] }
}

fn fingers<R: Real>() -> Vec<(&'static str, Finger<R>)> {
    let d = Params::<R>::default();
    let paper = Params::<R> { m: 1, plate: false, flex_links: false, ..Params::default() };
    vec![("default", Finger::new(d).unwrap()), ("calibrated", Finger::with_calibration(d, calibration()).unwrap()), ("paper-m1", Finger::new(paper).unwrap())]
}

fn tip_err<A: Real, B: Real>(a: &Solution<A>, b: &Solution<B>) -> f64 {
    let (x, y) = (a.tip().x.to_f64() - b.tip().x.to_f64(), a.tip().y.to_f64() - b.tip().y.to_f64());
    (x * x + y * y).sqrt()
}

fn grid(top: f64) -> Vec<(f64, [f64; 3])> {
    let mut g = Vec::new();
    for p in [0.05, 0.2, 0.5, 1.0, 1.9, 3.0, 5.0, 7.0, 10.0, 15.0] {
        for v in [[0.0; 3], [0.5 * top; 3], [top; 3], [0.9 * top, 0.5 * top, 0.0], [0.3 * top, 0.99 * top, 0.7 * top]] {
            g.push((p, v));
        }
    }
    g
}

/// f64: the tabled answer is the full solve's (tip within 1e-7 mm, the same refusals).
#[test]
fn tabled_forward_is_the_full_solve_f64() {
    for (name, f) in fingers::<f64>() {
        let table = BranchTable::new(&f, &Options::default()).unwrap();
        let top = f.voltage_ceiling() * (1.0 - 1e-4);
        let mut answered = 0;
        for (p, v) in grid(top) {
            let full = f.solve(p, &v, Method::converged());
            let tab = table.solve(p, &v);
            match (&full, &tab) {
                (Ok(a), Ok(b)) => {
                    answered += 1;
                    assert!(tip_err(a, b) < 1e-7, "{name} P {p} V {v:?}: tip {:?} vs {:?}", a.tip(), b.tip());
                    for k in 0..3 {
                        assert!((a.joint_angle[k] - b.joint_angle[k]).abs() < 1e-9, "{name} P {p}: angle {k}");
                    }
                    assert!(b.residual <= 1e-9, "{name} P {p}: residual {}", b.residual);
                    assert!((a.cable_excursion - b.cable_excursion).abs() < 1e-8);
                }
                (Err(_), Err(_)) => {}
                _ => panic!("{name} P {p} V {v:?}: full {full:?} tabled {tab:?}"),
            }
        }
        assert!(answered > 20, "{name}: {answered}");
    }
}

/// f32 (the firmware): within 1e-3 mm of the f64 full solve, and the table does the work: most
/// joints are answered by the march at the table's hole (no Newton iteration).
#[test]
fn tabled_forward_f32_within_1um_of_f64() {
    for ((name, f), (_, f64f)) in fingers::<f32>().into_iter().zip(fingers::<f64>()) {
        let table = BranchTable::new(&f, &Options::default()).unwrap();
        let top = f64f.voltage_ceiling() * (1.0 - 1e-3);
        let (mut first_march, mut all, mut worst) = (0, 0, 0.0f64);
        for (p, v) in grid(top) {
            let Ok(want) = f64f.solve(p, &v, Method::converged()) else { continue };
            let v32 = [v[0] as f32, v[1] as f32, v[2] as f32];
            let got = table.solve(p as f32, &v32).unwrap_or_else(|e| panic!("{name} P {p} V {v:?}: {e:?}"));
            let e = tip_err(&got, &want);
            worst = worst.max(e);
            assert!(e < 1e-3, "{name} P {p} V {v:?}: tip error {e} mm");
            all += 1;
            if got.iterations == 0 {
                first_march += 1;
            }
        }
        eprintln!("{name}: worst tip error {worst:.2e} mm, {first_march} of {all} answered at the first march");
        assert!(first_march * 2 > all, "{name}: only {first_march} of {all} at the first march");
    }
}

/// fmax from the table is `Finger::fmax` (same end to its 1e-4 relative, same joint and kind).
#[test]
fn tabled_fmax_is_fmax() {
    let mut all = fingers::<f64>();
    // contact at a span of a micrometre: the branch's last few percent of tension
    all.push(("floor1e-6", Finger::new(Params { span_floor: 1e-6, ..Params::default() }).unwrap()));
    for (name, f) in all {
        let table = BranchTable::new(&f, &Options::default()).unwrap();
        let top = f.voltage_ceiling() * (1.0 - 1e-4);
        for v in [[0.0; 3], [0.5 * top; 3], [top; 3], [0.0, 0.5 * top, top], [top, 0.2 * top, 0.7 * top]] {
            let a = f.fmax(&v).unwrap();
            let b = table.fmax(&v).unwrap();
            assert!((a.tension - b.tension).abs() <= 2e-4 * a.tension, "{name} {v:?}: {a:?} vs {b:?}");
            assert_eq!(a.kind, b.kind, "{name} {v:?}: {a:?} vs {b:?}");
            // joints that end within the search's 1e-4 of each other tie (contact at the span
            // floor hardly depends on the stack): either may be named
            assert!(a.joint == b.joint || (a.tension - b.tension).abs() <= 1e-4 * a.tension, "{name} {v:?}: {a:?} vs {b:?}");
            // the tabled end is the last tension with an equilibrium
            assert!(f.solve(b.tension, &v, Method::converged()).is_ok(), "{name} {v:?}");
        }
    }
}

/// In f32 (the firmware), fmax from the table is the f64 fmax (1e-3 relative) for every model,
/// a tiny span floor and uniform and mixed voltages.
#[test]
fn tabled_fmax_f32_is_the_f64_fmax() {
    let mut all32 = fingers::<f32>();
    let mut all64 = fingers::<f64>();
    all32.push(("floor1e-6", Finger::new(Params { span_floor: 1e-6, ..Params::default() }).unwrap()));
    all64.push(("floor1e-6", Finger::new(Params { span_floor: 1e-6, ..Params::default() }).unwrap()));
    for ((name, f), (_, g)) in all32.into_iter().zip(all64) {
        let table = BranchTable::new(&f, &Options::default()).unwrap();
        let top = g.voltage_ceiling() * (1.0 - 1e-3);
        for v in [[0.0; 3], [0.5 * top; 3], [top; 3], [0.0, 0.5 * top, top]] {
            let want = g.fmax(&v).unwrap().tension;
            let got = table.fmax(&v.map(|x| x as f32)).unwrap().tension as f64;
            assert!((got - want).abs() <= 1e-3 * want, "{name} {v:?}: table {got} vs f64 {want}");
        }
    }
}

/// Over random tensions up to past fmax and random voltages below the ceiling (a fixed
/// pseudo-random sequence), the tabled forward answers exactly where the full solve does, with
/// the full solve's answer (f64: tip within 1e-7 mm; f32: within 1e-3 mm of f64), finite.
#[test]
fn tabled_forward_agrees_with_the_full_solve_over_the_domain() {
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for ((name, f32f), (_, f)) in fingers::<f32>().into_iter().zip(fingers::<f64>()) {
        let t64 = BranchTable::new(&f, &Options::default()).unwrap();
        let t32 = BranchTable::new(&f32f, &Options::default()).unwrap();
        let top = f.voltage_ceiling() * (1.0 - 1e-3);
        let pmax = 1.1 * f.fmax(&[0.0; 3]).unwrap().tension;
        let (mut both, mut neither) = (0, 0);
        for _ in 0..400 {
            let p = pmax * rnd() * rnd().sqrt();
            let v = [top * rnd(), top * rnd(), top * rnd()];
            let full = f.solve(p, &v, Method::converged());
            match (&full, t64.solve(p, &v)) {
                (Ok(a), Ok(b)) => {
                    both += 1;
                    assert!(tip_err(a, &b) < 1e-7, "{name} P {p} V {v:?}");
                    let v32 = v.map(|x| x as f32);
                    let c = t32.solve(p as f32, &v32).unwrap_or_else(|e| panic!("{name} f32 P {p} V {v:?}: {e:?}"));
                    assert!(tip_err(&c, a) < 1e-3 && c.residual.is_finite(), "{name} f32 P {p} V {v:?}: {}", tip_err(&c, a));
                }
                (Err(_), Err(_)) => neither += 1,
                (a, b) => panic!("{name} P {p} V {v:?}: full {a:?}, tabled {b:?}"),
            }
        }
        assert!(both > 300 && neither > 0, "{name}: {both} answered, {neither} refused");
    }
}

/// `solve_into` writes the whole solution into storage the caller keeps: one `Solution` reused
/// across voltage changes (each with its own compliances), after a solve of a finger with more
/// joints and sub-elements and after a refused solve, holds exactly what a fresh solve returns
/// (every field, the rows past (n, m) zero), never a previous voltage's state; and compliances
/// of other voltages give those voltages' answer, not the table's last one.
#[test]
fn solve_into_reused_storage_is_a_fresh_solve() {
    let f = Finger::new(Params::<f32>::default()).unwrap();
    let table = BranchTable::new(&f, &Options::default()).unwrap();
    // a solution of a finger with five joints first (rows past this finger's three are held)
    let big = Finger::new(Params::<f32> { n: 5, ..Params::default() }).unwrap();
    let big_table = BranchTable::new(&big, &Options::default()).unwrap();
    let mut sol = Solution::empty();
    big_table.solve_into(&big.compliances(&[4000.0; 5]).unwrap(), 2.0, &mut sol).unwrap();
    assert_eq!(sol.n, 5);
    let top = f.voltage_ceiling() * 0.99;
    let cases = [
        (1.0, [0.9 * top, 0.5 * top, 0.0]),
        (7.0, [0.0; 3]),
        (1.0, [top; 3]),
        (15.0, [0.2 * top, 0.6 * top, 0.9 * top]),
        (1e9, [0.0; 3]),
        (0.5, [0.3 * top, 0.3 * top, 0.8 * top]),
    ];
    for (p, v) in cases {
        let c = f.compliances(&v).unwrap();
        let fresh = table.solve(p, &v);
        let into = table.solve_into(&c, p, &mut sol);
        match (fresh, into) {
            (Ok(a), Ok(())) => {
                assert!(a == sol, "P {p} V {v:?}: reused storage differs from a fresh solve");
                assert!(sol.q[3..].iter().flatten().flatten().all(|&x| x == 0.0) && sol.tangent_det[3..] == [1.0; 2]);
                assert!(sol.volts[..3] == v && sol.thickness[..3] == c.thickness[..3]);
            }
            (Err(a), Err(b)) => assert_eq!(a, b, "P {p}"),
            (a, b) => panic!("P {p} V {v:?}: fresh {a:?}, into {b:?}"),
        }
    }
    // a voltage change without new compliances answers for the compliances' voltages
    let (v_old, v_new) = ([0.0f32; 3], [top; 3]);
    let c_old = f.compliances(&v_old).unwrap();
    table.solve_into(&c_old, 1.0, &mut sol).unwrap();
    let want_old = f.solve_with(&c_old, 1.0, [0.0; 2], finger_model::Method::converged()).unwrap();
    let want_new = f.solve(1.0, &v_new, finger_model::Method::converged()).unwrap();
    assert!(tip_err(&sol, &want_old) < 1e-4 && tip_err(&sol, &want_new) > 1e-2 && sol.volts[..3] == v_old);
}
