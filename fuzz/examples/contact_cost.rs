//! Times every contact request of a corpus (default fuzz/corpus/model_contact and
//! fuzz/regressions/model_contact): `cargo run --release --example contact_cost [DIR...]`.
//! Prints the refusals' and answers' counts and times, the slowest requests and their outcome.
use finger_model::inverse::contact_force;
use std::time::Instant;

fn main() {
    let mut dirs: Vec<String> = std::env::args().skip(1).collect();
    if dirs.is_empty() {
        dirs = vec!["corpus/model_contact".into(), "regressions/model_contact".into()];
    }
    let mut rows = Vec::new();
    for d in &dirs {
        let Ok(rd) = std::fs::read_dir(d) else { continue };
        for e in rd.flatten() {
            let data = std::fs::read(e.path()).unwrap();
            let Some((f, p0, p, v)) = finger_fuzz::model_contact::request(&data) else { continue };
            let n = f.params().n;
            let t0 = Instant::now();
            let r = contact_force(&f, p0, &vec![0.0; n], p, &v);
            let us = t0.elapsed().as_secs_f64() * 1e6;
            let what = match &r {
                Ok(c) => format!("ok {} iters |F| {:.4e}", c.iterations, c.magnitude()),
                Err(e) => format!("err {e}"),
            };
            let what = format!("{what} (P0 {p0:e} N, P {p:e} N, V {v:?})");
            rows.push((us, e.path().display().to_string(), what, r.is_err()));
        }
    }
    rows.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
    let (mut t_ref, mut n_ref, mut t_ok, mut n_ok) = (0.0, 0, 0.0, 0);
    for r in &rows {
        if r.3 {
            t_ref += r.0;
            n_ref += 1;
        } else {
            t_ok += r.0;
            n_ok += 1;
        }
    }
    println!("{} requests: {n_ok} answered, {:.0} us total; {n_ref} refused, {:.0} us total", rows.len(), t_ok, t_ref);
    for r in rows.iter().take(25) {
        println!("{:10.0} us  {}  {}", r.0, r.2, r.1);
    }
}
