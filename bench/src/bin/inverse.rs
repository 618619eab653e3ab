//! Bench image for the inverse model's cost on the target (docs/inverse-cost.md):
//! instructions of one `inverse::solve_pose` (joint angles, optionally a tension, to the
//! tension and the three voltages), f32, for the paper's model (m = 1, rigid links, E_b) and
//! the default model (m = 8, plate modulus, flexible links). Prints `CAL`, then one line per
//! case `I <case> ok <ticks> <tension N> <v1> <v2> <v3>` (or `I <case> err <ticks> <code>`),
//! then `END`. Every parameter that matters is set explicitly. Driven by
//! `cargo run --release --example inverse_cost` in host-tests.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use finger_model::inverse::{solve_pose, solve_pose_tabled, BranchTable, Options};
use finger_model::{Finger, Params};

use bench::cycles;

const DEG: f32 = core::f32::consts::PI / 180.0;

/// The branch table of `f` when the image is built with the `table` feature (its build is
/// not part of a solve's count; `T` lines report it once per model).
fn table(f: &Finger<f32>) -> Option<BranchTable<f32>> {
    if cfg!(feature = "table") {
        BranchTable::new(f, &Options::default()).ok()
    } else {
        None
    }
}

fn run(name: &str, p: Params<f32>, deg: [f32; 3], tension: Option<f32>) {
    let f = match Finger::new(p) {
        Ok(f) => f,
        Err(e) => {
            hprintln!("I {} err 0 {}", name, e.code());
            return;
        }
    };
    let tb = table(&f);
    let angles = core::hint::black_box([deg[0] * DEG, deg[1] * DEG, deg[2] * DEG]);
    let t0 = cycles::now();
    let tension = core::hint::black_box(tension);
    let r = tb.as_ref().map_or_else(|| solve_pose(&f, &angles, tension), |t| solve_pose_tabled(t, &angles, tension));
    let t1 = cycles::now();
    match core::hint::black_box(r) {
        Ok(s) => hprintln!("I {} ok {} {} {} {} {}", name, t1 - t0, s.tension, s.volts[0], s.volts[1], s.volts[2]),
        Err(e) => hprintln!("I {} err {} {}", name, t1 - t0, e.code()),
    }
}

/// Profiling markers (`--features profile`): the execution trace between the two calls is one
/// solve (`cargo run --release --example inverse_profile` in host-tests).
#[inline(never)]
#[no_mangle]
pub extern "C" fn profile_start() {
    core::hint::black_box(());
}
#[inline(never)]
#[no_mangle]
pub extern "C" fn profile_stop() {
    core::hint::black_box(());
}

#[cfg(feature = "profile")]
#[entry]
fn main() -> ! {
    let p = Params::<f32> { m: 8, plate: true, flex_links: true, ..Params::default() };
    let f = Finger::new(p).unwrap();
    let tb = table(&f);
    let deg = core::hint::black_box([10.03f32, 10.0, 9.97]);
    let angles = [deg[0] * DEG, deg[1] * DEG, deg[2] * DEG];
    profile_start();
    let r = tb.as_ref().map_or_else(|| solve_pose(&f, &angles, None), |t| solve_pose_tabled(t, &angles, None));
    profile_stop();
    match core::hint::black_box(r) {
        Ok(s) => hprintln!("P ok {} {} {} {}", s.tension, s.volts[0], s.volts[1], s.volts[2]),
        Err(e) => hprintln!("P err {}", e.code()),
    }
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_SUCCESS);
    loop {}
}

#[cfg(not(feature = "profile"))]
#[entry]
fn main() -> ! {
    bench::start!();
    let paper = Params::<f32> { m: 1, plate: false, flex_links: false, ..Params::default() };
    let real = Params::<f32> { m: 8, plate: true, flex_links: true, ..Params::default() };
    for (cfg, p) in [("m1-rigid", paper), ("m8-plate-flex", real)] {
        // the branch table's build, once per model
        if cfg!(feature = "table") {
            if let Ok(f) = Finger::new(p) {
                let t0 = cycles::now();
                let r = BranchTable::new(&f, &Options::default());
                let t1 = cycles::now();
                if let Ok(tb) = core::hint::black_box(r) {
                    let len = tb.len();
                    hprintln!("T {} {} {} {} {}", cfg, t1 - t0, len[0], len[1], len[2]);
                }
            }
        }
        for (case, deg) in [("10-10-10", [10.0, 10.0, 10.0]), ("10.03-10-9.97", [10.03, 10.0, 9.97]), ("10.05-10-9.95", [10.05, 10.0, 9.95])] {
            let mut name: heapless_name::Name = heapless_name::Name::new();
            name.push(cfg);
            name.push("/");
            name.push(case);
            run(name.as_str(), p, deg, None);
        }
    }
    // a given tension inside the interval of the uniform posture
    run("m1-rigid/10-10-10@1.548N", paper, [10.0; 3], Some(1.548));
    run("m8-plate-flex/10-10-10@1.90N", real, [10.0; 3], Some(1.90));
    bench::end()
}

/// A tiny fixed-capacity string for case names (no allocation, no extra crate).
mod heapless_name {
    pub struct Name {
        buf: [u8; 48],
        len: usize,
    }
    impl Name {
        pub fn new() -> Self {
            Name { buf: [0; 48], len: 0 }
        }
        pub fn push(&mut self, s: &str) {
            for &b in s.as_bytes() {
                if self.len < self.buf.len() {
                    self.buf[self.len] = b;
                    self.len += 1;
                }
            }
        }
        pub fn as_str(&self) -> &str {
            core::str::from_utf8(&self.buf[..self.len]).unwrap_or("?")
        }
    }
}
