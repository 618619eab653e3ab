use finger_model::*;
fn main() {
    for (m, plate) in [(1usize, false), (4, false), (8, false), (8, true)] {
        let p = Params::<f64> { m, plate, ..Params::default() }.without_stacks();
        let f = Finger::new(p).unwrap();
        let mut line = format!("m={m} plate={plate}:");
        for t in [0.2, 1.0, 2.0, 4.0, 6.0, 7.0, 7.5, 8.0, 9.0, 12.0, 20.0] {
            match f.solve(t, &[0.0; 3], Method::converged()) {
                Ok(s) => line += &format!(" {t}:{:.2}deg/span{:.2}/it{}/det{:.2}", s.joint_angle[0].to_degrees(), s.span[0], s.iterations, s.tangent_det[0]),
                Err(e) => {
                    line += &format!(" {t}:ERR {e}");
                    break;
                }
            }
        }
        println!("{line}");
    }
}
