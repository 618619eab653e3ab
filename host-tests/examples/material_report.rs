//! The generated part of docs/materials.md (below its `<!-- generated below: ... -->` line):
//! per card the pull-in and hold ceilings for the board's layer, s_hold; each integrator's
//! thickness error against the f64 reference on step, ramp and random histories, with its
//! cost (host ns and, from the bench image `bench/src/bin/material.rs` in QEMU, M4F and M3
//! instructions per channel-tick); the shaped actuation's settling time against a plain step.
//!
//! `cd host-tests && cargo run --release --example material_report`

use finger_model::material::drive::{Channel, DriveLimits, Mode};
use finger_model::material::{
    equilibrium_pull_in_voltage, equilibrium_ratio, equilibrium_voltage, guarded_tick, hold_ceiling, hold_ratio, ratio_at_voltage,
    reference::advance_reference, voltage_at_ratio, Card, Integrator, Relaxation, StackLaw, StackState, CARDS, LIMIT_RATIO, VHB_4905,
};
use finger_model::params::EPS0;
use host_tests::perf::{build, read_bench, run_qemu, M3, M4F};
use std::fmt::Write as _;
use std::time::Instant;

/// The board's layer (src/board.rs: BOARD_Z0_MM, BOARD_MARGIN) and supply.
const Z0: f64 = 0.5;
const MARGIN: f64 = 0.9;
const SUPPLY: f64 = 10_000.0;
const MARKER: &str = "<!-- generated below:";

fn law<R: finger_model::Real>(card: &Card) -> StackLaw<R> {
    StackLaw::new(card, R::from_f64(Z0), R::from_f64(MARGIN)).expect("card")
}

fn cards_section(doc: &mut String) {
    writeln!(doc, "## Ceilings per card (one layer, z0 = {Z0} mm, margin {MARGIN})\n").unwrap();
    writeln!(
        doc,
        "Volts per layer. *pull-in, relaxed*: the end of the relaxed film's stable branch \
         (s = 4^(-1/3) = 0.630); *2/3, relaxed* and *2/3, instant*: the voltage that holds the film at \
         the 33 % limit once fully relaxed and at the first instant (branches unrelaxed); *breakdown at \
         2/3*: E_B(2/3) x 2/3 z0; *hold ceiling*: margin x min(2/3 relaxed, breakdown at 2/3); \
         *s_hold*: the relaxed thickness stretch at the hold ceiling, the thinnest a held voltage ever \
         gets; *linear law*: docs/model.md's linear balance E (1 - s) = eps V^2 / (s z0)^2 (E = 2 G_eq (1 + 0.49)), \
         its pull-in at s = 2/3, for comparison.\n"
    )
    .unwrap();
    writeln!(doc, "| card | G_eq kPa | branches G kPa : tau s | eps_r | E_B0 V/um | pull-in, relaxed | 2/3, relaxed | 2/3, instant | breakdown at 2/3 | hold ceiling | s_hold | linear law pull-in |").unwrap();
    writeln!(doc, "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |").unwrap();
    for card in CARDS {
        let l = law::<f64>(card);
        let s = LIMIT_RATIO;
        let branches: Vec<String> = card.branches().iter().map(|b| format!("{:.2} : {}", b.g_mpa * 1e3, b.tau_s)).collect();
        let instant = voltage_at_ratio(&l, &[1.0; 3], s).unwrap();
        let e_lin = 2.0 * card.g_eq_mpa * 1.49;
        let v_lin = (4.0 * e_lin * Z0 * Z0 / (27.0 * EPS0 * card.eps_r)).sqrt();
        writeln!(
            doc,
            "| {} | {:.2} | {} | {} | {} | {:.0} | {:.0} | {:.0} | {:.0} | **{:.0}** | {:.4} | {:.0} |",
            card.name,
            card.g_eq_mpa * 1e3,
            if branches.is_empty() { "none".to_string() } else { branches.join(", ") },
            card.eps_r,
            card.breakdown.field0_v_per_um,
            equilibrium_pull_in_voltage(&l),
            equilibrium_voltage(&l, s).unwrap(),
            instant,
            l.breakdown_volts(s),
            hold_ceiling(&l, l.margin),
            hold_ratio(&l).unwrap(),
            v_lin
        )
        .unwrap();
    }
    writeln!(doc).unwrap();
}

/// A voltage history sampled at tick starts.
struct History {
    volts: Box<dyn Fn(f64) -> f64>,
}

fn histories() -> Vec<History> {
    let hold = hold_ceiling(&law::<f64>(&VHB_4905), MARGIN);
    let mut v = vec![History { volts: Box::new(|_| 5000.0) }, History { volts: Box::new(|t| 6000.0 * (t / 5.0).min(1.0)) }];
    // random: piecewise constant, 4-20 s segments, 0..hold ceiling (fixed seed)
    let mut rng = finger_model_testkit::material::Rng(0x2545_F491_4F6C_DD1D);
    let mut rnd = move || rng.next();
    for _ in 0..4 {
        let mut segs = Vec::new();
        let mut t = 0.0;
        while t < 120.0 {
            segs.push((t, hold * rnd()));
            t += 4.0 + 16.0 * rnd();
        }
        v.push(History { volts: Box::new(move |t| segs.iter().rev().find(|s| s.0 <= t).map_or(0.0, |s| s.1)) });
    }
    v
}

/// Max |z - z_ref| (um) and max relative thinning error over one 120 s history, ticks of `dt`.
fn error_vs_reference(h: &History, integrator: Integrator, dt: f64, reference: &[f64]) -> (f64, f64) {
    let l = law::<f32>(&VHB_4905);
    let relax = Relaxation::with_integrator(&l, dt as f32, integrator).unwrap();
    let mut st = StackState::<f32>::rest();
    let (mut dz, mut rel) = (0f64, 0f64);
    for (k, s_ref) in reference.iter().enumerate() {
        st.advance(&l, &relax, (h.volts)(k as f64 * dt) as f32).unwrap();
        let s = st.s as f64;
        dz = dz.max((s - s_ref).abs() * Z0 * 1e3);
        if 1.0 - s_ref > 1e-3 {
            rel = rel.max(((1.0 - s) - (1.0 - s_ref)).abs() / (1.0 - s_ref));
        }
    }
    (dz, rel)
}

fn reference_run(h: &History, dt: f64) -> Vec<f64> {
    let l = law::<f64>(&VHB_4905);
    let sub = ((dt / 0.5e-3).round() as u32).max(2);
    let mut st = StackState::<f64>::rest();
    (0..(120.0 / dt).round() as usize)
        .map(|k| {
            advance_reference(&l, &mut st, (h.volts)(k as f64 * dt), dt, sub).unwrap();
            st.s
        })
        .collect()
}

fn host_ns_per_tick(integrator: Integrator) -> f64 {
    let l = law::<f32>(&VHB_4905);
    let relax = Relaxation::with_integrator(&l, 0.001, integrator).unwrap();
    let s_hold = hold_ratio(&l).unwrap();
    let hold = hold_ceiling(&l, l.margin);
    let mut st = StackState::<f32>::rest();
    let n = 2_000_000u32;
    let t0 = Instant::now();
    for k in 0..n {
        let v = std::hint::black_box(hold * ((k % 4000) as f32 / 4000.0));
        let _ = std::hint::black_box(guarded_tick(&l, &relax, &mut st, v, s_hold));
    }
    t0.elapsed().as_nanos() as f64 / n as f64
}

/// Instructions per call from the bench image: (integrator, case) -> instructions.
fn target_counts(triple: &str, machine: &str, shift: u32) -> Result<Vec<(String, String, f64)>, String> {
    let elf = build("material", triple, "de,f32", &format!("material-{triple}"))?;
    let out = run_qemu(&elf, machine, shift)?;
    let bench = read_bench(&out)?;
    let mut v = Vec::new();
    for f in bench.lines.iter().filter(|f| f[0] == "T") {
        let ticks: f64 = f[3].parse().map_err(|_| "ticks")?;
        let n: f64 = f[4].parse().map_err(|_| "count")?;
        v.push((f[1].to_string(), f[2].to_string(), (bench.instructions(ticks) / n).round()));
    }
    Ok(v)
}

fn integrator_section(doc: &mut String) {
    writeln!(doc, "## The per-tick integration against the f64 reference (VHB 4905)\n").unwrap();
    writeln!(
        doc,
        "Each tick (the firmware's, `material::StackState::advance` in f32): the thickness at the \
         tick's voltage from the film balance (Newton warm-started from the last tick), then the \
         branches relaxed over the tick at that thickness by the integrator. The reference \
         (`material::reference`, f64): the same held voltages, RK4 on the branch flow in 0.5 ms \
         substeps with the balance solved at every stage. Errors over 120 s of each history, at every \
         tick: the largest thickness error of one layer (um, z0 = {Z0} mm) and the largest error of \
         the thinning 1 - s relative to the reference's (where it exceeds 0.1 %). Histories: a 5 kV \
         step held, a ramp 0 -> 6 kV in 5 s held, four random piecewise-constant histories below the \
         hold ceiling. Cost: host ns per channel-tick (`guarded_tick`, this machine, release) and \
         instructions per channel-tick on the Cortex-M4F (f32, FPU) and the Cortex-M3 (f32 in \
         software), counted in QEMU (`bench/src/bin/material.rs`: a ramp to the hold ceiling, then a \
         held voltage; *relax* is the relaxation alone).\n"
    )
    .unwrap();
    let hs = histories();
    let counts = |triple, machine, shift| match target_counts(triple, machine, shift) {
        Ok(v) => v,
        Err(e) => panic!("bench image on {triple}: {e}"),
    };
    let m4f = counts(M4F, "netduinoplus2", 0);
    let m3 = counts(M3, "mps2-an385", 4);
    let instr = |v: &[(String, String, f64)], i: Integrator, case: &str| {
        v.iter().find(|r| r.0 == i.name() && r.1 == case).map_or("-".to_string(), |r| format!("{:.0}", r.2))
    };
    writeln!(doc, "| integrator | tick | max thickness error um (step / ramp / random) | max thinning error % (step / ramp / random) | host ns per channel-tick | M4F instr (ramp / hold / relax) | M3 instr (ramp / hold / relax) |").unwrap();
    writeln!(doc, "| --- | --- | --- | --- | --- | --- | --- |").unwrap();
    let ns: Vec<f64> = Integrator::ALL.iter().map(|&i| host_ns_per_tick(i)).collect();
    for dt in [0.001, 0.01, 0.1] {
        let refs: Vec<Vec<f64>> = hs.iter().map(|h| reference_run(h, dt)).collect();
        for (ii, &integrator) in Integrator::ALL.iter().enumerate() {
            let errs: Vec<(f64, f64)> = hs.iter().zip(&refs).map(|(h, r)| error_vs_reference(h, integrator, dt, r)).collect();
            let random = errs[2..].iter().fold((0f64, 0f64), |a, e| (a.0.max(e.0), a.1.max(e.1)));
            let cost = if dt == 0.001 {
                (
                    format!("{:.0}", ns[ii]),
                    format!("{} / {} / {}", instr(&m4f, integrator, "ramp"), instr(&m4f, integrator, "hold"), instr(&m4f, integrator, "relax")),
                    format!("{} / {} / {}", instr(&m3, integrator, "ramp"), instr(&m3, integrator, "hold"), instr(&m3, integrator, "relax")),
                )
            } else {
                ("same".into(), "same".into(), "same".into())
            };
            writeln!(
                doc,
                "| {} | {} ms | {:.3} / {:.3} / {:.3} | {:.3} / {:.3} / {:.3} | {} | {} | {} |",
                integrator.name(),
                dt * 1e3,
                errs[0].0,
                errs[1].0,
                random.0,
                errs[0].1 * 100.0,
                errs[1].1 * 100.0,
                random.1 * 100.0,
                cost.0,
                cost.1,
                cost.2
            )
            .unwrap();
        }
    }
    writeln!(doc).unwrap();
}

/// Settling time (s) from rest with the control tick's step at 1 ms (`material::drive`, the
/// firmware's), `slew` V/s (`None`: no slew limit): the time after which the predicted thickness
/// stays within 1 % of the target thickness (`thickness`) or of the target thinning. Returns
/// (settling time within the horizon, peak voltage).
fn settle(card: &Card, target_v: f64, mode: Mode, slew: Option<f64>, thickness: bool) -> (Option<f64>, f64) {
    let l = law::<f32>(card);
    let dt = 0.001f32;
    let relax = Relaxation::new(&l, dt).unwrap();
    let lim = DriveLimits { s_hold: hold_ratio(&l).unwrap(), slew_step: slew.map_or(f32::INFINITY, |r| r as f32 * dt), v_cap: SUPPLY as f32 };
    let target = target_v as f32;
    let s_t = equilibrium_ratio(&l, target).unwrap();
    let band = if thickness { 0.01 * s_t } else { 0.01 * (1.0 - s_t) };
    let mut ch = Channel::<f32>::rest();
    let mut peak = 0f32;
    let mut settled_at = None;
    for k in 1..=(HORIZON_S / dt as f64) as u64 {
        ch.step(&l, &relax, &lim, mode, target, s_t).unwrap();
        peak = peak.max(ch.volts);
        let inside = (ch.state.s - s_t).abs() <= band;
        match (inside, settled_at) {
            (true, None) => settled_at = Some(k as f64 * dt as f64),
            (false, Some(_)) => settled_at = None,
            _ => {}
        }
    }
    (settled_at, peak as f64)
}

const HORIZON_S: f64 = 900.0;

fn settling_section(doc: &mut String) {
    writeln!(doc, "## Shaped actuation: settling time against a plain step\n").unwrap();
    writeln!(
        doc,
        "From rest, the control tick's step at 1 ms (`material::drive::Channel::step`, the \
         firmware's), f32. *Plain*: the setpoint goes to the target voltage, as a step or slewed at \
         the firmware's default 2,000 V/s (the guard's floor s_hold). *Shaped*: the goal is the \
         voltage that holds the target thickness now (`material::shaped_voltage`, capped by the \
         {SUPPLY:.0} V supply; the guard's floor the target thickness, so the breakdown bound there \
         applies), as a step or slewed at 2,000 V/s. Settling: the time after which the predicted \
         thickness stays within 1 % of the target thickness, and (stricter) within 1 % of the target \
         thinning 1 - s; simulated for {HORIZON_S:.0} s (*> {HORIZON_S:.0}*: not settled by then). \
         Targets: fractions of the ceiling in force, min(the card's hold ceiling, the supply). Times \
         in s.\n"
    )
    .unwrap();
    writeln!(doc, "| card | target V | target s | plain step (1 % z / 1 % thinning) | plain 2 kV/s (1 % z) | shaped step (1 % z / 1 % thinning) | shaped 2 kV/s (1 % z) | shaped peak V |").unwrap();
    writeln!(doc, "| --- | --- | --- | --- | --- | --- | --- | --- |").unwrap();
    let show = |t: Option<f64>| t.map_or(format!("> {HORIZON_S:.0}"), |t| format!("{t:.3}"));
    for card in CARDS {
        let l = law::<f64>(card);
        let ceiling = hold_ceiling(&l, l.margin).min(SUPPLY);
        for frac in [0.5, 0.8, 1.0] {
            let v = (ceiling * frac * (1.0 - 1e-6)).floor();
            let s_t = equilibrium_ratio(&l, v).unwrap();
            let (p_z, _) = settle(card, v, Mode::Plain, None, true);
            let (p_thin, _) = settle(card, v, Mode::Plain, None, false);
            let (slew_z, _) = settle(card, v, Mode::Plain, Some(2000.0), true);
            let (sh_z, peak) = settle(card, v, Mode::Shaped, None, true);
            let (sh_thin, _) = settle(card, v, Mode::Shaped, None, false);
            let (sh_slew_z, _) = settle(card, v, Mode::Shaped, Some(2000.0), true);
            writeln!(
                doc,
                "| {} | {v:.0} | {s_t:.4} | {} / {} | {} | {} / {} | {} | {peak:.0} |",
                card.name,
                show(p_z),
                show(p_thin),
                show(slew_z),
                show(sh_z),
                show(sh_thin),
                show(sh_slew_z)
            )
            .unwrap();
        }
    }
    writeln!(doc).unwrap();
}

fn main() {
    let mut doc = String::new();
    writeln!(doc).unwrap();
    cards_section(&mut doc);
    settling_section(&mut doc);
    integrator_section(&mut doc);
    // sanity of what is printed: the board card's instant response is stiffer than relaxed
    let l = law::<f64>(&VHB_4905);
    assert!(ratio_at_voltage(&l, &[1.0; 3], 5000.0, 1.0).unwrap() > equilibrium_ratio(&l, 5000.0).unwrap());
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/materials.md");
    let old = std::fs::read_to_string(&path).unwrap_or_default();
    let head = match old.find(MARKER) {
        Some(i) => {
            let end = old[i..].find('\n').map_or(old.len(), |j| i + j + 1);
            old[..end].to_string()
        }
        None => format!("{old}{MARKER} cd host-tests && cargo run --release --example material_report -->\n"),
    };
    std::fs::write(&path, format!("{head}{doc}")).expect("write docs/materials.md");
    print!("{doc}");
}
