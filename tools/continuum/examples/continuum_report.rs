//! Prints the numbers quoted in docs/continuum.md: convergence under refinement,
//! the default finger without stacks at P = 0.2, 0.5, 1, 2 N (with and without the
//! plate modulus), the tension at which a span closes, and the three-element
//! model's (finger-model) joint-angle error against this reference for m = 1, 2, 4, 8.
//! Run: cargo run --release --example continuum_report
use continuum::*;
use finger_model::{Finger, Method, Params};

fn deg(v: &[f64]) -> String {
    v.iter().map(|a| format!("{:8.4}", a.to_degrees())).collect::<Vec<_>>().join(" ")
}

fn main() {
    let p = ContinuumParams::default();
    println!("## Convergence (P = 1 N and 2 N; refinement by 2 in hinge and link steps)");
    for &t in &[1.0, 2.0] {
        for stacks in [vec![], vec![2.0, 1.5, 1.0]] {
            let mut prev: Option<ContinuumSolution> = None;
            let mut prev_d = f64::NAN;
            for k in 0..6 {
                let d = Discretisation::new(8, 2).refined(1 << k);
                let s = solve(&p, t, &stacks, [0.0, 0.0], d).unwrap();
                if let Some(q) = &prev {
                    let da = s.joint_angles.iter().zip(&q.joint_angles).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                    let dt = ((s.tip.x - q.tip.x).powi(2) + (s.tip.y - q.tip.y).powi(2)).sqrt();
                    println!("| {t} | {stacks:?} | {}/{} | {da:.3e} | {dt:.3e} | {:.2} |", d.hinge_steps, d.link_steps, prev_d / da);
                    prev_d = da;
                }
                prev = Some(s);
            }
        }
    }
    println!("\n## Default finger, no stacks (default discretisation)");
    for plate in [false, true] {
        let q = ContinuumParams { plate, ..p.clone() };
        for &t in &[0.2, 0.5, 1.0, 2.0] {
            let t0 = std::time::Instant::now();
            let s = solve(&q, t, &[], [0.0, 0.0], Discretisation::default()).unwrap();
            println!(
                "| {plate} | {t} | {} | {} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} | {:?} |",
                deg(&s.joint_angles),
                deg(&s.hinge_angles),
                s.tip.x,
                s.tip.y,
                s.tip.theta.to_degrees(),
                s.spans[0],
                s.excursion,
                t0.elapsed()
            );
        }
        let r = closing_tension(&q, &[], [0.0, 0.0], Discretisation::default(), 30.0).unwrap().unwrap();
        println!(
            "plate {plate}: span {} closes (floor {} mm) at P = {:.5} N, joint angle {:.3} deg, hinge {:.3} deg",
            r.joint,
            q.contact_floor,
            r.tension,
            r.solution.joint_angles[0].to_degrees(),
            r.solution.hinge_angles[0].to_degrees()
        );
    }
    println!("\n## Three-element model (finger-model, converged) against this reference, no stacks");
    println!("| plate | links | m | P | joint angle model (deg) | continuum (deg) | rel. error | tip error (mm) |");
    for plate in [false, true] {
        for flex in [false, true] {
            let q = ContinuumParams { plate, ..p.clone() };
            for m in [1usize, 2, 4, 8] {
                let mp = Params::<f64> { m, plate, flex_links: flex, ..Params::default() }.without_stacks();
                let f = match Finger::new(mp) {
                    Ok(f) => f,
                    Err(e) => {
                        println!("model refused: {e:?}");
                        continue;
                    }
                };
                for &t in &[0.2, 0.5, 1.0, 2.0] {
                    let c = solve(&q, t, &[], [0.0, 0.0], Discretisation::default()).unwrap();
                    match f.solve(t, &[0.0; 3], Method::converged()) {
                        Ok(s) => {
                            let ja = s.joint_angle[0];
                            let tip = s.nodes[3];
                            println!(
                                "| {plate} | {} | {m} | {t} | {:.4} | {:.4} | {:+.2} % | {:.3} |",
                                if flex { "flexible" } else { "rigid" },
                                ja.to_degrees(),
                                c.joint_angles[0].to_degrees(),
                                100.0 * (ja - c.joint_angles[0]) / c.joint_angles[0],
                                ((tip.x - c.tip.x).powi(2) + (tip.y - c.tip.y).powi(2)).sqrt()
                            );
                        }
                        Err(e) => println!("| {plate} | {flex} | {m} | {t} | model error {e:?} |"),
                    }
                }
            }
        }
    }
    println!("\n## With stacks at 0 V (t_k = layers z0 = 2 mm), plate off, flexible links");
    println!("| m | P | joint angle model (deg) | continuum (deg) | rel. error |");
    for m in [1usize, 2, 4, 8] {
        let mp = Params::<f64> { m, flex_links: true, ..Params::default() };
        let f = Finger::new(mp).unwrap();
        let tk = f.stack_thickness(0.0).unwrap();
        for &t in &[0.2, 1.0, 2.0] {
            let c = solve(&p, t, &[tk; 3], [0.0, 0.0], Discretisation::default()).unwrap();
            let s = f.solve(t, &[0.0; 3], Method::converged()).unwrap();
            let ja = s.joint_angle[0];
            println!(
                "| {m} | {t} | {:.4} | {:.4} | {:+.2} % |",
                ja.to_degrees(),
                c.joint_angles[0].to_degrees(),
                100.0 * (ja - c.joint_angles[0]) / c.joint_angles[0]
            );
        }
    }
}
