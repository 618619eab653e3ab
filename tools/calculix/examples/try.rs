use finger_calculix::*;
use finger_calculix::ccx::Kind;
use finger_calculix::mesh::Density;
use finger_model::Params;
fn main() {
    let p = Params::<f64>::default().without_stacks();
    for (kind, d) in [(Kind::PlaneStrain, Density::fine()), (Kind::Half3d, Density::coarse()), (Kind::Half3d, Density::fine())] {
        let t0 = std::time::Instant::now();
        let r = finger_under_cable_partial(&p, &[0.0;3], kind, &d, &[0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]).unwrap();
        for st in r.0 { println!("{:?} {} {:?} tip {:?} span {:?}", kind, st.tension, st.joint_angle.iter().map(|a| a.to_degrees()).collect::<Vec<_>>(), st.tip(), st.span); }
        if let Some(e) = r.1 { println!("{e}"); }
        println!("{:?} {:?}", d, t0.elapsed());
    }
}
