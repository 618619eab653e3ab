//! A scene file: which finger to solve, at which tensions and voltages (or stack thicknesses),
//! with which solver, and what to output. TOML, read with serde and toml (docs/scenes.md has
//! the format, key by key).
//!
//! What it is: the format and its checks. Every error carries the line and column it is about:
//! toml's own (syntax, duplicate keys, a wrong type) at toml's span, ours (a parameter out of
//! range, a thickness past the 33 % limit, a wrong number of joint values) at the key that
//! asked for it. A file in the old INI format is refused with a pointer to the new one.
//!
//! What it is not: the runner (`crate::run`) or the outputs (`crate::csv`, `crate::svg`).

use finger_model::{de, params::PARAMS, Error, Method, Params};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;
use toml::Spanned;

/// A place in a scene file, 1-based; line 0 is the scene as a whole.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct Pos {
    pub line: usize,
    pub column: usize,
}

impl Pos {
    /// The scene as a whole (no line).
    pub const WHOLE: Pos = Pos { line: 0, column: 0 };

    /// The line and column of byte `offset` of `text` (columns count characters).
    pub fn of(text: &str, offset: usize) -> Pos {
        let before = &text[..offset.min(text.len())];
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        Pos { line: before.matches('\n').count() + 1, column: before[line_start..].chars().count() + 1 }
    }
}

impl fmt::Display for Pos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}, column {}", self.line, self.column)
    }
}

/// An error while reading or running a scene: where, and what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// 1-based; 0 = the scene as a whole.
    pub line: usize,
    pub column: usize,
    pub message: String,
    /// The model's typed error, when the model refused.
    pub model: Option<Error>,
}

impl SceneError {
    pub fn at(at: Pos, message: impl Into<String>) -> Self {
        SceneError { line: at.line, column: at.column, message: message.into(), model: None }
    }
    pub fn model(at: Pos, what: &str, e: Error) -> Self {
        SceneError { line: at.line, column: at.column, message: format!("{what}: {e}"), model: Some(e) }
    }
    pub fn pos(&self) -> Pos {
        Pos { line: self.line, column: self.column }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "{}: {}", self.pos(), self.message)
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

/// A finger: parameters (preset + overrides) and its drive, with where they came from.
#[derive(Clone, Debug, PartialEq)]
pub struct FingerSpec {
    pub params: Params<f64>,
    pub drive: Drive,
    /// The `volts`/`thickness` key (`Pos::WHOLE` if defaulted to 0 V).
    pub drive_at: Pos,
    /// The section header (for parameter-set errors).
    pub section_at: Pos,
}

/// The `[match]` section: find the tension at which the scene's finger reaches the tip angle
/// that this other finger reaches at `tension`.
#[derive(Clone, Debug, PartialEq)]
pub struct MatchSpec {
    pub finger: FingerSpec,
    pub tension: f64,
    /// Also draw the matched finger's own posture (dashed).
    pub show: bool,
    pub at: Pos,
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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
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
    /// False (`board = false`): the paper's model past what the board's film holds (voltages
    /// past its ceiling); `finger run` refuses it before any board is touched.
    pub board: bool,
    pub finger: FingerSpec,
    pub tensions: Vec<f64>,
    pub tensions_at: Pos,
    pub matching: Option<MatchSpec>,
    pub solver: SolverSpec,
    pub solver_at: Pos,
    pub output: OutputSpec,
    pub output_at: Pos,
}

// ---------------------------------------------------------------------------------------------
// The file as serde reads it

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    title: Option<String>,
    board: Option<bool>,
    finger: Option<Spanned<Keys>>,
    drive: Option<Spanned<Keys>>,
    #[serde(rename = "match")]
    matching: Option<Spanned<Keys>>,
    solver: Option<Spanned<SolverFile>>,
    output: Option<Spanned<OutputFile>>,
}

/// A section whose keys include the model's parameter names (checked here, not by serde).
type Keys = BTreeMap<Spanned<String>, Spanned<toml::Value>>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename_all = "lowercase")]
enum MethodName {
    Converged,
    Stepping,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SolverFile {
    method: Option<MethodName>,
    n_inc: Option<Spanned<u32>>,
    tol: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputFile {
    postures: Option<bool>,
    tip_stiffness: Option<bool>,
    cable_excursion: Option<bool>,
    reference: Option<Reference>,
}

// ---------------------------------------------------------------------------------------------
// Checks

/// Where a key is, from its value's span: the first non-blank character of the value's line
/// (scene keys are never dotted or inline).
fn key_at(text: &str, value: &Range<usize>) -> Pos {
    let p = Pos::of(text, value.start);
    let line = text.lines().nth(p.line - 1).unwrap_or("");
    let indent = line.chars().take_while(|c| c.is_whitespace()).count();
    Pos { line: p.line, column: indent + 1 }
}

/// Where a `[section]` is: its header's line.
fn section_at(text: &str, name: &str, table: &Range<usize>) -> Pos {
    let header = format!("[{name}]");
    let mut off = 0;
    for l in text.split_inclusive('\n') {
        let t = l.trim_start();
        if t.starts_with(&header) {
            return Pos::of(text, off + l.len() - t.len());
        }
        off += l.len();
    }
    Pos::of(text, table.start)
}

fn number(text: &str, key: &str, v: &Spanned<toml::Value>) -> Result<f64, SceneError> {
    let at = key_at(text, &v.span());
    let x = match v.get_ref() {
        toml::Value::Float(x) => *x,
        toml::Value::Integer(i) => *i as f64,
        toml::Value::Boolean(b) => f64::from(u8::from(*b)),
        other => return Err(SceneError::at(at, format!("{key}: `{other}` is not a number"))),
    };
    if !x.is_finite() {
        return Err(SceneError::at(at, format!("{key}: `{x}` is not a finite number")));
    }
    Ok(x)
}

/// A number or an array of numbers.
fn numbers(text: &str, key: &str, v: &Spanned<toml::Value>) -> Result<Vec<f64>, SceneError> {
    match v.get_ref() {
        toml::Value::Array(a) => {
            if a.is_empty() {
                return Err(SceneError::at(key_at(text, &v.span()), format!("{key}: needs at least one value")));
            }
            a.iter().map(|x| number(text, key, &Spanned::new(v.span(), x.clone()))).collect()
        }
        _ => Ok(vec![number(text, key, v)?]),
    }
}

/// A finger section being read: preset, overrides in file order, drive.
#[derive(Default)]
struct FingerDraft {
    section_at: Pos,
    preset: Option<String>,
    overrides: Vec<(Pos, String, f64)>,
    drive: Option<(Pos, Drive)>,
}

impl FingerDraft {
    /// Read one key; false if it is not a finger key.
    fn key(&mut self, text: &str, key: &str, v: &Spanned<toml::Value>) -> Result<bool, SceneError> {
        let at = key_at(text, &v.span());
        match key {
            "preset" => match v.get_ref().as_str() {
                Some(p @ ("default" | "paper")) => self.preset = Some(p.to_string()),
                _ => return Err(SceneError::at(at, format!("preset: `{}` is not \"default\" or \"paper\"", v.get_ref()))),
            },
            "volts" | "thickness" => {
                if let Some((first, _)) = &self.drive {
                    return Err(SceneError::at(at, format!("{key}: the drive is already given on line {} (volts or thickness, not both)", first.line)));
                }
                let list = numbers(text, key, v)?;
                let d = if key == "volts" { Drive::Volts(list) } else { Drive::Thickness(list) };
                self.drive = Some((at, d));
            }
            _ if PARAMS.iter().any(|p| p.name == key) => {
                let x = number(text, key, v)?;
                self.overrides.push((at, key.to_string(), x));
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// Preset, then the overrides. `Params::set` validates the whole set after each change, so
    /// an override that is only consistent with a later one (e.g. `a` before `l`) is retried
    /// after the others; what still fails is reported at its key.
    fn build(mut self) -> Result<FingerSpec, SceneError> {
        let mut p = match self.preset.as_deref() {
            Some("paper") => Params::<f64>::paper(),
            _ => Params::<f64>::default(),
        };
        self.overrides.sort_by_key(|o| o.0);
        let mut pending = self.overrides;
        while !pending.is_empty() {
            let before = pending.len();
            let mut failed = Vec::new();
            let mut first_err = None;
            for (at, key, v) in pending {
                if let Err(e) = p.set(&key, v) {
                    first_err.get_or_insert(SceneError::model(at, &key, e));
                    failed.push((at, key, v));
                }
            }
            if failed.len() == before {
                return Err(first_err.unwrap_or_else(|| SceneError::at(self.section_at, "parameters")));
            }
            pending = failed;
        }
        let (drive_at, drive) = self.drive.unwrap_or((Pos::WHOLE, Drive::Volts(vec![0.0; p.n])));
        let (Drive::Volts(v) | Drive::Thickness(v)) = &drive;
        let len = v.len();
        let drive = if len == 1 && p.n > 1 {
            // one value for every joint
            match drive {
                Drive::Volts(v) => Drive::Volts(vec![v[0]; p.n]),
                Drive::Thickness(v) => Drive::Thickness(vec![v[0]; p.n]),
            }
        } else if len != p.n {
            let what = if matches!(drive, Drive::Volts(_)) { "volts" } else { "thickness" };
            return Err(SceneError::at(drive_at, format!("{what}: {len} values for {} joints (give one per joint, or one for all)", p.n)));
        } else {
            drive
        };
        Ok(FingerSpec { params: p, drive, drive_at, section_at: self.section_at })
    }
}

/// Sorted by place in the file, so the first error reported is the first in the file.
fn in_file_order(keys: &Keys) -> Vec<(&str, &Spanned<toml::Value>)> {
    let mut v: Vec<_> = keys.iter().map(|(k, v)| (k.get_ref().as_str(), v)).collect();
    v.sort_by_key(|(_, v)| v.span().start);
    v
}

fn unknown(text: &str, key: &str, v: &Spanned<toml::Value>, section: &str, expected: &str) -> SceneError {
    SceneError::at(key_at(text, &v.span()), format!("unknown key `{key}` in [{section}] (expected {expected})"))
}

/// A line of the old INI format that is not TOML: an unquoted word or a comma list without
/// brackets after `=`.
fn old_format_line(text: &str) -> Option<usize> {
    text.lines().position(|l| {
        let l = l.split('#').next().unwrap_or("").trim();
        let Some((k, v)) = l.split_once('=') else { return false };
        let v = v.trim();
        let word = v.chars().next().is_some_and(|c| c.is_ascii_alphabetic()) && !["true", "false", "inf", "nan"].contains(&v);
        !k.trim().is_empty() && !v.is_empty() && (word || (v.contains(',') && !v.starts_with('[')))
    })
}

/// The pointer to the new format for an old-format scene.
pub const OLD_FORMAT: &str = "this looks like the old INI scene format; scenes are TOML now (quoted strings, \
     `[a, b, c]` lists, true/false), see docs/scenes.md";

/// toml's error, at its span, with the old-format pointer when the file looks like one, and the
/// first occurrence of a duplicate key or section.
fn toml_error(text: &str, e: toml::de::Error) -> SceneError {
    if let Some(i) = old_format_line(text) {
        // toml reports one of the file's errors; name the first old-format line's own
        let upto: usize = text.split_inclusive('\n').take(i + 1).map(str::len).sum();
        let e = toml::from_str::<toml::Table>(&text[..upto]).err().unwrap_or(e);
        let at = e.span().map_or(Pos::WHOLE, |s| Pos::of(text, s.start));
        return SceneError::at(at, format!("{}; {OLD_FORMAT}", e.message().trim_end()));
    }
    let at = e.span().map_or(Pos::WHOLE, |s| Pos::of(text, s.start));
    let mut message = e.message().trim_end().to_string();
    if let Some(name) = message.strip_prefix("unknown field `").and_then(|r| r.split('`').next()) {
        let line = text.lines().nth(at.line.saturating_sub(1)).unwrap_or("").trim_start();
        if line.starts_with('[') {
            message = format!("unknown section [{name}] (known: finger, drive, match, solver, output)");
        } else {
            message = format!("unknown key `{name}`: {message}");
        }
    }
    if message.starts_with("duplicate key") {
        // toml names neither the key nor its first place: the key is what starts the line
        let line = text.lines().nth(at.line.saturating_sub(1)).unwrap_or("").trim();
        let name = match line.strip_prefix('[') {
            Some(h) => h.split(']').next().unwrap_or(""),
            None => line.split('=').next().unwrap_or(""),
        }
        .trim();
        if let Some(first) = first_definition(text, name, at.line) {
            message = format!("duplicate key `{name}` (first on line {first})");
        }
    }
    SceneError::at(at, message)
}

/// The line where `name` was first given, before `line`: a `[name]` header anywhere, or a
/// `name =` key in the same section.
fn first_definition(text: &str, name: &str, line: usize) -> Option<usize> {
    let lines: Vec<&str> = text.lines().take(line.saturating_sub(1)).collect();
    let header = format!("[{name}]");
    if let Some(i) = lines.iter().position(|l| l.trim_start().starts_with(&header)) {
        return Some(i + 1);
    }
    let here = text.lines().nth(line.saturating_sub(1)).unwrap_or("");
    if here.trim_start().starts_with('[') {
        return None;
    }
    let section_start = lines.iter().rposition(|l| l.trim_start().starts_with('[')).map_or(0, |i| i + 1);
    (section_start..lines.len()).find(|&i| lines[i].trim_start().strip_prefix(name).is_some_and(|r| r.trim_start().starts_with('='))).map(|i| i + 1)
}

/// Parse a scene's TOML text. `name` labels the outputs (usually the file stem).
pub fn parse(name: &str, text: &str) -> Result<Scene, SceneError> {
    let file: SceneFile = toml::from_str(text).map_err(|e| toml_error(text, e))?;

    let mut finger = FingerDraft::default();
    if let Some(t) = &file.finger {
        finger.section_at = section_at(text, "finger", &t.span());
        for (k, v) in in_file_order(t.get_ref()) {
            if !finger.key(text, k, v)? {
                return Err(unknown(text, k, v, "finger", "preset, volts, thickness or a parameter name"));
            }
        }
    }
    let mut tensions: Option<(Pos, Vec<f64>)> = None;
    if let Some(t) = &file.drive {
        for (k, v) in in_file_order(t.get_ref()) {
            match k {
                "tensions" | "tension" => {
                    let at = key_at(text, &v.span());
                    if let Some((first, _)) = &tensions {
                        return Err(SceneError::at(at, format!("{k}: the tensions are already given on line {}", first.line)));
                    }
                    let list = numbers(text, k, v)?;
                    if let Some(bad) = list.iter().find(|&&x| x < 0.0) {
                        return Err(SceneError::at(at, format!("{k}: {bad} N: a cable cannot push (tension >= 0)")));
                    }
                    tensions = Some((at, list));
                }
                "volts" | "thickness" => {
                    finger.key(text, k, v)?;
                }
                _ => return Err(unknown(text, k, v, "drive", "tensions, volts or thickness")),
            }
        }
    }
    let Some((tensions_at, tensions)) = tensions else {
        return Err(SceneError::at(Pos::WHOLE, "no tensions: the [drive] section needs `tensions = [...]` (N)"));
    };
    let finger = finger.build()?;

    let matching = match &file.matching {
        None => None,
        Some(t) => {
            let at = section_at(text, "match", &t.span());
            let mut mfinger = FingerDraft { section_at: at, ..FingerDraft::default() };
            let (mut tension, mut show) = (None, true);
            for (k, v) in in_file_order(t.get_ref()) {
                match k {
                    "tension" => {
                        let x = number(text, k, v)?;
                        if x <= 0.0 {
                            return Err(SceneError::at(key_at(text, &v.span()), "tension: the match needs a positive tension"));
                        }
                        tension = Some(x);
                    }
                    "show" => match v.get_ref() {
                        toml::Value::Boolean(b) => show = *b,
                        other => return Err(SceneError::at(key_at(text, &v.span()), format!("show: `{other}` is not true or false"))),
                    },
                    _ => {
                        if !mfinger.key(text, k, v)? {
                            return Err(unknown(text, k, v, "match", "tension, show, preset, volts, thickness or a parameter name"));
                        }
                    }
                }
            }
            let Some(tension) = tension else {
                return Err(SceneError::at(at, "[match] needs `tension = ...` (N)"));
            };
            let f = mfinger.build()?;
            if f.params.n != finger.params.n {
                return Err(SceneError::at(at, "[match]: the finger must have as many joints as the scene's"));
            }
            Some(MatchSpec { finger: f, tension, show, at })
        }
    };

    let (solver, solver_at) = match &file.solver {
        None => (SolverSpec::Converged { tol: 1e-9 }, Pos::WHOLE),
        Some(s) => {
            let at = section_at(text, "solver", &s.span());
            let f = s.get_ref();
            let solver = match f.method {
                Some(MethodName::Stepping) => {
                    if let Some(t) = &f.tol {
                        return Err(SceneError::at(key_at(text, &t.span()), "tol: only for method = \"converged\""));
                    }
                    let n_inc = match &f.n_inc {
                        Some(n) if !(1..=100_000).contains(n.get_ref()) => return Err(SceneError::at(key_at(text, &n.span()), "n_inc: an integer 1..100000")),
                        Some(n) => *n.get_ref(),
                        None => finger.params.n_inc,
                    };
                    SolverSpec::Stepping { n_inc }
                }
                _ => {
                    if let Some(n) = &f.n_inc {
                        return Err(SceneError::at(key_at(text, &n.span()), "n_inc: only for method = \"stepping\""));
                    }
                    let tol = match &f.tol {
                        Some(t) if !(*t.get_ref() > 0.0 && t.get_ref().is_finite()) => {
                            return Err(SceneError::at(key_at(text, &t.span()), "tol: must be positive (mm)"))
                        }
                        Some(t) => *t.get_ref(),
                        None => 1e-9,
                    };
                    SolverSpec::Converged { tol }
                }
            };
            (solver, at)
        }
    };

    let (output, output_at) = match &file.output {
        None => (OutputSpec { postures: true, tip_stiffness: false, cable_excursion: true, reference: Reference::None }, Pos::WHOLE),
        Some(o) => {
            let f = o.get_ref();
            (
                OutputSpec {
                    postures: f.postures.unwrap_or(true),
                    tip_stiffness: f.tip_stiffness.unwrap_or(false),
                    cable_excursion: f.cable_excursion.unwrap_or(true),
                    reference: f.reference.unwrap_or(Reference::None),
                },
                section_at(text, "output", &o.span()),
            )
        }
    };

    Ok(Scene {
        name: name.to_string(),
        title: file.title.unwrap_or_else(|| name.to_string()),
        board: file.board.unwrap_or(true),
        finger,
        tensions,
        tensions_at,
        matching,
        solver,
        solver_at,
        output,
        output_at,
    })
}

/// Read and parse a scene file; the name is the file stem. A `.scene` file (the old INI
/// format) is refused with a pointer to the new one.
pub fn read_file(path: &std::path::Path) -> Result<Scene, SceneError> {
    if path.extension().is_some_and(|x| x == "scene") {
        return Err(SceneError::at(
            Pos::WHOLE,
            format!("{}: a .scene file is the old INI scene format; scenes are TOML now, named .toml: see docs/scenes.md", path.display()),
        ));
    }
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::at(Pos::WHOLE, format!("cannot read {}: {e}", path.display())))?;
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
    parse(name, &text)
}

/// Check a voltage list against the ceiling, or convert thicknesses to voltages: the channel
/// voltages of a finger spec.
pub fn volts_of(spec: &FingerSpec) -> Result<Vec<f64>, SceneError> {
    match &spec.drive {
        Drive::Volts(v) => {
            for (k, &x) in v.iter().enumerate() {
                de::check_voltage(&spec.params, k + 1, x).map_err(|e| SceneError::model(spec.drive_at, "volts", e))?;
            }
            Ok(v.clone())
        }
        Drive::Thickness(t) => t
            .iter()
            .enumerate()
            .map(|(k, &x)| de::voltage_for_thickness(&spec.params, k + 1, x).map_err(|e| SceneError::model(spec.drive_at, "thickness", e)))
            .collect(),
    }
}
