//! The contact requests of docs/performance.md's contact table, timed on the host in f32 (the
//! firmware's scalar): `cargo run --release --example contact_grid`. The default finger as the
//! board boots (its calibration) and the paper preset, P0 0.05-5 N, P from P0 to 1.2 fmax, six
//! voltage sets; prints each finger's slowest answer and slowest refusals.
use finger_model::calibration::Calibration;
use finger_model::inverse::contact_force;
use finger_model::{Finger, Params};
use std::time::Instant;

fn run(name: &str, f: &Finger<f32>) {
    let top = f.voltage_ceiling() * (1.0 - 1e-4);
    let vs = [[0.0; 3], [top / 3.0; 3], [2.0 * top / 3.0; 3], [top; 3], [0.0, top / 2.0, top], [top, 0.0, top / 2.0]];
    let mut rows = Vec::new();
    for v in vs {
        let fmax = f.fmax(&v).map(|l| l.tension).unwrap_or(f32::NAN);
        for i in 0..8 {
            let p0 = 0.05 + (5.0 - 0.05) * i as f32 / 7.0;
            for j in 0..=12 {
                let p = p0 + (fmax * 1.2 - p0) * j as f32 / 12.0;
                let t0 = Instant::now();
                let r = contact_force(f, p0, &[0.0; 3], p, &v);
                let us = t0.elapsed().as_secs_f64() * 1e6;
                rows.push((us, p0, p, v, r.map(|c| c.iterations).map_err(|e| e.to_string())));
            }
        }
    }
    rows.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
    let refused = rows.iter().filter(|r| r.4.is_err()).count();
    println!("{name}: {} requests, {refused} refused", rows.len());
    for r in rows.iter().filter(|r| r.4.is_ok()).take(2).chain(rows.iter().filter(|r| r.4.is_err()).take(4)) {
        println!("  {:8.0} us  P0 {} P {} V {:?}: {:?}", r.0, r.1, r.2, r.3, r.4);
    }
}

fn main() {
    let p = Params::<f32>::default();
    run("default (calibrated)", &Finger::with_calibration(p, Calibration::for_params(&p)).unwrap());
    run("paper", &Finger::new(Params::<f32>::paper()).unwrap());
}
