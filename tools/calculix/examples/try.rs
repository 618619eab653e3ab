use finger_calculix::*;
use finger_calculix::ccx::Kind;
use finger_calculix::mesh::Density;
use finger_model::Params;
fn main() {
    for nu in [0.49, 0.3] {
    for stack in [2.0, 4.5] {
    let p = Params::<f64> { nu, ..Params::default() };
    for kind in [Kind::PlaneStrain, Kind::PlaneStress, Kind::Half3d] {
            for k in [1] {
                let d = Density::coarse().times(k);
                let c = element_compliance(&p, stack, kind, &d).unwrap();
                println!("nu {nu} {:?} stack {stack} x{k}: xx {:.6e} yy {:.6e} ym {:.6e} mm {:.6e} xm {:.6e}", kind, c[0][0], c[1][1], c[1][2], c[2][2], c[0][2]);
            }
        }
    }}
}
