//! The contact bench image's cases (bench/src/bin/contact.rs) on the host, f32 and f64, with
//! and without the board's gravity: outcome and host µs each (`cargo run --release --example
//! contact_bench_host` in fuzz/).
use finger_model::calibration::Calibration;
use finger_model::inverse::contact_force;
use finger_model::real::Real;
use finger_model::{Finger, Params};
use std::time::Instant;

fn run<R: Real>(name: &str, f: &Finger<R>, p0: f64, p: f64, v: [f64; 3]) {
    let z = [R::zero(); 3];
    let v = v.map(R::from_f64);
    let mut us = f64::INFINITY;
    let mut out = String::new();
    for _ in 0..3 {
        let t0 = Instant::now();
        let r = contact_force(f, R::from_f64(p0), &z, R::from_f64(p), &v);
        us = us.min(t0.elapsed().as_secs_f64() * 1e6);
        out = match r {
            Ok(c) => format!("ok {} iters |F| {:.4}", c.iterations, c.magnitude().to_f64()),
            Err(e) => format!("err {e}"),
        };
    }
    let t0 = Instant::now();
    let e = f.fmax(&v);
    let us_fmax = t0.elapsed().as_secs_f64() * 1e6;
    let t0 = Instant::now();
    let _ = f.solve(R::from_f64(p0), &z, finger_model::Method::converged());
    let us_free = t0.elapsed().as_secs_f64() * 1e6;
    println!("{name:40} {us:9.0} us  (fmax {us_fmax:.0} us, free {us_free:.0} us, fmax {:?})  {out}", e.map(|e| e.tension.to_f64()).ok());
}

fn cases<R: Real>(tag: &str, grav: f64) {
    let p = Params::<R>::default().with_gravity(R::from_f64(grav), R::zero());
    let board = Finger::with_calibration(p, Calibration::for_params(&p)).unwrap();
    let paper = Finger::new(Params::<R>::paper().with_gravity(R::from_f64(grav), R::zero())).unwrap();
    let (t1, t2) = (9999.0, 4999.5);
    let d = |s: &str| format!("{tag} default/{s}");
    let q = |s: &str| format!("{tag} paper/{s}");
    run(&d("1-1.5N-0V"), &board, 1.0, 1.5, [0.0; 3]);
    run(&d("2.879-5.566N-0,5,10kV"), &board, 2.8785713, 5.5656843, [0.0, t2, t1]);
    run(&d("4.293-14.098N-0,5,10kV"), &board, 4.292857, 14.098452, [0.0, t2, t1]);
    run(&d("0.05-6.399N-6.7kV"), &board, 0.05, 6.3994436, [6666.0; 3]);
    run(&d("1.464-11.694N-0,5,10kV"), &board, 1.4642856, 11.694181, [0.0, t2, t1]);
    run(&d("2.879-8.304N-3.3kV"), &board, 2.8785713, 8.304465, [3333.0; 3]);
    run(&d("0.757-12.920N-10,0,5kV"), &board, 0.75714284, 12.919881, [t1, 0.0, t2]);
    run(&d("1.464-10.233N-10,0,5kV"), &board, 1.4642856, 10.232768, [t1, 0.0, t2]);
    run(&d("1-30N-0V-past-fmax"), &board, 1.0, 30.0, [0.0; 3]);
    run(&d("1-0.5N-0V-pulls"), &board, 1.0, 0.5, [0.0; 3]);
    run(&q("4.293-93.947N-0V"), &paper, 4.292857, 93.94711, [0.0; 3]);
    run(&q("2.171-152.468N-3.3kV"), &paper, 2.1714284, 152.46796, [3333.0; 3]);
    run(&q("5-173.704N-0,5,10kV"), &paper, 5.0, 173.70447, [0.0, t2, t1]);
    run(&q("3.586-232.743N-6.7kV"), &paper, 3.5857143, 232.74316, [6666.0; 3]);
    run(&q("1.464-29.876N-10,0,5kV"), &paper, 1.4642856, 29.876339, [t1, 0.0, t2]);
}

fn main() {
    let which: Vec<String> = std::env::args().skip(1).collect();
    let want = |s: &str| which.is_empty() || which.iter().any(|w| w == s);
    if want("f32") {
        cases::<f32>("f32", 0.0);
    }
    if want("f32g") {
        cases::<f32>("f32 g", finger_model::params::G_STANDARD);
    }
    if want("f64") {
        cases::<f64>("f64", 0.0);
    }
    if want("f64g") {
        cases::<f64>("f64 g", finger_model::params::G_STANDARD);
    }
}
