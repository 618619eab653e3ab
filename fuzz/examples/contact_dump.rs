//! Every contact request of the corpora (f64) and of the two fingers' grids (f32 and f64), one
//! line each with its outcome to the last bit: `cargo run --release --example contact_dump`.
//! Two runs' outputs diffed show what a change to the pinned continuation moved.
use finger_model::calibration::Calibration;
use finger_model::inverse::contact_force;
use finger_model::real::Real;
use finger_model::{Finger, Params};

fn line<R: Real>(r: Result<finger_model::inverse::Contact<R>, finger_model::Error>) -> String {
    match r {
        Ok(c) => format!("ok {:?} {:?}", c.force.map(|x| x.to_f64()), c.solution.joint_angle.map(|x| x.to_f64())),
        Err(e) => format!("err {e:?}"),
    }
}

fn grid<R: Real>(name: &str, f: &Finger<R>) {
    let top = f.voltage_ceiling().to_f64() * (1.0 - 1e-4);
    let vs = [[0.0; 3], [top / 3.0; 3], [2.0 * top / 3.0; 3], [top; 3], [0.0, top / 2.0, top], [top, 0.0, top / 2.0]];
    for v in vs {
        let v = v.map(R::from_f64);
        let fmax = f.fmax(&v).map(|l| l.tension.to_f64()).unwrap_or(f64::NAN);
        for i in 0..8 {
            let p0 = 0.05 + (5.0 - 0.05) * i as f64 / 7.0;
            for j in 0..=12 {
                let p = p0 + (fmax * 1.2 - p0) * j as f64 / 12.0;
                let r = contact_force(f, R::from_f64(p0), &[R::zero(); 3], R::from_f64(p), &v);
                println!("{name} P0 {p0} P {p} V {:?}: {}", v.map(|x| x.to_f64()), line(r));
            }
        }
    }
}

fn main() {
    for d in ["corpus/model_contact", "regressions/model_contact", "corpus/model", "regressions/model"] {
        let Ok(rd) = std::fs::read_dir(d) else { continue };
        let mut names: Vec<_> = rd.flatten().map(|e| e.path()).collect();
        names.sort();
        for path in names {
            let data = std::fs::read(&path).unwrap();
            let Some((f, p0, p, v)) = finger_fuzz::model_contact::request(&data) else { continue };
            let n = f.params().n;
            println!("{}: {}", path.display(), line(contact_force(&f, p0, &vec![0.0; n], p, &v)));
        }
    }
    let p = Params::<f32>::default();
    grid("default32", &Finger::with_calibration(p, Calibration::for_params(&p)).unwrap());
    grid("paper32", &Finger::new(Params::<f32>::paper()).unwrap());
    let p = Params::<f64>::default();
    grid("default64", &Finger::with_calibration(p, Calibration::for_params(&p)).unwrap());
    grid("paper64", &Finger::new(Params::<f64>::paper()).unwrap());
}
