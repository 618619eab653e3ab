//! `fe-em card=<card> <name>=<value> ... [volts=<V>[,<V>,<V>]] [tension=<N>[,<N>...]]
//! [theta=<deg>] [density=coarse|medium|fine] [rtol=<x>]` (in tools/calculix; `--release` for fine
//! meshes): the electromechanical FE (`em`), the voltage applied to the stacks, not the
//! model's thicknesses. The card and the console parameters as `fe-design` takes them.
//!
//! - without `tension`: one hinge of the design (`hinge_em`) at 0 V and at `volts` (default:
//!   the film's hold ceiling): its rotation under the voltage alone, its stiffness at the fixed
//!   rotation `theta` (default 10°) at both and their ratio, the bonded layers' thickness
//!   stretch at mid-hinge, and the free film's at that voltage; beside them the model's
//!   (`em::model_hinge`: the laminate, the finger's calibration): its rotation under the
//!   voltage alone and its stiffness ratio at a fixed rotation;
//! - with `tension`: the whole finger under the cable with `volts` per joint (one value: every
//!   joint), its joint angles per tension (`finger_under_cable_em`).
//!
//! Prints `key=value` lines; an error on stderr with exit code 1 (ccx failed) or 2 (bad
//! arguments).
use finger_calculix::em::{finger_under_cable_em, hinge_em, model_hinge, FixedPoint};
use finger_calculix::mesh::Density;
use finger_model::material::cards::CARDS;
use finger_model::{de, Params};

fn usage(msg: &str) -> ! {
    eprintln!("error: {msg}");
    std::process::exit(2)
}

fn list(v: &str, what: &str) -> Vec<f64> {
    v.split(',').map(|x| x.parse::<f64>().unwrap_or_else(|_| usage(&format!("{what}: comma-separated numbers")))).collect()
}

fn main() {
    let started = std::time::Instant::now();
    let mut p: Option<Params<f64>> = None;
    let (mut sets, mut volts, mut tensions, mut theta_deg, mut density) = (Vec::new(), None, None, 10.0, Density::coarse());
    let mut fp = FixedPoint::default();
    for a in std::env::args().skip(1) {
        let Some((k, v)) = a.split_once('=') else { usage(&format!("{a}: name=value expected")) };
        match k {
            "card" => match CARDS.iter().find(|c| c.name == v) {
                Some(c) => p = Some(Params::with_card(c)),
                None => usage(&format!("card {v}: one of {}", CARDS.iter().map(|c| c.name).collect::<Vec<_>>().join(", "))),
            },
            "volts" => volts = Some(list(v, "volts")),
            "tension" => tensions = Some(list(v, "tension")),
            "theta" => theta_deg = v.parse::<f64>().unwrap_or_else(|_| usage("theta: degrees")),
            "rtol" => fp.rtol = v.parse::<f64>().unwrap_or_else(|_| usage("rtol: a number")),
            "density" => {
                density = match v {
                    "coarse" => Density::coarse(),
                    "fine" => Density::fine(),
                    // between the two: the notch and the stack across its depth and the width
                    // refined, the body's rows and links left coarse
                    "medium" => Density { notch_cols: 12, stack_rows: 2, layers: 3, ..Density::coarse() },
                    _ => usage("density: coarse, medium or fine"),
                }
            }
            _ => sets.push((k.to_string(), v.parse::<f64>().unwrap_or_else(|_| usage(&format!("{k}: a number"))))),
        }
    }
    let mut p = p.unwrap_or_else(|| usage("card=<card> first"));
    if let Err(e) = finger_calculix::apply_overrides(&mut p, sets) {
        usage(&e);
    }
    let ceiling = de::voltage_ceiling(&p);
    let volts = volts.unwrap_or_else(|| vec![ceiling]);
    if volts.iter().any(|&v| !(0.0..=ceiling).contains(&v)) {
        usage(&format!("volts: 0 to the ceiling, {ceiling:.1} V"));
    }
    let fail = |e: finger_calculix::ccx::FeError| -> ! {
        eprintln!("error: {e}");
        std::process::exit(1)
    };
    let join = |v: &[f64]| v.iter().map(|x| format!("{x:e}")).collect::<Vec<_>>().join(",");
    println!("ceiling_volts={ceiling:.3}");
    match tensions {
        None => {
            if volts.len() != 1 {
                usage("volts: one value for a hinge");
            }
            let (th, dth) = (theta_deg.to_radians(), 0.5f64.to_radians());
            let off = hinge_em(&p, 0.0, th, dth, &density, fp).unwrap_or_else(|e| fail(e));
            let on = hinge_em(&p, volts[0], th, dth, &density, fp).unwrap_or_else(|e| fail(e));
            let s_free = de::layer_thickness_ratio(&p, 1, volts[0]).unwrap_or(f64::NAN);
            println!("volts={:.3}", volts[0]);
            println!("rotation_deg={:.6}", on.rotation.to_degrees());
            println!("turned_deg={:.6},{:.6}", off.turned.to_degrees(), on.turned.to_degrees());
            println!("stiffness_nmm_per_rad={:.9e},{:.9e}", off.k, on.k);
            println!("ratio={:.6}", off.k / on.k);
            println!("s_mid_bonded={:.6},{:.6}", on.s_mid_centre, on.s_mid_edge);
            println!("s_free_film={s_free:.6}");
            println!("runs={}", off.iterations + on.iterations);
            // the solves' model: the laminate (its softening and its actuation), calibrated
            match model_hinge(&p, volts[0].min(0.999_999 * ceiling)) {
                Ok(m) => {
                    println!("model_rotation_deg={:.6}", m.rotation.to_degrees());
                    println!("model_ratio={:.6}", m.ratio);
                }
                Err(e) => println!("model_error={e}"),
            }
        }
        Some(t) => {
            let v: Vec<f64> = if volts.len() == 1 { vec![volts[0]; p.n] } else { volts };
            if v.len() != p.n {
                usage(&format!("volts: one value or {} (one per joint)", p.n));
            }
            let joints = finger_under_cable_em(&p, &v, &density, &t, fp).unwrap_or_else(|e| fail(e));
            for (tn, j) in t.iter().zip(&joints) {
                println!("tension={tn} joints={}", join(j));
            }
        }
    }
    println!("seconds={:.3}", started.elapsed().as_secs_f64());
}
