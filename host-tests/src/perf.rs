//! The bench images (bench/, a `no_std` firmware of its own) seen from the host: build them
//! for a core ([`crate::image::cargo_build`]), run them in QEMU with `-icount` (deterministic
//! instruction counts), read what they print over semihosting ([`read_bench`]: the `CAL`
//! calibration, the result lines, `END`), and compare against the host's f64 reference. Used
//! by the `perf-report` binary (docs/performance.md), the reports that count instructions
//! (examples/*_cost.rs, fixed_report, material_report, fidelity) and `tests/perf_bench.rs`.
//!
//! What it is not: a benchmark harness for host nanoseconds (that is criterion, `benches/host_solve.rs`).

use crate::image::{cargo_build, CargoBuild};
use crate::qemu::qemu_command;
use finger_model::{Finger, Method, Params};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub use finger_scenes as scenes;
use scenes::Scene;

/// One bench image: a core, the QEMU machine for it, the model features compiled in.
#[derive(Clone, Copy, Debug)]
pub struct Image {
    pub name: &'static str,
    pub core: &'static str,
    pub triple: &'static str,
    pub machine: &'static str,
    /// `-icount shift`: 0 on the M4F (1 ns per instruction); 4 on the AN385, whose SysTick
    /// (25 MHz) is too coarse at shift 0 for the calibration loop.
    pub shift: u32,
    pub features: &'static str,
}

pub const M4F: &str = "thumbv7em-none-eabihf";
pub const M3: &str = "thumbv7m-none-eabi";

/// Every image the report runs.
pub const IMAGES: &[Image] = &[
    Image { name: "m4f-libm", core: "M4F", triple: M4F, machine: "netduinoplus2", shift: 0, features: "de,f32,f64,gravity" },
    Image { name: "m4f-micromath", core: "M4F", triple: M4F, machine: "netduinoplus2", shift: 0, features: "de,f32,micromath,gravity" },
    Image { name: "m4f-fasttrig", core: "M4F", triple: M4F, machine: "netduinoplus2", shift: 0, features: "de,f32,fast-trig,gravity" },
    Image { name: "m3-softfloat", core: "M3", triple: M3, machine: "mps2-an385", shift: 4, features: "de,f32,gravity" },
    Image { name: "m3-micromath", core: "M3", triple: M3, machine: "mps2-an385", shift: 4, features: "de,f32,micromath,gravity" },
    Image { name: "m3-fasttrig", core: "M3", triple: M3, machine: "mps2-an385", shift: 4, features: "de,f32,fast-trig,gravity" },
    Image { name: "m3-fixed", core: "M3", triple: M3, machine: "mps2-an385", shift: 4, features: "de,fixed,gravity" },
];

/// The quick image for the CI smoke test: one scene, converged solver, f32 with the model's
/// `fast-trig` sin/cos, M4F.
pub const QUICK: Image = Image { name: "m4f-quick", core: "M4F", triple: M4F, machine: "netduinoplus2", shift: 0, features: "de,f32,fast-trig,quick" };

pub fn bench_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join("bench")
}

/// Where cargo puts the bench builds: $CARGO_TARGET_DIR if set, else bench/target.
pub fn target_dir() -> PathBuf {
    crate::image::cargo_target_dir(bench_dir().join("target"))
}

/// Build binary `bin` of the bench crate for `triple` with `features` (no defaults), and copy
/// the ELF to `<target>/perf-images/<name>.elf` (builds with other features overwrite the
/// cargo output). Returns the copy's path.
pub fn build(bin: &str, triple: &str, features: &str, name: &str) -> Result<PathBuf, String> {
    build_with_env(bin, triple, features, name, &[])
}

/// `build` with build-time variables: each (name, Some(value)) set, each (name, None) removed
/// (an image that reads `option_env!`, like table.rs's profile cases).
pub fn build_with_env(bin: &str, triple: &str, features: &str, name: &str, env: &[(&str, Option<&str>)]) -> Result<PathBuf, String> {
    let tdir = target_dir();
    let b = CargoBuild { dir: bench_dir(), bin, target: triple, features: Some(features), target_dir: tdir.clone(), env };
    let elf = cargo_build(&b).map_err(|e| format!("{name}: {e}"))?;
    let dir = tdir.join("perf-images");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let copy = dir.join(format!("{name}.elf"));
    std::fs::copy(&elf, &copy).map_err(|e| format!("{}: {e}", elf.display()))?;
    Ok(copy)
}

/// Run an image in QEMU (semihosting, -icount) and return what it printed. Fails on a
/// non-zero exit (the image exits 1 on a panic) or a timeout.
pub fn run_qemu(elf: &Path, machine: &str, shift: u32) -> Result<String, String> {
    let out = qemu_command(machine, &format!("shift={shift}"), elf, Some(900)).arg("-nographic").output().map_err(|e| format!("qemu-system-arm: {e}"))?;
    // semihosting output comes on QEMU's stdout or stderr depending on its version
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    if !out.status.success() {
        return Err(format!("{} exited with {:?}:\n{text}", elf.display(), out.status));
    }
    Ok(text)
}

/// One result line of a bench image.
#[derive(Clone, Debug)]
pub struct Rec {
    pub image: String,
    pub core: String,
    pub scene: String,
    pub scalar: String,
    pub method: String,
    /// Ok: tip (x, y) mm, joint angles rad, iterations; Err: the error code.
    pub result: Result<([f64; 2], [f64; 3], u32), String>,
    /// Instructions of `solve_with` and of `compliances` (setup).
    pub instr: f64,
    pub setup_instr: f64,
}

/// A bench image's `CAL <instructions> <ticks> <overhead>` line (a loop of known length):
/// SysTick ticks per instruction and the timing overhead in ticks.
fn calibration(f: &[&str]) -> Result<(f64, f64), String> {
    let num = |i: usize| -> Result<f64, String> { f.get(i).and_then(|x| x.parse().ok()).ok_or_else(|| format!("bad CAL line: {f:?}")) };
    let (n, t, overhead) = (num(1)?, num(2)?, num(3)?);
    if !(t > 0.0 && t < 1e12) {
        return Err(format!("calibration failed: {f:?}"));
    }
    Ok((t / n, overhead))
}

/// A bench image's output, read: the `CAL` line's calibration and the other lines as words.
pub struct BenchOut<'a> {
    /// SysTick ticks per instruction and the timing overhead in ticks (the `CAL` line).
    pub per_instr: f64,
    pub overhead: f64,
    /// Every other line but `END`, split into words.
    pub lines: Vec<Vec<&'a str>>,
}

/// Read a bench image's output; fails on a `PANIC` line, a bad or missing `CAL` line, or no
/// `END` (the image did not finish).
pub fn read_bench(out: &str) -> Result<BenchOut<'_>, String> {
    let (mut cal, mut ended, mut lines) = (None, false, Vec::new());
    for line in out.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        match f.first() {
            Some(&"CAL") => cal = Some(calibration(&f)?),
            Some(&"END") => ended = true,
            Some(&"PANIC") => return Err(format!("the image panicked: {line}")),
            Some(_) => lines.push(f),
            None => {}
        }
    }
    let (per_instr, overhead) = cal.ok_or("no CAL line")?;
    if !ended {
        return Err(format!("the image did not finish (no END):\n{out}"));
    }
    Ok(BenchOut { per_instr, overhead, lines })
}

impl BenchOut<'_> {
    /// The instructions behind a count of `ticks`: the timing overhead subtracted, never below zero.
    pub fn instructions(&self, ticks: f64) -> f64 {
        (ticks - self.overhead).max(0.0) / self.per_instr
    }
}

/// Parse a bench image's result lines ([`read_bench`]: ticks per instruction from the `CAL`
/// line, its timing overhead subtracted).
pub fn parse(image: &Image, out: &str) -> Result<Vec<Rec>, String> {
    let bench = read_bench(out)?;
    let mut recs = Vec::new();
    for f in &bench.lines {
        match f.first() {
            Some(&"R") if f.len() >= 8 => {
                let num = |i: usize| -> Result<f64, String> { f[i].parse::<f64>().map_err(|_| format!("bad number in {f:?}")) };
                let instr = bench.instructions(num(5)?);
                let setup_instr = num(6)? / bench.per_instr;
                let result = if f[4] == "ok" && f.len() >= 13 {
                    Ok(([num(7)?, num(8)?], [num(9)?, num(10)?, num(11)?], num(12)? as u32))
                } else {
                    Err(f[7].to_string())
                };
                recs.push(Rec {
                    image: image.name.into(),
                    core: image.core.into(),
                    scene: f[1].into(),
                    scalar: f[2].into(),
                    method: f[3].into(),
                    result,
                    instr,
                    setup_instr,
                });
            }
            _ => {}
        }
    }
    Ok(recs)
}

pub fn scene_params(s: &Scene) -> Params<f64> {
    scenes::params(s)
}

/// The reference: f64, converged solver at 1e-12 mm. Tip (x, y) mm and joint angles rad.
pub fn reference(s: &Scene) -> Result<([f64; 2], [f64; 3]), finger_model::Error> {
    let f = Finger::new(scene_params(s))?;
    let sol = f.solve(s.tension, &s.volts, Method::Converged { tol: 1e-12, max_iter: 400 })?;
    let t = sol.tip();
    let a = sol.joint_angles();
    Ok(([t.x, t.y], [a[0], a[1], a[2]]))
}

/// Tip position error (mm) and largest joint-angle error (degrees) against the reference.
pub fn errors(tip: [f64; 2], angles: [f64; 3], reference: &([f64; 2], [f64; 3])) -> (f64, f64) {
    let (rt, ra) = reference;
    let tip_err = ((tip[0] - rt[0]).powi(2) + (tip[1] - rt[1]).powi(2)).sqrt();
    let ang = (0..3).map(|i| (angles[i] - ra[i]).abs().to_degrees()).fold(0.0, f64::max);
    (tip_err, ang)
}

/// Flash (allocated sections with contents: vectors, text, rodata, data's load image) and
/// static RAM (writable allocated sections: data, bss, uninit; the stack not included) of a
/// 32-bit little-endian ELF, in bytes.
pub fn elf_sizes(path: &Path) -> Result<(u64, u64), String> {
    let b = std::fs::read(path).map_err(|e| e.to_string())?;
    if b.len() < 52 || &b[..4] != b"\x7fELF" || b[4] != 1 || b[5] != 1 {
        return Err("not a 32-bit little-endian ELF".into());
    }
    let u16_at = |o: usize| u16::from_le_bytes([b[o], b[o + 1]]) as usize;
    let u32_at = |o: usize| u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]) as u64;
    let (shoff, shentsize, shnum) = (u32_at(0x20) as usize, u16_at(0x2e), u16_at(0x30));
    let (mut flash, mut ram) = (0, 0);
    for i in 0..shnum {
        let h = shoff + i * shentsize;
        if h + 24 > b.len() {
            return Err("truncated section headers".into());
        }
        let (ty, flags, size) = (u32_at(h + 4), u32_at(h + 8), u32_at(h + 20));
        const ALLOC: u64 = 2;
        const WRITE: u64 = 1;
        const NOBITS: u64 = 8;
        if flags & ALLOC == 0 {
            continue;
        }
        if ty != NOBITS {
            flash += size;
        }
        if flags & WRITE != 0 {
            ram += size;
        }
    }
    Ok((flash, ram))
}

/// Instructions per inverse solve on the Cortex-M4F: builds `bench/src/bin/inverse.rs`
/// in four variants (libm and fast-trig trig, with and without the m = 1 fast path; fast-trig
/// without it is the firmware's build), runs each in QEMU netduinoplus2 with `-icount
/// shift=0`, and returns the markdown table (one row per case, one column per variant).
/// `cargo run --release --example inverse_cost` writes it to docs/inverse-cost.md; the
/// performance report (`perf-report`) includes it.
pub fn inverse_cost_table() -> String {
    use std::fmt::Write as _;
    let variants = [
        ("libm, fast path", "de,inverse-fast"),
        ("fast-trig, fast path", "de,inverse-fast,fast-trig"),
        ("libm, general path", "de"),
        ("fast-trig, general path", "de,fast-trig"),
        ("fast-trig, general path, branch table (the firmware)", "de,fast-trig,table"),
    ];
    let mut rows: Vec<(String, Vec<(String, String)>)> = Vec::new();
    let mut table_builds: Vec<String> = Vec::new();
    for (label, features) in variants {
        let name = format!("inverse-{}", features.replace(',', "-"));
        let elf = build("inverse", M4F, features, &name).unwrap_or_else(|e| panic!("{e}"));
        let out = run_qemu(&elf, "netduinoplus2", 0).unwrap_or_else(|e| panic!("{e}"));
        let bench = read_bench(&out).unwrap_or_else(|e| panic!("{e}"));
        let mut cells = Vec::new();
        let mut builds: Vec<String> = Vec::new();
        for f in &bench.lines {
            match f.first() {
                Some(&"I") => {
                    let instr = bench.instructions(f[3].parse().unwrap()).round();
                    let cell = if f[2] == "ok" {
                        let t: f64 = f[4].parse().unwrap();
                        let v: Vec<f64> = f[5..8].iter().map(|s| s.parse().unwrap()).collect();
                        format!("{instr:.0} (P {t:.4} N; V {:.0}, {:.0}, {:.0})", v[0], v[1], v[2])
                    } else {
                        format!("{instr:.0} (err {})", f[4])
                    };
                    cells.push((f[1].to_string(), cell));
                }
                Some(&"T") => {
                    let instr = bench.instructions(f[2].parse().unwrap()).round();
                    builds.push(format!("{} {:.0} instructions ({} samples per branch)", f[1], instr, f[3]));
                }
                _ => {}
            }
        }
        if !builds.is_empty() {
            table_builds = builds;
        }
        rows.push((label.to_string(), cells));
    }
    let mut doc = String::new();
    let cases: Vec<String> = rows[0].1.iter().map(|(c, _)| c.clone()).collect();
    write!(doc, "| case |").unwrap();
    for (label, _) in &rows {
        write!(doc, " {label} |").unwrap();
    }
    writeln!(doc).unwrap();
    writeln!(doc, "|{}", " --- |".repeat(rows.len() + 1)).unwrap();
    for (i, case) in cases.iter().enumerate() {
        write!(doc, "| {case} |").unwrap();
        for (_, cells) in &rows {
            write!(doc, " {} |", cells.get(i).map(|c| c.1.as_str()).unwrap_or("-")).unwrap();
        }
        writeln!(doc).unwrap();
    }
    if !table_builds.is_empty() {
        writeln!(doc).unwrap();
        writeln!(
            doc,
            "Building the branch table (`inverse::BranchTable::new`, once per parameter set; the firmware at its first use after a change: `solve`, `status`, `pose`, `force`, `volt`), same image: {}.",
            table_builds.join("; ")
        )
        .unwrap();
    }
    doc
}

/// The methods timed on the host (benches/host_solve.rs): `step<n>` for each of [`scenes::N_INC`],
/// then `conv`.
pub fn host_methods() -> Vec<String> {
    scenes::N_INC.iter().map(|n| format!("step{n}")).chain(std::iter::once("conv".to_string())).collect()
}

/// A criterion benchmark's id for a scene and method (a scene name's `/` would be a path).
pub fn bench_id(scene: &str, method: &str) -> String {
    format!("{}.{method}", scene.replace('/', "_"))
}

/// The criterion group of a scalar's host timings.
pub fn bench_group(scalar: &str) -> String {
    format!("solve_with_{scalar}")
}

/// The f64 finger of a branch-table model (`scenes::TABLE_MODELS`), calibration applied.
pub fn table_finger(m: &scenes::TableModel) -> Result<Finger<f64>, finger_model::Error> {
    let (p, g) = scenes::table_params(m);
    let cal = finger_model::Calibration { hinge: [g[0], g[1], g[2], g[3]], stack_axial: [g[4], g[5]], stack_bending: [g[6], g[7]] };
    Finger::with_calibration(p, cal)
}

/// The branch-table path on the Cortex-M4F: builds `bench/src/bin/table.rs` with the
/// firmware's trig (fast-trig, no inverse fast path or fallback: the firmware's model
/// features), runs it in QEMU netduinoplus2 with `-icount shift=0`, and returns the report's
/// section (markdown): per model the table's build, per scene the forward solve without and
/// with the table, the tabled inverse and fmax, each against the host's f64 full solve.
pub fn table_cost_section() -> String {
    use std::fmt::Write as _;
    let elf = build("table", M4F, "de,fast-trig", "table-de-fast-trig").unwrap_or_else(|e| panic!("{e}"));
    let out = run_qemu(&elf, "netduinoplus2", 0).unwrap_or_else(|e| panic!("{e}"));
    let bench = read_bench(&out).unwrap_or_else(|e| panic!("table image: {e}"));
    let num = |t: &str| t.parse::<f64>().unwrap();
    let instr = |t: &str| bench.instructions(num(t)).round();
    // (model, scene) -> row cells
    #[derive(Default)]
    struct Row {
        full: Option<f64>,
        table: Option<(f64, f64, f64, u32)>,
        inv: Vec<(f64, f64)>,
        fmax: [Option<(f64, f64)>; 2],
        err: Vec<String>,
    }
    let mut builds: Vec<(String, f64, String)> = Vec::new();
    let mut rows: Vec<(String, String, Row)> = Vec::new();
    let models: Vec<(&str, Finger<f64>)> = scenes::TABLE_MODELS.iter().map(|m| (m.name, table_finger(m).expect("table model"))).collect();
    let finger_of = |name: &str| &models.iter().find(|m| m.0 == name).expect("model").1;
    let scene_of = |name: &str| scenes::TABLE_SCENES.iter().find(|s| s.0 == name).expect("scene");
    for f in &bench.lines {
        if f[0] == "B" {
            builds.push((f[1].into(), instr(f[3]), f.get(4).unwrap_or(&"").to_string()));
            continue;
        }
        // `S`/`I`/`F <model> <scene> <variant> ok|err <ticks> ...`: a row's cell, or its error
        let what = match f[0] {
            "S" => "forward",
            "I" => "inverse",
            "F" => "fmax",
            _ => continue,
        };
        let i = match rows.iter().position(|r| r.0 == f[1] && r.1 == f[2]) {
            Some(i) => i,
            None => {
                rows.push((f[1].into(), f[2].into(), Row::default()));
                rows.len() - 1
            }
        };
        if f[4] != "ok" {
            rows[i].2.err.push(format!("{what} {} {}", f[3], f.last().unwrap()));
            continue;
        }
        let n = instr(f[5]);
        match f[0] {
            "S" if f[3] == "full" => rows[i].2.full = Some(n),
            "S" => {
                let (_, p, v) = scene_of(f[2]);
                let reference = finger_of(f[1]).solve(*p, v, Method::Converged { tol: 1e-12, max_iter: 400 }).expect("reference");
                let (tip, ang) = ([num(f[7]), num(f[8])], [num(f[9]), num(f[10]), num(f[11])]);
                let a = reference.joint_angles();
                let (te, ae) = errors(tip, ang, &([reference.tip().x, reference.tip().y], [a[0], a[1], a[2]]));
                rows[i].2.table = Some((n, te, ae, f[12].parse().unwrap()));
            }
            "I" => {
                // the round trip: the f64 forward at the inverse's tension and voltages
                let (p, v, want) = (num(f[6]), [num(f[7]), num(f[8]), num(f[9])], [num(f[10]), num(f[11]), num(f[12])]);
                let back = finger_of(f[1]).solve(p, &v, Method::Converged { tol: 1e-12, max_iter: 400 });
                let e = match back {
                    Ok(s) => (0..3).map(|k| (s.joint_angle[k] - want[k]).abs().to_degrees()).fold(0.0, f64::max),
                    Err(_) => f64::INFINITY,
                };
                rows[i].2.inv.push((n, e));
            }
            _ => {
                let slot = if f[3] == "full" { 0 } else { 1 };
                rows[i].2.fmax[slot] = Some((n, num(f[6])));
            }
        }
    }
    let mut w = String::new();
    writeln!(w, "## The branch-table path on the Cortex-M4F\n").unwrap();
    writeln!(
        w,
        "Under tension alone the joints decouple and a joint's equilibrium depends on the tension and its stack \
         thickness. `inverse::BranchTable` (model inverse/table.rs) tabulates that branch once per parameter set: \
         64 joint angles (1.5 deg apart, or to the branch's end) at three stack thicknesses (0 V, the ceiling, \
         the middle), each sample the tension and the guide hole. From it: **forward** (`BranchTable::solve_into`, \
         written into a solution the caller holds; `solve_with` returns it by value): each joint's hole read off \
         the table at (P, t) (on the table's tension grid: 64 uniform tensions to the three branches' common \
         end, each interval holding the hole's cubic in P for each coefficient of its quadratic in stack \
         thickness, read where the grid agrees with the inversion below to 1/8 of the solver's tolerance; else \
         the cubic P(theta) inverted at P on each thickness, then the quadratic across the thicknesses), then \
         Newton on the full model from that hole; a march whose hole residual is within the converged solver's \
         own tolerance is the answer (Newton's first evaluation; that march is `march_cable` by `ByCompliance`, the plain \
         march's equations carried in each sub-element's own frame, the same answer to rounding), else Newton \
         iterates, else the full solve's continuation; the posture is composed as the joints are marched, from \
         each march's own sin/cos. **Inverse** (`solve_pose_tabled`): the \
         tension range and the thickness solve start from the table (docs/inverse.md). **fmax** \
         (`BranchTable::fmax`): the march up the branch continues from the table's last two samples (docs/fmax-cost.md). Every answer is a \
         converged solve of the full model; the table only chooses where it starts. Bench image \
         `bench/src/bin/table.rs`, f32 with the firmware's model features (fast-trig, general inverse path, \
         no fallback), QEMU netduinoplus2 `-icount shift=0`; errors against the host's f64 full solve at \
         1e-12 mm; the inverse's round trip is the f64 forward solve at the inverse's tension and voltages \
         against the target angles (the tabled forward's). Models: `m8-default` (docs/model.md's defaults: m = 8, \
         plate modulus, flexible links), `m8-calibrated` (the same with docs/model.md's FE calibration factors, \
         docs/fidelity-fe.md), `m1-paper` (m = 1, body modulus, rigid links). Compliances (*setup*, once per \
         voltage change) are outside both forward counts, as in the tables above.\n"
    )
    .unwrap();
    for (m, n, len) in &builds {
        writeln!(w, "- table build, {m}: {n:.0} instructions ({len} samples per thickness)").unwrap();
    }
    writeln!(w).unwrap();
    writeln!(
        w,
        "| model | scene | forward full | forward table | Newton iterations (table) | tip error mm (table) | angle error deg (table) | inverse, P given | inverse, P free | round trip deg (max) | fmax full | fmax table | fmax (table) N | notes |"
    )
    .unwrap();
    writeln!(w, "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |").unwrap();
    let fmt = |x: Option<f64>| x.map(|v| format!("{v:.0}")).unwrap_or_else(|| "-".into());
    let mut worst: BTreeMap<String, [f64; 5]> = BTreeMap::new();
    for (m, s, r) in &rows {
        let wr = worst.entry(m.clone()).or_insert([0.0; 5]);
        let (tn, te, ae, it) = r.table.map(|t| (Some(t.0), Some(t.1), Some(t.2), Some(t.3))).unwrap_or((None, None, None, None));
        if let (Some(n), Some(e)) = (tn, te) {
            wr[0] = wr[0].max(n);
            wr[1] = wr[1].max(e);
        }
        let rt = r.inv.iter().map(|x| x.1).fold(0.0, f64::max);
        for x in &r.inv {
            wr[2] = wr[2].max(x.0);
        }
        wr[3] = wr[3].max(rt);
        if let Some((n, _)) = r.fmax[1] {
            wr[4] = wr[4].max(n);
        }
        writeln!(
            w,
            "| {m} | {s} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            fmt(r.full),
            fmt(tn),
            it.map(|v| v.to_string()).unwrap_or_else(|| "-".into()),
            te.map(|v| format!("{v:.2e}")).unwrap_or_else(|| "-".into()),
            ae.map(|v| format!("{v:.2e}")).unwrap_or_else(|| "-".into()),
            fmt(r.inv.first().map(|x| x.0)),
            fmt(r.inv.get(1).map(|x| x.0)),
            if r.inv.is_empty() { "-".into() } else { format!("{rt:.2e}") },
            fmt(r.fmax[0].map(|x| x.0)),
            fmt(r.fmax[1].map(|x| x.0)),
            r.fmax[1].map(|x| format!("{:.4}", x.1)).unwrap_or_else(|| "-".into()),
            r.err.join("; ")
        )
        .unwrap();
    }
    writeln!(w, "\nWorst over the scenes, against the goals (forward and inverse at most 3,000 instructions; within 1e-3 mm and 0.01 deg of the f64 full solve; the build at most 2,000,000):\n").unwrap();
    writeln!(w, "| model | forward (table) | tip error mm | inverse | round trip deg | fmax (table) | build | goals |").unwrap();
    writeln!(w, "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |").unwrap();
    for (m, v) in &worst {
        let b = builds.iter().find(|b| &b.0 == m).map(|b| b.1).unwrap_or(f64::NAN);
        let met = |ok: bool| if ok { "met" } else { "not met" };
        writeln!(
            w,
            "| {m} | {:.0} | {:.2e} | {:.0} | {:.2e} | {:.0} | {b:.0} | speed {}, {}; accuracy {}; build {} |",
            v[0],
            v[1],
            v[2],
            v[3],
            v[4],
            met(v[0] <= 3000.0),
            met(v[2] <= 3000.0),
            met(v[1] <= 1e-3 && v[3] <= 0.01),
            met(b <= 2e6)
        )
        .unwrap();
    }
    // what bounds the forward: a distinct joint's march (the three-voltage scene minus the
    // uniform one at the same tension, per extra joint)
    for m in worst.keys() {
        let get = |s: &str| rows.iter().find(|r| &r.0 == m && r.1 == s).and_then(|r| r.2.table.map(|t| t.0));
        if let (Some(a), Some(b)) = (get("de-1.0N"), get("de-1.0N-per9/5/0kV")) {
            writeln!(
                w,
                "\n- {m}: a forward solve with one distinct joint costs {a:.0}, each further distinct joint {:.0} (its march on the full model).",
                (b - a) / 2.0
            )
            .unwrap();
        }
        // the inverse's: identical joints inside the stack's range (8 kV), three different
        // ones inside it (2/6/9 kV), identical joints at 0 V (no compliance evaluation), each
        // with the tension given and free
        let inv = |s: &str, i: usize| rows.iter().find(|r| &r.0 == m && r.1 == s).and_then(|r| r.2.inv.get(i).map(|x| x.0));
        if let (Some(a), Some(b), Some(fa), Some(fb), Some(z)) =
            (inv("de-1.0N-uni8kV", 0), inv("de-15N-per2/6/9kV", 0), inv("de-1.0N-uni8kV", 1), inv("de-15N-per2/6/9kV", 1), inv("de-0.2N", 0))
        {
            writeln!(
                w,
                "- {m}: an inverse with the tension given and one distinct joint (de-1.0N-uni8kV) costs {a:.0}, each further distinct joint {:.0} (de-15N-per2/6/9kV: its reading, march from the stiffnesses and voltage); with the joints at the scene's 0 V (de-0.2N) {z:.0} (the solved thickness is t0 itself: the compliance march with the table's compliances); the tension free adds {:.0} with one distinct joint, {:.0} with three (the two confirming marches of the interval's bounds).",
                (b - a) / 2.0,
                fa - a,
                fb - b
            )
            .unwrap();
        }
    }
    writeln!(
        w,
        "\n**What bounds it.** The full model's march: m sub-elements per distinct joint. The forward marches \
         each distinct joint once (`march_cable` by `ByCompliance`, in each sub-element's own frame: per sub-element the \
         closed-form 3x3 equilibrium with its one division, from the six entries of the symmetric compliance, \
         the cable force turned by the sub-element's rotation from the sine and cosine series, one term longer \
         where the stiffest scenes' middle sub-elements pass the short series' bound, and the moment and the \
         hole's dot product carried by two rotation-free recurrences; no pose update, no moment arm rebuilt); \
         with its end's pose recovered once and the joint's share of the posture (the node composed, its span \
         and excursion) that is the figure per further joint above. Once per solve: the lookup (six cubics in P \
         on the grid's interval, then one quadratic per distinct joint; past the grid the cubic inversion on \
         each branch, several hundred more), the link's deflection and rotation (the series turn), the \
         solution's scalars (the {}-byte solution is written in place; only rows it held past this finger's \
         (n, m) are cleared), and for identical joints the copy of a joint's rows. The once-per-solve part and \
         one march come to the first figure above, each further distinct joint to the second: with three \
         different voltages at m = 8 the sum is what the table shows. Below that a march would have to be \
         cheaper than m sub-elements of the full model (fewer sub-elements, or the table itself as the answer), \
         which would no longer be the full model's converged solve. The inverse (`solve_pose_tabled_into`, written in \
         place) spends per distinct joint the table's reading (three branches' cubics at one set of weights), \
         one march of the full model at the thickness the table gives along the level curve, from the \
         stiffnesses (`march_cable` by `ByStiffness`: per sub-element the parallel sum of the hinge's and the stack's \
         stiffness and its 3x3 equilibrium by Gaussian elimination, no compliance formed; at either end of the \
         stack's range the compliance march with the table's compliances), which is the answer where it is \
         within the converged solver's tolerance (the quasi-Newton solve only if not), and the voltage; with \
         the tension free, one march more for each end of the feasible interval that bounds it (the midpoint \
         rule rests on them: two, each at the table's reading); with a tension given the ends are not \
         confirmed (step 4's converged solve inside the stack's range shows the tension within every joint's \
         range; `interval` is then the table's reading). docs/inverse-profile.md splits one such solve by \
         function (QEMU's per-instruction trace): the marches, m sub-elements each, are the largest part. \
         So at m = 8 three different voltages take three \
         marches and a free tension two more; below that the interval's ends and the sub-element states \
         would have to be the table's readings instead of the full model's solves (docs/inverse.md).\n",
        std::mem::size_of::<finger_model::Solution<f32>>()
    )
    .unwrap();
    w
}

/// `contact` on the Cortex-M4F: builds `bench/src/bin/contact.rs` (f32, fast-trig: the
/// firmware's model), runs it in QEMU netduinoplus2 with `-icount shift=0` and returns the
/// report's section: one row per case, the worst refusal against the goal (5 ms at 168 MHz).
pub fn contact_cost_section() -> String {
    use std::fmt::Write as _;
    const HZ: f64 = 168e6;
    const GOAL_MS: f64 = 5.0;
    let elf = build("contact", M4F, "de,f32,fast-trig,gravity", "contact-de-f32-fast-trig-gravity").unwrap_or_else(|e| panic!("{e}"));
    let out = run_qemu(&elf, "netduinoplus2", 0).unwrap_or_else(|e| panic!("{e}"));
    let bench = read_bench(&out).unwrap_or_else(|e| panic!("contact image: {e}"));
    let mut doc = String::new();
    writeln!(
        doc,
        "## `contact` on the Cortex-M4F\n\n\
         Instructions per `inverse::contact_force` in f32 with the firmware's model features (fast-trig, gravity), \
         bench image `bench/src/bin/contact.rs`, QEMU netduinoplus2 with `-icount shift=0`; ms at 168 MHz taking \
         one instruction a cycle (a lower bound: a `vdiv.f32` takes 14, a flash wait state is not counted). One \
         request is the fmax check (once where P0 and P have the same voltages; under gravity a free solve at each \
         tension, fmax only to quote a refusal), the free posture at P0 and the pinned \
         continuation (model finger/pinned.rs; docs/inverse.md \"Contact force\"): steps that halve on a failed \
         Newton solve (up to 30 iterations a try; the Jacobian by forward differences at the free posture, then \
         Broyden's update across iterates and steps, a failed step retried once on fresh differences) or land off \
         the branch the finger reaches, a refusal as the limit point where a failed step passes the fold the \
         tangent's determinants place, at a step of 1/8,192 or past 32,768 residual evaluations, and as a pulling \
         stop (issue 55). `default`: the default \
         finger as the board boots (its FE calibration); `paper`: the paper preset. The cases are each finger's slowest \
         answers and refusals over a grid of 624 requests timed on the host (`cargo run --release --example \
         contact_grid` in fuzz/: P0 0.05-5 N, P to 1.2 fmax, six voltage sets; the slowest before and after issue 55), \
         a request past fmax and one below P0; `default-g0`: the board's finger under its weight (grav 9.81, \
         grav_dir 0), the board's default.\n\n\
         | case (P0-P, voltages) | outcome | instructions | ms at 168 MHz | Newton iterations or refusal |\n\
         | --- | --- | ---: | ---: | --- |"
    )
    .unwrap();
    let mut worst: Option<(f64, String)> = None;
    for f in &bench.lines {
        if f.first() != Some(&"C") {
            continue;
        }
        let instr = bench.instructions(f[3].parse().unwrap()).round();
        let ms = instr / HZ * 1e3;
        let what = if f[2] == "ok" {
            format!("{} iterations, force {:.4} N", f[4], f[5].parse::<f64>().unwrap())
        } else {
            format!("`err {}`: {}", f[4], f[5..].join(" "))
        };
        writeln!(doc, "| {} | {} | {instr:.0} | {ms:.1} | {what} |", f[1], f[2]).unwrap();
        if f[2] == "err" && worst.as_ref().is_none_or(|w| instr > w.0) {
            worst = Some((instr, f[1].to_string()));
        }
    }
    if let Some((instr, case)) = worst {
        let ms = instr / HZ * 1e3;
        writeln!(
            doc,
            "\n**The worst refused `contact`: {instr:.0} instructions, {ms:.0} ms at 168 MHz** ({case}); the goal, {GOAL_MS} ms \
             ({:.0} instructions), is {}.",
            GOAL_MS * 1e-3 * HZ,
            if ms <= GOAL_MS { "met".to_string() } else { format!("not met ({:.0}x over)", ms / GOAL_MS) }
        )
        .unwrap();
    }
    doc
}
