use finger_calculix::*;
use finger_calculix::ccx::Kind;
use finger_calculix::mesh::Density;
use finger_model::{Params, Finger, Method};
fn main() {
    let p = Params::<f64>::default().without_stacks();
    let d = Density::coarse();
    for kind in [Kind::PlaneStrain, Kind::Half3d] {
        let t0 = std::time::Instant::now();
        let c = element_compliance(&p, 0.0, kind, &d);
        println!("{:?} {:?} {:?}", kind, c, t0.elapsed());
        let t0 = std::time::Instant::now();
        let r = finger_under_cable(&p, &[0.0;3], kind, &d, &[0.3, 0.8, 1.5]);
        match r { Ok(s) => for st in s { println!("{} {:?} tip {:?}", st.tension, st.joint_angle.iter().map(|a| a.to_degrees()).collect::<Vec<_>>(), st.tip()); }, Err(e) => println!("{e}") }
        println!("{:?}", t0.elapsed());
    }
    let f = Finger::new(p).unwrap();
    for t in [0.3, 0.8, 1.5] { let s = f.solve(t, &[0.0;3], Method::converged()).unwrap(); println!("model {t} {:?} tip {:?}", s.joint_angles().iter().map(|a| a.to_degrees()).collect::<Vec<_>>(), s.tip()); }
}
