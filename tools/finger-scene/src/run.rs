//! Running a scene on the model (f64): every posture it asks for, nothing more. `run` computes
//! everything first, so a refused scene leaves no output behind (the binary writes only on
//! success). The model's refusals carry the joint, the limit and the scene key that asked.
//!
//! What it is not: the continuum reference, reached only through [`ReferenceSolver`] when a
//! scene asks for `reference = "continuum"` (`crate::reference` implements it).

use crate::scene::{volts_of, FingerSpec, Pos, Reference, Scene, SceneError};
use finger_model::{mat3::Mat3, Finger, Params, Pose, Solution};

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

/// A prepared finger: the model, its channel voltages and stack thicknesses.
struct Prepared {
    finger: Finger<f64>,
    volts: Vec<f64>,
}

fn prepare(spec: &FingerSpec) -> Result<Prepared, SceneError> {
    let finger = Finger::new(spec.params).map_err(|e| SceneError::model(spec.section_at, "parameters", e))?;
    let volts = volts_of(spec)?;
    // the compliances check every voltage against the ceiling once more
    finger.compliances(&volts).map_err(|e| SceneError::model(spec.drive_at, "drive", e))?;
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
    at: Pos,
    label: String,
    kind: Kind,
    reference: Option<&dyn ReferenceSolver>,
) -> Result<Posture, SceneError> {
    let sol = prep.finger.solve(tension, &prep.volts, scene.solver.method()).map_err(|e| SceneError::model(at, &format!("tension {tension} N"), e))?;
    let p = prep.finger.params();
    let stiffness = if scene.output.tip_stiffness {
        Some(prep.finger.tip_stiffness(&sol).map_err(|e| SceneError::model(scene.output_at, "tip_stiffness", e))?)
    } else {
        None
    };
    let reference = match (scene.output.reference, reference) {
        (Reference::None, _) => None,
        (Reference::Continuum, Some(r)) => Some(
            r.solve(p, tension, &prep.volts, &sol.thickness[..sol.n]).map_err(|e| SceneError::at(scene.output_at, format!("reference at {tension} N: {e}")))?,
        ),
        (Reference::Continuum, None) => return Err(SceneError::at(scene.output_at, "reference = continuum: no continuum reference in this build")),
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
fn tension_for_tip_angle(prep: &Prepared, scene: &Scene, target: f64, at: Pos) -> Result<f64, SceneError> {
    let angle = |p: f64| -> Result<f64, SceneError> {
        prep.finger.solve(p, &prep.volts, scene.solver.method()).map(|s| s.tip().theta).map_err(|e| SceneError::model(at, "match", e))
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    let mut grow = 0;
    while angle(hi)? < target {
        lo = hi;
        hi *= 2.0;
        grow += 1;
        if grow > 20 {
            return Err(SceneError::at(at, "match: no tension reaches the target tip angle"));
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
    if s == "-0" {
        "0".into()
    } else {
        s.to_string()
    }
}

/// A finger in words, for a legend: "finger with 4 DE layers" or "finger without DE layers".
fn describe(spec: &FingerSpec) -> String {
    match spec.params.layers {
        0 => "finger without DE layers".into(),
        n => format!("finger with {n} DE layers"),
    }
}

/// Run a scene: every posture it asks for, nothing more. `reference` is the continuum
/// reference (needed only if the scene says `reference = continuum`).
pub fn run(scene: &Scene, reference: Option<&dyn ReferenceSolver>) -> Result<SceneResult, SceneError> {
    let prep = prepare(&scene.finger)?;
    let n = scene.finger.params.n;
    let mut postures = Vec::new();
    for &t in &scene.tensions {
        postures.push(solve_one(&prep, scene, t, scene.tensions_at, format!("{} N", fmt_g(t)), Kind::Tension, reference)?);
    }
    let mut matched_tension = None;
    if let Some(m) = &scene.matching {
        let mprep = prepare(&m.finger)?;
        let target = mprep.finger.solve(m.tension, &mprep.volts, scene.solver.method()).map_err(|e| SceneError::model(m.at, "match", e))?;
        let tm = tension_for_tip_angle(&prep, scene, target.tip().theta, m.at)?;
        matched_tension = Some(tm);
        postures.push(solve_one(
            &prep,
            scene,
            tm,
            m.at,
            format!("{} N: same tip angle as the {} at {} N", fmt_g(tm), describe(&m.finger), fmt_g(m.tension)),
            Kind::Matched,
            reference,
        )?);
        if m.show {
            let mscene = Scene { finger: m.finger.clone(), ..scene.clone() };
            postures.push(solve_one(
                &mprep,
                &mscene,
                m.tension,
                m.at,
                format!("{} at {} N", describe(&m.finger), fmt_g(m.tension)),
                Kind::MatchTarget,
                reference,
            )?);
        }
    }
    Ok(SceneResult { scene: scene.clone(), n, postures, matched_tension })
}
