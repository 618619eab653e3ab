use finger_model::{Params, Finger, Method};
fn main() {
    for layers in [0u32, 4] {
        let p = Params::<f64> { n: 1, layers, ..Params::default() };
        let f = Finger::new(p).unwrap();
        let c = f.compliances(&[0.0]).unwrap();
        let s = f.solve(0.0, &[0.0], Method::converged()).unwrap();
        let ct = f.tip_compliance(&c, &s);
        println!("layers {layers}: {:?}", ct);
        let p = Params::<f64> { n: 1, layers, plate: false, ..Params::default() };
        let f = Finger::new(p).unwrap();
        let c = f.compliances(&[0.0]).unwrap();
        let s = f.solve(0.0, &[0.0], Method::converged()).unwrap();
        println!("  E_b: {:?}", f.tip_compliance(&c, &s));
    }
}
