//! `cargo run --bin fe-calibrate [-- --paper] [--card <name>] [--set name=value ...] [--coarse] [--plane-strain]`
//! (in tools/calculix): the FE calibration of the model's sub-element compliances for the default
//! finger (docs/model.md "Geometry"), `--paper` with the paper preset's E_de (Eq. 3), `--card` on a
//! film card (`Params::with_card`: a design's, python's `softfinger.design calibrate`), `--set` for any other parameter set
//! (console names, `Params::set`): linear CalculiX unit loads on one element (3D half width by
//! default), with and without its stack at three thicknesses; prints the factors
//! (`finger_model::Calibration`), the element compliances before and after, and the factors
//! as a `cal` console line and a Rust literal.
use finger_calculix::calibrate::{self, model_element_compliance};
use finger_calculix::ccx::Kind;
use finger_calculix::mesh::Density;
use finger_model::{Calibration, DeModulusRule, Params};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let has = |a: &str| args.iter().any(|x| x == a);
    let mut p = Params::<f64>::default();
    if let Some(i) = args.iter().position(|a| a == "--card") {
        let name = args.get(i + 1).map(String::as_str).unwrap_or("");
        match finger_model::material::cards::CARDS.iter().find(|c| c.name == name) {
            Some(c) => p = Params::with_card(c),
            None => {
                let names: Vec<_> = finger_model::material::cards::CARDS.iter().map(|c| c.name).collect();
                eprintln!("error: --card {name}: one of {}", names.join(", "));
                std::process::exit(2);
            }
        }
    }
    if has("--paper") {
        p.de_rule = DeModulusRule::PaperEq3;
    }
    for (i, a) in args.iter().enumerate() {
        if a == "--set" {
            let kv = args.get(i + 1).and_then(|s| s.split_once('='));
            let ok = kv.and_then(|(k, v)| v.parse::<f64>().ok().map(|v| (k, v))).map(|(k, v)| p.set(k, v));
            match ok {
                Some(Ok(())) => {}
                Some(Err(e)) => {
                    eprintln!("error: --set {}: {e}", args[i + 1]);
                    std::process::exit(2);
                }
                None => {
                    eprintln!("error: --set needs name=value (a console parameter name and a number)");
                    std::process::exit(2);
                }
            }
        }
    }
    let kind = if has("--plane-strain") { Kind::PlaneStrain } else { Kind::Half3d };
    let d = if has("--coarse") { Density::coarse() } else { Density::fine() };
    let run = match calibrate::run(&p, kind, &d) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    println!(
        "# FE calibration ({}, {:?}); parameters: {}",
        kind.name(),
        d,
        if has("--paper") {
            "paper preset's E_de"
        } else if has("--set") || has("--card") {
            "the defaults (docs/model.md) with --card / --set"
        } else {
            "the defaults (docs/model.md)"
        }
    );
    let c = run.cal;
    println!("hinge factors (C_x-Fx, C_y-Fy, C_y-M, C_θ-M): {:.6} {:.6} {:.6} {:.6}", c.hinge[0], c.hinge[1], c.hinge[2], c.hinge[3]);
    println!(
        "stack EA factor: {:.6} + {:.6} t; EI factor: {:.6} + {:.6} t (t in mm)",
        c.stack_axial[0], c.stack_axial[1], c.stack_bending[0], c.stack_bending[1]
    );
    let none = Calibration::none();
    let row = |t: f64, fe: &[[f64; 3]; 3]| {
        let m0 = model_element_compliance(&p, &none, t).unwrap();
        let m1 = model_element_compliance(&p, &c, t).unwrap();
        for (name, r, col) in [("θ-M", 2, 2), ("θ-Fx", 2, 0), ("y-M", 1, 2), ("y-Fy", 1, 1), ("x-Fx", 0, 0)] {
            let e = |m: &[[f64; 3]; 3]| 100.0 * (m[r][col] - fe[r][col]) / fe[r][col].abs().max(1e-30);
            if fe[r][col].abs() > 1e-12 {
                println!("  stack {t:.3} mm {name:5}: FE {:.6e}  model {:+.2} %  calibrated {:+.3} %", fe[r][col], e(&m0), e(&m1));
            }
        }
    };
    row(0.0, &run.fe_hinge);
    for s in &run.stacks {
        println!("  (t = {:.3} mm alone: EA x {:.4}, EI x {:.4})", s.thickness_mm, s.factors[0], s.factors[1]);
        row(s.thickness_mm, &s.fe);
    }
    println!(
        "cal {:.6} {:.6} {:.6} {:.6} {:.6} {:.6} {:.6} {:.6}",
        c.hinge[0], c.hinge[1], c.hinge[2], c.hinge[3], c.stack_axial[0], c.stack_axial[1], c.stack_bending[0], c.stack_bending[1]
    );
    println!(
        "Calibration {{ hinge: [{:.6}, {:.6}, {:.6}, {:.6}], stack_axial: [{:.6}, {:.6}], stack_bending: [{:.6}, {:.6}] }}",
        c.hinge[0], c.hinge[1], c.hinge[2], c.hinge[3], c.stack_axial[0], c.stack_axial[1], c.stack_bending[0], c.stack_bending[1]
    );
}
