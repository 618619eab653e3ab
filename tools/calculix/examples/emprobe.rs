use finger_calculix::em::{hinge_em, FixedPoint};
use finger_calculix::mesh::Density;
use finger_model::{de, Params};
fn main() {
    let a: Vec<usize> = std::env::args().skip(1).map(|x| x.parse().unwrap()).collect();
    let mut p = Params::<f64>::vhb4905();
    if let Ok(sets) = std::env::var("SETS") {
        for kv in sets.split(',') {
            let (k, v) = kv.split_once('=').unwrap();
            p.set(k, v.parse().unwrap()).unwrap();
        }
    }
    let v = de::voltage_ceiling(&p) * std::env::var("VF").map(|s| s.parse::<f64>().unwrap()).unwrap_or(1.0);
    let d = Density { notch_cols: a[0], link_cols: a[4], rows: a[1], stack_rows: a[2], layers: a[3] };
    let fp = FixedPoint { rtol: std::env::var("RTOL").map(|s| s.parse::<f64>().unwrap()).unwrap_or(1e-7), max_iter: 40 };
    let mut k = Vec::new();
    for volts in if std::env::var_os("ONLYV").is_some() { vec![v] } else { vec![0.0, v] } {
        let t = std::time::Instant::now();
        let r = hinge_em(&p, volts, 10f64.to_radians(), 0.5f64.to_radians(), &d, fp).unwrap();
        println!(
            "V {volts:.1}: rot {:.4} deg, s_mid centre {:.4} edge {:.4}, k {:.6} M {:.5} turned {:.4} iters {} {:?}",
            r.rotation.to_degrees(),
            r.s_mid_centre,
            r.s_mid_edge,
            r.k,
            r.moment,
            r.turned.to_degrees(),
            r.iterations,
            t.elapsed()
        );
        k.push(r.k);
    }
    if k.len() > 1 {
        println!("ratio {:.6}", k[0] / k[1]);
    }
}
