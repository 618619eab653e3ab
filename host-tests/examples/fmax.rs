use finger_model::*;
fn main() {
    for (m, plate, layers) in [(1usize, false, 0u32), (8, true, 0), (8, false, 0), (4, true, 4), (1, false, 4)] {
        let p = Params::<f64> { m, plate, layers, ..Params::default() };
        let f = Finger::new(p).unwrap();
        let t = std::time::Instant::now();
        let r = f.fmax(&[0.0; 3]);
        println!("m={m} plate={plate} layers={layers}: {:?} in {:?}", r, t.elapsed());
    }
}
