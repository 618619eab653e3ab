//! Model fidelity: the three-element model (`finger-model`, converged solver) against
//! the continuum reference (`host_tests::continuum`), per scene and tension up to the end of the
//! equilibrium branch, for m = 1, 2, 4, 8 sub-elements per hinge, with and without the plate
//! modulus (the reference with the same setting: same physics), with and without flexible links;
//! the end of the branch (fmax) of both models; and the M4F instructions of one forward solve
//! per m (bench image `bench/src/bin/fidelity.rs` in QEMU with -icount, f32 with libm and with
//! micromath), with the total error the target's f32 answer has against the reference.
//!
//! Writes docs/fidelity.md (every table and the recommendation), docs/fidelity/fidelity.csv
//! (every number) and docs/fidelity/*.svg (overlays: model solid, continuum dashed).
//!
//! Run: `cd host-tests && cargo run --release --example fidelity` (about two minutes; needs
//! qemu-system-arm and the thumbv7em-none-eabihf target, as scripts/setup installs).
//! `-- --out DIR` writes elsewhere (the default is docs/ at the repository top).
//!
//! Every model parameter that the defaults might change (m, plate, flex_links, nu_b) is set
//! explicitly for each configuration, so these tables stay valid when `Params::default()` does.
use finger_model::{BranchEnd, Calibration, Finger, Method, Params};
use host_tests::continuum::{self, ContinuumSolution, Discretisation};
use host_tests::perf;
use host_tests::scene::{self, continuum_params};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Sub-elements per hinge.
const MS: [usize; 4] = [1, 2, 4, 8];
/// Tensions below the branch end (N); 0.95 x the reference's closing tension is added.
const TENSIONS: [f64; 6] = [0.2, 0.5, 1.0, 2.0, 3.0, 5.0];
/// The acceptance: joint angles within this of the reference (%) up to `LIMIT_TENSION`.
const TOL_PCT: f64 = 3.0;
const LIMIT_TENSION: f64 = 2.0;
/// M4F instructions per forward solve allowed.
const BUDGET: f64 = 10_000.0;
/// The body's Poisson ratio used throughout (docs/model.md's default).
const NU_B: f64 = 0.45;

/// A scene: a finger (layers, preset) and its channel voltages.
struct SceneDef {
    name: &'static str,
    what: &'static str,
    paper: bool,
    layers: u32,
    volts: [f64; 3],
}

const SCENES: &[SceneDef] = &[
    SceneDef { name: "no-stacks", what: "no DE stacks (the paper's finger without DE)", paper: false, layers: 0, volts: [0.0; 3] },
    SceneDef { name: "stacks-0V", what: "4 layers per joint, 0 V (stacks 2.0 mm)", paper: false, layers: 4, volts: [0.0; 3] },
    SceneDef { name: "uniform-8kV", what: "4 layers, every channel 8 kV", paper: false, layers: 4, volts: [8000.0; 3] },
    SceneDef { name: "per-joint", what: "4 layers, 9 / 5 / 0 kV (three different joints)", paper: false, layers: 4, volts: [9000.0, 5000.0, 0.0] },
    SceneDef { name: "paper-0V", what: "paper preset (E_de of Eq. 3 as printed), 4 layers, 0 V", paper: true, layers: 4, volts: [0.0; 3] },
];

/// A model configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Config {
    plate: bool,
    flex: bool,
    m: usize,
}

impl Config {
    fn label(&self) -> String {
        format!("{} | {} | {}", if self.plate { "plate" } else { "E_b" }, if self.flex { "flexible" } else { "rigid" }, self.m)
    }
    fn bench_name(&self) -> String {
        format!("m{}-p{}-f{}", self.m, self.plate as u32, self.flex as u32)
    }
}

fn configs() -> Vec<Config> {
    let mut v = Vec::new();
    for plate in [false, true] {
        for flex in [false, true] {
            for m in MS {
                v.push(Config { plate, flex, m });
            }
        }
    }
    v
}

/// The scene's parameters for a configuration: docs/model.md's values (or the paper preset), every
/// fidelity switch set explicitly.
fn params(s: &SceneDef, c: Config) -> Params<f64> {
    let base = if s.paper { Params::<f64>::paper() } else { Params::<f64>::default() };
    Params { layers: s.layers, m: c.m, plate: c.plate, flex_links: c.flex, nu_b: NU_B, ..base }
}

/// Errors of one model answer against the reference.
#[derive(Clone, Copy, Debug)]
struct Err3 {
    /// The joint with the largest relative error: its signed error, %.
    pct: f64,
    /// Largest absolute joint-angle error, degrees.
    deg: f64,
    /// Tip position error, mm.
    tip: f64,
}

fn compare(angles: &[f64], tip: [f64; 2], r: &ContinuumSolution) -> Err3 {
    let mut pct: f64 = 0.0;
    let mut deg: f64 = 0.0;
    for (a, b) in angles.iter().zip(&r.joint_angles) {
        let p = 100.0 * (a - b) / b;
        if p.abs() > pct.abs() {
            pct = p;
        }
        deg = deg.max((a - b).abs().to_degrees());
    }
    let tip = ((tip[0] - r.tip.x).powi(2) + (tip[1] - r.tip.y).powi(2)).sqrt();
    Err3 { pct, deg, tip }
}

/// One row: scene, configuration, tension, the model's errors (or why it has no answer).
struct Row {
    scene: usize,
    cfg: Config,
    tension: f64,
    out: Result<Err3, String>,
}

/// The reference of one scene and plate setting: closing tension, tensions, solutions.
struct RefSet {
    closing: Option<f64>,
    closing_joint: usize,
    tensions: Vec<f64>,
    sols: Vec<Result<ContinuumSolution, String>>,
}

fn reference(s: &SceneDef, plate: bool) -> RefSet {
    let p = params(s, Config { plate, flex: true, m: 1 });
    let finger = Finger::new(p).expect("scene parameters are valid");
    let stacks: Vec<f64> =
        if s.layers == 0 { Vec::new() } else { finger.compliances(&s.volts).expect("voltages within the ceiling").thickness[..p.n].to_vec() };
    let cp = continuum_params(&p);
    let disc = Discretisation::default();
    let close = continuum::closing_tension(&cp, &stacks, [0.0, 0.0], disc, 60.0).expect("continuum closing tension");
    let (closing, closing_joint) = match &close {
        Some(r) => (Some(r.tension), r.joint),
        None => (None, 0),
    };
    let mut tensions: Vec<f64> = TENSIONS.iter().copied().filter(|&t| closing.is_none_or(|c| t < 0.95 * c)).collect();
    if let Some(c) = closing {
        tensions.push(0.95 * c);
    }
    let sols = tensions.iter().map(|&t| continuum::solve(&cp, t, &stacks, [0.0, 0.0], disc).map_err(|e| e.to_string())).collect();
    RefSet { closing, closing_joint, tensions, sols }
}

/// Model fmax: (tension, kind, joint) or the error's text.
fn model_fmax(s: &SceneDef, c: Config) -> Result<(f64, BranchEnd, usize), String> {
    let f = Finger::new(params(s, c)).map_err(|e| e.to_string())?;
    let b = f.fmax(&s.volts).map_err(|e| e.to_string())?;
    Ok((b.tension, b.kind, b.joint))
}

fn kind_name(k: BranchEnd) -> &'static str {
    match k {
        BranchEnd::Contact => "contact",
        BranchEnd::LimitPoint => "limit point",
        BranchEnd::SearchBound => "search bound",
    }
}

/// Bench results: (image, config name, case) -> record.
type Bench = BTreeMap<(String, String, String), perf::Rec>;

const IMAGES: &[(&str, &str)] = &[("m4f-libm", "de,f32"), ("m4f-fast-trig", "de,f32,fast-trig"), ("m4f-micromath", "de,f32,micromath")];

fn run_bench() -> Result<Bench, String> {
    let mut out = Bench::new();
    for &(name, features) in IMAGES {
        let img = perf::Image { name, core: "M4F", triple: perf::M4F, machine: "netduinoplus2", shift: 0, features };
        let elf = perf::build("fidelity", img.triple, img.features, &format!("fidelity-{name}"))?;
        let text = perf::run_qemu(&elf, img.machine, img.shift)?;
        for r in perf::parse(&img, &text)? {
            let (cfg, case) = r.scene.split_once('/').ok_or("bad scene field")?;
            out.insert((name.to_string(), cfg.to_string(), case.to_string()), r);
        }
    }
    Ok(out)
}

/// The bench cases: (case name, scene index, tension). Must match bench/src/bin/fidelity.rs.
const CASES: &[(&str, usize, f64)] = &[("no-stacks-1N", 0, 1.0), ("no-stacks-2N", 0, 2.0), ("stacks-0V-2N", 1, 2.0), ("per-joint-2N", 3, 2.0)];
/// The configurations the bench image runs.
const BENCH_CFGS: &[(bool, bool)] = &[(false, false), (true, true)];

fn pct(x: f64) -> String {
    format!("{x:+.2} %")
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let top = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out_dir: PathBuf = match args.iter().position(|a| a == "--out") {
        Some(i) => PathBuf::from(args.get(i + 1).expect("--out DIR")),
        None => top.join("docs"),
    };
    let fig_dir = out_dir.join("fidelity");
    std::fs::create_dir_all(&fig_dir).expect("create output directory");

    // 1. the reference, per scene and plate setting
    eprintln!("continuum reference ...");
    let mut refs: BTreeMap<(usize, bool), RefSet> = BTreeMap::new();
    for (i, s) in SCENES.iter().enumerate() {
        for plate in [false, true] {
            refs.insert((i, plate), reference(s, plate));
        }
    }

    // 2. the model, every configuration
    eprintln!("three-element model ...");
    let cfgs = configs();
    let mut rows = Vec::new();
    let mut fmax: BTreeMap<(usize, Config), Result<(f64, BranchEnd, usize), String>> = BTreeMap::new();
    for (i, s) in SCENES.iter().enumerate() {
        for &c in &cfgs {
            let rs = &refs[&(i, c.plate)];
            let f = Finger::new(params(s, c)).expect("valid parameters");
            for (&t, r) in rs.tensions.iter().zip(&rs.sols) {
                let out = match (f.solve(t, &s.volts, Method::converged()), r) {
                    (Ok(sol), Ok(r)) => Ok(compare(sol.joint_angles(), [sol.tip().x, sol.tip().y], r)),
                    (Err(e), _) => Err(format!("model: {e}")),
                    (_, Err(e)) => Err(format!("reference: {e}")),
                };
                rows.push(Row { scene: i, cfg: c, tension: t, out });
            }
            fmax.insert((i, c), model_fmax(s, c));
        }
    }

    // 3. instructions on the M4F (and the target's own answers against the reference)
    eprintln!("bench image in QEMU ...");
    let bench = run_bench().unwrap_or_else(|e| panic!("bench image: {e}"));
    let instr = |image: &str, c: Config, case: &str| -> Option<&perf::Rec> { bench.get(&(image.to_string(), c.bench_name(), case.to_string())) };
    // worst solve (and setup) instructions of a bench configuration (its name) over the bench cases
    let worst_named = |image: &str, name: &str| -> Option<(f64, f64)> {
        let v: Vec<_> = CASES.iter().filter_map(|(case, _, _)| bench.get(&(image.to_string(), name.to_string(), case.to_string()))).collect();
        if v.len() != CASES.len() {
            return None;
        }
        Some((v.iter().map(|r| r.instr).fold(0.0, f64::max), v.iter().map(|r| r.setup_instr).fold(0.0, f64::max)))
    };
    let worst_instr = |image: &str, c: Config| -> Option<(f64, f64)> {
        let v: Vec<_> = CASES.iter().filter_map(|(case, _, _)| instr(image, c, case)).collect();
        if v.len() != CASES.len() {
            return None;
        }
        Some((v.iter().map(|r| r.instr).fold(0.0, f64::max), v.iter().map(|r| r.setup_instr).fold(0.0, f64::max)))
    };

    // summaries
    let worst = |c: Config, upto: f64| -> Option<(f64, f64, f64, String)> {
        // (worst |%| signed, worst deg, worst tip mm, where) over every scene, tensions <= upto
        let mut w: Option<(f64, f64, f64, String)> = None;
        for r in rows.iter().filter(|r| r.cfg == c && r.tension <= upto + 1e-12) {
            let e = r.out.as_ref().ok()?;
            let cur = w.get_or_insert((0.0, 0.0, 0.0, String::new()));
            if e.pct.abs() > cur.0.abs() {
                cur.0 = e.pct;
                cur.3 = format!("{} {} N", SCENES[r.scene].name, fmt_t(r.tension));
            }
            cur.1 = cur.1.max(e.deg);
            cur.2 = cur.2.max(e.tip);
        }
        w
    };
    let worst_all = |c: Config| -> (f64, f64, usize) {
        // over every tension the reference has (to 0.95 x its closing): worst |%|, worst tip, refused
        let mut p: f64 = 0.0;
        let mut t: f64 = 0.0;
        let mut refused = 0;
        for r in rows.iter().filter(|r| r.cfg == c) {
            match &r.out {
                Ok(e) => {
                    if e.pct.abs() > p.abs() {
                        p = e.pct;
                    }
                    t = t.max(e.tip);
                }
                Err(_) => refused += 1,
            }
        }
        (p, t, refused)
    };

    // the choice: smallest m with plate + flexible links within TOL up to LIMIT on every scene
    let passes = |c: Config| worst(c, LIMIT_TENSION).is_some_and(|w| w.0.abs() <= TOL_PCT);
    let chosen_m = MS.iter().copied().find(|&m| passes(Config { plate: true, flex: true, m }));
    let chosen = chosen_m.map(|m| Config { plate: true, flex: true, m });

    // 4. figures
    eprintln!("figures ...");
    let mut figures = Vec::new();
    let fig_cfg = chosen.unwrap_or(Config { plate: true, flex: true, m: 8 });
    let paper_cfg = Config { plate: false, flex: false, m: 1 };
    for (file, s, c, title) in [
        ("no-stacks-paper-m1.svg", &SCENES[0], paper_cfg, "No stacks: the paper's model (m = 1, rigid links, E_b) vs continuum (E_b)".to_string()),
        ("no-stacks-chosen.svg", &SCENES[0], fig_cfg, format!("No stacks: m = {}, plate modulus, flexible links vs continuum (plate)", fig_cfg.m)),
        ("per-joint-chosen.svg", &SCENES[3], fig_cfg, format!("9 / 5 / 0 kV: m = {}, plate modulus, flexible links vs continuum (plate)", fig_cfg.m)),
    ] {
        let i = SCENES.iter().position(|x| x.name == s.name).unwrap();
        let rs = &refs[&(i, c.plate)];
        let mut ts: Vec<f64> = [0.5, 1.0, 2.0, 3.0].into_iter().filter(|&t| rs.closing.is_none_or(|cl| t < 0.95 * cl)).collect();
        if let Some(cl) = rs.closing {
            // the last tension both models reach
            let mf = fmax[&(i, c)].as_ref().map(|f| f.0).unwrap_or(cl);
            ts.push((0.95 * cl.min(mf) * 1000.0).floor() / 1000.0);
        }
        let text = scene_text(&title, s, c, &ts);
        let sc = scene::parse(file.trim_end_matches(".svg"), &text).expect("generated scene parses");
        let reference = scene::reference_solver();
        let res = scene::run(&sc, reference.as_deref()).unwrap_or_else(|e| panic!("figure {file}: {}", e.message));
        std::fs::write(fig_dir.join(file), host_tests::svg::plot(&res)).expect("write svg");
        figures.push((file, title));
    }

    // 5. CSV of every number
    let mut csv = String::from("scene,plate,flex_links,m,tension_N,worst_joint_err_pct,max_joint_err_deg,tip_err_mm,note\n");
    for r in &rows {
        let (a, b, c, note) = match &r.out {
            Ok(e) => (e.pct.to_string(), e.deg.to_string(), e.tip.to_string(), String::new()),
            Err(e) => (String::new(), String::new(), String::new(), e.replace(',', ";")),
        };
        let _ = writeln!(csv, "{},{},{},{},{},{a},{b},{c},{note}", SCENES[r.scene].name, r.cfg.plate as u32, r.cfg.flex as u32, r.cfg.m, r.tension);
    }
    std::fs::write(fig_dir.join("fidelity.csv"), csv).expect("write csv");

    // 6. the document
    let mut d = String::new();
    let w = &mut d;
    let _ = writeln!(w, "# Model fidelity: the three-element model against the continuum reference\n");
    let _ = writeln!(
        w,
        "Against a real finite-element solver (CalculiX, 3D), with and without the FE calibration of the \
sub-element compliances: docs/fidelity-fe.md (`cd tools/calculix && cargo run --bin fe-report`).\n"
    );
    let _ = writeln!(
        w,
        "Generated by `cd host-tests && cargo run --release --example fidelity` (about two minutes; it \
builds the bench image `bench/src/bin/fidelity.rs` for the Cortex-M4F and runs it in QEMU with \
`-icount`). Do not edit by hand: every number, table, figure and the recommendation below come \
from that command. Every number is also in `docs/fidelity/fidelity.csv`. Tests: \
`cd host-tests && cargo test --test fidelity`.\n"
    );
    let _ = writeln!(
        w,
        "The question: how far is `finger-model`'s node-based model (docs/model.md, the paper's \
n-FEM-NI) from the real structure, as a function of the hinge subdivision m, the plate modulus and \
flexible links, and what does each m cost on the target? The real structure is stood in for by the \
continuum reference (`host_tests::continuum`, docs/continuum.md): a planar extensible elastica of \
the real geometry (notches of varying thickness, links as beams of the body, bonded DE layers, the \
cable as an exact follower load), converged to ~1e-8 rad. It always has flexible links; its plate \
setting is the model's (the same physics: the plate modulus is a statement about the material, \
so the reference carries it too).\n"
    );
    let _ = writeln!(w, "## What is measured\n");
    let _ = writeln!(w, "- Scenes (docs/model.md's default finger, 3 joints; voltages inside the 10 kV ceiling):");
    for s in SCENES {
        let _ = writeln!(w, "  - `{}`: {}", s.name, s.what);
    }
    let _ = writeln!(
        w,
        "- Tensions: {} N and 0.95 × the reference's span-closing tension (the end of its branch), \
each only if below that end.",
        TENSIONS.iter().map(|t| fmt_t(*t)).collect::<Vec<_>>().join(", ")
    );
    let _ = writeln!(
        w,
        "- Configurations: m = 1, 2, 4, 8 sub-elements per hinge (m = 1 is the paper's model); body \
modulus E_b = 12 MPa or the plate modulus E_b/(1 − ν_b²) = {:.2} MPa (ν_b = {NU_B}); rigid links (the \
paper) or flexible links (each link a uniform beam of the body under the cable's eccentric load). \
Each configuration sets `m`, `plate`, `flex_links` and `nu_b` explicitly, so the tables do not \
depend on `Params::default()`.",
        12.0 / (1.0 - NU_B * NU_B)
    );
    let _ = writeln!(
        w,
        "- Errors, model minus reference: the joint-angle error of the worst joint in % of the \
reference's angle (signed; joint angle = rotation node to node, hinge and link), the largest \
joint-angle error in degrees, and the tip position error in mm (centreline at node 3).\n"
    );

    // summary table
    let _ = writeln!(w, "## Summary\n");
    let _ = writeln!(
        w,
        "Worst over every scene. \"≤ {} N\": tensions up to {} N; \"to the end\": every tension up to \
0.95 × the reference's closing tension (a tension past the model's own fmax is refused by the \
model and counted under \"refused\"). M4F instructions: one forward solve (`Finger::solve_with`, \
converged, f32) and the setup for new voltages (`Finger::compliances`), worst over the bench \
cases (below); only the paper's and the real-structure configurations are in the bench image.\n",
        fmt_t(LIMIT_TENSION),
        fmt_t(LIMIT_TENSION)
    );
    let _ = writeln!(
        w,
        "| modulus | links | m | joint ≤ {l} N | where | max deg ≤ {l} N | tip ≤ {l} N (mm) | joint to the end | tip to the end (mm) | refused | fmax no-stacks: model / reference | M4F instr. solve (libm / fast-trig / micromath) | setup (libm) |",
        l = fmt_t(LIMIT_TENSION)
    );
    let _ = writeln!(w, "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for &c in &cfgs {
        let (wp, wd, wt, wh) = worst(c, LIMIT_TENSION).unwrap_or((f64::NAN, f64::NAN, f64::NAN, "model failed".into()));
        let (ap, at, refused) = worst_all(c);
        let fm = match (&fmax[&(0, c)], refs[&(0, c.plate)].closing) {
            (Ok(f), Some(cl)) => format!("{:.3} / {:.3} N ({:+.1} %)", f.0, cl, 100.0 * (f.0 - cl) / cl),
            (Ok(f), None) => format!("{:.3} / none", f.0),
            (Err(e), _) => format!("error: {e}"),
        };
        let (ins, setup) = match (worst_instr("m4f-libm", c), worst_instr("m4f-fast-trig", c), worst_instr("m4f-micromath", c)) {
            (Some(a), Some(f), Some(b)) => (format!("{:.0} / {:.0} / {:.0}", a.0, f.0, b.0), format!("{:.0}", a.1)),
            _ => ("—".into(), "—".into()),
        };
        let mark = if wp.abs() <= TOL_PCT { " ✓" } else { "" };
        let _ = writeln!(w, "| {} | {}{mark} | {wh} | {wd:.2} | {wt:.2} | {} | {at:.2} | {refused} | {fm} | {ins} | {setup} |", c.label(), pct(wp), pct(ap));
    }
    let _ = writeln!(w, "\n✓: within {TOL_PCT} % up to {} N on every scene.\n", fmt_t(LIMIT_TENSION));

    // the recommendation
    let _ = writeln!(w, "## The default m, plate modulus and flexible links\n");
    let budget_ok: Vec<usize> =
        MS.iter().copied().filter(|&m| worst_instr("m4f-libm", Config { plate: true, flex: true, m }).is_some_and(|x| x.0 <= BUDGET)).collect();
    let budget_ok_mm: Vec<usize> =
        MS.iter().copied().filter(|&m| worst_instr("m4f-micromath", Config { plate: true, flex: true, m }).is_some_and(|x| x.0 <= BUDGET)).collect();
    match chosen {
        Some(c) => {
            let (wp, _, wt, wh) = worst(c, LIMIT_TENSION).unwrap();
            let _ = writeln!(
                w,
                "**Accuracy: m = {}** is the smallest m whose joint angles are within {TOL_PCT} % of the \
reference up to {} N on every scene (plate modulus and flexible links on): worst {} ({wh}), tip within \
{wt:.2} mm.",
                c.m,
                fmt_t(LIMIT_TENSION),
                pct(wp)
            );
        }
        None => {
            let _ = writeln!(w, "**Accuracy: no m up to 8 is within {TOL_PCT} % on every scene up to {} N.**", fmt_t(LIMIT_TENSION));
        }
    }
    let cost = |img: &str, m: usize| worst_instr(img, Config { plate: true, flex: true, m }).map(|x| x.0).unwrap_or(f64::NAN);
    let _ = writeln!(
        w,
        "\n**Run time: no m meets the {BUDGET:.0}-instruction budget** with the current solver{}. One \
forward solve costs {:.0} (m = 1) to {:.0} (m = 8) M4F instructions with libm's f32 trig, {:.0} to {:.0} with the model's `fast-trig` feature (f32 \
sin/cos, ~1 ulp; the firmware's build), {:.0} to {:.0} with micromath's; m's own share is about {:.0} (libm) or {:.0} (micromath) \
instructions per sub-element per distinct joint, the rest is the solver's fixed cost (continuation, \
dual-number Newton iterations, the posture and the tangent determinant of every joint in \
`assemble`). What bounds it: the number of marches per solve, not the model's arithmetic. \
A march turns each sub-element's sine and cosine from the previous one by a short series where \
the step is small (`Real::turn`, docs/model.md \"Which march to call\"), so the trig (libm's f32 `sincosf` \
runs its polynomials in f64, in software on the M4F) is called about once per march: a libm \
sub-element costs {:.1} times a micromath one. The per-joint case (three different \
joints, no reuse of a solved joint) is the worst case.",
        if budget_ok.is_empty() && budget_ok_mm.is_empty() {
            String::new()
        } else {
            format!(" (within it: libm m ∈ {budget_ok:?}, micromath m ∈ {budget_ok_mm:?})")
        },
        cost("m4f-libm", 1),
        cost("m4f-libm", 8),
        cost("m4f-fast-trig", 1),
        cost("m4f-fast-trig", 8),
        cost("m4f-micromath", 1),
        cost("m4f-micromath", 8),
        (cost("m4f-libm", 8) - cost("m4f-libm", 1)) / 7.0 / 3.0,
        (cost("m4f-micromath", 8) - cost("m4f-micromath", 1)) / 7.0 / 3.0,
        (cost("m4f-libm", 8) - cost("m4f-libm", 1)) / (cost("m4f-micromath", 8) - cost("m4f-micromath", 1)),
    );
    if let Some(c) = chosen {
        let _ = writeln!(
            w,
            "\n**Recommended defaults: `m = {}`, `plate = 1` (ν_b = {NU_B}), `flex_links = 1`.** Accuracy is \
the requirement that can be met, and the cost is affordable for what the firmware does with a solve \
(a console command or a setpoint change, not a control loop): {:.0} instructions (the firmware's \
`fast-trig` build) are about {:.2} ms \
at 168 MHz (QEMU counts instructions, not wait states; the real M4F at 168 MHz with flash wait states \
and the ART accelerator is within a small factor of that). The paper's m = 1 costs {:.0} and is \
{} off at {} N. These are full solves; the firmware's forward solve under tension alone starts from its \
branch table and is within the budget (docs/performance.md, \"The branch-table path\"); m is not the lever.",
            c.m,
            cost("m4f-fast-trig", c.m),
            cost("m4f-fast-trig", c.m) / 168e3,
            cost("m4f-fast-trig", 1),
            pct(worst(Config { plate: false, flex: false, m: 1 }, LIMIT_TENSION).map_or(f64::NAN, |x| x.0)),
            fmt_t(LIMIT_TENSION)
        );
    }
    // the board's default: m = 8, plate, flexible links, with docs/model.md's FE calibration
    let plain = Config { plate: true, flex: true, m: 8 };
    let (u, c) = (worst_instr("m4f-fast-trig", plain), worst_named("m4f-fast-trig", &format!("{}-cal", plain.bench_name())));
    let (ul, cl) = (worst_instr("m4f-libm", plain), worst_named("m4f-libm", &format!("{}-cal", plain.bench_name())));
    let g = |x: Option<(f64, f64)>, k: usize| x.map_or(f64::NAN, |x| if k == 0 { x.0 } else { x.1 });
    let _ = writeln!(
        w,
        "\n**The board's default is calibrated**: docs/model.md's finger carries its FE calibration \
(`Calibration::model_md`, `cal` at the console; docs/fidelity-fe.md for its accuracy against a 3D \
finite-element solution). The factors change the sub-element compliances once, when the finger is \
built, and the stack's stiffness once per voltage change (`Finger::compliances`), not the solve: m = 8 \
(plate, flexible links) calibrated costs {:.0} M4F instructions per forward solve (`fast-trig`, the \
firmware's build; worst over the bench cases) against {:.0} uncalibrated ({:+.0}); libm {:.0} against \
{:.0}; the setup {:.0} against {:.0} (`fast-trig`). This report's accuracy tables are the uncalibrated \
model: it shares the continuum reference's beam assumptions, so the pair checks the model's \
discretisation; the calibration moves the model away from beam theory toward the FE by design.",
        g(c, 0),
        g(u, 0),
        g(c, 0) - g(u, 0),
        g(cl, 0),
        g(ul, 0),
        g(c, 1),
        g(u, 1),
    );
    let rigid_vs_flex = |m: usize, plate: bool| {
        (
            worst(Config { plate, flex: false, m }, LIMIT_TENSION).map_or(f64::NAN, |x| x.0),
            worst(Config { plate, flex: true, m }, LIMIT_TENSION).map_or(f64::NAN, |x| x.0),
        )
    };
    let (r8, f8) = rigid_vs_flex(8, true);
    let _ = writeln!(
        w,
        "\n**Flexible links: on.** The links are 10 mm thick beams of the same TPU; their bending \
under the cable's eccentric load is 1.7 % of a joint's compliance (docs/continuum.md), which rigid \
links miss at every load: worst error with m = 8 and the plate modulus {} rigid vs {} flexible. They \
cost nothing measurable (one 3x3 product per link per solve; compare the rigid and flexible rows of \
the instruction table).",
        pct(r8),
        pct(f8)
    );
    let _ = writeln!(
        w,
        "\n**Plate modulus: on for the default finger**, by the rule below (w/t_min = 20/1.5 = 13.3). The \
reference carries whichever modulus the model uses, so this table cannot decide between E_b and the \
plate modulus; it shows that with the same modulus the two models agree. Which one the real hinge \
has is a question of its stress state, answered by the rule.\n"
    );
    let _ = writeln!(w, "### When a hinge is wide enough for the plate modulus\n");
    let _ = writeln!(
        w,
        "Use `plate = 1` when **w ≥ 10 t_min** (and the notch is short against its width, 2a ≲ w, as \
every notch hinge is); keep E_b (`plate = 0`) when w ≤ 2 t_min; in between, neither is exact (the \
answer lies between the two, closer to the plate the wider the hinge). The default hinge has \
w/t_min = 13.3 and 2a/w = 0.5: plate.\n\n\
Why: a bent beam wants the anticlastic (saddle) curvature −ν κ across its width. In a hinge much \
wider than thick that transverse strain is held back, by the material on either side of each fibre \
and by the thick links at both ends of the short notch, so the thin section bends in plane strain \
(ε_z = 0), whose bending modulus is E/(1 − ν²). Only edge zones about one thickness wide on each side \
are free to contract (plane stress, E). With w ≥ 10 t_min these zones cover at most ~20 % of the width, \
and since E/(1 − ν²) exceeds E by {:.0} % for ν_b = {NU_B}, the plate modulus is then right to within \
about 5 %, against a {:.0} % error for E_b. At w ≈ t (a square section) the free contraction reaches \
the whole section and E is the right modulus. This is the usual rule for wide plates and flexure \
hinges: plane strain when the width is much larger than the thickness, plane stress when they are \
comparable; the issue's independent plane-strain finite-element solution takes the same view for \
this 20 mm × 1.5 mm hinge. The DE layers keep E_de (docs/model.md).\n",
        100.0 * (1.0 / (1.0 - NU_B * NU_B) - 1.0),
        100.0 * (1.0 - (1.0 - NU_B * NU_B))
    );

    // branch ends
    let _ = writeln!(w, "## The end of the equilibrium branch (fmax)\n");
    let _ = writeln!(
        w,
        "The reference's span-closing tension (`continuum::closing_tension`: the first span at the \
0.1 mm floor) against the model's `Finger::fmax` (the first joint whose span closes or whose \
equilibrium tangent turns singular), flexible links. {} The model refuses any tension past its fmax (`Error::Contact` / `Error::LimitPoint` from the \
solver; `limits` reports fmax at the console and `force` refuses past it).\n",
        if fmax.values().any(|f| matches!(f, Ok((_, BranchEnd::LimitPoint, _)))) {
            "In some configurations the model's branch ends at a limit point (marked below)."
        } else {
            "The model's branch ends by contact (or, for m = 1, not below the search bound) in every \
scene and configuration: no limit point comes first; the reference's ends by contact too."
        }
    );
    let _ = writeln!(w, "| scene | modulus | reference closes at (N) | m = 1 | m = 2 | m = 4 | m = 8 |");
    let _ = writeln!(w, "| --- | --- | --- | --- | --- | --- | --- |");
    for (i, s) in SCENES.iter().enumerate() {
        for plate in [false, true] {
            let rs = &refs[&(i, plate)];
            let mut line = format!(
                "| {} | {} | {} |",
                s.name,
                if plate { "plate" } else { "E_b" },
                rs.closing.map_or("none below 60".into(), |c| format!("{c:.3} (span {})", rs.closing_joint))
            );
            for m in MS {
                let c = Config { plate, flex: true, m };
                let cell = match (&fmax[&(i, c)], rs.closing) {
                    (Ok((t, k, j)), Some(cl)) => format!(" {t:.3} ({:+.1} %, {} {j}) |", 100.0 * (t - cl) / cl, kind_name(*k)),
                    (Ok((t, k, j)), None) => format!(" {t:.3} ({} {j}) |", kind_name(*k)),
                    (Err(e), _) => format!(" {e} |"),
                };
                line += &cell;
            }
            let _ = writeln!(w, "{line}");
        }
    }

    // instruction table
    let _ = writeln!(w, "\n## Instructions per forward solve on the Cortex-M4F, and the total error\n");
    let _ = writeln!(
        w,
        "QEMU `netduinoplus2` with `-icount shift=0`, f32, converged solver (its default tolerance, \
raised to f32's resolution), the bench image `bench/src/bin/fidelity.rs` (same counting and \
calibration as `finger-bench`, docs/performance.md). \"solve\": `Finger::solve_with` (equilibrium, \
posture, excursion, tangent); \"setup\": `Finger::compliances` (once per voltage change). \"total \
error\": the target's own f32 answer against the continuum reference: model and numerics together, \
what a user of the board sees.\n"
    );
    let _ = writeln!(w, "| case | modulus, links | m | solve libm | solve fast-trig | solve micromath | setup libm | total error libm: joint / tip | total error micromath: joint / tip |");
    let _ = writeln!(w, "| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for &(case, si, t) in CASES {
        for &(plate, flex) in BENCH_CFGS {
            for m in MS {
                let c = Config { plate, flex, m };
                let rs = &refs[&(si, plate)];
                let r = rs.tensions.iter().position(|&x| x == t).and_then(|k| rs.sols[k].as_ref().ok());
                let tot = |img: &str| -> String {
                    match (instr(img, c, case).map(|x| &x.result), r) {
                        (Some(Ok((tip, a, _))), Some(r)) => {
                            let e = compare(a, *tip, r);
                            format!("{} / {:.2} mm", pct(e.pct), e.tip)
                        }
                        (Some(Err(code)), _) => format!("err {code}"),
                        _ => "—".into(),
                    }
                };
                let n = |img: &str, setup: bool| instr(img, c, case).map_or("—".into(), |x| format!("{:.0}", if setup { x.setup_instr } else { x.instr }));
                let _ = writeln!(
                    w,
                    "| {case} | {}, {} | {m} | {} | {} | {} | {} | {} | {} |",
                    if plate { "plate" } else { "E_b" },
                    if flex { "flexible" } else { "rigid" },
                    n("m4f-libm", false),
                    n("m4f-fast-trig", false),
                    n("m4f-micromath", false),
                    n("m4f-libm", true),
                    tot("m4f-libm"),
                    tot("m4f-micromath")
                );
            }
        }
    }

    // detail tables
    let _ = writeln!(w, "\n## Per scene\n");
    let _ = writeln!(
        w,
        "Each cell: worst joint's error in % / largest joint-angle error in degrees / tip error in mm. \
\"refused\": the tension is past the model's own fmax (it refuses it with a typed error).\n"
    );
    for (i, s) in SCENES.iter().enumerate() {
        for plate in [false, true] {
            let rs = &refs[&(i, plate)];
            let _ = writeln!(w, "### `{}`, {}\n", s.name, if plate { "plate modulus" } else { "E_b" });
            let _ = writeln!(
                w,
                "Reference joint angles (degrees, joints 1..3): {}\n",
                rs.tensions
                    .iter()
                    .zip(&rs.sols)
                    .map(|(t, r)| match r {
                        Ok(r) => format!("{} N: {}", fmt_t(*t), r.joint_angles.iter().map(|a| format!("{:.2}", a.to_degrees())).collect::<Vec<_>>().join(", ")),
                        Err(e) => format!("{} N: {e}", fmt_t(*t)),
                    })
                    .collect::<Vec<_>>()
                    .join("; ")
            );
            let mut head = "| links | m |".to_string();
            let mut sep = "| --- | --- |".to_string();
            for t in &rs.tensions {
                head += &format!(" {} N |", fmt_t(*t));
                sep += " --- |";
            }
            let _ = writeln!(w, "{head}\n{sep}");
            for flex in [false, true] {
                for m in MS {
                    let c = Config { plate, flex, m };
                    let mut line = format!("| {} | {m} |", if flex { "flexible" } else { "rigid" });
                    for &t in &rs.tensions {
                        let r = rows.iter().find(|r| r.scene == i && r.cfg == c && r.tension == t).unwrap();
                        line += &match &r.out {
                            Ok(e) => format!(" {:+.1} % / {:.2}° / {:.2} |", e.pct, e.deg, e.tip),
                            Err(e) if e.starts_with("model") => " refused |".to_string(),
                            Err(e) => format!(" {e} |"),
                        };
                    }
                    let _ = writeln!(w, "{line}");
                }
            }
            let _ = writeln!(w);
        }
    }

    // figures
    let _ = writeln!(w, "## Figures\n");
    let _ = writeln!(
        w,
        "Postures of the three-element model (solid, nodes as dots, sub-element ends as vertices) and \
of the continuum reference (dashed, same colour) at the same tensions; the last tension is 0.95 × the \
smaller of the two branch ends. Drawn by `host_tests::svg::plot` from generated scenes.\n"
    );
    for (file, title) in &figures {
        let _ = writeln!(w, "![{title}](fidelity/{file})\n");
    }

    // console
    let _ = writeln!(w, "## Console parameters (docs/console.md style)\n");
    let _ = writeln!(
        w,
        "`param <name> [<value>]` reads or sets them (only while disarmed; the ceilings and `fmax` are \
recomputed). They are rows of `finger_model::params::PARAMS`, so the console, the scene files and \
`Params::set` share names and ranges. A value outside its range is `err usage: ...` naming the range; \
a rejected command changes nothing.\n"
    );
    let _ = writeln!(w, "| name | meaning | range | default now | recommended |");
    let _ = writeln!(w, "| --- | --- | --- | --- | --- |");
    let d0 = Params::<f64>::default();
    let rec_m = chosen.map_or("8".to_string(), |c| c.m.to_string());
    for (name, meaning, rec) in [
        ("m", "sub-elements per hinge; 1 is the paper's model", rec_m.as_str()),
        ("plate", "1: hinges and links bend with the plate modulus E_b/(1 − nu_b²); 0: E_b", "1"),
        ("nu_b", "the body's Poisson ratio (used when plate = 1)", "0.45"),
        ("flex_links", "1: the links are beams of the body (compression and bending under the cable); 0: rigid", "1"),
    ] {
        let info = finger_model::params::PARAMS.iter().find(|p| p.name == name).expect("console parameter exists");
        let _ = writeln!(w, "| `{name}` | {meaning} | {} | {} | {rec} |", info.range, d0.get(name).unwrap());
    }
    // the console's view of the default finger (4 layers, 0 V) with the recommended switches
    let cc = chosen.unwrap_or(Config { plate: true, flex: true, m: 8 });
    let cp = params(&SCENES[1], cc);
    let cf = Finger::with_calibration(cp, Calibration::for_params(&cp)).expect("valid parameters");
    let cb = cf.fmax(&SCENES[1].volts).expect("fmax of the default finger");
    let past = 1.1 * cb.tension;
    // what `force` answers (src/app.rs: the tension against `Finger::fmax`, f32 on the board)
    let refusal = {
        let e = finger_model::Error::ForceLimit { tension: past as f32 as f64, fmax: cb.tension as f32 as f64 };
        format!("err {}: {e}", e.code())
    };
    assert!(cf.solve(past, &SCENES[1].volts, Method::converged()).is_err(), "the solver refuses past fmax too");
    let _ = writeln!(
        w,
        "\nExamples (the finger with 4 layers at 0 V, m = {}, plate = 1, flex_links = 1, as the board holds it: with its FE calibration for m = 8; numbers from the model):\n\n```\n\
> param m 9\nerr usage: parameter m out of range: integer 1..8\n> param nu_b 0.5\nerr usage: parameter nu_b out of range: 0..0.499\n\
> param m {}\nok m={}\n> limits\nok ... fmax={:.4} fmax_end={},{} ...\n> force {:.1}\n{refusal}\n```\n",
        cc.m,
        cc.m,
        cc.m,
        cb.tension,
        match cb.kind {
            BranchEnd::Contact => "contact",
            BranchEnd::LimitPoint => "limit-point",
            BranchEnd::SearchBound => "search-bound",
        },
        cb.joint,
        past
    );
    let _ = writeln!(
        w,
        "`limits` reports `fmax` and `fmax_end=<contact|limit-point|search-bound>,<joint>` from \
`Finger::fmax` for the target voltages: the lowest tension at which a span closes to `span_floor` \
(contact) or a joint's equilibrium tangent turns singular (limit point). `force` refuses a tension \
past it with `err limit` naming fmax (`Error::ForceLimit`), and changes nothing; `solve` and the \
other commands that solve are refused by the converged solver itself, whose continuation cannot \
pass the branch end (`Error::Contact` / `Error::LimitPoint`, code `limit`). With m = 1 and \
no stacks the span never closes below the search bound (50 × the tension that turns the softest \
joint by 1 rad linearly), so fmax is that bound (`search-bound`): one more reason not to use m = 1."
    );

    std::fs::write(out_dir.join("fidelity.md"), d).expect("write fidelity.md");
    eprintln!("wrote {}", out_dir.join("fidelity.md").display());
}

/// Tension without trailing zeros.
fn fmt_t(t: f64) -> String {
    let s = format!("{t:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// A scene file for a figure: the scene's finger with the configuration's switches.
fn scene_text(title: &str, s: &SceneDef, c: Config, tensions: &[f64]) -> String {
    let v = s.volts.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", ");
    format!(
        "title = {title:?}\n[finger]\npreset = \"{}\"\nlayers = {}\nm = {}\nplate = {}\nflex_links = {}\nnu_b = {NU_B}\nvolts = [{v}]\n\
[drive]\ntensions = [{}]\n[output]\npostures = true\nreference = \"continuum\"\n",
        if s.paper { "paper" } else { "default" },
        s.layers,
        c.m,
        c.plate as u32,
        c.flex as u32,
        tensions.iter().map(|t| t.to_string()).collect::<Vec<_>>().join(", ")
    )
}
