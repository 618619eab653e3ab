//! The finger under its own weight (docs/fidelity-fe.md "Under its own weight"): the FE in three
//! orientations, with and without the board's stacks, and the model's errors against it (tip
//! in % of its travel from the straight finger, joint 1 in degrees).
//!
//! The calibration (`calibrate::run`) never sees gravity: its unit loads carry no body load, so
//! it cannot absorb it; gravity is compared only after it.

use crate::ccx::{FeError, Gravity, Kind, Law};
use crate::mesh::Density;
use crate::{finger_under_load, FeState};
use finger_model::{Calibration, Finger, Method, Params};

/// The orientations compared (gravity's direction, degrees from +x toward +y) and their names.
pub const ORIENTATIONS: [(f64, &str); 3] =
    [(90.0, "held horizontally, curling downward with gravity"), (-90.0, "held horizontally, curling upward against it"), (0.0, "hanging straight down")];

/// The cable tensions of the comparison, N: the goals hold to 2 N; 3 N is shown.
pub const TENSIONS_N: [f64; 5] = [0.0, 0.5, 1.0, 2.0, 3.0];

/// Gravity's magnitude in the comparison, m/s².
pub const G_M_S2: f64 = 9.81;

/// A tip travel below this (mm) gives no % error (hanging straight down without cable the
/// tip only stretches).
pub const MIN_TRAVEL_MM: f64 = 1.0;

/// These parameters under gravity of `G_M_S2` in direction `dir_deg`.
pub fn oriented(p: &Params<f64>, dir_deg: f64) -> Params<f64> {
    p.with_gravity(G_M_S2, dir_deg)
}

/// The board's stacks at 0 V (the model's thickness, mm per joint), zeros without stacks.
pub fn stacks_at_0v(p: &Params<f64>) -> Result<Vec<f64>, String> {
    if p.layers == 0 {
        return Ok(vec![0.0; p.n]);
    }
    let f = Finger::<f64>::new(*p).map_err(|e| e.to_string())?;
    let c = f.compliances(&vec![0.0; p.n]).map_err(|e| e.to_string())?;
    Ok(c.thickness[..p.n].to_vec())
}

/// The FE (neo-Hooke, the board's stacks at 0 V) under the gravity `p` carries and each
/// tension.
pub fn fe_states(p: &Params<f64>, kind: Kind, d: &Density, tensions: &[f64]) -> Result<Vec<FeState>, FeError> {
    let th = stacks_at_0v(p).map_err(FeError::Mesh)?;
    finger_under_load(p, &th, kind, d, Law::NeoHooke, &Gravity::of(p), tensions)
}

/// A model posture: joint angles (rad) and tip (x, y mm, θ rad).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub joint: [f64; 3],
    pub tip: [f64; 3],
}

/// The board's model (f32, `fast-trig`, converged solver) with calibration `cal`, at 0 V, under
/// each tension, with the gravity `p` carries.
pub fn model_poses(p: &Params<f64>, cal: &Calibration<f64>, tensions: &[f64]) -> Result<Vec<Pose>, String> {
    let cal32 =
        Calibration { hinge: cal.hinge.map(|x| x as f32), stack_axial: cal.stack_axial.map(|x| x as f32), stack_bending: cal.stack_bending.map(|x| x as f32) };
    let f = Finger::<f32>::with_calibration(p.cast(), cal32).map_err(|e| e.to_string())?;
    let c = f.compliances(&vec![0.0f32; p.n]).map_err(|e| e.to_string())?;
    tensions
        .iter()
        .map(|&t| {
            let s = f.solve_with(&c, t as f32, [0.0; 2], Method::converged()).map_err(|e| format!("model at {t} N: {e}"))?;
            let tip = s.tip();
            Ok(Pose { joint: [0, 1, 2].map(|k| s.joint_angle[k] as f64), tip: [tip.x as f64, tip.y as f64, tip.theta as f64] })
        })
        .collect()
}

/// The model's error against the FE at one state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseError {
    /// The FE tip's travel from the straight finger's tip (n l, 0), mm.
    pub travel_mm: f64,
    /// |model tip − FE tip|, mm.
    pub tip_mm: f64,
    /// `tip_mm` in % of `travel_mm` (None below `MIN_TRAVEL_MM`).
    pub tip_pct: Option<f64>,
    /// Model joint 1 − FE joint 1, degrees.
    pub joint1_deg: f64,
}

pub fn pose_error(p: &Params<f64>, m: &Pose, fe: &FeState) -> PoseError {
    let t = fe.tip();
    let travel_mm = (t.x - p.n as f64 * p.l).hypot(t.y);
    let tip_mm = (m.tip[0] - t.x).hypot(m.tip[1] - t.y);
    let tip_pct = (travel_mm >= MIN_TRAVEL_MM).then(|| 100.0 * tip_mm / travel_mm);
    PoseError { travel_mm, tip_mm, tip_pct, joint1_deg: (m.joint[0] - fe.joint_angle[0]).to_degrees() }
}

/// The model's worst errors over a range of tensions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Worst {
    /// Largest tip error, % of travel (over the states with a travel of `MIN_TRAVEL_MM` or more).
    pub tip_pct: f64,
    /// Joint 1's error of the largest magnitude, degrees (signed).
    pub joint1_deg: f64,
}

/// One orientation: the FE and the model, with gravity and without, at each tension.
#[derive(Clone, Debug)]
pub struct Case {
    pub dir_deg: f64,
    pub tensions: Vec<f64>,
    pub fe: Vec<FeState>,
    /// The model under the same gravity.
    pub model: Vec<Pose>,
    pub err: Vec<PoseError>,
    /// The model without gravity, against the same FE.
    pub err_without: Vec<PoseError>,
    /// The FE's CPU time (ccx, one thread), s.
    pub fe_cpu_s: f64,
}

/// The finger `p` (its gravity replaced by `G_M_S2` along `dir_deg`) in the FE and in the
/// board's model with calibration `cal` (computed without gravity), at each tension.
pub fn compare(p: &Params<f64>, dir_deg: f64, kind: Kind, d: &Density, cal: &Calibration<f64>, tensions: &[f64]) -> Result<Case, String> {
    let pg = oriented(p, dir_deg);
    let cpu0 = crate::ccx::thread_cpu_seconds();
    let fe = fe_states(&pg, kind, d, tensions).map_err(|e| format!("FE at {dir_deg}°: {e}"))?;
    let fe_cpu_s = crate::ccx::thread_cpu_seconds() - cpu0;
    let model = model_poses(&pg, cal, tensions)?;
    let without = model_poses(&Params { grav: 0.0, ..pg }, cal, tensions)?;
    let err = model.iter().zip(&fe).map(|(m, f)| pose_error(&pg, m, f)).collect();
    let err_without = without.iter().zip(&fe).map(|(m, f)| pose_error(&pg, m, f)).collect();
    Ok(Case { dir_deg, tensions: tensions.to_vec(), fe, model, err, err_without, fe_cpu_s })
}

impl Case {
    /// The worst errors over the tensions up to `up_to_n` N, with gravity in the model or not.
    pub fn worst(&self, with_gravity: bool, up_to_n: f64) -> Worst {
        let errs = if with_gravity { &self.err } else { &self.err_without };
        let mut w = Worst { tip_pct: 0.0, joint1_deg: 0.0 };
        for (e, t) in errs.iter().zip(&self.tensions) {
            if *t <= up_to_n {
                w.tip_pct = w.tip_pct.max(e.tip_pct.unwrap_or(0.0));
                if e.joint1_deg.abs() > w.joint1_deg.abs() {
                    w.joint1_deg = e.joint1_deg;
                }
            }
        }
        w
    }
}
