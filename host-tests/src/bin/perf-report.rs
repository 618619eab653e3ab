//! perf-report: error against run time for every solver variant, and flash/RAM of lean
//! images. Writes docs/performance.md and docs/perf-error-vs-instructions.svg.
//!
//! `cd host-tests && cargo run --release --bin perf-report` (needs qemu-system-arm and the
//! rustup targets thumbv7em-none-eabihf and thumbv7m-none-eabi; takes a few minutes).
//!
//! - Target instructions: the bench images (bench/) built for the Cortex-M4F (netduinoplus2)
//!   and the Cortex-M3 (mps2-an385), run in QEMU with `-icount` (see host_tests::perf).
//! - Errors: tip position (mm) and joint angles (degrees) against the host's f64 converged
//!   solution at 1e-12 mm.
//! - Host nanoseconds: criterion (benches/host_solve.rs, run from here), its median estimate
//!   per variant; bench profile (the release settings), inputs through `black_box`.

use finger_model::{Finger, Method, Params, Real};
use host_tests::perf::{self, scenes::N_INC, scenes::SCENES, Rec, IMAGES};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// The paper's scenes (0.2..1.0 N, paper's model): the error and instruction summaries use
/// these; the two high-tension scenes and the fidelity-model scenes are reported separately.
fn is_paper_scene(name: &str) -> bool {
    !(name.starts_with("bare-7N") || name.starts_with("bare-250N") || name.contains("-fid"))
}

fn method_label(m: &str) -> String {
    match m.strip_prefix("step") {
        Some(n) => format!("stepping n_inc={n}"),
        None => "converged".into(),
    }
}

/// Host ns per solve per scalar, (scene, method): criterion's median estimate from
/// benches/host_solve.rs, which this runs (`cargo bench`; estimates under target/criterion).
fn host_times(root: &Path) -> [BTreeMap<(String, String), f64>; 2] {
    let home = root.join("target").join("criterion");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let st = std::process::Command::new(cargo)
        .current_dir(root.join("host-tests"))
        .env("CRITERION_HOME", &home)
        .args(["bench", "--quiet", "--bench", "host_solve"])
        .stdout(std::process::Stdio::null())
        .status()
        .expect("cargo bench");
    assert!(st.success(), "cargo bench --bench host_solve failed");
    ["f64", "f32"].map(|scalar| {
        let mut out = BTreeMap::new();
        for s in SCENES {
            for m in perf::host_methods() {
                let f = home.join(perf::bench_group(scalar)).join(perf::bench_id(s.name, &m)).join("new/estimates.json");
                let Ok(text) = std::fs::read_to_string(&f) else { continue };
                let v: serde_json::Value = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
                if let Some(ns) = v["median"]["point_estimate"].as_f64() {
                    out.insert((s.name.to_string(), m), ns);
                }
            }
        }
        out
    })
}

struct Row {
    rec: Rec,
    tip_err: Option<f64>,
    ang_err: Option<f64>,
}

fn fmt_e(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else {
        format!("{x:.2e}")
    }
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut refs = BTreeMap::new();
    for s in SCENES {
        refs.insert(s.name.to_string(), perf::reference(s));
    }

    // ---- target runs
    let mut rows: Vec<Row> = Vec::new();
    let mut cal_notes = Vec::new();
    let mut warm = Vec::new();
    for img in IMAGES {
        eprintln!("perf-report: building and running {} ({})", img.name, img.features);
        let elf = perf::build("finger-bench", img.triple, img.features, img.name).unwrap_or_else(|e| panic!("{e}"));
        let out = perf::run_qemu(&elf, img.machine, img.shift).unwrap_or_else(|e| panic!("{e}"));
        let recs = perf::parse(img, &out).unwrap_or_else(|e| panic!("{}: {e}", img.name));
        warm.extend(warm_rows(img, &out));
        let cal = out.lines().find(|l| l.starts_with("CAL")).unwrap_or("").to_string();
        cal_notes.push(format!("{}: `{}`", img.name, cal));
        for rec in recs {
            let (tip_err, ang_err) = match (&rec.result, refs.get(&rec.scene)) {
                (Ok((tip, ang, _)), Some(Ok(r))) => {
                    let (t, a) = perf::errors(*tip, *ang, r);
                    (Some(t), Some(a))
                }
                _ => (None, None),
            };
            rows.push(Row { rec, tip_err, ang_err });
        }
    }

    // ---- host timings
    eprintln!("perf-report: host timings");
    let [host64, host32] = host_times(&root);

    // ---- lean images
    eprintln!("perf-report: lean images");
    let lean: &[(&str, &str, &str, &str, u32)] = &[
        ("M4F f32 libm, DE", perf::M4F, "de", "netduinoplus2", 0),
        ("M4F f32 libm, no DE", perf::M4F, "", "netduinoplus2", 0),
        ("M4F f32 fast-trig, no DE", perf::M4F, "fast-trig", "netduinoplus2", 0),
        ("M4F f32 micromath, DE", perf::M4F, "de,micromath", "netduinoplus2", 0),
        ("M4F f32 micromath, no DE", perf::M4F, "micromath", "netduinoplus2", 0),
        ("M3 f32 soft-float libm, no DE", perf::M3, "", "mps2-an385", 4),
        ("M3 f32 soft-float micromath, no DE", perf::M3, "micromath", "mps2-an385", 4),
        ("M3 fixed I16F16 (setup in f32), no DE", perf::M3, "fixed", "mps2-an385", 4),
        ("M3 fixed I16F16 (setup in f32), DE", perf::M3, "fixed,de", "mps2-an385", 4),
    ];
    let mut lean_rows = Vec::new();
    for (i, (label, triple, feats, machine, shift)) in lean.iter().enumerate() {
        let name = format!("lean-{i}");
        let elf = perf::build("lean", triple, feats, &name).unwrap_or_else(|e| panic!("{e}"));
        let (flash, ram) = perf::elf_sizes(&elf).unwrap_or_else(|e| panic!("{e}"));
        let out = perf::run_qemu(&elf, machine, *shift).unwrap_or_else(|e| panic!("{e}"));
        let y = out.lines().find_map(|l| u64::from_str_radix(l.trim(), 16).ok()).map(f64::from_bits).unwrap_or(f64::NAN);
        lean_rows.push((label.to_string(), feats.to_string(), flash, ram, y));
    }

    // ---- stepping study on the host (f64)
    let tensions = [0.2, 0.5, 1.0, 2.0, 4.0, 7.0, 10.0, 20.0, 50.0, 100.0, 250.0];
    let n_incs = [1u32, 2, 5, 10, 20, 50, 100, 200, 1000];
    // the paper's model, pinned (as the scenes are)
    let f = Finger::new(Params::<f64> { m: 1, plate: false, flex_links: false, ..Params::default() }.without_stacks()).unwrap();
    let mut study = Vec::new();
    for &p in &tensions {
        let reference = f.solve(p, &[0.0; 3], Method::Converged { tol: 1e-12, max_iter: 400 });
        let mut cells = Vec::new();
        for &n in &n_incs {
            let cell = match (&reference, f.solve(p, &[0.0; 3], Method::Stepping { n_inc: n })) {
                (Ok(r), Ok(s)) => {
                    let (rt, st) = (r.tip(), s.tip());
                    Ok((st.x - rt.x, st.y - rt.y, (s.joint_angle[0] - r.joint_angle[0]).to_degrees()))
                }
                (_, Err(e)) => Err(e.code().to_string()),
                (Err(e), _) => Err(format!("ref {}", e.code())),
            };
            cells.push(cell);
        }
        study.push((p, cells));
    }

    // ---- the inverse: the same table as docs/inverse-cost.md
    eprintln!("perf-report: inverse images");
    let inverse_table = perf::inverse_cost_table();

    let mut md = report(&rows, &host64, &host32, &lean_rows, &study, &n_incs, &cal_notes);
    let section = format!(
        "## The inverse model on the Cortex-M4F\n\n\
         Instructions per `inverse::solve_pose` in f32 (joint angles, optionally a tension, to the tension \
         and three voltages; without a tension also both ends of the feasible tension interval), QEMU \
         netduinoplus2 with `-icount shift=0`, bench image `bench/src/bin/inverse.rs`; the same table as \
         docs/inverse-cost.md (`cargo run --release --example inverse_cost`), docs/inverse.md (\"Cost on the \
         target\") says what bounds it. `m1-rigid`: the paper's model (m = 1, E_b, rigid links); \
         `m8-plate-flex`: the default (m = 8, plate modulus, flexible links). Target: at most 20,000 on the \
         firmware's path (the last column). The untabled columns end with the forward solve from rest at \
         the answer (docs/inverse.md \"Reached from rest\": an answer the finger does not reach is \
         refused), which the tabled path does not need: 13,000 to 19,000 (m = 1) and 20,000 to 39,000 (m = 8) of theirs.\n\n{inverse_table}\n"
    );
    let section = format!("{section}{}\n", warm_section(&rows, &warm));
    // ---- the branch-table path
    eprintln!("perf-report: branch-table image");
    let section = format!("{section}{}\n", perf::table_cost_section());
    // ---- contact
    eprintln!("perf-report: contact image");
    let section = format!("{section}{}\n", perf::contact_cost_section());
    match md.find("## Stability tests") {
        Some(i) => md.insert_str(i, &section),
        None => md.push_str(&section),
    }
    let previous = std::fs::read_to_string(root.join("docs/performance.md")).unwrap_or_default();
    md.push_str(&moved(&previous, &md));
    std::fs::write(root.join("docs/performance.md"), md).unwrap();
    std::fs::write(root.join("docs/perf-error-vs-instructions.svg"), plot(&rows)).unwrap();
    eprintln!("perf-report: wrote docs/performance.md and docs/perf-error-vs-instructions.svg");
}

/// A bench image's `W` lines (the forward under gravity started from an earlier answer) in the
/// firmware's image (m4f-fasttrig), as table rows: image, scene, scalar, case, instructions, iterations, tip moved (mm) or
/// the error code.
fn warm_rows(img: &perf::Image, out: &str) -> Vec<[String; 7]> {
    let Ok(bench) = perf::read_bench(out) else { return Vec::new() };
    if img.name != "m4f-fasttrig" {
        return Vec::new();
    }
    let mut rows = Vec::new();
    for f in bench.lines.iter().filter(|f| f.first() == Some(&"W") && f.len() >= 6) {
        let instr = f[5].parse::<f64>().map(|t| format!("{:.0}", bench.instructions(t))).unwrap_or_else(|_| "-".into());
        let (iters, moved) = match (f[4], f.get(6), f.get(7)) {
            ("ok", Some(i), Some(m)) => (i.to_string(), m.parse::<f64>().map(|m| format!("{m:.1e}")).unwrap_or_else(|_| "-".into())),
            _ => ("-".into(), format!("err {}", f.get(6).copied().unwrap_or("?"))),
        };
        rows.push([img.name.to_string(), f[1].to_string(), f[2].to_string(), f[3].to_string(), instr, iters, moved]);
    }
    rows
}

/// The section on the forward under gravity started from an earlier answer (`W` lines).
fn warm_section(rows: &[Row], warm: &[[String; 7]]) -> String {
    let mut s = String::from(
        "## The forward under gravity from the last answer on the Cortex-M4F\n\n\
         `Finger::solve_from` (the model's; the firmware does not use it, docs/model.md \"Gravity\" says why): \
         the coupled solve started from an earlier answer of the same finger (its coupled unknowns, \
         joints and Broyden Jacobian estimate, kept by the caller) instead of from the straight finger; Newton on the \
         carried estimate, forward differences at the start where that fails, the solve from straight where that \
         fails too (docs/model.md \"Gravity\"). Bench image `bench/src/main.rs` (`warm_starts`), the gravity scenes at \
         their tension and voltages, after solves not counted: `again`, the same solve before; `from-0.9P`, one at 0.9 \
         of the tension (the estimate carried from the solve from straight); `from-0.5P-0.9P`, two before (the \
         estimate carried from the second); `from-0V`, one with the stacks at 0 V; `from-0V-0.9P`, one at 0 V then one at 0.9 of the tension. \
         *cold*: the same scene's converged solve from straight (the tables above). *tip moved*: from the cold \
         answer's tip, mm.\n\n\
         **What bounds it** (QEMU's per-instruction trace of the `-g0` scene's cold solve, f32/fast-trig, 114,980): the marches (3 joints of 8 sub-elements; the 12 forward-difference columns, each resumed where its unknown enters, and 4 whole evaluations) about 32,000; two 12 x 12 LU factorizations about 16,000; the evaluations' chain, loads and centroids about 19,000; the answer's assembly (the chain, and each joint's tangent determinant by a dual march) about 14,000; zeroing and copying about 21,000 (residuals and states returned by value, the evaluation's per-slot states set up). From the last answer the Jacobian is carried (no forward differences): one or two iterations, 46,000 to 67,000; asked again, one evaluation and the assembly, 29,000. So the issue's 10,000 is not reached: below about 20,000 (one evaluation of the full model and the assembly) the answer would have to drop the tangent determinants or march fewer than m sub-elements.\n\n\
         | image | scene | scalar | from | instructions | cold | iterations | tip moved mm |\n| --- | --- | --- | --- | ---: | ---: | ---: | ---: |\n",
    );
    for [image, scene, scalar, case, instr, iters, moved] in warm {
        let cold = rows
            .iter()
            .find(|r| &r.rec.image == image && &r.rec.scene == scene && &r.rec.scalar == scalar && r.rec.method == "conv")
            .map_or("-".to_string(), |r| format!("{:.0}", r.rec.instr));
        s.push_str(&format!("| {image} | {scene} | {scalar} | {case} | {instr} | {cold} | {iters} | {moved} |\n"));
    }
    s
}

/// Series key: image + scalar.
fn series(r: &Rec) -> String {
    format!("{} {}", r.core, r.scalar)
}

struct Summary {
    instr_mean: f64,
    instr_max: f64,
    tip_max: f64,
    ang_max: f64,
    fails: usize,
    n: usize,
}

fn summarize<'a>(rows: impl Iterator<Item = &'a Row>) -> Summary {
    let mut s = Summary { instr_mean: 0.0, instr_max: 0.0, tip_max: 0.0, ang_max: 0.0, fails: 0, n: 0 };
    for r in rows {
        s.n += 1;
        s.instr_mean += r.rec.instr;
        s.instr_max = s.instr_max.max(r.rec.instr);
        match (r.tip_err, r.ang_err) {
            (Some(t), Some(a)) => {
                s.tip_max = s.tip_max.max(t);
                s.ang_max = s.ang_max.max(a);
            }
            _ => s.fails += 1,
        }
    }
    if s.n > 0 {
        s.instr_mean /= s.n as f64;
    }
    s
}

fn methods_in_order() -> Vec<String> {
    N_INC.iter().map(|n| format!("step{n}")).chain(std::iter::once("conv".into())).collect()
}

fn report(
    rows: &[Row],
    host64: &BTreeMap<(String, String), f64>,
    host32: &BTreeMap<(String, String), f64>,
    lean: &[(String, String, u64, u64, f64)],
    study: &[(f64, Vec<Result<(f64, f64, f64), String>>)],
    n_incs: &[u32],
    cal: &[String],
) -> String {
    let mut o = String::new();
    let w = &mut o;
    writeln!(w, "# Performance: error against run time, stability, lean builds\n").unwrap();
    writeln!(w, "Generated by `cd host-tests && cargo run --release --bin perf-report` (a few minutes; needs").unwrap();
    writeln!(w, "`qemu-system-arm` and the rustup targets `thumbv7em-none-eabihf`, `thumbv7m-none-eabi`). Do not edit by hand.\n").unwrap();
    writeln!(w, "## How it is measured\n").unwrap();
    writeln!(
        w,
        "- **Scenes** (`host-tests/scenes`, crate finger-scenes): docs/model.md's default finger, without (`bare`) and with (`de`) DE stacks, the paper's"
    )
    .unwrap();
    writeln!(w, "  loads 0.2, 0.5, 1.0 N, uniform (8 kV) and per-joint (9/5/0 kV) voltages, and two high tensions: 7 N and").unwrap();
    writeln!(w, "  250 N (the links touch at about 300 N). The hinge model is pinned to the paper's (m = 1, E_b, rigid").unwrap();
    writeln!(w, "  links); two `-fid` scenes use the fidelity model (m = 8, plate modulus, flexible links) to show its cost, and two more put it under gravity (docs/model.md \"Gravity\"): `-g0` hanging straight down (the board's default), `-g90` held horizontally; the joints are then coupled and the converged solve is the coupled one.").unwrap();
    writeln!(w, "- **Instructions on the target**: the bench image (`bench/`, its own `no_std` binary, not the firmware) runs every").unwrap();
    writeln!(w, "  scene in QEMU 7.2 with `-icount` (deterministic: one instruction, one fixed virtual time step) and reads").unwrap();
    writeln!(w, "  SysTick around each `Finger::solve_with` (equilibrium, posture, excursion; the compliances for the scene's").unwrap();
    writeln!(w, "  voltages are computed before, once per voltage change, and reported as *setup*). Ticks per instruction are").unwrap();
    writeln!(w, "  calibrated in each image on a loop of 2,000,000 known instructions; the timing overhead is subtracted.").unwrap();
    writeln!(w, "  Cortex-M4F: `netduinoplus2`, `-icount shift=0`. Cortex-M3 (no FPU): `mps2-an385`, `-icount shift=4`").unwrap();
    writeln!(w, "  (its 25 MHz SysTick is too coarse at shift 0 for the calibration; `lm3s6965evb` stops SysTick: period zero).").unwrap();
    writeln!(w, "  Instruction counts, not cycles: a `vdiv.f32` counts 1 (14 cycles on the silicon), a flash wait state 0.").unwrap();
    writeln!(w, "  Calibration lines (`CAL loop_instructions ticks overhead_ticks`): {}.", cal.join("; ")).unwrap();
    writeln!(w, "- **Errors**: tip position (mm, Euclidean) and the largest joint-angle error (degrees) against the host's f64").unwrap();
    writeln!(w, "  converged solution at 1e-12 mm.").unwrap();
    writeln!(w, "- **Host nanoseconds**: criterion (`host-tests/benches/host_solve.rs`, which this command runs with `cargo bench`),").unwrap();
    writeln!(w, "  the median estimate per variant (30 samples over 0.3 s after 0.1 s of warm-up); bench profile (the release").unwrap();
    writeln!(
        w,
        "  settings), inputs through `black_box`; same `solve_with` call as on the target. Host f32 uses `{}`; micromath and fixed point are",
        <f32 as Real>::NAME
    )
    .unwrap();
    writeln!(w, "  measured on the targets only. Host numbers vary with the machine and its load; target counts do not.").unwrap();
    writeln!(w, "- **Fixed point** (`bench/src/fix.rs`): `Real` for newtypes over the `fixed` crate's I16F16 and I32F32,").unwrap();
    writeln!(w, "  saturating arithmetic (MIN/MAX act as infinity, so overflow becomes a typed error), Taylor sin/cos after").unwrap();
    writeln!(w, "  reduction by pi/2, digit-by-digit integer sqrt. The hinge and joint compliances are computed once in f32 and").unwrap();
    writeln!(w, "  cast (`Finger::cast`, `Compliances::cast`): E w t^3 overflows I16F16 and eps0 = 8.9e-12 is below both").unwrap();
    writeln!(w, "  resolutions. The converged solver's tolerance is raised to the scalar's resolution.\n").unwrap();

    // ---- summary
    writeln!(w, "## Summary over the paper's scenes (0.2 to 1.0 N, 8 scenes)\n").unwrap();
    writeln!(w, "Instructions: mean and worst over the 8 scenes; errors: worst. Host ns: mean over the same scenes.\n").unwrap();
    writeln!(w, "| core | scalar | method | instructions (mean) | instructions (max) | tip error mm (max) | angle error deg (max) | failures | host ns |")
        .unwrap();
    writeln!(w, "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |").unwrap();
    let mut keys: Vec<(String, String, String)> = Vec::new();
    for r in rows {
        let k = (r.rec.core.clone(), r.rec.scalar.clone(), r.rec.image.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let mut best: Vec<(String, f64, f64)> = Vec::new();
    for (core, scalar, image) in &keys {
        for m in methods_in_order() {
            let sel = rows
                .iter()
                .filter(|r| &r.rec.core == core && &r.rec.scalar == scalar && &r.rec.image == image && r.rec.method == m && is_paper_scene(&r.rec.scene));
            let s = summarize(sel);
            if s.n == 0 {
                continue;
            }
            let host = if core == "M4F" && image == "m4f-libm" {
                let tab = if scalar.starts_with("f64") {
                    Some(host64)
                } else if scalar.starts_with("f32") {
                    Some(host32)
                } else {
                    None
                };
                tab.map(|t| {
                    let v: Vec<f64> = t.iter().filter(|((sc, mm), _)| mm == &m && is_paper_scene(sc)).map(|(_, v)| *v).collect();
                    format!("{:.0}", v.iter().sum::<f64>() / v.len().max(1) as f64)
                })
                .unwrap_or_default()
            } else {
                String::new()
            };
            writeln!(
                w,
                "| {core} | {scalar} | {} | {:.0} | {:.0} | {} | {} | {} | {host} |",
                method_label(&m),
                s.instr_mean,
                s.instr_max,
                fmt_e(s.tip_max),
                fmt_e(s.ang_max),
                s.fails
            )
            .unwrap();
            if core == "M4F" && s.fails == 0 && s.tip_max <= 1e-3 {
                best.push((format!("{scalar} {}", method_label(&m)), s.instr_max, s.tip_max));
            }
        }
    }
    best.sort_by(|a, b| a.1.total_cmp(&b.1));
    writeln!(w, "\n### The target: a forward solve within 1e-3 mm of the reference in at most 5,000 M4F instructions\n").unwrap();
    writeln!(w, "M4F variants within 1e-3 mm on every paper scene, cheapest first (worst-case instructions over the scenes):\n").unwrap();
    match best.first() {
        Some((name, instr, _)) if *instr <= 5000.0 => writeln!(w, "Met: {name} stays within 5,000 instructions on every paper scene.\n").unwrap(),
        Some((name, instr, _)) => writeln!(
            w,
            "**Not met.** The cheapest variant within 1e-3 mm is {name}: {instr:.0} instructions on its worst scene (see below for what bounds it).\n"
        )
        .unwrap(),
        None => writeln!(w, "**Not met**: no M4F variant is within 1e-3 mm on every paper scene.\n").unwrap(),
    }
    for (name, instr, err) in best.iter().take(6) {
        writeln!(
            w,
            "- {name}: {instr:.0} instructions (worst scene), tip error at most {}{}",
            fmt_e(*err),
            if *instr <= 5000.0 { " — meets the target" } else { "" }
        )
        .unwrap();
    }
    // per scene for the converged f32 variants
    writeln!(w, "\nConverged solver per scene (instructions of `solve_with`; *setup* = `compliances` for the scene's voltages):\n").unwrap();
    writeln!(w, "| scene | core | scalar | instructions | setup | iterations | tip error mm | angle error deg |").unwrap();
    writeln!(w, "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: |").unwrap();
    for r in rows.iter().filter(|r| r.rec.method == "conv") {
        let it = r.rec.result.as_ref().map(|x| x.2.to_string()).unwrap_or_else(|e| format!("err {e}"));
        writeln!(
            w,
            "| {} | {} | {} | {:.0} | {:.0} | {} | {} | {} |",
            r.rec.scene,
            r.rec.core,
            r.rec.scalar,
            r.rec.instr,
            r.rec.setup_instr,
            it,
            r.tip_err.map(fmt_e).unwrap_or_else(|| "-".into()),
            r.ang_err.map(fmt_e).unwrap_or_else(|| "-".into())
        )
        .unwrap();
    }
    writeln!(w, "\nWhat bounds each variant (the floor: three 2-unknown Newton solves of one march per iteration, plus").unwrap();
    writeln!(w, "the posture):\n").unwrap();
    writeln!(w, "- Converged solver: one dual-number march per Newton iteration gives the residual and the exact 2x2").unwrap();
    writeln!(w, "  Jacobian (`model/src/finger/dual.rs`); 2 to 3 iterations per joint at the paper's loads, so 3 to 4 dual").unwrap();
    writeln!(w, "  marches per joint including the final check. Joints with equal compliance are solved once (uniform").unwrap();
    writeln!(w, "  voltages, bare finger) and `assemble` reuses their residual and tangent, so the per-joint-voltage scene").unwrap();
    writeln!(w, "  costs about twice the uniform ones. The rest is the zero-tension start march per joint, the posture (two").unwrap();
    writeln!(w, "  sin/cos per joint) and, the largest single share in a QEMU execution profile of the quick image, the").unwrap();
    writeln!(w, "  zeroing and copying of the fixed-capacity `Solution` and joint-state arrays (5 joints x 8 sub-elements,").unwrap();
    writeln!(w, "  `memclr`/`memcpy`). Reaching 5,000 instructions on the per-joint scene needs those out (an in-place").unwrap();
    writeln!(w, "  solution, joint states sized by m) and Newton's last march reused by `assemble`; the uniform scenes are").unwrap();
    writeln!(w, "  within about 1.6x of the target.").unwrap();
    writeln!(w, "- f32 with libm: `sinf`/`cosf` reduce and evaluate in f64, software on a single-precision FPU (about 1,000").unwrap();
    writeln!(w, "  instructions a call), and a solve needs about 15 of them: libm f32 cannot get near 5,000.").unwrap();
    writeln!(w, "- f32 with the model's `fast-trig` feature (sin/cos in f32: Cody-Waite reduction, minimax polynomials,").unwrap();
    writeln!(w, "  about 1 ulp, ~40 instructions a pair): the accuracy of libm f32 at a fraction of the count; the fastest").unwrap();
    writeln!(w, "  variant within 1e-3 mm.").unwrap();
    writeln!(w, "- f32 with micromath: as fast as `fast-trig` but its sin/cos error (~1e-4 to 1e-3 relative) moves the").unwrap();
    writeln!(w, "  equilibrium by a few hundredths of a millimetre: it cannot meet 1e-3 mm at any step count.").unwrap();
    writeln!(w, "- f64 on the M4F: soft-float throughout (the FPU is single precision), several times f32.").unwrap();
    writeln!(w, "- Square roots: the M4F's `vsqrt.f32` (one instruction in a two-instruction leaf, model `real.rs`); libm's").unwrap();
    writeln!(w, "  `sqrtf` is a software routine there (~100 instructions), so every f32 figure here uses the instruction.").unwrap();
    writeln!(w, "- Stepping: n_inc explicit steps, each a march per joint plus the posture, and first-order error: reaching").unwrap();
    writeln!(w, "  1e-3 mm at 1 N takes thousands of steps (see the stepping study below); it never competes.\n").unwrap();

    // ---- fixed vs soft float
    writeln!(w, "## Fixed point against soft-float f32 on the Cortex-M3\n").unwrap();
    let pick = |core: &str, scalar: &str, m: &str| {
        summarize(rows.iter().filter(|r| r.rec.core == core && r.rec.scalar == scalar && r.rec.method == m && is_paper_scene(&r.rec.scene)))
    };
    writeln!(w, "| scalar (M3) | converged: instructions (mean) | tip error mm (max) | stepping n_inc=20: instructions (mean) | tip error mm (max) |").unwrap();
    writeln!(w, "| --- | ---: | ---: | ---: | ---: |").unwrap();
    let mut m3 = Vec::new();
    for scalar in ["f32/libm", "f32/fast-trig", "f32/micromath", "i16f16", "i32f32"] {
        let c = pick("M3", scalar, "conv");
        let s20 = pick("M3", scalar, "step20");
        if c.n == 0 {
            continue;
        }
        writeln!(w, "| {scalar} | {:.0} | {} | {:.0} | {} |", c.instr_mean, fmt_e(c.tip_max), s20.instr_mean, fmt_e(s20.tip_max)).unwrap();
        m3.push((scalar, c.instr_mean, c.tip_max, c.fails));
    }
    let get = |s: &str| m3.iter().find(|x| x.0 == s).map(|x| (x.1, x.2));
    if let (Some(q16), Some(q32), Some(sf), Some(mm), Some(ft)) = (get("i16f16"), get("i32f32"), get("f32/libm"), get("f32/micromath"), get("f32/fast-trig")) {
        writeln!(w, "\nFrom these numbers:\n").unwrap();
        writeln!(w, "- I16F16 (32-bit words: one `smull` per multiply) takes {:.2}x the instructions of soft-float f32 with libm,", q16.0 / sf.0).unwrap();
        writeln!(
            w,
            "  {:.2}x soft-float f32 with `fast-trig` and {:.2}x with micromath, at a tip error of {} mm (resolution",
            q16.0 / ft.0,
            q16.0 / mm.0,
            fmt_e(q16.1)
        )
        .unwrap();
        writeln!(w, "  1.5e-5, and its converged tolerance is that resolution times the finger's size; the compliances carry").unwrap();
        writeln!(w, "  3 to 4 significant digits), against {} mm for f32 with `fast-trig` and {} mm with micromath.", fmt_e(ft.1), fmt_e(mm.1)).unwrap();
        let verdict = if q16.0 < ft.0.min(mm.0) {
            "beats every soft-float f32 variant on instructions"
        } else if q16.0 < sf.0 {
            "beats soft-float f32 with libm, but not f32 with a cheap f32 sin/cos"
        } else {
            "does not beat soft-float f32"
        };
        writeln!(w, "  So on this core I16F16 {verdict}; it is the choice when about 1e-2 mm is enough. Its").unwrap();
        writeln!(w, "  multiply-adds are 2 to 4 integer instructions against a 30 to 60 instruction soft-float call; its").unwrap();
        writeln!(w, "  divisions (64-by-32-bit, a library call on the M3), the integer sqrt and the saturation checks are its").unwrap();
        writeln!(w, "  expensive part. When 1e-3 mm is needed it does not reach it; use f32 (`fast-trig`).").unwrap();
        writeln!(w, "- I32F32 (64-bit words: 128-bit products and 128-by-64 divisions in software) takes {:.2}x soft-float f32:", q32.0 / sf.0).unwrap();
        writeln!(w, "  as accurate as f32 or better ({} mm) but it loses on speed. Where accuracy near f32's is needed on an M3,", fmt_e(q32.1)).unwrap();
        writeln!(w, "  soft-float f32 (with `fast-trig`) is the better choice; on the M4F (hardware f32) fixed point does not pay.").unwrap();
    }

    // ---- stepping study
    writeln!(w, "\n## Where the paper's load stepping loses accuracy, oscillates or diverges\n").unwrap();
    writeln!(w, "Host, f64, bare finger, 0 V: tip error of stepping against the converged equilibrium, `dx/dy` in mm (signed).\n").unwrap();
    write!(w, "| tension N |").unwrap();
    for n in n_incs {
        write!(w, " n_inc={n} |").unwrap();
    }
    writeln!(w).unwrap();
    write!(w, "| ---: |").unwrap();
    for _ in n_incs {
        write!(w, " ---: |").unwrap();
    }
    writeln!(w).unwrap();
    for (p, cells) in study {
        write!(w, "| {p} |").unwrap();
        for c in cells {
            match c {
                Ok((dx, dy, _)) => write!(w, " {dx:+.3}/{dy:+.3} |").unwrap(),
                Err(e) => write!(w, " {e} |").unwrap(),
            }
        }
        writeln!(w).unwrap();
    }
    // classify
    writeln!(w).unwrap();
    for (p, cells) in study {
        let errs: Vec<Option<f64>> = cells.iter().map(|c| c.as_ref().ok().map(|(dx, dy, _)| (dx * dx + dy * dy).sqrt())).collect();
        let signs: Vec<f64> = cells.iter().filter_map(|c| c.as_ref().ok().map(|x| x.1.signum())).collect();
        let flips = signs.windows(2).filter(|s| s[0] != s[1]).count();
        let nonmono = errs.windows(2).filter(|e| matches!((e[0], e[1]), (Some(a), Some(b)) if b > a * 1.01)).count();
        let first_ok = n_incs.iter().zip(&errs).find(|(_, e)| matches!(e, Some(x) if *x <= 1e-3)).map(|(n, _)| *n);
        let n1 = errs[0].map(|e| format!("{e:.3}")).unwrap_or_else(|| "failed".into());
        // more steps making it worse: the last (largest n_inc) error above the one before
        let diverges = matches!((errs[errs.len() - 2], errs[errs.len() - 1]), (Some(a), Some(b)) if b > 2.0 * a);
        writeln!(
            w,
            "- {p} N: n_inc=1 is off by {n1} mm; the error's sign changes {flips} time(s) as n_inc grows{}{}; 1e-3 mm first reached at {}.",
            if nonmono > 0 { ", it is not monotone in n_inc (over- and undershoot)" } else { "" },
            if diverges { ", and more steps make it worse (the iteration diverges)" } else { "" },
            first_ok.map(|n| format!("n_inc = {n}")).unwrap_or_else(|| format!("no n_inc up to {}", n_incs[n_incs.len() - 1]))
        )
        .unwrap();
    }
    // same shape as the converged solver's notes above (writeln! of prose): other text
    writeln!(w, "\nWhy: the paper's stepping is not an incremental method but a fixed-point (Picard) iteration with a").unwrap();
    writeln!(w, "load ramp: step n takes every hinge's displacement as `q = C w`, with the load `w` (cable direction, moment").unwrap();
    writeln!(w, "arms) evaluated on the geometry of step n-1 at the load P n/n_inc. Two things follow.\n").unwrap();
    writeln!(w, "- While that map is a contraction (low tension: the moment arm changes little as a joint bends), each").unwrap();
    writeln!(w, "  step lags the equilibrium of its own load by one step of the ramp, so the final error is first order in").unwrap();
    writeln!(w, "  1/n_inc (error x n_inc nearly constant along a row), with a constant that grows quickly with tension:").unwrap();
    writeln!(w, "  0.2 N needs a couple of hundred steps for 1e-3 mm, 1 N more than a thousand. n_inc = 1 applies the whole").unwrap();
    writeln!(w, "  tension on the straight finger's moment arm, which overestimates the moment, so the finger overshoots").unwrap();
    writeln!(w, "  (tip y high at 0.2 to 2 N).").unwrap();
    writeln!(w, "- The map's gain grows with tension (the moment's sensitivity to the hole position scales with P times the").unwrap();
    writeln!(w, "  hinge compliance). Past a few newtons one step overshoots so far that the finger curls past the").unwrap();
    writeln!(w, "  equilibrium (tip y tens of mm low at 4 to 7 N with n_inc = 1) and the error changes sign with n_inc").unwrap();
    writeln!(w, "  (oscillation). Past about 10 N the map stops being a contraction near the equilibrium: the iterates move").unwrap();
    writeln!(w, "  away from it, and more steps only give the divergence more iterations to grow (n_inc = 1000 worse than").unwrap();
    writeln!(w, "  200 at 10 N). Near contact (250 N) the answer is arbitrary at every n_inc, or a coarse step reaches a").unwrap();
    writeln!(w, "  span below the floor and the stepping stops with a contact error although the equilibrium exists.\n").unwrap();
    writeln!(w, "The converged solver has none of these: Newton on the equilibrium in the deformed geometry, with load").unwrap();
    writeln!(w, "continuation and a branch check. Note also the cost: stepping at n_inc = 1 takes about as many").unwrap();
    writeln!(w, "instructions as the converged solve (table above), so it never pays on the target.\n").unwrap();

    // ---- stability
    writeln!(w, "## Stability tests\n").unwrap();
    writeln!(w, "`cd host-tests && cargo test --test stability --test proptest_model` (part of the regular suite):").unwrap();
    writeln!(w, "stiff (E_b = 3,500 MPa) and soft (1 MPa) bodies, very thin and very thick hinges, tension raised until the").unwrap();
    writeln!(w, "branch ends (contact or limit point, a typed error), voltages at the ceiling (refused) and just below").unwrap();
    writeln!(w, "(solved), n_inc = 1 at every tension, tiny and huge geometry at the ends of the documented ranges in f32").unwrap();
    writeln!(w, "and f64, and NaN/infinite inputs; proptest over the valid domain (f32 and f64, 1..5 joints, m = 1..3,").unwrap();
    writeln!(w, "E_b 1..3,500 MPa, stacks, voltages below the ceiling, tensions to 2 kN): every Ok result finite, every").unwrap();
    writeln!(w, "failure a typed error, the converged solver converging or ending in contact, limit point or").unwrap();
    writeln!(w, "non-convergence. The model's own unit tests (`cd model && cargo test`, and `--features fast-trig`)").unwrap();
    writeln!(w, "check the dual-number march against the plain one bit for bit, its Jacobian against central").unwrap();
    writeln!(w, "differences, and the f32 sine/cosine against f64. The bench image path is exercised once by").unwrap();
    writeln!(w, "`host-tests/tests/perf_bench.rs` (one scene in QEMU against the host reference).\n").unwrap();

    // ---- lean
    writeln!(w, "## Lean builds: flash and static RAM per feature set\n").unwrap();
    writeln!(w, "The `lean` binary of `bench/` (`bench/src/lean.rs`): one converged solve of the bare 1.0 N scene (with DE:").unwrap();
    writeln!(w, "the same scene on a finger with stacks), result out over semihosting as raw bits, no float formatting.").unwrap();
    writeln!(w, "Flash: allocated sections with contents (vectors, text, rodata, data's load image); RAM: data + bss").unwrap();
    writeln!(w, "(+ uninit), the stack not included. Model features: `de` (DE stacks; without it `Finger::new` refuses").unwrap();
    writeln!(w, "`layers > 0` and the DE code is left out), `micromath` (f32 trig); fixed point is the bench's `fixed` feature.").unwrap();
    writeln!(w, "The firmware's console and defmt are the firmware's features (not measured here). The fixed-point").unwrap();
    writeln!(w, "images carry the f32 setup (hinge quadrature, DE thinning, compliances) besides the fixed-point solver,").unwrap();
    writeln!(w, "and the `fixed` crate's conversions and panic paths; their size was not analysed further.\n").unwrap();
    writeln!(w, "| image | bench features | flash bytes | static RAM bytes | tip y mm (QEMU) |").unwrap();
    writeln!(w, "| --- | --- | ---: | ---: | ---: |").unwrap();
    for (label, feats, flash, ram, y) in lean {
        writeln!(w, "| {label} | `{}` | {flash} | {ram} | {y:.4} |", if feats.is_empty() { "(none)" } else { feats }).unwrap();
    }

    // ---- full table
    writeln!(w, "\n## Every scene and variant\n").unwrap();
    writeln!(w, "Target instructions of `solve_with`; host ns for the M4F libm image's scalars.\n").unwrap();
    writeln!(w, "| scene | image | scalar | method | instructions | tip error mm | angle error deg | host ns |").unwrap();
    writeln!(w, "| --- | --- | --- | --- | ---: | ---: | ---: | ---: |").unwrap();
    for r in rows {
        let host = if r.rec.image == "m4f-libm" {
            let t = if r.rec.scalar.starts_with("f64") { host64 } else { host32 };
            t.get(&(r.rec.scene.clone(), r.rec.method.clone())).map(|v| format!("{v:.0}")).unwrap_or_default()
        } else {
            String::new()
        };
        let (te, ae) = match (&r.rec.result, r.tip_err, r.ang_err) {
            (Ok(_), Some(t), Some(a)) => (fmt_e(t), fmt_e(a)),
            (Err(e), _, _) => (format!("error: {e}"), "-".into()),
            _ => ("-".into(), "-".into()),
        };
        writeln!(w, "| {} | {} | {} | {} | {:.0} | {te} | {ae} | {host} |", r.rec.scene, r.rec.image, r.rec.scalar, r.rec.method, r.rec.instr).unwrap();
    }
    writeln!(w, "\n![tip error against instructions](perf-error-vs-instructions.svg)").unwrap();
    o
}

/// Log-log plot: per series (core + scalar), the paper scenes' mean instructions against their
/// worst tip error, stepping points joined by a line (n_inc growing to the right), the
/// converged solver as a ring.
fn plot(rows: &[Row]) -> String {
    let (w, h, ml, mr, mt, mb) = (820.0, 560.0, 80.0, 230.0, 30.0, 60.0);
    let (x0, x1, y0, y1) = (2.0f64, 8.0f64, -7.0f64, 2.0f64); // log10 ranges
    let px = |x: f64| ml + (x.log10().clamp(x0, x1) - x0) / (x1 - x0) * (w - ml - mr);
    let py = |y: f64| mt + (y1 - y.max(1e-7).log10().clamp(y0, y1)) / (y1 - y0) * (h - mt - mb);
    let colors = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"];
    let mut s = String::new();
    writeln!(s, r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">"#).unwrap();
    writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#).unwrap();
    for e in (x0 as i32)..=(x1 as i32) {
        let x = px(10f64.powi(e));
        writeln!(
            s,
            r##"<line x1="{x}" y1="{mt}" x2="{x}" y2="{}" stroke="#ddd"/><text x="{x}" y="{}" text-anchor="middle">1e{e}</text>"##,
            h - mb,
            h - mb + 16.0
        )
        .unwrap();
    }
    for e in (y0 as i32)..=(y1 as i32) {
        let y = py(10f64.powi(e));
        writeln!(
            s,
            r##"<line x1="{ml}" y1="{y}" x2="{}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">1e{e}</text>"##,
            w - mr,
            ml - 6.0,
            y + 4.0
        )
        .unwrap();
    }
    let (tx, ty) = (px(5000.0), py(1e-3));
    writeln!(s, r##"<line x1="{tx}" y1="{mt}" x2="{tx}" y2="{}" stroke="#999" stroke-dasharray="4 3"/><line x1="{ml}" y1="{ty}" x2="{}" y2="{ty}" stroke="#999" stroke-dasharray="4 3"/>"##, h - mb, w - mr).unwrap();
    writeln!(s, r##"<text x="{}" y="{}" fill="#666">target: 1e-3 mm, 5,000 M4F instructions</text>"##, tx + 4.0, ty - 4.0).unwrap();
    writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">instructions per solve (mean over the paper scenes, QEMU -icount)</text>"#,
        (ml + w - mr) / 2.0,
        h - 15.0
    )
    .unwrap();
    writeln!(s, r#"<text transform="translate(18 {}) rotate(-90)" text-anchor="middle">worst tip error, mm (0 drawn at 1e-7)</text>"#, (mt + h - mb) / 2.0)
        .unwrap();
    let mut names: Vec<String> = Vec::new();
    for r in rows {
        let k = series(&r.rec);
        if !names.contains(&k) {
            names.push(k);
        }
    }
    for (i, name) in names.iter().enumerate() {
        let col = colors[i % colors.len()];
        let mut pts = Vec::new();
        let mut conv = None;
        for m in methods_in_order() {
            let sm = summarize(rows.iter().filter(|r| &series(&r.rec) == name && r.rec.method == m && is_paper_scene(&r.rec.scene)));
            if sm.n == 0 || sm.fails > 0 {
                continue;
            }
            let p = (px(sm.instr_mean), py(sm.tip_max));
            if m == "conv" {
                conv = Some(p);
            } else {
                pts.push(p);
            }
        }
        let poly: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
        writeln!(s, r#"<polyline class="stepping" points="{}" fill="none" stroke="{col}" stroke-width="1.5"/>"#, poly.join(" ")).unwrap();
        for (x, y) in &pts {
            writeln!(s, r#"<circle cx="{x:.1}" cy="{y:.1}" r="2.5" fill="{col}"/>"#).unwrap();
        }
        if let Some((x, y)) = conv {
            writeln!(s, r#"<circle class="converged" cx="{x:.1}" cy="{y:.1}" r="6" fill="none" stroke="{col}" stroke-width="2"/>"#).unwrap();
        }
        let ly = mt + 10.0 + 18.0 * i as f64;
        writeln!(
            s,
            r#"<line x1="{}" y1="{ly}" x2="{}" y2="{ly}" stroke="{col}" stroke-width="2"/><text x="{}" y="{}">{}</text>"#,
            w - mr + 10.0,
            w - mr + 30.0,
            w - mr + 35.0,
            ly + 4.0,
            name
        )
        .unwrap();
    }
    let ly = mt + 10.0 + 18.0 * names.len() as f64 + 10.0;
    writeln!(
        s,
        r##"<circle cx="{}" cy="{ly}" r="6" fill="none" stroke="#333" stroke-width="2"/><text x="{}" y="{}">converged</text>"##,
        w - mr + 20.0,
        w - mr + 35.0,
        ly + 4.0
    )
    .unwrap();
    writeln!(
        s,
        r##"<circle cx="{}" cy="{}" r="2.5" fill="#333"/><text x="{}" y="{}">stepping, n_inc 1..200</text>"##,
        w - mr + 20.0,
        ly + 18.0,
        w - mr + 35.0,
        ly + 22.0
    )
    .unwrap();
    writeln!(s, "</svg>").unwrap();
    s
}

/// Why the counts of the last structural change moved (the section `moved` writes).
const MOVED_WHY: &str = "This change (issue 53, 2026-12-08): the coupled forward under gravity without the by-value copies of its 22 x 22 arrays (the LU factored in place, `Lu::in_place`; Newton's Jacobian written into one array per solve, `Equations::jacobian_into`, the coupled system's Broyden estimate copied by its leading block only; each forward-difference column resumed on one copy of the evaluation, what it wrote undone after it): the gravity scenes' converged forward on the M4F, f32/fast-trig, 125,581 -> 114,980 (`-g0`) and 125,599 -> 114,992 (`-g90`), the same iterations and answers; fmax under gravity walks up the coupled branch (docs/model.md \"Gravity\"): the contact bench's request past fmax under gravity 627 -> 118 ms. The per-joint Newton (2 x 2, the converged forward without gravity) writes its Jacobian into one array too: the paper scenes' converged forward on the M4F, f32/fast-trig, mean 6,958 -> 6,718. The stepping rows and *setup* moved by about 1 % either way (code layout; the commits since the last report). Errors unchanged. New section: the forward under gravity from the last answer (`Finger::solve_from`). \"Before\" is this report at the parent commit.";

/// The rows of the tables under `heading` in `md`: the first `key` cells joined, then the next `cols` cells.
fn table_rows(md: &str, heading: &str, key: usize, cols: usize) -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    let Some(start) = md.find(heading) else { return out };
    let body = &md[start + heading.len()..];
    let body = &body[..body.find("\n## ").unwrap_or(body.len())];
    for line in body.lines().filter(|l| l.starts_with("| ") && !l.starts_with("| ---")) {
        let cells: Vec<String> = line.trim_matches('|').split('|').map(|c| c.trim().to_string()).collect();
        if cells.len() >= key + cols {
            out.insert(cells[..key].join(" / "), cells[key..key + cols].to_vec());
        }
    }
    out
}

/// The section listing what moved against the report this run replaces: per summary row and per
/// scene row, the instruction counts and errors whose text changed (host ns left out: they
/// vary with the machine).
fn moved(previous: &str, new: &str) -> String {
    let mut s = String::from("\n## Counts moved since the previous report\n\n");
    s.push_str(MOVED_WHY);
    s.push_str("\n\n| table | row | before | after |\n| --- | --- | --- | --- |\n");
    let mut n = 0;
    for (heading, key, cols) in [("## Summary over the paper's scenes", 3, 4), ("## Every scene and variant", 4, 3)] {
        let (a, b) = (table_rows(previous, heading, key, cols), table_rows(new, heading, key, cols));
        for (k, v) in &b {
            if let Some(old) = a.get(k).filter(|old| *old != v) {
                n += 1;
                s.push_str(&format!("| {} | {k} | {} | {} |\n", &heading[3..], old.join(", "), v.join(", ")));
            }
        }
    }
    if n == 0 {
        s.push_str("| - | nothing moved | | |\n");
    }
    s
}
