//! Bench image for the fidelity table (docs/fidelity.md): the instructions of one
//! forward solve for every sub-element count m = 1, 2, 4, 8 of the hinge, in the paper's
//! configuration (rigid links, E_b) and the real-structure one (plate modulus, flexible links).
//! f32 on the M4F. Prints the same `CAL` / `R` / `END` lines as `finger-bench` (so
//! `host_tests::perf::parse` reads them); the scene field names the configuration and the case:
//! `m<m>-p<plate>-f<flex>/<case>`; the board's default, m = 8 with plate modulus, flexible links
//! and the default finger's FE calibration (`Calibration::model_md`, docs/model.md "FE calibration"), is `m8-p1-f1-cal/<case>`.
//!
//! Every model parameter is set explicitly (m, plate, flex_links, layers), so the counts do not
//! move when `Params::default()` changes. Driven by `cargo run --release --example fidelity`
//! in host-tests.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use finger_model::{Calibration, Finger, Method, Params};

use bench::cycles;

/// A forward solve: layers per stack, channel voltages (V), cable tension (N).
pub struct Case {
    pub name: &'static str,
    pub layers: u32,
    pub volts: [f32; 3],
    pub tension: f32,
}

/// The cases (the fidelity scenes at 1 and 2 N): no stacks, stacks at 0 V, per-joint voltages
/// (three distinct joints: the decoupled solver cannot reuse a joint's solution).
pub const CASES: &[Case] = &[
    Case { name: "no-stacks-1N", layers: 0, volts: [0.0; 3], tension: 1.0 },
    Case { name: "no-stacks-2N", layers: 0, volts: [0.0; 3], tension: 2.0 },
    Case { name: "stacks-0V-2N", layers: 4, volts: [0.0; 3], tension: 2.0 },
    Case { name: "per-joint-2N", layers: 4, volts: [9000.0, 5000.0, 0.0], tension: 2.0 },
];

/// Sub-elements per hinge.
pub const MS: &[usize] = &[1, 2, 4, 8];
/// (plate, flex_links).
pub const CONFIGS: &[(bool, bool)] = &[(false, false), (true, true)];

fn run(m: usize, plate: bool, flex: bool, cal: bool, case: &Case) {
    let p = Params::<f32> { m, plate, flex_links: flex, layers: case.layers, ..Params::default() };
    let (pi, fi) = (plate as u32, flex as u32);
    let (c, tag) = if cal { (Calibration::model_md(), "-cal") } else { (Calibration::none(), "") };
    let f = match Finger::with_calibration(p, c) {
        Ok(f) => f,
        Err(e) => {
            hprintln!("R m{}-p{}-f{}{}/{} f32 conv err 0 0 {}", m, pi, fi, tag, case.name, e.code());
            return;
        }
    };
    let t0 = cycles::now();
    let c = f.compliances(&case.volts);
    let t1 = cycles::now();
    let c = match core::hint::black_box(c) {
        Ok(c) => c,
        Err(e) => {
            hprintln!("R m{}-p{}-f{}{}/{} f32 conv err 0 {} {}", m, pi, fi, tag, case.name, t1 - t0, e.code());
            return;
        }
    };
    let tension = core::hint::black_box(case.tension);
    let t2 = cycles::now();
    let r = f.solve_with(&c, tension, [0.0; 2], Method::converged());
    let t3 = cycles::now();
    match core::hint::black_box(r) {
        Ok(s) => {
            let tip = s.tip();
            let a = s.joint_angles();
            hprintln!(
                "R m{}-p{}-f{}{}/{} f32 conv ok {} {} {:e} {:e} {:e} {:e} {:e} {}",
                m,
                pi,
                fi,
                tag,
                case.name,
                t3 - t2,
                t1 - t0,
                tip.x,
                tip.y,
                a[0],
                a[1],
                a[2],
                s.iterations
            );
        }
        Err(e) => hprintln!("R m{}-p{}-f{}{}/{} f32 conv err {} {} {}", m, pi, fi, tag, case.name, t3 - t2, t1 - t0, e.code()),
    }
}

#[entry]
fn main() -> ! {
    bench::start!();
    for &(plate, flex) in CONFIGS {
        for &m in MS {
            for case in CASES {
                run(m, plate, flex, false, case);
            }
        }
    }
    for case in CASES {
        run(8, true, true, true, case);
    }
    bench::end()
}
