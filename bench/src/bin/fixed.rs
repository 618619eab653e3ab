//! Bench image for docs/fixed-point.md: every scene of finger-scenes (host-tests/scenes), for the scene's
//! pinned model and for the default model (`Params::default()`, the firmware's), solved by
//! the model's f32 forward solve and by its fixed-point one (`finger_model::fixed`), with the
//! instruction count of each solve (and of each set-up: the compliances at the scene's
//! voltages). Build for thumbv7m-none-eabi (soft float) and run in QEMU mps2-an385; driven by
//! `cd host-tests && cargo run --release --example fixed_report`. Prints the `CAL` line of
//! `finger-bench`, then one line per solve:
//!
//! `F <scene> <model> <scalar> ok <solve_ticks> <setup_ticks> <tip_x> <tip_y> <a1> <a2> <a3> <excursion> <iters>`
//! `F <scene> <model> <scalar> err <solve_ticks> <setup_ticks> <error code>`
//!
//! Then the inverse at a given tension (default model with stacks) for the postures of
//! [`POSES`]: the fixed-point one (`FixedInverse`, set-up once) and the f32 one
//! (`finger_model::solve_pose`), one line each:
//! `I <case> <scalar> ok <solve_ticks> <setup_ticks> <V1> <V2> <V3>` or `... err <ticks> 0 <code>`
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use finger_model::fixed::q::{Nt, Rad};
use finger_model::fixed::{FixedFinger, FixedInverse, FixedInverseDirect};
use finger_model::{Finger, Method, Params};

use bench::cycles;
use finger_scenes as scenes;

fn run(s: &scenes::Scene, model: &str, p: Params<f64>) {
    let f = match Finger::new(p.cast::<f32>()) {
        Ok(f) => f,
        Err(e) => {
            hprintln!("F {} {} all err 0 0 {}", s.name, model, e.code());
            return;
        }
    };
    let v = [s.volts[0] as f32, s.volts[1] as f32, s.volts[2] as f32];
    let tension = s.tension as f32;
    // f32 (soft float on the M3)
    let t0 = cycles::now();
    let comp = f.compliances(&v);
    let t1 = cycles::now();
    let setup = t1 - t0;
    match comp {
        Ok(comp) => {
            let t0 = cycles::now();
            let r = f.solve_with(&comp, tension, [0.0; 2], Method::converged());
            core::hint::black_box(&r);
            let t1 = cycles::now();
            match r {
                Ok(sol) => {
                    let (tip, a) = (sol.tip(), sol.joint_angles());
                    hprintln!(
                        "F {} {} f32 ok {} {} {:e} {:e} {:e} {:e} {:e} {:e} {}",
                        s.name,
                        model,
                        t1 - t0,
                        setup,
                        tip.x,
                        tip.y,
                        a[0],
                        a[1],
                        a[2],
                        sol.cable_excursion,
                        sol.iterations
                    );
                }
                Err(e) => hprintln!("F {} {} f32 err {} {} {}", s.name, model, t1 - t0, setup, e.code()),
            }
        }
        Err(e) => hprintln!("F {} {} f32 err 0 {} {}", s.name, model, setup, e.code()),
    }
    // fixed point (its set-up: the same compliances in f32, then scaled to Q formats)
    let t0 = cycles::now();
    let ff = FixedFinger::new(&f, &v);
    let t1 = cycles::now();
    let setup = t1 - t0;
    let ff = match ff {
        Ok(ff) => ff,
        Err(e) => {
            hprintln!("F {} {} fixed err 0 {} {}", s.name, model, setup, e.code());
            return;
        }
    };
    let p = Nt::from_f32(tension);
    let t0 = cycles::now();
    let r = ff.solve(p);
    core::hint::black_box(&r);
    let t1 = cycles::now();
    match r {
        Ok(sol) => {
            let tip = sol.tip();
            let a = sol.joint_angle;
            hprintln!(
                "F {} {} fixed ok {} {} {:e} {:e} {:e} {:e} {:e} {:e} {}",
                s.name,
                model,
                t1 - t0,
                setup,
                tip.x.to_f32(),
                tip.y.to_f32(),
                a[0].to_f32(),
                a[1].to_f32(),
                a[2].to_f32(),
                sol.cable_excursion.to_f32(),
                sol.iterations
            );
        }
        Err(e) => hprintln!("F {} {} fixed err {} {} {}", s.name, model, t1 - t0, setup, e.code()),
    }
}

/// Postures for the inverse: the forward solve's joint angles at (tension N, voltages V).
const POSES: &[(f32, [f32; 3])] =
    &[(0.5, [0.0, 2000.0, 4000.0]), (0.8, [1000.0, 3000.0, 5000.0]), (1.0, [9000.0, 5000.0, 100.0]), (1.5, [2000.0; 3]), (0.3, [8000.0; 3])];

fn run_inverse() {
    let f = match Finger::new(Params::<f32> { layers: 4, ..Params::default() }) {
        Ok(f) => f,
        Err(_) => return,
    };
    let t0 = cycles::now();
    let inv = FixedInverse::new(&f);
    let setup = cycles::now() - t0;
    // the top voltage of the firmware's `pose` (the F405's inverse: `Options::top` of the ceiling)
    let top = finger_model::inverse::Options::<f32>::default().top;
    for (i, (p, v)) in POSES.iter().enumerate() {
        let Ok(want) = f.solve(*p, v, Method::converged()) else { continue };
        let a = want.joint_angles();
        if let Ok(inv) = &inv {
            let angles = [Rad::from_f32(a[0]), Rad::from_f32(a[1]), Rad::from_f32(a[2])];
            let t0 = cycles::now();
            let r = inv.solve(&angles, Nt::from_f32(*p));
            core::hint::black_box(&r);
            let t1 = cycles::now();
            match r.and_then(|sol| inv.volts(&f, &sol)) {
                Ok(vs) => hprintln!("I pose{} fixed ok {} {} {:e} {:e} {:e}", i, t1 - t0, setup, vs[0], vs[1], vs[2]),
                Err(e) => hprintln!("I pose{} fixed err {} 0 {}", i, t1 - t0, e.code()),
            }
        }
        // the firmware's (M3 image) `pose`: no table, its set-up included (a FixedFinger)
        let t0 = cycles::now();
        let mut ff = FixedFinger::empty();
        let r = ff.prepare(&f, &[0.0; 3]).and_then(|_| {
            let d = FixedInverseDirect::new(&f, &ff, f.ceiling_in_force(None) * top)?;
            let angles = [Rad::from_f32(a[0]), Rad::from_f32(a[1]), Rad::from_f32(a[2])];
            d.solve(&angles, Nt::from_f32(*p)).and_then(|sol| d.volts(&sol))
        });
        core::hint::black_box(&r);
        let t1 = cycles::now();
        match r {
            Ok(vs) => hprintln!("I pose{} direct ok {} 0 {:e} {:e} {:e}", i, t1 - t0, vs[0], vs[1], vs[2]),
            Err(e) => hprintln!("I pose{} direct err {} 0 {}", i, t1 - t0, e.code()),
        }
        // the firmware's `pose` without P: the tension rule, then the same solve
        let t0 = cycles::now();
        let mut ff = FixedFinger::empty();
        let mut used = Nt::ZERO;
        let r = ff.prepare(&f, &[0.0; 3]).and_then(|_| {
            let d = FixedInverseDirect::new(&f, &ff, f.ceiling_in_force(None) * top)?;
            let angles = [Rad::from_f32(a[0]), Rad::from_f32(a[1]), Rad::from_f32(a[2])];
            d.solve_free(&angles, &mut used).and_then(|(sol, _)| d.volts(&sol))
        });
        core::hint::black_box(&r);
        let t1 = cycles::now();
        match r {
            Ok(vs) => hprintln!("I pose{} free ok {} 0 {:e} {:e} {:e} {:e}", i, t1 - t0, vs[0], vs[1], vs[2], used.to_f32()),
            Err(e) => hprintln!("I pose{} free err {} 0 {}", i, t1 - t0, e.code()),
        }
        let t0 = cycles::now();
        let r = finger_model::solve_pose(&f, a, Some(*p));
        core::hint::black_box(&r);
        let t1 = cycles::now();
        match r {
            Ok(sol) => hprintln!("I pose{} f32 ok {} 0 {:e} {:e} {:e}", i, t1 - t0, sol.volts[0], sol.volts[1], sol.volts[2]),
            Err(e) => hprintln!("I pose{} f32 err {} 0 {}", i, t1 - t0, e.code()),
        }
    }
}

#[entry]
fn main() -> ! {
    bench::start!();
    for s in scenes::SCENES.iter() {
        run(s, "pinned", scenes::params(s));
        run(s, "default", Params { layers: s.layers, ..Params::default() });
    }
    run_inverse();
    bench::end()
}
