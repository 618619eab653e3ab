//! Prints the f64 model's answers on the bench scenes (`finger-scenes`: SCENES with the
//! converged solver, and with the paper's stepping at n_inc = 20), one line per scene:
//! `name method tension v1 v2 v3 | joints… | tip x y θ | cable | thick… | kxx kyy kθθ | iters`,
//! every number in Rust's shortest round-trip form, or `name method err <kind>`. The Python
//! package's test compares its own results with these digit for digit.
use finger_model::{mat3, Finger, Method};
use finger_scenes::{params, SCENES};

fn main() {
    for s in SCENES {
        let f = Finger::new(params(s)).expect("bench scene parameters");
        for (label, m) in [("converged", Method::converged()), ("stepping20", Method::Stepping { n_inc: 20 })] {
            let r = f.compliances(&s.volts).and_then(|c| {
                let sol = f.solve_with(&c, s.tension, [0.0; 2], m)?;
                let k = mat3::inverse_spd(&f.tip_compliance(&c, &sol)).ok_or(finger_model::Error::Singular { what: "tip compliance" })?;
                Ok((sol, k))
            });
            let head = format!("{} {label} {} {} {} {}", s.name, s.tension, s.volts[0], s.volts[1], s.volts[2]);
            match r {
                Ok((sol, k)) => {
                    let t = sol.tip();
                    let j: Vec<String> = sol.joint_angles().iter().map(|x| x.to_string()).collect();
                    let th: Vec<String> = sol.thickness[..sol.n].iter().map(|x| x.to_string()).collect();
                    println!(
                        "{head} | {} | {} {} {} | {} | {} | {} {} {} | {}",
                        j.join(" "),
                        t.x,
                        t.y,
                        t.theta,
                        sol.cable_excursion,
                        th.join(" "),
                        k[0][0],
                        k[1][1],
                        k[2][2],
                        sol.iterations
                    );
                }
                Err(e) => println!("{head} | err {e:?}"),
            }
        }
    }
}
