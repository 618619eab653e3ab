//! `fe-design card=<card> <name>=<value> ... tension=<N> stack=<mm>,<mm>,<mm> [kind=3d|pe]
//! [density=coarse|notch|fine] [tip_deg=<deg>]` (in tools/calculix): one design of the design study (python's
//! `softfinger.design.fe`, docs/design.md) in CalculiX at one end of its reference posture:
//! the finger on the card's film with the console parameters given (`Params::set`), its stacks
//! at the thicknesses that end's voltages give, under the cable tension; then its tip
//! compliance there (`tip_compliance_under_cable`). With `tip_deg`, the tension is the FE's own
//! for the reference posture: the one at which the FE's tip angle (the joints' sum) is
//! `tip_deg`, found from `tension` (the model's, the first guess) by a sweep of load steps and
//! secant runs (`tension_for_tip`, to 0.01°); then the compliance there. Prints `key=value`
//! lines: `tension` (N, the one solved at), `joints` (rad),
//! `tip` (x mm, y mm, θ rad), `compliance` and `stiffness` (row-major 3×3, base frame: x mm,
//! y mm, θ rad), `nodes` (mesh nodes), `seconds`; an error on stderr with exit code 1 (ccx
//! failed) or 2 (bad arguments).
use finger_calculix::ccx::{Kind, Law};
use finger_calculix::mesh::Density;
use finger_calculix::{finger_mesh, finger_under_cable_partial, tip_compliance_under_cable};
use finger_model::material::cards::CARDS;
use finger_model::{mat3, Params};

fn usage(msg: &str) -> ! {
    eprintln!("error: {msg}");
    std::process::exit(2)
}

fn main() {
    let started = std::time::Instant::now();
    let mut p: Option<Params<f64>> = None;
    let (mut sets, mut tension, mut stack, mut kind, mut density) = (Vec::new(), None, None, Kind::Half3d, Density::coarse());
    let mut tip_deg: Option<f64> = None;
    for a in std::env::args().skip(1) {
        let Some((k, v)) = a.split_once('=') else { usage(&format!("{a}: name=value expected")) };
        match k {
            "card" => match CARDS.iter().find(|c| c.name == v) {
                Some(c) => p = Some(Params::with_card(c)),
                None => usage(&format!("card {v}: one of {}", CARDS.iter().map(|c| c.name).collect::<Vec<_>>().join(", "))),
            },
            "tension" => tension = Some(v.parse::<f64>().unwrap_or_else(|_| usage("tension: a number (N)"))),
            "tip_deg" => {
                tip_deg = Some(v.parse::<f64>().ok().filter(|x| x.is_finite() && x.abs() < 180.0).unwrap_or_else(|| usage("tip_deg: degrees, -180..180")))
            }
            "stack" => {
                stack = Some(v.split(',').map(|x| x.parse::<f64>().unwrap_or_else(|_| usage("stack: mm per joint, comma-separated"))).collect::<Vec<_>>())
            }
            "kind" => {
                kind = match v {
                    "3d" => Kind::Half3d,
                    "pe" => Kind::PlaneStrain,
                    _ => usage("kind: 3d or pe"),
                }
            }
            "density" => {
                density = match v {
                    "coarse" => Density::coarse(),
                    "fine" => Density::fine(),
                    // coarse, with the notch's columns of the fine mesh: a stack that nearly
                    // fills its notch ends in a column too thin for 8 (ccx diverges)
                    "notch" => Density { notch_cols: Density::fine().notch_cols, ..Density::coarse() },
                    _ => usage("density: coarse, notch or fine"),
                }
            }
            _ => sets.push((k.to_string(), v.parse::<f64>().unwrap_or_else(|_| usage(&format!("{k}: a number"))))),
        }
    }
    let mut p = p.unwrap_or_else(|| usage("card=<card> first"));
    if let Err(e) = finger_calculix::apply_overrides(&mut p, sets) {
        usage(&e);
    }
    let tension = tension.unwrap_or_else(|| usage("tension=<N>"));
    let stack = stack.unwrap_or_else(|| usage("stack=<mm>,<mm>,<mm>"));
    if stack.len() != p.n {
        usage(&format!("stack: {} thicknesses (one per joint)", p.n));
    }
    let tension = match tip_deg {
        None => tension,
        Some(deg) => tension_for_tip(&p, &stack, kind, &density, tension, deg.to_radians()).unwrap_or_else(|e| {
            eprintln!("error: {e}");
            std::process::exit(1)
        }),
    };
    println!("tension={tension:e}");
    // small tip loads against the cable's: a few % of what the tension bends the finger with
    let perturb = [0.02 * tension.max(0.05), 0.02 * tension.max(0.05), 0.02 * tension.max(0.05) * p.b];
    match tip_compliance_under_cable(&p, &stack, kind, &density, Law::NeoHooke, tension, perturb) {
        Ok((s, c)) => {
            let join = |v: &[f64]| v.iter().map(|x| format!("{x:e}")).collect::<Vec<_>>().join(",");
            let k = mat3::inverse(&c).unwrap_or([[0.0; 3]; 3]);
            let t = s.tip();
            println!("joints={}", join(&s.joint_angle));
            println!("tip={}", join(&[t.x, t.y, t.theta]));
            println!("compliance={}", join(&c.concat()));
            println!("stiffness={}", join(&k.concat()));
            println!("nodes={}", finger_mesh(&p, &stack, kind, &density).node_count());
            println!("seconds={:.3}", started.elapsed().as_secs_f64());
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1)
        }
    }
}

/// The FE's tension for a tip angle `tip_rad` (the joints' sum): load steps from `guess` / 2 to
/// 2 `guess` bracket it (ccx stopping early is the end of the sweep), a line between the
/// bracket's ends, then secant runs until the tip is within 0.01° (at most 6 runs).
fn tension_for_tip(p: &Params<f64>, stack: &[f64], kind: Kind, d: &Density, guess: f64, tip_rad: f64) -> Result<f64, String> {
    let tip_at = |t: &[f64]| -> Result<Vec<(f64, f64)>, String> {
        let (states, err) = finger_under_cable_partial(p, stack, kind, d, Law::NeoHooke, t).map_err(|e| e.to_string())?;
        if states.is_empty() {
            return Err(err.map_or("ccx: no step converged".into(), |e| e.to_string()));
        }
        Ok(states.iter().map(|s| (s.tension, s.joint_angle.iter().sum::<f64>() - tip_rad)).collect())
    };
    let guess = guess.max(1e-3);
    let sweep: Vec<f64> = [0.5, 0.7, 0.85, 1.0, 1.15, 1.3, 1.6, 2.0].iter().map(|k| k * guess).collect();
    let pts = tip_at(&sweep)?;
    let Some(i) = pts.windows(2).position(|w| w[0].1 <= 0.0 && w[1].1 >= 0.0) else {
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        return Err(format!(
            "the FE's tip angle is {:.2}..{:.2} deg over {:.4}..{:.4} N: no tension there gives {:.2} deg",
            (a.1 + tip_rad).to_degrees(),
            (b.1 + tip_rad).to_degrees(),
            a.0,
            b.0,
            tip_rad.to_degrees()
        ));
    };
    let (mut a, mut b) = (pts[i], pts[i + 1]);
    let tol = 0.01f64.to_radians();
    for _ in 0..6 {
        let t = if b.1 == a.1 { 0.5 * (a.0 + b.0) } else { a.0 - a.1 * (b.0 - a.0) / (b.1 - a.1) };
        let r = tip_at(&[t])?[0];
        if r.1.abs() < tol {
            return Ok(t);
        }
        // keep a bracket: the new point replaces the end of its sign
        if r.1 < 0.0 {
            a = r;
        } else {
            b = r;
        }
    }
    Err(format!("the FE's tension for a tip of {:.2} deg: not within 0.01 deg after 6 runs (bracket {:.5}..{:.5} N)", tip_rad.to_degrees(), a.0, b.0))
}
