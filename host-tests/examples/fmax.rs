//! fmax (`Finger::fmax`) for a few hinge models and span floors, with its host run time.
//! `cd host-tests && cargo run --release --example fmax`
use finger_model::*;
fn main() {
    for (m, plate, layers, floor) in [
        (1usize, false, 0u32, 0.1),
        (8, true, 0, 0.1),
        (8, false, 0, 0.1),
        (4, true, 4, 0.1),
        (1, false, 4, 0.1),
        (8, true, 4, 1e-6),
        (1, false, 4, 1e-6),
        (8, true, 4, 2.0),
    ] {
        let p = Params::<f64> { m, plate, layers, span_floor: floor, ..Params::default() };
        let f = Finger::new(p).unwrap();
        let t = std::time::Instant::now();
        let r = f.fmax(&[0.0; 3]);
        let dt = t.elapsed();
        let check = r.map(|b| f.solve(b.tension, &[0.0; 3], Method::converged()).map(|s| s.span[0]));
        println!("m={m} plate={plate} layers={layers} span_floor={floor}: {r:?} in {dt:?}; forward at fmax: {check:?}");
    }
}
