//! Writes docs/inverse-tables.md: the stiffness range one posture can be held with for each
//! material card (the board's VHB 4905 first, stated in one sentence), on the paper's card and on
//! variants (higher-voltage supply, softer elastomer, thinner layers,
//! the paper preset), the contact force against the voltages at one tension, and the host
//! time of one inverse solve.
//!
//! Run from host-tests/: `cargo run --release --example stiffness_range` (writes
//! ../docs/inverse-tables.md; pass another path as the first argument to write elsewhere).

use finger_model::inverse::{contact_force, solve_pose, stiffness_range};
use finger_model::material::{ELASTOSIL_2030, VHB_4905};
use finger_model::{Calibration, Finger, Method, Params};
use std::fmt::Write as _;
use std::time::Instant;

fn main() {
    let path = std::env::args().nth(1).unwrap_or_else(|| "../docs/inverse-tables.md".to_string());
    let deg = 10.0f64;
    let angles = [deg.to_radians(); 3];
    let mut o = host_tests::report::generated_header(
        "cargo run --release --example stiffness_range",
        &format!("## Stiffness range of one posture (all three joints at {deg}°)"),
    );
    writeln!(
        o,
        "Tip stiffness K_tip (`Finger::tip_stiffness`) at the two ends of the tension interval: low end = \
         the softest stacks the ceiling allows (a joint at the top voltage), high end = a joint at 0 V. \
         kyy in N/mm, kθθ in N·mm/rad. Thinning = stack thickness reduction at the ceiling, relaxed \
         (the film's law at equilibrium, docs/materials.md). V_pi = the relaxed film's pull-in; the \
         ceiling = the card's hold ceiling (margin x min(the voltage holding 2/3 of the thickness \
         relaxed, the breakdown field there)), capped by the supply. E_de = the stack's beam modulus \
         2 G (1 + nu).\n"
    )
    .unwrap();
    // kyy at 0 V, at the ceiling, and of the finger without stacks, at the same posture
    let range_cal = |p: Params<f64>, cal: Calibration<f64>| -> Option<(f64, f64, f64)> {
        let f = Finger::with_calibration(p, cal).ok()?;
        let s = solve_pose(&f, &angles, None).ok()?;
        let r = stiffness_range(&f, &s).ok()?;
        let bare = Finger::with_calibration(p.without_stacks(), cal).ok()?;
        let sb = solve_pose(&bare, &angles, None).ok()?;
        let kb = bare.tip_stiffness(&bare.solve(sb.tension, &[0.0; 3], Method::converged()).ok()?).ok()?;
        Some((r.stiffness[1][1][1], r.stiffness[0][1][1], kb[1][1]))
    };
    let range = |p: Params<f64>| range_cal(p, Calibration::none());
    // the board's finger: VHB 4905 with the board's FE calibration (src/app/params.rs)
    let board = range_cal(Params::vhb4905(), Calibration::model_md());
    match range(Params::vhb4905()) {
        Some((k_0v, k_top, k_bare)) => writeln!(
            o,
            "**With the board's film, VHB 4905 (relaxed shear modulus {:.1} kPa), the stacks make the \
             default finger's tip {:.2} % stiffer (kyy) than the same finger without stacks, and the whole \
             voltage range changes that stiffness by {:.2} %: the stacks add almost nothing to the \
             joint, so voltage cannot vary this finger's stiffness in any useful way.**\n",
            VHB_4905.g_eq_mpa * 1e3,
            100.0 * (k_0v / k_bare - 1.0),
            100.0 * (k_0v / k_top - 1.0),
        )
        .unwrap(),
        None => writeln!(o, "**With the board's film, VHB 4905, the default finger's posture could not be solved.**\n").unwrap(),
    }
    let d = Params::<f64>::default();
    let vhb_row = format!(
        "card VHB 4905, the board's film, uncalibrated (G_eq {:.1} kPa relaxed; 4 x 0.5 mm, 10 kV; m = 8, plate, flexible links)",
        VHB_4905.g_eq_mpa * 1e3
    );
    let cases: Vec<(&str, Params<f64>)> = vec![
        (vhb_row.as_str(), Params::vhb4905()),
        ("card Elastosil Film 2030 (silicone)", Params::with_card(&ELASTOSIL_2030)),
        ("card paper-elastic, the model's default (G 0.6 MPa; 4 x 0.5 mm, 10 kV; m = 8, plate, flexible links)", d),
        ("supply 20 kV", Params { v_supply: 20_000.0, ..d }),
        ("supply 30 kV", Params { v_supply: 30_000.0, ..d }),
        ("softer elastomer G 0.2 MPa", Params { g: 0.2, ..d }),
        ("softer elastomer G 0.05 MPa", Params { g: 0.05, ..d }),
        ("thinner layers z0 0.25 mm", Params { z0: 0.25, ..d }),
        ("thinner layers z0 0.1 mm", Params { z0: 0.1, ..d }),
        ("thinner layers z0 0.1 mm, 20 layers", Params { z0: 0.1, layers: 20, ..d }),
        ("G 0.2 MPa, z0 0.25 mm, 30 kV", Params { g: 0.2, z0: 0.25, v_supply: 30_000.0, ..d }),
        ("paper preset (E_de 0.201 MPa)", Params::paper()),
        ("the paper's model (m = 1, E_b, rigid links)", Params::paper_model()),
        ("m = 4, plate modulus, rigid links", Params { m: 4, plate: true, flex_links: false, ..d }),
        ("m = 8, plate modulus, rigid links", Params { m: 8, plate: true, flex_links: false, ..d }),
        ("supply 30 kV, paper's model (m = 1)", Params { v_supply: 30_000.0, ..Params::paper_model() }),
    ];
    writeln!(
        o,
        "| hardware | E_de MPa | V_pi kV | ceiling kV | thinning at the ceiling % | tension interval N | tension window % | \
         kyy at the top voltage..at 0 V, N/mm | kyy change over the voltage range (0 V / top) | kθθ at the top voltage..at 0 V, N·mm/rad |"
    )
    .unwrap();
    writeln!(o, "| --- | ---: | ---: | ---: | ---: | --- | ---: | --- | ---: | --- |").unwrap();
    let mut rows: Vec<(String, Params<f64>, Calibration<f64>)> = cases.iter().map(|(n, p)| (n.to_string(), *p, Calibration::none())).collect();
    rows.insert(
        1,
        (
            "card VHB 4905 with the board's FE calibration (`cal`): the board's finger, what `solve`, `pose` and the web view show".to_string(),
            Params::vhb4905(),
            Calibration::model_md(),
        ),
    );
    // (kθθ low..high, the kyy ratio) of each row, for the note on the calibration below
    let mut seen: Vec<Option<(f64, f64, f64)>> = Vec::new();
    for (name, p, cal) in &rows {
        let f = Finger::with_calibration(*p, *cal).unwrap();
        let ceil = f.voltage_ceiling();
        let t0 = p.layers as f64 * p.z0;
        let thin = 100.0 * (1.0 - f.stack_thickness(ceil * (1.0 - 1e-4)).unwrap() / t0);
        match solve_pose(&f, &angles, None).and_then(|s| stiffness_range(&f, &s).map(|r| (s, r))) {
            Ok((s, r)) => {
                let (lo, hi) = (s.interval[0], s.interval[1]);
                let (k0, k1) = (r.stiffness[0], r.stiffness[1]);
                seen.push(Some((k0[2][2], k1[2][2], k1[1][1] / k0[1][1])));
                writeln!(
                    o,
                    "| {name} | {:.3} | {:.1} | {:.1} | {:.2} | {:.4}..{:.4} | {:.2} | {:.4}..{:.4} | {:.4} | {:.1}..{:.1} |",
                    p.e_de(),
                    f.pull_in_voltage() / 1e3,
                    ceil / 1e3,
                    thin,
                    lo,
                    hi,
                    100.0 * (hi - lo) / hi,
                    k0[1][1],
                    k1[1][1],
                    k1[1][1] / k0[1][1],
                    k0[2][2],
                    k1[2][2]
                )
                .unwrap();
            }
            Err(e) => {
                seen.push(None);
                writeln!(o, "| {name} | {:.3} | | {:.1} | {thin:.2} | err: {e} | | | | |", p.e_de(), ceil / 1e3).unwrap()
            }
        }
    }

    if let (Some(Some(plain)), Some(Some(cal))) = (seen.first(), seen.get(1)) {
        writeln!(
            o,
            "\nEvery row but the second is the uncalibrated model (`Finger::new`), as docs/inverse.md's figures are; the \
             second is the board's finger with its FE calibration (docs/model.md \"FE calibration\"), which changes the \
             hinges' compliances: that is why the board, the Python `Finger()` and the web view give kθθ {:.1}..{:.1} \
             N·mm/rad at this posture where the first row gives {:.1}..{:.1}, for the same film and about the same change \
             over the voltage range ({:.2} % calibrated, {:.2} % not).",
            cal.0,
            cal.1,
            plain.0,
            plain.1,
            100.0 * (cal.2 - 1.0),
            100.0 * (plain.2 - 1.0)
        )
        .unwrap();
    }
    writeln!(o, "\n## Contact force against the voltages at one tension\n").unwrap();
    writeln!(
        o,
        "The tip stops at the free tip of P0 = 1 N at 0 V; the cable is then pulled to P = 1.5 N with all \
         three channels at the voltage shown. F = force of the object on the tip (base frame), N; the \
         finger presses with -F.\n"
    )
    .unwrap();
    writeln!(o, "| hardware | V (all channels) | fx N | fy N | abs(F) N | change vs 0 V % |").unwrap();
    writeln!(o, "| --- | --- | --- | --- | --- | --- |").unwrap();
    for (name, p) in [("default", d), ("supply 30 kV", Params { v_supply: 30_000.0, ..d }), ("paper preset", Params::paper())] {
        let f = Finger::new(p).unwrap();
        let ceil = f.voltage_ceiling();
        let mut base = None;
        for frac in [0.0, 0.5, 0.95] {
            let v = [frac * ceil; 3];
            match contact_force(&f, 1.0, &[0.0; 3], 1.5, &v) {
                Ok(c) => {
                    let m = c.magnitude();
                    let b = *base.get_or_insert(m);
                    writeln!(o, "| {name} | {:.0} | {:.4} | {:.4} | {:.4} | {:+.2} |", v[0], c.force[0], c.force[1], m, 100.0 * (m - b) / b).unwrap();
                }
                Err(e) => writeln!(o, "| {name} | {:.0} | err: {e} | | | |", v[0]).unwrap(),
            }
        }
    }

    writeln!(o, "\n## Contact force against the tension (default hardware, 0 V)\n").unwrap();
    writeln!(o, "| P0 N | P N | abs(F) N |").unwrap();
    writeln!(o, "| --- | --- | --- |").unwrap();
    let f = Finger::new(d).unwrap();
    for p in [1.0, 1.25, 1.5, 2.0, 3.0] {
        match contact_force(&f, 1.0, &[0.0; 3], p, &[0.0; 3]) {
            Ok(c) => writeln!(o, "| 1 | {p} | {:.4} |", c.magnitude()).unwrap(),
            Err(e) => writeln!(o, "| 1 | {p} | err: {e} |").unwrap(),
        }
    }

    // host time of one inverse solve (a posture from a forward solve), f64 and f32
    let n = 20_000;
    let s = f.solve(1.0, &[3000.0, 6000.0, 9000.0], Method::converged()).unwrap();
    let a64 = s.joint_angles().to_vec();
    let t = Instant::now();
    let mut acc = 0.0;
    for _ in 0..n {
        acc += solve_pose(&f, std::hint::black_box(&a64), None).unwrap().tension;
    }
    let us64 = t.elapsed().as_secs_f64() / n as f64 * 1e6;
    let f32f = Finger::new(Params::<f32>::default()).unwrap();
    let a32: Vec<f32> = a64.iter().map(|&x| x as f32).collect();
    let t = Instant::now();
    let mut acc32 = 0.0f32;
    for _ in 0..n {
        acc32 += solve_pose(&f32f, std::hint::black_box(&a32), None).unwrap().tension;
    }
    let us32 = t.elapsed().as_secs_f64() / n as f64 * 1e6;
    let it = solve_pose(&f, &a64, None).unwrap().iterations;
    let it32 = solve_pose(&f32f, &a32, None).unwrap().iterations;
    writeln!(o, "\n## Cost\n").unwrap();
    writeln!(
        o,
        "`inverse::solve_pose` on one posture (Newton iterations in all: {} in f64, {it32} in f32): \
         {us64:.2} µs (f64) and {us32:.2} µs (f32) per solve on the host that generated this file (release build, mean of {n}; \
         checksum {:.3}/{:.3}). Instructions on the Cortex-M4F are measured in QEMU with the other \
         performance figures.\n",
        it,
        acc / n as f64,
        acc32 / n as f32
    )
    .unwrap();
    writeln!(
        o,
        "Every hinge model, the same posture (the default finger's at P = 1 N, 3/6/9 kV), tension free. \
         m = 1 with rigid links is the closed fast path; every other row the general path (root finding \
         on the forward per-joint equilibrium). Forward = one converged `Finger::solve` at the same \
         parameters, for scale. Host µs, release build, mean of the count shown.\n"
    )
    .unwrap();
    writeln!(o, "| m | plate | flexible links | path | Newton iterations f64 / f32 | inverse µs f64 | inverse µs f32 | forward µs f64 | inverse / forward |")
        .unwrap();
    writeln!(o, "| --- | --- | --- | --- | --- | --- | --- | --- | --- |").unwrap();
    for m in [1usize, 4, 8] {
        for (plate, flex_links) in [(false, false), (true, false), (true, true)] {
            let p = Params { m, plate, flex_links, ..d };
            let f = Finger::new(p).unwrap();
            let v = [3000.0, 6000.0, 9000.0];
            let s = f.solve(1.0, &v, Method::converged()).unwrap();
            let a = s.joint_angles().to_vec();
            let f32f = Finger::new(Params { m, plate, flex_links, ..Params::<f32>::default() }).unwrap();
            let a32: Vec<f32> = a.iter().map(|&x| x as f32).collect();
            let fast = m == 1 && !flex_links;
            let reps = if fast { 20_000 } else { 2_000 };
            let t = Instant::now();
            let mut acc = 0.0;
            for _ in 0..reps {
                acc += solve_pose(&f, std::hint::black_box(&a), None).unwrap().tension;
            }
            let inv64 = t.elapsed().as_secs_f64() / reps as f64 * 1e6;
            let t = Instant::now();
            let mut acc32 = 0.0f32;
            for _ in 0..reps {
                acc32 += solve_pose(&f32f, std::hint::black_box(&a32), None).unwrap().tension;
            }
            let inv32 = t.elapsed().as_secs_f64() / reps as f64 * 1e6;
            let t = Instant::now();
            for _ in 0..reps {
                acc += f.solve(1.0, std::hint::black_box(&v), Method::converged()).unwrap().tension;
            }
            let fw = t.elapsed().as_secs_f64() / reps as f64 * 1e6;
            std::hint::black_box((acc, acc32));
            let it = solve_pose(&f, &a, None).unwrap().iterations;
            let it32 = solve_pose(&f32f, &a32, None).unwrap().iterations;
            writeln!(
                o,
                "| {m} | {} | {} | {} | {it} / {it32} | {inv64:.1} | {inv32:.1} | {fw:.1} | {:.1} |",
                plate as u8,
                flex_links as u8,
                if fast { "fast" } else { "general" },
                inv64 / fw
            )
            .unwrap();
        }
    }
    std::fs::write(&path, o).unwrap();
    println!("wrote {path}");
    // the front page's finding (README.md, between its markers), from the board's finger
    if let (Some((k_0v, k_top, _)), true) = (board, std::env::args().nth(1).is_none()) {
        let readme = "../README.md";
        let text = std::fs::read_to_string(readme).unwrap();
        let (begin, end) = ("<!-- BEGIN generated by host-tests stiffness_range: the finding -->\n", "<!-- END generated -->");
        let (a, b) = (text.find(begin).expect("README's finding markers") + begin.len(), text.find(end).expect("README's finding markers"));
        let line = format!(
            "**On the board's film, VHB 4905, the whole voltage range changes this finger's tip stiffness by {:.1} %** \
             (k_yy, all three joints at {deg}°, the board's calibrated finger: [docs/inverse-tables.md](docs/inverse-tables.md), \
             generated). The stacks' film is too soft to stiffen the joints it sits on, so a voltage can thin a stack but \
             barely change how stiff the finger is; [docs/materials.md](docs/materials.md) says why and what film would.\n",
            100.0 * (k_0v / k_top - 1.0)
        );
        std::fs::write(readme, format!("{}{line}{}", &text[..a], &text[b..])).unwrap();
        println!("wrote {readme} (the finding)");
    }
}
