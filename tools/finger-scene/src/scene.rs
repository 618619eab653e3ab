//! Scenes: small text files that say which finger to solve, at which tensions and voltages
//! (or stack thicknesses), with which solver, and what to output (docs/scenes.md has the
//! format, key by key). This module parses a scene, runs it on the model (f64), and renders
//! the results as CSV; `crate::svg` draws the postures.
//!
//! What it is: a host tool. Parsing errors carry the scene's line number; the model's refusals
//! (a thickness past the 33 % limit, a voltage past the ceiling) carry the joint, the limit and
//! the line that asked for it. Nothing is written by this module: `run` computes everything
//! first, so a refused scene leaves no output file behind (the binary writes only on success).
//!
//! What it is not: the model (finger_model) or the continuum reference (`crate::continuum`,
//! reached only through [`ReferenceSolver`] when a scene asks for `reference = continuum`).
//!
//! The format is a deliberately tiny `key = value` file with `[section]` headers and `#`
//! comments: no dependency, and every error names its line.

use finger_model::{de, mat3::Mat3, params::PARAMS, Error, Finger, Method, Params, Pose, Solution};
use std::fmt;

/// An error while reading or running a scene: the line (1-based; 0 = the scene as a whole) and
/// what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    pub line: usize,
    pub message: String,
    /// The model's typed error, when the model refused.
    pub model: Option<Error>,
}

impl SceneError {
    fn at(line: usize, message: impl Into<String>) -> Self {
        SceneError { line, message: message.into(), model: None }
    }
    fn model(line: usize, what: &str, e: Error) -> Self {
        SceneError { line, message: format!("{what}: {e}"), model: Some(e) }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "line {}: {}", self.line, self.message)
        } else {
            write!(f, "{}", self.message)
        }
    }
}

impl std::error::Error for SceneError {}

/// How the stacks are driven: one voltage per joint (V), or one target stack thickness per
/// joint (mm), converted with `finger_model::de::voltage_for_thickness`.
#[derive(Clone, Debug, PartialEq)]
pub enum Drive {
    Volts(Vec<f64>),
    Thickness(Vec<f64>),
}

/// A finger: parameters (preset + overrides) and its drive, with the lines they came from.
#[derive(Clone, Debug, PartialEq)]
pub struct FingerSpec {
    pub params: Params<f64>,
    pub drive: Drive,
    /// Line of the `volts`/`thickness` key (0 if defaulted to 0 V).
    pub drive_line: usize,
    /// Line of the section header (for parameter-set errors).
    pub section_line: usize,
}

/// The `[match]` section: find the tension at which the scene's finger reaches the tip angle
/// that this other finger reaches at `tension`.
#[derive(Clone, Debug, PartialEq)]
pub struct MatchSpec {
    pub finger: FingerSpec,
    pub tension: f64,
    /// Also draw the matched finger's own posture (dashed).
    pub show: bool,
    pub line: usize,
}

/// Which solver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SolverSpec {
    Converged { tol: f64 },
    Stepping { n_inc: u32 },
}

impl SolverSpec {
    pub fn method(&self) -> Method<f64> {
        match *self {
            SolverSpec::Converged { tol } => Method::Converged { tol, max_iter: 200 },
            SolverSpec::Stepping { n_inc } => Method::Stepping { n_inc },
        }
    }
}

/// A reference model to overlay.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reference {
    None,
    Continuum,
}

/// What a scene outputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputSpec {
    /// Postures CSV (node and hinge-end positions) and the SVG plot.
    pub postures: bool,
    /// Linearised tip stiffness (computed only when asked).
    pub tip_stiffness: bool,
    /// Cable excursion column.
    pub cable_excursion: bool,
    pub reference: Reference,
}

/// A parsed scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// From the file name (or "scene").
    pub name: String,
    pub title: String,
    pub finger: FingerSpec,
    pub tensions: Vec<f64>,
    pub tensions_line: usize,
    pub matching: Option<MatchSpec>,
    pub solver: SolverSpec,
    pub solver_line: usize,
    pub output: OutputSpec,
    pub output_line: usize,
}

/// Where a posture comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// One of the scene's tensions.
    Tension,
    /// The `[match]` result: the scene's finger at the matching tension.
    Matched,
    /// The `[match]` finger's own posture at its tension.
    MatchTarget,
}

impl Kind {
    pub fn name(&self) -> &'static str {
        match self {
            Kind::Tension => "tension",
            Kind::Matched => "matched",
            Kind::MatchTarget => "match-target",
        }
    }
}

/// A reference model's posture for the same finger, tension and voltages.
#[derive(Clone, Debug, PartialEq)]
pub struct RefPosture {
    /// Polyline of the reference's centreline, mm (base frame).
    pub points: Vec<[f64; 2]>,
    /// Joint angles, rad.
    pub joint_angles: Vec<f64>,
    /// Tip pose.
    pub tip: Pose<f64>,
}

/// A solved posture and what the scene asked for with it.
#[derive(Clone, Debug)]
pub struct Posture {
    pub label: String,
    pub kind: Kind,
    pub tension: f64,
    pub volts: Vec<f64>,
    pub thickness: Vec<f64>,
    pub solution: Solution<f64>,
    /// Centreline polyline: node 0, then per joint the sub-element ends of its hinge, then
    /// its distal node. mm, base frame.
    pub points: Vec<[f64; 2]>,
    /// K_tip (x mm, y mm, θ rad), when asked.
    pub stiffness: Option<Mat3<f64>>,
    pub reference: Option<RefPosture>,
}

impl Posture {
    pub fn joint_angles(&self) -> &[f64] {
        self.solution.joint_angles()
    }
    pub fn tip(&self) -> Pose<f64> {
        self.solution.tip()
    }
}

/// A run scene.
#[derive(Clone, Debug)]
pub struct SceneResult {
    pub scene: Scene,
    pub n: usize,
    pub postures: Vec<Posture>,
    /// The matching tension, N, when the scene has `[match]`.
    pub matched_tension: Option<f64>,
}

/// A reference model the runner can overlay (the continuum reference implements it).
pub trait ReferenceSolver {
    /// The reference posture of the finger `params` under `tension` (N), its stacks driven at
    /// `volts` (V) to whole-stack thicknesses `thickness` (mm, as the model computes them).
    fn solve(&self, params: &Params<f64>, tension: f64, volts: &[f64], thickness: &[f64]) -> Result<RefPosture, String>;
}

// ---------------------------------------------------------------------------------------------
// Parsing

const SECTIONS: &[&str] = &["scene", "finger", "drive", "match", "solver", "output"];

fn parse_number(line: usize, key: &str, s: &str) -> Result<f64, SceneError> {
    let t = s.trim();
    let v: f64 = t
        .parse()
        .map_err(|_| SceneError::at(line, format!("{key}: `{t}` is not a number")))?;
    if !v.is_finite() {
        return Err(SceneError::at(line, format!("{key}: `{t}` is not a finite number")));
    }
    Ok(v)
}

fn parse_list(line: usize, key: &str, s: &str) -> Result<Vec<f64>, SceneError> {
    if s.trim().is_empty() {
        return Err(SceneError::at(line, format!("{key}: needs at least one value")));
    }
    s.split(',').map(|x| parse_number(line, key, x)).collect()
}

fn parse_bool(line: usize, key: &str, s: &str) -> Result<bool, SceneError> {
    match s.trim().to_ascii_lowercase().as_str() {
        "yes" | "true" | "on" | "1" => Ok(true),
        "no" | "false" | "off" | "0" => Ok(false),
        other => Err(SceneError::at(line, format!("{key}: `{other}` is not yes/no"))),
    }
}

/// Strip a trailing `# comment` and surrounding space.
fn strip(raw: &str) -> &str {
    match raw.find('#') {
        Some(i) => raw[..i].trim(),
        None => raw.trim(),
    }
}

/// A finger section being read: preset, overrides in order, drive.
#[derive(Default)]
struct FingerDraft {
    section_line: usize,
    preset: Option<(usize, String)>,
    overrides: Vec<(usize, String, f64)>,
    drive: Option<(usize, Drive)>,
}

impl FingerDraft {
    fn key(&mut self, line: usize, key: &str, val: &str) -> Result<bool, SceneError> {
        match key {
            "preset" => {
                let v = val.to_ascii_lowercase();
                if v != "default" && v != "paper" {
                    return Err(SceneError::at(line, format!("preset: `{val}` is not default or paper")));
                }
                self.preset = Some((line, v));
            }
            "volts" | "thickness" => {
                if let Some((l, _)) = &self.drive {
                    return Err(SceneError::at(
                        line,
                        format!("{key}: the drive is already given on line {l} (volts or thickness, not both)"),
                    ));
                }
                let list = parse_list(line, key, val)?;
                let d = if key == "volts" { Drive::Volts(list) } else { Drive::Thickness(list) };
                self.drive = Some((line, d));
            }
            _ if PARAMS.iter().any(|p| p.name == key) => {
                if self.overrides.iter().any(|(_, k, _)| k == key) {
                    return Err(SceneError::at(line, format!("{key}: given twice")));
                }
                let v = parse_number(line, key, val)?;
                self.overrides.push((line, key.to_string(), v));
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// Preset, then the overrides. `Params::set` validates the whole set after each change, so
    /// an override that is only consistent with a later one (e.g. `a` before `l`) is retried
    /// after the others; what still fails is reported at its line.
    fn build(self, base_line: usize) -> Result<FingerSpec, SceneError> {
        let mut p = match self.preset.as_ref().map(|(_, s)| s.as_str()) {
            Some("paper") => Params::<f64>::paper(),
            _ => Params::<f64>::default(),
        };
        let mut pending = self.overrides;
        loop {
            let before = pending.len();
            let mut failed = Vec::new();
            let mut first_err = None;
            for (line, key, v) in pending {
                if let Err(e) = p.set(&key, v) {
                    if first_err.is_none() {
                        first_err = Some(SceneError::model(line, &key, e));
                    }
                    failed.push((line, key, v));
                }
            }
            if failed.is_empty() {
                break;
            }
            if failed.len() == before {
                return Err(first_err.unwrap_or_else(|| SceneError::at(base_line, "parameters")));
            }
            pending = failed;
        }
        let section_line = if self.section_line > 0 { self.section_line } else { base_line };
        let (drive_line, drive) = self.drive.unwrap_or((0, Drive::Volts(vec![0.0; p.n])));
        let len = match &drive {
            Drive::Volts(v) | Drive::Thickness(v) => v.len(),
        };
        let drive = if len == 1 && p.n > 1 {
            // one value for every joint
            match drive {
                Drive::Volts(v) => Drive::Volts(vec![v[0]; p.n]),
                Drive::Thickness(v) => Drive::Thickness(vec![v[0]; p.n]),
            }
        } else if len != p.n {
            let what = if matches!(drive, Drive::Volts(_)) { "volts" } else { "thickness" };
            return Err(SceneError::at(
                drive_line,
                format!("{what}: {len} values for {} joints (give one per joint, or one for all)", p.n),
            ));
        } else {
            drive
        };
        Ok(FingerSpec { params: p, drive, drive_line, section_line })
    }
}

/// Parse a scene's text. `name` labels the outputs (usually the file stem).
pub fn parse(name: &str, text: &str) -> Result<Scene, SceneError> {
    let mut section = "scene".to_string();
    let mut seen_sections: Vec<(String, usize)> = Vec::new();
    let mut seen_keys: Vec<(String, String, usize)> = Vec::new();
    let mut title = None;
    let mut finger = FingerDraft::default();
    let mut mfinger = FingerDraft::default();
    let mut m_tension = None;
    let mut m_show = true;
    let mut m_line = 0;
    let mut tensions = None;
    let mut method = None;
    let mut n_inc = None;
    let mut tol = None;
    let mut solver_line = 0;
    let mut output = OutputSpec { postures: true, tip_stiffness: false, cable_excursion: true, reference: Reference::None };
    let mut output_line = 0;

    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let s = strip(raw);
        if s.is_empty() {
            continue;
        }
        if let Some(rest) = s.strip_prefix('[') {
            let Some(inner) = rest.strip_suffix(']') else {
                return Err(SceneError::at(line, format!("`{s}`: a section header is `[name]`")));
            };
            let inner = inner.trim().to_ascii_lowercase();
            if !SECTIONS.contains(&inner.as_str()) {
                return Err(SceneError::at(
                    line,
                    format!("unknown section [{inner}] (known: {})", SECTIONS.join(", ")),
                ));
            }
            if let Some((_, l)) = seen_sections.iter().find(|(n, _)| *n == inner) {
                return Err(SceneError::at(line, format!("section [{inner}] already opened on line {l}")));
            }
            seen_sections.push((inner.clone(), line));
            match inner.as_str() {
                "finger" => finger.section_line = line,
                "match" => {
                    mfinger.section_line = line;
                    m_line = line;
                }
                "solver" => solver_line = line,
                "output" => output_line = line,
                _ => {}
            }
            section = inner;
            continue;
        }
        let Some(eq) = s.find('=') else {
            return Err(SceneError::at(line, format!("`{s}`: expected `key = value` or `[section]`")));
        };
        let key = s[..eq].trim().to_ascii_lowercase();
        let val = s[eq + 1..].trim();
        if key.is_empty() {
            return Err(SceneError::at(line, "missing key before `=`"));
        }
        if val.is_empty() {
            return Err(SceneError::at(line, format!("{key}: missing value")));
        }
        if let Some((_, _, l)) = seen_keys.iter().find(|(sec, k, _)| *sec == section && *k == key) {
            return Err(SceneError::at(line, format!("{key}: already given on line {l}")));
        }
        seen_keys.push((section.clone(), key.clone(), line));
        let unknown = |what: &str| {
            SceneError::at(line, format!("unknown key `{key}` in [{section}] (expected {what})"))
        };
        match section.as_str() {
            "scene" => match key.as_str() {
                "title" => title = Some(val.trim_matches('"').to_string()),
                _ => return Err(unknown("title")),
            },
            "finger" => {
                if !finger.key(line, &key, val)? {
                    return Err(unknown("preset, volts, thickness or a parameter name"));
                }
            }
            "drive" => match key.as_str() {
                "tensions" | "tension" => {
                    let t = parse_list(line, &key, val)?;
                    if let Some(bad) = t.iter().find(|&&x| x < 0.0) {
                        return Err(SceneError::at(line, format!("{key}: {bad} N: a cable cannot push (tension >= 0)")));
                    }
                    tensions = Some((line, t));
                }
                "volts" | "thickness" => {
                    finger.key(line, &key, val)?;
                }
                _ => return Err(unknown("tensions, volts or thickness")),
            },
            "match" => match key.as_str() {
                "tension" => {
                    let t = parse_number(line, &key, val)?;
                    if t <= 0.0 {
                        return Err(SceneError::at(line, "tension: the match needs a positive tension"));
                    }
                    m_tension = Some(t);
                }
                "show" => m_show = parse_bool(line, &key, val)?,
                _ => {
                    if !mfinger.key(line, &key, val)? {
                        return Err(unknown("tension, show, preset, volts, thickness or a parameter name"));
                    }
                }
            },
            "solver" => match key.as_str() {
                "method" => {
                    let v = val.to_ascii_lowercase();
                    if v != "converged" && v != "stepping" {
                        return Err(SceneError::at(line, format!("method: `{val}` is not converged or stepping")));
                    }
                    method = Some((line, v));
                }
                "n_inc" => {
                    let v = parse_number(line, &key, val)?;
                    if !(1.0..=100_000.0).contains(&v) || v.fract() != 0.0 {
                        return Err(SceneError::at(line, "n_inc: an integer 1..100000"));
                    }
                    n_inc = Some((line, v as u32));
                }
                "tol" => {
                    let v = parse_number(line, &key, val)?;
                    if v <= 0.0 {
                        return Err(SceneError::at(line, "tol: must be positive (mm)"));
                    }
                    tol = Some((line, v));
                }
                _ => return Err(unknown("method, n_inc or tol")),
            },
            "output" => match key.as_str() {
                "postures" => output.postures = parse_bool(line, &key, val)?,
                "tip_stiffness" => output.tip_stiffness = parse_bool(line, &key, val)?,
                "cable_excursion" => output.cable_excursion = parse_bool(line, &key, val)?,
                "reference" => {
                    output.reference = match val.to_ascii_lowercase().as_str() {
                        "none" => Reference::None,
                        "continuum" => Reference::Continuum,
                        _ => return Err(SceneError::at(line, format!("reference: `{val}` is not none or continuum"))),
                    }
                }
                _ => return Err(unknown("postures, tip_stiffness, cable_excursion or reference")),
            },
            _ => unreachable!("sections are checked above"),
        }
    }

    let Some((tensions_line, tensions)) = tensions else {
        return Err(SceneError::at(0, "no tensions: the [drive] section needs `tensions = ...` (N)"));
    };
    let finger = finger.build(1)?;
    let matching = if m_line > 0 {
        let Some(t) = m_tension else {
            return Err(SceneError::at(m_line, "[match] needs `tension = ...` (N)"));
        };
        let f = mfinger.build(m_line)?;
        if f.params.n != finger.params.n {
            return Err(SceneError::at(m_line, "[match]: the finger must have as many joints as the scene's"));
        }
        Some(MatchSpec { finger: f, tension: t, show: m_show, line: m_line })
    } else {
        None
    };
    let solver = match method.as_ref().map(|(_, m)| m.as_str()) {
        Some("stepping") => {
            if let Some((l, _)) = tol {
                return Err(SceneError::at(l, "tol: only for method = converged"));
            }
            SolverSpec::Stepping { n_inc: n_inc.map(|(_, n)| n).unwrap_or(finger.params.n_inc) }
        }
        _ => {
            if let Some((l, _)) = n_inc {
                return Err(SceneError::at(l, "n_inc: only for method = stepping"));
            }
            SolverSpec::Converged { tol: tol.map(|(_, t)| t).unwrap_or(1e-9) }
        }
    };
    Ok(Scene {
        name: name.to_string(),
        title: title.unwrap_or_else(|| name.to_string()),
        finger,
        tensions,
        tensions_line,
        matching,
        solver,
        solver_line,
        output,
        output_line,
    })
}

// ---------------------------------------------------------------------------------------------
// Running

/// A prepared finger: the model, its channel voltages and stack thicknesses.
struct Prepared {
    finger: Finger<f64>,
    volts: Vec<f64>,
}

fn prepare(spec: &FingerSpec) -> Result<Prepared, SceneError> {
    let finger = Finger::new(spec.params).map_err(|e| SceneError::model(spec.section_line, "parameters", e))?;
    let volts = match &spec.drive {
        Drive::Volts(v) => {
            for (k, &x) in v.iter().enumerate() {
                de::check_voltage(&spec.params, k + 1, x).map_err(|e| SceneError::model(spec.drive_line, "volts", e))?;
            }
            v.clone()
        }
        Drive::Thickness(t) => t
            .iter()
            .enumerate()
            .map(|(k, &x)| {
                de::voltage_for_thickness(&spec.params, k + 1, x)
                    .map_err(|e| SceneError::model(spec.drive_line, "thickness", e))
            })
            .collect::<Result<Vec<_>, _>>()?,
    };
    // the compliances check every voltage against the ceiling once more
    finger.compliances(&volts).map_err(|e| SceneError::model(spec.drive_line, "drive", e))?;
    Ok(Prepared { finger, volts })
}

/// The centreline polyline of a solution: node 0, each hinge's sub-element ends, each node.
pub fn posture_points(params: &Params<f64>, sol: &Solution<f64>) -> Vec<[f64; 2]> {
    let sub = params.hinge_len() / sol.m as f64;
    let mut pts = vec![[sol.nodes[0].x, sol.nodes[0].y]];
    for k in 0..sol.n {
        let mut pose = sol.nodes[k];
        for j in 0..sol.m {
            let q = sol.q[k][j];
            pose = pose.then(sub + q[0], q[1], q[2]);
            pts.push([pose.x, pose.y]);
        }
        // the node as solved (a flexible link bends between the hinge's end and the node)
        pts.push([sol.nodes[k + 1].x, sol.nodes[k + 1].y]);
    }
    pts
}

fn solve_one(
    prep: &Prepared,
    scene: &Scene,
    tension: f64,
    line: usize,
    label: String,
    kind: Kind,
    reference: Option<&dyn ReferenceSolver>,
) -> Result<Posture, SceneError> {
    let sol = prep
        .finger
        .solve(tension, &prep.volts, scene.solver.method())
        .map_err(|e| SceneError::model(line, &format!("tension {tension} N"), e))?;
    let p = prep.finger.params();
    let stiffness = if scene.output.tip_stiffness {
        Some(prep.finger.tip_stiffness(&sol).map_err(|e| SceneError::model(scene.output_line, "tip_stiffness", e))?)
    } else {
        None
    };
    let reference = match (scene.output.reference, reference) {
        (Reference::None, _) => None,
        (Reference::Continuum, Some(r)) => Some(
            r.solve(p, tension, &prep.volts, &sol.thickness[..sol.n])
                .map_err(|e| SceneError::at(scene.output_line, format!("reference at {tension} N: {e}")))?,
        ),
        (Reference::Continuum, None) => {
            return Err(SceneError::at(scene.output_line, "reference = continuum: no continuum reference in this build"))
        }
    };
    Ok(Posture {
        label,
        kind,
        tension,
        volts: prep.volts.clone(),
        thickness: sol.thickness[..sol.n].to_vec(),
        points: posture_points(p, &sol),
        solution: sol,
        stiffness,
        reference,
    })
}

/// The tension (N) at which `prep`'s tip angle equals `target` (rad): bisection, the tip angle
/// growing monotonically with the tension under tension alone.
fn tension_for_tip_angle(prep: &Prepared, scene: &Scene, target: f64, line: usize) -> Result<f64, SceneError> {
    let angle = |p: f64| -> Result<f64, SceneError> {
        prep.finger
            .solve(p, &prep.volts, scene.solver.method())
            .map(|s| s.tip().theta)
            .map_err(|e| SceneError::model(line, "match", e))
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    let mut grow = 0;
    while angle(hi)? < target {
        lo = hi;
        hi *= 2.0;
        grow += 1;
        if grow > 20 {
            return Err(SceneError::at(line, "match: no tension reaches the target tip angle"));
        }
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if angle(mid)? < target {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-12 * hi.max(1.0) {
            break;
        }
    }
    Ok(0.5 * (lo + hi))
}

fn fmt_g(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}

/// Run a scene: every posture it asks for, nothing more. `reference` is the continuum
/// reference (needed only if the scene says `reference = continuum`).
pub fn run(scene: &Scene, reference: Option<&dyn ReferenceSolver>) -> Result<SceneResult, SceneError> {
    let prep = prepare(&scene.finger)?;
    let n = scene.finger.params.n;
    let mut postures = Vec::new();
    for &t in &scene.tensions {
        postures.push(solve_one(&prep, scene, t, scene.tensions_line, format!("{} N", fmt_g(t)), Kind::Tension, reference)?);
    }
    let mut matched_tension = None;
    if let Some(m) = &scene.matching {
        let mprep = prepare(&m.finger)?;
        let target = mprep
            .finger
            .solve(m.tension, &mprep.volts, scene.solver.method())
            .map_err(|e| SceneError::model(m.line, "match", e))?;
        let tm = tension_for_tip_angle(&prep, scene, target.tip().theta, m.line)?;
        matched_tension = Some(tm);
        postures.push(solve_one(
            &prep,
            scene,
            tm,
            m.line,
            format!("{} N: same tip angle as [match] at {} N", fmt_g(tm), fmt_g(m.tension)),
            Kind::Matched,
            reference,
        )?);
        if m.show {
            let mscene = Scene { finger: m.finger.clone(), ..scene.clone() };
            postures.push(solve_one(
                &mprep,
                &mscene,
                m.tension,
                m.line,
                format!("[match] finger at {} N", fmt_g(m.tension)),
                Kind::MatchTarget,
                reference,
            )?);
        }
    }
    Ok(SceneResult { scene: scene.clone(), n, postures, matched_tension })
}

// ---------------------------------------------------------------------------------------------
// CSV

/// One row per posture: tension, voltages, thicknesses, joint angles, tip pose, and what the
/// scene asked for (cable excursion, tip stiffness, reference errors). Numbers are written in
/// Rust's shortest round-trip form, so a reader gets the model's f64 values exactly.
pub fn summary_csv(r: &SceneResult) -> String {
    let n = r.n;
    let o = &r.scene.output;
    let mut head = vec!["scene".to_string(), "label".into(), "kind".into(), "tension_N".into()];
    head.extend((1..=n).map(|k| format!("volts{k}_V")));
    head.extend((1..=n).map(|k| format!("thickness{k}_mm")));
    head.extend((1..=n).map(|k| format!("joint{k}_deg")));
    head.extend(["tip_x_mm", "tip_y_mm", "tip_deg"].map(String::from));
    if o.cable_excursion {
        head.push("cable_excursion_mm".into());
    }
    if o.tip_stiffness {
        head.extend(["k_xx_N_per_mm", "k_yy_N_per_mm", "k_tt_Nmm_per_rad", "k_xy_N_per_mm", "k_xt_N_per_rad", "k_yt_N_per_rad"].map(String::from));
    }
    if o.reference != Reference::None {
        head.extend((1..=n).map(|k| format!("ref_joint{k}_deg")));
        head.extend(["ref_tip_x_mm", "ref_tip_y_mm", "ref_tip_deg", "err_tip_mm", "err_tip_deg"].map(String::from));
        head.extend((1..=n).map(|k| format!("err_joint{k}_deg")));
    }
    head.extend(["iterations", "residual_mm"].map(String::from));
    let mut out = head.join(",");
    out.push('\n');
    for p in &r.postures {
        let s = &p.solution;
        let mut row = vec![r.scene.name.clone(), csv_text(&p.label), p.kind.name().into(), p.tension.to_string()];
        row.extend(p.volts.iter().map(|v| v.to_string()));
        row.extend(p.thickness.iter().map(|v| v.to_string()));
        row.extend(p.joint_angles().iter().map(|a| a.to_degrees().to_string()));
        let tip = p.tip();
        row.extend([tip.x, tip.y, tip.theta.to_degrees()].map(|v| v.to_string()));
        if o.cable_excursion {
            row.push(s.cable_excursion.to_string());
        }
        if o.tip_stiffness {
            let k = p.stiffness.unwrap_or([[f64::NAN; 3]; 3]);
            row.extend([k[0][0], k[1][1], k[2][2], k[0][1], k[0][2], k[1][2]].map(|v| v.to_string()));
        }
        if o.reference != Reference::None {
            match &p.reference {
                Some(rf) => {
                    row.extend(rf.joint_angles.iter().map(|a| a.to_degrees().to_string()));
                    let e = ((tip.x - rf.tip.x).powi(2) + (tip.y - rf.tip.y).powi(2)).sqrt();
                    row.extend([rf.tip.x, rf.tip.y, rf.tip.theta.to_degrees(), e, (tip.theta - rf.tip.theta).to_degrees()].map(|v| v.to_string()));
                    row.extend(
                        p.joint_angles().iter().zip(&rf.joint_angles).map(|(a, b)| (a - b).to_degrees().to_string()),
                    );
                }
                None => row.extend(std::iter::repeat(String::new()).take(2 * n + 5)),
            }
        }
        row.push(s.iterations.to_string());
        row.push(s.residual.to_string());
        out.push_str(&row.join(","));
        out.push('\n');
    }
    out
}

/// One row per polyline point: the posture's label, tension, point index, what the point is
/// (node k / hinge k end), x, y (mm). With a reference, its points follow with source=reference.
pub fn postures_csv(r: &SceneResult) -> String {
    let mut out = String::from("scene,posture,label,tension_N,source,point,what,x_mm,y_mm\n");
    for (i, p) in r.postures.iter().enumerate() {
        let m = p.solution.m;
        for (j, pt) in p.points.iter().enumerate() {
            let what = if j == 0 {
                "node 0".to_string()
            } else {
                let k = (j - 1) / (m + 1) + 1;
                let r = (j - 1) % (m + 1);
                if r == m { format!("node {k}") } else if r + 1 == m { format!("hinge {k} end") } else { format!("hinge {k} sub {}", r + 1) }
            };
            out.push_str(&format!(
                "{},{},{},{},model,{},{},{},{}\n",
                r.scene.name,
                i + 1,
                csv_text(&p.label),
                p.tension,
                j,
                what,
                pt[0],
                pt[1]
            ));
        }
        if let Some(rf) = &p.reference {
            for (j, pt) in rf.points.iter().enumerate() {
                out.push_str(&format!(
                    "{},{},{},{},reference,{},,{},{}\n",
                    r.scene.name,
                    i + 1,
                    csv_text(&p.label),
                    p.tension,
                    j,
                    pt[0],
                    pt[1]
                ));
            }
        }
    }
    out
}

fn csv_text(s: &str) -> String {
    if s.contains(',') || s.contains('"') {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The files a scene writes, by name, with their contents (nothing is written here).
pub fn outputs(r: &SceneResult) -> Vec<(String, String)> {
    let mut files = vec![(format!("{}.csv", r.scene.name), summary_csv(r))];
    if r.scene.output.postures {
        files.push((format!("{}-postures.csv", r.scene.name), postures_csv(r)));
        files.push((format!("{}.svg", r.scene.name), crate::svg::plot(r)));
    }
    files
}

/// Read, parse and run a scene file; the name is the file stem.
pub fn run_file(path: &std::path::Path, reference: Option<&dyn ReferenceSolver>) -> Result<SceneResult, SceneError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::at(0, format!("cannot read {}: {e}", path.display())))?;
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
    let scene = parse(name, &text)?;
    run(&scene, reference)
}

/// The continuum reference (`crate::continuum`) as a scene's `reference = continuum`: the real
/// geometry (notches, links as beams of the body material, bonded stacks of the thicknesses
/// the model computed for the scene's voltages, the cable as a follower load), at its default
/// discretisation. Its joint angle is the rotation node to node (hinge and link together), the
/// quantity the three-element model's joint angle stands for.
pub struct ContinuumReference {
    pub disc: continuum::Discretisation,
}

/// The continuum model's parameters for a finger of the model's parameters.
pub fn continuum_params(p: &Params<f64>) -> continuum::ContinuumParams {
    continuum::ContinuumParams {
        n: p.n,
        l: p.l,
        b: p.b,
        w: p.w,
        t_min: p.t_min,
        a: p.a,
        e_b: p.e_b,
        e: p.e,
        layers: p.layers as usize,
        z0: p.z0,
        e_de: p.e_de(),
        plate: p.plate,
        nu_b: p.nu_b,
        rigid_links: false,
        contact_floor: p.span_floor,
    }
}

impl ReferenceSolver for ContinuumReference {
    fn solve(&self, params: &Params<f64>, tension: f64, _volts: &[f64], thickness: &[f64]) -> Result<RefPosture, String> {
        let cp = continuum_params(params);
        let stacks: Vec<f64> = if params.layers == 0 { Vec::new() } else { thickness.to_vec() };
        let s = continuum::solve(&cp, tension, &stacks, [0.0, 0.0], self.disc).map_err(|e| e.to_string())?;
        Ok(RefPosture {
            points: s.centreline.iter().map(|c| [c[1], c[2]]).collect(),
            joint_angles: s.joint_angles.clone(),
            tip: Pose { x: s.tip.x, y: s.tip.y, theta: s.tip.theta },
        })
    }
}

/// The continuum reference, for scenes that say `reference = continuum`.
pub fn reference_solver() -> Option<Box<dyn ReferenceSolver>> {
    Some(Box::new(ContinuumReference { disc: continuum::Discretisation::default() }))
}
