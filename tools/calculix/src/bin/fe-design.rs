//! `fe-design card=<card> <name>=<value> ... tension=<N> stack=<mm>,<mm>,<mm> [kind=3d|pe]
//! [density=coarse|notch|fine]` (in tools/calculix): one design of the design study (python's
//! `softfinger.design.fe`, docs/design.md) in CalculiX at one end of its reference posture:
//! the finger on the card's film with the console parameters given (`Params::set`), its stacks
//! at the thicknesses that end's voltages give, under the cable tension; then its tip
//! compliance there (`tip_compliance_under_cable`). Prints `key=value` lines: `joints` (rad),
//! `tip` (x mm, y mm, θ rad), `compliance` and `stiffness` (row-major 3×3, base frame: x mm,
//! y mm, θ rad), `nodes` (mesh nodes), `seconds`; an error on stderr with exit code 1 (ccx
//! failed) or 2 (bad arguments).
use finger_calculix::ccx::{Kind, Law};
use finger_calculix::mesh::Density;
use finger_calculix::{finger_mesh, tip_compliance_under_cable};
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
    for a in std::env::args().skip(1) {
        let Some((k, v)) = a.split_once('=') else { usage(&format!("{a}: name=value expected")) };
        match k {
            "card" => match CARDS.iter().find(|c| c.name == v) {
                Some(c) => p = Some(Params::with_card(c)),
                None => usage(&format!("card {v}: one of {}", CARDS.iter().map(|c| c.name).collect::<Vec<_>>().join(", "))),
            },
            "tension" => tension = Some(v.parse::<f64>().unwrap_or_else(|_| usage("tension: a number (N)"))),
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
