//! Bench image for `contact`'s cost on the target (docs/performance.md "`contact` on the
//! Cortex-M4F"): instructions of one `inverse::contact_force` in f32 (the two fmax checks, the
//! free posture, the pinned continuation), on the default finger as the board boots (its FE
//! calibration) and the paper preset. The cases are the slowest refusals and answers of
//! `cargo run --release --example contact_grid` in fuzz/ (each finger's grid of 624 requests
//! timed on the host, before and after issue 55's branch and pull checks), a request past fmax
//! and one below P0 (the stop would pull); then the board's finger under gravity (`default-g0`:
//! its slowest answers, past fmax, a pull). Prints `CAL`, then one line per case
//! `C <case> ok <ticks> <iterations> <|F| N>` or `C <case> err <ticks> <code> <message>`, then
//! `END`.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use finger_model::calibration::Calibration;
use finger_model::inverse::contact_force;
use finger_model::{Finger, Params};

use bench::cycles;

fn run(name: &str, f: &Finger<f32>, p0: f32, p: f32, v: [f32; 3]) {
    let (p0, p, v) = core::hint::black_box((p0, p, v));
    let t0 = cycles::now();
    let r = contact_force(f, p0, &[0.0; 3], p, &v);
    let t1 = cycles::now();
    match core::hint::black_box(r) {
        Ok(c) => hprintln!("C {} ok {} {} {}", name, t1 - t0, c.iterations, c.magnitude()),
        Err(e) => hprintln!("C {} err {} {} {}", name, t1 - t0, e.code(), e),
    }
}

#[entry]
fn main() -> ! {
    bench::start!();
    let p = Params::<f32>::default();
    let board = Finger::with_calibration(p, Calibration::for_params(&p)).unwrap();
    let paper = Finger::new(Params::<f32>::paper()).unwrap();
    let (t1, t2) = (9999.0f32, 4999.5f32);
    run("default/1-1.5N-0V", &board, 1.0, 1.5, [0.0; 3]);
    run("default/2.879-5.566N-0,5,10kV", &board, 2.8785713, 5.5656843, [0.0, t2, t1]);
    run("default/4.293-14.098N-0,5,10kV", &board, 4.292857, 14.098452, [0.0, t2, t1]);
    run("default/0.05-6.399N-6.7kV", &board, 0.05, 6.3994436, [6666.0; 3]);
    run("default/1.464-11.694N-0,5,10kV", &board, 1.4642856, 11.694181, [0.0, t2, t1]);
    run("default/2.879-8.304N-3.3kV", &board, 2.8785713, 8.304465, [3333.0; 3]);
    run("default/0.757-12.920N-10,0,5kV", &board, 0.75714284, 12.919881, [t1, 0.0, t2]);
    run("default/1.464-10.233N-10,0,5kV", &board, 1.4642856, 10.232768, [t1, 0.0, t2]);
    run("default/1-30N-0V-past-fmax", &board, 1.0, 30.0, [0.0; 3]);
    run("default/1-0.5N-0V-pulls", &board, 1.0, 0.5, [0.0; 3]);
    run("paper/4.293-93.947N-0V", &paper, 4.292857, 93.94711, [0.0; 3]);
    run("paper/2.171-152.468N-3.3kV", &paper, 2.1714284, 152.46796, [3333.0; 3]);
    run("paper/5-173.704N-0,5,10kV", &paper, 5.0, 173.70447, [0.0, t2, t1]);
    run("paper/3.586-232.743N-6.7kV", &paper, 3.5857143, 232.74316, [6666.0; 3]);
    run("paper/1.464-29.876N-10,0,5kV", &paper, 1.4642856, 29.876339, [t1, 0.0, t2]);
    // the board's finger as it boots, under its weight (grav 9.81, grav_dir 0)
    let pg = p.with_gravity(finger_model::params::G_STANDARD as f32, 0.0);
    let hung = Finger::with_calibration(pg, Calibration::for_params(&pg)).unwrap();
    run("default-g0/1-1.5N-0V", &hung, 1.0, 1.5, [0.0; 3]);
    run("default-g0/0.757-12.920N-10,0,5kV", &hung, 0.75714284, 12.919881, [t1, 0.0, t2]);
    run("default-g0/1.464-11.694N-0,5,10kV", &hung, 1.4642856, 11.694181, [0.0, t2, t1]);
    run("default-g0/1-30N-0V-past-fmax", &hung, 1.0, 30.0, [0.0; 3]);
    run("default-g0/1-0.5N-0V-pulls", &hung, 1.0, 0.5, [0.0; 3]);
    bench::end()
}
