//! The Cortex-M3 image's model calls (`cfg(m3)`, docs/firmware.md "Cortex-M3 image"): the
//! console's forward solves (`solve`, `status`, the servo plan) and fmax on the fixed-point
//! model (`finger_model::fixed`, docs/fixed-point.md) instead of the f32 model in soft float.
//! The set-up (compliances at the voltages) is the f32 model's; the solve has no float
//! operation; `solve`'s tip stiffness from the converged fixed-point state, once in f32.
//! (`pose` on the fixed-point inverse is `super::pose`'s.)

use finger_model::fixed::q::Nt;
use finger_model::fixed::{FixedFinger, FixedSolution};
use finger_model::mat3::Mat3;
use finger_model::{BranchLimit, Error as ModelError, Finger, Pose};

use super::params::CHANNELS;

/// What the console prints of a forward solve (the f32 `Solution`'s fields it reads).
pub(crate) struct Solved {
    pub joint_angle: [f32; CHANNELS],
    pub cable_excursion: f32,
    pub thickness: [f32; CHANNELS],
    pub iterations: u32,
    tip: Pose<f32>,
}

impl Solved {
    pub fn tip(&self) -> Pose<f32> {
        self.tip
    }
}

/// The converged equilibrium under tension `p` (N) alone at `volts`, in fixed point.
#[inline(never)]
pub(crate) fn forward(f: &Finger<f32>, p: f32, volts: &[f32; CHANNELS]) -> Result<Solved, ModelError> {
    let mut ff = FixedFinger::empty();
    ff.prepare(f, volts)?;
    solved(f, &ff.solve(Nt::from_f32(p))?, volts)
}

/// [`forward`] and the tip stiffness at its posture (`solve`): the fixed-point state's
/// sub-element displacements, then K_tip = (Σ J C Jᵀ)⁻¹ once in f32 (`FixedFinger::tip_stiffness`).
#[inline(never)]
pub(crate) fn forward_stiffness(f: &Finger<f32>, p: f32, volts: &[f32; CHANNELS]) -> Result<(Solved, Mat3<f32>), ModelError> {
    let mut ff = FixedFinger::empty();
    ff.prepare(f, volts)?;
    let s = ff.solve(Nt::from_f32(p))?;
    Ok((solved(f, &s, volts)?, stiffness(f, &ff, &s)?))
}

#[inline(never)]
fn stiffness(f: &Finger<f32>, ff: &FixedFinger, s: &FixedSolution) -> Result<Mat3<f32>, ModelError> {
    ff.tip_stiffness(f, s)
}

fn solved(f: &Finger<f32>, s: &FixedSolution, volts: &[f32; CHANNELS]) -> Result<Solved, ModelError> {
    let mut out = Solved {
        joint_angle: [0.0; CHANNELS],
        cable_excursion: s.cable_excursion.to_f32(),
        thickness: [0.0; CHANNELS],
        iterations: s.iterations,
        tip: Pose::origin(),
    };
    for k in 0..CHANNELS {
        out.joint_angle[k] = s.joint_angle[k].to_f32();
        if f.params().layers > 0 {
            out.thickness[k] = f.stack_thickness(volts[k])?;
        }
    }
    let t = s.tip();
    out.tip = Pose { x: t.x.to_f32(), y: t.y.to_f32(), theta: t.theta.to_f32() };
    Ok(out)
}

/// fmax at `volts`: the largest tension the fixed-point solve holds (`FixedFinger::branch_end`).
#[inline(never)]
pub(crate) fn fmax_of(f: &Finger<f32>, volts: &[f32; CHANNELS]) -> Result<BranchLimit<f32>, ModelError> {
    let mut ff = FixedFinger::empty();
    ff.prepare(f, volts)?;
    let e = ff.branch_end()?;
    Ok(BranchLimit { tension: e.tension.to_f32(), joint: e.joint, kind: e.kind })
}
