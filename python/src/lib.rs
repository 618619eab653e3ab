#![allow(non_snake_case)]
//! `softfinger._core`: the `finger-model` crate (f64) as Python classes. One `Finger` holds a
//! prepared model; its solves return result objects whose fields are NumPy arrays; the model's
//! typed errors become the exception classes of `errors.rs`.
//!
//! What it is not: a second implementation of any equation (every number comes from
//! `finger-model`), nor the board (Python, `softfinger/board.py`; its replies are read by the
//! console protocol crate through `reply.rs`). Units are the model's:
//! mm, N, N·mm, MPa, V, angles in rad (degrees only where a name says `_deg`).
use finger_model::inverse::{self, contact_force};
use finger_model::mat3::{self, Mat3};
use finger_model::material::cards::CARDS;
use finger_model::material::Card;
use finger_model::params::PARAMS;
use finger_model::{BranchEnd, Calibration, DeModulusRule, Error, Finger as Model, Method, Params, Solution as ModelSolution, MAX_JOINTS};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayLike1, PyArrayLike2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rayon::prelude::*;

mod design;
mod errors;
mod reply;
use errors::{model_err, row_err};

type R = f64;

/// Which solver `solve` runs (`finger_model::Method`).
fn method(name: &str, n_inc: Option<u32>, tol: f64, max_iter: u32, p: &Params<R>) -> PyResult<Method<R>> {
    match name {
        "converged" => Ok(Method::Converged { tol, max_iter }),
        "stepping" => Ok(Method::Stepping { n_inc: n_inc.unwrap_or(p.n_inc) }),
        _ => Err(PyValueError::new_err(format!("method must be \"converged\" or \"stepping\", not {name:?}"))),
    }
}

/// One solved posture, what the Python side keeps of `finger_model::Solution` (and K_tip).
#[derive(Clone, Copy)]
struct Row {
    sol: ModelSolution<R>,
    stiffness: Option<Mat3<R>>,
}

/// The forward solve and, when asked, the tip stiffness from the same compliances.
fn solve_row(f: &Model<R>, tension: R, volts: &[R], m: Method<R>, stiffness: bool) -> Result<Row, Error> {
    let c = f.compliances(volts)?;
    let sol = f.solve_with(&c, tension, [0.0; 2], m).map_err(|e| past_fmax(f, tension, volts, e))?;
    let stiffness = if stiffness { Some(mat3::inverse_spd(&f.tip_compliance(&c, &sol)).ok_or(Error::Singular { what: "tip compliance" })?) } else { None };
    Ok(Row { sol, stiffness })
}

/// A solve that ran off the branch's end (links touching, a limit point, a stall past it) quotes the limit
/// itself, `fmax` at its voltages (`Finger.fmax`, the board's `limits`), not the tension where
/// the solver's steps found the end (the board's `solve` does the same).
fn past_fmax(f: &Model<R>, tension: R, volts: &[R], e: Error) -> Error {
    match e {
        // under gravity the coupled solve's continuation can also stall there (NotConverged)
        Error::Contact { .. } | Error::LimitPoint { .. } | Error::NotConverged { .. } => match f.fmax(volts) {
            Ok(b) if tension > b.tension => Error::ForceLimit { tension, fmax: b.tension },
            _ => e,
        },
        _ => e,
    }
}

/// What `solve_many` keeps of one posture (a refused row: NaN, numpy's missing value).
#[derive(Clone, Copy, Default)]
struct Compact {
    tension: R,
    volts: [R; MAX_JOINTS],
    joints: [R; MAX_JOINTS],
    nodes: [[R; 3]; MAX_JOINTS + 1],
    thickness: [R; MAX_JOINTS],
    cable: R,
    stiffness: Mat3<R>,
    iterations: u32,
    residual: R,
}

impl Compact {
    /// A refused row of `errors="mask"`: the asked tension and voltages, NaN for every result.
    fn refused(tension: R, volts: &[R]) -> Self {
        let mut v = [R::NAN; MAX_JOINTS];
        v[..volts.len()].copy_from_slice(volts);
        Compact {
            tension,
            volts: v,
            joints: [R::NAN; MAX_JOINTS],
            nodes: [[R::NAN; 3]; MAX_JOINTS + 1],
            thickness: [R::NAN; MAX_JOINTS],
            cable: R::NAN,
            stiffness: [[R::NAN; 3]; 3],
            iterations: 0,
            residual: R::NAN,
        }
    }
    fn of(r: &Row) -> Self {
        let s = &r.sol;
        Compact {
            tension: s.tension,
            volts: s.volts,
            joints: s.joint_angle,
            nodes: s.nodes.map(|p| [p.x, p.y, p.theta]),
            thickness: s.thickness,
            cable: s.cable_excursion,
            stiffness: r.stiffness.unwrap_or([[0.0; 3]; 3]),
            iterations: s.iterations,
            residual: s.residual,
        }
    }
}

fn arr1<'py>(py: Python<'py>, v: &[R]) -> Bound<'py, PyArray1<R>> {
    PyArray1::from_slice(py, v)
}

fn mat<'py>(py: Python<'py>, k: &Mat3<R>) -> Bound<'py, PyArray2<R>> {
    Array2::from_shape_fn((3, 3), |(i, j)| k[i][j]).into_pyarray(py)
}

/// A solved posture (`Finger.solve`). Arrays are fresh copies; angles in rad unless `_deg`.
#[pyclass(module = "softfinger._core", frozen)]
struct Solution {
    row: Row,
}

#[pymethods]
impl Solution {
    /// Number of joints n.
    #[getter]
    fn n(&self) -> usize {
        self.row.sol.n
    }
    /// Cable tension P, N.
    #[getter]
    fn tension_N(&self) -> R {
        self.row.sol.tension
    }
    /// Channel voltages, V, shape (n,).
    #[getter]
    fn volts_V<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        arr1(py, &self.row.sol.volts[..self.row.sol.n])
    }
    /// Joint angles Δθ_k, rad, shape (n,).
    #[getter]
    fn joints_rad<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        arr1(py, self.row.sol.joint_angles())
    }
    /// Joint angles, degrees, shape (n,).
    #[getter]
    fn joints_deg<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        let d: Vec<R> = self.row.sol.joint_angles().iter().map(|a| a.to_degrees()).collect();
        arr1(py, &d)
    }
    /// Node poses 0..=n, shape (n+1, 3): x mm, y mm, θ rad (base frame; node n is the tip).
    #[getter]
    fn nodes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<R>> {
        let s = &self.row.sol;
        Array2::from_shape_fn((s.n + 1, 3), |(k, j)| [s.nodes[k].x, s.nodes[k].y, s.nodes[k].theta][j]).into_pyarray(py)
    }
    /// Tip pose, shape (3,): x mm, y mm, θ rad.
    #[getter]
    fn tip<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        let t = self.row.sol.tip();
        arr1(py, &[t.x, t.y, t.theta])
    }
    /// Cable the servo must pull in, Σ (L_h − |span k|), mm.
    #[getter]
    fn cable_mm(&self) -> R {
        self.row.sol.cable_excursion
    }
    /// Whole-stack thickness per joint, mm, shape (n,) (0 without stacks).
    #[getter]
    fn thickness_mm<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        arr1(py, &self.row.sol.thickness[..self.row.sol.n])
    }
    /// Linearised tip stiffness K_tip, shape (3, 3), rows/columns (x mm, y mm, θ rad): N/mm,
    /// N/rad, N·mm/rad. None when solved with `stiffness=False`.
    #[getter]
    fn stiffness<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<R>>> {
        self.row.stiffness.as_ref().map(|k| mat(py, k))
    }
    /// Newton iterations (converged) or load steps (stepping).
    #[getter]
    fn iterations(&self) -> u32 {
        self.row.sol.iterations
    }
    /// Final equilibrium residual (guide-hole mismatch), mm.
    #[getter]
    fn residual_mm(&self) -> R {
        self.row.sol.residual
    }
    fn __repr__(&self) -> String {
        let s = &self.row.sol;
        let t = s.tip();
        let list = |v: &[R], scale: R, prec: usize| v.iter().map(|x| format!("{:.*}", prec, x * scale)).collect::<Vec<_>>().join(", ");
        let mut out = format!(
            "Solution(tension_N={}, volts_V=[{}], joints_deg=[{}], tip=({:.3} mm, {:.3} mm, {:.2} deg), cable_mm={:.4}, thickness_mm=[{}]",
            s.tension,
            list(&s.volts[..s.n], 1.0, 1),
            list(s.joint_angles(), 180.0 / core::f64::consts::PI, 3),
            t.x,
            t.y,
            t.theta.to_degrees(),
            s.cable_excursion,
            list(&s.thickness[..s.n], 1.0, 4),
        );
        if let Some(k) = &self.row.stiffness {
            out += &format!(", stiffness_diag=({:.4e} N/mm, {:.4e} N/mm, {:.4e} Nmm/rad)", k[0][0], k[1][1], k[2][2]);
        }
        out + &format!(", iterations={})", s.iterations)
    }
}

/// `solve_many`'s answers: one row per posture, every array's first axis N.
#[pyclass(module = "softfinger._core", frozen)]
struct Solutions {
    #[pyo3(get)]
    tension_N: Py<PyArray1<R>>,
    #[pyo3(get)]
    volts_V: Py<PyArray2<R>>,
    #[pyo3(get)]
    joints_rad: Py<PyArray2<R>>,
    #[pyo3(get)]
    nodes: Py<PyArray3<R>>,
    #[pyo3(get)]
    tip: Py<PyArray2<R>>,
    #[pyo3(get)]
    cable_mm: Py<PyArray1<R>>,
    #[pyo3(get)]
    thickness_mm: Py<PyArray2<R>>,
    #[pyo3(get)]
    stiffness: Option<Py<PyArray3<R>>>,
    #[pyo3(get)]
    iterations: Py<PyArray1<u32>>,
    #[pyo3(get)]
    residual_mm: Py<PyArray1<R>>,
    #[pyo3(get)]
    ok: Py<PyArray1<bool>>,
    #[pyo3(get)]
    errors: Py<PyList>,
}

#[pymethods]
impl Solutions {
    fn __len__(&self, py: Python<'_>) -> usize {
        self.ok.bind(py).len()
    }
    /// Joint angles, degrees, shape (N, n).
    #[getter]
    fn joints_deg<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<R>> {
        let j = self.joints_rad.bind(py).to_owned_array();
        j.mapv(|a| a.to_degrees()).into_pyarray(py)
    }
    fn __repr__(&self, py: Python<'_>) -> String {
        let ok = self.ok.bind(py).to_vec().unwrap_or_default();
        format!("Solutions(N={}, ok={})", ok.len(), ok.iter().filter(|&&b| b).count())
    }
}

/// The branch end (`Finger.fmax`): the tension where the equilibrium branch ends, where, how.
#[pyclass(module = "softfinger._core", frozen, get_all)]
struct BranchLimit {
    /// N.
    tension_N: R,
    /// 1-based joint where it ends first.
    joint: usize,
    /// "contact", "limit-point" or "search-bound".
    kind: &'static str,
}

#[pymethods]
impl BranchLimit {
    fn __repr__(&self) -> String {
        format!("BranchLimit(tension_N={}, joint={}, kind={:?})", self.tension_N, self.joint, self.kind)
    }
    fn __float__(&self) -> R {
        self.tension_N
    }
}

/// The inverse model's answer (`Finger.pose`).
#[pyclass(module = "softfinger._core", frozen)]
struct PoseSolution {
    pose: inverse::PoseSolution<R>,
    forward: ModelSolution<R>,
    /// The tip stiffness of the posture at its tension and voltages.
    stiffness: Mat3<R>,
}

#[pymethods]
impl PoseSolution {
    /// The target joint angles, rad, shape (n,).
    #[getter]
    fn angles_rad<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        arr1(py, &self.pose.angles[..self.pose.n])
    }
    /// The cable tension, N (given, or the midpoint of `interval_N`).
    #[getter]
    fn tension_N(&self) -> R {
        self.pose.tension
    }
    /// Whether the tension was given (else chosen by the midpoint rule).
    #[getter]
    fn tension_given(&self) -> bool {
        self.pose.tension_given
    }
    /// Channel voltages that hold the posture, V, shape (n,).
    #[getter]
    fn volts_V<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        arr1(py, &self.pose.volts[..self.pose.n])
    }
    /// Stack thickness per joint, mm, shape (n,).
    #[getter]
    fn thickness_mm<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        arr1(py, &self.pose.thickness[..self.pose.n])
    }
    /// The feasible interval: the tensions that can hold the posture, [low, high], N.
    #[getter]
    fn interval_N<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        arr1(py, &self.pose.interval)
    }
    /// The posture as a forward solution (nodes, tip, cable and the tip stiffness there).
    #[getter]
    fn solution(&self) -> Solution {
        Solution { row: Row { sol: self.forward, stiffness: Some(self.stiffness) } }
    }
    /// Newton iterations spent in all.
    #[getter]
    fn iterations(&self) -> u32 {
        self.pose.iterations
    }
    fn __repr__(&self) -> String {
        let p = &self.pose;
        let l = |v: &[R], s: R| v.iter().map(|x| format!("{:.3}", x * s)).collect::<Vec<_>>().join(", ");
        format!(
            "PoseSolution(angles_deg=[{}], tension_N={:.4}, volts_V=[{}], interval_N=[{:.4}, {:.4}])",
            l(&p.angles[..p.n], 180.0 / core::f64::consts::PI),
            p.tension,
            l(&p.volts[..p.n], 1.0),
            p.interval[0],
            p.interval[1]
        )
    }
}

/// The contact force of a tip held at a point (`Finger.contact`).
#[pyclass(module = "softfinger._core", frozen)]
struct Contact {
    c: inverse::Contact<R>,
}

#[pymethods]
impl Contact {
    /// The contact point (the free tip at P0), base frame, mm, shape (2,).
    #[getter]
    fn point_mm<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        arr1(py, &self.c.point)
    }
    /// The force the object exerts on the tip (base frame), N, shape (2,); the finger presses
    /// with minus this.
    #[getter]
    fn force_N<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        arr1(py, &self.c.force)
    }
    /// The stop's force on the tip, N, shape (2,): `force_N` by the name of its sign (the
    /// console's `force_on_tip`; its `fx`, `fy` are the opposite).
    #[getter]
    fn force_on_tip_N<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<R>> {
        arr1(py, &self.c.force)
    }
    /// |force|, N.
    #[getter]
    fn magnitude_N(&self) -> R {
        self.c.magnitude()
    }
    /// The loaded equilibrium that holds the tip at the point.
    #[getter]
    fn solution(&self) -> Solution {
        Solution { row: Row { sol: self.c.solution, stiffness: None } }
    }
    /// Newton iterations on the force.
    #[getter]
    fn iterations(&self) -> u32 {
        self.c.iterations
    }
    fn __repr__(&self) -> String {
        format!(
            "Contact(point_mm=({:.3}, {:.3}), force_on_tip_N=({:.4}, {:.4}), magnitude_N={:.4})",
            self.c.point[0],
            self.c.point[1],
            self.c.force[0],
            self.c.force[1],
            self.c.magnitude()
        )
    }
}

/// Channel voltages of one posture: a sequence of n numbers, or one number for every joint.
fn volts_of(obj: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<R>> {
    numbers_of(obj, n, "volts", "V")
}

/// One number for every joint, or a sequence of them: the argument `what` (unit `unit`); any
/// other type is a `TypeError` that names the argument and what it takes.
fn numbers_of(obj: &Bound<'_, PyAny>, n: usize, what: &str, unit: &str) -> PyResult<Vec<R>> {
    if let Ok(v) = obj.extract::<R>() {
        return Ok(vec![v; n]);
    }
    let not_numbers = || {
        let ty = obj.get_type().name().map(|t| t.to_string()).unwrap_or_else(|_| "?".into());
        let shown = obj.repr().map(|r| r.to_string()).unwrap_or_default();
        let shown: String = shown.chars().take(40).collect();
        PyTypeError::new_err(format!("{what}: a number ({unit}) for every joint or a sequence of {n} numbers, not {ty} {shown}"))
    };
    if obj.is_instance_of::<pyo3::types::PyString>() || obj.is_instance_of::<pyo3::types::PyBytes>() {
        return Err(not_numbers());
    }
    let a = obj.extract::<PyArrayLike1<'_, R, AllowTypeChange>>().map_err(|_| not_numbers())?;
    Ok(a.as_array().to_vec())
}

/// The FE calibration the board gives a parameter set (src/app/params.rs `calibration_for`):
/// docs/model.md's finger on the board's film or on the default film has docs/model.md's
/// factors (`Calibration::for_params` judges the structure; the board's film does not clear
/// them), any other finger none.
fn board_calibration(p: &Params<R>) -> Calibration<R> {
    let d = Params::<R>::default();
    let b = Params::<R>::with_card(BOARD_CARD);
    let mut q = *p;
    if p.card == b.card && p.g == b.g && p.nu == b.nu && p.de_rule == b.de_rule {
        (q.card, q.g, q.nu, q.de_rule) = (d.card, d.g, d.nu, d.de_rule);
    }
    Calibration::for_params(&q)
}

/// The parameters in which `p` is not the finger the FE calibration belongs to (the rule of
/// `Calibration::for_params`, the board's `param` too: docs/model.md's finger, every parameter
/// but `KEEPS_CALIBRATION`'s at its default, `layers` the default or 0, on the board's film or
/// the default one): each as `name = value (the calibrated finger's: default)`.
fn calibration_differs(p: &Params<R>) -> Vec<(&'static str, String)> {
    use finger_model::calibration::KEEPS_CALIBRATION;
    let d = Params::<R>::default();
    let b = Params::<R>::with_card(BOARD_CARD);
    let boards_film = p.card == b.card && p.g == b.g && p.nu == b.nu && p.de_rule == b.de_rule;
    let mut out = Vec::new();
    if !boards_film && (p.card != d.card || p.de_rule != d.de_rule) {
        out.push(("card", format!("card = {} (the calibrated finger's: {} or {})", p.card.name, d.card.name, b.card.name)));
    }
    for i in PARAMS {
        let film = matches!(i.name, "g" | "nu" | "e_de");
        if KEEPS_CALIBRATION.contains(&i.name) || (film && boards_film) || (i.name == "layers" && p.layers == 0) {
            continue;
        }
        if let (Some(v), Some(dv)) = (p.get(i.name), d.get(i.name)) {
            if v != dv {
                out.push((i.name, format!("{} = {v} (the calibrated finger's: {dv})", i.name)));
            }
        }
    }
    out
}

/// An `InputError` for a calibration that does not apply to the finger asked for: named after
/// the first parameter that leaves the calibrated finger, every such parameter in the message.
fn calibration_refused(what: &str, p: &Params<R>) -> PyErr {
    let differs = calibration_differs(p);
    let name = differs.first().map_or("calibration", |d| d.0);
    let which = if differs.is_empty() {
        format!("card {}, m = {}, layers = {}", p.card.name, p.m, p.layers)
    } else {
        differs.iter().map(|d| d.1.as_str()).collect::<Vec<_>>().join(", ")
    };
    errors::model_err_msg(
        Error::Param { name, range: "docs/model.md's finger (m = 8, plate, flexible links, its geometry, body modulus and stack count) on VHB 4905 or the default film" },
        format!(
            "calibration {what} does not apply to this finger: {which}; the FE factors belong to docs/model.md's finger on VHB 4905 or the default film (a board's `param` set drops them the same way); pass calibration=None for the uncalibrated model, or 8 factors"
        ),
    )
}

/// `Finger(calibration=...)`: a name or the 8 factors.
#[derive(FromPyObject)]
enum CalArg {
    Name(String),
    Factors(Vec<R>),
}

/// A calibration given as "auto", None, "model_md" or 8 factors (hinge ×4, stack EA g0 g1,
/// stack EI g0 g1), and how the repr names it. "auto": on the board's finger (preset
/// "board") the board's calibration, an error where none applies; on the other presets none
/// (their models are uncalibrated). "model_md" where it does not apply is an error.
fn calibration_of(arg: Option<CalArg>, p: &Params<R>, preset: &str) -> PyResult<(Calibration<R>, &'static str)> {
    let Some(arg) = arg else { return Ok((Calibration::none(), "none")) };
    if let CalArg::Name(s) = &arg {
        let applies = board_calibration(p) == Calibration::model_md();
        return match s.as_str() {
            "none" => Ok((Calibration::none(), "none")),
            "model_md" if applies => Ok((Calibration::model_md(), "model_md")),
            "model_md" => Err(calibration_refused("\"model_md\"", p)),
            "auto" if preset != "board" => Ok((Calibration::none(), "none")),
            "auto" if applies => Ok((Calibration::model_md(), "model_md")),
            "auto" => Err(calibration_refused("\"auto\" (the board's)", p)),
            _ => Err(PyValueError::new_err(format!("calibration must be \"auto\", None, \"model_md\" or 8 factors, not {s:?}"))),
        };
    }
    let CalArg::Factors(v) = arg else { unreachable!("names are handled above") };
    if v.len() != 8 {
        return Err(PyValueError::new_err("calibration: 8 factors (hinge x4, stack EA g0 g1, stack EI g0 g1)"));
    }
    Ok((Calibration { hinge: [v[0], v[1], v[2], v[3]], stack_axial: [v[4], v[5]], stack_bending: [v[6], v[7]] }, "factors"))
}

/// The board's film, compiled into the firmware (src/board.rs `BOARD_CARD`).
const BOARD_CARD: &Card = &finger_model::material::VHB_4905;
/// The board's finger's orientation (src/board.rs `BOARD_GRAVITY`, issue 53): standard gravity,
/// hanging straight down. The one switch: false gives preset "board" without gravity.
const BOARD_GRAVITY: bool = true;
/// The board's finger's `grav` (m/s²) and `grav_dir` (degrees).
const BOARD_GRAV_M_S2: R = if BOARD_GRAVITY { finger_model::params::G_STANDARD } else { 0.0 };
const BOARD_GRAV_DIR_DEG: R = 0.0;
/// The board's HV modules' limit, V (src/board.rs `HV_MAX_V`).
const BOARD_HV_MAX_V: R = 10_000.0;

/// The board's hold ceiling on a finger's film (src/board.rs `board_hold_ceiling_of`): the
/// card's hold ceiling at the finger's z0 and margin, at most the HV modules' limit, V.
fn hold_ceiling_of(p: &Params<R>) -> PyResult<R> {
    let law = finger_model::material::StackLaw::<R>::new(p.card, p.z0, p.margin).map_err(model_err)?;
    let v = finger_model::material::hold_ceiling(&law, p.margin);
    Ok(if v > 0.0 { v.min(BOARD_HV_MAX_V) } else { 0.0 })
}

/// The parameter set: a preset, then the keyword overrides by their console names (docs/model.md
/// "Geometry"). An override that is only consistent with a later one is retried after the others.
fn params_of(preset: &str, card: Option<&str>, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Params<R>> {
    let mut p = match preset {
        "board" => Params::with_card(BOARD_CARD).with_gravity(BOARD_GRAV_M_S2, BOARD_GRAV_DIR_DEG),
        "default" => Params::default(),
        "paper" => Params::paper(),
        "paper_model" => Params::paper_model(),
        _ => return Err(PyValueError::new_err(format!("preset must be \"board\", \"default\", \"paper\" or \"paper_model\", not {preset:?}"))),
    };
    if let Some(name) = card {
        // the film of the card on the preset's finger, as `Params::with_card` does on the default finger
        let c = card_of(name)?;
        let with = Params::<R>::with_card(c);
        p = Params { card: with.card, g: with.g, eps_r: with.eps_r, de_rule: with.de_rule, ..p };
    }
    let mut pending: Vec<(String, R)> = Vec::new();
    if let Some(kw) = kwargs {
        for (k, v) in kw.iter() {
            let name: String = k.extract()?;
            if !PARAMS.iter().any(|i| i.name == name) {
                let names: Vec<&str> = PARAMS.iter().map(|i| i.name).collect();
                return Err(PyTypeError::new_err(format!("Finger() got an unknown parameter {name:?}; parameters: {}", names.join(", "))));
            }
            pending.push((name, v.extract::<R>()?));
        }
    }
    set_all(&mut p, pending)?;
    Ok(p)
}

/// Set parameters by name, all at once (`Params::set_many`: each in its range, then the set).
fn set_all(p: &mut Params<R>, pending: Vec<(String, R)>) -> PyResult<()> {
    let sets: Vec<(&str, f64)> = pending.iter().map(|(k, v)| (k.as_str(), *v)).collect();
    p.set_many(&sets).map_err(model_err)
}

/// A pickled `Finger` rebuilt (`Finger.__reduce__`): the card, the DE modulus rule, every
/// settable parameter by name, the 8 calibration factors, the preset and how the calibration
/// was given (the repr's; the board's hold ceiling follows the preset).
#[pyfunction]
#[pyo3(signature = (card, de_rule, params, calibration, preset = "default", cal_name = "factors"))]
fn _finger_from_state(card: &str, de_rule: &str, params: Vec<(String, R)>, calibration: Vec<R>, preset: &str, cal_name: &str) -> PyResult<Finger> {
    let de_rule = match de_rule {
        "isotropic" => DeModulusRule::Isotropic,
        "paper_eq3" => DeModulusRule::PaperEq3,
        _ => return Err(PyValueError::new_err(format!("de_rule {de_rule:?}"))),
    };
    let mut p = Params { card: card_of(card)?, de_rule, ..Params::default() };
    set_all(&mut p, params)?;
    if calibration.len() != 8 {
        return Err(PyValueError::new_err("calibration: 8 factors"));
    }
    let c = &calibration;
    let cal = Calibration { hinge: [c[0], c[1], c[2], c[3]], stack_axial: [c[4], c[5]], stack_bending: [c[6], c[7]] };
    let preset = match preset {
        "board" => "board",
        "paper" => "paper",
        "paper_model" => "paper_model",
        _ => "default",
    };
    let cal_name = match cal_name {
        "model_md" => "model_md",
        "none" => "none",
        _ => "factors",
    };
    let hold = if preset == "board" && p.layers > 0 { Some(hold_ceiling_of(&p)?) } else { None };
    Ok(Finger { f: Model::with_calibration(p, cal).map_err(model_err)?, preset, cal_name, hold })
}

/// A material card by its name or a short key (`cards::CARDS`; docs/materials.md).
fn card_of(name: &str) -> PyResult<&'static Card> {
    let key = |s: &str| s.chars().filter(|c| c.is_ascii_alphanumeric()).collect::<String>().to_ascii_lowercase();
    let want = key(name);
    CARDS.iter().copied().find(|c| key(c.name) == want || key(c.name).starts_with(&want) && want.len() >= 3).ok_or_else(|| {
        let names: Vec<&str> = CARDS.iter().map(|c| c.name).collect();
        PyValueError::new_err(format!("unknown card {name:?}; cards: {}", names.join(", ")))
    })
}

/// Every material card's name (`Finger(card=...)`).
#[pyfunction]
fn cards() -> Vec<&'static str> {
    CARDS.iter().map(|c| c.name).collect()
}

/// The finger's model: validated parameters and their hinge compliances, prepared once.
#[pyclass(module = "softfinger._core", frozen)]
struct Finger {
    f: Model<R>,
    preset: &'static str,
    /// How the calibration was given: "model_md", "none" or "factors".
    cal_name: &'static str,
    /// The board's hold ceiling (preset "board"), V: every voltage stays below it too.
    hold: Option<R>,
}

impl Finger {
    /// The ceiling in force, V: the model's (margin × V_pi, supply) and, on the board's finger,
    /// the board's hold ceiling.
    fn ceiling_V(&self) -> R {
        let m = self.f.voltage_ceiling();
        self.hold.map_or(m, |h| m.min(h))
    }

    /// Channel voltages checked against the board's hold ceiling (the model checks its own),
    /// refused as the model refuses a voltage at or past its ceiling.
    fn check_hold(&self, volts: &[R]) -> Result<(), Error> {
        let Some(h) = self.hold else { return Ok(()) };
        let c = self.ceiling_V().min(h);
        for (k, &v) in volts.iter().enumerate() {
            if v > 0.0 && v >= c {
                return Err(Error::VoltageCeiling { joint: k + 1, volts: v, ceiling: c });
            }
        }
        Ok(())
    }
}

#[pymethods]
impl Finger {
    #[new]
    #[pyo3(signature = (preset = "board", calibration = Some(CalArg::Name("auto".into())), card = None, **params))]
    fn new(preset: &str, calibration: Option<CalArg>, card: Option<&str>, params: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let p = params_of(preset, card, params)?;
        let (cal, cal_name) = calibration_of(calibration, &p, preset)?;
        let preset = match preset {
            "board" => "board",
            "default" => "default",
            "paper" => "paper",
            _ => "paper_model",
        };
        let hold = if preset == "board" && p.layers > 0 { Some(hold_ceiling_of(&p)?) } else { None };
        Ok(Finger { f: Model::with_calibration(p, cal).map_err(model_err)?, preset, cal_name, hold })
    }

    /// The preset the finger started from: "board" (the board's finger: docs/model.md's on
    /// VHB 4905, its FE calibration and hold ceiling), "default", "paper" or "paper_model".
    #[getter]
    fn preset(&self) -> &'static str {
        self.preset
    }

    /// Every parameter by its console name (`e_de` derived), units as in docs/model.md.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for i in PARAMS {
            d.set_item(i.name, self.f.params().get(i.name).unwrap_or(0.0))?;
        }
        Ok(d)
    }

    /// The calibration factors: hinge ×4, stack EA (g0, g1 per mm), stack EI (g0, g1 per mm).
    #[getter]
    fn calibration(&self) -> Vec<R> {
        let c = self.f.calibration();
        let mut v = c.hinge.to_vec();
        v.extend(c.stack_axial);
        v.extend(c.stack_bending);
        v
    }

    /// Number of joints n.
    #[getter]
    fn n(&self) -> usize {
        self.f.params().n
    }

    /// The film's material card (its name).
    #[getter]
    fn card(&self) -> &'static str {
        self.f.params().card.name
    }

    /// The ceiling every channel stays below, V: min(margin × V_pi, v_supply) and, on the
    /// board's finger, the board's hold ceiling (docs/materials.md; 5,400 V on VHB 4905).
    fn ceiling(&self) -> R {
        self.ceiling_V()
    }

    /// The pull-in voltage V_pi of one layer (the 33 % limit), V (0 without stacks).
    fn pull_in_voltage(&self) -> R {
        self.f.pull_in_voltage()
    }

    /// Whole-stack thickness at `volts` (V), mm.
    fn stack_thickness(&self, volts: R) -> PyResult<R> {
        self.check_hold(&[volts]).map_err(model_err)?;
        self.f.stack_thickness(volts).map_err(model_err)
    }

    /// The channel voltages (V, shape (n,)) that thin the stacks to `thickness_mm` (mm per
    /// joint, or one number for all).
    fn volts_for_thickness<'py>(&self, py: Python<'py>, thickness_mm: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray1<R>>> {
        let n = self.f.params().n;
        let t = numbers_of(thickness_mm, n, "thickness_mm", "mm")?;
        if t.len() != n {
            return Err(PyValueError::new_err(format!("thickness_mm: {n} values (one per joint) or one number")));
        }
        let mut v = Vec::with_capacity(n);
        for (k, &tk) in t.iter().enumerate() {
            v.push(finger_model::de::voltage_for_thickness(self.f.params(), k + 1, tk).map_err(model_err)?);
        }
        self.check_hold(&v).map_err(model_err)?;
        Ok(arr1(py, &v))
    }

    /// Solve the posture under cable tension `P` (N) with channel voltages `volts` (V, one per
    /// joint or one number for all).
    #[pyo3(signature = (P, volts, *, method = "converged", n_inc = None, tol = 1e-9, max_iter = 200, stiffness = true))]
    #[allow(non_snake_case, clippy::too_many_arguments)]
    fn solve(
        &self,
        py: Python<'_>,
        P: R,
        volts: &Bound<'_, PyAny>,
        method: &str,
        n_inc: Option<u32>,
        tol: R,
        max_iter: u32,
        stiffness: bool,
    ) -> PyResult<Solution> {
        let v = volts_of(volts, self.f.params().n)?;
        let m = self::method(method, n_inc, tol, max_iter, self.f.params())?;
        let f = &self.f;
        self.check_hold(&v).map_err(model_err)?;
        let row = py.detach(|| solve_row(f, P, &v, m, stiffness)).map_err(model_err)?;
        Ok(Solution { row })
    }

    /// `solve` over N postures in parallel, without the GIL: `P` shape (N,) or a number,
    /// `volts` shape (N, n), (n,) or a number; `grav_dir` (degrees, the finger's orientation,
    /// docs/python.md) shape (N,) or a number, None: the finger's own.
    #[pyo3(signature = (P, volts, *, grav_dir = None, method = "converged", n_inc = None, tol = 1e-9, max_iter = 200, stiffness = true, errors = "raise"))]
    #[allow(non_snake_case, clippy::too_many_arguments)]
    fn solve_many(
        &self,
        py: Python<'_>,
        P: &Bound<'_, PyAny>,
        volts: &Bound<'_, PyAny>,
        grav_dir: Option<&Bound<'_, PyAny>>,
        method: &str,
        n_inc: Option<u32>,
        tol: R,
        max_iter: u32,
        stiffness: bool,
        errors: &str,
    ) -> PyResult<Solutions> {
        let n = self.f.params().n;
        let raise = match errors {
            "raise" => true,
            "mask" => false,
            _ => return Err(PyValueError::new_err(format!("errors must be \"raise\" or \"mask\", not {errors:?}"))),
        };
        let m = self::method(method, n_inc, tol, max_iter, self.f.params())?;
        // inputs copied out of NumPy before the GIL is released
        let (tensions, p_rows): (Vec<R>, Option<usize>) = match P.extract::<R>() {
            Ok(x) => (vec![x], None),
            Err(_) => {
                let a = P.extract::<PyArrayLike1<'_, R, AllowTypeChange>>()?;
                let v = a.as_array().to_vec();
                let len = v.len();
                (v, Some(len))
            }
        };
        let (volts, v_rows): (Vec<R>, Option<usize>) = if let Ok(x) = volts.extract::<R>() {
            (vec![x; n], None)
        } else if let Ok(a) = volts.extract::<PyArrayLike2<'_, R, AllowTypeChange>>() {
            let a = a.as_array();
            if a.ncols() != n {
                return Err(PyValueError::new_err(format!("volts: shape (N, {n}) expected, got {:?}", a.shape())));
            }
            (a.iter().copied().collect(), Some(a.nrows()))
        } else {
            let v = volts_of(volts, n)?;
            if v.len() != n {
                return Err(PyValueError::new_err(format!("volts: shape (N, {n}), ({n},) or a number expected, got ({},)", v.len())));
            }
            (v, None)
        };
        // the orientations: one finger per distinct grav_dir, each checked as `Finger(grav_dir=)`
        let (dirs, d_rows): (Vec<R>, Option<usize>) = match grav_dir {
            None => (vec![], None),
            Some(g) => match g.extract::<R>() {
                Ok(x) => (vec![x], None),
                Err(_) => {
                    let a = g.extract::<PyArrayLike1<'_, R, AllowTypeChange>>()?;
                    let v = a.as_array().to_vec();
                    let len = v.len();
                    (v, Some(len))
                }
            },
        };
        let mut fingers: Vec<(R, Model<R>)> = Vec::new();
        for &d in &dirs {
            if !fingers.iter().any(|x| x.0.to_bits() == d.to_bits()) {
                let mut p = *self.f.params();
                p.set("grav_dir", d).map_err(model_err)?;
                fingers.push((d, Model::with_calibration(p, *self.f.calibration()).map_err(model_err)?));
            }
        }
        let rows = match (p_rows, v_rows) {
            (Some(a), Some(b)) if a != b => return Err(PyValueError::new_err(format!("P has {a} rows, volts {b}"))),
            (Some(a), _) | (None, Some(a)) => a,
            (None, None) => 1,
        };
        let rows = match (d_rows, rows) {
            (Some(d), r) if d != r && (p_rows.is_some() || v_rows.is_some()) => {
                return Err(PyValueError::new_err(format!("grav_dir has {d} rows, P and volts {r}")))
            }
            (Some(d), _) => d,
            (None, r) => r,
        };
        let finger_of = |i: usize| -> &Model<R> {
            match dirs.get(if d_rows.is_some() { i } else { 0 }) {
                Some(d) => &fingers.iter().find(|x| x.0.to_bits() == d.to_bits()).expect("every grav_dir prepared").1,
                None => &self.f,
            }
        };
        // one compact row per posture (not the whole model Solution, which carries every
        // sub-element's state), filled in parallel
        let out: Vec<Result<Compact, Error>> = py.detach(|| {
            (0..rows)
                .into_par_iter()
                .map(|i| {
                    let t = tensions[if p_rows.is_some() { i } else { 0 }];
                    let v = if v_rows.is_some() { &volts[i * n..(i + 1) * n] } else { &volts[..n] };
                    self.check_hold(v)?;
                    solve_row(finger_of(i), t, v, m, stiffness).map(|r| Compact::of(&r))
                })
                .collect()
        });
        let err_list = PyList::empty(py);
        for (i, r) in out.iter().enumerate() {
            if let Err(e) = r {
                let e = row_err(py, *e, i);
                if raise {
                    return Err(e);
                }
                err_list.append((i, e.value(py)))?;
            }
        }
        let rows_c: Vec<Compact> = out
            .iter()
            .enumerate()
            .map(|(i, r)| match r {
                Ok(c) => *c,
                Err(_) => {
                    Compact::refused(tensions[if p_rows.is_some() { i } else { 0 }], if v_rows.is_some() { &volts[i * n..(i + 1) * n] } else { &volts[..n] })
                }
            })
            .collect();
        let c = |i: usize| &rows_c[i];
        let per_joint = |g: &dyn Fn(&Compact, usize) -> R| Array2::from_shape_fn((rows, n), |(i, k)| g(c(i), k));
        let stiff = stiffness.then(|| Array3::from_shape_fn((rows, 3, 3), |(i, a, b)| c(i).stiffness[a][b]).into_pyarray(py).unbind());
        Ok(Solutions {
            tension_N: Array1::from_shape_fn(rows, |i| c(i).tension).into_pyarray(py).unbind(),
            volts_V: per_joint(&|s, k| s.volts[k]).into_pyarray(py).unbind(),
            joints_rad: per_joint(&|s, k| s.joints[k]).into_pyarray(py).unbind(),
            nodes: Array3::from_shape_fn((rows, n + 1, 3), |(i, k, j)| c(i).nodes[k][j]).into_pyarray(py).unbind(),
            tip: Array2::from_shape_fn((rows, 3), |(i, j)| c(i).nodes[n][j]).into_pyarray(py).unbind(),
            cable_mm: Array1::from_shape_fn(rows, |i| c(i).cable).into_pyarray(py).unbind(),
            thickness_mm: per_joint(&|s, k| s.thickness[k]).into_pyarray(py).unbind(),
            stiffness: stiff,
            iterations: Array1::from_shape_fn(rows, |i| c(i).iterations).into_pyarray(py).unbind(),
            residual_mm: Array1::from_shape_fn(rows, |i| c(i).residual).into_pyarray(py).unbind(),
            ok: Array1::from_shape_fn(rows, |i| out[i].is_ok()).into_pyarray(py).unbind(),
            errors: err_list.unbind(),
        })
    }

    /// The inverse: joint angles (rad, or degrees with `degrees=True`) and optionally a
    /// tension `P` (N) to the tension and voltages that hold them, with the feasible interval.
    #[pyo3(signature = (angles, P = None, *, degrees = false))]
    #[allow(non_snake_case)]
    fn pose(&self, py: Python<'_>, angles: &Bound<'_, PyAny>, P: Option<R>, degrees: bool) -> PyResult<PoseSolution> {
        let mut a = numbers_of(angles, self.f.params().n, "angles", if degrees { "degrees" } else { "rad" })?;
        // the firmware's words (src/app/pose.rs): the cable runs on the flexor side
        if let Some(k) = a.iter().position(|&x| x < 0.0) {
            let deg = if degrees { a[k] } else { a[k].to_degrees() };
            return Err(errors::extension_err(k + 1, deg));
        }
        if degrees {
            a.iter_mut().for_each(|x| *x = x.to_radians());
        }
        let f = &self.f;
        // the board's inverse: its top voltage under the ceiling in force
        let opts = inverse::Options { hv_fs: self.hold, ..Default::default() };
        let out = py.detach(|| -> Result<_, Error> {
            let pose = inverse::solve_pose_with(f, &a, P, &opts)?;
            let forward = pose.to_solution(f)?;
            let c = f.compliances(&pose.volts[..pose.n])?;
            let stiffness = mat3::inverse_spd(&f.tip_compliance(&c, &forward)).ok_or(Error::Singular { what: "tip compliance" })?;
            Ok((pose, forward, stiffness))
        });
        match out {
            Ok((pose, forward, stiffness)) => Ok(PoseSolution { pose, forward, stiffness }),
            // a tension given outside the tensions that hold the posture: say so, with them
            Err(e @ Error::Unreachable { .. }) if P.is_some() => {
                let p = P.unwrap_or(0.0);
                match py.detach(|| inverse::solve_pose_with(f, &a, None, &opts)) {
                    Ok(free) if !(free.interval[0] <= p && p <= free.interval[1]) => Err(errors::model_err_msg(
                        e,
                        format!(
                            "P = {p} N is outside the tensions that hold this posture, {:.4} to {:.4} N (pose(angles) without P takes the midpoint; the model: {e})",
                            free.interval[0], free.interval[1]
                        ),
                    )),
                    _ => Err(model_err(e)),
                }
            }
            Err(e) => Err(model_err(e)),
        }
    }

    /// The contact force: the tip stops at the free tip of (`P0`, `volts0`, default `volts`);
    /// at tension `P` (N) and `volts` (V) the load that holds it there.
    #[pyo3(signature = (P0, P, volts, volts0 = None))]
    #[allow(non_snake_case)]
    fn contact(&self, py: Python<'_>, P0: R, P: R, volts: &Bound<'_, PyAny>, volts0: Option<&Bound<'_, PyAny>>) -> PyResult<Contact> {
        let n = self.f.params().n;
        let v = volts_of(volts, n)?;
        let v0 = match volts0 {
            Some(o) => numbers_of(o, n, "volts0", "V")?,
            None => v.clone(),
        };
        let f = &self.f;
        self.check_hold(&v).and_then(|_| self.check_hold(&v0)).map_err(model_err)?;
        let c = py.detach(|| contact_force(f, P0, &v0, P, &v)).map_err(model_err)?;
        Ok(Contact { c })
    }

    /// The tension where the equilibrium branch ends at these voltages (V), with the joint and
    /// the kind of end.
    fn fmax(&self, py: Python<'_>, volts: &Bound<'_, PyAny>) -> PyResult<BranchLimit> {
        let v = volts_of(volts, self.f.params().n)?;
        let f = &self.f;
        self.check_hold(&v).map_err(model_err)?;
        let b = py.detach(|| f.fmax(&v)).map_err(model_err)?;
        let kind = match b.kind {
            BranchEnd::Contact => "contact",
            BranchEnd::LimitPoint => "limit-point",
            BranchEnd::SearchBound => "search-bound",
        };
        Ok(BranchLimit { tension_N: b.tension, joint: b.joint, kind })
    }

    /// Pickling (and so Dask and multiprocessing): the state `_finger_from_state` rebuilds the
    /// same model from, every parameter's f64 value exactly.
    #[allow(clippy::type_complexity)]
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (&'static str, &'static str, Vec<(&'static str, R)>, Vec<R>, &'static str, &'static str))> {
        let p = self.f.params();
        let rule = match p.de_rule {
            DeModulusRule::Isotropic => "isotropic",
            DeModulusRule::PaperEq3 => "paper_eq3",
        };
        let params = PARAMS.iter().filter(|i| !i.read_only).filter_map(|i| p.get(i.name).map(|v| (i.name, v))).collect();
        let make = py.import("softfinger._core")?.getattr("_finger_from_state")?;
        Ok((make, (p.card.name, rule, params, self.calibration(), self.preset, self.cal_name)))
    }

    fn __repr__(&self) -> String {
        let p = self.f.params();
        let why = match self.hold {
            _ if p.layers == 0 => "no stacks",
            Some(h) if h <= self.f.voltage_ceiling() => "the board's hold ceiling",
            _ if self.f.voltage_ceiling() >= p.v_supply => "the supply",
            _ => "margin x pull-in",
        };
        format!(
            "Finger(preset={:?}, card={:?}, calibration={:?}, ceiling={:.1} V ({why}), n={}, m={}, layers={}, e_de={:.4} MPa, grav={} m/s2 at {} deg)",
            self.preset,
            p.card.name,
            self.cal_name,
            self.ceiling_V(),
            p.n,
            p.m,
            p.layers,
            p.e_de(),
            p.grav,
            p.grav_dir
        )
    }
}

/// The parameter names with their valid ranges, as the console states them.
#[pyfunction]
fn parameter_ranges() -> Vec<(&'static str, &'static str)> {
    PARAMS.iter().map(|i| (i.name, i.range)).collect()
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Finger>()?;
    m.add_class::<Solution>()?;
    m.add_class::<Solutions>()?;
    m.add_class::<PoseSolution>()?;
    m.add_class::<Contact>()?;
    m.add_class::<BranchLimit>()?;
    m.add_function(wrap_pyfunction!(parameter_ranges, m)?)?;
    // the board's finger's orientation (preset "board"; softfinger.design's default)
    m.add("BOARD_GRAV_M_S2", BOARD_GRAV_M_S2)?;
    m.add("BOARD_GRAV_DIR_DEG", BOARD_GRAV_DIR_DEG)?;
    m.add_function(wrap_pyfunction!(cards, m)?)?;
    m.add_function(wrap_pyfunction!(_finger_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(design::evaluate_designs, m)?)?;
    m.add_function(wrap_pyfunction!(reply::_reply_final, m)?)?;
    m.add_function(wrap_pyfunction!(reply::_reply_fields, m)?)?;
    m.add_function(wrap_pyfunction!(reply::_reply_measured, m)?)?;
    errors::register(m)?;
    Ok(())
}
