//! One model_contact input's contact at tensions and voltages along its continuation, each
//! solved afresh from the free posture (λ from A to B, default 0 to 1, in 64 steps): every
//! hinge's turn and the force, to tell a continuous path from a jump (docs/reliability.md, the
//! S-shaped find): `A=0.33 B=0.37 cargo run --release --example contact_sweep <input>` in fuzz/.
use finger_model::inverse::contact_force;
use finger_model::Method;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let data = std::fs::read(path).unwrap();
    let (f, p0, p, v) = finger_fuzz::model_contact::request(&data).unwrap();
    let n = f.params().n;
    println!("n {n} p0 {p0} p {p} v {v:?} params {:?}", f.params());
    let free0 = f.solve(p0, &vec![0.0; n], Method::converged()).unwrap();
    let hinge = |s: &finger_model::Solution<f64>, k: usize| s.q[k][..s.m].iter().map(|q| q[2]).sum::<f64>().to_degrees();
    println!("free0 hinges {:?}", (0..n).map(|k| hinge(&free0, k)).collect::<Vec<_>>());
    let (a, b, k): (f64, f64, usize) =
        (std::env::var("A").map(|s| s.parse().unwrap()).unwrap_or(0.0), std::env::var("B").map(|s| s.parse().unwrap()).unwrap_or(1.0), 64);
    for i in 0..=k {
        let lam = a + (b - a) * i as f64 / k as f64;
        let pl = p0 + lam * (p - p0);
        let vl: Vec<f64> = v.iter().map(|x| lam * x).collect();
        let free = f
            .solve(pl, &vl, Method::converged())
            .map(|s| (0..n).map(|k| format!("{:.1}", hinge(&s, k))).collect::<Vec<_>>().join(","))
            .unwrap_or_else(|e| format!("{e:?}"));
        match contact_force(&f, p0, &vec![0.0; n], pl, &vl) {
            Ok(c) => println!(
                "lam {lam:.4} P {pl:.4} F {:?} hinges {:?} free {free}",
                c.force.map(|x| (x * 1e4).round() / 1e4),
                (0..n).map(|k| (hinge(&c.solution, k) * 10.0).round() / 10.0).collect::<Vec<_>>()
            ),
            Err(e) => println!("lam {lam:.4} P {pl:.4} err {e:?} free {free}"),
        }
    }
}
