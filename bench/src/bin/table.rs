//! Bench image for the branch-table path on the target (docs/performance.md): per model of
//! `scenes::TABLE_MODELS`, the cost of building `inverse::BranchTable` (once per parameter
//! set), then per scene of `scenes::TABLE_SCENES` the forward solve (full: `Finger::solve_with`;
//! table: `BranchTable::solve_into` into a solution the caller holds, both after the same `compliances`), the inverse from the
//! table (`solve_pose_tabled_into`, the table forward's angles, with the scene's tension and without
//! one) and fmax (full and from the table). f32. Prints `CAL`, then
//! `B <model> <ticks> <samples>`,
//! `S <model> <scene> <full|table> ok <ticks> <setup_ticks> <tip_x> <tip_y> <a1> <a2> <a3> <iters>`,
//! `I <model> <scene> <given|free> ok <ticks> <P> <v1> <v2> <v3> <a1> <a2> <a3>` (the targets),
//! `F <model> <scene> <full|table> ok <ticks> <fmax N> <joint>` (or `... err <ticks> <code>`),
//! then `END`. Driven by `host_tests::perf::table_cost` (perf-report, docs/performance.md).
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use finger_model::inverse::{solve_pose_tabled_into, BranchTable, Options, PoseSolution};
use finger_model::{Calibration, Finger, Method, Solution};

use bench::cycles;
use finger_scenes as scenes;

fn model(m: &scenes::TableModel) -> Result<Finger<f32>, finger_model::Error> {
    let (p, g) = scenes::table_params(m);
    let g = g.map(|x| x as f32);
    let cal = Calibration { hinge: [g[0], g[1], g[2], g[3]], stack_axial: [g[4], g[5]], stack_bending: [g[6], g[7]] };
    Finger::with_calibration(p.cast::<f32>(), cal)
}

fn run_model(m: &scenes::TableModel) {
    let f = match model(m) {
        Ok(f) => f,
        Err(e) => {
            hprintln!("B {} err 0 {}", m.name, e.code());
            return;
        }
    };
    let opts = Options::default();
    let t0 = cycles::now();
    let tb = BranchTable::new(core::hint::black_box(&f), &opts);
    let t1 = cycles::now();
    let tb = match core::hint::black_box(tb) {
        Ok(t) => t,
        Err(e) => {
            hprintln!("B {} err {} {}", m.name, t1 - t0, e.code());
            return;
        }
    };
    hprintln!("B {} ok {} {}", m.name, t1 - t0, tb.len()[0]);
    for &(name, tension, volts) in scenes::TABLE_SCENES {
        let v = core::hint::black_box([volts[0] as f32, volts[1] as f32, volts[2] as f32]);
        let p = core::hint::black_box(tension as f32);
        let s0 = cycles::now();
        let c = f.compliances(&v);
        let s1 = cycles::now();
        let Ok(c) = c else {
            hprintln!("S {} {} all err 0 0 compliances", m.name, name);
            continue;
        };
        let mut angles = None;
        for method in ["full", "table"] {
            // the tabled solve writes into the caller's solution (`solve_into`, as a caller
            // that keeps one would); the full solve returns by value
            let mut out = Solution::empty();
            let t0 = cycles::now();
            let r = if method == "full" {
                Some(f.solve_with(&c, p, [0.0; 2], Method::converged()))
            } else {
                core::hint::black_box(tb.solve_into(&c, p, core::hint::black_box(&mut out))).err().map(Err)
            };
            core::hint::black_box(&r);
            let t1 = cycles::now();
            let r = r.unwrap_or(Ok(out));
            match r {
                Ok(sol) => {
                    let a = sol.joint_angles();
                    hprintln!(
                        "S {} {} {} ok {} {} {:e} {:e} {:e} {:e} {:e} {}",
                        m.name,
                        name,
                        method,
                        t1 - t0,
                        s1 - s0,
                        sol.tip().x,
                        sol.tip().y,
                        a[0],
                        a[1],
                        a[2],
                        sol.iterations
                    );
                    angles = Some([a[0], a[1], a[2]]);
                }
                Err(e) => hprintln!("S {} {} {} err {} {} {}", m.name, name, method, t1 - t0, s1 - s0, e.code()),
            }
        }
        if let Some(a) = angles {
            for (case, given) in [("given", Some(p)), ("free", None)] {
                let a = core::hint::black_box(a);
                // written into a solution the caller holds (`solve_pose_tabled_into`), as the
                // forward's `solve_into`
                let mut s = PoseSolution::empty();
                let t0 = cycles::now();
                let r = solve_pose_tabled_into(&tb, &a, core::hint::black_box(given), core::hint::black_box(&mut s));
                let t1 = cycles::now();
                match core::hint::black_box(r).map(|()| s) {
                    Ok(s) => hprintln!(
                        "I {} {} {} ok {} {:e} {:e} {:e} {:e} {:e} {:e} {:e}",
                        m.name,
                        name,
                        case,
                        t1 - t0,
                        s.tension,
                        s.volts[0],
                        s.volts[1],
                        s.volts[2],
                        a[0],
                        a[1],
                        a[2]
                    ),
                    Err(e) => hprintln!("I {} {} {} err {} {}", m.name, name, case, t1 - t0, e.code()),
                }
            }
        }
        for method in ["full", "table"] {
            let t0 = cycles::now();
            let r = if method == "full" { f.fmax(&v) } else { tb.fmax(&v) };
            let t1 = cycles::now();
            match core::hint::black_box(r) {
                Ok(b) => hprintln!("F {} {} {} ok {} {:e} {}", m.name, name, method, t1 - t0, b.tension, b.joint),
                Err(e) => hprintln!("F {} {} {} err {} {}", m.name, name, method, t1 - t0, e.code()),
            }
        }
    }
}

/// Profiling markers (`--features profile`): the execution trace between the two calls is one
/// tabled forward solve of the default model at three different voltages (or, built with
/// PROFILE_SAME set, one voltage; with PROFILE_HARD, the calibrated model's 15 N scene at
/// 2/6/9 kV; with PROFILE_M1 too, the paper's m = 1 finger at those voltages; with
/// PROFILE_INVERSE, the tabled inverse of its angles at 1 N, with PROFILE_FREE too without a
/// tension).
#[inline(never)]
#[no_mangle]
pub extern "C" fn profile_start() {
    core::hint::black_box(1u32);
}
#[inline(never)]
#[no_mangle]
pub extern "C" fn profile_stop() {
    core::hint::black_box(2u64);
}

#[entry]
fn main() -> ! {
    let cp = cortex_m::Peripherals::take().unwrap();
    cycles::start(cp.SYST);
    if cfg!(feature = "profile") {
        // PROFILE_HARD set at build time: the calibrated model's 15 N scene at 2/6/9 kV instead
        let hard = option_env!("PROFILE_HARD").is_some();
        let which = if option_env!("PROFILE_M1").is_some() {
            2
        } else if hard {
            1
        } else {
            0
        };
        let f = model(&scenes::TABLE_MODELS[which]).unwrap();
        let tb = BranchTable::new(&f, &Options::default()).unwrap();
        // PROFILE_SAME=1 at build time: the three joints at the same voltage instead
        let v = if option_env!("PROFILE_SAME").is_some() {
            [5000.0; 3]
        } else if hard {
            [2000.0, 6000.0, 9000.0]
        } else {
            [9000.0, 5000.0, 0.0]
        };
        let p = if hard { 15.0 } else { 1.0 };
        let c = f.compliances(&core::hint::black_box(v)).unwrap();
        let mut out = Solution::empty();
        if option_env!("PROFILE_INVERSE").is_some() {
            // PROFILE_INVERSE set at build time: the tabled inverse of that solve's angles
            tb.solve_into(&c, 1.0, &mut out).unwrap();
            let a = core::hint::black_box([out.joint_angle[0], out.joint_angle[1], out.joint_angle[2]]);
            let mut s = PoseSolution::empty();
            profile_start();
            // PROFILE_FREE set too: without a tension (the midpoint rule)
            let p = if option_env!("PROFILE_FREE").is_some() { None } else { Some(1.0) };
            let r = solve_pose_tabled_into(&tb, &a, core::hint::black_box(p), core::hint::black_box(&mut s));
            profile_stop();
            core::hint::black_box(r).ok();
            core::hint::black_box(&s);
            debug::exit(debug::EXIT_SUCCESS);
        }
        profile_start();
        let r = tb.solve_into(&c, core::hint::black_box(p), core::hint::black_box(&mut out));
        profile_stop();
        core::hint::black_box(r).ok();
        core::hint::black_box(&out);
        debug::exit(debug::EXIT_SUCCESS);
    }
    let (ticks, overhead) = cycles::calibrate(1_000_000);
    hprintln!("CAL {} {} {}", 2_000_000u32, ticks, overhead);
    for m in scenes::TABLE_MODELS {
        run_model(m);
    }
    hprintln!("END");
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::wfi();
    }
}
