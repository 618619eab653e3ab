//! `evaluate_designs`: the design study's candidate evaluation (`softfinger.design`) in one
//! batched, parallel call. Per candidate (a parameter set on one card): the finger, the
//! reference posture by the inverse with its tension interval, the tip stiffness at both ends
//! (`inverse::stiffness_range`: the top voltage the ceiling allows, and 0 V), fmax at both
//! ends' voltages and the grip force at fmax (the tip stopped at the posture's 0 V end, the
//! cable pulled to fmax). A refusal is a code per row, not an exception, so that a million
//! candidates cost no Python objects.
//!
//! What it is not: the objectives or the constraints (Python, `softfinger/design.py`), nor any
//! equation (every number is `finger-model`'s).
use finger_model::inverse::{contact_force, solve_pose, stiffness_range};
use finger_model::{Error, Finger as Model, Params};
use numpy::ndarray::Array1;
use numpy::{AllowTypeChange, IntoPyArray, PyArrayLike1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

type R = f64;

/// The model's refusals by kind, as `evaluate_designs` codes them (0: solved).
pub const ERROR_KINDS: [&str; 14] = [
    "",
    "Param",
    "NonFinite",
    "Input",
    "VoltageCeiling",
    "ThicknessLimit",
    "PullIn",
    "Contact",
    "LimitPoint",
    "ForceLimit",
    "NotConverged",
    "Singular",
    "Unreachable",
    "PullingStop",
];

/// Which step refused (0: none). `reference`: under gravity, the 0 V posture of the reference's
/// tip angle (`reference_under_weight`).
pub const STAGES: [&str; 7] = ["", "params", "pose", "range", "fmax", "grip", "reference"];

/// The reference posture under the finger's weight: the 0 V posture whose tip angle is the
/// reference's (the sum of `angles`), at the tension that gives it (found by bracketing and
/// regula falsi on the forward solve). A weight alone can bend the joints unequally, so every
/// joint at the same angle is no posture a finger under its weight reaches with one cable and
/// stacks of a few % of authority; its tip angle is. Refused: the weight alone bends the tip past
/// it (`Unreachable`, joint 0, needed the tip angle, min what the weight gives), or no tension
/// up to the branch's end reaches it (the forward solve's refusal).
fn reference_under_weight(f: &Model<R>, angles: &[R]) -> Result<([R; finger_model::params::MAX_JOINTS], R), Error> {
    let n = f.params().n;
    let target: R = angles[..n].iter().sum();
    let zeros = [0.0; finger_model::params::MAX_JOINTS];
    let tip = |t: R| -> Result<(R, [R; finger_model::params::MAX_JOINTS]), Error> {
        let s = f.solve(t, &zeros[..n], finger_model::Method::converged())?;
        Ok((s.joint_angle[..n].iter().sum::<R>() - target, s.joint_angle))
    };
    let (mut lo, mut r_lo) = (0.0, tip(0.0)?.0);
    if r_lo >= 0.0 {
        return Err(Error::Unreachable { joint: 0, needed: target, min: r_lo + target, max: f64::INFINITY });
    }
    let (mut hi, mut r_hi) = (0.25, tip(0.25)?.0);
    while r_hi < 0.0 {
        (lo, r_lo) = (hi, r_hi);
        hi *= 2.0;
        if hi > 1024.0 {
            return Err(Error::Unreachable { joint: 0, needed: target, min: r_lo + target, max: r_lo + target });
        }
        r_hi = tip(hi)?.0;
    }
    // Illinois regula falsi on [lo, hi]: r(lo) < 0 <= r(hi)
    let (mut side, mut best) = (0i8, (hi, r_hi));
    for _ in 0..60 {
        let t = (lo * r_hi - hi * r_lo) / (r_hi - r_lo);
        let (r, q) = tip(t)?;
        if r.abs() < 1e-12 || (hi - lo) < 1e-12 * hi {
            return Ok((q, t));
        }
        best = (t, r);
        if r < 0.0 {
            (lo, r_lo) = (t, r);
            if side == -1 {
                r_hi /= 2.0;
            }
            side = -1;
        } else {
            (hi, r_hi) = (t, r);
            if side == 1 {
                r_lo /= 2.0;
            }
            side = 1;
        }
    }
    Err(Error::NotConverged { iterations: 60, residual: best.1.abs() })
}

fn kind_code(e: &Error) -> u8 {
    match e {
        Error::Param { .. } => 1,
        Error::NonFinite { .. } => 2,
        Error::Input { .. } => 3,
        Error::VoltageCeiling { .. } => 4,
        Error::ThicknessLimit { .. } => 5,
        Error::PullIn { .. } => 6,
        Error::Contact { .. } => 7,
        Error::LimitPoint { .. } => 8,
        Error::ForceLimit { .. } => 9,
        Error::NotConverged { .. } => 10,
        Error::Singular { .. } => 11,
        Error::Unreachable { .. } => 12,
        Error::PullingStop { .. } => 13,
        #[allow(unreachable_patterns)]
        _ => 11,
    }
}

/// One candidate's answers (zeros where it was refused).
#[derive(Clone, Copy, Default)]
struct Eval {
    ceiling: R,
    tension: [R; 2],
    volts_top: R,
    s_min: R,
    field_top: R,
    kyy: [R; 2],
    ktt: [R; 2],
    fmax: R,
    grip: R,
    kind: u8,
    stage: u8,
}

/// The inputs of one candidate: console names t_min, a, e_b, w, layers, z0, v_supply, margin.
#[derive(Clone, Copy)]
struct Candidate([R; 8]);

const NAMES: [&str; 8] = ["t_min", "a", "e_b", "w", "layers", "z0", "v_supply", "margin"];

fn evaluate(base: &Params<R>, c: &Candidate, angles: &[R], grip: bool, fmax_floor: Option<R>) -> Eval {
    let mut out = Eval::default();
    let fail = |mut out: Eval, stage: u8, e: Error| {
        out.kind = kind_code(&e);
        out.stage = stage;
        out
    };
    let mut p = *base;
    for (name, &v) in NAMES.iter().zip(c.0.iter()) {
        // set one by one, then validate the whole set: an order-dependent check (2a < l) holds
        // for the set, not for each step
        let r = match *name {
            "t_min" => &mut p.t_min,
            "a" => &mut p.a,
            "e_b" => &mut p.e_b,
            "w" => &mut p.w,
            "z0" => &mut p.z0,
            "v_supply" => &mut p.v_supply,
            "margin" => &mut p.margin,
            _ => {
                if !((0.0..=64.0).contains(&v) && v.fract() == 0.0) {
                    return fail(out, 1, Error::Param { name: "layers", range: "integer 0..64" });
                }
                p.layers = v as u32;
                continue;
            }
        };
        *r = v;
    }
    if let Err(e) = p.validate() {
        return fail(out, 1, e);
    }
    let f = match Model::new(p) {
        Ok(f) => f,
        Err(e) => return fail(out, 1, e),
    };
    out.ceiling = f.voltage_ceiling();
    let under_weight;
    let angles = if f.has_weight() {
        match reference_under_weight(&f, angles) {
            Ok((q, _)) => {
                under_weight = q;
                &under_weight[..p.n]
            }
            Err(e) => return fail(out, 6, e),
        }
    } else {
        angles
    };
    let pose = match solve_pose(&f, angles, None) {
        Ok(s) => s,
        Err(e) => return fail(out, 2, e),
    };
    let r = match stiffness_range(&f, &pose) {
        Ok(r) => r,
        Err(e) => return fail(out, 3, e),
    };
    let n = p.n;
    let (lo, hi) = (&r.ends[0], &r.ends[1]);
    out.tension = [lo.tension, hi.tension];
    out.kyy = [r.stiffness[0][1][1], r.stiffness[1][1][1]];
    out.ktt = [r.stiffness[0][2][2], r.stiffness[1][2][2]];
    let t0 = p.layers as R * p.z0;
    let mut s_min: R = 1.0;
    let mut field: R = 0.0;
    for k in 0..n {
        for end in [lo, hi] {
            let s = if t0 > 0.0 { end.thickness[k] / t0 } else { 1.0 };
            s_min = s_min.min(s);
            out.volts_top = out.volts_top.max(end.volts[k]);
            // V/um across one layer at its present thickness s z0 (mm)
            field = field.max(end.volts[k] / (s * p.z0 * 1e3));
        }
    }
    out.s_min = s_min;
    out.field_top = field;
    // under gravity fmax is a bisection of coupled solves (hundreds of ms): without the grip, a
    // finger that holds the floor at both ends is reported at the floor (the constraint's 0:
    // fmax >= floor); only one that does not gets its fmax (how far it falls short)
    let holds_floor = |floor: R| [lo, hi].iter().all(|end| f.solve(floor, &end.volts[..n], finger_model::Method::converged()).is_ok());
    let fmax = match fmax_floor {
        Some(floor) if !grip && f.has_weight() && holds_floor(floor) => Ok(floor),
        _ => [lo, hi].iter().try_fold(R::INFINITY, |m, end| f.fmax(&end.volts[..n]).map(|b| m.min(b.tension))),
    };
    out.fmax = match fmax {
        Ok(t) => t,
        Err(e) => return fail(out, 4, e),
    };
    if grip {
        // the tip stopped where the posture's 0 V end puts it; the cable pulled to fmax there
        match contact_force(&f, hi.tension, &hi.volts[..n], out.fmax, &hi.volts[..n]) {
            Ok(c) => out.grip = c.magnitude(),
            Err(e) => return fail(out, 5, e),
        }
    }
    out
}

fn column(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<R>> {
    if let Ok(x) = obj.extract::<R>() {
        return Ok(vec![x]);
    }
    let a = obj.extract::<PyArrayLike1<'_, R, AllowTypeChange>>().map_err(|_| PyValueError::new_err(format!("{name}: a number or a 1-D array")))?;
    Ok(a.as_array().to_vec())
}

/// Evaluate N designs on one material card in parallel (GIL released). Every design variable
/// is a number or an array of N (console names and units: mm, MPa, V); `angle_deg` the
/// reference posture (every joint at this angle, degrees; under gravity the 0 V posture of
/// their tip angle, `reference_under_weight`). `fmax_floor` (N): under gravity and without the
/// grip, a finger that holds it at both ends reports `fmax_N` = the floor (at least that). Returns a dict of arrays (N,):
/// `kind`/`stage` (0: solved; else the index into `error_kinds`/`stages`), `ceiling_V`,
/// `tension_N` (N, 2: the interval's ends, low = top voltage, high = 0 V), `kyy` and `ktt`
/// (N, 2) at those ends (N/mm, N·mm/rad), `volts_top_V`, `s_min` (the thinnest stack's thickness
/// stretch), `margin` defaults to the card's finger's (0.9). `field_V_per_um` (the highest field across a layer), `fmax_N` (the lower of the
/// two ends'), `grip_N` (0 with `grip=False`), and the card's `breakdown_V_per_um`. `grav`
/// (m/s²) and `grav_dir` (degrees) the orientation every candidate is judged in (default: no
/// gravity), refused out of range as `Finger(grav=...)` is.
#[pyfunction]
#[pyo3(signature = (card, t_min, a, e_b, w, layers, z0, v_supply, *, margin = None, angle_deg = 10.0, grip = true, grav = 0.0, grav_dir = 0.0, fmax_floor = None))]
#[allow(clippy::too_many_arguments)]
pub fn evaluate_designs<'py>(
    py: Python<'py>,
    card: &str,
    t_min: &Bound<'py, PyAny>,
    a: &Bound<'py, PyAny>,
    e_b: &Bound<'py, PyAny>,
    w: &Bound<'py, PyAny>,
    layers: &Bound<'py, PyAny>,
    z0: &Bound<'py, PyAny>,
    v_supply: &Bound<'py, PyAny>,
    margin: Option<&Bound<'py, PyAny>>,
    angle_deg: R,
    grip: bool,
    grav: R,
    grav_dir: R,
    fmax_floor: Option<R>,
) -> PyResult<Bound<'py, PyDict>> {
    let c = crate::card_of(card)?;
    let mut base = Params::<R>::with_card(c);
    base.set("grav", grav).map_err(crate::model_err)?;
    base.set("grav_dir", grav_dir).map_err(crate::model_err)?;
    let mut cols: Vec<Vec<R>> = [("t_min", t_min), ("a", a), ("e_b", e_b), ("w", w), ("layers", layers), ("z0", z0), ("v_supply", v_supply)]
        .iter()
        .map(|(n, o)| column(o, n))
        .collect::<PyResult<_>>()?;
    cols.push(match margin {
        Some(m) => column(m, "margin")?,
        None => vec![base.margin],
    });
    let rows = cols.iter().map(|v| v.len()).max().unwrap_or(1);
    if let Some(bad) = cols.iter().zip(NAMES).find(|(v, _)| v.len() != 1 && v.len() != rows) {
        return Err(PyValueError::new_err(format!("{}: {} values, others {rows}", bad.1, bad.0.len())));
    }
    if !angle_deg.is_finite() {
        return Err(PyValueError::new_err("angle_deg: a finite number"));
    }
    let angles = vec![angle_deg.to_radians(); base.n];
    let at = |i: usize| Candidate(core::array::from_fn(|j| cols[j][if cols[j].len() == 1 { 0 } else { i }]));
    let out: Vec<Eval> = py.detach(|| (0..rows).into_par_iter().map(|i| evaluate(&base, &at(i), &angles, grip, fmax_floor)).collect());
    let d = PyDict::new(py);
    let col1 = |g: &dyn Fn(&Eval) -> R| Array1::from_shape_fn(rows, |i| g(&out[i]));
    let col2 = |g: &dyn Fn(&Eval) -> [R; 2]| numpy::ndarray::Array2::from_shape_fn((rows, 2), |(i, j)| g(&out[i])[j]);
    d.set_item("kind", Array1::from_shape_fn(rows, |i| out[i].kind).into_pyarray(py))?;
    d.set_item("stage", Array1::from_shape_fn(rows, |i| out[i].stage).into_pyarray(py))?;
    d.set_item("ceiling_V", col1(&|e| e.ceiling).into_pyarray(py))?;
    d.set_item("tension_N", col2(&|e| e.tension).into_pyarray(py))?;
    d.set_item("kyy", col2(&|e| e.kyy).into_pyarray(py))?;
    d.set_item("ktt", col2(&|e| e.ktt).into_pyarray(py))?;
    d.set_item("volts_top_V", col1(&|e| e.volts_top).into_pyarray(py))?;
    d.set_item("s_min", col1(&|e| e.s_min).into_pyarray(py))?;
    d.set_item("field_V_per_um", col1(&|e| e.field_top).into_pyarray(py))?;
    d.set_item("fmax_N", col1(&|e| e.fmax).into_pyarray(py))?;
    d.set_item("grip_N", col1(&|e| e.grip).into_pyarray(py))?;
    d.set_item("breakdown_V_per_um", c.breakdown.field0_v_per_um)?;
    d.set_item("error_kinds", ERROR_KINDS.to_vec())?;
    d.set_item("stages", STAGES.to_vec())?;
    Ok(d)
}
