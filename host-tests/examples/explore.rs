use finger_model::*;
fn main() {
    for layers in [0u32, 4] {
        let p = Params::<f64>::default();
        let p = Params { layers, ..p };
        let f = Finger::new(p).unwrap();
        println!("layers {layers} Vpi {:.1} ceil {:.1} C_h {:?}", f.pull_in_voltage(), f.voltage_ceiling(), f.hinge_compliance(0));
        for t in [0.2, 0.5, 1.0, 2.0, 4.0, 7.0] {
            let v = [0.0f64; 3];
            match f.solve(t, &v, Method::converged()) {
                Ok(s) => {
                    let st = f.tip_stiffness(&s).unwrap();
                    println!(
                        "P={t} ang={:?} tip={:?} cable={:.4} it={} res={:.2e} det={:.3} k={:.3},{:.3},{:.1}",
                        s.joint_angles().iter().map(|a| a.to_degrees()).collect::<Vec<_>>(),
                        s.tip(),
                        s.cable_excursion,
                        s.iterations,
                        s.residual,
                        s.tangent_det[0],
                        st[0][0],
                        st[1][1],
                        st[2][2]
                    );
                    for n in [1, 10, 100, 1000] {
                        let s2 = f.solve(t, &v, Method::Stepping { n_inc: n }).unwrap();
                        print!(" n{n}: {:.5}", (s2.tip().y - s.tip().y));
                    }
                    println!();
                }
                Err(e) => println!("P={t} err {e}"),
            }
        }
        let v = [9000.0; 3];
        let s = f.solve(1.0, &v, Method::converged());
        println!("9kV: {:?}", s.map(|s| (s.joint_angles().to_vec(), s.thickness)));
        let s = f.solve_loaded(1.0, &[0.0; 3], [0.0, -0.1], Method::converged());
        println!("tipload: {:?}", s.map(|s| (s.joint_angles().to_vec(), s.tip(), s.iterations)));
    }
}
