//! Host nanoseconds per solve, with criterion: `solve_with` (compliances precomputed, as on the
//! target) for every bench scene (finger-scenes, host-tests/scenes) and method, in f64 and f32.
//! `cargo bench --bench host_solve`; perf-report runs it and reads criterion's estimates
//! (median) for docs/performance.md. `cargo test --bench host_solve` runs each once.
use criterion::{criterion_group, criterion_main, Criterion};
use finger_model::{Finger, Method, Real};
use host_tests::perf::{self, scenes::SCENES};
use std::hint::black_box;
use std::time::Duration;

fn method_of<S: Real>(name: &str) -> Method<S> {
    match name.strip_prefix("step") {
        Some(n) => Method::Stepping { n_inc: n.parse().expect("step<n>") },
        None => match Method::<f64>::converged() {
            Method::Converged { tol, max_iter } => Method::Converged { tol: S::from_f64(tol), max_iter },
            Method::Stepping { n_inc } => Method::Stepping { n_inc },
        },
    }
}

fn solves<S: Real>(c: &mut Criterion, scalar: &str) {
    let mut g = c.benchmark_group(perf::bench_group(scalar));
    // short runs: 216 variants; a solve takes microseconds, so 30 samples in 0.3 s are plenty
    g.warm_up_time(Duration::from_millis(100)).measurement_time(Duration::from_millis(300)).sample_size(30);
    for s in SCENES {
        let Ok(f) = Finger::new(perf::scene_params(s).cast::<S>()) else { continue };
        let v = s.volts.map(S::from_f64);
        let Ok(comp) = f.compliances(&v) else { continue };
        let p = S::from_f64(s.tension);
        for m in perf::host_methods() {
            let method = method_of::<S>(&m);
            g.bench_function(perf::bench_id(s.name, &m), |b| b.iter(|| f.solve_with(black_box(&comp), black_box(p), [S::zero(); 2], method)));
        }
    }
    g.finish();
}

fn all(c: &mut Criterion) {
    solves::<f64>(c, "f64");
    solves::<f32>(c, "f32");
}

criterion_group!(benches, all);
criterion_main!(benches);
