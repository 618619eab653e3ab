//! The continuum reference (tools/continuum) as a scene's `reference = "continuum"`.

use crate::run::{RefPosture, ReferenceSolver};
use finger_model::{Params, Pose};

/// The continuum reference (the `continuum` crate) as a scene's `reference = continuum`: the real
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
