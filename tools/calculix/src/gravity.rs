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

/// TPU's density, g/cm³ (the body).
pub const RHO_BODY_G_CM3: f64 = 1.2;
/// The stacks' film density, g/cm³.
pub const RHO_STACK_G_CM3: f64 = 1.0;

/// A tip travel below this (mm) gives no % error (hanging straight down without cable the
/// tip only stretches).
pub const MIN_TRAVEL_MM: f64 = 1.0;

/// Gravity of magnitude `G_M_S2` in direction `dir_deg` on this finger's materials.
pub fn earth(_p: &Params<f64>, dir_deg: f64) -> Gravity {
    Gravity { g_m_s2: G_M_S2, dir_deg, rho_body_g_cm3: RHO_BODY_G_CM3, rho_stack_g_cm3: RHO_STACK_G_CM3 }
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

/// The FE (neo-Hooke) under gravity `grav` and each tension.
pub fn fe_states(p: &Params<f64>, kind: Kind, d: &Density, grav: &Gravity, tensions: &[f64]) -> Result<Vec<FeState>, FeError> {
    let th = stacks_at_0v(p).map_err(FeError::Mesh)?;
    finger_under_load(p, &th, kind, d, Law::NeoHooke, grav, tensions)
}

/// A model posture: joint angles (rad) and tip (x, y mm, θ rad).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub joint: [f64; 3],
    pub tip: [f64; 3],
}

/// The board's model (f32, `fast-trig`, converged solver) with calibration `cal`, at 0 V, under
/// each tension, with the gravity its parameters carry.
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
